// PLY meshes: writing dpts output, reading any triangle PLY (ascii or binary, float or double).
#pragma once

#include <array>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/mesh.hpp"
#include "io/spilled_mesh.hpp"

namespace dpts::io {

// A mesh as a file holds it: core::TriMesh (faces counter-clockwise seen from above) and the
// header comments, in order.
struct Mesh : core::TriMesh {
  std::vector<std::string> comments;
};

enum class PlyFormat { binary_little_endian, ascii };

// Writes `mesh` as PLY: vertex x y z as double, faces as `list uchar int vertex_indices`,
// each comment as a `comment` line (newlines in comments become spaces). Numbers in ASCII
// use the shortest round-trip form (std::to_chars, no locale). Throws IoError if the stream
// fails.
void write_ply(std::ostream& out, const Mesh& mesh, PlyFormat format);
// The same from a mesh in runs (a SpilledMesh's parts): the same bytes.
void write_ply(std::ostream& out, const MeshParts& mesh, PlyFormat format);
// An in-memory mesh as one run of each.
MeshParts parts_of(const Mesh& mesh);

// Reads a PLY mesh with vertex properties x, y, z (float or double, other properties
// ignored) and triangular faces. Throws InputError naming `name` on malformed input.
Mesh read_ply(std::istream& in, const std::string& name);
Mesh read_ply_file(const std::string& path);

// The checks a mesh must pass before its surface distances are measured: at least one face,
// finite coordinates, three distinct vertices per face. Throws InputError naming `name`.
// Flat (zero-area) and folded (clockwise) faces pass: they are a property of the mesh that
// dpts-eval measures and reports, not a reason to refuse it.
void check_triangles(const Mesh& mesh, const std::string& name);

}  // namespace dpts::io
