// dpts-par --batch: many DEMs in one resumable run, each simplified by a child dpts-par.
#pragma once

#include <atomic>
#include <string>
#include <vector>

#include "apps/cli.hpp"

namespace dpts::cli {

// The inputs of --batch SRC: every raster of a folder (GDAL recognises it, or its extension
// is a raster one; sidecars skipped), or the paths listed in a file (one per line, '#'
// comments, relative paths relative to the list's folder). Sorted as given / by name.
// Throws UsageError naming SRC when it is neither.
std::vector<std::string> batch_inputs(const std::string& source);

// Runs the batch: each input not already done (its report says ok with the same resume key
// and its output has the bytes the report gives) is simplified by a child process `self`
// with o.child_args, --quiet, --report and its share of threads and memory, o.jobs at a
// time. Writes OUT/batch-summary.json. A signal (cancel set) stops new inputs, passes SIGTERM
// to the running ones, and writes the summary of what ended. Returns 0 when every input is
// done, 1 otherwise.
int run_batch(const ParOptions& o, const std::string& self, const std::atomic<int>* cancel);

}  // namespace dpts::cli
