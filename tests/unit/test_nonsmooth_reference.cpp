// The converged reference of a step: projected Gauss-Seidel and semismooth Newton reach a
// complementarity residual of 1e-10 and agree with each other and with the settled MUMPS
// answer of the active-set loop; step_accuracy measures by row group.
#include <gtest/gtest.h>

#include "fibre/algebra/spook.hpp"
#include "fibre/scenes.hpp"
#include "fibre/step/step_solver.hpp"
#include "fibre/study/nonsmooth_reference.hpp"
#include "reference.hpp"

using namespace fibre;
using fibre::test::rel_diff;

TEST(NonsmoothReference, TwoMethodsAgreeWithTheSettledDirectAnswer)
{
  SceneParams p;
  p.seed = 11;
  ContactSystem sys = pile_scene(80, p);
  sys.set_friction(FrictionParams{0.4, 0.02, 0.02});
  StepOptions direct;
  direct.solver = Method::direct;
  direct.form = Form::contact;
  direct.active_set_max = 60;
  const StepResult settled = solve_step(sys, serial_exchange(), direct, nullptr, MPI_COMM_SELF);
  ASSERT_TRUE(settled.set_settled);

  StepOptions cut; // one default pass without sweeps: far from converged
  cut.sweeps = 0;
  const StepResult start = solve_step(sys, serial_exchange(), cut, nullptr, MPI_COMM_SELF);
  const Reference ref = nonsmooth_reference(sys, start.lambda);
  EXPECT_LE(ref.complementarity_pgs, 1e-10);
  EXPECT_TRUE(ref.newton.converged);
  EXPECT_LE(ref.newton.complementarity, 1e-10);
  EXPECT_LT(ref.newton.iterations, 40);
  EXPECT_TRUE(ref.confirmed()) << "velocity " << ref.agreement.velocity() << " impulse "
                               << ref.agreement.impulse();
  // the settled MUMPS answer: its caps settle to cap_tol 1e-6 of the largest impulse
  const StepAccuracy vs_direct = step_accuracy(sys, settled.lambda, ref.lambda);
  EXPECT_LT(vs_direct.velocity(), 1e-5);
  EXPECT_LT(vs_direct.lambda_n, 1e-5);
  // the cut solve is far off, and the measure says so
  const StepAccuracy vs_cut = step_accuracy(sys, start.lambda, ref.lambda);
  EXPECT_GT(vs_cut.velocity(), 1e-2);
}

TEST(NonsmoothReference, AccuracyByGroup)
{
  SceneParams p;
  p.seed = 3;
  ContactSystem sys = pile_scene(30, p);
  const int rows = sys.rows();
  Vector ref = Vector::Zero(sys.contact_dofs());
  for (int c = 0; c < sys.num_contacts(); ++c) {
    ref[rows * c] = 2.0;
    ref[rows * c + 1] = 0.5;
    ref[rows * c + 4] = 0.1;
  }
  Vector lambda = ref;
  for (int c = 0; c < sys.num_contacts(); ++c) lambda[rows * c + 1] *= 1.1; // friction 10% off
  const StepAccuracy a = step_accuracy(sys, lambda, ref);
  EXPECT_DOUBLE_EQ(a.lambda_n, 0.0);
  EXPECT_NEAR(a.lambda_t, 0.1, 1e-12);
  EXPECT_DOUBLE_EQ(a.lambda_roll, 0.0);
  EXPECT_DOUBLE_EQ(a.lambda_twist, 0.0); // no twisting impulse anywhere: 0, not 0/0
  EXPECT_GT(a.dv_trans, 0.0);
  EXPECT_NEAR(a.impulse(), 0.1, 1e-12);
  const StepAccuracy same = step_accuracy(sys, ref, ref);
  EXPECT_EQ(same.velocity(), 0.0);
  EXPECT_EQ(same.impulse(), 0.0);
}
