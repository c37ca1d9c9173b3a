// Meshes by format: PLY, Wavefront OBJ, STL and GeoPackage (one layer of triangles), written
// and read.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "io/ply.hpp"

namespace dpts::io {

class AtomicOutputFile;

enum class MeshFormat { ply, obj, stl, gpkg };

// The format --format names ("ply", "obj", "stl", "gpkg"; any case), or none.
std::optional<MeshFormat> parse_mesh_format(std::string_view text);
// The format a file name's extension names (.ply .obj .stl .gpkg, any case); PLY for any
// other name, so that an output without a known extension stays PLY.
MeshFormat mesh_format_of(const std::string& path);
// ".ply", ".obj", ".stl", ".gpkg".
const char* extension_of(MeshFormat format);

struct MeshWriteOptions {
  MeshFormat format = MeshFormat::ply;
  bool ascii = false;   // PLY and STL: text instead of binary (OBJ is text; GeoPackage refuses)
  std::string crs_wkt;  // GeoPackage: the layer's CRS (empty: none)
  std::string layer;    // GeoPackage: the layer's name
};

// Writes `mesh` (x, y, z; faces counter-clockwise seen from above) into `out` as `options` say:
// - PLY: write_ply.
// - OBJ: the comments as '#' lines, "v x y z" (shortest round-trip doubles), "f a b c" (1-based).
// - STL: binary (80-byte header, float32 normals and corners) or ASCII (round-trip doubles);
//   a facet's normal is its unit normal, its corners counter-clockwise.
// - GeoPackage (through OGR): one layer of Polygon Z features, one per face (closed rings of
//   its three corners, counter-clockwise), in the CRS given; `out` must be a file, not a stream.
// Returns, for binary STL, how far float32 moved the farthest coordinate (0 otherwise): a
// caller warns when that is more than the data can bear. Throws IoError naming nothing (the
// caller names the file) when writing fails; UsageError for a stream given GeoPackage.
double write_mesh(AtomicOutputFile& out, const Mesh& mesh, const MeshWriteOptions& options);
// The same from a spilled mesh, with the header comments: PLY and OBJ a run at a time (the
// same bytes, without the mesh in memory), STL and GeoPackage from the mesh read back whole.
double write_mesh(AtomicOutputFile& out, const SpilledMesh& mesh,
                  const std::vector<std::string>& comments, const MeshWriteOptions& options);

// Reads a triangle mesh in any of the formats (io/mesh_read.cpp): PLY or GeoPackage known by
// their first bytes, else by the extension (.obj, .stl binary or ASCII, .gpkg; PLY for any
// other). OBJ faces must be triangles; STL and GeoPackage give a triangle soup (three vertices
// of its own per face, STL's binary ones float32): weld it where faces must share vertices.
// Throws InputError naming the file on malformed input.
Mesh read_mesh_file(const std::string& path);

}  // namespace dpts::io
