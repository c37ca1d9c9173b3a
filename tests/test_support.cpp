// Helpers shared by the tests.
#include "test_support.hpp"

#include <fcntl.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

namespace dpts::test {

core::HeightGrid make_grid(int width, int height, const std::function<double(int, int)>& f) {
  core::HeightGrid g;
  g.width = width;
  g.height = height;
  g.z.resize(static_cast<std::size_t>(width) * height);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) g.z[g.index(c, r)] = f(c, r);
  }
  return g;
}

TempDir::TempDir() {
  std::string tmpl = (std::filesystem::temp_directory_path() / "dpts-test-XXXXXX").string();
  std::vector<char> buf(tmpl.begin(), tmpl.end());
  buf.push_back('\0');
  if (!::mkdtemp(buf.data())) throw std::runtime_error("mkdtemp failed");
  path_ = buf.data();
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::permissions(path_, std::filesystem::perms::owner_all,
                               std::filesystem::perm_options::add, ec);
  std::filesystem::remove_all(path_, ec);
}

std::vector<std::string> TempDir::files() const {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(path_)) {
    names.push_back(e.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

namespace {
std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

RunResult run(const std::string& exe, const std::vector<std::string>& args) {
  TempDir io;
  const auto out_path = io / "stdout", err_path = io / "stderr";
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ::dup2(out, 1);
    ::dup2(err, 2);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(exe.c_str()));
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(exe.c_str(), argv.data());
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = slurp(out_path);
  r.err = slurp(err_path);
  return r;
}

void write_geotiff(const std::filesystem::path& path, const core::HeightGrid& grid,
                   const std::vector<double>& geotransform, const std::string& wkt, double nodata) {
  GDALAllRegister();
  GDALDriver* drv = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds = drv->Create(path.c_str(), grid.width, grid.height, 1, GDT_Float32, nullptr);
  if (!ds) throw std::runtime_error("cannot create " + path.string());
  std::vector<double> gt = geotransform;
  ds->SetGeoTransform(gt.data());
  if (!wkt.empty()) ds->SetProjection(wkt.c_str());
  GDALRasterBand* band = ds->GetRasterBand(1);
  band->SetNoDataValue(nodata);
  std::vector<float> values(grid.z.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    values[i] = std::isnan(grid.z[i]) ? static_cast<float>(nodata) : static_cast<float>(grid.z[i]);
  }
  if (band->RasterIO(GF_Write, 0, 0, grid.width, grid.height, values.data(), grid.width,
                     grid.height, GDT_Float32, 0, 0) != CE_None) {
    throw std::runtime_error("cannot write " + path.string());
  }
  GDALClose(ds);
}

std::vector<double> grid_xy(const core::HeightGrid& grid, const core::Tin& tin) {
  std::vector<double> xy;
  for (std::uint32_t cell : tin.cells) {
    xy.push_back(cell % grid.width);
    xy.push_back(cell / grid.width);
  }
  return xy;
}

std::string shared_data(const std::string& name) {
  return std::string(DPTS_SHARED_DATA_DIR) + "/" + name;
}

}  // namespace dpts::test
