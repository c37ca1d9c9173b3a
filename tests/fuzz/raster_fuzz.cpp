// libFuzzer harness: the raster-to-vertices path of dpts-par. The input is either a raw file
// (a TIFF, or anything GDAL may recognise) or, more often, a small raster described by the
// bytes: size, cell type, geotransform and CRS variant, no-data, then the cells. It is written
// as a GeoTIFF to GDAL's /vsimem/ and goes where dpts-par takes it: open_dem, the whole-DEM
// elimination (VP) with its grid TIN, the streaming meta engine (VP') on several pieces, and
// the default mode, qem's piece engine (its TIN checked for folds).
// Refusals (InputError, IoError) are answers; any other exception or crash is a finding.
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/mesh_check.hpp"
#include "io/dem_reader.hpp"
#include "parallel/meta.hpp"
#include "parallel/qem_engine.hpp"
#include "parallel/simplify.hpp"

namespace {

const char* kPath = "/vsimem/fuzz.tif";

struct Bytes {
  const std::uint8_t* p;
  std::size_t n;
  std::uint8_t byte() {
    if (n == 0) return 0;
    --n;
    return *p++;
  }
  double real() {
    double v = 0;
    if (n >= 8) {
      std::memcpy(&v, p, 8);
      p += 8, n -= 8;
    }
    return v;
  }
};

// Writes the described raster to kPath; false when GDAL refuses to create it.
bool write_structured(Bytes in) {
  static const GDALDataType types[] = {GDT_Byte,    GDT_UInt16,  GDT_Int16,   GDT_UInt32,
                                       GDT_Int32,   GDT_Float32, GDT_Float64, GDT_CInt16,
                                       GDT_CFloat32, GDT_UInt64, GDT_Int64};
  const int width = 1 + in.byte() % 24, height = 1 + in.byte() % 24;
  const GDALDataType type = types[in.byte() % (sizeof types / sizeof types[0])];
  const std::uint8_t flags = in.byte();
  const int bands = 1 + (flags & 1);
  // Geotransform: north-up, south-up, east-west flipped, rotated, sheared, or fuzzed.
  double gt[6] = {500000, 10, 0, 4000000, 0, -10};
  switch ((flags >> 1) & 7) {
    case 1: gt[5] = 10; break;
    case 2: gt[1] = -10; break;
    case 3: gt[1] = 8, gt[2] = 6, gt[4] = 6, gt[5] = -8; break;
    case 4: gt[2] = 5; break;
    case 5: gt[1] = 0; break;
    case 6: for (double& g : gt) g = in.real(); break;
    default: break;
  }
  const int crs = (flags >> 4) & 3;  // none, UTM 11N, WGS 84 (degrees), fuzzed EPSG
  if (crs == 2) gt[0] = -118, gt[1] = 0.001, gt[3] = 34, gt[5] = -0.001, gt[2] = gt[4] = 0;
  const bool nodata = flags & 64;
  const double nodata_value = in.real();

  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds = mem->Create("", width, height, bands, type, nullptr);
  if (!ds) return false;
  ds->SetGeoTransform(gt);
  if (crs != 0) {
    OGRSpatialReference srs;
    const int epsg = crs == 1 ? 32611 : crs == 2 ? 4326 : 2000 + in.byte() * 128 + in.byte();
    if (srs.importFromEPSG(epsg) == OGRERR_NONE) ds->SetSpatialRef(&srs);
  }
  const int size = GDALGetDataTypeSizeBytes(type);
  std::vector<std::uint8_t> cells(static_cast<std::size_t>(width) * height * size);
  for (std::size_t i = 0; i < cells.size(); ++i) cells[i] = in.byte();
  for (int b = 1; b <= bands; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b);
    if (nodata) band->SetNoDataValue(nodata_value);
    (void)band->RasterIO(GF_Write, 0, 0, width, height, cells.data(), width, height, type, 0, 0,
                         nullptr);
  }
  GDALDataset* out = gtiff->CreateCopy(kPath, ds, FALSE, nullptr, nullptr, nullptr);
  GDALClose(ds);
  if (!out) return false;
  GDALClose(out);
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  GDALAllRegister();
  CPLPushErrorHandler(CPLQuietErrorHandler);
  CPLSetConfigOption("GDAL_CACHEMAX", "16");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace dpts;
  VSIUnlink(kPath);
  if (size >= 4 && (std::memcmp(data, "II*", 3) == 0 || std::memcmp(data, "MM\0*", 4) == 0)) {
    VSILFILE* f = VSIFileFromMemBuffer(kPath, const_cast<GByte*>(data), size, FALSE);
    if (!f) return 0;
    VSIFCloseL(f);
  } else if (!write_structured(Bytes{data, size})) {
    return 0;
  }
  try {
    const io::DemInfo info = io::open_dem(kPath, {});
    // Bounded work per input (a huge raster is refused by open_dem or its size check).
    if (info.cell_count() > 4096) {
      VSIUnlink(kPath);
      return 0;
    }
    io::Dem dem = io::read_dem(kPath, {}, nullptr);
    dem.grid_mesh();
    core::EliminationOptions elimination;
    elimination.outline_chord_ok = dem.outline_chord_test(dem.outline_tolerance_m());
    par::simplify_dem(dem.grid, dem.frame, elimination, par::KeepTarget{50.0, {}}, nullptr);
    par::MetaOptions meta;
    meta.keep.percent = 30.0;
    meta.levels = 2;
    meta.tile_bytes = 1 << 12;
    par::simplify_meta(io::GdalRaster(info), meta, nullptr);
    // The default mode, qem's piece engine, alone and with --max-error: its TIN must be valid
    // (a fold or a flat face is a finding, as a crash is).
    for (const double bound : {0.0, 1.0}) {
      par::QemEngineOptions qo;
      qo.keep.percent = 30.0;
      qo.levels = 2;
      qo.tile_bytes = 1 << 12;
      qo.max_error = bound;
      const core::TriMesh m = par::simplify_qem(io::GdalRaster(info), qo, nullptr);
      const core::MeshCheck mc = core::check_mesh(core::xy_of(m.xyz), m.faces);
      if (mc.clockwise_or_flat != 0 || mc.bad_edges != 0) __builtin_trap();
    }
  } catch (const InputError&) {
  } catch (const IoError&) {
  }
  VSIUnlink(kPath);
  return 0;
}
