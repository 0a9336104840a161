// The split recovery of penetrations (step/recovery.hpp) against analytic cases: an isolated
// pair opens by a step of max_recovery (less the rows' regularization), split by the masses,
// without a velocity; a shallow overlap is left to the velocity rows; a sphere caged between
// two walls has no room, and it moves no more than a step of max_recovery. Under compliance
// material a new deep overlap is a penetration as a whole, opened as a rigid row's whatever the
// law's softness; the spring keeps what the contact closes after it, and the history's
// penetration shrinks by what the displacement opened. A jammed row is not moved; one with room
// opens.
#include <gtest/gtest.h>

#include <vector>

#include "fibre/core/exchange.hpp"
#include "fibre/model/contact_model.hpp"
#include "fibre/step/recovery.hpp"

using namespace fibre;

namespace {

Body sphere(double x, double mass)
{
  Body b;
  b.type = 1;
  b.mass = mass;
  b.radius = 0.5;
  b.x = Vec3(x, 0, 0);
  return b;
}

SpookParams params()
{
  SpookParams p;
  p.h = 1e-3;
  p.max_recovery = 5.0; // a step of it: 0.005
  return p;
}

// compliance auto's contact model on the contacts (rigid rows, their penetrations)
std::vector<Contact> modelled(const std::vector<Body> &bodies, std::vector<Contact> contacts)
{
  ContactModel model;
  model.compliance.automatic = true;
  apply_contact_model(model, params(), 1.0, bodies, contacts);
  return contacts;
}

// compliance material with one soft Hertz law (E about 1e5: Sigma is many times w)
ContactModel soft_material()
{
  ContactModel model;
  model.compliance.automatic = false;
  model.compliance.material = true;
  model.materials = MaterialTable(1);
  PairCoefficients &law = model.materials.at(1, 1);
  law.set = true;
  law.normal = NormalLaw::hertz_material;
  law.k_n = 1e5;
  return model;
}

// soft_material's contact model on the contacts
std::vector<Contact> material(const std::vector<Body> &bodies, std::vector<Contact> contacts)
{
  apply_contact_model(soft_material(), params(), 1.0, bodies, contacts);
  return contacts;
}

Vector at_rest(const std::vector<Body> &bodies)
{
  return Vector::Zero(6 * Eigen::Index(bodies.size()));
}

} // namespace

TEST(Recovery, AnIsolatedPairOpensByAStepOfTheRecoverySpeed)
{
  // 20% of a diameter deep, masses 1 and 3: the lighter moves three quarters of the opening
  const std::vector<Body> bodies{sphere(0.0, 1.0), sphere(0.8, 3.0)};
  const std::vector<Contact> contacts = modelled(bodies, {sphere_sphere_contact(bodies, 1, 0)});
  ASSERT_NEAR(contacts[0].penetration, 0.2, 1e-12);
  ContactSystem sys(bodies, contacts, 6, params());
  Vector dx;
  ASSERT_EQ(
      recovery_displacement(sys, serial_exchange(), at_rest(bodies), sys.params().h, dx).outcome,
      Recovery::Outcome::opened);
  // the opening: h max_recovery, less the rigid row's regularization Sigma (w mu + Sigma mu = b,
  // w = 1/1 + 1/3), split 3 : 1 by the masses
  const double w = 4.0 / 3.0, open = 0.005 * w / (w + sys.sigma()[0]);
  EXPECT_NEAR(dx[6] - dx[0], open, 1e-12);
  EXPECT_GT(open, 0.99 * 0.005);
  EXPECT_NEAR(dx[0], -0.75 * open, 1e-12);
  EXPECT_NEAR(dx[6], 0.25 * open, 1e-12);
  EXPECT_NEAR(dx.segment<3>(3).norm() + dx.segment<3>(9).norm(), 0.0, 1e-15); // no rotation
  EXPECT_NEAR(dx[1] + dx[2] + dx[7] + dx[8], 0.0, 1e-15);
}

TEST(Recovery, AShallowOverlapIsLeftToTheRows)
{
  // 2% of a diameter: below kPenetrationStart steps of recovery (0.05)
  const std::vector<Body> bodies{sphere(0.0, 1.0), sphere(0.98, 1.0)};
  const std::vector<Contact> contacts = modelled(bodies, {sphere_sphere_contact(bodies, 1, 0)});
  EXPECT_EQ(contacts[0].penetration, 0.0);
  ContactSystem sys(bodies, contacts, 6, params());
  Vector dx;
  EXPECT_EQ(
      recovery_displacement(sys, serial_exchange(), at_rest(bodies), sys.params().h, dx).outcome,
      Recovery::Outcome::none);
  EXPECT_EQ(dx.size(), 0);
}

TEST(Recovery, ACagedSphereIsNotMoved)
{
  // a sphere between two walls 0.8 apart, overlapping both by 0.1: they cannot both open, and
  // whatever opens one closes the other as much (a cage: the displacement is refused)
  std::vector<Body> bodies{sphere(0.0, 1.0)};
  std::vector<Contact> contacts{sphere_wall_contact(bodies, 0, Vec3::UnitX(), 0.4),
                                sphere_wall_contact(bodies, 0, -Vec3::UnitX(), 0.4)};
  contacts = modelled(bodies, contacts);
  ASSERT_GT(contacts[0].penetration, 0.0);
  ContactSystem sys(bodies, contacts, 6, params());
  Vector dx;
  const Recovery recovery =
      recovery_displacement(sys, serial_exchange(), at_rest(bodies), sys.params().h, dx);
  EXPECT_EQ(recovery.outcome, Recovery::Outcome::refused);
  EXPECT_EQ(recovery.split, 2);
  EXPECT_EQ(dx.lpNorm<Eigen::Infinity>(), 0.0);
}

// Three spheres in a row, each pair 0.1 deep, between walls (each 0.1 deep) or against the
// left one alone.
std::vector<Contact> row_of_three(const std::vector<Body> &bodies, bool right_wall)
{
  std::vector<Contact> contacts{sphere_wall_contact(bodies, 0, Vec3::UnitX(), 0.4),
                                sphere_sphere_contact(bodies, 1, 0),
                                sphere_sphere_contact(bodies, 2, 1)};
  if (right_wall) contacts.push_back(sphere_wall_contact(bodies, 2, -Vec3::UnitX(), 0.4));
  return modelled(bodies, contacts);
}

TEST(Recovery, AJammedRowIsNotMoved)
{
  // 2.6 between the walls for three diameters: every opening closes another contact as much
  // (a jammed pack), and the displacement is refused
  const std::vector<Body> bodies{sphere(0.0, 1.0), sphere(0.9, 1.0), sphere(1.8, 1.0)};
  ContactSystem sys(bodies, row_of_three(bodies, true), 6, params());
  Vector dx;
  const Recovery recovery =
      recovery_displacement(sys, serial_exchange(), at_rest(bodies), sys.params().h, dx);
  EXPECT_EQ(recovery.outcome, Recovery::Outcome::refused);
  EXPECT_EQ(recovery.split, 4);
  EXPECT_EQ(dx.lpNorm<Eigen::Infinity>(), 0.0);
}

TEST(Recovery, ARowWithRoomOpens)
{
  // without the right wall the row slides right: every penetration opens, none closes
  const std::vector<Body> bodies{sphere(0.0, 1.0), sphere(0.9, 1.0), sphere(1.8, 1.0)};
  ContactSystem sys(bodies, row_of_three(bodies, false), 6, params());
  Vector dx;
  ASSERT_EQ(
      recovery_displacement(sys, serial_exchange(), at_rest(bodies), sys.params().h, dx).outcome,
      Recovery::Outcome::opened);
  EXPECT_GE(dx[0], 0.0);
  EXPECT_GT(dx[6], dx[0]);
  EXPECT_GT(dx[12], dx[6]);
  EXPECT_LE(dx[12], 0.005 * (1 + 1e-12));
}

TEST(Recovery, AnElasticPenetrationOpensAsARigidRow)
{
  const std::vector<Body> bodies{sphere(0.0, 1.0), sphere(0.8, 3.0)};
  const std::vector<Contact> contacts = material(bodies, {sphere_sphere_contact(bodies, 1, 0)});
  ASSERT_TRUE(contacts[0].elastic[0]);
  ASSERT_NEAR(contacts[0].penetration, 0.2, 1e-12); // the whole overlap: no load explains it
  ContactSystem sys(bodies, contacts, 6, params());
  const double w = 4.0 / 3.0;
  ASSERT_GT(sys.sigma()[0], 2 * w); // the law's row alone would keep most of the opening
  EXPECT_EQ(sys.params().gap_term(sys.contacts()[0], sys.params().upsilon()), 0.0); // no push
  const Vector sigma = sys.sigma();
  Vector dx;
  ASSERT_EQ(
      recovery_displacement(sys, serial_exchange(), at_rest(bodies), sys.params().h, dx).outcome,
      Recovery::Outcome::opened);
  // the rows are rigid only during the solve: the law's compliance and Sigma come back exactly
  EXPECT_EQ(sys.contacts()[0].compliance[0], contacts[0].compliance[0]);
  EXPECT_TRUE((sys.sigma().array() == sigma.array()).all());
  // the rows rigid for the displacement (Sigma below 1e-4 w): a step of max_recovery, 3 : 1
  const double open = dx[6] - dx[0];
  EXPECT_NEAR(open, 0.005, 0.005 * 1e-4);
  EXPECT_NEAR(dx[0], -0.75 * open, 1e-15);
  // the history's penetration left shrinks by the opening
  std::vector<std::array<double, kMaxRows>> springs(1);
  springs[0][0] = contacts[0].penetration;
  take_opening(sys, dx, springs);
  EXPECT_NEAR(springs[0][0], 0.2 - open, 1e-12);
}

TEST(Recovery, AKnownElasticPenetrationLeavesTheClosingToTheSpring)
{
  // a split penetration of 0.1 kept from the last step, the overlap now 0.2: the spring holds
  // the 0.1 the contact closed since, and the penetration stays as it was, split
  const std::vector<Body> bodies{sphere(0.0, 1.0), sphere(0.8, 1.0)};
  Contact c = sphere_sphere_contact(bodies, 1, 0);
  c.penetration = 0.1;
  c.split = true;
  const std::vector<Contact> contacts = material(bodies, {c});
  EXPECT_EQ(contacts[0].penetration, 0.1);
  EXPECT_TRUE(contacts[0].split);
  ContactSystem sys(bodies, contacts, 6, params());
  const SpookParams &p = sys.params();
  EXPECT_NEAR(p.gap_term(sys.contacts()[0], p.upsilon()), 4.0 / p.h * p.upsilon() * 0.1, 1e-9);
}

// While another penetration is recovered (the floor at kPenetrationFloor), a shallow elastic
// penetration (6 or 4 steps of max_recovery: above the floor, below kPenetrationStart), found
// now or kept unsplit from the last step, is not split: its row pushes it open at a bounded speed
// and the spring keeps its load's overlap. A split one stays split down to the floor's depth.
TEST(Recovery, AShallowElasticPenetrationIsNotSplitWhileAnotherIsRecovered)
{
  SpookParams p = params();
  p.penetration_floor = kPenetrationFloor;
  const double step = p.h * p.max_recovery, overlap = 6.0 * step;
  const std::vector<Body> bodies{sphere(0.0, 1.0), sphere(1.0 - overlap, 1.0)};
  const ContactModel model = soft_material();
  Contact found = sphere_sphere_contact(bodies, 1, 0); // new: the whole overlap unexplained
  Contact kept = found, split = found;
  kept.penetration = 4.0 * step; // kept from the last step, unsplit
  split.penetration = 4.0 * step;
  split.split = true;
  std::vector<Contact> contacts{found, kept, split};
  for (Contact &c : contacts) c.gap = -overlap;
  apply_contact_model(model, p, 1.0, bodies, contacts);
  EXPECT_GT(contacts[0].penetration, 0.0);
  EXPECT_FALSE(p.split_penetration(contacts[0]));
  EXPECT_EQ(contacts[1].penetration, 4.0 * step);
  EXPECT_FALSE(p.split_penetration(contacts[1]));
  EXPECT_TRUE(p.split_penetration(contacts[2]));
  // a split one shallower than the floor's depth is no longer split
  contacts[2].penetration = 0.5 * kPenetrationFloor * step;
  apply_contact_model(model, p, 1.0, bodies, contacts);
  EXPECT_FALSE(p.split_penetration(contacts[2]));
}
