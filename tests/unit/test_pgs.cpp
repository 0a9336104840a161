// Projected Gauss-Seidel as a solver of its own: its fixed point solves the nonsmooth step
// (the same impulses as the settled MUMPS answer), and every stop has its typed reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numeric>
#include <utility>

#include "fibre/algebra/kernels.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/scenes.hpp"
#include "fibre/solvers/apgd.hpp"
#include "fibre/solvers/pgs.hpp"
#include "fibre/solvers/sweep_groups.hpp"
#include "fibre/step/step_solver.hpp"
#include "fibre/study/nonsmooth_reference.hpp"
#include "reference.hpp"

using namespace fibre;
using fibre::test::rel_diff;

namespace {

struct Problem {
  ContactSystem sys;
  Vector b;
};

Problem pile(int n, double mu)
{
  SceneParams p;
  p.seed = 11;
  Problem pr{pile_scene(n, p), Vector()};
  pr.sys.set_friction(FrictionParams{mu, 0.0, 0.0});
  pr.b = spook_rhs(pr.sys);
  return pr;
}

} // namespace

TEST(Pgs, ConvergesToTheSettledDirectAnswer)
{
  Problem pr = pile(60, 0.4);
  StepOptions ref_opt;
  ref_opt.solver = Method::direct;
  ref_opt.form = Form::contact;
  ref_opt.active_set_max = 60;
  const StepResult ref = solve_step(pr.sys, serial_exchange(), ref_opt, nullptr, MPI_COMM_SELF);
  ASSERT_TRUE(ref.set_settled);

  const Cones cones(pr.sys);
  const std::vector<Vec6> scale = row_scales(pr.sys);
  Vector lambda = Vector::Zero(pr.sys.contact_dofs());
  const PgsResult res =
      pgs(pr.sys, serial_exchange(), cones, pr.b, scale, lambda, PgsControl{100000, 1e-12, 100000});
  EXPECT_EQ(res.reason, StopReason::converged);
  EXPECT_LT(res.last_change, 1e-12);
  EXPECT_LT(complementarity(pr.sys, serial_exchange(), cones, pr.b, lambda, scale), 1e-9);
  EXPECT_LT(rel_diff(lambda, ref.lambda), 1e-6);
  // the reference's caps settle to cap_tol 1e-6 of the largest impulse
  EXPECT_LT(rel_diff(velocity_change(pr.sys, serial_exchange(), lambda), ref.dv), 1e-5);
}

namespace {

// One process without ghosts that says it has a halo: the sweeps take the exchange path
// (copies, reverse_sum, forward) that SerialExchange lets them skip.
class HaloExchange final : public Exchange {
 public:
  void forward(Vector &) const override {}
  void reverse_sum(Vector &) const override {}
  void sum(double *, int) const override {}
  void max(double *, int) const override {}
  long exclusive_prefix_sum(long) const override { return 0; }
};

} // namespace

// Skipping the halo round trip changes nothing but round-off: the same sweeps, the same
// stop, and the impulses of both paths agree to 1e-12 on a frictional pile.
TEST(Pgs, SkippingAnEmptyHaloChangesNothing)
{
  EXPECT_FALSE(serial_exchange().has_halo());
  EXPECT_TRUE(HaloExchange().has_halo());
  Problem pr = pile(60, 0.4);
  const Cones cones(pr.sys);
  const std::vector<Vec6> scale = row_scales(pr.sys);
  PgsControl control{2000, 0.0, 2000};
  control.accuracy = 1e-8;
  Vector fast = Vector::Zero(pr.sys.contact_dofs()), halo = fast;
  const PgsResult a = pgs(pr.sys, serial_exchange(), cones, pr.b, scale, fast, control);
  const PgsResult b = pgs(pr.sys, HaloExchange(), cones, pr.b, scale, halo, control);
  EXPECT_EQ(a.reason, StopReason::converged);
  EXPECT_EQ(a.sweeps, b.sweeps);
  EXPECT_GT(a.sweeps, 20);
  EXPECT_LT(rel_diff(fast, halo), 1e-12);
}

TEST(Pgs, TypedStopReasons)
{
  Problem pr = pile(60, 0.4);
  const Cones cones(pr.sys);
  const std::vector<Vec6> scale = row_scales(pr.sys);
  Vector lambda = Vector::Zero(pr.sys.contact_dofs());
  PgsResult res =
      pgs(pr.sys, serial_exchange(), cones, pr.b, scale, lambda, PgsControl{3, 1e-12, 100});
  EXPECT_EQ(res.reason, StopReason::max_iterations);
  EXPECT_EQ(res.sweeps, 3);
  // a stall window of one sweep: the first sweep that does not beat the best stops it
  lambda.setZero();
  res = pgs(pr.sys, serial_exchange(), cones, pr.b, scale, lambda, PgsControl{100000, 0.0, 1});
  EXPECT_EQ(res.reason, StopReason::stagnation);
  EXPECT_LT(res.sweeps, 100000);
  // non-finite rows of b project to zero: the impulses stay finite
  Vector bad = pr.b;
  bad[0] = std::numeric_limits<double>::quiet_NaN();
  bad[7] = std::numeric_limits<double>::infinity();
  lambda.setZero();
  res = pgs(pr.sys, serial_exchange(), cones, bad, scale, lambda, PgsControl{});
  EXPECT_NE(res.reason, StopReason::non_finite);
  EXPECT_TRUE(lambda.allFinite());
  // a non-finite start poisons the velocities: the first sweep is undone and says so
  lambda.setZero();
  lambda[3] = std::numeric_limits<double>::quiet_NaN();
  res = pgs(pr.sys, serial_exchange(), cones, pr.b, scale, lambda, PgsControl{});
  EXPECT_EQ(res.reason, StopReason::non_finite);
  EXPECT_EQ(res.sweeps, 1);
  EXPECT_TRUE(std::isnan(lambda[3]));
  EXPECT_EQ(lambda.norm() != lambda.norm(), true); // unchanged: the caller's start
}

// The sweeps still needed, from changes that fall geometrically: log(tol / e) / log(c), e the
// remaining error c / (1 - c) times the last change.
TEST(Pgs, PredictsTheSweepsStillNeeded)
{
  PgsResult res;
  for (int s = 0; s < kPredictSweeps; ++s) res.record(1e-2 * std::pow(0.9, s));
  EXPECT_EQ(res.predicted_sweeps(1e-4), -1); // not enough sweeps yet
  res.record(1e-2 * std::pow(0.9, kPredictSweeps));
  const double e = res.last_change * 0.9 / 0.1;
  EXPECT_NEAR(res.error_estimate(), e, 1e-12 * e);
  EXPECT_NEAR(res.predicted_sweeps(1e-4), std::log(1e-4 / e) / std::log(0.9), 1e-9);
  EXPECT_EQ(res.predicted_sweeps(1.0), 0); // met
  PgsResult flat;
  for (int s = 0; s <= kPredictSweeps; ++s) flat.record(1e-3);
  EXPECT_EQ(flat.predicted_sweeps(1e-4), INFINITY);
}

// A solve that starts again reports both parts: its sweeps, visits and changes in order.
TEST(Pgs, ASlowSolveStartsAgainOnce)
{
  Problem pr = pile(60, 0.4);
  const Cones cones(pr.sys);
  const std::vector<Vec6> scale = row_scales(pr.sys);
  PgsControl control{2000, 0.0};
  control.accuracy = 1e-12;
  control.anderson = 3;
  control.anderson_period = 2;
  control.min_sweeps = 10;
  Vector plain = Vector::Zero(pr.sys.contact_dofs());
  const PgsResult never = pgs(pr.sys, serial_exchange(), cones, pr.b, scale, plain, control);
  EXPECT_EQ(never.slow_restarts, 0);
  control.restart_sweeps = 1; // any solve not done by sweep 30 starts again
  Vector lambda = Vector::Zero(pr.sys.contact_dofs());
  const PgsResult res = pgs(pr.sys, serial_exchange(), cones, pr.b, scale, lambda, control);
  ASSERT_GT(never.sweeps, 40);
  EXPECT_EQ(res.slow_restarts, 1);
  EXPECT_TRUE(res.converged());
  EXPECT_EQ(static_cast<int>(res.changes.size()), res.sweeps);
  EXPECT_EQ(res.visits, static_cast<long long>(res.sweeps) * pr.sys.num_contacts());
  EXPECT_EQ(res.full_sweeps.back(), res.sweeps - 1);
  EXPECT_LT(rel_diff(lambda, plain), 1e-8); // the same solution
}

// solver pgs in the step: no linear pass, and the sweeps' accuracy in the result.
TEST(Pgs, AsTheStepSolver)
{
  Problem pr = pile(60, 0.4);
  StepOptions o;
  o.solver = Method::pgs;
  o.sweeps = 100000;
  o.sweep_tol = 1e-10;
  o.accuracy = 0; // stop on sweep_tol
  const StepResult res = solve_step(pr.sys, serial_exchange(), o, nullptr, MPI_COMM_SELF);
  EXPECT_EQ(res.total_iterations, 0);
  EXPECT_EQ(res.active_set_passes, 0);
  EXPECT_TRUE(res.converged);
  EXPECT_EQ(res.sweep_reason, StopReason::converged);
  EXPECT_LT(res.complementarity, 1e-7);
  o.sweeps = 2;
  const StepResult cut = solve_step(pr.sys, serial_exchange(), o, nullptr, MPI_COMM_SELF);
  EXPECT_FALSE(cut.converged);
  EXPECT_EQ(cut.reason, StopReason::max_iterations);
  EXPECT_EQ(cut.sweeps, 2);
  EXPECT_TRUE(cut.lambda.allFinite());
}

namespace {

// One process whose body `ghost` is a ghost of body 0: forward copies 0 to it, reverse_sum
// adds it into 0. With `owners` naming body 0 as its body it is a periodic image on the same
// process (LAMMPS's serial periodic runs); without, it relaxes apart from body 0 within a sweep
// as the other process's copy does.
class GhostOfBodyZero final : public Exchange {
 public:
  GhostOfBodyZero(int ghost, std::vector<int> owners) : owners(std::move(owners)), ghost_(6 * ghost)
  {
  }
  void forward(Vector &v) const override { v.segment<6>(ghost_) = v.segment<6>(0); }
  void reverse_sum(Vector &v) const override
  {
    v.segment<6>(0) += v.segment<6>(ghost_);
    v.segment<6>(ghost_).setZero();
  }
  void sum(double *, int) const override {}
  void max(double *, int) const override {}
  long exclusive_prefix_sum(long) const override { return 0; }
  const std::vector<int> &local_owners() const override { return owners; }
  std::vector<int> owners; // a test may clear them

 private:
  Eigen::Index ghost_;
};

} // namespace

// Three spheres A B C on a periodic line, touching, and the image A' of A: B and C rush at A
// from both sides, through the contacts A-B and C-A', on two copies of A. The SPOOK step
// (d = 2, gaps 0) asks G v+ = G v / 9 of both pressing rows: with masses 1, 1.5, 2 and
// approach speeds 1, lambda = (40/27, 128/81). With local_owners() the sweeps update A in place
// (Gauss-Seidel on the one body); relaxing A' apart from A within a sweep converges more slowly:
// as Jacobi across the boundary the shear cell of examples/shear stalled at a residual of 0.05
// and blew up, and as two mass-split copies (what processes do) it is still slower.
TEST(Pgs, PeriodicImagesAreOneBody)
{
  const double xs[4] = {0.0, 1.0, 2.0, 3.0}; // A, B, C, A'
  const double vs[4] = {0.0, -1.0, 1.0, 0.0};
  const double masses[4] = {1.0, 1.5, 2.0, 1.0};
  std::vector<Body> bodies(4);
  for (int k = 0; k < 4; ++k) {
    bodies[k].mass = masses[k];
    bodies[k].radius = 0.5;
    bodies[k].x = Vec3(xs[k], 0, 0);
    bodies[k].v = Vec3(vs[k], 0, 0);
  }
  std::vector<Contact> contacts{sphere_sphere_contact(bodies, 1, 0),
                                sphere_sphere_contact(bodies, 2, 1),
                                sphere_sphere_contact(bodies, 3, 2)};
  for (Contact &c : contacts) {
    c.compliance.fill(1e-12);
    c.friction = FrictionParams{0.0, 0.0, 0.0};
  }
  SpookParams params;
  params.h = 1e-2;
  ContactSystem sys(bodies, contacts, 3, params, 3);
  GhostOfBodyZero ring(3, {0, 1, 2, 0}); // bodies 0..2 owned, body 3 the image of body 0
  const Vector b = spook_rhs(sys);
  const Cones cones(sys);
  const std::vector<Vec6> scale = row_scales(sys);
  const auto error_after = [&](int sweeps) {
    Vector lambda = Vector::Zero(sys.contact_dofs());
    pgs(sys, ring, cones, b, scale, lambda, PgsControl{sweeps, 1e-15, sweeps});
    return std::hypot(lambda[0] - 40.0 / 27.0, lambda[6] - 128.0 / 81.0) + std::abs(lambda[3]);
  };
  EXPECT_LT(error_after(200), 1e-6);
  const double in_place = error_after(8);
  ring.owners.clear();               // the image relaxes apart from A within a sweep
  EXPECT_LT(error_after(200), 1e-6); // the same fixed point
  const double apart = error_after(8);
  EXPECT_LT(in_place, 0.1 * apart) << in_place << " " << apart;

  // Every solver of the step sees the image as its body: MUMPS in both forms (the contact
  // form's A once coupled the two contacts on A only through separate copies of it, and gave
  // 0.53 and 0.59), and CG in both forms, with the active set finding the released B-C.
  ring.owners = {0, 1, 2, 0};
  for (Method m : {Method::direct, Method::cg})
    for (Form f : {Form::body, Form::contact}) {
      StepOptions o;
      o.form = f;
      o.solver = m;
      o.stop.tol = 1e-12;
      o.active_set_max = 10;
      o.sweeps = 0;
      ContactSystem step = sys;
      const StepResult r = solve_step(step, ring, o, nullptr, MPI_COMM_SELF);
      SCOPED_TRACE(describe(o));
      EXPECT_NEAR(r.lambda[0], 40.0 / 27.0, 1e-6);
      EXPECT_NEAR(r.lambda[6], 128.0 / 81.0, 1e-6);
      EXPECT_EQ(r.lambda[3], 0.0);
    }
}

// A sphere landing on a floor whose two halves meet under it, one contact on each process.
// Each process alone stops the whole sphere, and together they overshoot: block Jacobi swings
// between twice the needed impulse and none for ever. Split into two copies of half the mass,
// each contact takes half the impulse of one contact on one process, at once.
TEST(Pgs, MassSplittingStopsSharedBodiesFromOvershooting)
{
  std::vector<Body> one(1);
  one[0].mass = 2.0;
  one[0].radius = 0.5;
  one[0].v = Vec3(0.1, 0, -1.0);
  one[0].force = Vec3(0, 0, -9.81 * one[0].mass);
  std::vector<Contact> floor{sphere_wall_contact(one, 0, Vec3::UnitZ(), 0.5)};
  floor[0].compliance.fill(1e-10);
  floor[0].friction = FrictionParams{0.0, 0.0, 0.0};
  SpookParams params;
  params.h = 1e-2;
  const ContactSystem serial(one, floor, 3, params);
  Vector whole = Vector::Zero(serial.contact_dofs());
  pgs(serial, serial_exchange(), Cones(serial), spook_rhs(serial), row_scales(serial), whole,
      PgsControl{10, 1e-14, 10});
  ASSERT_GT(whole[0], 0.0);

  std::vector<Body> two{one[0], one[0]}; // the body and the other process's copy
  std::vector<Contact> halves{floor[0], floor[0]};
  halves[1].a = 1;
  const ContactSystem split(two, halves, 3, params, 1);
  Vector lambda = Vector::Zero(split.contact_dofs());
  const PgsResult res = pgs(split, GhostOfBodyZero(1, {}), Cones(split), spook_rhs(split),
                            row_scales(split), lambda, PgsControl{50, 1e-12, 50});
  EXPECT_EQ(res.reason, StopReason::converged);
  EXPECT_LE(res.sweeps, 3);
  // (two contacts in parallel are twice as stiff: Sigma / (1 / m) = 9e-7 apart)
  EXPECT_NEAR(lambda[0], 0.5 * whole[0], 1e-5 * whole[0]);
  EXPECT_NEAR(lambda[3], 0.5 * whole[0], 1e-5 * whole[0]);
}

namespace {

// One process whose body `body` has a ghost copy `ghost` (as another process's copy of it
// would be) holding some of its contacts. With `named`, its halo names the two bodies
// (Halo::bodies, as LAMMPS's does), and the sweeps carry only their changes around each
// exchange; without, every body's (the default halo's full vectors).
class GhostOfBody final : public Exchange {
 public:
  GhostOfBody(int body, int ghost, bool named) : body_(body), ghost_(ghost), named_(named) {}
  void forward(Vector &v) const override { v.segment<6>(6 * ghost_) = v.segment<6>(6 * body_); }
  void reverse_sum(Vector &v) const override
  {
    v.segment<6>(6 * body_) += v.segment<6>(6 * ghost_);
    v.segment<6>(6 * ghost_).setZero();
  }
  void sum(double *, int) const override {}
  void max(double *, int) const override {}
  long exclusive_prefix_sum(long) const override { return 0; }
  std::unique_ptr<Halo> halo(const std::vector<char> &, bool) const override
  {
    return std::make_unique<Copies>(*this, named_);
  }

 private:
  class Copies final : public Halo {
   public:
    Copies(const GhostOfBody &ex, bool named)
        : ex_(ex), bodies_{std::min(ex.body_, ex.ghost_), std::max(ex.body_, ex.ghost_)},
          named_(named)
    {
    }
    void sum_copies(Vector &v) const override
    {
      ex_.reverse_sum(v);
      ex_.forward(v);
    }
    const std::vector<int> *bodies() const override { return named_ ? &bodies_ : nullptr; }

   private:
    const GhostOfBody &ex_;
    std::vector<int> bodies_;
    bool named_;
  };
  int body_, ghost_;
  bool named_;
};

} // namespace

// A frictional pile whose busiest sphere is split between two copies, every other one of its
// contacts on the ghost: the sweeps over the halo's two bodies only take the full vectors'
// sweeps and impulses (to round-off), and both converge to the whole sphere's impulses on
// one process (the mass-split copies' fixed point is the serial one).
TEST(Pgs, HaloOfNamedBodiesCarriesTheSameChanges)
{
  const Problem pr = pile(60, 0.4);
  const int n = pr.sys.num_bodies();
  std::vector<int> degree(n, 0);
  for (const Contact &c : pr.sys.contacts()) {
    ++degree[c.a];
    if (c.b >= 0) ++degree[c.b];
  }
  const int body = int(std::max_element(degree.begin(), degree.end()) - degree.begin());
  ASSERT_GE(degree[body], 4);
  std::vector<Body> bodies = pr.sys.bodies();
  bodies.push_back(bodies[body]);
  std::vector<Contact> contacts = pr.sys.contacts();
  int moved = 0;
  for (Contact &c : contacts)
    if (c.a == body || c.b == body) {
      if (moved++ % 2 == 0) continue;
      (c.a == body ? c.a : c.b) = n;
    }
  const ContactSystem split(bodies, contacts, pr.sys.rows(), pr.sys.params(), n);
  const Vector b = spook_rhs(split);
  const Cones cones(split);
  const std::vector<Vec6> scale = row_scales(split);
  PgsControl control{20000, 0.0, 20000};
  control.accuracy = 1e-11;
  Vector named = Vector::Zero(split.contact_dofs()), full = named;
  const PgsResult a = pgs(split, GhostOfBody(body, n, true), cones, b, scale, named, control);
  const PgsResult f = pgs(split, GhostOfBody(body, n, false), cones, b, scale, full, control);
  EXPECT_EQ(a.reason, StopReason::converged);
  EXPECT_EQ(a.sweeps, f.sweeps);
  EXPECT_GT(a.sweeps, 20);
  EXPECT_LT(rel_diff(named, full), 1e-12);

  Vector whole = Vector::Zero(pr.sys.contact_dofs());
  const PgsResult w =
      pgs(pr.sys, serial_exchange(), Cones(pr.sys), pr.b, row_scales(pr.sys), whole, control);
  EXPECT_EQ(w.reason, StopReason::converged);
  EXPECT_LT(rel_diff(named, whole), 1e-6) << rel_diff(named, whole);
}

namespace {

// A column of n spheres (radius 0.5) on a floor, its contacts listed from the top down: the
// order in which point sweeps carry the load down most slowly.
ContactSystem column(int n)
{
  std::vector<Body> bodies(n);
  for (int k = 0; k < n; ++k) {
    bodies[k].radius = 0.5;
    bodies[k].mass = 0.5;
    bodies[k].x = Vec3(0, 0, 0.5 + k);
    bodies[k].force = Vec3(0.1, 0, -9.81 * bodies[k].mass);
  }
  std::vector<Contact> contacts;
  for (int k = n - 1; k > 0; --k) contacts.push_back(sphere_sphere_contact(bodies, k, k - 1));
  contacts.push_back(sphere_wall_contact(bodies, 0, Vec3::UnitZ(), 0.5));
  for (Contact &c : contacts) {
    c.compliance.fill(1e-9);
    c.friction = FrictionParams{0.5, 0.1, 0.05};
  }
  SpookParams spook;
  spook.h = 1e-3;
  return ContactSystem(bodies, contacts, 6, spook);
}

} // namespace

// Fibre-block Gauss-Seidel: the column is one block (its chain and the floor), solved exactly
// by its corrections, where point sweeps crawl.
TEST(FibreBlocks, SolveAColumnInAFewSweeps)
{
  const ContactSystem sys = column(30);
  const Vector b = spook_rhs(sys);
  const Cones cones(sys);
  const std::vector<Vec6> scale = row_scales(sys);
  const Reference ref = nonsmooth_reference(sys, Vector::Zero(sys.contact_dofs()));
  // Point sweeps crawl here (a contraction near 1): their residual of 1e-10 is still 1e-4 off
  // in velocity, so the reference is the semismooth Newton solution.
  ASSERT_TRUE(ref.newton.converged);
  PgsControl control{20000, 1e-10, 100000};
  Vector point = Vector::Zero(sys.contact_dofs());
  const PgsResult by_point = pgs(sys, serial_exchange(), cones, b, scale, point, control);
  control.fibre_blocks = true;
  control.block_weight = EdgeWeight::z;
  Vector block = Vector::Zero(sys.contact_dofs());
  const PgsResult by_block = pgs(sys, serial_exchange(), cones, b, scale, block, control);
  EXPECT_TRUE(by_block.converged());
  EXPECT_LE(by_block.sweeps, 50); // the rolling cones on their boundary follow lambda_n lagged
  EXPECT_LT(step_accuracy(sys, block, ref.lambda).velocity(), 1e-8);
  // 20,000 point sweeps (400 times as many) are still far off
  EXPECT_EQ(by_point.sweeps, 20000);
  EXPECT_GT(step_accuracy(sys, point, ref.lambda).velocity(), 1e-5);
  std::printf("column: point sweeps %d, error %.3g; block sweeps %d, error %.3g\n", by_point.sweeps,
              step_accuracy(sys, point, ref.lambda).velocity(), by_block.sweeps,
              step_accuracy(sys, block, ref.lambda).velocity());
}

namespace {

// The 200-sphere pile with its cones, row scales and converged reference.
struct PileCase {
  Problem pr = pile(200, 0.4);
  Cones cones{pr.sys};
  std::vector<Vec6> scale = row_scales(pr.sys);
  Reference ref = nonsmooth_reference(pr.sys, Vector::Zero(pr.sys.contact_dofs()));
};

} // namespace

// On a pile with sliding and released contacts the corrections change the path, not the fixed
// point: the same impulses as the reference.
TEST(FibreBlocks, ConvergeToTheReferenceOnAPile)
{
  const PileCase pc;
  const Problem &pr = pc.pr;
  const Cones &cones = pc.cones;
  const std::vector<Vec6> &scale = pc.scale;
  const Reference &ref = pc.ref;
  ASSERT_TRUE(ref.confirmed());
  for (EdgeWeight weight : {EdgeWeight::z, EdgeWeight::impulse}) {
    PgsControl control{100000, 1e-12, 100000};
    control.fibre_blocks = true;
    control.block_weight = weight;
    Vector lambda = Vector::Zero(pr.sys.contact_dofs());
    const PgsResult res = pgs(pr.sys, serial_exchange(), cones, pr.b, scale, lambda, control);
    EXPECT_TRUE(res.converged()) << to_string(weight);
    EXPECT_LT(complementarity(pr.sys, serial_exchange(), cones, pr.b, lambda, scale), 1e-9);
    EXPECT_LT(step_accuracy(pr.sys, lambda, ref.lambda).velocity(), 1e-6) << to_string(weight);
  }
}

// APGD has the sweeps' fixed point (the cones' projection at any step length keeps it), so it
// converges to the same reference; capped, it says so and keeps its best iterate.
TEST(Apgd, ConvergesToTheReferenceOnAPile)
{
  const PileCase pc;
  const Problem &pr = pc.pr;
  const Cones &cones = pc.cones;
  const std::vector<Vec6> &scale = pc.scale;
  const Reference &ref = pc.ref;
  ASSERT_TRUE(ref.confirmed());
  Vector lambda = Vector::Zero(pr.sys.contact_dofs());
  const PgsResult res =
      apgd(pr.sys, serial_exchange(), cones, pr.b, scale, lambda, PgsControl{20000, 1e-8});
  EXPECT_TRUE(res.converged());
  EXPECT_LT(complementarity(pr.sys, serial_exchange(), cones, pr.b, lambda, scale), 1e-8);
  EXPECT_LT(step_accuracy(pr.sys, lambda, ref.lambda).velocity(), 1e-5);
  std::printf("apgd: %d iterations, velocity error %.3g\n", res.sweeps,
              step_accuracy(pr.sys, lambda, ref.lambda).velocity());

  lambda.setZero();
  const PgsResult capped =
      apgd(pr.sys, serial_exchange(), cones, pr.b, scale, lambda, PgsControl{5, 1e-11});
  EXPECT_EQ(capped.reason, StopReason::max_iterations);
  EXPECT_EQ(capped.sweeps, 5);
  EXPECT_NEAR(capped.last_change,
              complementarity(pr.sys, serial_exchange(), cones, pr.b, lambda, scale), 1e-12);
  EXPECT_TRUE(lambda.allFinite());
}

// Focused sweeps (PgsControl::focus_sweeps) have the sweeps' fixed point: they skip only
// contacts that the last full sweep left (almost) where they were. From a cold start on a pile,
// where the load paths form from the bottom up, they reach the step's accuracy on fewer contact
// visits, as accurate as plain sweeps against the converged reference.
TEST(Pgs, FocusedSweepsReachTheReferenceOnFewerVisits)
{
  const PileCase pc;
  const Problem &pr = pc.pr;
  ASSERT_TRUE(pc.ref.confirmed());
  const int nc = pr.sys.num_contacts();
  const auto solve = [&](int focus, double accuracy, Vector &lambda) {
    PgsControl control{100000, 1e-12, 100000};
    control.accuracy = accuracy;
    control.min_sweeps = 10;
    control.focus_sweeps = focus;
    lambda = Vector::Zero(pr.sys.contact_dofs());
    return pgs(pr.sys, serial_exchange(), pc.cones, pr.b, pc.scale, lambda, control);
  };
  Vector plain, focused;
  const PgsResult rp = solve(0, 0.0, plain), rf = solve(3, 0.0, focused);
  EXPECT_TRUE(rp.converged());
  EXPECT_TRUE(rf.converged());
  EXPECT_EQ(rp.visits, static_cast<long long>(rp.sweeps) * nc);
  EXPECT_LT(step_accuracy(pr.sys, focused, pc.ref.lambda).velocity(), 1e-6);
  EXPECT_LT(rf.visits, 0.7 * rp.visits); // measured 0.46

  const PgsResult ap = solve(0, 1e-4, plain), af = solve(3, 1e-4, focused);
  const StepAccuracy ep = step_accuracy(pr.sys, plain, pc.ref.lambda);
  const StepAccuracy ef = step_accuracy(pr.sys, focused, pc.ref.lambda);
  std::printf("to 1e-12: plain %d sweeps (%lld visits), focused %d (%lld); to 1e-4: plain %d "
              "sweeps %.2f sweep-equivalents, error %.3g / %.3g; focused %d sweeps %.2f, error "
              "%.3g / %.3g\n",
              rp.sweeps, rp.visits, rf.sweeps, rf.visits, ap.sweeps, double(ap.visits) / nc,
              ep.velocity(), ep.lambda_n, af.sweeps, double(af.visits) / nc, ef.velocity(),
              ef.lambda_n);
  EXPECT_TRUE(af.converged());
  EXPECT_LT(af.visits, 0.7 * ap.visits); // measured 0.55
  // the same true accuracy as the plain sweeps' (the estimate follows the full sweeps)
  EXPECT_LT(ef.lambda_n, 2.0 * ep.lambda_n + 1e-5);
  EXPECT_LT(ef.velocity(), 2.0 * ep.velocity() + 1e-5);
  EXPECT_EQ(af.full_sweeps.back(), af.sweeps - 1); // it stopped on a full sweep
}

namespace {

// The same contacts in another order (rows 3 or 6 as `rows`), with its rhs.
Problem reordered(const ContactSystem &sys, const std::vector<int> &order, int rows)
{
  std::vector<Contact> contacts;
  for (int c : order) contacts.push_back(sys.contacts()[c]);
  Problem pr{ContactSystem(sys.bodies(), contacts, rows, sys.params()), Vector()};
  pr.b = spook_rhs(pr.sys);
  return pr;
}

// The groups' order of the contacts: group by group, the empty lanes left out, then the singles.
std::vector<int> group_order(const ContactGroups &grouped)
{
  std::vector<int> order;
  for (const ContactGroup &g : grouped.groups)
    for (int c : g)
      if (c >= 0) order.push_back(c);
  order.insert(order.end(), grouped.singles.begin(), grouped.singles.end());
  return order;
}

} // namespace

// Every contact is in one group or among the singles, no group holds a body twice (a periodic
// image counts as its body), and a body against its own image is a single.
TEST(SweepGroups, ShareNoBodyAndHoldEveryContactOnce)
{
  const Problem pr = pile(300, 0.4);
  const ContactGroups grouped = group_contacts(pr.sys, {});
  EXPECT_TRUE(grouped.singles.empty());
  std::vector<int> seen(pr.sys.num_contacts(), 0);
  int full = 0;
  for (const ContactGroup &g : grouped.groups) {
    std::vector<int> bodies;
    int lanes = 0;
    for (int c : g) {
      if (c < 0) continue;
      ++lanes;
      ++seen[c];
      const Contact &k = pr.sys.contacts()[c];
      bodies.push_back(k.a);
      if (k.b >= 0) bodies.push_back(k.b);
    }
    EXPECT_GT(lanes, 0);
    full += lanes == kGroupLanes;
    std::sort(bodies.begin(), bodies.end());
    EXPECT_EQ(std::adjacent_find(bodies.begin(), bodies.end()), bodies.end());
  }
  for (int n : seen) EXPECT_EQ(n, 1);
  // the groups are nearly all full: a pile's contacts are mostly independent four by four
  EXPECT_GT(full, 0.9 * double(grouped.groups.size()));

  // bodies 0..2 owned, 3 the image of 0 and 4 of 1: 3-2 and 0-2 share body 0 through the
  // image, and 1 against its image 4 is one body on both sides
  std::vector<Body> bodies(5);
  const double xs[5] = {0.0, 1.0, 2.0, 3.0, 1.95};
  for (int k = 0; k < 5; ++k) {
    bodies[k].mass = 1.0;
    bodies[k].radius = 0.5;
    bodies[k].x = Vec3(xs[k], 0.0, k == 4 ? 0.6 : 0.0);
  }
  std::vector<Contact> contacts{sphere_sphere_contact(bodies, 3, 2),
                                sphere_sphere_contact(bodies, 2, 0),
                                sphere_sphere_contact(bodies, 4, 1)};
  for (Contact &c : contacts) c.compliance.fill(1e-12);
  const ContactSystem ring(bodies, contacts, 6, SpookParams{}, 3);
  const ContactGroups images = group_contacts(ring, {0, 1, 2, 0, 1});
  EXPECT_EQ(images.singles, std::vector<int>{2});
  ASSERT_EQ(images.groups.size(), 2u); // 3-2 and 2-0 apart
  EXPECT_EQ(images.groups[0], (ContactGroup{0, -1, -1, -1}));
  EXPECT_EQ(images.groups[1], (ContactGroup{1, -1, -1, -1}));
}

// A grouped sweep is a one-at-a-time sweep in the groups' order: from a cold start, three
// sweeps of each agree to round-off (the grouped lanes use fused multiply-adds), with rows 6
// (every cone) and rows 3; and both reach the converged reference.
TEST(SweepGroups, AreGaussSeidelInTheGroupsOrder)
{
  if (!grouped_sweeps_available()) GTEST_SKIP() << "no AVX2 and FMA on this processor";
  Problem pr = pile(200, 0.4);
  pr.sys.set_friction(FrictionParams{0.4, 0.05, 0.02});
  for (int rows : {6, 3}) {
    SCOPED_TRACE(rows);
    std::vector<int> listed(pr.sys.num_contacts());
    std::iota(listed.begin(), listed.end(), 0);
    const Problem base = reordered(pr.sys, listed, rows);
    const std::vector<int> order = group_order(group_contacts(base.sys, {}));
    const Problem in_order = reordered(base.sys, order, rows);
    const auto sweeps = [](const Problem &p, bool grouped, int count, double accuracy) {
      PgsControl control{count, 0.0, count};
      control.grouped = grouped;
      control.accuracy = accuracy;
      Vector lambda = Vector::Zero(p.sys.contact_dofs());
      pgs(p.sys, serial_exchange(), Cones(p.sys), p.b, row_scales(p.sys), lambda, control);
      return lambda;
    };
    const Vector grouped = sweeps(base, true, 3, 0.0);
    const Vector one_by_one = sweeps(in_order, false, 3, 0.0);
    Vector back(grouped.size());
    for (std::size_t k = 0; k < order.size(); ++k)
      back.segment(rows * Eigen::Index(order[k]), rows) =
          one_by_one.segment(rows * Eigen::Index(k), rows);
    EXPECT_GT(grouped.norm(), 0.0);
    EXPECT_LT(rel_diff(grouped, back), 1e-12);
    // and not the listed order's sweeps, which differ after the first group
    EXPECT_GT(rel_diff(grouped, sweeps(base, false, 3, 0.0)), 1e-6);

    const Reference ref = nonsmooth_reference(base.sys, Vector::Zero(base.sys.contact_dofs()));
    ASSERT_TRUE(ref.confirmed());
    const Vector converged = sweeps(base, true, 100000, 1e-11);
    EXPECT_LT(step_accuracy(base.sys, converged, ref.lambda).velocity(), 1e-7);
    EXPECT_LT(step_accuracy(base.sys, converged, ref.lambda).lambda_n, 1e-7);
  }
}

// The groups kept for the next substep (SweepCache) sweep as groups built anew: after the
// substep's new velocities, compliances, friction and rhs the kept solve is the fresh one bit
// for bit, and a system of other kinematics gets its own groups.
TEST(SweepGroups, KeptForTheNextSubstepSweepAsBuiltAnew)
{
  if (!grouped_sweeps_available()) GTEST_SKIP() << "no AVX2 and FMA on this processor";
  Problem pr = pile(200, 0.4);
  pr.sys.set_friction(FrictionParams{0.4, 0.05, 0.02});
  const auto solve = [](const ContactSystem &sys, SweepCache *cache) {
    PgsControl control{30, 0.0, 30};
    control.cache = cache;
    Vector lambda = Vector::Zero(sys.contact_dofs());
    pgs(sys, serial_exchange(), Cones(sys), spook_rhs(sys), row_scales(sys), lambda, control);
    return lambda;
  };
  SweepCache cache;
  const Vector first = solve(pr.sys, &cache);
  EXPECT_EQ(cache.kinematics, pr.sys.kinematics_id());
  ASSERT_EQ(cache.grouped.size(), 1u);
  const GroupedSweep *kept = cache.grouped[0].get();

  // the next substep: the bodies at the velocities the impulses give, softer rows, more friction
  const Vector v_plus = velocities_after(pr.sys, serial_exchange(), first);
  Vector rows;
  g_apply(pr.sys, v_plus, rows);
  const std::uint64_t id = pr.sys.kinematics_id();
  pr.sys.next_substep(
      [&](std::vector<Body> &bodies, std::vector<Contact> &contacts) {
        for (std::size_t i = 0; i < bodies.size(); ++i) {
          bodies[i].v = v_plus.segment<3>(6 * Eigen::Index(i));
          bodies[i].omega = v_plus.segment<3>(6 * Eigen::Index(i) + 3);
        }
        for (Contact &c : contacts) {
          for (double &eps : c.compliance) eps *= 3.0;
          c.friction.mu = 0.6;
        }
      },
      std::move(rows));
  ASSERT_EQ(pr.sys.kinematics_id(), id); // the kinematics hold
  const Vector again = solve(pr.sys, &cache);
  EXPECT_EQ(cache.grouped[0].get(), kept); // refreshed, not rebuilt
  const Vector fresh = solve(pr.sys, nullptr);
  EXPECT_GT(rel_diff(again, first), 1e-3); // the substep changed the solve
  EXPECT_EQ(again, fresh);

  const Problem other = pile(120, 0.4);
  EXPECT_EQ(solve(other.sys, &cache), solve(other.sys, nullptr));
  EXPECT_EQ(cache.kinematics, other.sys.kinematics_id());
}
