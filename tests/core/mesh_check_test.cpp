// Welding a triangle soup: vertices at one position become one, deterministically.
#include "core/mesh_check.hpp"

#include <catch2/catch.hpp>
#include <vector>

using namespace dpts;

TEST_CASE("weld_identical_vertices merges a triangle soup into an indexed mesh",
          "[core][mesh_check][weld]") {
  // Two triangles of a unit square, each with its own three corners (as an STL has them).
  core::TriMesh soup;
  soup.xyz = {0, 0, 1, 1, 0, 2, 1, 1, 3,   // face 0: (0,0) (1,0) (1,1)
              0, 0, 1, 1, 1, 3, 0, 1, 4};  // face 1: (0,0) (1,1) (0,1)
  soup.faces = {{0, 1, 2}, {3, 4, 5}};
  CHECK(core::weld_identical_vertices(soup) == 2);
  // The first of each position kept, in order; the face of the copies indexes it.
  CHECK(soup.xyz == std::vector<double>{0, 0, 1, 1, 0, 2, 1, 1, 3, 0, 1, 4});
  CHECK(soup.faces == std::vector<std::array<std::uint32_t, 3>>{{0, 1, 2}, {0, 2, 3}});
  // The welded mesh shares its diagonal: no more boundary edges than the square's four.
  CHECK(core::check_mesh(core::xy_of(soup.xyz), soup.faces).boundary_edges == 4);
}

TEST_CASE("weld_identical_vertices leaves an indexed mesh as it is and tells apart any difference",
          "[core][mesh_check][weld]") {
  core::TriMesh m;
  // Same x, y at two heights, and positions one ulp apart: all different vertices.
  m.xyz = {0, 0, 1, 1, 0, 1, 0, 1, 1, 0, 0, 2, 1, 0, 1.0000000000000002, 0, 1, 1};
  m.faces = {{0, 1, 2}, {3, 4, 2}};
  const auto before = m;
  CHECK(core::weld_identical_vertices(m) == 1);  // only vertex 5 (a copy of vertex 2)
  CHECK(m.vertex_count() == 5);
  core::TriMesh indexed = before;
  indexed.xyz.resize(15);
  CHECK(core::weld_identical_vertices(indexed) == 0);
  CHECK(indexed.xyz == std::vector<double>(before.xyz.begin(), before.xyz.begin() + 15));
  CHECK(indexed.faces == before.faces);
}
