// The public library (include/dpts/dpts.hpp) over the engines dpts-par and dpts-eval run.
#include "dpts/dpts.hpp"

#include <cpl_vsi.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>

#include "api/evaluation.hpp"
#include "core/errors.hpp"
#include "core/mesh_check.hpp"
#include "io/atomic_output_file.hpp"
#include "io/dem_reader.hpp"
#include "io/mesh_formats.hpp"
#include "parallel/memory.hpp"
#include "parallel/meta.hpp"
#include "parallel/qem_engine.hpp"
#include "parallel/simplify.hpp"

namespace dpts {
namespace {

// The user's callback, one call at a time (the engines may call from worker threads).
class SerialProgress {
 public:
  explicit SerialProgress(const ProgressFn& fn) : fn_(fn) {}
  bool operator()(double fraction, std::string_view stage) {
    if (!fn_) return true;
    std::lock_guard<std::mutex> lock(m_);
    return fn_(fraction, stage);
  }

 private:
  const ProgressFn& fn_;
  std::mutex m_;
};

// Runs f in an arena of `threads` workers (0: all cores), GDAL registered; std::invalid_argument
// (an engine's refusal of an option) becomes UsageError.
template <typename F>
auto in_arena(int threads, F&& f) {
  GDALAllRegister();
  tbb::task_arena arena(par::thread_count(threads));
  try {
    return arena.execute(std::forward<F>(f));
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
}

par::KeepTarget keep_target(const SimplifyOptions& o) {
  par::KeepTarget keep;
  if (o.vertices > 0) {
    if (o.vertices < 3)
      throw UsageError("vertices " + std::to_string(o.vertices) + ": expected >= 3");
    keep.vertices = o.vertices;
  } else {
    if (!(o.keep > 0 && o.keep <= 1)) {
      throw UsageError("keep " + std::to_string(o.keep) + ": expected 0 < keep <= 1");
    }
    keep.percent = 100 * o.keep;
  }
  return keep;
}

// Simplifies an opened DEM; `name` is what the mesh's comment says it came from.
Mesh simplify_dem(const io::DemInfo& dem, const std::string& name, const SimplifyOptions& o,
                  const ProgressFn& progress) {
  const par::KeepTarget keep = keep_target(o);
  if (o.levels < 0 || o.levels > 16) throw UsageError("levels: expected 0 to 16");
  if (o.tile_mb < 1) throw UsageError("tile_mb: expected >= 1");
  if (o.max_error < 0) throw UsageError("max_error: expected >= 0");
  const std::optional<par::Algorithm> algo = par::parse_algorithm(o.algo);
  if (!algo || !(*algo == par::Algorithm::qem || par::is_meta(*algo))) {
    throw UsageError("algo " + o.algo +
                     ": expected qem, vp-meta or pld-meta (vp, pld and qslim run in dpts-par)");
  }
  if (o.max_error > 0 && *algo != par::Algorithm::qem) {
    throw UsageError("max_error: only with algo qem");
  }
  SerialProgress serial(progress);
  const core::Progress report = [&](double f, std::string_view stage) { return serial(f, stage); };
  const io::GdalRaster source(dem);
  Mesh out;
  if (*algo == par::Algorithm::qem) {
    par::QemEngineOptions qo;
    qo.keep = keep;
    qo.levels = o.levels;
    qo.tile_bytes = static_cast<std::size_t>(o.tile_mb) << 20;
    qo.max_error = o.max_error;
    qo.memory_limit_bytes = par::available_memory_bytes();
    par::MetaStats stats;
    core::TriMesh result = par::simplify_qem(source, qo, report, &stats);
    out.xyz = std::move(result.xyz);
    out.faces = std::move(result.faces);
    out.input_vertices = stats.input_vertices;
  } else {
    io::check_whole_size(dem, "algo " + o.algo + " (32-bit cell ids); qem reads it in tiles");
    par::MetaOptions mo;
    mo.elimination.importance = par::importance_of(*algo);
    mo.elimination.seed = o.seed;
    mo.keep = keep;
    mo.levels = o.levels;
    mo.tile_bytes = static_cast<std::size_t>(o.tile_mb) << 20;
    if (o.value_points < 2) throw UsageError("value_points: expected >= 2");
    mo.value_points = o.value_points;
    mo.seed = o.seed;
    mo.memory_limit_bytes = par::available_memory_bytes();
    par::MetaStats stats;
    par::MetaResult result = par::simplify_meta(source, mo, report, &stats);
    const std::vector<double> xy = dem.output_xy(result.tin.cells);
    out.xyz.resize(3 * result.tin.cells.size());
    for (std::size_t i = 0; i < result.tin.cells.size(); ++i) {
      out.xyz[3 * i] = xy[2 * i];
      out.xyz[3 * i + 1] = xy[2 * i + 1];
      out.xyz[3 * i + 2] = result.z[i];
    }
    out.faces = std::move(result.tin.faces);
    out.input_vertices = stats.input_vertices;
  }
  // note: as dpts-par, a mesh that would fold over in the output CRS is refused, not returned.
  const core::MeshCheck check = core::check_mesh(core::xy_of(out.xyz), out.faces);
  if (check.clockwise_or_flat != 0) {
    throw InputError(name + ": " + std::to_string(check.clockwise_or_flat) +
                     " faces would fold over in " + dem.output_crs_name);
  }
  out.crs_wkt = dem.output_wkt;
  std::string made = "generated by dpts " + version() + " (library) --algo " + o.algo;
  char keep_text[32];
  std::snprintf(keep_text, sizeof keep_text, "%g%%", 100 * o.keep);
  made += o.vertices > 0 ? " --vertices " + std::to_string(o.vertices)
                         : std::string(" --keep ") + keep_text;
  made += " --levels " + std::to_string(o.levels) + " --tile-mb " + std::to_string(o.tile_mb);
  out.comments = {made + " from " + name, "crs " + (out.crs_wkt.empty() ? "none" : out.crs_wkt)};
  return out;
}

}  // namespace

std::string version() { return DPTS_VERSION; }

void Mesh::write(const std::string& path, const std::string& format, bool ascii) const {
  GDALAllRegister();
  io::MeshWriteOptions wo;
  if (!format.empty()) {
    const auto f = io::parse_mesh_format(format);
    if (!f) throw UsageError("format " + format + ": expected ply, obj, stl or gpkg");
    wo.format = *f;
  } else {
    wo.format = io::mesh_format_of(path);
  }
  if (ascii && wo.format == io::MeshFormat::gpkg) {
    throw UsageError("ascii: a GeoPackage has no ASCII form");
  }
  wo.ascii = ascii;
  wo.crs_wkt = crs_wkt;
  wo.layer = std::filesystem::path(path).stem().string();
  io::Mesh m;
  m.xyz = xyz;
  m.faces = faces;
  m.comments = comments;
  for (const auto& f : faces) {
    for (const std::uint32_t v : f) {
      if (v >= vertex_count())
        throw UsageError("face index " + std::to_string(v) + " out of range");
    }
  }
  io::AtomicOutputFile out(path);
  try {
    io::write_mesh(out, m, wo);
  } catch (const IoError& e) {
    throw IoError(path + ": " + e.what());
  }
  out.commit();
}

Mesh simplify(const std::string& path, const SimplifyOptions& options, const ProgressFn& progress) {
  return in_arena(options.threads, [&] {
    const io::DemInfo dem = io::open_dem(path, io::DemReadOptions{options.t_srs, options.band});
    return simplify_dem(dem, std::filesystem::path(path).filename().string(), options, progress);
  });
}

Mesh simplify(const double* heights, int width, int height,
              const std::array<double, 6>& geotransform, const std::string& crs, double nodata,
              const SimplifyOptions& options, const ProgressFn& progress) {
  if (heights == nullptr || width < 2 || height < 2) {
    throw UsageError("heights: expected a grid of at least 2 x 2 cells");
  }
  GDALAllRegister();
  // The grid as a GeoTIFF in GDAL's memory file system, read like any file.
  char name[80];
  std::snprintf(name, sizeof name, "/vsimem/dpts-heights-%p.tif",
                static_cast<const void*>(heights));
  struct Unlink {
    const char* path;
    ~Unlink() { VSIUnlink(path); }
  } unlink{name};
  {
    GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
    std::unique_ptr<GDALDataset> ds(
        gtiff == nullptr ? nullptr : gtiff->Create(name, width, height, 1, GDT_Float64, nullptr));
    if (!ds) throw IoError("cannot hold the heights in GDAL's memory");
    double gt[6];
    std::copy(geotransform.begin(), geotransform.end(), gt);
    if (ds->SetGeoTransform(gt) != CE_None) throw UsageError("geotransform: GDAL refuses it");
    if (!crs.empty()) {
      OGRSpatialReference srs;
      if (srs.SetFromUserInput(crs.c_str()) != OGRERR_NONE) {
        throw UsageError("crs " + crs + ": not a CRS GDAL understands");
      }
      ds->SetSpatialRef(&srs);
    }
    GDALRasterBand* band = ds->GetRasterBand(1);
    if (!std::isnan(nodata)) band->SetNoDataValue(nodata);
    if (band->RasterIO(GF_Write, 0, 0, width, height, const_cast<double*>(heights), width, height,
                       GDT_Float64, 0, 0, nullptr) != CE_None) {
      throw IoError("cannot hold the heights in GDAL's memory");
    }
  }
  return in_arena(options.threads, [&] {
    const io::DemInfo dem = io::open_dem(name, io::DemReadOptions{options.t_srs, options.band});
    return simplify_dem(dem, "an array of heights", options, progress);
  });
}

Evaluation evaluate(const std::string& dem, const std::string& mesh, const EvaluateOptions& options,
                    const ProgressFn& progress) {
  if (options.points < 2) throw UsageError("points: expected >= 2");
  if (options.sets < 1) throw UsageError("sets: expected >= 1");
  return in_arena(options.threads, [&] {
    api::EvalRequest request;
    request.dem = dem;
    request.mesh = mesh;
    request.t_srs = options.t_srs;
    request.eval.points = options.points;
    request.eval.sets = options.sets;
    request.eval.seed = options.seed;
    const auto start = std::chrono::steady_clock::now();
    const std::unique_ptr<api::Evaluation> e = api::load(request);
    SerialProgress serial(progress);
    api::measure(*e, request, [&](double f, std::string_view stage) { return serial(f, stage); });
    Evaluation out;
    out.distance_error = e->result.distance_error;
    out.set_errors = e->result.set_errors;
    out.vertical_rmse = e->rmse;
    out.vertical_max = e->vmax;
    out.mesh_vertices = e->s.vertex_count();
    out.mesh_faces = e->s.faces.size();
    out.pairs_measured = e->result.pairs_measured;
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    out.json = e->json(request, par::thread_count(options.threads), secs);
    return out;
  });
}

}  // namespace dpts
