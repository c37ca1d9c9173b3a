// Merging the pieces' kept vertices into one Delaunay TIN (CGAL), footprint by flood fill.
#include "core/merge.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace dpts::core {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, K>;  // index into cells
using Fb = CGAL::Triangulation_face_base_with_info_2<std::int8_t, K>;      // 1: inside
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
}

}  // namespace

Tin merge_kept(int width, const GridFrame& frame, const std::vector<std::uint32_t>& cells,
               const std::vector<OutlineEdge>& outline) {
  Tin tin;
  tin.cells = cells;
  std::vector<std::pair<K::Point_2, std::uint32_t>> points;
  points.reserve(cells.size());
  for (std::uint32_t i = 0; i < cells.size(); ++i) {
    const int c = static_cast<int>(cells[i] % static_cast<std::uint32_t>(width));
    const int r = static_cast<int>(cells[i] / static_cast<std::uint32_t>(width));
    points.emplace_back(K::Point_2(frame.u(c, r), frame.w(c, r)), i);
  }
  Delaunay dt;
  dt.insert(points.begin(), points.end());
  points = {};
  if (dt.dimension() < 2) return tin;
  std::vector<Delaunay::Vertex_handle> handle(cells.size());
  for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) {
    handle[v->info()] = v;
  }
  for (auto f = dt.all_faces_begin(); f != dt.all_faces_end(); ++f) f->info() = 0;

  auto index_of = [&](std::uint32_t cell) {
    const auto it = std::lower_bound(cells.begin(), cells.end(), cell);
    if (it == cells.end() || *it != cell) {
      throw std::logic_error("outline edge at cell " + std::to_string(cell) +
                             ", which no piece kept");
    }
    return static_cast<std::uint32_t>(it - cells.begin());
  };
  // The outline edges (as vertex index pairs) and the faces on their left: the seeds.
  std::vector<std::uint64_t> walls;
  std::vector<Delaunay::Face_handle> stack;
  walls.reserve(outline.size());
  for (const OutlineEdge& e : outline) {
    const std::uint32_t a = index_of(e[0]), b = index_of(e[1]);
    Delaunay::Face_handle f;
    int i = 0;
    if (!dt.is_edge(handle[a], handle[b], f, i)) {
      throw std::logic_error("outline edge " + std::to_string(e[0]) + "-" + std::to_string(e[1]) +
                             " is not Delaunay in the merged TIN");
    }
    if (f->vertex(Delaunay::ccw(i)) != handle[a]) f = f->neighbor(i);
    if (dt.is_infinite(f)) {
      throw std::logic_error("outline edge " + std::to_string(e[0]) + "-" + std::to_string(e[1]) +
                             " has the outside of the hull on its left");
    }
    walls.push_back(edge_key(a, b));
    stack.push_back(f);
  }
  std::sort(walls.begin(), walls.end());
  // Flood fill from the seeds without crossing an outline edge.
  for (const auto& f : stack) f->info() = 1;
  while (!stack.empty()) {
    const Delaunay::Face_handle f = stack.back();
    stack.pop_back();
    for (int i = 0; i < 3; ++i) {
      const Delaunay::Face_handle g = f->neighbor(i);
      if (g->info() == 1 || dt.is_infinite(g)) continue;
      const std::uint64_t key =
          edge_key(f->vertex(Delaunay::ccw(i))->info(), f->vertex(Delaunay::cw(i))->info());
      if (std::binary_search(walls.begin(), walls.end(), key)) continue;
      g->info() = 1;
      stack.push_back(g);
    }
  }
  for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f) {
    if (f->info() != 1) continue;
    std::array<std::uint32_t, 3> t{f->vertex(0)->info(), f->vertex(1)->info(),
                                   f->vertex(2)->info()};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    tin.faces.push_back(t);
  }
  std::sort(tin.faces.begin(), tin.faces.end());
  return tin;
}

}  // namespace dpts::core
