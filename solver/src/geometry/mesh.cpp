#include "fibre/geometry/mesh.hpp"

#include <cmath>

#include <algorithm>
#include <array>
#include <limits>
#include <map>
#include <utility>

namespace fibre {

namespace {

// num / den clamped to [0, 1]; 0 when den is not positive (a zero-length edge), so that
// rounding at region boundaries never yields NaN or a point off the triangle.
double ratio(double num, double den)
{
  if (!(den > 0.0)) return 0.0;
  return std::min(1.0, std::max(0.0, num / den));
}

// Closest point of segment p + t (q - p), t in [0, 1]; a zero-length segment is its point.
Vec3 closest_on_segment(const Vec3 &x, const Vec3 &p, const Vec3 &q, double &t)
{
  const Vec3 d = q - p;
  t = ratio((x - p).dot(d), d.squaredNorm());
  return p + t * d;
}

// The edge or node the parameter t of an edge lands on.
TriangleFeature edge_feature(double t)
{
  return (t > 0.0 && t < 1.0) ? TriangleFeature::edge : TriangleFeature::vertex;
}

// A zero-area triangle: its longest edge contains the third node (collinear) or all three
// coincide, so the closest point of that segment is the closest point of the triangle.
Vec3 closest_on_degenerate(const Vec3 &x, const Vec3 &a, const Vec3 &b, const Vec3 &c,
                           double bary[3], TriangleFeature &feature)
{
  const Vec3 *node[3] = {&a, &b, &c};
  const double len2[3] = {(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()};
  const int e = static_cast<int>(std::max_element(len2, len2 + 3) - len2); // edge e: e -> e+1
  const int i = e, j = (e + 1) % 3;
  double t = 0.0;
  const Vec3 point = closest_on_segment(x, *node[i], *node[j], t);
  bary[0] = bary[1] = bary[2] = 0.0;
  bary[i] = 1.0 - t;
  bary[j] += t;
  feature = edge_feature(t);
  return point;
}

// The longest edge of a triangle (its scale).
double longest_edge(const Triangle &tri)
{
  return std::sqrt(
      std::max({(tri.p[1] - tri.p[0]).squaredNorm(), (tri.p[2] - tri.p[1]).squaredNorm(),
                (tri.p[0] - tri.p[2]).squaredNorm()}));
}

// The normal of a centre lying on the triangle: the geometric face normal; for a zero-area
// triangle a unit vector normal to its longest edge, for a point +z.
Vec3 face_normal(const Triangle &tri)
{
  const Vec3 n = (tri.p[1] - tri.p[0]).cross(tri.p[2] - tri.p[0]);
  const double len = n.norm();
  if (len > 0.0 && std::isfinite(len)) return n / len;
  Vec3 edge = tri.p[1] - tri.p[0];
  for (const Vec3 &other : {Vec3(tri.p[2] - tri.p[1]), Vec3(tri.p[0] - tri.p[2])})
    if (other.squaredNorm() > edge.squaredNorm()) edge = other;
  if (edge.squaredNorm() > 0.0 && edge.allFinite()) return edge.unitOrthogonal();
  return Vec3::UnitZ();
}

} // namespace

Vec3 closest_point_on_triangle(const Vec3 &x, const Vec3 &a, const Vec3 &b, const Vec3 &c,
                               double bary[3], TriangleFeature &feature)
{
  const Vec3 ab = b - a, ac = c - a;
  // Zero area relative to the edges (collinear or coincident nodes): the region tests below
  // divide by edge lengths and the area, so take the segment path.
  const double len2 = std::max({ab.squaredNorm(), ac.squaredNorm(), (c - b).squaredNorm()});
  if (!(ab.cross(ac).squaredNorm() > 1e-24 * len2 * len2))
    return closest_on_degenerate(x, a, b, c, bary, feature);

  auto set = [&](double u, double v, double w, TriangleFeature f) {
    bary[0] = u;
    bary[1] = v;
    bary[2] = w;
    feature = f;
    return Vec3(u * a + v * b + w * c);
  };

  // Node regions: x lies behind both edges leaving the node.
  const Vec3 ax = x - a;
  const double d1 = ab.dot(ax), d2 = ac.dot(ax);
  if (d1 <= 0.0 && d2 <= 0.0) return set(1, 0, 0, TriangleFeature::vertex);
  const Vec3 bx = x - b;
  const double d3 = ab.dot(bx), d4 = ac.dot(bx);
  if (d3 >= 0.0 && d4 <= d3) return set(0, 1, 0, TriangleFeature::vertex);
  const Vec3 cx = x - c;
  const double d5 = ab.dot(cx), d6 = ac.dot(cx);
  if (d6 >= 0.0 && d5 <= d6) return set(0, 0, 1, TriangleFeature::vertex);

  // Edge regions: x projects inside the edge's span and beyond the edge in the triangle's
  // plane. va, vb, vc are the barycentric coordinates of x's projection times |ab x ac|^2 (they
  // sum to it); vc <= 0 puts it beyond edge ab, vb beyond ac, va beyond bc.
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double t = ratio(d1, d1 - d3); // along ab; d1 - d3 = |ab|^2
    return set(1 - t, t, 0, edge_feature(t));
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double t = ratio(d2, d2 - d6); // along ac; d2 - d6 = |ac|^2
    return set(1 - t, 0, t, edge_feature(t));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    const double t = ratio(d4 - d3, (d4 - d3) + (d5 - d6)); // along bc; the sum is |bc|^2
    return set(0, 1 - t, t, edge_feature(t));
  }

  // Face region: the barycentric coordinates are the sub-areas over the whole area. Rounding
  // near a boundary may leave one slightly negative; clamp so the point stays on the triangle.
  const double u = std::max(va, 0.0), v = std::max(vb, 0.0), w = std::max(vc, 0.0);
  const double sum = u + v + w;
  if (!(sum > 0.0) || !std::isfinite(sum)) return closest_on_degenerate(x, a, b, c, bary, feature);
  return set(u / sum, v / sum, w / sum, TriangleFeature::face);
}

namespace {

// The grid's cell: the given one, else about one triangle across (its middle extent, mean_size),
// which keeps both the lists and the cells scanned per query short; grown until the grid has
// at most TriangleGrid::kMaxCells cells.
double grid_cell(double cell, double mean_size, const Vec3 &extent)
{
  if (!(cell > 0.0) || !std::isfinite(cell)) cell = mean_size;
  if (!(cell > 0.0)) cell = extent.maxCoeff();
  if (!(cell > 0.0)) cell = 1.0; // all triangles are one point
  for (;;) {
    double total = 1.0;
    for (int d = 0; d < 3; ++d) total *= std::floor(extent[d] / cell) + 1.0;
    if (total <= TriangleGrid::kMaxCells) return cell;
    cell *= std::max(1.01, std::cbrt(total / TriangleGrid::kMaxCells));
  }
}

} // namespace

void TriangleGrid::build(const std::vector<Triangle> &tris, double cell)
{
  const int n = static_cast<int>(tris.size());
  const double inf = std::numeric_limits<double>::infinity();
  box_lo_.assign(n, Vec3::Constant(inf));
  box_hi_.assign(n, Vec3::Constant(-inf));
  Vec3 lo = Vec3::Constant(inf), hi = Vec3::Constant(-inf);
  double size_sum = 0.0;
  int finite = 0;
  for (int t = 0; t < n; ++t) {
    const Triangle &tri = tris[t];
    // A triangle with a non-finite node keeps an empty box: never binned, never a candidate.
    if (!tri.p[0].allFinite() || !tri.p[1].allFinite() || !tri.p[2].allFinite()) continue;
    box_lo_[t] = tri.p[0].cwiseMin(tri.p[1]).cwiseMin(tri.p[2]);
    box_hi_[t] = tri.p[0].cwiseMax(tri.p[1]).cwiseMax(tri.p[2]);
    lo = lo.cwiseMin(box_lo_[t]);
    hi = hi.cwiseMax(box_hi_[t]);
    // the middle extent: a long thin facet (a silo's side) spans many cells instead of making
    // every cell as long as itself
    Vec3 extent = box_hi_[t] - box_lo_[t];
    std::sort(extent.data(), extent.data() + 3);
    size_sum += extent[1];
    ++finite;
  }
  items_.clear();
  cell_start_.assign(1, 0);
  dims_[0] = dims_[1] = dims_[2] = 0;
  if (finite == 0) return;
  lo_ = lo;
  hi_ = hi;

  const Vec3 extent = hi - lo;
  cell = grid_cell(cell, size_sum / finite, extent);
  cell_ = cell;
  for (int d = 0; d < 3; ++d) dims_[d] = static_cast<int>(std::floor(extent[d] / cell)) + 1;

  // Two passes (count, fill) into a compressed row layout.
  const int ncells = dims_[0] * dims_[1] * dims_[2];
  cell_start_.assign(ncells + 1, 0);
  int r0[3], r1[3];
  auto range = [&](int t) {
    for (int d = 0; d < 3; ++d) {
      r0[d] = coord(d, box_lo_[t][d]);
      r1[d] = coord(d, box_hi_[t][d]);
    }
  };
  for (int pass = 0; pass < 2; ++pass) {
    for (int t = 0; t < n; ++t) {
      if (!(box_lo_[t][0] <= box_hi_[t][0])) continue; // empty box
      range(t);
      for (int k = r0[2]; k <= r1[2]; ++k)
        for (int j = r0[1]; j <= r1[1]; ++j)
          for (int i = r0[0]; i <= r1[0]; ++i) {
            const int c = cell_index(i, j, k);
            if (pass == 0)
              ++cell_start_[c + 1];
            else
              items_[cell_start_[c]++] = t;
          }
    }
    if (pass == 0) {
      for (int c = 0; c < ncells; ++c) cell_start_[c + 1] += cell_start_[c];
      items_.resize(cell_start_[ncells]);
    } else {
      // the fill advanced each start to the next cell's; shift back
      for (int c = ncells; c > 0; --c) cell_start_[c] = cell_start_[c - 1];
      cell_start_[0] = 0;
    }
  }
}

int TriangleGrid::coord(int d, double v) const
{
  const double f = std::floor((v - lo_[d]) / cell_);
  return static_cast<int>(std::min(static_cast<double>(dims_[d] - 1), std::max(0.0, f)));
}

void TriangleGrid::candidates(const Vec3 &x, double reach, std::vector<int> &out) const
{
  out.clear();
  if (dims_[0] == 0 || !(reach >= 0.0) || !x.allFinite()) return;
  const Vec3 qlo = x.array() - reach, qhi = x.array() + reach;
  for (int d = 0; d < 3; ++d)
    if (qhi[d] < lo_[d] || qlo[d] > hi_[d]) return;
  int r0[3], r1[3];
  for (int d = 0; d < 3; ++d) {
    r0[d] = coord(d, qlo[d]);
    r1[d] = coord(d, qhi[d]);
  }
  for (int k = r0[2]; k <= r1[2]; ++k)
    for (int j = r0[1]; j <= r1[1]; ++j)
      for (int i = r0[0]; i <= r1[0]; ++i) {
        const int c = cell_index(i, j, k);
        for (int s = cell_start_[c]; s < cell_start_[c + 1]; ++s) {
          const int t = items_[s];
          if ((x.array() >= box_lo_[t].array() - reach).all() &&
              (x.array() <= box_hi_[t].array() + reach).all())
            out.push_back(t);
        }
      }
  // a triangle spanning several cells is listed in each
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

int mesh_hits(const std::vector<Triangle> &tris, const TriangleGrid &grid, const Vec3 &x,
              double reach, std::vector<TriangleHit> &hits)
{
  MeshScratch scratch;
  return mesh_hits(tris, grid, x, reach, hits, scratch);
}

int mesh_hits(const std::vector<Triangle> &tris, const TriangleGrid &grid, const Vec3 &x,
              double reach, std::vector<TriangleHit> &hits, MeshScratch &scratch)
{
  std::vector<int> &candidates = scratch.candidates;
  candidates.clear();
  grid.candidates(x, reach, candidates);
  std::vector<TriangleHit> &found = scratch.found;
  found.clear();
  for (int t : candidates) {
    if (t >= static_cast<int>(tris.size())) continue; // grid built on another array
    const Triangle &tri = tris[t];
    TriangleHit hit;
    double bary[3];
    hit.triangle = t;
    hit.point = closest_point_on_triangle(x, tri.p[0], tri.p[1], tri.p[2], bary, hit.feature);
    hit.distance = (x - hit.point).norm();
    if (!(hit.distance <= reach)) continue;
    // A centre on the triangle has no direction to the point: below rounding of the
    // coordinates take the face normal.
    const double on_face = 1e-12 * (longest_edge(tri) + x.cwiseAbs().maxCoeff());
    hit.normal = hit.distance > on_face ? Vec3((x - hit.point) / hit.distance) : face_normal(tri);
    hit.velocity = bary[0] * tri.v[0] + bary[1] * tri.v[1] + bary[2] * tri.v[2];
    found.push_back(hit);
  }
  // Smallest id first, so that of coincident points the smallest id is kept whatever the
  // storage order.
  std::sort(found.begin(), found.end(), [&](const TriangleHit &p, const TriangleHit &q) {
    const long ip = tris[p.triangle].id, iq = tris[q.triangle].id;
    return ip != iq ? ip < iq : p.triangle < q.triangle;
  });
  const double same = 1e-9 * std::max(1.0, reach);
  const std::size_t first = hits.size();
  for (const TriangleHit &hit : found) {
    bool duplicate = false;
    for (std::size_t k = first; k < hits.size() && !duplicate; ++k)
      duplicate = (hits[k].point - hit.point).norm() <= same;
    if (!duplicate) hits.push_back(hit);
  }
  return static_cast<int>(hits.size() - first);
}

int open_edges(const std::vector<Triangle> &tris, double tol)
{
  using Node = std::array<long long, 3>;
  const auto node = [tol](const Vec3 &p) {
    return Node{std::llround(p.x() / tol), std::llround(p.y() / tol), std::llround(p.z() / tol)};
  };
  std::map<std::pair<Node, Node>, int> uses;
  for (const Triangle &t : tris)
    for (int j = 0; j < 3; ++j) {
      Node a = node(t.p[j]), b = node(t.p[(j + 1) % 3]);
      if (a == b) continue; // a degenerate edge bounds nothing
      if (b < a) std::swap(a, b);
      ++uses[{a, b}];
    }
  int open = 0;
  for (const auto &edge : uses)
    if (edge.second == 1) ++open;
  return open;
}

} // namespace fibre
