// Shared set-up of the benchmark programs.
#include "bench_support.hpp"

#include <cpl_conv.h>
#include <gdal_priv.h>

#include <map>
#include <memory>

namespace dpts::bench {

std::string shared_path(const std::string& file) {
  return std::string(DPTS_SHARED_DATA_DIR) + "/" + file;
}

const io::Dem* shared_dem(const std::string& file) {
  static std::map<std::string, std::unique_ptr<io::Dem>> cache;
  auto it = cache.find(file);
  if (it == cache.end()) {
    GDALAllRegister();
    CPLSetConfigOption("GDAL_CACHEMAX", "64");
    std::unique_ptr<io::Dem> dem;
    try {
      dem = std::make_unique<io::Dem>(io::read_dem(shared_path(file), {}, nullptr));
    } catch (const std::exception&) {
    }
    it = cache.emplace(file, std::move(dem)).first;
  }
  return it->second.get();
}

}  // namespace dpts::bench
