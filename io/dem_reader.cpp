// Reading a DEM with GDAL: block-aligned strips of band 1, no-data handling, CRS choice.
#include "io/dem_reader.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <dlfcn.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "core/surface_sampling.hpp"
#include "io/input_file.hpp"
#include "io/netcdf_classic.hpp"

namespace dpts::io {
namespace {

std::string last_gdal_error() {
  std::string msg = CPLGetLastErrorMsg();
  std::replace(msg.begin(), msg.end(), '\n', ' ');
  return msg.empty() ? "unknown GDAL error" : msg;
}

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(ds); }
};

std::string crs_name(const OGRSpatialReference& srs) {
  const char* name = srs.GetName();
  std::string out = name ? name : "unnamed CRS";
  const char* auth = srs.GetAuthorityName(nullptr);
  const char* code = srs.GetAuthorityCode(nullptr);
  if (auth && code) out += std::string(" (") + auth + ":" + code + ")";
  return out;
}

// The UTM zone CRS (same datum) for a geographic CRS at (lon, lat).
OGRSpatialReference utm_for(const OGRSpatialReference& geographic, double lon, double lat) {
  // Longitudes may run 0-360 (or beyond): the zone of the same meridian in -180..180.
  const double east = std::fmod(std::fmod(lon + 180.0, 360.0) + 360.0, 360.0);
  const int zone = std::clamp(static_cast<int>(std::floor(east / 6.0)) + 1, 1, 60);
  const bool north = lat >= 0;
  OGRSpatialReference utm;
  const char* code = geographic.GetAuthorityCode(nullptr);
  if (code && std::string(code) == "4326") {
    utm.importFromEPSG((north ? 32600 : 32700) + zone);
  } else {
    utm.CopyGeogCSFrom(&geographic);
    utm.SetUTM(zone, north ? TRUE : FALSE);
    utm.SetProjCS(("UTM zone " + std::to_string(zone) + (north ? "N" : "S")).c_str());
  }
  utm.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return utm;
}

}  // namespace

void TransformDeleter::operator()(OGRCoordinateTransformation* t) const {
  OGRCoordinateTransformation::DestroyCT(t);
}

std::vector<double> DemInfo::output_xy(const std::vector<std::uint32_t>& cells) const {
  std::vector<double> grid(2 * cells.size());
  for (std::size_t i = 0; i < cells.size(); ++i) {
    grid[2 * i] = static_cast<double>(cells[i] % static_cast<std::uint32_t>(width));
    grid[2 * i + 1] = static_cast<double>(cells[i] / static_cast<std::uint32_t>(width));
  }
  return output_xy_of_grid(grid);
}

std::vector<double> DemInfo::output_xy_of_grid(const std::vector<double>& grid) const {
  return project_grid(grid, to_output.get());
}

std::vector<double> DemInfo::output_xy_of_grid_concurrent(const std::vector<double>& grid) const {
  if (!to_output) return project_grid(grid, nullptr);
  std::unique_ptr<OGRCoordinateTransformation, TransformDeleter> ct(to_output->Clone());
  if (!ct) throw IoError(path + ": cannot copy the transformation to " + output_crs_name);
  return project_grid(grid, ct.get());
}

std::vector<double> DemInfo::project_grid(const std::vector<double>& grid,
                                          OGRCoordinateTransformation* to_output) const {
  const double* gt = geotransform;
  const std::size_t n = grid.size() / 2;
  std::vector<double> x(n), y(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double c = grid[2 * i] + 0.5, r = grid[2 * i + 1] + 0.5;
    x[i] = gt[0] + c * gt[1] + r * gt[2];
    y[i] = gt[3] + c * gt[4] + r * gt[5];
  }
  if (to_output && n > 0) {
    std::vector<int> ok(n, 0);
    if (!to_output->Transform(static_cast<int>(n), x.data(), y.data(), nullptr, ok.data()) ||
        std::find(ok.begin(), ok.end(), 0) != ok.end()) {
      throw IoError(path + ": cannot transform cell centres to " + output_crs_name + " (" +
                    last_gdal_error() + ")");
    }
  }
  std::vector<double> xy(2 * n);
  for (std::size_t i = 0; i < n; ++i) xy[2 * i] = x[i], xy[2 * i + 1] = y[i];
  return xy;
}

void DemInfo::frame_mesh_to_output(core::TriMesh& mesh) const {
  const std::size_t n = mesh.vertex_count();
  double inv[2][2];
  frame.inverse(inv);
  std::vector<double> grid(2 * n);
  for (std::size_t v = 0; v < n; ++v) {
    const double u = mesh.xyz[3 * v], w = mesh.xyz[3 * v + 1];
    grid[2 * v] = inv[0][0] * u + inv[0][1] * w;
    grid[2 * v + 1] = inv[1][0] * u + inv[1][1] * w;
  }
  const std::vector<double> xy = output_xy_of_grid_concurrent(grid);
  for (std::size_t v = 0; v < n; ++v) {
    mesh.xyz[3 * v] = xy[2 * v];
    mesh.xyz[3 * v + 1] = xy[2 * v + 1];
    mesh.xyz[3 * v + 2] *= frame.metres_per_unit;
  }
}

namespace {
// A longitude the inverse transformation gave (PROJ's are in -180..180) moved by whole turns
// into the DEM's own range (0..360, or across 180): the turn nearest the DEM's centre.
double unwrap_lon(double lon, double centre) {
  return lon + 360.0 * std::round((centre - lon) / 360.0);
}

// The grid position (col, row; cell centres at integers) of point (x, y) in the DEM's CRS,
// given by the inverse transformation from the output CRS (transformed): the geotransform gt
// inverted, (x - gt0, y - gt3) = A (col + 0.5, row + 0.5), a longitude first brought to the
// DEM's own turn (geographic, centred on centre_lon).
void source_to_grid(const double* gt, bool transformed, bool geographic, double centre_lon,
                    double x, double y, double& col, double& row) {
  if (transformed && geographic) x = unwrap_lon(x, centre_lon);
  const double det = gt[1] * gt[5] - gt[2] * gt[4];
  const double dx = x - gt[0], dy = y - gt[3];
  col = (gt[5] * dx - gt[2] * dy) / det - 0.5;
  row = (-gt[4] * dx + gt[1] * dy) / det - 0.5;
}
}  // namespace

std::vector<double> DemInfo::grid_xy(const std::vector<double>& output_xy) const {
  const std::size_t n = output_xy.size() / 2;
  std::vector<double> x(n), y(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = output_xy[2 * i], y[i] = output_xy[2 * i + 1];
  if (from_output) {
    std::vector<int> ok(n, 0);
    if (n > 0 &&
        (!from_output->Transform(static_cast<int>(n), x.data(), y.data(), nullptr, ok.data()) ||
         std::find(ok.begin(), ok.end(), 0) != ok.end())) {
      throw IoError(path + ": cannot transform points from " + output_crs_name +
                    " to the DEM's CRS");
    }
  }
  std::vector<double> grid(2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    source_to_grid(geotransform, from_output != nullptr, source_geographic, centre_lon, x[i], y[i],
                   grid[2 * i], grid[2 * i + 1]);
  }
  return grid;
}

std::function<bool(double, double, double&, double&)> DemInfo::grid_of_output_fn() const {
  std::shared_ptr<OGRCoordinateTransformation> ct;
  if (from_output) {
    ct.reset(from_output->Clone(), TransformDeleter());
    if (!ct) throw IoError(path + ": cannot copy the transformation from " + output_crs_name);
  }
  const double* gt = geotransform;
  const std::array<double, 6> g{gt[0], gt[1], gt[2], gt[3], gt[4], gt[5]};
  const bool geographic = source_geographic;
  const double centre = centre_lon;
  return [ct, g, geographic, centre](double x, double y, double& col, double& row) {
    int ok = 0;
    if (ct && (!ct->Transform(1, &x, &y, nullptr, &ok) || !ok)) return false;
    source_to_grid(g.data(), ct != nullptr, geographic, centre, x, y, col, row);
    return true;
  };
}

double DemInfo::outline_tolerance_m() const {
  return 0.01 * frame.metres_per_unit * std::min(1.0, std::fabs(frame.m[1][1]));
}

std::function<bool(std::uint64_t, std::uint64_t)> DemInfo::outline_chord_test(
    double tolerance_m, int col0, int row0, int window_width) const {
  if (!to_output) return nullptr;
  // A transformation of our own (they are not thread-safe), shared by the copies of the test
  // and used under a lock: the test runs for outline vertices only, a small share of the work.
  struct Shared {
    std::unique_ptr<OGRCoordinateTransformation, TransformDeleter> ct;
    std::mutex lock;
  };
  auto shared = std::make_shared<Shared>();
  shared->ct.reset(to_output->Clone());
  if (!shared->ct) throw IoError(path + ": cannot copy the transformation to " + output_crs_name);
  const double* gt = geotransform;
  const std::array<double, 6> g{gt[0], gt[1], gt[2], gt[3], gt[4], gt[5]};
  const long win_w = window_width > 0 ? window_width : width;
  const double unit_m = metres_per_output_unit;
  return [shared, g, win_w, col0, row0, unit_m, tolerance_m](std::uint64_t a, std::uint64_t b) {
    const auto w = static_cast<std::uint64_t>(win_w);
    const long ca = static_cast<long>(a % w), ra = static_cast<long>(a / w);
    const long cb = static_cast<long>(b % w), rb = static_cast<long>(b / w);
    const long steps = std::max(std::labs(cb - ca), std::labs(rb - ra));
    if (steps < 2) return true;
    // The cell halfway along the grid line (a and b lie on one row, column or diagonal).
    const long half = steps / 2;
    const long cm = ca + (cb - ca) / steps * half, rm = ra + (rb - ra) / steps * half;
    double x[3], y[3];
    const long cs[3] = {ca, cb, cm}, rs[3] = {ra, rb, rm};
    for (int i = 0; i < 3; ++i) {
      const double c = static_cast<double>(cs[i] + col0) + 0.5;
      const double r = static_cast<double>(rs[i] + row0) + 0.5;
      x[i] = g[0] + c * g[1] + r * g[2];
      y[i] = g[3] + c * g[4] + r * g[5];
    }
    int ok[3] = {0, 0, 0};
    {
      std::lock_guard<std::mutex> hold(shared->lock);
      if (!shared->ct->Transform(3, x, y, nullptr, ok) || !ok[0] || !ok[1] || !ok[2]) {
        return false;
      }
    }
    const double dx = x[1] - x[0], dy = y[1] - y[0];
    const double len = std::hypot(dx, dy);
    const double off = len > 0 ? std::fabs(dx * (y[2] - y[0]) - dy * (x[2] - x[0])) / len : 0.0;
    return off * unit_m <= tolerance_m;
  };
}

namespace {

// Metres per unit of a band's height unit ("m", "metre", "ft", "US survey foot", "km"...): 1
// when it is metres or empty (also "metres above sea level", "m MSL": metres and a datum), 0
// when it is not a unit dpts knows.
double height_unit_metres(std::string unit) {
  std::transform(unit.begin(), unit.end(), unit.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  const std::string first = unit.substr(0, unit.find_first_of(" _("));
  for (const char* m : {"", "m", "metre", "metres", "meter", "meters"}) {
    if (first == m) return 1.0;
  }
  static constexpr std::pair<const char*, double> kUnits[] = {{"ft", 0.3048},
                                                              {"foot", 0.3048},
                                                              {"feet", 0.3048},
                                                              {"international foot", 0.3048},
                                                              {"us survey foot", 1200.0 / 3937.0},
                                                              {"us-ft", 1200.0 / 3937.0},
                                                              {"ftus", 1200.0 / 3937.0},
                                                              {"us_survey_foot", 1200.0 / 3937.0},
                                                              {"km", 1000.0},
                                                              {"kilometre", 1000.0},
                                                              {"kilometres", 1000.0},
                                                              {"kilometer", 1000.0},
                                                              {"kilometers", 1000.0},
                                                              {"dm", 0.1},
                                                              {"cm", 0.01},
                                                              {"centimetre", 0.01},
                                                              {"centimetres", 0.01},
                                                              {"centimeter", 0.01},
                                                              {"centimeters", 0.01},
                                                              {"mm", 0.001},
                                                              {"millimetre", 0.001},
                                                              {"millimetres", 0.001},
                                                              {"millimeter", 0.001},
                                                              {"millimeters", 0.001}};
  for (const auto& [name, metres] : kUnits) {
    if (unit == name) return metres;
  }
  return 0.0;  // not known
}

// A raw raster (ENVI, EHdr and the like: a header and a plain data file) cut short reads as
// zeros beyond its end, without an error from GDAL: its data file must hold every cell.
void check_raw_size(GDALDataset& ds, const std::string& path) {
  GDALDataset::RawBinaryLayout layout;
  if (!ds.GetRawBinaryLayout(layout) || layout.osRawFilename.empty()) return;
  const GIntBig w = ds.GetRasterXSize(), h = ds.GetRasterYSize(), b = ds.GetRasterCount();
  GIntBig last = 0;  // the farthest byte any cell starts at, from the image's offset
  for (const GIntBig r : {GIntBig{0}, h - 1}) {
    for (const GIntBig c : {GIntBig{0}, w - 1}) {
      for (const GIntBig k : {GIntBig{0}, b - 1}) {
        last = std::max(last,
                        r * layout.nLineOffset + c * layout.nPixelOffset + k * layout.nBandOffset);
      }
    }
  }
  const GIntBig need =
      static_cast<GIntBig>(layout.nImageOffset) + last + GDALGetDataTypeSizeBytes(layout.eDataType);
  VSIStatBufL st;
  if (VSIStatL(layout.osRawFilename.c_str(), &st) != 0) return;  // the read then fails
  if (static_cast<GIntBig>(st.st_size) < need) {
    throw InputError(path + ": truncated: its data file " + layout.osRawFilename + " has " +
                     std::to_string(st.st_size) + " bytes, its cells need " + std::to_string(need));
  }
}

// The plain file behind a name GDAL reads: the name itself, or for /vsizip/, /vsitar/,
// /vsigzip/ and the like the archive (the first prefix of the path inside that is a regular
// file, or the {braced} archive name); empty for what is no local file (/vsimem/, /vsicurl/).
std::string local_file_of(const std::string& name) {
  if (name.rfind("/vsi", 0) != 0) return name;
  const std::size_t slash = name.find('/', 1);
  if (slash == std::string::npos) return {};
  const std::string rest = name.substr(slash + 1);
  if (rest.rfind("/vsi", 0) == 0) return local_file_of(rest);
  if (!rest.empty() && rest[0] == '{') {
    const std::size_t close = rest.find('}');
    return close == std::string::npos ? std::string() : local_file_of(rest.substr(1, close - 1));
  }
  for (std::size_t p = rest.find('/', 1);; p = rest.find('/', p + 1)) {
    const std::string prefix = rest.substr(0, p);
    struct stat st {};
    if (::stat(prefix.c_str(), &st) == 0 && S_ISREG(st.st_mode)) return prefix;
    if (p == std::string::npos) return {};
  }
}

// The dataset's files, as local files; and each netCDF classic file among them must hold
// every value its header declares (cut short, it reads as zeros without an error).
std::vector<std::string> dataset_files(GDALDataset& ds, const std::string& path) {
  std::vector<std::string> files;
  const auto add = [&](const std::string& f) {
    if (!f.empty() && std::find(files.begin(), files.end(), f) == files.end()) files.push_back(f);
  };
  std::vector<std::string> names;
  char** list = ds.GetFileList();
  for (int i = 0; list && list[i]; ++i) names.emplace_back(list[i]);
  CSLDestroy(list);
  for (const std::string& name : names) {
    add(local_file_of(name));
    if (const auto need = netcdf_classic_needed_bytes(name)) {
      VSIStatBufL st;
      if (VSIStatL(name.c_str(), &st) == 0 && static_cast<std::uint64_t>(st.st_size) < *need) {
        throw InputError(path + ": truncated: " + name + " has " + std::to_string(st.st_size) +
                         " bytes, its netCDF header declares " + std::to_string(*need));
      }
    }
  }
  add(local_file_of(path));
  return files;
}

}  // namespace

DemInfo::FileStamp DemInfo::stamp_of(const std::string& path) {
  FileStamp f;
  struct stat st {};
  if (path.rfind("/vsi", 0) == 0 || ::stat(path.c_str(), &st) != 0) return f;
  f.set = true;
  f.device = static_cast<std::uint64_t>(st.st_dev);
  f.inode = static_cast<std::uint64_t>(st.st_ino);
  f.size = static_cast<std::int64_t>(st.st_size);
  f.mtime_ns = static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
  return f;
}

void DemInfo::check_unchanged() const {
  if (stamp.set && !(stamp_of(path) == stamp)) {
    throw InputError(path + ": changed while it was being read (replaced or rewritten); " +
                     "no output written");
  }
}

namespace {

// A path that names a plain file must exist and be one: not a directory, and not a FIFO or
// device, whose open would block or whose read would not end. GDAL's /vsimem/, /vsizip/... and
// names with a driver prefix (subdatasets and connection strings: GTIFF_DIR:1:f.tif,
// NETCDF:"f.nc":var, HDF5:...) are not plain files and are left to GDAL.
void check_plain_file(const std::string& path) {
  std::error_code ec;
  const std::size_t colon = path.find(':');
  const bool prefixed = colon != std::string::npos && colon > 1 &&
                        std::all_of(path.begin(), path.begin() + static_cast<long>(colon),
                                    [](unsigned char c) { return std::isalnum(c) || c == '_'; });
  const bool virtual_file = path.rfind("/vsi", 0) == 0 || prefixed;
  if (!virtual_file && !std::filesystem::exists(path, ec)) {
    throw_if_unreachable(path, ec);
    throw InputError(path + ": no such file");
  }
  if (!virtual_file && std::filesystem::is_directory(path, ec))
    throw InputError(path + ": is a directory, not a raster");
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (!virtual_file && !std::filesystem::is_regular_file(st)) {
    throw InputError(
        path +
        ": is a pipe or a device, not a raster file (a raster on standard input: \"-\" as "
        "dpts-par's INPUT, or /vsistdin/)");
  }
}

// The dataset's geotransform into dem (1 m cells, noted, when it has none), refused when it is
// not finite, has zero cell size, or cells too small for doubles to place apart.
void read_geotransform(GDALDataset& ds, const std::string& path, int width, int height,
                       DemInfo& dem) {
  double* gt = dem.geotransform;
  const bool has_gt = ds.GetGeoTransform(gt) == CE_None;
  if (!has_gt && ds.GetGCPCount() > 0) {
    throw InputError(path + ": georeferenced by " + std::to_string(ds.GetGCPCount()) +
                     " ground control points, not a geotransform; warp it to a grid first "
                     "(gdalwarp)");
  }
  if (!has_gt) {
    gt[0] = 0, gt[1] = 1, gt[2] = 0, gt[3] = 0, gt[4] = 0, gt[5] = -1;
    dem.notes.push_back("warning: " + path + " has no geotransform; using 1 m cells");
  }
  for (int i = 0; i < 6; ++i) {
    if (!std::isfinite(gt[i])) throw InputError(path + ": geotransform is not finite");
  }
  if (gt[1] * gt[5] - gt[2] * gt[4] == 0.0) {
    char coefficients[128];
    std::snprintf(coefficients, sizeof coefficients, "%.9g, %.9g, %.9g, %.9g", gt[1], gt[2], gt[4],
                  gt[5]);
    throw InputError(path + ": geotransform is singular: its cells have no area (" + coefficients +
                     ")");
  }
  // Cells so small beside the coordinates' magnitude that doubles hardly tell their corners
  // apart (fewer than ~5000 steps of the last bit per cell; folds were measured from 2e-14)
  // give rounded, folded triangles: refused here, not as folds found at the end.
  {
    const double far_corner = std::max({std::abs(gt[0]), std::abs(gt[3]),
                                        std::abs(gt[0] + width * gt[1] + height * gt[2]),
                                        std::abs(gt[3] + width * gt[4] + height * gt[5])});
    const double cell = std::min(std::hypot(gt[1], gt[4]), std::hypot(gt[2], gt[5]));
    if (cell < 1e-12 * far_corner) {
      char why[160];
      std::snprintf(why, sizeof why,
                    ": cells of %.3g are too small for coordinates of %.3g (doubles cannot "
                    "place them apart); shift the geotransform's origin",
                    cell, far_corner);
      throw InputError(path + why);
    }
  }
}

// The output CRS (--t-srs, the DEM's own if projected, else its UTM zone), the transformations
// to and from it, and the metric frame of the grid in it (core::GridFrame) into dem.
void set_output_crs(GDALDataset& ds, const std::string& path, const DemReadOptions& options,
                    int width, int height, DemInfo& dem) {
  const double* gt = dem.geotransform;
  // CRS: distances and volumes must be metric; project geographic coordinates.
  OGRSpatialReference src;
  const char* wkt = ds.GetProjectionRef();
  const bool has_crs = wkt && *wkt && src.importFromWkt(wkt) == OGRERR_NONE;
  src.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  if (has_crs && src.IsGeocentric()) {
    throw InputError(path + ": has a geocentric CRS (" + crs_name(src) +
                     "); a DEM needs a geographic or projected one");
  }
  OGRSpatialReference dst;
  bool transform = false;
  if (!options.t_srs.empty()) {
    if (dst.SetFromUserInput(options.t_srs.c_str()) != OGRERR_NONE) {
      throw UsageError("--t-srs " + options.t_srs + ": not a CRS GDAL knows");
    }
    if (!dst.IsProjected()) {
      throw UsageError("--t-srs " + options.t_srs + ": expected a projected CRS (metres or feet)");
    }
    if (!has_crs) throw InputError(path + ": has no CRS, so --t-srs cannot be applied");
    dst.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    transform = !src.IsSame(&dst);
  } else if (has_crs && src.IsGeographic()) {
    const double c = width / 2.0, r = height / 2.0;
    const double lon = gt[0] + c * gt[1] + r * gt[2], lat = gt[3] + c * gt[4] + r * gt[5];
    dst = utm_for(src, lon, lat);
    transform = true;
  } else if (has_crs) {
    dst = src;
  } else {
    // note: a geographic DEM that lost its CRS (an old ASCII grid, a stripped GeoTIFF) reads
    // as a cliff of metre-high walls over cells of a thousandth: the warning says so where
    // the cells are small and the corners all lie within longitudes and latitudes.
    std::string degrees;
    const double xs[4] = {gt[0], gt[0] + width * gt[1], gt[0] + height * gt[2],
                          gt[0] + width * gt[1] + height * gt[2]};
    const double ys[4] = {gt[3], gt[3] + width * gt[4], gt[3] + height * gt[5],
                          gt[3] + width * gt[4] + height * gt[5]};
    bool lon_lat = std::hypot(gt[1], gt[4]) <= 0.1 && std::hypot(gt[2], gt[5]) <= 0.1;
    for (int k = 0; k < 4; ++k)
      lon_lat = lon_lat && std::fabs(xs[k]) <= 360 && std::fabs(ys[k]) <= 90;
    if (lon_lat) {
      char cells[200];
      std::snprintf(cells, sizeof cells,
                    " (cells of %.3g x %.3g, every corner within longitudes and latitudes: if "
                    "they are degrees, give it its CRS, e.g. gdal_edit.py -a_srs EPSG:4326)",
                    std::hypot(gt[1], gt[4]), std::hypot(gt[2], gt[5]));
      degrees = cells;
    }
    dem.notes.push_back("warning: " + path + " has no CRS; treating x, y as metres" + degrees);
  }
  double jac[2][2] = {{gt[1], gt[2]}, {gt[4], gt[5]}};
  if (has_crs) {
    dem.output_crs_name = crs_name(dst);
    char* out = nullptr;
    dst.exportToWkt(&out);
    dem.output_wkt = out ? out : "";
    CPLFree(out);
    const double unit_m = dst.IsProjected() ? dst.GetLinearUnits() : 1.0;
    dem.metres_per_output_unit = unit_m;
    if (transform) {
      dem.source_geographic = src.IsGeographic();
      dem.centre_lon = gt[0] + width / 2.0 * gt[1] + height / 2.0 * gt[2];
      dem.to_output.reset(OGRCreateCoordinateTransformation(&src, &dst));
      dem.from_output.reset(OGRCreateCoordinateTransformation(&dst, &src));
      if (!dem.to_output || !dem.from_output) {
        throw InputError(path + ": cannot transform " + crs_name(src) + " to " +
                         dem.output_crs_name + " (" + last_gdal_error() + ")");
      }
      dem.notes.push_back("projecting " + path + " from " + crs_name(src) + " to " +
                          dem.output_crs_name + " (metres)");
      // The frame: the Jacobian of the projection at the DEM's centre, by central differences
      // over a quarter of the DEM (see README: the core's geometry uses this local affine map).
      const double c = width / 2.0, r = height / 2.0;
      const double hc = std::max(1.0, width / 4.0), hr = std::max(1.0, height / 4.0);
      double x[4], y[4];
      const double cs[4] = {c - hc, c + hc, c, c}, rs[4] = {r, r, r - hr, r + hr};
      for (int i = 0; i < 4; ++i) {
        x[i] = gt[0] + cs[i] * gt[1] + rs[i] * gt[2];
        y[i] = gt[3] + cs[i] * gt[4] + rs[i] * gt[5];
      }
      int ok[4] = {0, 0, 0, 0};
      if (!dem.to_output->Transform(4, x, y, nullptr, ok) || !ok[0] || !ok[1] || !ok[2] || !ok[3]) {
        // note: the points half a DEM's width and height apart round its centre (the
        // frame's), which a whole-world DEM puts 90 degrees from a UTM zone's meridian.
        throw InputError(path + ": cannot project the half of it round its centre to " +
                         dem.output_crs_name +
                         " (too wide for that CRS, or past a pole); choose one with --t-srs");
      }
      jac[0][0] = (x[1] - x[0]) / (2 * hc) * unit_m, jac[1][0] = (y[1] - y[0]) / (2 * hc) * unit_m;
      jac[0][1] = (x[3] - x[2]) / (2 * hr) * unit_m, jac[1][1] = (y[3] - y[2]) / (2 * hr) * unit_m;
    } else {
      for (auto& row : jac) row[0] *= unit_m, row[1] *= unit_m;
    }
  }
  try {
    dem.frame = core::GridFrame::from_jacobian(jac);
  } catch (const std::invalid_argument& e) {
    throw InputError(path + ": degenerate cell geometry (" + std::string(e.what()) + ")");
  }
}

// The band's cell type, no-data, scale and offset (feet made metres) and blocks into dem.
void read_band_info(GDALRasterBand* band, const std::string& path, DemInfo& dem) {
  const GDALDataType type = band->GetRasterDataType();
  dem.type_name = GDALGetDataTypeName(type) ? GDALGetDataTypeName(type) : "unknown";
  if (GDALDataTypeIsComplex(type) || type == GDT_Unknown) {
    throw InputError(path + ": band " + std::to_string(dem.band) + " holds " + dem.type_name +
                     " cells; heights must be real numbers");
  }
  int has_nodata = 0;
  if (type == GDT_Int64) {
    const std::int64_t v = band->GetNoDataValueAsInt64(&has_nodata);
    dem.nodata = static_cast<double>(v);
  } else if (type == GDT_UInt64) {
    const std::uint64_t v = band->GetNoDataValueAsUInt64(&has_nodata);
    dem.nodata = static_cast<double>(v);
  } else {
    dem.nodata = band->GetNoDataValue(&has_nodata);
  }
  dem.has_nodata = has_nodata != 0;
  dem.float32 = type == GDT_Float32;
  const char* pixel_type = band->GetMetadataItem("PIXELTYPE", "IMAGE_STRUCTURE");
  dem.signed_byte = type == GDT_Byte && pixel_type && std::string(pixel_type) == "SIGNEDBYTE";
  if (dem.signed_byte && dem.has_nodata && dem.nodata > 127) dem.nodata -= 256;
  int has_scale = 0, has_offset = 0;
  const double scale = band->GetScale(&has_scale), offset = band->GetOffset(&has_offset);
  if ((has_scale && scale != 1.0) || (has_offset && offset != 0.0)) {
    if (!std::isfinite(scale) || !std::isfinite(offset) || scale == 0.0) {
      throw InputError(path + ": band " + std::to_string(dem.band) + " has an unusable scale (" +
                       std::to_string(scale) + ") or offset (" + std::to_string(offset) + ")");
    }
    dem.scale = has_scale ? scale : 1.0;
    dem.offset = has_offset ? offset : 0.0;
    char note[160];
    std::snprintf(note, sizeof note, "%s: heights = stored value x %.9g + %.9g (band scale/offset)",
                  path.c_str(), dem.scale, dem.offset);
    dem.notes.push_back(note);
  }
  // Heights in feet, km, cm or mm (the band's unit type) become metres, as the output's
  // heights are; a unit not known is said, and its values read as metres.
  const std::string unit = band->GetUnitType() ? band->GetUnitType() : "";
  const double unit_m = height_unit_metres(unit);
  if (unit_m == 0.0) {
    dem.notes.push_back("warning: " + path + ": heights in '" + unit +
                        "' (the band's unit), a unit dpts does not know; read as metres");
  } else if (unit_m != 1.0) {
    dem.scale *= unit_m;
    dem.offset *= unit_m;
    dem.notes.push_back(path + ": heights in " + unit + " (the band's unit), converted to metres");
  }
  band->GetBlockSize(&dem.block_width, &dem.block_height);
  dem.block_width = std::max(1, dem.block_width);
  dem.block_height = std::max(1, dem.block_height);
}

}  // namespace

DemInfo open_dem(const std::string& path, const DemReadOptions& options) {
  DemInfo dem;
  dem.path = path;
  dem.stamp = DemInfo::stamp_of(path);
  check_plain_file(path);

  CPLErrorReset();
  std::unique_ptr<GDALDataset, DatasetCloser> ds(
      GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY | GDAL_OF_VERBOSE_ERROR));
  if (!ds) {
    const std::string why = CPLGetLastErrorMsg();
    throw InputError(path + ": not a raster GDAL can read" +
                     (why.empty() ? std::string() : " (" + last_gdal_error() + ")"));
  }
  if (ds->GetRasterCount() < 1) throw InputError(path + ": has no raster band");
  if (options.band < 1 || options.band > ds->GetRasterCount()) {
    throw InputError(path + ": has " + std::to_string(ds->GetRasterCount()) + " band" +
                     (ds->GetRasterCount() == 1 ? "" : "s") + "; there is no band " +
                     std::to_string(options.band));
  }
  const int width = ds->GetRasterXSize(), height = ds->GetRasterYSize();
  check_raw_size(*ds, path);
  dem.files = dataset_files(*ds, path);
  if (width < 2 || height < 2) {
    throw InputError(path + ": " + std::to_string(width) + " x " + std::to_string(height) +
                     " cells; at least 2 x 2 are needed");
  }
  if (ds->GetRasterCount() > 1) {
    dem.bands_note = path + ": " + std::to_string(ds->GetRasterCount()) + " bands; using band " +
                     std::to_string(options.band) +
                     (options.band == 1 ? " (--band picks another)" : "");
    dem.notes.push_back(dem.bands_note);
  }
  read_geotransform(*ds, path, width, height, dem);
  set_output_crs(*ds, path, options, width, height, dem);
  dem.band = options.band;
  read_band_info(ds->GetRasterBand(options.band), path, dem);
  dem.width = width;
  dem.height = height;
  return dem;
}

namespace {

// HDF5 (under GDAL's netCDF-4 and HDF5 drivers) prints its error stack on stderr, hundreds of
// lines for the optional attributes GDAL probes, from every thread that has not turned that
// off; GDAL turns it off on the thread that opens a file only. So each thread turns it off
// before its first open or read (H5Eset_auto2(H5E_DEFAULT, null, null), looked up at run time:
// dpts does not link HDF5, and GDAL may be built without it).
void quiet_hdf5_on_this_thread() {
  thread_local bool done = false;
  if (done) return;
  done = true;
  using SetAuto = int (*)(std::int64_t, void*, void*);
  static const auto set_auto = reinterpret_cast<SetAuto>(::dlsym(RTLD_DEFAULT, "H5Eset_auto2"));
  if (set_auto) set_auto(0, nullptr, nullptr);
}

}  // namespace

WindowReader::WindowReader(const DemInfo& info) : info_(info), dataset_(nullptr) {
  quiet_hdf5_on_this_thread();
  CPLErrorReset();
  dataset_ = GDALDataset::Open(info.path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY);
  if (!dataset_ || static_cast<GDALDataset*>(dataset_)->GetRasterCount() < info.band) {
    if (dataset_) GDALClose(dataset_);
    throw InputError(info.path + ": cannot open it again (" + last_gdal_error() + ")");
  }
}

WindowReader::~WindowReader() { GDALClose(dataset_); }

core::HeightGrid WindowReader::read(int col0, int row0, int width, int height,
                                    const core::Progress& progress) {
  quiet_hdf5_on_this_thread();
  info_.check_unchanged();
  GDALRasterBand* band = static_cast<GDALDataset*>(dataset_)->GetRasterBand(info_.band);
  core::HeightGrid grid;
  grid.width = width;
  grid.height = height;
  grid.z.resize(static_cast<std::size_t>(width) * height);
  // Strips of whole blocks of about 4M cells.
  const int bh = info_.block_height;
  const int strip = bh * std::max(1, (1 << 22) / std::max(1, bh * width));
  const int end = row0 + height;
  for (int r = row0; r < end;) {
    const int next = std::min(end, (r / bh) * bh + strip);
    const int rows = next - r;
    double* dst = grid.z.data() + static_cast<std::size_t>(r - row0) * width;
    CPLErrorReset();
    if (band->RasterIO(GF_Read, col0, r, width, rows, dst, width, rows, GDT_Float64, 0, 0,
                       nullptr) != CE_None) {
      throw InputError(info_.path + ": read failed at rows " + std::to_string(r) + "-" +
                       std::to_string(next - 1) + ", truncated or damaged? (" + last_gdal_error() +
                       ")");
    }
    // A mask of its own (an alpha band, a .msk, an internal mask; not one derived from the
    // no-data value, handled below): cells it masks out are no-data too.
    const int mask_flags = band->GetMaskFlags();
    if (!(mask_flags & GMF_ALL_VALID) && !(mask_flags & GMF_NODATA)) {
      std::vector<GByte> mask(static_cast<std::size_t>(width) * rows);
      if (band->GetMaskBand()->RasterIO(GF_Read, col0, r, width, rows, mask.data(), width, rows,
                                        GDT_Byte, 0, 0, nullptr) != CE_None) {
        throw InputError(info_.path + ": read failed at rows " + std::to_string(r) + "-" +
                         std::to_string(next - 1) + " of its mask (" + last_gdal_error() + ")");
      }
      for (std::size_t i = 0; i < mask.size(); ++i) {
        if (mask[i] == 0) dst[i] = std::numeric_limits<double>::quiet_NaN();
      }
    }
    r = next;
    if (progress && !progress(static_cast<double>(r - row0) / height, "read")) throw Cancelled();
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const bool f32 = info_.float32;
  const double nd = info_.nodata, scale = info_.scale, offset = info_.offset;
  // Rows [first, last) of the grid are those counted (count_rows).
  const std::size_t w = static_cast<std::size_t>(width);
  const std::size_t first =
      w * static_cast<std::size_t>(std::clamp(count_row0_ - row0, 0, height));
  const std::size_t last =
      w * static_cast<std::size_t>(std::clamp(count_row1_ - row0, 0, height));
  for (std::size_t i = 0; i < grid.z.size(); ++i) {
    double& z = grid.z[i];
    if (info_.signed_byte && z > 127) z -= 256;
    const bool is_nodata =
        info_.has_nodata && (f32 ? static_cast<float>(z) == static_cast<float>(nd) : z == nd);
    // note: cells holding a usual no-data value other than the band's (it has none, or another)
    // are heights as the band says, counted for a warning (a pit 9999 m deep where a void lost
    // its tag, or voids of -32768 under a tag of -9999).
    const bool counted = i >= first && i < last;
    if (!is_nodata && counted && (z <= -9999.0 || z >= 32767.0)) {
      for (std::size_t k = 0; k < core::kUsualNoData.size(); ++k) {
        if (z == core::kUsualNoData[k]) ++usual_[k];
      }
    }
    // note: NaN is a no-data of its own (float DEMs' usual one); an infinite height is not,
    // and is counted with the absurd ones below.
    if (is_nodata || std::isnan(z)) {
      z = nan;
      continue;
    }
    z = z * scale + offset;
    if (!(std::fabs(z) <= kMaxAbsHeight)) {
      z = nan;
      absurd_ += counted ? 1 : 0;
    }
  }
  info_.check_unchanged();  // also while it was read
  return grid;
}

core::TriMesh DemInfo::output_mesh(core::Tin tin, const std::vector<double>& z) const {
  core::TriMesh mesh;
  const std::vector<double> xy = output_xy(tin.cells);
  mesh.xyz.resize(3 * tin.cells.size());
  for (std::size_t i = 0; i < tin.cells.size(); ++i) {
    mesh.xyz[3 * i] = xy[2 * i];
    mesh.xyz[3 * i + 1] = xy[2 * i + 1];
    mesh.xyz[3 * i + 2] = z[i];
  }
  mesh.faces = std::move(tin.faces);
  return mesh;
}

core::TriMesh Dem::grid_mesh() const {
  core::Tin tin = core::grid_tin(grid, core::delaunay_diagonal(frame));
  if (tin.faces.empty()) throw InputError(path + ": " + kNothingToTriangulate);
  std::vector<double> z(tin.cells.size());
  for (std::size_t i = 0; i < tin.cells.size(); ++i) z[i] = grid.z[tin.cells[i]];
  core::TriMesh mesh = output_mesh(std::move(tin), z);
  core::fix_orientation(mesh);
  return mesh;
}

std::string absurd_heights_note(const DemInfo& dem, std::size_t count) {
  if (count == 0) return "";
  return "warning: " + dem.path + ": " + std::to_string(count) +
         " cells with heights beyond +-1e7 read as no-data";
}

std::string usual_nodata_note(const DemInfo& dem, const core::UsualNoDataCounts& counts) {
  std::size_t total = 0, most = 0;
  for (std::size_t k = 0; k < counts.size(); ++k) {
    total += counts[k];
    if (counts[k] > counts[most]) most = k;
  }
  if (total == 0) return "";
  char value[32];
  std::snprintf(value, sizeof value, "%.17g", core::kUsualNoData[most]);
  const std::string others =
      total > counts[most] ? " (" + std::to_string(total - counts[most]) + " more hold another)"
                           : "";
  const std::string head = "warning: " + dem.path + ": " + std::to_string(counts[most]) +
                           " cells hold " + value + others + ", a usual no-data value, but band " +
                           std::to_string(dem.band);
  if (!dem.has_nodata) {
    return head +
           " has none: read as heights; if they are voids, give the band its no-data value "
           "(gdal_translate -a_nodata " +
           value + " IN OUT)";
  }
  char tag[32];
  std::snprintf(tag, sizeof tag, "%.17g", dem.nodata);
  return head + "'s no-data value is " + tag +
         ": read as heights; if they are voids, set them to " + tag;
}

std::vector<std::string> height_warnings(const DemInfo& dem, std::size_t absurd_cells,
                                         const core::UsualNoDataCounts& usual) {
  std::vector<std::string> out;
  for (std::string note : {absurd_heights_note(dem, absurd_cells), usual_nodata_note(dem, usual)})
    if (!note.empty()) out.push_back(std::move(note));
  return out;
}

std::string all_nodata_message(const DemInfo& dem, std::size_t absurd_cells) {
  char nodata[48] = "";
  if (dem.has_nodata) std::snprintf(nodata, sizeof nodata, " (no-data value %.17g)", dem.nodata);
  const std::string absurd =
      absurd_cells > 0 ? ": " + std::to_string(absurd_cells) +
                             " cells hold heights beyond +-1e7, read as no-data (wrong units, "
                             "scale or offset?)"
                       : "";
  return dem.path + ": band " + std::to_string(dem.band) + " is all no-data" + nodata + absurd;
}

void check_whole_size(const DemInfo& dem, const std::string& what) {
  if (dem.cell_count() <= core::kMaxGridCells) return;
  throw InputError(dem.path + ": " + std::to_string(dem.width) + " x " +
                   std::to_string(dem.height) + " cells, more than 2^32: too many for " + what);
}

bool WindowReader::empty(int col0, int row0, int width, int height) {
  if (!info_.has_nodata) return false;  // a sparse file's missing blocks read as 0 then
  GDALRasterBand* band = static_cast<GDALDataset*>(dataset_)->GetRasterBand(info_.band);
  const int status = band->GetDataCoverageStatus(col0, row0, width, height);
  return status == GDAL_DATA_COVERAGE_STATUS_EMPTY;
}

GdalRaster::GdalRaster(const DemInfo& info)
    : core::RasterSource(info.path, info.width, info.height, info.frame, info.block_height),
      info_(info),
      reader_(info) {}

core::HeightGrid GdalRaster::read(int col0, int row0, int width, int height,
                                  Implausible* implausible) const {
  std::lock_guard<std::mutex> hold(lock_);
  const std::size_t before = reader_.absurd_cells();
  const core::UsualNoDataCounts usual_before = reader_.usual_nodata_cells();
  if (implausible) reader_.count_rows(implausible->row0, implausible->row1);
  core::HeightGrid g = reader_.read(col0, row0, width, height);
  if (implausible) {
    implausible->cells += reader_.absurd_cells() - before;
    for (std::size_t k = 0; k < usual_before.size(); ++k)
      implausible->usual[k] += reader_.usual_nodata_cells()[k] - usual_before[k];
  }
  return g;
}

bool GdalRaster::empty(int col0, int row0, int width, int height) const {
  std::lock_guard<std::mutex> hold(lock_);
  return reader_.empty(col0, row0, width, height);
}

std::string GdalRaster::no_valid_cell_message(std::size_t absurd_cells) const {
  return all_nodata_message(info_, absurd_cells);
}

Dem read_dem(DemInfo info, const core::Progress& progress) {
  check_whole_size(info, "reading it whole (32-bit cell ids)");
  Dem dem;
  static_cast<DemInfo&>(dem) = std::move(info);
  WindowReader reader(dem);
  dem.grid = reader.read(0, 0, dem.width, dem.height, progress);
  for (double z : dem.grid.z) dem.valid_cells += std::isnan(z) ? 0 : 1;
  dem.height_warnings = height_warnings(dem, reader.absurd_cells(), reader.usual_nodata_cells());
  dem.notes.insert(dem.notes.end(), dem.height_warnings.begin(), dem.height_warnings.end());
  if (dem.valid_cells == 0) throw InputError(all_nodata_message(dem, reader.absurd_cells()));
  return dem;
}

Dem read_dem(const std::string& path, const DemReadOptions& options,
             const core::Progress& progress) {
  return read_dem(open_dem(path, options), progress);
}

}  // namespace dpts::io
