// Helpers shared by the tests: hand-made grids, temporary folders, running executables.
#pragma once

#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "core/elimination.hpp"
#include "core/grid.hpp"
#include "core/steiner_graph.hpp"

namespace dpts::test {

// A width x height grid with z = f(col, row); f returning NaN makes a no-data cell.
core::HeightGrid make_grid(int width, int height, const std::function<double(int, int)>& f);

// Small grids with random voids, for tests against a definition: grid `trial` of a fixed
// sequence (seed), 1 to 8 cells a side (one row or column included), 0 to 3 quarters of its
// cells no-data (about), z = f(col, row) elsewhere.
core::HeightGrid random_voids_grid(std::uint32_t seed, int trial,
                                   const std::function<double(int, int)>& f);

// Hills with voids placed across the piece engines' first split lines: a round void in the
// middle, a long straight one-row river, a notch in the east edge and a cut corner.
core::HeightGrid hills_with_voids(int width = 96, int height = 80);

// The grid TIN of hills with a void, a notch and a cut corner, vertices at (col, -row) so
// faces are counter-clockwise (the collapse tests' input). With opposites given: grid_tin's
// pairing of its half-edges (as fix_orientation leaves it).
core::TriMesh hills_mesh(int width = 40, int height = 32,
                         std::vector<std::uint32_t>* opposites = nullptr);

// An n-sided pyramid (a polyhedral cone): apex 0 at (0, 0, height), base vertices 1..n on the
// circle of `radius` at z = 0, faces (0, i, i + 1) counter-clockwise; no base face.
core::TriMesh pyramid_mesh(int n, double radius, double height);

// Positions (x, y) of the vertices on a mesh's border.
std::set<std::pair<double, double>> border_points(const core::TriMesh& mesh);

// A fresh, empty temporary folder, removed with its contents when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  std::vector<std::string> files() const;  // names of the entries, sorted

 private:
  std::filesystem::path path_;
};

struct RunResult {
  int exit_code = -1;
  std::string out, err;
  double seconds_after_signal = -1;  // from the signal (RunOptions) to the exit; -1: none sent
};

// How to run a child: limits and an interruption.
struct RunOptions {
  std::size_t file_size_limit = 0;      // RLIMIT_FSIZE in bytes (0: none); SIGXFSZ ignored, so a
                                        // write past it fails like one to a full disk
  std::string signal_when;              // send `signal` once stderr contains this text...
  double signal_after_s = 0;            // ...or once this many seconds have passed (0: never)
  int signal = 15;                      // SIGTERM
  std::string stdout_to;                // a file stdout goes to (e.g. /dev/full), not captured
  std::string stdin_from;               // a file stdin reads (empty: /dev/null)
  std::string cwd;                      // the child's working folder (empty: ours)
  bool close_stderr = false;            // start the child with descriptor 2 closed (2>&-)
  bool close_stdout = false;            // start the child with descriptor 1 closed (>&-)
  std::size_t address_space_limit = 0;  // RLIMIT_AS in bytes (0: none)
  int cpu_limit_s = 0;  // RLIMIT_CPU's soft limit (0: none): SIGXCPU kills past it (no core)
  // A child still running after this many seconds is killed (SIGKILL: exit code 137) and
  // reported with its command and stderr, so that a hang fails its own checks, named, before
  // ctest's TIMEOUT of 1200 s ends the whole test (the slowest test, under ThreadSanitizer,
  // takes 227 s in all).
  double wall_limit_s = 900;
  // Environment variables set (NAME, value) in the child only, over ours.
  std::vector<std::pair<std::string, std::string>> env;
};

// A file's bytes ("" when it cannot be read); a FIFO is read to its end.
std::string file_bytes(const std::filesystem::path& path);

// Runs an executable with arguments (no shell), capturing stdout and stderr.
RunResult run(const std::string& exe, const std::vector<std::string>& args,
              const RunOptions& options = {});

// Writes a single-band Float32 GeoTIFF of the grid; NaN cells get the nodata value.
// geotransform and wkt as GDAL takes them (wkt may be empty).
void write_geotiff(const std::filesystem::path& path, const core::HeightGrid& grid,
                   const std::vector<double>& geotransform, const std::string& wkt,
                   double nodata = -9999.0);

// Any GeoTIFF: cell type by GDAL name, bands (each the grid's values plus 1000 x its band
// index - 1), no-data (NaN cells get it; without one they are written as NaN), creation
// options (e.g. PIXELTYPE=SIGNEDBYTE), band scale and offset.
struct RasterSpec {
  std::string type = "Float32";
  int bands = 1;
  std::vector<double> geotransform = {0, 1, 0, 0, 0, -1};
  std::string wkt;
  bool has_nodata = false;
  double nodata = 0;
  std::vector<std::string> creation_options;
  double scale = 1, offset = 0;
  std::string driver = "GTiff";  // GDAL's name of the format written
};
void write_raster(const std::filesystem::path& path, const core::HeightGrid& grid,
                  const RasterSpec& spec);

// WKT of an EPSG code.
std::string epsg_wkt(int code);

// Grid positions (col, row) of a TIN's vertices, for footprint checks.
std::vector<double> grid_xy(const core::HeightGrid& grid, const core::Tin& tin);

// Frame positions of a TIN's vertices (cells of grid g).
std::vector<double> frame_xy(const core::HeightGrid& g, const core::GridFrame& f,
                             const core::Tin& tin);

// Number of interior edges whose opposite vertex lies strictly inside the circumcircle.
std::size_t non_delaunay_edges(const std::vector<double>& xy, const core::Tin& tin);

// Checks (Catch2 CHECKs) every structural property of a simplified TIN over grid g:
// counter-clockwise faces, proper edges, area = the footprint's, no face over no-data,
// Delaunay, cells sorted, every vertex used.
void check_tin(const core::HeightGrid& g, const core::Tin& tin, const core::GridFrame& f = {});

// The shared real-DEM folder (../shared/data).
std::string shared_data(const std::string& name);

}  // namespace dpts::test
