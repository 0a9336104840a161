// Cohesive laws (fibre/model/cohesion.hpp) against their closed forms: JKR's pull-off force
// -3 pi gamma r at its reach and -8/9 of it at zero overlap, DMT's and sjkr's smallest force;
// the inverse law; the cones' shifted bound; and the step's normal row, which holds a pair
// pulled apart by less than the pull-off force and lets it go under more.
#include <gtest/gtest.h>

#include <cmath>

#include "fibre/algebra/cones.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/model/cohesion.hpp"
#include "fibre/model/contact_model.hpp"
#include "fibre/solvers/pgs.hpp"
#include "reference.hpp"

using namespace fibre;

namespace {

constexpr double kPi = 3.14159265358979323846;

PairCoefficients law(CohesionLaw cohesion, double gamma)
{
  PairCoefficients p;
  p.set = true;
  p.mu = 0.5;
  p.normal = NormalLaw::hertz_material;
  p.k_n = 4.0 / 3.0 * 5.0e3; // E_eff 5e3
  p.cohesion = cohesion;
  p.cohesion_energy = gamma;
  return p;
}

} // namespace

TEST(Cohesion, JkrPullOffAtItsReachAndAtZeroOverlap)
{
  const double r = 0.25, gamma = 1.5;
  const PairCoefficients p = law(CohesionLaw::jkr, gamma);
  const double fc = 3.0 * kPi * gamma * r;
  EXPECT_NEAR(pull_off_force(p, r), fc, 1e-12 * fc);
  // LAMMPS's delta_pulloff at a = (9 pi gamma r^2 / 4 E)^(1/3)
  const double E = 5.0e3, a = std::cbrt(9.0 * kPi * gamma * r * r / (4.0 * E));
  const double reach = -(a * a / r - 2.0 * std::sqrt(kPi * gamma * a / E));
  EXPECT_NEAR(cohesive_reach(p, r), reach, 1e-12 * reach);
  EXPECT_NEAR(cohesive_force(p, r, -reach), -fc, 1e-9 * fc);
  EXPECT_NEAR(cohesive_force(p, r, 0.0), -8.0 / 9.0 * fc, 1e-9 * fc);
  // beyond its reach the law holds at the pull-off force (the contact breaks there)
  EXPECT_NEAR(cohesive_force(p, r, -2.0 * reach), -fc, 1e-9 * fc);
  // deep in, JKR's force approaches Hertz's from below
  const double d = 50.0 * reach, hertz = p.k_n * std::sqrt(r * d) * d;
  EXPECT_LT(cohesive_force(p, r, d), hertz);
  EXPECT_GT(cohesive_force(p, r, d), hertz - 2.0 * fc - 4.0 * std::sqrt(kPi * gamma * E) * d);
}

TEST(Cohesion, DmtAndSjkrSmallestForces)
{
  const double r = 0.3;
  const PairCoefficients dmt = law(CohesionLaw::dmt, 2.0);
  EXPECT_NEAR(pull_off_force(dmt, r), 4.0 * kPi * 2.0 * r, 1e-12);
  EXPECT_NEAR(cohesive_force(dmt, r, 0.0), -4.0 * kPi * 2.0 * r, 1e-12);
  EXPECT_EQ(cohesive_reach(dmt, r), 0.0);
  // sjkr: F = K d^1.5 - c d, smallest at d_m = (2c / 3K)^2 with -4 c^3 / (27 K^2)
  const PairCoefficients sjkr = law(CohesionLaw::sjkr, 400.0);
  const double K = sjkr.k_n * std::sqrt(r), c = 2.0 * kPi * r * 400.0;
  const double dm = std::pow(2.0 * c / (3.0 * K), 2.0);
  const double fmin = 4.0 * c * c * c / (27.0 * K * K);
  EXPECT_NEAR(pull_off_force(sjkr, r), fmin, 1e-12 * fmin);
  EXPECT_NEAR(cohesive_force(sjkr, r, dm), -fmin, 1e-9 * fmin);
  EXPECT_GT(cohesive_force(sjkr, r, 0.9 * dm), -fmin);
  EXPECT_GT(cohesive_force(sjkr, r, 1.1 * dm), -fmin);
  EXPECT_EQ(cohesive_force(sjkr, r, -1e-3), 0.0);
}

TEST(Cohesion, OverlapInvertsTheLawOnItsStableBranch)
{
  const double r = 0.25;
  for (CohesionLaw kind : {CohesionLaw::jkr, CohesionLaw::dmt, CohesionLaw::sjkr}) {
    const PairCoefficients p = law(kind, kind == CohesionLaw::sjkr ? 300.0 : 1.0);
    const double fc = pull_off_force(p, r);
    for (double f : {-0.9 * fc, -0.5 * fc, 0.0, 0.7 * fc, 5.0 * fc, 100.0 * fc}) {
      const double d = cohesive_overlap(p, r, f);
      EXPECT_NEAR(cohesive_force(p, r, d), f, 1e-9 * fc) << int(kind) << " " << f;
    }
    // at or below the pull-off: the branch's end
    const double end = cohesive_overlap(p, r, -2.0 * fc);
    EXPECT_NEAR(cohesive_force(p, r, end), -fc, 1e-9 * fc) << int(kind);
  }
  // without cohesion: Hertz's
  PairCoefficients hertz = law(CohesionLaw::none, 0.0);
  EXPECT_DOUBLE_EQ(cohesive_overlap(hertz, r, 3.0), law_overlap(hertz, r, 3.0));
  EXPECT_EQ(pull_off_force(hertz, r), 0.0);
}

TEST(Cohesion, ConesShiftTheNormalBoundAndLoadTheFriction)
{
  std::vector<Body> bodies(2);
  bodies[0].radius = bodies[1].radius = 0.5;
  bodies[1].x = Vec3(0.99, 0, 0);
  std::vector<Contact> contacts{sphere_sphere_contact(bodies, 1, 0)};
  contacts[0].compliance.fill(1e-10);
  contacts[0].friction = FrictionParams{0.5, 0.0, 0.0};
  contacts[0].pull = 2.0;
  SpookParams params;
  params.h = 0.01;
  const ContactSystem sys(bodies, contacts, 3, params);
  const Cones cones(sys);
  ASSERT_TRUE(cones.cohesive());
  double l[3] = {-1.0, 0.0, 0.0}; // below -h pull = -0.02
  cones.project(l, 0);
  EXPECT_DOUBLE_EQ(l[0], -0.02);
  double m[3] = {-0.01, 0.3, 0.4}; // radius 0.5 (-0.01 + 0.04) = 0.015
  cones.project(m, 0);
  EXPECT_DOUBLE_EQ(m[0], -0.01);
  EXPECT_NEAR(std::hypot(m[1], m[2]), 0.015, 1e-15);
  EXPECT_NEAR(m[1] / m[2], 0.75, 1e-12);
}

// Two spheres in touch, pulled apart by opposite forces f: a rigid cohesive row holds them
// (lambda_n = -h f, no relative motion) while f is below the pull-off force, and carries the
// pull-off force only when f exceeds it.
TEST(Cohesion, TheStepHoldsBelowThePullOffAndLetsGoAbove)
{
  const double pull = 3.0, h = 1e-3;
  for (double f : {0.5 * pull, 0.95 * pull, 1.5 * pull}) {
    std::vector<Body> bodies(2);
    for (Body &b : bodies) {
      b.radius = 0.5;
      b.mass = 0.5;
    }
    bodies[1].x = Vec3(1.0, 0, 0);
    bodies[0].force = Vec3(-f, 0, 0);
    bodies[1].force = Vec3(f, 0, 0);
    std::vector<Contact> contacts{sphere_sphere_contact(bodies, 1, 0)};
    contacts[0].compliance.fill(1e-14);
    contacts[0].friction = FrictionParams{0.5, 0.0, 0.0};
    contacts[0].pull = pull;
    SpookParams params;
    params.h = h;
    const ContactSystem sys(bodies, contacts, 3, params);
    const Cones cones(sys);
    Vector lambda = Vector::Zero(sys.contact_dofs());
    pgs(sys, serial_exchange(), cones, spook_rhs(sys), row_scales(sys), lambda,
        PgsControl{10000, 1e-14, 10000});
    const double expected = -h * std::min(f, pull);
    EXPECT_NEAR(lambda[0], expected, 1e-6 * h * pull) << f;
    // contact 0 is sphere 1 (a) against sphere 0 (b), its normal along +x
    const Vector v = velocities_after(sys, serial_exchange(), lambda);
    const double opening = v[6] - v[0];
    if (f < pull)
      EXPECT_NEAR(opening, 0.0, 1e-6) << f;
    else
      EXPECT_NEAR(opening, 2.0 * h * (f - pull) / 0.5, 1e-6) << f;
  }
}
