// Reading a DEM (one band of any raster GDAL opens) into a height grid, with its CRS handling.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/elimination.hpp"
#include "core/grid.hpp"
#include "core/raster_source.hpp"
#include "core/steiner_graph.hpp"

class OGRCoordinateTransformation;

namespace dpts::io {

struct DemReadOptions {
  // Output CRS as GDAL understands it (EPSG:32633, a WKT, a PROJ string). Empty: keep a
  // projected CRS as it is, and project a geographic one to the UTM zone of the DEM's centre.
  std::string t_srs;
  int band = 1;  // the raster band holding the heights (1-based)
};

// Heights beyond +-1e7 (10,000 km in metres; still beyond Everest in millimetres) are not
// terrain in any unit a DEM uses: undeclared no-data such as -3.4e38 or 1e30, or infinite.
// WindowReader reads them as no-data and counts them (NaN cells too, not counted).
inline constexpr double kMaxAbsHeight = 1e7;

struct TransformDeleter {
  void operator()(OGRCoordinateTransformation* t) const;
};

// Everything about a DEM but its heights: size, geometry, CRS handling, no-data. Opening one
// reads no heights, so a DEM of any size can be described, divided and read window by window.
struct DemInfo {
  std::string path;
  int width = 0, height = 0;
  core::GridFrame frame;           // metric frame of the grid (see core/grid.hpp)
  std::string output_wkt;          // CRS of the output coordinates; empty if the DEM has none
  std::string output_crs_name;     // short name for messages
  std::vector<std::string> notes;  // what the user should know (CRS choices, warnings)
  // The plain files the dataset is read from (GDAL's file list: an ENVI .hdr, a VRT's
  // sources; the archive behind /vsizip/ and the like), so that no output is written over one.
  std::vector<std::string> files;
  double metres_per_output_unit = 1.0;
  // Whether the DEM's CRS is geographic, and its centre's longitude: points mapped back from the
  // output CRS are brought to the DEM's own range of longitudes (0..360, across 180).
  bool source_geographic = false;
  double centre_lon = 0;
  double geotransform[6] = {0, 1, 0, 0, 0, -1};
  int band = 1;            // the band read (1-based)
  std::string bands_note;  // of a raster of several bands, which is read (also in notes)
  std::string type_name;   // GDAL's name of the cell type (Int16, Float32...)
  bool has_nodata = false;
  double nodata = 0;
  bool float32 = false;          // band type Float32: no-data compares in single precision
  bool signed_byte = false;      // Byte band marked PIXELTYPE=SIGNEDBYTE (values -128..127)
  double scale = 1, offset = 0;  // height = stored value * scale + offset (band metadata)
  int block_width = 0, block_height = 0;
  std::unique_ptr<OGRCoordinateTransformation, TransformDeleter> to_output;    // null: identity
  std::unique_ptr<OGRCoordinateTransformation, TransformDeleter> from_output;  // null: identity

  // The file as it was opened (device, inode, size, modification time; not for GDAL's /vsi
  // paths): every window read checks that it is still the same file, so a DEM replaced or
  // rewritten mid-run fails the run instead of mixing two DEMs in one TIN.
  struct FileStamp {
    bool set = false;
    std::uint64_t device = 0, inode = 0;
    std::int64_t size = 0, mtime_ns = 0;
    bool operator==(const FileStamp& o) const {
      return set == o.set && device == o.device && inode == o.inode && size == o.size &&
             mtime_ns == o.mtime_ns;
    }
  };
  FileStamp stamp;
  static FileStamp stamp_of(const std::string& path);
  // Throws InputError when the file is no longer the one opened.
  void check_unchanged() const;

  std::size_t cell_count() const { return static_cast<std::size_t>(width) * height; }

  // Bytes read_dem and a whole-DEM run hold per cell of the raster (the grid, its TIN and
  // the elimination's state), measured on real DEMs with some margin: see README.
  static constexpr std::size_t kWholeDemBytesPerCell = 320;

  // Cell centres of the given cells (row-major indices) in the output CRS: x0, y0, x1, ...
  // Throws IoError if the CRS transformation fails. Not thread-safe (one transformation).
  std::vector<double> output_xy(const std::vector<std::uint32_t>& cells) const;

  // A TIN over this DEM as a mesh in the output CRS: its cells' centres with heights z (one
  // per cell), its faces. Throws as output_xy.
  core::TriMesh output_mesh(core::Tin tin, const std::vector<double>& z) const;

  // The same for any grid positions (col, row; cell centres at integers): x0, y0, ...
  std::vector<double> output_xy_of_grid(const std::vector<double>& grid_xy) const;
  // The same, safe to call from concurrent tasks: with a transformation of its own (a copy
  // made for the call).
  std::vector<double> output_xy_of_grid_concurrent(const std::vector<double>& grid_xy) const;

  // A mesh built in the frame (u, w, heights in frame units: core::GridFrame) moved to the
  // output CRS in place: x, y through the grid positions (the frame is linear), heights in
  // metres. Throws IoError if the CRS transformation fails. Safe from concurrent tasks.
  void frame_mesh_to_output(core::TriMesh& mesh) const;

  // Grid positions (col, row; cell centres at integers) of points given in the output CRS:
  // the inverse of output_xy. Throws IoError if the CRS transformation fails.
  std::vector<double> grid_xy(const std::vector<double>& output_xy) const;

  // A point map from the output CRS to grid positions (col, row), as grid_xy, with a
  // transformation of its own: concurrent tasks each make their own. False where the
  // transformation fails.
  std::function<bool(double x, double y, double& col, double& row)> grid_of_output_fn() const;

  // For a reprojected DEM (to_output set): a thread-safe test for core's outline rule, for an
  // Eliminator working on the window of `window_width` columns whose first cell is (col0,
  // row0) (window-local cell indices). It accepts the straight outline chord from cell a to
  // cell b when the exact projection of the outline cell halfway between them lies within
  // tolerance_m of the chord (the grid line is a smooth curve in the output CRS, farthest from
  // its chord near the middle). Null for a DEM whose frame is exact.
  std::function<bool(std::uint64_t, std::uint64_t)> outline_chord_test(double tolerance_m,
                                                                       int col0 = 0, int row0 = 0,
                                                                       int window_width = 0) const;

  // The tolerance dpts-par uses for outline_chord_test: 1 % of a cell.
  double outline_tolerance_m() const;

 private:
  std::vector<double> project_grid(const std::vector<double>& grid_xy,
                                   OGRCoordinateTransformation* ct) const;
};

// A DEM in memory: its description and all its heights (NaN = no-data).
struct Dem : DemInfo {
  core::HeightGrid grid;
  std::size_t valid_cells = 0;
  // Warnings of the heights read (absurd ones read as no-data, usual no-data values read as
  // heights; also in notes): a measure against such cells is told of them.
  std::vector<std::string> height_warnings;

  // The DEM's full-resolution grid TIN (core::grid_tin with the frame's Delaunay diagonal: the
  // TIN the elimination starts from) in the output CRS, faces counter-clockwise; vertices in
  // surface-cell order. Throws InputError when the DEM has no face.
  core::TriMesh grid_mesh() const;
};

// Opens the band of `path` and checks it without reading heights: throws InputError naming the
// file (missing, not a raster, no such band, complex cells, too small or too large, degenerate
// geotransform), or UsageError for a bad --t-srs. GDALAllRegister() must have been called.
DemInfo open_dem(const std::string& path, const DemReadOptions& options);

// Reads windows of the DEM's band through its own GDAL dataset handle (GDAL handles are not
// thread-safe: one reader per thread or task). No-data, NaN and infinite heights become NaN.
class WindowReader {
 public:
  explicit WindowReader(const DemInfo& info);
  ~WindowReader();
  WindowReader(const WindowReader&) = delete;
  WindowReader& operator=(const WindowReader&) = delete;

  // Heights of columns [col0, col0 + width) and rows [row0, row0 + height), read in strips of
  // whole blocks. Throws InputError naming the file and rows when GDAL fails. Calls progress
  // (if given) with stage "read" after each strip.
  core::HeightGrid read(int col0, int row0, int width, int height,
                        const core::Progress& progress = nullptr);

  // Whether GDAL knows the window holds no data without reading it (blocks never written to a
  // sparse file, GDALGetDataCoverageStatus): it then reads as no-data. False when in doubt
  // (most formats), and for a band without a no-data value (missing blocks read as 0 there).
  bool empty(int col0, int row0, int width, int height);

  // Cells read so far whose height was beyond kMaxAbsHeight (read as no-data), counting only
  // rows in [row0, row1) as set by count_rows (all rows by default: windows read twice count
  // twice; a streaming pass with overlapping strips narrows the rows to each strip's own).
  std::size_t absurd_cells() const { return absurd_; }
  // The cells read so far (in the same rows) holding each of core::kUsualNoData, but for the
  // band's no-data value.
  const core::UsualNoDataCounts& usual_nodata_cells() const { return usual_; }
  void count_rows(int row0, int row1) { count_row0_ = row0, count_row1_ = row1; }

 private:
  const DemInfo& info_;
  void* dataset_;  // GDALDataset*
  std::size_t absurd_ = 0;
  core::UsualNoDataCounts usual_{};
  int count_row0_ = 0, count_row1_ = std::numeric_limits<int>::max();
};

// Throws InputError naming the file when the DEM has more than core::kMaxGridCells cells (a
// DEM read whole is one core::HeightGrid; the piece engine of qem reads larger ones), for
// `what` (what cannot take it, and what can instead).
void check_whole_size(const DemInfo& dem, const std::string& what);

// The DEM as the piece engines read it (core::RasterSource): one GDAL handle, opened here for
// the whole run and shared by every task under a lock (GDAL handles are not thread-safe; a
// piece's read is a small share of its work). The description must outlive it.
class GdalRaster final : public core::RasterSource {
 public:
  explicit GdalRaster(const DemInfo& info);
  core::HeightGrid read(int col0, int row0, int width, int height,
                        Implausible* implausible = nullptr) const override;
  bool empty(int col0, int row0, int width, int height) const override;
  std::string no_valid_cell_message(std::size_t absurd_cells) const override;
  bool reprojected() const override { return info_.to_output != nullptr; }
  std::vector<double> output_xy_of_grid(const std::vector<double>& grid_xy) const override {
    return info_.output_xy_of_grid_concurrent(grid_xy);
  }
  double metres_per_output_unit() const override { return info_.metres_per_output_unit; }
  std::function<bool(double, double, double&, double&)> grid_of_output_fn() const override {
    return info_.grid_of_output_fn();
  }
  std::function<bool(std::uint64_t, std::uint64_t)> outline_chord_test(
      int col0, int row0, int window_width) const override {
    return info_.outline_chord_test(info_.outline_tolerance_m(), col0, row0, window_width);
  }
  void frame_mesh_to_output(core::TriMesh& mesh) const override {
    info_.frame_mesh_to_output(mesh);
  }

 private:
  const DemInfo& info_;
  mutable std::mutex lock_;
  mutable WindowReader reader_;
};

// A warning for `count` cells read as no-data because of absurd heights ("" when none).
std::string absurd_heights_note(const DemInfo& dem, std::size_t count);

// A warning for cells holding usual no-data values other than the band's (it has none, or
// another; counts per core::kUsualNoData; "" when none): read as heights, maybe voids that lost
// their tag.
std::string usual_nodata_note(const DemInfo& dem, const core::UsualNoDataCounts& counts);

// Those two warnings, the empty ones left out.
std::vector<std::string> height_warnings(const DemInfo& dem, std::size_t absurd_cells,
                                         const core::UsualNoDataCounts& usual);

// The message for a DEM whose band has no valid cell, naming the file and the band, and how
// many cells held heights beyond +-1e7 (read as no-data), if any.
std::string all_nodata_message(const DemInfo& dem, std::size_t absurd_cells);

// Reads the band of `path` (options.band), at most core::kMaxGridCells cells. No-data cells, NaN,
// infinite and absurd heights become NaN. Checks the raster before reading it and throws InputError
// naming the file (not a raster, no band, degenerate geotransform, too large), or UsageError for a
// bad --t-srs. Calls progress with stage "read". GDALAllRegister() must have been called.
Dem read_dem(const std::string& path, const DemReadOptions& options,
             const core::Progress& progress);

// The same for a DEM already opened (and checked) by open_dem.
Dem read_dem(DemInfo info, const core::Progress& progress);

}  // namespace dpts::io
