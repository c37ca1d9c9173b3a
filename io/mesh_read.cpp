// Mesh inputs: PLY (io/ply.cpp), Wavefront OBJ and STL read here, GeoPackage through OGR.
#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include <array>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.hpp"
#include "io/input_file.hpp"
#include "io/mesh_formats.hpp"

namespace dpts::io {
namespace {

// The whole file, or InputError naming it.
std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(path + ": cannot read");
  return bytes;
}

// The next whitespace-separated token of a line at pos (empty at its end).
std::string_view token(std::string_view line, std::size_t& pos) {
  while (pos < line.size() && (line[pos] == ' ' || line[pos] == '\t' || line[pos] == '\r')) ++pos;
  const std::size_t start = pos;
  while (pos < line.size() && line[pos] != ' ' && line[pos] != '\t' && line[pos] != '\r') ++pos;
  return line.substr(start, pos - start);
}

bool parse_double(std::string_view text, double& value) {
  const auto res = std::from_chars(text.data(), text.data() + text.size(), value);
  return res.ec == std::errc() && res.ptr == text.data() + text.size();
}

// Wavefront OBJ: "v x y z" vertices and "f a b c" triangles (a corner "i", "i/t", "i//n" or
// "i/t/n"; negative i counts back from the last vertex); other statements are ignored.
Mesh read_obj(const std::string& path, const std::string& text) {
  Mesh mesh;
  std::size_t line_no = 0, begin = 0;
  auto fail = [&](const std::string& why) {
    throw InputError(path + ": line " + std::to_string(line_no) + ": " + why);
  };
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const std::string_view line(text.data() + begin, end - begin);
    begin = end + 1;
    ++line_no;
    std::size_t pos = 0;
    const std::string_view kind = token(line, pos);
    if (kind == "v") {
      for (int k = 0; k < 3; ++k) {
        double x = 0;
        if (!parse_double(token(line, pos), x)) fail("expected a vertex's x y z");
        mesh.xyz.push_back(x);
      }
    } else if (kind == "f") {
      std::array<std::uint32_t, 3> face{};
      int corners = 0;
      for (std::string_view t = token(line, pos); !t.empty(); t = token(line, pos), ++corners) {
        const std::string_view index = t.substr(0, t.find('/'));
        long long i = 0;
        const auto res = std::from_chars(index.data(), index.data() + index.size(), i);
        const long long n = static_cast<long long>(mesh.vertex_count());
        if (res.ec != std::errc() || res.ptr != index.data() + index.size() || i == 0) {
          fail("face corner " + std::string(t) + ": expected a vertex number");
        }
        if (i < 0) i += n + 1;
        if (i < 1 || i > n) fail("face corner " + std::string(t) + ": no such vertex");
        if (corners < 3)
          face[static_cast<std::size_t>(corners)] = static_cast<std::uint32_t>(i - 1);
      }
      if (corners != 3) {
        fail("a face of " + std::to_string(corners) + " corners; expected triangles");
      }
      mesh.faces.push_back(face);
    }
  }
  return mesh;
}

// STL, binary (84 + 50 n bytes) or ASCII ("solid ... facet ... vertex x y z ..."): a triangle
// soup, three vertices of its own per face (welded by the caller where it must be).
bool is_binary_stl(const std::string& bytes) {
  if (bytes.size() < 84) return false;
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);  // little-endian hosts only (as the writer)
  return bytes.size() == 84 + 50 * static_cast<std::uint64_t>(n);
}

Mesh read_binary_stl(const std::string& bytes) {
  Mesh mesh;
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  mesh.xyz.reserve(9 * std::size_t{n});
  mesh.faces.reserve(n);
  for (std::uint32_t f = 0; f < n; ++f) {
    const char* rec = bytes.data() + 84 + 50 * std::size_t{f};
    for (int k = 0; k < 9; ++k) {
      float x = 0;
      std::memcpy(&x, rec + 12 + 4 * k, 4);
      mesh.xyz.push_back(x);
    }
    mesh.faces.push_back({3 * f, 3 * f + 1, 3 * f + 2});
  }
  return mesh;
}

Mesh read_ascii_stl(const std::string& path, const std::string& text) {
  Mesh mesh;
  std::size_t pos = 0, in_facet = 0;
  bool facet = false;
  const std::string_view all(text);
  auto next = [&] {
    while (pos < all.size() && std::isspace(static_cast<unsigned char>(all[pos]))) ++pos;
    const std::size_t start = pos;
    while (pos < all.size() && !std::isspace(static_cast<unsigned char>(all[pos]))) ++pos;
    return all.substr(start, pos - start);
  };
  auto fail = [&](const std::string& why) {
    throw InputError(path + ": ASCII STL, facet " + std::to_string(mesh.faces.size()) + ": " + why);
  };
  for (std::string_view t = next(); !t.empty(); t = next()) {
    if (t == "facet") {
      if (facet) fail("a facet inside a facet");
      facet = true;
      in_facet = 0;
    } else if (t == "vertex") {
      if (!facet) fail("a vertex outside a facet");
      for (int k = 0; k < 3; ++k) {
        double x = 0;
        if (!parse_double(next(), x)) fail("expected a vertex's x y z");
        mesh.xyz.push_back(x);
      }
      ++in_facet;
    } else if (t == "endfacet") {
      if (!facet || in_facet != 3) fail("expected three vertices");
      const auto v = static_cast<std::uint32_t>(mesh.vertex_count());
      mesh.faces.push_back({v - 3, v - 2, v - 1});
      facet = false;
    }
  }
  if (facet) fail("the file ends inside it");
  return mesh;
}

// GeoPackage (any OGR vector source): the triangles of its one layer, as Polygon Z (a ring of
// three corners, closed), Triangle Z, or collections of them (MultiPolygon Z, TIN Z,
// PolyhedralSurface Z); a triangle soup.
Mesh read_ogr(const std::string& path) {
  std::unique_ptr<GDALDataset> ds(static_cast<GDALDataset*>(
      GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  if (!ds) throw InputError(path + ": cannot open as a vector dataset");
  if (ds->GetLayerCount() != 1) {
    throw InputError(path + ": holds " + std::to_string(ds->GetLayerCount()) +
                     " layers; expected one layer of triangles");
  }
  OGRLayer* layer = ds->GetLayer(0);
  Mesh mesh;
  std::size_t feature_no = 0;
  auto fail = [&](const std::string& why) {
    throw InputError(path + ": feature " + std::to_string(feature_no) + ": " + why);
  };
  auto add_polygon = [&](const OGRGeometry* g) {
    const OGRwkbGeometryType type = wkbFlatten(g->getGeometryType());
    if (type != wkbPolygon && type != wkbTriangle) {
      fail(std::string("a ") + OGRGeometryTypeToName(g->getGeometryType()) +
           "; expected triangles (Polygon Z, Triangle Z, MultiPolygon Z, TIN Z)");
    }
    const OGRPolygon* poly = g->toPolygon();
    const OGRLinearRing* ring = poly->getExteriorRing();
    if (poly->getNumInteriorRings() != 0 || ring == nullptr || ring->getNumPoints() != 4 ||
        !ring->get_IsClosed()) {
      fail("a polygon that is not a triangle (a closed ring of three corners)");
    }
    if (!g->Is3D()) fail("a triangle without heights (Z)");
    const auto v = static_cast<std::uint32_t>(mesh.vertex_count());
    for (int k = 0; k < 3; ++k) {
      mesh.xyz.push_back(ring->getX(k));
      mesh.xyz.push_back(ring->getY(k));
      mesh.xyz.push_back(ring->getZ(k));
    }
    mesh.faces.push_back({v, v + 1, v + 2});
  };
  layer->ResetReading();
  for (std::unique_ptr<OGRFeature> f(layer->GetNextFeature()); f;
       f.reset(layer->GetNextFeature()), ++feature_no) {
    const OGRGeometry* g = f->GetGeometryRef();
    if (g == nullptr) fail("has no geometry");
    const OGRwkbGeometryType type = wkbFlatten(g->getGeometryType());
    if (type == wkbMultiPolygon) {
      for (const OGRPolygon* p : *g->toMultiPolygon()) add_polygon(p);
    } else if (type == wkbTIN || type == wkbPolyhedralSurface) {
      for (const OGRPolygon* p : *g->toPolyhedralSurface()) add_polygon(p);
    } else {
      add_polygon(g);
    }
  }
  return mesh;
}

bool starts_with(const std::string& s, std::string_view prefix) {
  return s.size() >= prefix.size() && std::string_view(s).substr(0, prefix.size()) == prefix;
}

}  // namespace

Mesh read_mesh_file(const std::string& path) {
  check_plain_input(path, "mesh");
  // note: by content where the format says what it is, else by extension.
  std::string head(100, '\0');
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open");
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
  }
  if (starts_with(head, "ply")) return read_ply_file(path);
  if (starts_with(head, "SQLite format 3")) return read_ogr(path);
  const MeshFormat by_name = mesh_format_of(path);
  if (by_name == MeshFormat::gpkg) return read_ogr(path);
  if (by_name == MeshFormat::obj) return read_obj(path, slurp(path));
  if (by_name == MeshFormat::stl) {
    const std::string bytes = slurp(path);
    if (is_binary_stl(bytes)) return read_binary_stl(bytes);
    std::size_t pos = 0;
    while (pos < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
    if (bytes.compare(pos, 5, "solid") == 0) return read_ascii_stl(path, bytes);
    throw InputError(path + ": neither binary STL (84 + 50 bytes per facet) nor ASCII STL");
  }
  return read_ply_file(path);
}

}  // namespace dpts::io
