// The bad-input table (see bad_inputs.hpp).
#include "cli/bad_inputs.hpp"

#include <sys/stat.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <vector>

#include "test_support.hpp"

namespace dpts::test {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double hill(int c, int r) { return 200.0 + 30.0 * std::sin(0.3 * c) + 2.0 * r; }

}  // namespace

std::vector<BadInput> make_bad_inputs(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  const std::string utm = epsg_wkt(32611);
  const std::vector<double> gt = {400000, 10, 0, 3800000, 0, -10};
  auto path = [&](const std::string& name) { return (dir / name).string(); };
  const std::string out = path("out.ply");
  auto raster = [&](const std::string& name, int w, int h, auto f, RasterSpec spec = {}) {
    if (spec.geotransform == std::vector<double>{0, 1, 0, 0, 0, -1}) spec.geotransform = gt;
    if (spec.wkt.empty()) spec.wkt = utm;
    write_raster(dir / name, make_grid(w, h, f), spec);
    return path(name);
  };
  std::vector<BadInput> cases;
  auto add = [&](std::string what, std::vector<std::string> args, int code, std::string msg) {
    cases.push_back({std::move(what), std::move(args), code, std::move(msg), "", 0});
  };

  // Files that are not rasters, or not whole.
  add("missing file", {path("missing.tif"), out}, 1, path("missing.tif") + ": no such file");
  add("missing file, a line break in its name", {path("miss\ning.tif"), out}, 1,
      path("miss") + "\\ning.tif: no such file");  // one line: the break written \n
  fs::create_directories(dir / "folder.tif");
  add("a directory", {path("folder.tif"), out}, 1,
      path("folder.tif") + ": is a directory, not a raster");
  std::ofstream(dir / "empty.tif").close();
  add("empty file", {path("empty.tif"), out}, 1,
      path("empty.tif") + ": not a raster GDAL can read");
  std::ofstream(dir / "notes.tif") << "these are not heights\n";
  add("text file", {path("notes.tif"), out}, 1, path("notes.tif") + ": not a raster GDAL can read");
  {
    // An uncompressed GeoTIFF cut in the middle of its cells. It has a raw layout (one strip),
    // so its size is checked as a raw raster's when it is opened.
    const std::string cut = raster("truncated.tif", 200, 200, hill);
    fs::resize_file(cut, fs::file_size(cut) / 2);
    const std::string why = cut + ": truncated: its data file " + cut + " has ";
    add("truncated GeoTIFF (vp)", {"--algo", "vp", cut, out}, 1, why);
    add("truncated GeoTIFF (vp-meta)", {"--algo", "vp-meta", cut, out}, 1, why);
    add("truncated GeoTIFF (qslim)", {"--algo", "qslim", cut, out}, 1, why);
    add("truncated GeoTIFF (qem)", {"--algo", "qem", cut, out}, 1, why);
    // A tiled, compressed GeoTIFF cut short: its pieces' reads fail on worker threads, which
    // must not print GDAL's own lines beside the one message.
    RasterSpec tiled;
    tiled.creation_options = {"TILED=YES", "COMPRESS=DEFLATE"};
    const std::string cut_tiles = raster(
        "cut_tiles.tif", 600, 600, [](int c, int r) { return hill(c, r) + 0.01 * c * r; }, tiled);
    fs::resize_file(cut_tiles, fs::file_size(cut_tiles) / 2);
    add("truncated tiled GeoTIFF, read by workers", {"--threads", "2", cut_tiles, out}, 1,
        cut_tiles + ": read failed at rows ");
    // An ENVI raster (a text header and raw cells) cut short: GDAL reads zeros past its end.
    std::ofstream(dir / "cut.hdr") << "ENVI\nsamples = 20\nlines = 15\nbands = 1\n"
                                      "header offset = 0\ndata type = 4\ninterleave = bsq\n"
                                      "byte order = 0\n"
                                      "map info = {UTM, 1, 1, 400000, 3800000, 10, 10, 11, North, "
                                      "WGS-84}\n";
    {
      std::ofstream raw(dir / "cut.envi", std::ios::binary);
      const std::vector<float> cells(20 * 8, 100.0f);  // 8 of 15 rows
      raw.write(reinterpret_cast<const char*>(cells.data()),
                static_cast<std::streamsize>(cells.size() * sizeof(float)));
    }
    add("truncated ENVI raster", {path("cut.envi"), out}, 1,
        path("cut.envi") + ": truncated: its data file " + path("cut.envi") +
            " has 640 bytes, its cells need 1200");
  }

  {
    // netCDF classic files cut short (CDF-1 and CDF-2): their library reads zeros past the
    // end, so the size the header declares is checked when the file is opened.
    for (const std::string format : {"NC", "NC2"}) {
      RasterSpec nc;
      nc.driver = "netCDF";
      nc.creation_options = {"FORMAT=" + format};
      const std::string name = "cut_" + format + ".nc";
      const std::string cut = raster(name, 40, 30, hill, nc);
      const auto full = fs::file_size(cut);
      fs::resize_file(cut, full - 1);
      add("truncated netCDF (" + format + ")", {cut, out}, 1,
          cut + ": truncated: " + cut + " has " + std::to_string(full - 1) +
              " bytes, its netCDF header declares " + std::to_string(full));
      add("truncated netCDF subdataset (" + format + ")", {"NETCDF:\"" + cut + "\":Band1", out}, 1,
          "NETCDF:\"" + cut + "\":Band1: truncated: " + cut + " has ");
    }
  }

  // Too few valid cells.
  RasterSpec nodata;
  nodata.has_nodata = true;
  nodata.nodata = -9999;
  const std::string all_void = raster("void.tif", 8, 8, [](int, int) { return kNaN; }, nodata);
  add("all no-data (vp)", {all_void, out}, 1, all_void + ": band 1 is all no-data (no-data value -9999)");
  add("all no-data (vp-meta)", {"--algo", "vp-meta", all_void, out}, 1,
      all_void + ": band 1 is all no-data (no-data value -9999)");
  {
    // A geographic one: the note of its projection to UTM is held back until its cells are
    // counted, so the refusal is the one line (the piece engines count after opening).
    RasterSpec geographic = nodata;
    geographic.wkt = epsg_wkt(4326);
    geographic.geotransform = {7.0, 0.001, 0, 46.0, 0, -0.001};
    const std::string geo_void = raster(
        "geo_void.tif", 8, 8, [](int, int) { return kNaN; }, geographic);
    add("all no-data, geographic (qem)", {geo_void, out}, 1,
        geo_void + ": band 1 is all no-data (no-data value -9999)");
    add("all no-data, geographic (vp-meta)", {"--algo", "vp-meta", geo_void, out}, 1,
        geo_void + ": band 1 is all no-data (no-data value -9999)");
    // Every height absurd (read as no-data): the message says so.
    const std::string huge = raster("huge.tif", 8, 8, [](int, int) { return 3e7; });
    const std::string why =
        huge + ": band 1 is all no-data: 64 cells hold heights beyond +-1e7, read as no-data";
    add("every height beyond 1e7 (qem)", {huge, out}, 1, why);
    add("every height beyond 1e7 (vp)", {"--algo", "vp", huge, out}, 1, why);
  }
  const std::string one = raster(
      "one_cell.tif", 8, 8, [](int c, int r) { return c == 3 && r == 3 ? 5.0 : kNaN; }, nodata);
  add("one valid cell", {one, out}, 1, one + ": no three neighbouring valid cells");
  const std::string line =
      raster("collinear.tif", 8, 8, [](int, int r) { return r == 4 ? 5.0 : kNaN; }, nodata);
  add("valid cells on one line (vp)", {line, out}, 1, line + ": no three neighbouring valid cells");
  add("valid cells on one line (vp-meta)", {"--algo", "vp-meta", line, out}, 1,
      line + ": no three neighbouring valid cells");
  add("valid cells on one line (qslim)", {"--algo", "qslim", line, out}, 1,
      line + ": no three neighbouring valid cells");
  const std::string checker = raster(
      "checker.tif", 8, 8, [](int c, int r) { return (c + r) % 2 ? 5.0 : kNaN; }, nodata);
  add("checkerboard of valid cells", {checker, out}, 1,
      checker + ": no three neighbouring valid cells");

  // Raster shapes and geotransforms.
  const std::string row = raster("one_row.tif", 30, 1, hill);
  add("1 x N raster", {row, out}, 1, row + ": 30 x 1 cells; at least 2 x 2 are needed");
  // Geotransforms GeoTIFF cannot hold: VRTs over a valid raster.
  const std::string fine = raster("fine.tif", 30, 20, hill);
  auto vrt = [&](const std::string& name, const std::string& geotransform) {
    std::ofstream(dir / name)
        << "<VRTDataset rasterXSize=\"30\" rasterYSize=\"20\"><GeoTransform>" << geotransform
        << "</GeoTransform><VRTRasterBand dataType=\"Float32\" band=\"1\"><SimpleSource>"
           "<SourceFilename relativeToVRT=\"1\">fine.tif</SourceFilename><SourceBand>1"
           "</SourceBand></SimpleSource></VRTRasterBand></VRTDataset>\n";
    return path(name);
  };
  const std::string zero = vrt("zero_cell.vrt", "400000, 0, 0, 3800000, 0, -10");
  add("zero pixel size", {zero, out}, 1,
      zero + ": geotransform is singular: its cells have no area");
  ::mkfifo((dir / "pipe.tif").c_str(), 0600);
  add("a FIFO with no writer", {path("pipe.tif"), out}, 1,
      path("pipe.tif") + ": is a pipe or a device, not a raster file");
  add("a character device", {"/dev/zero", out}, 1,
      "/dev/zero: is a pipe or a device, not a raster file");
  const std::string degenerate = vrt("degenerate.vrt", "400000, 10, 20, 3800000, 5, 10");
  add("degenerate geotransform (parallel axes)", {degenerate, out}, 1,
      degenerate + ": geotransform is singular: its cells have no area");
  const std::string thin = vrt("thin.vrt", "400000, 10, 0, 3800000, 0, -0.00001");
  add("cells 10^6 times wider than high", {thin, out}, 1,
      thin + ": degenerate cell geometry (cells are too thin");
  const std::string tiny = vrt("tiny_cells.vrt", "400000, 1e-9, 0, 3800000, 0, -1e-9");
  add("cells of 1e-9 at coordinates of 4e6", {tiny, out}, 1,
      tiny + ": cells of 1e-09 are too small for coordinates of 3.8e+06");
  const std::string inf = vrt("nan_gt.vrt", "400000, nan, 0, 3800000, 0, -10");
  add("non-finite geotransform", {inf, out}, 1, inf + ": geotransform is not finite");
  {
    // 60000 x 60000 cells described by a VRT of a few hundred bytes: refused from the size.
    std::ofstream(dir / "huge.vrt")
        << "<VRTDataset rasterXSize=\"60000\" rasterYSize=\"60000\"><GeoTransform>0, 1, 0, 0, "
           "0, -1</GeoTransform><VRTRasterBand dataType=\"Float32\" band=\"1\"/></VRTDataset>\n";
    add("60000 x 60000 raster, whole-DEM vp", {"--algo", "vp", path("huge.vrt"), out}, 1,
        path("huge.vrt") + ": 60000 x 60000 cells need about");
    std::ofstream(dir / "too_many.vrt")
        << "<VRTDataset rasterXSize=\"70000\" rasterYSize=\"70000\"><VRTRasterBand "
           "dataType=\"Float32\" band=\"1\"/></VRTDataset>\n";
    add("70000 x 70000 raster", {"--algo", "vp-meta", path("too_many.vrt"), out}, 1,
        path("too_many.vrt") +
            ": 70000 x 70000 cells, more than 2^32: too many for --algo vp-meta (32-bit cell ids)");
  }
  // One piece of 8000 cells (about 2.6 MB by core::piece_bytes) and 800 kept vertices.
  const std::string medium = raster("medium.tif", 100, 80, hill);
  add("pieces and output too large for --max-memory (vp-meta)",
      {"--algo", "vp-meta", "--levels", "0", "--max-memory", "1", medium, out}, 1,
      medium + ": keeping 800 vertices, with its pieces in flight, needs about");
  add("pieces and output too large for --max-memory (qem, the default)",
      {"--levels", "0", "--max-memory", "1", medium, out}, 1,
      medium + ": keeping 800 vertices, with its pieces in flight, needs about");
  add("DEM too large for --max-memory (vp)", {"--algo", "vp", "--max-memory", "1", medium, out}, 1,
      medium + ": 100 x 80 cells need about");
  {
    // Georeferenced by ground control points only.
    std::ofstream(dir / "gcps.vrt")
        << "<VRTDataset rasterXSize=\"30\" rasterYSize=\"20\"><GCPList>"
           "<GCP Id=\"1\" Pixel=\"0\" Line=\"0\" X=\"0\" Y=\"0\"/>"
           "<GCP Id=\"2\" Pixel=\"30\" Line=\"0\" X=\"300\" Y=\"10\"/>"
           "<GCP Id=\"3\" Pixel=\"0\" Line=\"20\" X=\"5\" Y=\"-200\"/></GCPList>"
           "<VRTRasterBand dataType=\"Float32\" band=\"1\"><SimpleSource>"
           "<SourceFilename relativeToVRT=\"1\">fine.tif</SourceFilename><SourceBand>1"
           "</SourceBand></SimpleSource></VRTRasterBand></VRTDataset>\n";
    add("georeferenced by GCPs only", {path("gcps.vrt"), out}, 1,
        path("gcps.vrt") + ": georeferenced by 3 ground control points");
  }

  // Cell types and bands.
  RasterSpec complex;
  complex.type = "CFloat32";
  const std::string cplx = raster("complex.tif", 10, 10, hill, complex);
  add("complex cells (CFloat32)", {cplx, out}, 1,
      cplx + ": band 1 holds CFloat32 cells; heights must be real numbers");
  RasterSpec two;
  two.bands = 2;
  const std::string bands = raster("two_bands.tif", 10, 10, hill, two);
  add("--band 3 of a 2-band raster", {"--band", "3", bands, out}, 1,
      bands + ": has 2 bands; there is no band 3");

  // Usage and output safety.
  add("output is the input", {fine, fine}, 2, fine + ": OUTPUT is the INPUT file");
  add("empty OUTPUT name", {fine, ""}, 2, "OUTPUT is an empty name");
  add("empty INPUT name", {"", out}, 2, "INPUT is an empty name");
  add("output folder missing", {fine, path("no/such/dir/out.ply")}, 1,
      path("no/such/dir/out.ply") + ": cannot create output");
  // note: 20 vertices, so that the mesh's temporary files (qem) stay under the limit and the
  // output is what fills it (a full TMPDIR: dpts_par_cli_test.cpp).
  cases.push_back({"disk full while writing (1 kB file size limit)",
                   {"--ascii", "--vertices", "20", fine, out}, 1,
                   out + ": write failed (File too large)", "", 1024});

  // Strange but valid: each must succeed and write its output.
  auto ok = [&](std::string what, std::vector<std::string> args, std::string msg = "") {
    cases.push_back({std::move(what), std::move(args), 0, std::move(msg), out, 0});
  };
  ok("2-band raster (band 1 used, said)", {bands, out}, bands + ": 2 bands; using band 1");
  // A small DEM is charged its pieces' size, not a whole --tile-mb per thread (512 MB).
  ok("600 cells under --max-memory 16 (qem)", {"--max-memory", "16", fine, out});
  ok("600 cells under --max-memory 16 (vp-meta)",
     {"--algo", "vp-meta", "--max-memory", "16", fine, out});
  RasterSpec rotated;
  rotated.geotransform = {400000, 8, 6, 3800000, 6, -8};
  // qslim locks its outline: a strip two cells wide keeps every vertex, and says why.
  ok("a strip 2 cells wide (qslim)", {"--algo", "qslim", raster("strip.tif", 50, 2, hill), out},
     "warning: kept 100 vertices, not 10: qslim keeps every vertex of the outline");
  {
    // A whole-world geographic DEM: its UTM zone cannot hold it.
    RasterSpec world;
    world.wkt = epsg_wkt(4326);
    world.geotransform = {-180, 6, 0, 90, 0, -6};
    const std::string whole = raster("world.tif", 60, 30, hill, world);
    add("the whole world in EPSG:4326", {whole, out}, 1,
        whole + ": cannot project the half of it round its centre to WGS 84 / UTM zone ");
  }
  ok("rotated geotransform", {raster("rotated.tif", 20, 15, hill, rotated), out});
  RasterSpec sheared;
  sheared.geotransform = {400000, 10, 4, 3800000, 0, -10};
  ok("sheared geotransform", {raster("sheared.tif", 20, 15, hill, sheared), out});
  RasterSpec south_up;
  south_up.geotransform = {400000, 10, 0, 3800000, 0, 10};
  ok("south-up (positive pixel height)", {raster("south_up.tif", 20, 15, hill, south_up), out});
  RasterSpec flipped;
  flipped.geotransform = {400000, -10, 0, 3800000, 0, -10};
  ok("negative pixel width", {raster("flipped.tif", 20, 15, hill, flipped), out});
  const std::string nan_cells = raster("nan_inf.tif", 20, 15, [](int c, int r) {
    if (c == 5 && r == 5) return kNaN;
    if (c == 6 && r == 5) return std::numeric_limits<double>::infinity();
    return hill(c, r);
  });
  ok("NaN and infinite heights (read as no-data, the infinite one said)", {nan_cells, out},
     "warning: " + nan_cells + ": 1 cells with heights beyond +-1e7 read as no-data");
  const std::string absurd = raster("absurd.tif", 20, 15, [](int c, int r) {
    return c == 7 && r < 3 ? 1e30 : hill(c, r);
  });
  ok("heights of 1e30 (read as no-data, said)", {absurd, out},
     "warning: " + absurd + ": 3 cells with heights beyond +-1e7 read as no-data");
  ok("heights of 1e30 (vp-meta)", {"--algo", "vp-meta", absurd, out},
     "warning: " + absurd + ": 3 cells with heights beyond +-1e7 read as no-data");
  // An OUTPUT whose extension no format has: PLY, said (a name without one says nothing).
  const std::string tif_out = (dir / "out.tif").string();
  cases.push_back({"OUTPUT out.tif (written as PLY, said)", {fine, tif_out}, 0,
                   tif_out + ": written as PLY (.tif is not .ply, .obj, .stl or .gpkg; --format "
                   "picks the format)", tif_out, 0});
  // Voids that lost their no-data tag: heights as the band says, and said, by either engine.
  const std::string untagged = raster("untagged.tif", 20, 15, [](int c, int r) {
    return r == 4 && c > 2 && c < 7 ? -9999.0 : hill(c, r);
  });
  const std::string untagged_msg =
      "warning: " + untagged + ": 4 cells hold -9999, a usual no-data value, but band 1 has none";
  ok("-9999 cells in a band without no-data (said)", {untagged, out}, untagged_msg);
  ok("-9999 cells in a band without no-data (vp)", {"--algo", "vp", untagged, out},
     untagged_msg);
  RasterSpec int16;
  int16.type = "Int16";
  const std::string srtm = raster("srtm_voids.tif", 20, 15, [](int c, int r) {
    return c == 0 && r < 2 ? -32768.0 : 100.0 + c + r;
  }, int16);
  ok("Int16 -32768 cells without no-data (said)", {srtm, out},
     "warning: " + srtm + ": 2 cells hold -32768, a usual no-data value, but band 1 has none");
  for (const char* type : {"Byte", "UInt16", "Int16", "UInt32", "Int32", "UInt64", "Int64",
                           "Float32", "Float64"}) {
    RasterSpec t;
    t.type = type;
    ok(std::string(type) + " cells", {raster(std::string("type_") + type + ".tif", 12, 10,
                                             [](int c, int r) { return 100.0 + 7 * c + r; }, t),
                                      out});
  }
  for (const std::string format : {"NC", "NC2", "NC4"}) {
    RasterSpec nc;
    nc.driver = "netCDF";
    nc.creation_options = {"FORMAT=" + format};
    ok("netCDF raster (" + format + ")",
       {raster("whole_" + format + ".nc", 20, 15, hill, nc), out});
  }
  RasterSpec sbyte;
  sbyte.type = "Byte";
  sbyte.creation_options = {"PIXELTYPE=SIGNEDBYTE"};
  ok("signed Byte cells", {raster("type_sbyte.tif", 12, 10,
                                  [](int c, int r) { return -60.0 + 7 * c + r; }, sbyte),
                           out});
  return cases;
}

}  // namespace dpts::test
