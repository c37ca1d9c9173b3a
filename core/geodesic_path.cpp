// Straightening Steiner paths into exact (locally shortest) geodesics: unfolding, funnel,
// rerouting around vertices (see geodesic_path.hpp for the sources).
#include "core/geodesic_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dpts::core {
namespace {

constexpr std::uint32_t kNoVertex = 0xFFFFFFFFu;
constexpr double kPi = 3.14159265358979323846;
// Most faces around one vertex a walk visits (a fan larger than this is treated as open).
constexpr int kMaxFan = SteinerGraph::kMaxFan;
// Most passes of pulling taut and rerouting for one path (each pass strictly shortens it).
constexpr int kMaxPasses = 256;
// shortest(): how many nodes back from the target's face another path is followed to see
// whether it joins one tried already.
constexpr int kJoinSteps = 8;
// A route's taut points (PathRoute::taut) are thinned to within this fraction of the graph's
// delta of the taut path (Douglas-Peucker): on a synthetic volcano and terraces
// (bench/synthetic_dems.py) the measure came out the same with every crossing kept and at 0.01
// to 0.2; at 0.5, and with every second crossing kept, up to 15 % high again.
constexpr double kTautTolerance = 0.05;

// Twice the signed area of triangle (a, b, c) seen from above: > 0 counter-clockwise.
double orient2(std::array<double, 2> a, std::array<double, 2> b, std::array<double, 2> c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

struct Vec3 {
  double x, y, z;
};
Vec3 at(const TriMesh& m, std::uint32_t v) {
  return {m.xyz[3 * v], m.xyz[3 * v + 1], m.xyz[3 * v + 2]};
}
Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
double cross_norm(Vec3 a, Vec3 b) {
  const double cx = a.y * b.z - a.z * b.y, cy = a.z * b.x - a.x * b.z, cz = a.x * b.y - a.y * b.x;
  return std::sqrt(cx * cx + cy * cy + cz * cz);
}

// Barycentric coordinates (of b and c) of p in the 3D triangle a, b, c (p on its plane).
std::array<double, 2> barycentric(Vec3 a, Vec3 b, Vec3 c, Vec3 p) {
  const Vec3 v0 = sub(b, a), v1 = sub(c, a), v2 = sub(p, a);
  const double d00 = dot(v0, v0), d01 = dot(v0, v1), d11 = dot(v1, v1);
  const double d20 = dot(v2, v0), d21 = dot(v2, v1);
  const double den = d00 * d11 - d01 * d01;
  return {(d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den};
}

}  // namespace

bool PathStraightener::contains(std::uint32_t f, std::uint32_t v) const {
  const auto& face = g_.mesh().faces[f];
  return face[0] == v || face[1] == v || face[2] == v;
}

double PathStraightener::total_angle(std::uint32_t v, std::uint32_t f) const {
  // note: kept by the graph where v's faces are one fan (the same walk from its first face).
  const double kept = g_.vertex_angle(v);
  if (!std::isnan(kept)) return kept;
  // Around v from f, across the edge to one of f's other corners, until back at f.
  const auto fan = g_.walk_fan(v, f, g_.third_corner(f, v, kNoVertex));
  return fan.closed ? fan.angle : -1;
}

bool PathStraightener::walk_around(std::uint32_t v, std::uint32_t from, std::uint32_t to,
                                   bool shortest, std::uint32_t avoid,
                                   std::vector<std::uint32_t>& fan) const {
  // The faces strictly between `from` and `to` around v, leaving `from` across its edge (v, x).
  auto walk = [&](std::uint32_t x, std::vector<std::uint32_t>& out) {
    out.clear();
    std::uint32_t cur = from;
    for (int step = 0; step < kMaxFan; ++step) {
      const std::uint32_t next = g_.across_edge(cur, v, x);
      if (next == SteinerGraph::kNoFace || next == from) return false;
      if (next == to) return true;
      out.push_back(next);
      x = g_.third_corner(next, v, x);
      cur = next;
    }
    return false;
  };
  const auto& face = g_.mesh().faces[from];
  const int i = face[0] == v ? 0 : face[1] == v ? 1 : 2;
  const std::uint32_t x0 = face[(i + 1) % 3], x1 = face[(i + 2) % 3];
  if (!shortest) {
    // The direction whose first face is not `avoid`.
    return walk(g_.across_edge(from, v, x0) == avoid ? x1 : x0, fan);
  }
  std::vector<std::uint32_t> other;
  const bool ok0 = walk(x0, fan), ok1 = walk(x1, other);
  if (ok1 && (!ok0 || other.size() < fan.size())) fan.swap(other);
  return ok0 || ok1;
}

void PathStraightener::push_face(std::uint32_t f) {
  // note: a strip that steps back into the face it came from is reduced (x, y, x -> x): the
  // detour through y can only be longer.
  const std::size_t n = strip_.size();
  if (n >= 2 && strip_[n - 2] == f) {
    strip_.pop_back();
  } else if (n == 0 || strip_.back() != f) {
    strip_.push_back(f);
  }
}

bool PathStraightener::build_strip(const SurfacePoint& source,
                                   const std::vector<std::uint32_t>& nodes, std::size_t begin,
                                   const SurfacePoint& target, std::size_t& pinch,
                                   std::uint32_t& next_face) {
  pinch = kNoPinch;
  strip_.clear();
  push_face(source.face);
  const std::uint32_t nv = static_cast<std::uint32_t>(g_.mesh().vertex_count());
  // Whether face f holds graph node p (a vertex, or a point inside one of its edges).
  auto holds = [&](std::uint32_t f, std::uint32_t p) {
    const auto ends = g_.node_edge_ends(p);
    return contains(f, ends[0]) && contains(f, ends[1]);
  };
  for (std::size_t i = begin; i < nodes.size(); ++i) {
    const std::uint32_t u = nodes[i];
    const std::uint32_t a = strip_.back();
    // The face of the next segment: the target's, or one holding both its nodes (the current
    // face if it does: a segment along an edge lies in either of its faces).
    std::uint32_t b = SteinerGraph::kNoFace;
    if (i + 1 == nodes.size()) {
      b = target.face;
    } else if (holds(a, u) && holds(a, nodes[i + 1])) {
      b = a;
    } else {
      g_.for_each_face_of_vertex(g_.node_edge_ends(u)[0], [&](std::uint32_t f) {
        if (b == SteinerGraph::kNoFace && holds(f, u) && holds(f, nodes[i + 1])) b = f;
      });
    }
    if (b == SteinerGraph::kNoFace || !holds(b, u) || !holds(a, u)) return false;
    if (b == a) continue;
    if (edge_to(a, b) < 0) {
      // The path passes through vertex u: around it, the side with fewer faces.
      if (u >= nv) return false;
      if (!walk_around(u, a, b, true, SteinerGraph::kNoFace, fan_)) {
        // note: from one of u's fans to another (faces meeting at u alone, where a void
        // touches itself): the strip so far ends at u, in face a; the path goes on from b.
        pinch = i;
        next_face = b;
        return false;
      }
      for (std::uint32_t f : fan_) push_face(f);
    }
    push_face(b);
  }
  return strip_.back() == target.face && strip_.front() == source.face;
}

bool PathStraightener::unfold(const SurfacePoint& source, const SurfacePoint& target,
                              std::size_t from) {
  const TriMesh& m = g_.mesh();
  // The current face: its corners and their plane positions.
  std::array<std::uint32_t, 3> ids;
  std::array<Point2, 3> p2;
  auto lift2 = [&](const SurfacePoint& s) {
    const auto w = barycentric(at(m, ids[0]), at(m, ids[1]), at(m, ids[2]), Vec3{s.x, s.y, s.z});
    return Point2{p2[0].x + w[0] * (p2[1].x - p2[0].x) + w[1] * (p2[2].x - p2[0].x),
                  p2[0].y + w[0] * (p2[1].y - p2[0].y) + w[1] * (p2[2].y - p2[0].y)};
  };
  if (from == 0) {
    portals_.clear();
    unfolded_.clear();
    ids = m.faces[strip_[0]];
    const Vec3 a = at(m, ids[0]), b = at(m, ids[1]), c = at(m, ids[2]);
    const Vec3 ab = sub(b, a), ac = sub(c, a);
    const double len = std::sqrt(dot(ab, ab));
    if (!(len > 0)) return false;
    p2 = {Point2{0, 0}, Point2{len, 0}, Point2{dot(ac, ab) / len, cross_norm(ab, ac) / len}};
    if (!(p2[2].y > 1e-12 * len)) return false;
    const Point2 s2 = lift2(source);
    portals_.push_back({kNoVertex, kNoVertex, s2, s2});
    unfolded_.push_back({ids, p2});
    from = 1;
  } else {
    // note: face j's unfolding depends on faces 0..j alone: those the last call unfolded are
    // kept (the same bits as unfolding them again).
    portals_.resize(from);
    unfolded_.resize(from);
    ids = unfolded_.back().ids;
    p2 = unfolded_.back().p2;
  }
  if (hinges_.empty()) hinges_.resize(std::size_t{1} << kHingeBits);
  for (std::size_t j = from; j < strip_.size(); ++j) {
    Hinge& h = hinges_[hinge_slot(strip_[j])];
    // note: the corners compared one by one: std::array's != calls memcmp here.
    if (h.face != strip_[j] || h.prev[0] != ids[0] || h.prev[1] != ids[1] || h.prev[2] != ids[2]) {
      const auto& next = m.faces[strip_[j]];
      // The shared edge (u, w), the previous face's corner off it (k) and the new one (r).
      int k = -1, shared = 0;
      std::uint32_t r = kNoVertex;
      for (int c = 0; c < 3; ++c) {
        if (next[0] == ids[c] || next[1] == ids[c] || next[2] == ids[c]) {
          ++shared;
        } else {
          k = c;
        }
      }
      if (shared != 2 || k < 0) return false;
      for (std::uint32_t c : next) {
        if (c != ids[0] && c != ids[1] && c != ids[2]) r = c;
      }
      if (r == kNoVertex) return false;
      const int iu = (k + 1) % 3, iw = (k + 2) % 3;
      // r at its 3D offsets along and off the edge.
      const Vec3 u3 = at(m, ids[iu]), e3 = sub(at(m, ids[iw]), u3), r3 = sub(at(m, r), u3);
      const double len = std::sqrt(dot(e3, e3));
      const double along = dot(r3, e3) / len, off = cross_norm(e3, r3) / len;
      if (!(len > 0) || !(off > 1e-12 * len)) return false;
      h = Hinge{strip_[j], ids, r, k, len, along, off};
    }
    const int k = h.k, iu = (k + 1) % 3, iw = (k + 2) % 3;
    const std::uint32_t r = h.r;
    const double len = h.len, along = h.along, off = h.off;
    // r in the plane, on the side of the edge away from b.
    const Point2 u2 = p2[iu], w2 = p2[iw], b2 = p2[k];
    const double dx = (w2.x - u2.x) / len, dy = (w2.y - u2.y) / len;
    const double side = -dy * (b2.x - u2.x) + dx * (b2.y - u2.y);  // b's side of the edge
    const double s = side > 0 ? -1.0 : 1.0;
    const Point2 r2{u2.x + along * dx - s * off * dy, u2.y + along * dy + s * off * dx};
    // Seen from b, the portal's left end is counter-clockwise from its right end.
    const double turn = (w2.x - b2.x) * (u2.y - b2.y) - (w2.y - b2.y) * (u2.x - b2.x);
    // note: the records appended field by field from registers. Built on the stack and copied
    // in 16-byte pieces, each piece read back stores of 4 and 8 bytes, which the store buffer
    // cannot forward: the copy waited for them to reach the cache (perf: half of unfold's
    // samples on those copies).
    const std::uint32_t a = ids[iu], c = ids[iw];
    Portal& portal = portals_.emplace_back();
    if (turn > 0) {
      portal.left = a, portal.right = c, portal.l = u2, portal.r = w2;
    } else {
      portal.left = c, portal.right = a, portal.l = w2, portal.r = u2;
    }
    ids[0] = a, ids[1] = c, ids[2] = r;
    p2[0] = u2, p2[1] = w2, p2[2] = r2;
    Unfolded& face = unfolded_.emplace_back();
    face.ids[0] = a, face.ids[1] = c, face.ids[2] = r;
    face.p2[0] = u2, face.p2[1] = w2, face.p2[2] = r2;
  }
  const Point2 t2 = lift2(target);
  portals_.push_back({kNoVertex, kNoVertex, t2, t2});
  return true;
}

double PathStraightener::funnel(std::size_t from) {
  // The simple funnel: the apex, and the funnel's left and right ends (portal indices); a
  // portal end that is the apex itself constrains nothing.
  auto cross = [](Point2 a, Point2 b, Point2 c) {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  };
  auto same = [](Point2 a, Point2 b) { return a.x == b.x && a.y == b.y; };
  // note: a bend the last call fixed having read only portals before `from`, which are
  // unchanged, is fixed again, and the funnel goes on from it as it did then (the same bits
  // as a full run).
  std::size_t kept = 0;
  while (kept < bends_.size() && bends_[kept].seen < from) ++kept;
  bends_.resize(kept);
  taut_.resize(kept + 1);
  taut_[0] = portals_[0].l;
  Point2 apex = taut_.back(), left = apex, right = apex;
  // note: whether left (right) is the apex, kept as a flag: an end is only ever set to a point
  // other than the apex (the same test as comparing the points, fewer instructions).
  bool left_free = true, right_free = true;
  std::size_t left_i = kept > 0 ? bends_.back().portal : 0, right_i = left_i;
  std::size_t seen = kept > 0 ? bends_.back().seen : 0;  // the last portal read
  auto bend = [&](Point2 p, std::size_t i, std::uint32_t vertex) {
    taut_.push_back(p);
    bends_.push_back({vertex, i, seen});
    apex = left = right = p;
    left_free = right_free = true;
    left_i = right_i = i;
  };
  for (std::size_t i = left_i + 1; i < portals_.size(); ++i) {
    seen = std::max(seen, i);
    const Portal& p = portals_[i];
    // note: an end at the apex (unconstrained) narrows anything; a new end is checked against
    // the other side unless that one is unconstrained too, or the same point (the target).
    if (!same(p.r, apex) && (right_free || cross(apex, right, p.r) >= 0)) {
      if (left_free || same(p.r, left) || cross(apex, left, p.r) < 0) {
        right = p.r;
        right_free = false;
        right_i = i;
      } else {
        // The right side crosses the left one: the path bends at the left end.
        bend(left, left_i, portals_[left_i].left);
        i = left_i;
        continue;
      }
    }
    if (!same(p.l, apex) && (left_free || cross(apex, left, p.l) <= 0)) {
      if (right_free || same(p.l, right) || cross(apex, right, p.l) > 0) {
        left = p.l;
        left_free = false;
        left_i = i;
      } else {
        bend(right, right_i, portals_[right_i].right);
        i = right_i;
        continue;
      }
    }
  }
  taut_.push_back(portals_.back().l);
  double len = 0;
  for (std::size_t i = 1; i < taut_.size(); ++i) {
    len += std::hypot(taut_[i].x - taut_[i - 1].x, taut_[i].y - taut_[i - 1].y);
  }
  return len;
}

double PathStraightener::inside_angle(const Bend& b, std::size_t first, std::size_t last,
                                      Point2 prev, Point2 next) const {
  // The path meets v inside the run's first face and leaves it inside its last (a straight
  // segment that crossed an edge at v first would lie on that edge): the angle swept on the
  // strip's side is the part of the first face beyond the incoming segment, the faces between,
  // and the part of the last face before the outgoing one.
  const Portal& bp = portals_[b.portal];
  const Point2 v = bp.left == b.vertex ? bp.l : bp.r;
  auto other_end = [&](std::size_t portal) {
    const Portal& p = portals_[portal];
    return p.left == b.vertex ? Point2{p.r.x - v.x, p.r.y - v.y} : Point2{p.l.x - v.x, p.l.y - v.y};
  };
  auto angle = [](Point2 a, Point2 c) {
    return std::atan2(std::fabs(a.x * c.y - a.y * c.x), a.x * c.x + a.y * c.y);
  };
  const Point2 in{prev.x - v.x, prev.y - v.y}, out{next.x - v.x, next.y - v.y};
  double sum = angle(in, other_end(first + 1)) + angle(other_end(last), out);
  for (std::size_t j = first + 1; j < last; ++j) sum += g_.corner_angle(strip_[j], b.vertex);
  return sum;
}

double PathStraightener::length(const SurfacePoint& source, const std::vector<std::uint32_t>& nodes,
                                const SurfacePoint& target) {
  ++stats_.paths;
  // note: a path through a vertex whose faces are more than one fan (where a void touches
  // itself, corner to corner) may pass there from one fan to another, which no strip of faces
  // does: it is cut at each such vertex, each part pulled taut on its own (a locally shortest
  // path through a vertex is one to it and one from it), and their lengths added. Before, on
  // pyrenees_andorra_voids (10 % qem mesh, 30 points) 322 of 5738 paths kept their Steiner
  // length, 64 of the pairs' distances on the two meshes.
  const TriMesh& m = g_.mesh();
  split_ = false;
  PathRoute cut;
  double total = 0;
  SurfacePoint from = source;
  std::size_t begin = 0;
  for (;;) {
    std::size_t pinch = kNoPinch;
    std::uint32_t next_face = SteinerGraph::kNoFace;
    if (build_strip(from, nodes, begin, target, pinch, next_face)) break;
    if (pinch == kNoPinch) {
      ++stats_.failed;
      return -1;
    }
    const std::uint32_t v = nodes[pinch];
    const SurfacePoint at{m.xyz[3 * v], m.xyz[3 * v + 1], m.xyz[3 * v + 2], strip_.back()};
    const double len = pull_taut(from, at);
    if (len < 0) return -1;
    total += len;
    append_part(cut, &at);
    from = at;
    from.face = next_face;
    begin = pinch + 1;
  }
  const double last = pull_taut(from, target);
  if (last < 0 || begin == 0) return last;
  append_part(cut, nullptr);
  split_route_ = std::move(cut);
  split_ = true;
  return total + last;
}

void PathStraightener::append_part(PathRoute& cut, const SurfacePoint* end) {
  taut_route(part_);
  cut.bends.insert(cut.bends.end(), part_.bends.begin(), part_.bends.end());
  cut.taut.insert(cut.taut.end(), part_.taut.begin(), part_.taut.end());
  if (end) {
    cut.bends.push_back({end->x, end->y});
    cut.taut.push_back({end->x, end->y});
  }
}

double PathStraightener::pull_taut(const SurfacePoint& source, const SurfacePoint& target) {
  source_xy_ = {source.x, source.y};
  target_xy_ = {target.x, target.y};
  struct Reroute {
    std::size_t first, last, fan_begin, fan_end;
  };
  std::vector<Reroute> reroutes;
  std::vector<std::uint32_t> fans;
  double best = std::numeric_limits<double>::infinity();
  // note: each pass unfolds and pulls taut again from the first face the last one's reroutes
  // changed.
  std::size_t from = 0;
  for (int pass = 0; pass < kMaxPasses; ++pass) {
    if (!unfold(source, target, from)) break;
    const double len = funnel(from);
    ++stats_.passes;
    // note: each reroute shortens the path; one that does not (rounding) ends the passes.
    if (!(len < best * (1 - 1e-12))) return std::min(len, best);
    best = len;
    // Bends whose other side is shorter than pi: the path through that side is shorter.
    // note: one reroute per run of faces in a pass (runs of later bends must not overlap).
    reroutes.clear();
    fans.clear();
    std::size_t free_from = 0;
    for (std::size_t k = 0; k < bends_.size(); ++k) {
      const Bend& b = bends_[k];
      std::size_t first = b.portal - 1, last = b.portal;
      while (first > 0 && contains(strip_[first - 1], b.vertex)) --first;
      while (last + 1 < strip_.size() && contains(strip_[last + 1], b.vertex)) ++last;
      // note: a bend kept from the last pass (fixed reading only portals before `from`: a bend
      // this pass fixed read a later one) whose faces and next bend are too was found there not
      // to be rerouted (a reroute would have changed those faces).
      if (k + 1 < bends_.size() && bends_[k + 1].seen < from && last + 1 < from) continue;
      if (first < free_from) continue;
      const double total = total_angle(b.vertex, strip_[first]);
      if (total < 0) continue;  // on the outline: nothing on the other side
      const double inside = inside_angle(b, first, last, taut_[k], taut_[k + 2]);
      if (!(total - inside < kPi - 1e-9)) continue;
      const std::size_t begin = fans.size();
      if (!walk_around(b.vertex, strip_[first], strip_[last], false, strip_[first + 1], fan_)) {
        continue;
      }
      fans.insert(fans.end(), fan_.begin(), fan_.end());
      reroutes.push_back({first, last, begin, fans.size()});
      free_from = last;
    }
    if (reroutes.empty()) return len;
    stats_.reroutes += reroutes.size();
    next_strip_.swap(strip_);
    strip_.clear();
    std::size_t j = 0;
    for (const Reroute& r : reroutes) {
      for (; j <= r.first; ++j) push_face(next_strip_[j]);
      for (std::size_t f = r.fan_begin; f < r.fan_end; ++f) push_face(fans[f]);
      j = r.last;
    }
    for (; j < next_strip_.size(); ++j) push_face(next_strip_[j]);
    from = static_cast<std::size_t>(
        std::mismatch(strip_.begin(), strip_.end(), next_strip_.begin(), next_strip_.end()).first -
        strip_.begin());
  }
  if (best < std::numeric_limits<double>::infinity()) return best;
  ++stats_.failed;
  return -1;
}

double PathStraightener::shortest(const GeodesicQuery& query, const SurfacePoint& source,
                                  std::size_t target, const SurfacePoint& target_point,
                                  double steiner_distance, PathRoute* route) {
  if (!std::isfinite(steiner_distance)) return steiner_distance;
  double best = std::numeric_limits<double>::infinity();
  if (route) {
    route->bends.clear();
    route->taut.clear();
  }
  query.path(target, path_);
  const double direct = length(source, path_, target_point);
  if (direct >= 0) {
    best = direct;
    if (route) taut_route(*route);
  }
  // note: a node reached from a node already tried, or from the source, ends the same path
  // taut in the same way: one path per predecessor.
  tried_.clear();
  if (!path_.empty()) {
    tried_.push_back(path_.back());
    if (path_.size() > 1) tried_.push_back(path_[path_.size() - 2]);
  }
  // note: a path whose nodes join one tried already within kJoinSteps of the target's face, and
  // within its last `tail` (the search's paths form a tree: from there on they are one), takes
  // the same route but for its last faces: it is not tried again (about a quarter of the paths
  // straightened on San Gabriel; against exact geodesics the measure moved by 0.02 % at most
  // on three DEMs, every mode at 10 and 50 %). Where the route is no longer than two tails,
  // every path is tried (two routes round a hill share only their first nodes).
  const double tail = kJoinSteps * g_.max_segment();
  const bool check_joins = steiner_distance > 2 * tail;
  on_paths_.clear();
  if (check_joins) {
    on_paths_.assign(path_.begin(), path_.end());
    std::sort(on_paths_.begin(), on_paths_.end());
  }
  g_.face_nodes(target_point.face, around_);
  for (std::uint32_t v : around_) {
    if (!std::isfinite(query.settled_distance(v))) continue;
    const std::uint32_t p = query.pred(v);
    if (p == LabelHeap::kNone || std::find(tried_.begin(), tried_.end(), v) != tried_.end() ||
        std::find(tried_.begin(), tried_.end(), p) != tried_.end()) {
      continue;
    }
    tried_.push_back(p);
    bool joins = false;
    std::uint32_t w = p;
    for (int step = 0; check_joins && step < kJoinSteps && w != LabelHeap::kNone && !joins;
         ++step) {
      joins = std::binary_search(on_paths_.begin(), on_paths_.end(), w) &&
              query.settled_distance(w) >= steiner_distance - tail;
      w = query.pred(w);
    }
    if (joins) continue;
    query.path_to_node(v, path_);
    if (check_joins) {
      on_paths_.insert(on_paths_.end(), path_.begin(), path_.end());
      std::sort(on_paths_.begin(), on_paths_.end());
    }
    const double len = length(source, path_, target_point);
    if (len >= 0 && len < best) {
      best = len;
      if (route) taut_route(*route);
    }
  }
  // note: the straightened lengths, not the search's (an anchored search rounds its anchors
  // to floats, so its distance may sit a hair below the path it stands for).
  return std::isfinite(best) ? best : steiner_distance;
}

std::array<double, 2> PathStraightener::vertex_xy(std::uint32_t v) const {
  const TriMesh& m = g_.mesh();
  return {m.xyz[3 * v], m.xyz[3 * v + 1]};
}

std::uint32_t PathStraightener::face_toward(std::uint32_t v, std::array<double, 2> q) const {
  const TriMesh& m = g_.mesh();
  std::uint32_t found = SteinerGraph::kNoFace;
  const auto o = vertex_xy(v);
  g_.for_each_face_of_vertex(v, [&](std::uint32_t g) {
    if (found != SteinerGraph::kNoFace) return;
    const auto& c = m.faces[g];
    const int i = c[0] == v ? 0 : c[1] == v ? 1 : 2;
    const auto a = vertex_xy(c[(i + 1) % 3]), b = vertex_xy(c[(i + 2) % 3]);
    const double sign = orient2(o, a, b) < 0 ? -1.0 : 1.0;
    if (sign * orient2(o, a, q) >= 0 && sign * orient2(o, q, b) >= 0) found = g;
  });
  return found;
}

int PathStraightener::edge_to(std::uint32_t f, std::uint32_t g) const {
  int edge = -1;
  for (int i = 0; i < 3; ++i) {
    if (g_.across(f, i) == g) edge = i;
  }
  return edge;
}

int PathStraightener::exit_edge(std::uint32_t f, int entry, std::array<double, 2> p,
                                std::array<double, 2> q, double& ta, double& tb) const {
  const auto& c = g_.mesh().faces[f];
  const double sign = orient2(vertex_xy(c[0]), vertex_xy(c[1]), vertex_xy(c[2])) < 0 ? -1.0 : 1.0;
  for (int i = 0; i < 3; ++i) {
    if (i == entry) continue;
    const auto a = vertex_xy(c[i]), b = vertex_xy(c[(i + 1) % 3]);
    if (!(sign * orient2(a, b, q) < 0)) continue;  // q not beyond this edge
    ta = orient2(p, q, a);
    tb = orient2(p, q, b);
    if ((ta <= 0 && tb >= 0) || (ta >= 0 && tb <= 0)) return i;
  }
  return -1;
}

void PathStraightener::taut_route(PathRoute& route) const {
  if (split_) {
    route = split_route_;
    return;
  }
  const TriMesh& m = g_.mesh();
  route.bends.clear();
  route.taut.clear();
  for (const Bend& b : bends_) route.bends.push_back(vertex_xy(b.vertex));
  // Every crossing of the taut path with a portal (a bend: its vertex), between the ends.
  std::vector<std::array<double, 2>>& pts = route.taut;
  std::vector<char> keep;
  pts.push_back(source_xy_);
  keep.push_back(1);
  std::size_t k = 0;  // the taut path's segment: from taut_[k] to taut_[k + 1]
  for (std::size_t j = 1; j + 1 < portals_.size(); ++j) {
    for (; k < bends_.size() && bends_[k].portal < j; ++k) {
      pts.push_back(vertex_xy(bends_[k].vertex));
      keep.push_back(1);
    }
    if (k < bends_.size() && bends_[k].portal == j) continue;  // crossed at the bend
    const Portal& p = portals_[j];
    const Point2 a = taut_[k], b = taut_[k + 1];
    const double dl = (b.x - a.x) * (p.l.y - a.y) - (b.y - a.y) * (p.l.x - a.x);
    const double dr = (b.x - a.x) * (p.r.y - a.y) - (b.y - a.y) * (p.r.x - a.x);
    const double t = dl == dr ? 0.5 : std::clamp(dl / (dl - dr), 0.0, 1.0);
    const double* l = &m.xyz[3 * p.left];
    const double* r = &m.xyz[3 * p.right];
    pts.push_back({l[0] + t * (r[0] - l[0]), l[1] + t * (r[1] - l[1])});
    keep.push_back(0);
  }
  for (; k < bends_.size(); ++k) {
    pts.push_back(vertex_xy(bends_[k].vertex));
    keep.push_back(1);
  }
  pts.push_back(target_xy_);
  keep.push_back(1);
  // Thinned (Douglas-Peucker) between the bends: a crossing stays where it lies farther than
  // the tolerance from the line through its neighbours kept.
  const double tolerance = kTautTolerance * g_.delta();
  std::vector<std::pair<std::size_t, std::size_t>> spans;
  for (std::size_t i = 1, last = 0; i < pts.size(); ++i) {
    if (keep[i]) spans.push_back({last, i}), last = i;
  }
  while (!spans.empty()) {
    const auto [lo, hi] = spans.back();
    spans.pop_back();
    const double dx = pts[hi][0] - pts[lo][0], dy = pts[hi][1] - pts[lo][1];
    const double len = std::hypot(dx, dy);
    double worst = tolerance;
    std::size_t at = lo;
    for (std::size_t i = lo + 1; i < hi; ++i) {
      const double ex = pts[i][0] - pts[lo][0], ey = pts[i][1] - pts[lo][1];
      const double off = len > 0 ? std::fabs(dx * ey - dy * ex) / len : std::hypot(ex, ey);
      if (off > worst) worst = off, at = i;
    }
    if (at == lo) continue;
    keep[at] = 1;
    spans.push_back({lo, at});
    spans.push_back({at, hi});
  }
  std::size_t n = 0;
  for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
    if (keep[i]) pts[n++] = pts[i];
  }
  pts.resize(n);
}

double PathStraightener::follow(const SurfacePoint& source,
                                const std::vector<std::array<double, 2>>& route,
                                const SurfacePoint& target, PathRoute* taut) {
  split_ = false;
  if (taut) {
    taut->bends.clear();
    taut->taut.clear();
  }
  ++stats_.paths;
  const TriMesh& m = g_.mesh();
  // The strip is the faces the route crosses, walked straight (seen from above) from point to
  // point: the route's own way past every vertex, which the taut path then keeps unless a
  // vertex's other side is shorter. note: on a synthetic volcano (bench/synthetic_dems.py),
  // the exact geodesic's bends alone, walked by along() or here, gave a path 0.17 % long (the
  // straight lines between them passed a vertex on its other side); its taut points, here, the
  // geodesic itself. note: a walk that does not reach q within as many steps as the mesh has
  // faces is given up (a degenerate face).
  strip_.clear();
  push_face(source.face);
  std::uint32_t f = source.face;
  int entry = -1;
  std::size_t steps = 0;
  // note: a route through a vertex from one of its fans to another (where a void touches
  // itself corner to corner) is cut there, as length() cuts a path: the strip so far pulled
  // taut to the vertex, the rest from it, their lengths added.
  SurfacePoint from = source;
  PathRoute cut;
  double total = 0;
  // From f to face g around their common corner v (the side with fewer faces between).
  auto around = [&](std::uint32_t v, std::uint32_t g) {
    if (g == f) return true;
    if (!walk_around(v, f, g, true, SteinerGraph::kNoFace, fan_)) {
      // g lies in another of v's fans: the path so far ends at v.
      const SurfacePoint at{m.xyz[3 * v], m.xyz[3 * v + 1], m.xyz[3 * v + 2], f};
      const double len = pull_taut(from, at);
      if (len < 0) return false;
      total += len;
      append_part(cut, &at);
      from = at;
      from.face = g;
      strip_.clear();
      push_face(g);
      f = g;
      return true;
    }
    for (std::uint32_t h : fan_) push_face(h);
    push_face(g);
    f = g;
    return true;
  };
  // Where p is a corner of f (a route point on a vertex, or a crossing through one), f becomes
  // the face around it the segment to q leaves through: the face it came by may lie on another
  // side (a vertex of the outline, a sharp turn).
  auto pivot = [&](std::array<double, 2> p, std::array<double, 2> q) {
    for (std::uint32_t v : m.faces[f]) {
      if (vertex_xy(v) != p) continue;
      const std::uint32_t g = face_toward(v, q);
      if (g == SteinerGraph::kNoFace) return true;
      return around(v, g);
    }
    return true;
  };
  auto walk = [&](std::array<double, 2> p, std::array<double, 2> q) {
    // note: a segment may leave back through the edge the last one came in by (a sharp turn).
    entry = -1;
    if (!pivot(p, q)) return false;
    for (;;) {
      double ta = 0, tb = 0;
      const int exit = exit_edge(f, entry, p, q, ta, tb);
      if (exit < 0) return true;  // q is in f
      if (++steps > m.faces.size()) return false;
      std::uint32_t next = g_.across(f, exit);
      if (next == SteinerGraph::kNoFace && (ta == 0 || tb == 0)) {
        // Through a corner on the outline: on from that corner, into the face ahead.
        const std::uint32_t v = m.faces[f][ta == 0 ? exit : (exit + 1) % 3];
        next = face_toward(v, q);
        if (next == SteinerGraph::kNoFace || next == f || !around(v, next)) return false;
        entry = -1;
        continue;
      }
      if (next == SteinerGraph::kNoFace) return false;
      entry = edge_to(next, f);
      push_face(next);
      f = next;
    }
  };
  auto failed = [&] {
    ++stats_.failed;
    return -1.0;
  };
  std::array<double, 2> p{source.x, source.y};
  for (const auto& q : route) {
    if (!walk(p, q)) return failed();
    p = q;
  }
  if (!walk(p, {target.x, target.y})) return failed();
  if (f != target.face) {
    // The target on an edge or a corner of the face the walk ended in (its own face holds it
    // too): into its face across that edge, or around that corner.
    if (edge_to(f, target.face) >= 0) {
      push_face(target.face);
      f = target.face;
    } else {
      std::uint32_t shared = SteinerGraph::kNoFace;
      for (std::uint32_t v : m.faces[f]) {
        if (contains(target.face, v)) shared = v;
      }
      if (shared == SteinerGraph::kNoFace || !around(shared, target.face)) return failed();
    }
  }
  if (strip_.front() != from.face || strip_.back() != target.face) return failed();
  const double len = pull_taut(from, target);
  if (len < 0) return len;
  if (!cut.taut.empty()) {  // cut at a vertex (its point ends each part but the last)
    append_part(cut, nullptr);
    split_route_ = std::move(cut);
    split_ = true;
  }
  if (taut) taut_route(*taut);
  return total + len;
}

double PathStraightener::along(const SurfacePoint& source,
                               const std::vector<std::array<double, 2>>& route,
                               const SurfacePoint& target, PathRoute* bends) {
  if (bends) {
    bends->bends.clear();
    bends->taut.clear();
  }
  const TriMesh& m = g_.mesh();
  // Walks straight (seen from above) from p to q across the faces from f, appending the node
  // nearest each edge crossed; f ends as q's face. note: a walk that does not reach q within
  // as many steps as the mesh has faces is given up (a degenerate face).
  std::vector<std::uint32_t>& nodes = path_;
  nodes.clear();
  std::uint32_t f = source.face;
  int entry = -1;
  std::size_t steps = 0;
  // Where p is a corner of f (a route point on a vertex, or a crossing through one), f becomes
  // the face around it the segment to q leaves through: the face it came by may lie on another
  // side (a vertex of the outline, a sharp turn).
  auto pivot = [&](std::array<double, 2> p, std::array<double, 2> q) {
    for (std::uint32_t v : m.faces[f]) {
      if (vertex_xy(v) != p) continue;
      const std::uint32_t g = face_toward(v, q);
      if (g == SteinerGraph::kNoFace || g == f) return;
      // note: the path passes through v (the faces between f and g share only v).
      if (nodes.empty() || nodes.back() != v) nodes.push_back(v);
      f = g;
      return;
    }
  };
  auto walk = [&](std::array<double, 2> p, std::array<double, 2> q) {
    // note: a segment may leave back through the edge the last one came in by (a sharp turn).
    entry = -1;
    pivot(p, q);
    for (;;) {
      double ta = 0, tb = 0;
      const int exit = exit_edge(f, entry, p, q, ta, tb);
      if (exit < 0) return true;  // q is in f
      if (++steps > m.faces.size()) return false;
      // The crossing, as a fraction of the edge from corner `exit`; the node nearest it.
      const double t = ta == tb ? 0.5 : ta / (ta - tb);
      g_.edge_nodes(f, exit, around_);
      const auto pick = around_[static_cast<std::size_t>(
          std::lround(std::clamp(t, 0.0, 1.0) * static_cast<double>(around_.size() - 1)))];
      if (nodes.empty() || nodes.back() != pick) nodes.push_back(pick);
      std::uint32_t next = g_.across(f, exit);
      if (next == SteinerGraph::kNoFace && (ta == 0 || tb == 0)) {
        // Through a corner on the outline: on from that corner, into the face ahead.
        const std::uint32_t v = m.faces[f][ta == 0 ? exit : (exit + 1) % 3];
        next = face_toward(v, q);
        if (next == SteinerGraph::kNoFace || next == f) return false;
        f = next;
        entry = -1;
        continue;
      }
      if (next == SteinerGraph::kNoFace) return false;
      entry = edge_to(next, f);
      f = next;
    }
  };
  std::array<double, 2> p{source.x, source.y};
  for (const auto& q : route) {
    if (!walk(p, q)) return -1;
    p = q;
  }
  if (!walk(p, {target.x, target.y})) return -1;
  std::uint32_t at_corner = SteinerGraph::kNoFace;
  for (std::uint32_t v : m.faces[f]) {
    if (f != target.face && vertex_xy(v) == std::array<double, 2>{target.x, target.y})
      at_corner = v;
  }
  if (f != target.face && at_corner != SteinerGraph::kNoFace) {
    // The target on a corner of the face the walk ended in (a vertex, which the target's own
    // face holds too): through that vertex.
    if (nodes.empty() || nodes.back() != at_corner) nodes.push_back(at_corner);
  } else if (f != target.face) {
    // The target on an edge of the face the walk ended in: through the node of their shared
    // edge nearest it.
    const int shared = edge_to(f, target.face);
    if (shared < 0) return -1;
    g_.edge_nodes(f, shared, around_);
    std::uint32_t pick = around_[0];
    double best = std::numeric_limits<double>::infinity();
    for (std::uint32_t v : around_) {
      const double* q = g_.position(v);
      const double d2 =
          (q[0] - target.x) * (q[0] - target.x) + (q[1] - target.y) * (q[1] - target.y);
      if (d2 < best) {
        best = d2;
        pick = v;
      }
    }
    if (nodes.empty() || nodes.back() != pick) nodes.push_back(pick);
  }
  const double len = length(source, nodes, target);
  if (bends && len >= 0) taut_route(*bends);
  return len;
}

}  // namespace dpts::core
