// Explicit assembly against the independent dense references of reference.hpp.
#include <gtest/gtest.h>

#include "fibre/algebra/assembly.hpp"
#include "fibre/algebra/kernels.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/scenes.hpp"
#include "reference.hpp"

using namespace fibre;

namespace {

using fibre::test::rel_diff;

void expect_assembly_matches_dense(const ContactSystem &sys)
{
  const test::Dense G = test::dense_G(sys);
  const SparseMatrix Gs = assemble_G(sys);
  ASSERT_EQ(Gs.rows(), sys.contact_dofs());
  ASSERT_EQ(Gs.cols(), sys.body_dofs());
  EXPECT_LT(rel_diff(Eigen::MatrixXd(Gs), G), 1e-14);
  EXPECT_LT(rel_diff(assemble_inv_mass(sys), test::dense_Minv(sys).diagonal()), 1e-15);
  EXPECT_LT(rel_diff(assemble_sigma(sys), test::dense_sigma(sys)), 1e-15);
  const SparseMatrix A = assemble_A(sys);
  EXPECT_LT(rel_diff(Eigen::MatrixXd(A), test::dense_A(sys)), 1e-13);
  const SparseMatrix K = assemble_K(sys);
  EXPECT_LT(rel_diff(Eigen::MatrixXd(K), test::dense_K(sys)), 1e-13);
}

// b from the dense G and the design's formula, written out here.
Eigen::VectorXd dense_rhs(const ContactSystem &sys)
{
  const SpookParams &p = sys.params();
  const double ups = 1.0 / (1.0 + 4.0 * p.damping);
  Eigen::VectorXd v(sys.body_dofs()), f(sys.body_dofs());
  for (int i = 0; i < sys.num_bodies(); ++i) {
    const Body &b = sys.bodies()[i];
    v.segment<3>(6 * i) = b.v;
    v.segment<3>(6 * i + 3) = b.omega;
    f.segment<3>(6 * i) = b.force;
    f.segment<3>(6 * i + 3) = b.torque;
  }
  const test::Dense G = test::dense_G(sys);
  Eigen::VectorXd b = -(1.0 - ups) * G * v - p.h * G * test::dense_Minv(sys) * f;
  for (int c = 0; c < sys.num_contacts(); ++c)
    if (sys.row_active(Eigen::Index(sys.rows()) * c))
      b[sys.rows() * c] -= 4.0 / p.h * ups * sys.contacts()[c].gap;
  return b;
}

} // namespace

TEST(Assembly, GridMatchesDense)
{
  SceneParams p;
  expect_assembly_matches_dense(grid_scene(p));
}

TEST(Assembly, PilesWithWallsBothRowCounts)
{
  SceneParams p;
  expect_assembly_matches_dense(pile_scene(50, p));
  p.rows = 3;
  p.seed = 7;
  expect_assembly_matches_dense(pile_scene(40, p));
}

TEST(Assembly, MaskedRowsAreDecoupled)
{
  SceneParams p;
  ContactSystem sys = pile_scene(30, p);
  std::vector<unsigned char> mask(sys.contact_dofs(), 1);
  for (std::size_t r = 0; r < mask.size(); r += 5) mask[r] = 0;
  sys.set_row_mask(mask);
  expect_assembly_matches_dense(sys);
  const SparseMatrix A = assemble_A(sys);
  for (std::size_t r = 0; r < mask.size(); r += 5) {
    const Eigen::Index i = static_cast<Eigen::Index>(r);
    EXPECT_EQ(A.col(i).nonZeros(), 1);
    EXPECT_EQ(A.coeff(i, i), 1.0);
  }
}

TEST(Assembly, RhsMatchesFormulaAndMatrixFreeRhs)
{
  SceneParams p;
  p.spook.h = 2e-3;
  p.spook.damping = 3.0;
  const ContactSystem sys = pile_scene(60, p);
  const Eigen::VectorXd ref = dense_rhs(sys);
  EXPECT_LT(rel_diff(assemble_rhs(sys), ref), 1e-13);
  EXPECT_LT(rel_diff(spook_rhs(sys), ref), 1e-13);
  // The gap term matters: it must not vanish from the reference.
  double gap_norm = 0;
  for (const Contact &c : sys.contacts()) gap_norm += std::abs(c.gap);
  EXPECT_GT(gap_norm, 0.0);
}

// A moving wall is body b with a prescribed velocity: the rhs of a system whose walls move
// equals that of the same contacts against a real body b moving so (infinitely heavy, so
// that its own external forces do not enter), and per-contact damping agrees between the
// assembled and the matrix-free rhs, and so do the elastic rows' springs and the implicit
// normal rows (no memory of the approach speed).
TEST(Assembly, MovingWallsAndPerContactDamping)
{
  SceneParams p;
  ContactSystem pile = pile_scene(40, p);
  std::vector<Contact> contacts = pile.contacts();
  std::vector<Body> bodies = pile.bodies();
  int walls = 0;
  for (Contact &c : contacts) {
    c.damping = (c.a % 3 == 0) ? 7.5 : -1.0;
    if (c.a % 2 == 0) { // elastic rows with their springs
      c.elastic = {false, true, true, true, true, true};
      c.spring = {0.0, 1e-4, -2e-4, 0.01, 0.02, -0.03};
    }
    if (c.a % 5 == 1) { // an implicit normal row
      c.elastic[0] = c.implicit_normal = true;
      c.damping = 0.75 + 0.2;
    }
    if (!c.is_wall()) continue;
    ++walls;
    c.wall_v = Vec3(0.3, -0.2, 0.1);
    c.wall_omega = Vec3(0.0, 0.5, 1.5);
  }
  ASSERT_GT(walls, 0);
  const ContactSystem moving(bodies, contacts, 6, pile.params());
  EXPECT_LT(rel_diff(assemble_rhs(moving), spook_rhs(moving)), 1e-13);
  // the same walls as one heavy body whose velocity at each contact point is wall_v: a body at
  // the contact point itself (lever rb = 0) with v = wall_v and omega = wall_omega
  std::vector<Body> with_walls = bodies;
  std::vector<Contact> as_pairs = contacts;
  for (Contact &c : as_pairs) {
    if (!c.is_wall()) continue;
    Body w;
    w.mass = 1e300;
    w.radius = 1.0;
    w.x = c.point;
    w.v = c.wall_v;
    w.omega = c.wall_omega;
    c.b = static_cast<int>(with_walls.size());
    c.wall_v = c.wall_omega = Vec3::Zero();
    with_walls.push_back(w);
  }
  const ContactSystem bodies_moving(with_walls, as_pairs, 6, pile.params());
  EXPECT_LT(rel_diff(spook_rhs(moving), spook_rhs(bodies_moving)), 1e-12);
  // and at rest the wall terms vanish
  for (Contact &c : contacts) c.wall_v = c.wall_omega = Vec3::Zero();
  const ContactSystem still(bodies, contacts, 6, pile.params());
  EXPECT_GT(rel_diff(spook_rhs(moving), spook_rhs(still)), 1e-6);
}

TEST(Assembly, GhostBodiesGetNoMass)
{
  SceneParams p;
  const ContactSystem full = pile_scene(20, p);
  // Same bodies and contacts, the last five bodies treated as ghosts.
  const ContactSystem sys(full.bodies(), full.contacts(), full.rows(), full.params(),
                          full.num_bodies() - 5);
  const SparseMatrix K = assemble_K(sys);
  const test::Dense Kref = test::dense_K(full);
  const Eigen::Index owned = 6 * Eigen::Index(sys.num_owned_bodies());
  const Eigen::MatrixXd Kd(K);
  for (Eigen::Index i = 0; i < sys.body_dofs(); ++i) {
    const double m = 1.0 / full.inv_mass()[i];
    const double expected = i < owned ? Kref(i, i) : Kref(i, i) - m;
    EXPECT_NEAR(Kd(i, i), expected, 1e-12 * Kref(i, i)) << "dof " << i;
  }
}

TEST(Assembly, UpperTripletsRebuildTheMatrix)
{
  SceneParams p;
  const SparseMatrix A = assemble_A(pile_scene(25, p));
  std::vector<long> r, c;
  std::vector<double> v;
  upper_triplets(A, r, c, v);
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(A.rows(), A.cols());
  for (std::size_t e = 0; e < v.size(); ++e) {
    ASSERT_LE(r[e], c[e]);
    U(r[e], c[e]) += v[e];
  }
  Eigen::MatrixXd full = U + U.transpose();
  full.diagonal() /= 2.0;
  EXPECT_LT(rel_diff(full, Eigen::MatrixXd(A)), 1e-15);
}
