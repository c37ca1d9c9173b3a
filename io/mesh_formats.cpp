// Mesh outputs: OBJ and STL written here, PLY by io/ply.cpp, GeoPackage through OGR.
#include "io/mesh_formats.hpp"

#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <ostream>
#include <utility>

#include "core/errors.hpp"
#include "io/atomic_output_file.hpp"
#include "io/byte_writer.hpp"

namespace dpts::io {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

using bytes::flush;
using bytes::kChunk;
using bytes::put_le;
using bytes::put_number;

std::array<double, 3> corner(const Mesh& mesh, std::uint32_t v) {
  return {mesh.xyz[3 * v], mesh.xyz[3 * v + 1], mesh.xyz[3 * v + 2]};
}

// The unit normal of a face (its corners counter-clockwise), zero for a degenerate one.
std::array<double, 3> unit_normal(const std::array<double, 3>& a, const std::array<double, 3>& b,
                                  const std::array<double, 3>& c) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  std::array<double, 3> n = {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (len > 0) {
    for (double& x : n) x /= len;
  }
  return n;
}

void write_obj(std::ostream& out, const MeshParts& mesh) {
  std::string buf;
  for (std::string c : *mesh.comments) {
    std::replace(c.begin(), c.end(), '\n', ' ');
    std::replace(c.begin(), c.end(), '\r', ' ');
    buf += "# " + c + "\n";
  }
  mesh.each_vertices([&](const double* xyz, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      buf += "v ";
      bytes::put_xyz_line(buf, &xyz[3 * i]);
      if (buf.size() > kChunk) flush(out, buf);
    }
  });
  mesh.each_faces([&](const std::array<std::uint32_t, 3>* faces, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      buf += 'f';
      for (const std::uint32_t v : faces[i]) {
        buf += ' ';
        put_number(buf, std::size_t{v} + 1);
      }
      buf += '\n';
      if (buf.size() > kChunk) flush(out, buf);
    }
  });
  flush(out, buf);
}

// Returns how far float32 moved the farthest coordinate (binary only).
double write_stl(std::ostream& out, const Mesh& mesh, bool ascii) {
  std::string buf;
  double moved = 0;
  if (ascii) {
    buf += "solid dpts\n";
  } else {
    std::string header = "binary STL from dpts " DPTS_VERSION;
    if (!mesh.comments.empty()) header += "; " + mesh.comments.front();
    header.resize(80, ' ');
    buf += header;
    put_le(buf, static_cast<std::uint32_t>(mesh.faces.size()));
  }
  for (const auto& f : mesh.faces) {
    const std::array<std::array<double, 3>, 3> p = {corner(mesh, f[0]), corner(mesh, f[1]),
                                                    corner(mesh, f[2])};
    const std::array<double, 3> n = unit_normal(p[0], p[1], p[2]);
    if (ascii) {
      buf += "facet normal ";
      bytes::put_xyz_line(buf, n.data());
      buf += "outer loop\n";
      for (const auto& q : p) {
        buf += "vertex ";
        bytes::put_xyz_line(buf, q.data());
      }
      buf += "endloop\nendfacet\n";
    } else {
      for (const double x : n) put_le(buf, static_cast<float>(x));
      for (const auto& q : p) {
        for (const double x : q) {
          const auto single = static_cast<float>(x);
          moved = std::max(moved, std::abs(static_cast<double>(single) - x));
          put_le(buf, single);
        }
      }
      put_le(buf, std::uint16_t{0});
    }
    if (buf.size() > kChunk) flush(out, buf);
  }
  if (ascii) buf += "endsolid dpts\n";
  flush(out, buf);
  return moved;
}

// GDAL's last error, or `fallback` when it has none.
std::string gdal_error(const char* fallback) {
  const char* msg = CPLGetLastErrorMsg();
  return msg != nullptr && *msg != '\0' ? std::string(msg) : std::string(fallback);
}

struct DatasetCloser {
  void operator()(GDALDataset* ds) const {
    if (ds != nullptr) GDALClose(ds);
  }
};

// The last change date a GeoPackage is written with (ISO 8601, as GDAL's OGR_CURRENT_DATE).
constexpr const char* kGpkgDate = "2000-01-01T00:00:00.000Z";

void write_gpkg(const std::filesystem::path& path, const Mesh& mesh,
                const MeshWriteOptions& options) {
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GPKG");
  if (driver == nullptr) throw IoError("GDAL has no GeoPackage driver");
  // note: the temporary file's name does not end in .gpkg; GDAL warns about that, and about
  // nothing else here that the checks below do not catch. Quiet while writing.
  CPLPushErrorHandler(CPLQuietErrorHandler);
  struct Pop {
    ~Pop() { CPLPopErrorHandler(); }
  } pop;
  // note: GDAL stamps the layer's last change (gpkg_contents) with the time of writing, so
  // that no two runs gave the same bytes: a fixed date instead, unless the caller set one
  // (--config OGR_CURRENT_DATE).
  const bool dated = CPLGetConfigOption("OGR_CURRENT_DATE", nullptr) != nullptr;
  if (!dated) CPLSetThreadLocalConfigOption("OGR_CURRENT_DATE", kGpkgDate);
  struct Undate {
    bool dated;
    ~Undate() {
      if (!dated) CPLSetThreadLocalConfigOption("OGR_CURRENT_DATE", nullptr);
    }
  } undate{dated};
  CPLErrorReset();
  std::unique_ptr<GDALDataset, DatasetCloser> ds(
      driver->Create(path.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
  if (!ds) throw IoError(gdal_error("cannot create the GeoPackage"));
  OGRSpatialReference srs;
  const bool has_crs =
      !options.crs_wkt.empty() && srs.importFromWkt(options.crs_wkt.c_str()) == OGRERR_NONE;
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  const char* layer_options[] = {"SPATIAL_INDEX=YES", nullptr};
  OGRLayer* layer =
      ds->CreateLayer(options.layer.empty() ? "tin" : options.layer.c_str(),
                      has_crs ? &srs : nullptr, wkbPolygon25D, const_cast<char**>(layer_options));
  if (layer == nullptr) throw IoError(gdal_error("cannot create the GeoPackage layer"));
  if (ds->StartTransaction() != OGRERR_NONE) throw IoError(gdal_error("cannot start writing"));
  OGRFeatureDefn* defn = layer->GetLayerDefn();
  for (const auto& f : mesh.faces) {
    auto ring = std::make_unique<OGRLinearRing>();
    ring->setNumPoints(4);
    for (int k = 0; k < 4; ++k) {
      const auto p = corner(mesh, f[static_cast<std::size_t>(k % 3)]);
      ring->setPoint(k, p[0], p[1], p[2]);
    }
    OGRPolygon polygon;
    polygon.addRingDirectly(ring.release());
    OGRFeature feature(defn);
    feature.SetGeometry(&polygon);
    if (layer->CreateFeature(&feature) != OGRERR_NONE) {
      throw IoError(gdal_error("write failed"));
    }
  }
  if (ds->CommitTransaction() != OGRERR_NONE) throw IoError(gdal_error("write failed"));
  GDALDataset* raw = ds.release();
  CPLErrorReset();
  GDALClose(raw);
  if (CPLGetLastErrorType() >= CE_Failure) throw IoError(gdal_error("write failed on close"));
}

}  // namespace

namespace {
// Each format with its --format name, which is also its extension after the dot.
constexpr std::pair<MeshFormat, const char*> kFormats[] = {{MeshFormat::ply, ".ply"},
                                                           {MeshFormat::obj, ".obj"},
                                                           {MeshFormat::stl, ".stl"},
                                                           {MeshFormat::gpkg, ".gpkg"}};
}  // namespace

std::optional<MeshFormat> parse_mesh_format(std::string_view text) {
  const std::string t = lower(text);
  for (const auto& [format, ext] : kFormats) {
    if (t == ext + 1) return format;
  }
  return std::nullopt;
}

MeshFormat mesh_format_of(const std::string& path) {
  const std::string ext = lower(std::filesystem::path(path).extension().string());
  if (ext.size() > 1) {
    if (const auto f = parse_mesh_format(std::string_view(ext).substr(1))) return *f;
  }
  return MeshFormat::ply;
}

const char* extension_of(MeshFormat format) {
  for (const auto& [f, ext] : kFormats) {
    if (f == format) return ext;
  }
  return ".ply";
}

namespace {

// PLY and OBJ, the formats written a run at a time.
void write_runs(AtomicOutputFile& out, const MeshParts& mesh, const MeshWriteOptions& options) {
  if (options.format == MeshFormat::ply) {
    write_ply(out.stream(), mesh,
              options.ascii ? PlyFormat::ascii : PlyFormat::binary_little_endian);
  } else {
    write_obj(out.stream(), mesh);
  }
}

}  // namespace

double write_mesh(AtomicOutputFile& out, const Mesh& mesh, const MeshWriteOptions& options) {
  switch (options.format) {
    case MeshFormat::ply:
    case MeshFormat::obj:
      write_runs(out, parts_of(mesh), options);
      return 0;
    case MeshFormat::stl:
      return write_stl(out.stream(), mesh, options.ascii);
    case MeshFormat::gpkg:
      write_gpkg(out.release_path(), mesh, options);
      return 0;
  }
  return 0;
}

double write_mesh(AtomicOutputFile& out, const SpilledMesh& spilled,
                  const std::vector<std::string>& comments, const MeshWriteOptions& options) {
  if (options.format == MeshFormat::ply || options.format == MeshFormat::obj) {
    write_runs(out, spilled.parts(&comments), options);
    return 0;
  }
  Mesh mesh;
  static_cast<core::TriMesh&>(mesh) = spilled.load();
  mesh.comments = comments;
  return write_mesh(out, mesh, options);
}

}  // namespace dpts::io
