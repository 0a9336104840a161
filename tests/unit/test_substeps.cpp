// The contact solve in substeps (substeps.hpp): how many, and that n substeps of h / n are n
// steps of h / n where the step's geometry holds (a head-on collision on a line), and that a
// resting sphere's substeps carry its weight over the whole step.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fibre/algebra/spook.hpp"
#include "fibre/model/contact_model.hpp"
#include "fibre/step/step_solver.hpp"
#include "fibre/step/substeps.hpp"

using namespace fibre;

TEST(Substeps, AsManyAsTheCollisionTimeAsks)
{
  ContactModel model;
  // automatic: the fewest of at most 0.33 collision times (the material deck's step is 0.31,
  // 1.49 and 4.95 t_c at E = 1e5, 5e6 and 1e8)
  EXPECT_EQ(substeps_for(model, 4.4343e-3, 8.96051e-4), 15);
  EXPECT_EQ(substeps_for(model, 1.49, 1.0), 5);
  EXPECT_EQ(substeps_for(model, 0.312, 1.0), 1); // the step resolves the collisions already
  EXPECT_EQ(substeps_for(model, 0.66, 1.0), 2);  // exactly 0.33 t_c each
  EXPECT_EQ(substeps_for(model, 1.0, 0.0), 1);   // no elastic law
  EXPECT_EQ(substeps_for(model, 1.0, 1e-9), kMaxSubsteps);
  model.substep_collisions = 0.25;
  EXPECT_EQ(substeps_for(model, 1.0, 1.0), 4);
  model.substeps = 3; // typed: that many, whatever the law
  EXPECT_EQ(substeps_for(model, 1.0, 1e-9), 3);
  EXPECT_EQ(substeps_for(model, 1.0, 0.0), 3);
}

namespace {

// Frictionless compliant contacts of a fixed compliance, 3 rows, SPOOK d = 2.
ContactModel compliant_model(double eps)
{
  ContactModel model;
  model.rows = 3;
  model.compliance.automatic = false;
  model.compliance.eps_n = model.compliance.eps_t = eps;
  model.friction = FrictionParams{0.0, 0.0, 0.0};
  return model;
}

StepResult solve(ContactSystem &sys, const Vector &warm, SweepCache *cache = nullptr)
{
  StepOptions opt; // the fix's defaults, solved tighter than they stop
  opt.stop.tol = 1e-12;
  opt.accuracy = 1e-12;
  return solve_step(sys, serial_exchange(), opt, &warm, MPI_COMM_SELF, cache);
}

// The same as run_substeps's solve, the sweeps' groups kept from substep to substep.
StepResult substep_solve(ContactSystem &sys, const Vector &warm, bool, SweepCache &cache)
{
  return solve(sys, warm, &cache);
}

// One step as the fix did it before substeps: the model, the system, the solve; returns v+.
Vector one_step(const ContactModel &model, const SpookParams &params, std::vector<Body> bodies,
                std::vector<Contact> contacts, const Vector &warm, Vector &lambda)
{
  apply_contact_model(model, params, 1.0, bodies, contacts, &warm);
  ContactSystem sys(std::move(bodies), std::move(contacts), model.rows, params);
  const StepResult res = solve(sys, warm);
  lambda = res.lambda;
  return velocities_after_change(sys, serial_exchange(), res.dv);
}

} // namespace

// Two spheres (radius 0.5, masses 1 and 2) meet head-on at 1 m/s each, 1 cm apart, at a step
// of 10 ms, about five of their contact's collision times (k = 1e6). Ten substeps of 1 ms
// (the gap moved by h G v+) give what ten steps of 1 ms give with the contact built anew from
// the positions each step (x += h v+, as the fix's positions follow the substeps): the same
// velocities, the same impulse over the step and the same path, to round-off; momentum is
// conserved.
TEST(Substeps, AreStepsOfTheirLengthWhereTheGeometryHolds)
{
  const int n = 10;
  const double h = 0.01, hs = h / n;
  const ContactModel model = compliant_model(1e-6);
  SpookParams params;
  params.h = hs;
  std::vector<Body> start(2);
  start[0].radius = start[1].radius = 0.5;
  start[0].mass = 1.0;
  start[1].mass = 2.0;
  start[0].x = Vec3(0, 0, 0);
  start[1].x = Vec3(1.01, 0, 0);
  start[0].v = Vec3(1, 0, 0);
  start[1].v = Vec3(-1, 0, 0);

  // the substeps, with the contact detected once
  std::vector<Body> bodies = start;
  std::vector<Contact> contacts{sphere_sphere_contact(bodies, 1, 0)};
  const Substeps steps = run_substeps(n, model, params, 1.0, serial_exchange(), 2, bodies, contacts,
                                      Vector::Zero(3), substep_solve);
  ASSERT_EQ(steps.done, n);
  const Vector &v_final = steps.v_plus, &impulse = steps.lambda, &path = steps.path;

  // the reference: n steps of hs, positions moved and the contact rebuilt each step
  std::vector<Body> ref = start;
  Vector ref_warm = Vector::Zero(3), ref_impulse = Vector::Zero(3), ref_v;
  for (int k = 0; k < n; ++k) {
    Vector lambda;
    ref_v = one_step(model, params, ref, {sphere_sphere_contact(ref, 1, 0)}, ref_warm, lambda);
    ref_impulse += lambda;
    ref_warm = lambda;
    for (int b = 0; b < 2; ++b) {
      ref[b].v = ref_v.segment<3>(6 * b);
      ref[b].x += hs * ref[b].v;
    }
  }
  ASSERT_GT(ref_impulse[0], 1.0); // they collided within the step
  EXPECT_NEAR(impulse[0], ref_impulse[0], 1e-9 * ref_impulse[0]);
  for (int b = 0; b < 2; ++b) {
    EXPECT_LT((v_final.segment<3>(6 * b) - ref_v.segment<3>(6 * b)).norm(), 1e-9);
    EXPECT_LT((start[b].x + hs * path.segment<3>(6 * b) - ref[b].x).norm(), 1e-11);
  }
  const Vec3 p =
      start[0].mass * Vec3(v_final.segment<3>(0)) + start[1].mass * Vec3(v_final.segment<3>(6));
  EXPECT_LT((p - Vec3(-1, 0, 0)).norm(), 1e-10); // 1 * 1 + 2 * (-1)
}

// A sphere resting on a floor under gravity: over four substeps the floor's impulses add up to
// the weight times the step, and the sphere stays at rest.
TEST(Substeps, CarryARestingSpheresWeightOverTheStep)
{
  const int n = 4;
  const double h = 0.01, g = 9.81;
  const double eps = 1e-9;
  const ContactModel model = compliant_model(eps);
  SpookParams params;
  params.h = h / n;
  std::vector<Body> bodies(1);
  bodies[0].radius = 0.5;
  bodies[0].mass = 2.0;
  bodies[0].x = Vec3(0, 0, 0.5);
  bodies[0].force = Vec3(0, 0, -g * bodies[0].mass);
  // at the overlap its weight holds on the compliant floor (SPOOK's static state: eps F)
  std::vector<Contact> contacts{
      sphere_wall_contact(bodies, 0, Vec3::UnitZ(), 0.5 - eps * g * bodies[0].mass)};
  // the warm start of a sphere that has rested there: its weight over a substep
  Vector warm = Vector::Zero(3);
  warm[0] = g * bodies[0].mass * params.h;
  const Substeps steps = run_substeps(n, model, params, 1.0, serial_exchange(), 1, bodies, contacts,
                                      warm, substep_solve);
  ASSERT_EQ(steps.done, n);
  const double weight_impulse = g * 2.0 * h;
  EXPECT_NEAR(steps.lambda[0], weight_impulse, 1e-8 * weight_impulse);
  EXPECT_LT(steps.v_plus.norm(), 1e-8 * g * h);
  EXPECT_LT(std::abs(steps.path[2]), 1e-8 * g * h);
}

// One substep is the plain step, bit for bit, and the substeps before the last skip the
// residual they are told to skip: the step reports the last one's.
TEST(Substeps, OneIsThePlainStepAndOnlyTheLastMeasuresItsResidual)
{
  const double h = 0.01;
  const ContactModel model = compliant_model(1e-6);
  SpookParams params;
  params.h = h;
  std::vector<Body> bodies(2);
  bodies[0].radius = bodies[1].radius = 0.5;
  bodies[1].x = Vec3(0.99, 0, 0);
  bodies[0].v = Vec3(1, 0, 0);
  bodies[0].force = Vec3(0, 0, -9.81);
  const std::vector<Contact> contacts{sphere_sphere_contact(bodies, 1, 0)};
  Vector lambda;
  const Vector v_plus = one_step(model, params, bodies, contacts, Vector::Zero(3), lambda);
  const Substeps one = run_substeps(1, model, params, 1.0, serial_exchange(), 2, bodies, contacts,
                                    Vector::Zero(3), substep_solve);
  ASSERT_EQ(one.done, 1);
  EXPECT_EQ(one.lambda, lambda);
  EXPECT_EQ(one.v_plus, v_plus);
  EXPECT_EQ(one.result.lambda, lambda);

  const auto skipping = [](ContactSystem &sys, const Vector &warm, bool last, SweepCache &cache) {
    StepOptions opt;
    opt.residual = last;
    return solve_step(sys, serial_exchange(), opt, &warm, MPI_COMM_SELF, &cache);
  };
  params.h = h / 4;
  std::vector<double> residuals;
  const Substeps four =
      run_substeps(4, model, params, 1.0, serial_exchange(), 2, bodies, contacts, Vector::Zero(3),
                   [&](ContactSystem &sys, const Vector &warm, bool last, SweepCache &cache) {
                     const StepResult r = skipping(sys, warm, last, cache);
                     residuals.push_back(r.complementarity);
                     return r;
                   });
  ASSERT_EQ(four.done, 4);
  ASSERT_EQ(residuals.size(), 4u);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(residuals[k], kNotMeasured);
  EXPECT_GE(residuals[3], 0.0);
  EXPECT_EQ(four.totals.complementarity, residuals[3]);
}

// A step needs substeps where some contact moves (substep_when moving): its surfaces press,
// part, slide or roll at more than the speed where they touch, or where they will touch within
// its SPOOK row's reach, h (1 + 4 d) / 4 of the approach speed. A pile at rest, spheres that
// fly apart or beyond reach and motion below the speed do not count.
TEST(Substeps, OnlyAStepWithMotionAtAContactNeedsThem)
{
  const double h = 0.01, speed = 0.02;
  SpookParams step;
  step.h = h;
  step.damping = 0.75; // SPOOK's row reaches h (1 + 4 d) / 4 = h ahead
  std::vector<Body> bodies(2);
  bodies[0].radius = bodies[1].radius = 0.5;
  bodies[1].x = Vec3(0, 0, 1.0);
  // a sphere over the floor, `gap` above it
  const auto floor = [&](double gap) {
    return std::vector<Contact>{sphere_wall_contact(bodies, 0, Vec3::UnitZ(), 0.5 + gap)};
  };

  bodies[0].v = Vec3(0, 0, -1.0); // falling at 1 m/s: reaches the floor within 10 ms from 9 mm
  EXPECT_TRUE(step_moves(bodies, floor(0.009), step, speed));
  EXPECT_FALSE(step_moves(bodies, floor(0.011), step, speed)); // beyond reach
  EXPECT_TRUE(step_moves(bodies, floor(-0.001), step, speed)); // pressing on
  step.damping = 2.0;                                          // the row brakes from 2.25 h
  EXPECT_TRUE(step_moves(bodies, floor(0.022), step, speed));
  EXPECT_FALSE(step_moves(bodies, floor(0.023), step, speed));
  step.damping = 0.75;
  bodies[0].v = Vec3(0, 0, -0.5 * speed); // below the speed: it rests on arrival
  EXPECT_FALSE(step_moves(bodies, floor(0.0), step, speed));
  bodies[0].v = Vec3(0, 0, 1.0); // leaving the floor
  EXPECT_TRUE(step_moves(bodies, floor(-0.001), step, speed));
  EXPECT_FALSE(step_moves(bodies, floor(0.001), step, speed)); // apart already
  bodies[0].v = Vec3(0.1, 0, 0);                               // sliding on it
  EXPECT_TRUE(step_moves(bodies, floor(-0.001), step, speed));
  bodies[0].v = Vec3::Zero();
  bodies[0].omega = Vec3(0, 0.2, 0); // rolling on it: its surface moves at 0.1 m/s there
  EXPECT_TRUE(step_moves(bodies, floor(-0.001), step, speed));
  bodies[0].omega = Vec3(0, 0, 0.2); // spinning about the normal: no surface motion there
  EXPECT_FALSE(step_moves(bodies, floor(-0.001), step, speed));
  bodies[0].v = Vec3(0.2, 0, 0);
  bodies[0].omega = Vec3(0, 0.4, 0); // rolling without slip: the contact point rests
  EXPECT_FALSE(step_moves(bodies, floor(-0.001), step, speed));
  bodies[0].omega = Vec3::Zero();

  // two spheres: the relative velocity counts, and so does a moving wall's
  bodies[0].v = bodies[1].v = Vec3(0, 0, -3.0); // falling together
  const std::vector<Contact> pair{sphere_sphere_contact(bodies, 1, 0)};
  EXPECT_FALSE(step_moves(bodies, pair, step, speed));
  bodies[1].v = Vec3(0, 0, -4.0);
  EXPECT_TRUE(step_moves(bodies, pair, step, speed));
  bodies[0].v = Vec3::Zero();
  std::vector<Contact> wall = floor(0.005);
  wall[0].wall_v = Vec3(0, 0, 1.0); // a floor that rises at 1 m/s
  EXPECT_TRUE(step_moves(bodies, wall, step, speed));
}
