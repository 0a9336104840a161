// Triangle-mesh walls without a front end: the closest point of a triangle to a sphere centre
// (face, edge or vertex), a uniform bin grid over the triangles, and the hits of one sphere
// with shared edges and vertices counted once. A front end (LIGGGHTS fix mesh/surface) fills
// the triangles each step, node velocities included for moving meshes.
#pragma once

#include <vector>

#include "fibre/core/system.hpp"

namespace fibre {

// One triangle: node positions p, node velocities v (zero for a static mesh) and the front
// end's global triangle id, which makes the choice among duplicate hits deterministic.
struct Triangle {
  Vec3 p[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  Vec3 v[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  long id = 0;
};

// Where on the triangle the closest point lies: inside, on an edge, or at a node.
enum class TriangleFeature { face, edge, vertex };

// One triangle within reach of a sphere centre x. normal is the unit vector from point to x;
// distance = |x - point|. When x lies on the triangle (distance <= 1e-12 (longest edge +
// max |x_i|), i.e. rounding) normal is the geometric face normal (p1 - p0) x (p2 - p0),
// normalised (for a zero-area triangle: a unit vector normal to its longest edge, or +z for a
// point). velocity is the surface velocity at point, the barycentric interpolation of the
// node velocities (exact for a rigid motion, which is affine in position).
struct TriangleHit {
  int triangle;    // index into the triangle array
  Vec3 point;      // closest point on the triangle
  Vec3 normal;     // unit, from the triangle to the sphere centre
  double distance; // |x - point|
  TriangleFeature feature;
  Vec3 velocity; // surface velocity at point
};

// The point of triangle (a, b, c) closest to x, by the Voronoi regions of its nodes, edges and
// face. bary receives its barycentric coordinates (point = bary[0] a + bary[1] b + bary[2] c,
// non-negative, sum 1), feature the region. A zero-area triangle is treated as its longest
// segment (or its point); the result is always finite for finite input.
Vec3 closest_point_on_triangle(const Vec3 &x, const Vec3 &a, const Vec3 &b, const Vec3 &c,
                               double bary[3], TriangleFeature &feature);

// A uniform bin grid over the triangles' bounding boxes, rebuilt whenever the nodes move (once
// per step). Each triangle is listed in every cell its box overlaps.
class TriangleGrid {
 public:
  // cell <= 0: the mean of the triangles' middle box extents. The cell grows until the grid
  // has at most kMaxCells cells. Triangles with a non-finite node are left out.
  void build(const std::vector<Triangle> &tris, double cell);
  // The indices of the triangles whose bounding box, inflated by reach, contains x: each
  // once, ascending. out is overwritten; empty for reach < 0 or non-finite x.
  void candidates(const Vec3 &x, double reach, std::vector<int> &out) const;
  double cell() const { return cell_; }
  int size() const { return static_cast<int>(box_lo_.size()); } // triangles it was built on

  static constexpr double kMaxCells = 2e6;

 private:
  int cell_index(int i, int j, int k) const { return (k * dims_[1] + j) * dims_[0] + i; }
  int coord(int d, double v) const;            // the cell holding coordinate v along d, clamped
  Vec3 lo_ = Vec3::Zero(), hi_ = Vec3::Zero(); // the box of all triangles
  double cell_ = 1.0;
  int dims_[3] = {0, 0, 0};
  std::vector<int> cell_start_; // CSR: the triangles of cell c are items_[start[c], start[c+1])
  std::vector<int> items_;
  std::vector<Vec3> box_lo_, box_hi_; // per-triangle bounding boxes
};

// Appends to hits the triangles whose closest point to x is within reach (distance <= reach),
// found through grid (built on tris). A sphere touching an edge or node shared by several
// triangles finds the same closest point on each; of hits whose points coincide
// (|p1 - p2| <= 1e-9 max(1, reach)) only the one of smallest triangle id is kept. The appended
// hits are sorted by triangle id. Returns how many were appended.
int mesh_hits(const std::vector<Triangle> &tris, const TriangleGrid &grid, const Vec3 &x,
              double reach, std::vector<TriangleHit> &hits);
// The same with the caller's working storage, reused from call to call (the per-sphere loop).
struct MeshScratch {
  std::vector<int> candidates;
  std::vector<TriangleHit> found;
};
int mesh_hits(const std::vector<Triangle> &tris, const TriangleGrid &grid, const Vec3 &x,
              double reach, std::vector<TriangleHit> &hits, MeshScratch &scratch);

// Edges used by one triangle only: a mesh's rims and holes, where grains can leave (a closed
// surface has none). Nodes are matched by rounding their coordinates to multiples of tol; an
// edge of three or more triangles counts as closed.
int open_edges(const std::vector<Triangle> &tris, double tol);

} // namespace fibre
