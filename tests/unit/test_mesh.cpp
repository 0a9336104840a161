// Triangle-mesh walls without LIGGGHTS: the closest point's Voronoi regions, shared edges and
// nodes found once, the surface velocity of a rigid motion, and the bin grid against brute
// force, all against hand-computed cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "fibre/geometry/mesh.hpp"

using namespace fibre;

namespace {

Triangle triangle(const Vec3 &a, const Vec3 &b, const Vec3 &c, long id = 0)
{
  Triangle t;
  t.p[0] = a;
  t.p[1] = b;
  t.p[2] = c;
  for (Vec3 &v : t.v) v.setZero();
  t.id = id;
  return t;
}

struct Closest {
  Vec3 point;
  double bary[3];
  TriangleFeature feature;
};

Closest closest(const Vec3 &x, const Vec3 &a, const Vec3 &b, const Vec3 &c)
{
  Closest r;
  r.point = closest_point_on_triangle(x, a, b, c, r.bary, r.feature);
  return r;
}

void expect_near(const Vec3 &got, const Vec3 &want, double tol = 1e-14)
{
  EXPECT_NEAR((got - want).norm(), 0.0, tol)
      << "got " << got.transpose() << ", want " << want.transpose();
}

// The hits of x with every triangle, by brute force (no grid, no dedupe): indices within reach.
std::vector<int> brute_force(const std::vector<Triangle> &tris, const Vec3 &x, double reach)
{
  std::vector<int> out;
  for (int t = 0; t < static_cast<int>(tris.size()); ++t) {
    double bary[3];
    TriangleFeature f;
    const Vec3 p = closest_point_on_triangle(x, tris[t].p[0], tris[t].p[1], tris[t].p[2], bary, f);
    if ((x - p).norm() <= reach) out.push_back(t);
  }
  return out;
}

} // namespace

// Right triangle a = 0, b = 2 x, c = 2 y in the plane z = 0: one query in the face, in each
// edge region and in each node region, with the distances worked out by hand.
TEST(Mesh, ClosestPointInEveryVoronoiRegion)
{
  const Vec3 a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
  struct Case {
    Vec3 x, point;
    double distance;
    TriangleFeature feature;
    double bary[3];
  };
  const Case cases[] = {
      {Vec3(0.5, 0.5, 3), Vec3(0.5, 0.5, 0), 3.0, TriangleFeature::face, {0.5, 0.25, 0.25}},
      // edge ab (y < 0), edge ac (x < 0), edge bc (x + y > 2)
      {Vec3(1, -1, 2), Vec3(1, 0, 0), std::sqrt(5.0), TriangleFeature::edge, {0.5, 0.5, 0}},
      {Vec3(-2, 1, -1), Vec3(0, 1, 0), std::sqrt(5.0), TriangleFeature::edge, {0.5, 0, 0.5}},
      {Vec3(2, 2, 1), Vec3(1, 1, 0), std::sqrt(3.0), TriangleFeature::edge, {0, 0.5, 0.5}},
      // behind both edges at each node
      {Vec3(-1, -2, 0.5), a, std::sqrt(5.25), TriangleFeature::vertex, {1, 0, 0}},
      {Vec3(3, -1, 0), b, std::sqrt(2.0), TriangleFeature::vertex, {0, 1, 0}},
      {Vec3(-0.5, 3, 2), c, std::sqrt(5.25), TriangleFeature::vertex, {0, 0, 1}},
  };
  for (const Case &k : cases) {
    SCOPED_TRACE(testing::Message() << "x = " << k.x.transpose());
    const Closest r = closest(k.x, a, b, c);
    expect_near(r.point, k.point);
    EXPECT_NEAR((k.x - r.point).norm(), k.distance, 1e-14);
    EXPECT_EQ(r.feature, k.feature);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(r.bary[i], k.bary[i], 1e-15);
    expect_near(r.bary[0] * a + r.bary[1] * b + r.bary[2] * c, r.point);
  }
}

// On a triangle in general position the closest point p is the projection onto a convex set:
// (x - p) . (q - p) <= 0 for every node q, and p = sum bary_i q_i with bary >= 0, sum 1.
TEST(Mesh, ClosestPointIsTheProjectionOnRandomTriangles)
{
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  auto rnd = [&] { return Vec3(u(gen), u(gen), u(gen)); };
  int seen[3] = {0, 0, 0};
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 a = rnd(), b = rnd(), c = rnd(), x = 1.5 * rnd();
    const Closest r = closest(x, a, b, c);
    const Vec3 q[3] = {a, b, c};
    for (const Vec3 &node : q) EXPECT_LE((x - r.point).dot(node - r.point), 1e-12);
    double sum = 0.0;
    for (double w : r.bary) {
      EXPECT_GE(w, 0.0);
      sum += w;
    }
    EXPECT_NEAR(sum, 1.0, 1e-14);
    expect_near(r.bary[0] * a + r.bary[1] * b + r.bary[2] * c, r.point, 1e-13);
    const int zeros = (r.bary[0] == 0.0) + (r.bary[1] == 0.0) + (r.bary[2] == 0.0);
    EXPECT_EQ(static_cast<int>(r.feature), zeros); // face 0, edge 1, vertex 2 zero weights
    ++seen[static_cast<int>(r.feature)];
  }
  for (int f = 0; f < 3; ++f) EXPECT_GT(seen[f], 50);
}

// The unit square z = 0 as two triangles sharing the diagonal (0,0)-(1,1); ids 7 and 3.
TEST(Mesh, SharedDiagonalAndCornerOfAFlatSquareHitOnce)
{
  const Vec3 n0(0, 0, 0), n1(1, 0, 0), n2(1, 1, 0), n3(0, 1, 0);
  std::vector<Triangle> tris = {triangle(n0, n1, n2, 7), triangle(n0, n2, n3, 3)};
  TriangleGrid grid;
  grid.build(tris, 0.0);
  std::vector<TriangleHit> hits;

  // above the diagonal: both triangles find (0.5, 0.5, 0); the smaller id is kept
  ASSERT_EQ(mesh_hits(tris, grid, Vec3(0.5, 0.5, 0.3), 0.4, hits), 1);
  EXPECT_EQ(hits[0].triangle, 1);
  expect_near(hits[0].point, Vec3(0.5, 0.5, 0));
  expect_near(hits[0].normal, Vec3::UnitZ());
  EXPECT_NEAR(hits[0].distance, 0.3, 1e-15);
  EXPECT_EQ(hits[0].feature, TriangleFeature::edge);

  // inside the first triangle; the second's closest point (0.5, 0.5, 0) is sqrt(0.215) away
  hits.clear();
  ASSERT_EQ(mesh_hits(tris, grid, Vec3(0.75, 0.25, 0.3), 0.4, hits), 1);
  EXPECT_EQ(hits[0].triangle, 0);
  EXPECT_EQ(hits[0].feature, TriangleFeature::face);
  expect_near(hits[0].point, Vec3(0.75, 0.25, 0));
  EXPECT_NEAR(hits[0].distance, 0.3, 1e-15);

  // beyond the shared corner n0: both find the node
  hits.clear();
  const Vec3 x(-0.1, -0.1, 0.2);
  ASSERT_EQ(mesh_hits(tris, grid, x, 0.3, hits), 1);
  EXPECT_EQ(hits[0].triangle, 1);
  EXPECT_EQ(hits[0].feature, TriangleFeature::vertex);
  expect_near(hits[0].point, n0);
  EXPECT_NEAR(hits[0].distance, std::sqrt(0.06), 1e-15);
  expect_near(hits[0].normal, x / std::sqrt(0.06));

  // the storage order does not choose: reversed, the id-3 triangle (now index 0) is kept
  std::reverse(tris.begin(), tris.end());
  grid.build(tris, 0.0);
  hits.clear();
  ASSERT_EQ(mesh_hits(tris, grid, x, 0.3, hits), 1);
  EXPECT_EQ(tris[hits[0].triangle].id, 3);

  // hits already in the vector stay; only the new ones are counted
  ASSERT_EQ(mesh_hits(tris, grid, Vec3(0.5, 0.5, 0.3), 0.4, hits), 1);
  ASSERT_EQ(hits.size(), 2u);
  expect_near(hits[0].point, n0);
  expect_near(hits[1].point, Vec3(0.5, 0.5, 0));
  // out of reach: nothing
  EXPECT_EQ(mesh_hits(tris, grid, Vec3(0.5, 0.5, 0.5), 0.4, hits), 0);
}

// A floor z = 0 and a wall x = 0 meeting along the y axis, two triangles each: a sphere in the
// corner touches both faces, with their own normals.
TEST(Mesh, ConcaveCornerGivesBothFaces)
{
  const std::vector<Triangle> tris = {
      triangle(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(2, 2, 0), 1), // floor
      triangle(Vec3(0, 0, 0), Vec3(2, 2, 0), Vec3(0, 2, 0), 2),
      triangle(Vec3(0, 0, 0), Vec3(0, 2, 0), Vec3(0, 2, 2), 3), // wall
      triangle(Vec3(0, 0, 0), Vec3(0, 2, 2), Vec3(0, 0, 2), 4),
  };
  TriangleGrid grid;
  grid.build(tris, 0.0);
  std::vector<TriangleHit> hits;
  // the other triangle of each face is 0.636 (floor) and sqrt(0.27) (wall) away
  ASSERT_EQ(mesh_hits(tris, grid, Vec3(0.3, 1.0, 0.4), 0.5, hits), 2);
  EXPECT_EQ(hits[0].triangle, 1);
  EXPECT_EQ(hits[1].triangle, 2);
  expect_near(hits[0].point, Vec3(0.3, 1.0, 0));
  expect_near(hits[1].point, Vec3(0, 1.0, 0.4));
  expect_near(hits[0].normal, Vec3::UnitZ());
  expect_near(hits[1].normal, Vec3::UnitX());
  EXPECT_NEAR(hits[0].distance, 0.4, 1e-15);
  EXPECT_NEAR(hits[1].distance, 0.3, 1e-15);
  EXPECT_EQ(hits[0].feature, TriangleFeature::face);
  EXPECT_EQ(hits[1].feature, TriangleFeature::face);
}

// Node velocities of a rigid motion, v_i = V + w x p_i: the interpolated surface velocity is
// V + w x point wherever the closest point falls.
TEST(Mesh, RigidMotionVelocityAtTheHitPoint)
{
  const Vec3 V(0.3, -1.2, 0.5), w(0.7, 0.2, -1.1);
  Triangle tri = triangle(Vec3(1.0, 0.5, -0.2), Vec3(2.5, 1.0, 0.3), Vec3(1.2, 2.2, 0.9), 5);
  for (int i = 0; i < 3; ++i) tri.v[i] = V + w.cross(tri.p[i]);
  const std::vector<Triangle> tris = {tri};
  TriangleGrid grid;
  grid.build(tris, 0.0);
  const Vec3 centroid = (tri.p[0] + tri.p[1] + tri.p[2]) / 3.0;
  const Vec3 n = (tri.p[1] - tri.p[0]).cross(tri.p[2] - tri.p[0]).normalized();
  // above the face, beyond edge p0-p2 (outward in the plane, then off it), beyond node p1
  const Vec3 mid = 0.5 * (tri.p[0] + tri.p[2]);
  const Vec3 out = (mid - centroid).normalized();
  const Vec3 queries[] = {centroid + 0.3 * n, mid + 0.4 * out - 0.2 * n,
                          tri.p[1] + 0.5 * (tri.p[1] - centroid).normalized() + 0.1 * n};
  int features[3] = {0, 0, 0};
  for (const Vec3 &x : queries) {
    std::vector<TriangleHit> hits;
    ASSERT_EQ(mesh_hits(tris, grid, x, 10.0, hits), 1);
    expect_near(hits[0].velocity, V + w.cross(hits[0].point), 1e-12);
    ++features[static_cast<int>(hits[0].feature)];
  }
  EXPECT_GT(features[0], 0);
  EXPECT_GT(features[1], 0);
  EXPECT_GT(features[2], 0);
}

// A few hundred random triangles: the grid's candidates hold every triangle within reach,
// each once and ascending, and give the same hits as brute force, for several cell sizes.
TEST(Mesh, GridCandidatesMatchBruteForce)
{
  std::mt19937 gen(5);
  std::uniform_real_distribution<double> pos(0.0, 10.0), off(-0.8, 0.8), query(-1.0, 11.0),
      reach_of(0.0, 1.5);
  std::vector<Triangle> tris;
  for (int t = 0; t < 400; ++t) {
    const Vec3 c(pos(gen), pos(gen), pos(gen));
    tris.push_back(triangle(c + Vec3(off(gen), off(gen), off(gen)),
                            c + Vec3(off(gen), off(gen), off(gen)),
                            c + Vec3(off(gen), off(gen), off(gen)), 1000 - t));
  }
  TriangleGrid one_cell, automatic, fine, capped;
  one_cell.build(tris, 100.0);
  automatic.build(tris, 0.0);
  fine.build(tris, 0.2);
  capped.build(tris, 1e-6); // 1e21 cells asked for: the cell grows
  EXPECT_GT(automatic.cell(), 0.0);
  EXPECT_LT(automatic.cell(), 2.0);
  Vec3 lo = tris[0].p[0], hi = lo;
  for (const Triangle &t : tris)
    for (const Vec3 &p : t.p) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  double cells = 1.0;
  for (int d = 0; d < 3; ++d) cells *= std::floor((hi[d] - lo[d]) / capped.cell()) + 1.0;
  EXPECT_LE(cells, TriangleGrid::kMaxCells);
  EXPECT_GT(cells, 0.5 * TriangleGrid::kMaxCells); // grown no more than needed

  std::vector<int> cand;
  for (int q = 0; q < 500; ++q) {
    const Vec3 x(query(gen), query(gen), query(gen));
    const double reach = reach_of(gen);
    const std::vector<int> want = brute_force(tris, x, reach);
    std::vector<TriangleHit> reference;
    mesh_hits(tris, one_cell, x, reach, reference);
    for (const TriangleGrid *g : {&automatic, &fine, &capped}) {
      g->candidates(x, reach, cand);
      EXPECT_TRUE(std::adjacent_find(cand.begin(), cand.end(), std::greater_equal<int>()) ==
                  cand.end()); // strictly ascending: each once
      EXPECT_TRUE(std::includes(cand.begin(), cand.end(), want.begin(), want.end()));
      std::vector<int> within;
      for (int t : cand)
        if (std::binary_search(want.begin(), want.end(), t)) within.push_back(t);
      EXPECT_EQ(within, want);
      std::vector<TriangleHit> hits;
      EXPECT_EQ(mesh_hits(tris, *g, x, reach, hits), static_cast<int>(reference.size()));
      ASSERT_EQ(hits.size(), reference.size());
      for (std::size_t k = 0; k < hits.size(); ++k) {
        EXPECT_EQ(hits[k].triangle, reference[k].triangle);
        EXPECT_EQ(hits[k].point, reference[k].point);
        if (k > 0) {
          EXPECT_LT(tris[hits[k - 1].triangle].id, tris[hits[k].triangle].id);
        }
      }
    }
    // random triangles share no points: no hit is a duplicate
    EXPECT_EQ(reference.size(), want.size());
  }
  // outside the grid, with a negative reach or a non-finite centre: nothing
  automatic.candidates(Vec3(50, 50, 50), 1.0, cand);
  EXPECT_TRUE(cand.empty());
  automatic.candidates(Vec3(5, 5, 5), -1.0, cand);
  EXPECT_TRUE(cand.empty());
  automatic.candidates(Vec3(NAN, 5, 5), 1.0, cand);
  EXPECT_TRUE(cand.empty());
  TriangleGrid empty;
  empty.build({}, 0.0);
  empty.candidates(Vec3::Zero(), 1.0, cand);
  EXPECT_TRUE(cand.empty());
}

// A silo's wall: 32 tall, narrow facets (a cylinder of radius 1 and height 10, 64 triangles).
// The automatic cell follows a facet's middle extent (about its width, 0.2), not its length:
// with cells as long as the facets every query scanned all 64 triangles. A sphere at the wall
// still finds the facets within reach that brute force finds.
TEST(Mesh, TallFacetsKeepTheGridsCellsSmall)
{
  const int n = 32;
  const double pi = std::acos(-1.0), height = 10.0;
  std::vector<Triangle> tris;
  for (int k = 0; k < n; ++k) {
    const double a0 = 2 * pi * k / n, a1 = 2 * pi * (k + 1) / n;
    const Vec3 p0(std::cos(a0), std::sin(a0), 0), p1(std::cos(a1), std::sin(a1), 0);
    const Vec3 up(0, 0, height);
    tris.push_back(triangle(p0, p1, p1 + up, 2 * k));
    tris.push_back(triangle(p0, p1 + up, p0 + up, 2 * k + 1));
  }
  TriangleGrid grid;
  grid.build(tris, 0.0);
  const double width = 2 * std::sin(pi / n); // a facet's chord, 0.196
  EXPECT_GT(grid.cell(), 0.25 * width);
  EXPECT_LT(grid.cell(), width);
  std::vector<int> cand;
  // About 0.07 inside the wall near the seam of facets 0 and 31 (the edge at angle 0). Within
  // 0.1 (by hand): triangle 1, whose face lies under x (0.072); triangle 0, across facet 0's
  // diagonal (0.088); triangle 62, through the edge (0.073). Triangle 63 meets that edge only
  // at its top node.
  const Vec3 x(0.93, 0.02, 4.0);
  grid.candidates(x, 0.1, cand);
  const std::vector<int> within = brute_force(tris, x, 0.1);
  EXPECT_EQ(within, (std::vector<int>{0, 1, 62}));
  for (int t : within) EXPECT_TRUE(std::binary_search(cand.begin(), cand.end(), t)) << t;
  EXPECT_LE(cand.size(), 6u);
}

// A centre on the face: the geometric normal (p1 - p0) x (p2 - p0), so the winding decides.
TEST(Mesh, CentreOnTheFaceTakesTheGeometricNormal)
{
  const std::vector<Triangle> up = {triangle(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0))};
  const std::vector<Triangle> down = {triangle(Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(1, 0, 0))};
  TriangleGrid grid;
  std::vector<TriangleHit> hits;
  grid.build(up, 0.0);
  ASSERT_EQ(mesh_hits(up, grid, Vec3(0.2, 0.3, 0), 0.1, hits), 1);
  EXPECT_NEAR(hits[0].distance, 0.0, 1e-15); // rounding of the face point
  EXPECT_EQ(hits[0].normal, Vec3::UnitZ());
  grid.build(down, 0.0);
  ASSERT_EQ(mesh_hits(down, grid, Vec3(0.2, 0.3, 0), 0.1, hits), 1);
  EXPECT_EQ(hits[1].normal, -Vec3::UnitZ());
}

// Zero-area triangles (collinear nodes, one node thrice) are segments and points: finite
// points, distances and unit normals, also with the centre on them.
TEST(Mesh, DegenerateTrianglesStayFinite)
{
  // collinear, c beyond b: the segment a-c
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(3, 0, 0);
  Closest r = closest(Vec3(2, 1, 0), a, b, c);
  expect_near(r.point, Vec3(2, 0, 0));
  EXPECT_EQ(r.feature, TriangleFeature::edge);
  expect_near(r.bary[0] * a + r.bary[1] * b + r.bary[2] * c, r.point);
  r = closest(Vec3(4, 0, 1), a, b, c);
  expect_near(r.point, c);
  EXPECT_EQ(r.feature, TriangleFeature::vertex);
  r = closest(Vec3(-1, 2, 0), b, a, a); // a repeated node
  expect_near(r.point, a);
  EXPECT_EQ(r.feature, TriangleFeature::vertex);
  // all three equal
  const Vec3 p(1, 2, 3);
  r = closest(Vec3(1, 2, 4), p, p, p);
  expect_near(r.point, p);
  EXPECT_EQ(r.feature, TriangleFeature::vertex);
  EXPECT_NEAR(r.bary[0] + r.bary[1] + r.bary[2], 1.0, 1e-15);

  const std::vector<Triangle> tris = {triangle(a, b, c, 1), triangle(p, p, p, 2)};
  TriangleGrid grid;
  grid.build(tris, 0.0);
  for (const Vec3 &x : {Vec3(0.5, 0, 0), Vec3(0.5, 0.2, -0.1), p, Vec3(1, 2.1, 3)}) {
    std::vector<TriangleHit> hits;
    ASSERT_EQ(mesh_hits(tris, grid, x, 0.5, hits), 1) << x.transpose();
    EXPECT_TRUE(hits[0].point.allFinite());
    EXPECT_TRUE(hits[0].velocity.allFinite());
    EXPECT_TRUE(std::isfinite(hits[0].distance));
    EXPECT_NEAR(hits[0].normal.norm(), 1.0, 1e-15);
  }
  // on the segment the normal is normal to it; on the point it is +z
  std::vector<TriangleHit> hits;
  mesh_hits(tris, grid, Vec3(0.5, 0, 0), 0.5, hits);
  EXPECT_NEAR(hits[0].normal.dot(Vec3::UnitX()), 0.0, 1e-15);
  hits.clear();
  mesh_hits(tris, grid, p, 0.5, hits);
  EXPECT_EQ(hits[0].normal, Vec3::UnitZ());

  // a grid over one point only
  const std::vector<Triangle> dot = {triangle(p, p, p)};
  grid.build(dot, 0.0);
  EXPECT_GT(grid.cell(), 0.0);
  std::vector<int> cand;
  grid.candidates(p + Vec3(0.1, 0, 0), 0.2, cand);
  EXPECT_EQ(cand, std::vector<int>{0});
}

// Open edges: a closed cube has none; without its lid, the lid's 4 edges; a flat square of two
// triangles its 4 sides; nodes matched within the tolerance.
TEST(Mesh, OpenEdgesOfClosedAndOpenMeshes)
{
  const Vec3 v[8] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const int quads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                           {2, 3, 7, 6}, {1, 2, 6, 5}, {3, 0, 4, 7}};
  std::vector<Triangle> cube;
  for (const auto &q : quads) {
    Triangle a, b;
    a.p[0] = v[q[0]], a.p[1] = v[q[1]], a.p[2] = v[q[2]];
    b.p[0] = v[q[0]], b.p[1] = v[q[2]], b.p[2] = v[q[3]];
    cube.push_back(a);
    cube.push_back(b);
  }
  EXPECT_EQ(open_edges(cube, 1e-9), 0);
  std::vector<Triangle> open_box(cube.begin(), cube.end());
  open_box.erase(open_box.begin() + 2, open_box.begin() + 4); // the lid, z = 1
  EXPECT_EQ(open_edges(open_box, 1e-9), 4);
  std::vector<Triangle> square(cube.begin(), cube.begin() + 2); // the floor
  EXPECT_EQ(open_edges(square, 1e-9), 4);
  // a node off by less than the tolerance is the same node
  square[1].p[0] += Vec3(1e-12, 0, 0);
  EXPECT_EQ(open_edges(square, 1e-9), 4);
}
