// The matrix-free Schur product and blocks against the dense thesis formula.
#include <gtest/gtest.h>

#include "fibre/algebra/kernels.hpp"
#include "fibre/algebra/operators.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/scenes.hpp"
#include "reference.hpp"

using namespace fibre;

namespace {

using fibre::test::rel_diff;

void expect_schur_matches_dense(const ContactSystem &sys)
{
  const test::Dense A = test::dense_A(sys);
  ContactSpaceOperator op(sys, serial_exchange());
  for (int trial = 0; trial < 3; ++trial) {
    const Vector x = Vector::Random(sys.contact_dofs());
    Vector y;
    op.apply(x, y);
    EXPECT_LT(rel_diff(y, A * x), 1e-12);
  }
  const test::Dense K = test::dense_K(sys);
  BodySpaceOperator bop(sys, serial_exchange());
  const Vector v = Vector::Random(sys.body_dofs());
  Vector kv;
  bop.apply(v, kv);
  EXPECT_LT(rel_diff(kv, K * v), 1e-12);
}

} // namespace

TEST(Schur, GridHasTwelveContacts)
{
  SceneParams p;
  const ContactSystem sys = grid_scene(p);
  EXPECT_EQ(sys.num_bodies(), 9);
  EXPECT_EQ(sys.num_contacts(), 12);
  expect_schur_matches_dense(sys);
}

TEST(Schur, LoneContact)
{
  SceneParams p;
  expect_schur_matches_dense(pair_scene(p));
  p.rows = 3;
  expect_schur_matches_dense(pair_scene(p));
}

TEST(Schur, PolydispersePilesWithWalls)
{
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    SceneParams p;
    p.seed = seed;
    const ContactSystem sys = pile_scene(60, p);
    int walls = 0;
    for (const Contact &c : sys.contacts()) walls += c.is_wall();
    EXPECT_GT(walls, 0);
    EXPECT_GT(sys.num_contacts(), sys.num_bodies());
    expect_schur_matches_dense(sys);
  }
  SceneParams p;
  p.rows = 3;
  expect_schur_matches_dense(pile_scene(40, p));
}

// The diagonal alone (row scales, trial impulses) is the dense A's, with 6 and 3 rows, and the
// block's with rows masked out.
TEST(Schur, DiagonalEntriesMatchDense)
{
  for (int rows : {6, 3}) {
    SceneParams p;
    p.rows = rows;
    ContactSystem sys = pile_scene(40, p);
    const test::Dense A = test::dense_A(sys);
    for (int c = 0; c < sys.num_contacts(); ++c) {
      const Vec6 d = diagonal_entries(sys, c);
      for (int i = 0; i < rows; ++i)
        EXPECT_NEAR(d[i], A(rows * c + i, rows * c + i), 1e-12 * A(rows * c + i, rows * c + i));
      for (int i = rows; i < kMaxRows; ++i) EXPECT_EQ(d[i], 1.0);
    }
    std::vector<unsigned char> mask(sys.contact_dofs(), 1);
    for (std::size_t i = 0; i < mask.size(); i += 4) mask[i] = 0;
    sys.set_row_mask(mask);
    for (int c = 0; c < sys.num_contacts(); ++c) {
      const Mat6 D = diagonal_block(sys, c);
      EXPECT_LT((diagonal_entries(sys, c) - D.diagonal()).norm(), 1e-12 * D.norm());
    }
  }
}

TEST(Schur, BlocksMatchDense)
{
  SceneParams p;
  const ContactSystem sys = pile_scene(40, p);
  const test::Dense A = test::dense_A(sys);
  const int r = sys.rows();
  for (int c = 0; c < sys.num_contacts(); ++c) {
    EXPECT_LT((diagonal_block(sys, c) - A.block(r * c, r * c, r, r)).norm(),
              1e-12 * A.block(r * c, r * c, r, r).norm());
    for (int d = 0; d < sys.num_contacts(); ++d) {
      if (d == c) continue;
      const auto ref = A.block(r * c, r * d, r, r);
      EXPECT_LT((coupling_block(sys, c, d) - ref).norm(), 1e-12 * (1.0 + ref.norm()));
    }
  }
  const test::Dense K = test::dense_K(sys);
  const std::vector<Mat6> kd = body_diagonal_blocks(sys);
  for (int i = 0; i < sys.num_bodies(); ++i)
    EXPECT_LT((kd[i] - K.block(6 * i, 6 * i, 6, 6)).norm(),
              1e-10 * K.block(6 * i, 6 * i, 6, 6).norm());
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    if (k.is_wall()) continue;
    const auto ref = K.block(6 * k.a, 6 * k.b, 6, 6);
    EXPECT_LT((body_coupling_block(sys, c) - ref).norm(), 1e-10 * (1.0 + ref.norm()));
  }
}

TEST(Schur, MaskedRowsDecouple)
{
  SceneParams p;
  ContactSystem sys = pile_scene(30, p);
  std::vector<unsigned char> mask(sys.contact_dofs(), 1);
  for (std::size_t i = 0; i < mask.size(); i += 4) mask[i] = 0;
  sys.set_row_mask(mask);
  expect_schur_matches_dense(sys);
  const test::Dense A = test::dense_A(sys);
  EXPECT_DOUBLE_EQ(A(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(sys.rhs()[0], 0.0);
}

TEST(Schur, SpookRhsMatchesFormula)
{
  SceneParams p;
  const ContactSystem sys = pile_scene(30, p);
  const test::Dense G = test::dense_G(sys);
  const SpookParams &sp = sys.params();
  const double ups = sp.upsilon();
  Vector v(sys.body_dofs()), f(sys.body_dofs());
  for (int i = 0; i < sys.num_bodies(); ++i) {
    const Body &b = sys.bodies()[i];
    v.segment<3>(6 * i) = b.v;
    v.segment<3>(6 * i + 3) = b.omega;
    f.segment<3>(6 * i) = b.force;
    f.segment<3>(6 * i + 3) = b.torque;
  }
  Vector g = Vector::Zero(sys.contact_dofs());
  for (int c = 0; c < sys.num_contacts(); ++c) g[sys.rows() * c] = sys.contacts()[c].gap;
  const Vector ref =
      -(4.0 / sp.h) * ups * g - (1 - ups) * G * v - sp.h * G * test::dense_Minv(sys) * f;
  EXPECT_LT(rel_diff(spook_rhs(sys), ref), 1e-12);
}
