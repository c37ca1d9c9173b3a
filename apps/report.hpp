// dpts-par's machine-readable run report (--report FILE.json): what ran on what, what came
// out, how long each stage took, and how it ended. Written atomically, also on failure.
#pragma once

#include <chrono>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "apps/cli.hpp"
#include "io/dem_reader.hpp"
#include "io/json.hpp"
#include "parallel/meta.hpp"

namespace dpts::cli {

// Wall and CPU time (the whole process: all threads) per stage, from the stage names the
// progress callback reports. Thread-safe.
class StageClock {
 public:
  StageClock();
  void enter(std::string_view stage);  // a no-op while the stage stays the same
  std::string json() const;            // [{"stage":..,"wall_s":..,"cpu_s":..}, ...]
  double wall_s() const;
  double cpu_s() const;
  std::string stage() const;  // the stage entered last ("" before any)

 private:
  struct Mark {
    std::string stage;
    double wall = 0, cpu = 0;
  };
  mutable std::mutex lock_;
  std::vector<Mark> marks_;
  std::chrono::steady_clock::time_point start_;
};

// Process CPU time so far (user + system, all threads), seconds.
double process_cpu_s();

// The fields a resumed batch compares: the options that change the output (not --threads,
// --quiet, --verbose, --max-memory, --report), as a JSON object.
std::string output_options_json(const ParOptions& o);

// A fingerprint of the input (absolute path, size, modification time), the output options
// and the dpts version: equal keys mean a run would write the same output again.
std::string resume_key(const ParOptions& o);

// The report's parts: the input as read, the output as written (bytes and sha256 read back
// from file: path itself once committed, its temporary file before), the pieces of the meta
// engine.
std::string input_json(const io::DemInfo& dem, std::size_t valid_cells,
                       std::size_t surface_vertices);
std::string output_json(const std::string& path, std::size_t vertices, std::size_t faces,
                        const std::string& file);
std::string pieces_json(const par::MetaStats& stats);

struct RunReport {
  std::string path;               // where to write it ("" when no report was asked)
  std::vector<std::string> args;  // the command line
  std::string input_json = "{}", output_json = "null", pieces_json;
  int threads = 0;  // the threads the run used
  StageClock clock;
  bool written = false;  // written already (a streamed report, before OUTPUT's commit)

  // Writes the report (atomically). status: "ok", "failed" or "interrupted". Never throws:
  // returns why the report could not be written ("" when it was).
  std::string write(const ParOptions& o, const std::string& status, int exit_code,
                    const std::string& error) const;
};

}  // namespace dpts::cli
