// dpts as a library: simplify a DEM into a distance-preserving TIN, write it, measure it.
//
//   #include <dpts/dpts.hpp>
//   dpts::Mesh m = dpts::simplify("dem.tif");            // 10 % of the cells, qem
//   m.write("dem.ply");                                  // or .obj, .stl, .gpkg
//   dpts::Evaluation e = dpts::evaluate("dem.tif", "dem.ply");
//
// The same engines as dpts-par and dpts-eval (the same mesh for the same options); errors are
// thrown as dpts::Error (dpts/errors.hpp) with the one-line message the tools print. Thread-safe in
// the sense that separate calls may run concurrently; each call uses up to `threads` worker
// threads.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "dpts/errors.hpp"

namespace dpts {

// Called as work goes (fraction 0..1 of the stage named); return false to stop the call,
// which then throws dpts::Cancelled. May be called from worker threads, one call at a time.
using ProgressFn = std::function<bool(double fraction, std::string_view stage)>;

struct SimplifyOptions {
  // qem (default), vp-meta or pld-meta: the out-of-core piece engines; vp, pld (the paper's
  // elimination) or qslim (Garland-Heckbert): the whole DEM in memory
  std::string algo = "qem";
  double keep = 0.1;         // the fraction of the valid cells kept, 0 < keep <= 1...
  std::size_t vertices = 0;  // ...or this many vertices (>= 3) when not 0
  double max_error = 0;      // qem: vertical error bound in output CRS units (0: none)
  int levels = 4;            // at least 2^levels pieces
  int tile_mb = 256;         // memory budget of one piece
  int value_points = 20;     // vp-meta, pld-meta: random points per piece value
  std::uint64_t seed = 1;    // vp, pld, vp-meta, pld-meta (Monte Carlo volumes, piece values)
  int threads = 0;           // 0: all cores
  std::string t_srs;         // output CRS; empty: the DEM's if projected, else its UTM zone
  int band = 1;              // the band holding the heights
};

// A TIN: vertices x, y, z (output CRS), faces counter-clockwise seen from above.
struct Mesh {
  std::vector<double> xyz;                          // x0, y0, z0, x1, ...
  std::vector<std::array<std::uint32_t, 3>> faces;  // indices into the vertices
  std::string crs_wkt;                              // empty when the DEM had no CRS
  std::vector<std::string> comments;                // how it was made (written as comments)
  std::size_t input_vertices = 0;                   // the DEM's surface vertices
  // What was read of the heights that the user should know: cells of absurd heights read as
  // no-data, usual no-data values (-9999, -32768...) not the band's read as heights.
  std::vector<std::string> warnings;

  std::size_t vertex_count() const { return xyz.size() / 3; }
  // Writes the mesh atomically as PLY, OBJ, STL or GeoPackage: `format` ("ply", "obj", "stl",
  // "gpkg"), else the path's extension, else PLY. `ascii`: text PLY or STL.
  void write(const std::string& path, const std::string& format = "", bool ascii = false) const;
};

// Simplifies band `options.band` of any raster GDAL reads (a path, or /vsicurl/..., ...).
Mesh simplify(const std::string& path, const SimplifyOptions& options = {},
              const ProgressFn& progress = {});

// Simplifies heights in memory: `width` x `height` values, row-major from the top row;
// `geotransform` as GDAL's (x0, dx, rx, y0, ry, dy); `crs` as GDAL reads it (WKT, EPSG:n,
// PROJ; empty: none, read as metres); cells equal to `nodata` (or NaN) have no height.
Mesh simplify(const double* heights, int width, int height,
              const std::array<double, 6>& geotransform, const std::string& crs, double nodata,
              const SimplifyOptions& options = {}, const ProgressFn& progress = {});

struct EvaluateOptions {
  int points = 100;  // random points per set
  int sets = 3;      // independent sets
  std::uint64_t seed = 1;
  int threads = 0;    // 0: all cores
  std::string t_srs;  // the mesh's CRS when the DEM was simplified with t_srs
  int band = 1;       // the band holding the heights (as simplified)
};

// dpts-eval's figures for a mesh file made from a DEM: PLY, OBJ, STL (binary or ASCII) or
// GeoPackage, as Mesh::write writes them.
struct Evaluation {
  double distance_error = 0;       // mean over the sets of mean |GD_T - GD_T'| / GD_T
  std::vector<double> set_errors;  // per set
  double vertical_rmse = 0, vertical_max = 0;
  std::size_t mesh_vertices = 0, mesh_faces = 0, pairs_measured = 0;
  std::string json;  // every figure, as dpts-eval --json prints it
};

Evaluation evaluate(const std::string& dem, const std::string& mesh,
                    const EvaluateOptions& options = {}, const ProgressFn& progress = {});

// The library's version, "0.1.0".
std::string version();

}  // namespace dpts
