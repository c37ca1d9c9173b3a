// Reading a DEM with GDAL: block-aligned strips of band 1, no-data handling, CRS choice.
#include "io/dem_reader.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>

#include "core/errors.hpp"

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
  const int zone = std::clamp(static_cast<int>(std::floor((lon + 180.0) / 6.0)) + 1, 1, 60);
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

std::vector<double> Dem::output_xy(const std::vector<std::uint32_t>& cells) const {
  const double* gt = geotransform;
  std::vector<double> x(cells.size()), y(cells.size());
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const double c = cells[i] % grid.width + 0.5, r = cells[i] / grid.width + 0.5;
    x[i] = gt[0] + c * gt[1] + r * gt[2];
    y[i] = gt[3] + c * gt[4] + r * gt[5];
  }
  if (to_output) {
    std::vector<int> ok(cells.size(), 0);
    if (!to_output->Transform(static_cast<int>(cells.size()), x.data(), y.data(), nullptr,
                              ok.data()) ||
        std::find(ok.begin(), ok.end(), 0) != ok.end()) {
      throw IoError(path + ": cannot transform cell centres to " + output_crs_name + " (" +
                    last_gdal_error() + ")");
    }
  }
  std::vector<double> xy(2 * cells.size());
  for (std::size_t i = 0; i < cells.size(); ++i) xy[2 * i] = x[i], xy[2 * i + 1] = y[i];
  return xy;
}

std::vector<double> Dem::grid_xy(const std::vector<double>& output_xy) const {
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
  // Invert the geotransform: (x - gt0, y - gt3) = A (col + 0.5, row + 0.5).
  const double* gt = geotransform;
  const double det = gt[1] * gt[5] - gt[2] * gt[4];
  std::vector<double> grid(2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const double dx = x[i] - gt[0], dy = y[i] - gt[3];
    grid[2 * i] = (gt[5] * dx - gt[2] * dy) / det - 0.5;
    grid[2 * i + 1] = (-gt[4] * dx + gt[1] * dy) / det - 0.5;
  }
  return grid;
}

std::function<bool(std::uint32_t, std::uint32_t)> Dem::outline_chord_test(
    double tolerance_m) const {
  if (!to_output) return nullptr;
  // Outline cells: valid cells with a no-data or missing 8-neighbour. Their exact positions.
  const core::HeightGrid& g = grid;
  std::vector<std::uint32_t> outline;
  for (int r = 0; r < g.height; ++r) {
    for (int c = 0; c < g.width; ++c) {
      if (!g.is_valid(c, r)) continue;
      bool edge = false;
      for (int dr = -1; dr <= 1 && !edge; ++dr) {
        for (int dc = -1; dc <= 1 && !edge; ++dc) edge = !g.is_valid(c + dc, r + dr);
      }
      if (edge) outline.push_back(static_cast<std::uint32_t>(g.index(c, r)));
    }
  }
  auto xy = std::make_shared<const std::vector<double>>(output_xy(outline));
  auto cells = std::make_shared<const std::vector<std::uint32_t>>(std::move(outline));
  const double unit_m = metres_per_output_unit;
  const int width = g.width;
  return [xy, cells, width, unit_m, tolerance_m](std::uint32_t a, std::uint32_t b) {
    auto position = [&](std::uint32_t cell, double& x, double& y) {
      const auto it = std::lower_bound(cells->begin(), cells->end(), cell);
      if (it == cells->end() || *it != cell) return false;
      const std::size_t i = static_cast<std::size_t>(it - cells->begin());
      x = (*xy)[2 * i], y = (*xy)[2 * i + 1];
      return true;
    };
    const long ca = static_cast<long>(a % width), ra = static_cast<long>(a / width);
    const long cb = static_cast<long>(b % width), rb = static_cast<long>(b / width);
    const long steps = std::max(std::labs(cb - ca), std::labs(rb - ra));
    if (steps < 2) return true;
    // The cell halfway along the grid line (a and b lie on one row, column or diagonal).
    const long half = steps / 2;
    const auto mid = static_cast<std::uint32_t>((ra + (rb - ra) / steps * half) * width +
                                                (ca + (cb - ca) / steps * half));
    double xa, ya, xb, yb, xm, ym;
    if (!position(a, xa, ya) || !position(b, xb, yb) || !position(mid, xm, ym)) return false;
    const double dx = xb - xa, dy = yb - ya;
    const double len = std::hypot(dx, dy);
    const double off = len > 0 ? std::fabs(dx * (ym - ya) - dy * (xm - xa)) / len : 0.0;
    return off * unit_m <= tolerance_m;
  };
}

Dem read_dem(const std::string& path, const DemReadOptions& options,
             const core::Progress& progress) {
  Dem dem;
  dem.path = path;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path + ": no such file");
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path + ": is a directory, not a raster");

  CPLErrorReset();
  std::unique_ptr<GDALDataset, DatasetCloser> ds(
      GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY | GDAL_OF_VERBOSE_ERROR));
  if (!ds) {
    const std::string why = CPLGetLastErrorMsg();
    throw InputError(path + ": not a raster GDAL can read" +
                     (why.empty() ? std::string() : " (" + last_gdal_error() + ")"));
  }
  if (ds->GetRasterCount() < 1) throw InputError(path + ": has no raster band");
  const int width = ds->GetRasterXSize(), height = ds->GetRasterYSize();
  if (width < 2 || height < 2) {
    throw InputError(path + ": " + std::to_string(width) + " x " + std::to_string(height) +
                     " cells; at least 2 x 2 are needed");
  }
  if (static_cast<double>(width) * height >= 4294967295.0) {
    throw InputError(path + ": " + std::to_string(width) + " x " + std::to_string(height) +
                     " cells is too many for one piece (limit 2^32)");
  }
  if (ds->GetRasterCount() > 1) {
    dem.notes.push_back(path + ": " + std::to_string(ds->GetRasterCount()) +
                        " bands; using band 1");
  }
  double* gt = dem.geotransform;
  const bool has_gt = ds->GetGeoTransform(gt) == CE_None;
  if (!has_gt) {
    gt[0] = 0, gt[1] = 1, gt[2] = 0, gt[3] = 0, gt[4] = 0, gt[5] = -1;
    dem.notes.push_back("warning: " + path + " has no geotransform; using 1 m cells");
  }
  for (int i = 0; i < 6; ++i) {
    if (!std::isfinite(gt[i])) throw InputError(path + ": geotransform is not finite");
  }
  if (gt[1] * gt[5] - gt[2] * gt[4] == 0.0) {
    throw InputError(path + ": geotransform has zero cell size (" + std::to_string(gt[1]) + ", " +
                     std::to_string(gt[5]) + ")");
  }

  // CRS: distances and volumes must be metric; project geographic coordinates.
  OGRSpatialReference src;
  const char* wkt = ds->GetProjectionRef();
  const bool has_crs = wkt && *wkt && src.importFromWkt(wkt) == OGRERR_NONE;
  src.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
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
    dem.notes.push_back("warning: " + path + " has no CRS; treating x, y as metres");
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
        throw InputError(path + ": cannot project its centre to " + dem.output_crs_name);
      }
      jac[0][0] = (x[1] - x[0]) / (2 * hc) * unit_m, jac[1][0] = (y[1] - y[0]) / (2 * hc) * unit_m;
      jac[0][1] = (x[3] - x[2]) / (2 * hr) * unit_m, jac[1][1] = (y[3] - y[2]) / (2 * hr) * unit_m;
    } else {
      for (auto& row : jac) row[0] *= unit_m, row[1] *= unit_m;
    }
  }
  try {
    dem.frame = core::GridFrame::from_jacobian(jac);
  } catch (const std::invalid_argument&) {
    throw InputError(path + ": degenerate cell geometry (zero or non-finite cell size)");
  }

  // Read band 1 in block-aligned strips of rows.
  GDALRasterBand* band = ds->GetRasterBand(1);
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  const bool float32 = band->GetRasterDataType() == GDT_Float32;
  int block_x = 0, block_y = 0;
  band->GetBlockSize(&block_x, &block_y);
  const int strip = std::max(1, block_y) * std::max(1, (1 << 22) / (std::max(1, block_y) * width));
  dem.grid.width = width;
  dem.grid.height = height;
  dem.grid.z.resize(static_cast<std::size_t>(width) * height);
  for (int r0 = 0; r0 < height; r0 += strip) {
    const int rows = std::min(strip, height - r0);
    double* dst_rows = dem.grid.z.data() + static_cast<std::size_t>(r0) * width;
    CPLErrorReset();
    if (band->RasterIO(GF_Read, 0, r0, width, rows, dst_rows, width, rows, GDT_Float64, 0, 0,
                       nullptr) != CE_None) {
      throw InputError(path + ": read failed at rows " + std::to_string(r0) + "-" +
                       std::to_string(r0 + rows - 1) + " (" + last_gdal_error() + ")");
    }
    if (progress && !progress(static_cast<double>(r0 + rows) / height, "read")) throw Cancelled();
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (double& z : dem.grid.z) {
    const bool is_nodata =
        has_nodata && (float32 ? static_cast<float>(z) == static_cast<float>(nodata) : z == nodata);
    if (is_nodata || !std::isfinite(z)) {
      z = nan;
    } else {
      ++dem.valid_cells;
    }
  }
  if (dem.valid_cells == 0) {
    throw InputError(path + ": band 1 is all no-data" +
                     (has_nodata ? " (" + std::to_string(nodata) + ")" : std::string()));
  }
  return dem;
}

}  // namespace dpts::io
