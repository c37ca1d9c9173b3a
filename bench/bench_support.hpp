// Shared set-up of the benchmark programs.
#pragma once

#include <string>

#include "io/dem_reader.hpp"

namespace dpts::bench {

// The DEM `file` of the shared data folder (DPTS_SHARED_DATA_DIR), read once per process with a
// 64 MB GDAL cache; null when it cannot be read (the benchmark then reports an error).
const io::Dem* shared_dem(const std::string& file);

// Its full path, for messages.
std::string shared_path(const std::string& file);

}  // namespace dpts::bench
