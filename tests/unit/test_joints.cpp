// Lock joints (joint_contact): a clump of spheres held rigid by bilateral rows, against the
// analytic motion of the rigid body they make.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fibre/algebra/assembly.hpp"
#include "fibre/algebra/cones.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/solvers/pgs.hpp"

using namespace fibre;

namespace {

// Two spheres of radius 0.5 and mass 1, the hub (body 0) at the origin, the member (body 1) at
// (1, 0, 0), held by one joint; contact 0 is the joint.
struct Dumbbell {
  std::vector<Body> bodies = std::vector<Body>(2);
  SpookParams params;
  Dumbbell()
  {
    for (Body &b : bodies) b.radius = 0.5;
    bodies[1].x = Vec3(1.0, 0.0, 0.0);
    params.h = 1e-3;
  }
  Vector step(const Vec3 &error = Vec3::Zero()) const
  {
    std::vector<Contact> contacts{joint_contact(bodies, 1, 0, bodies[1].x - bodies[0].x, error)};
    contacts[0].compliance.fill(1e-14);
    const ContactSystem sys(bodies, contacts, 6, params);
    Vector lambda = Vector::Zero(sys.contact_dofs());
    pgs(sys, serial_exchange(), Cones(sys), spook_rhs(sys), row_scales(sys), lambda,
        PgsControl{10000, 1e-15, 10000});
    return velocities_after(sys, serial_exchange(), lambda);
  }
};

} // namespace

// A force on the member and a torque on the hub: the pair moves as one rigid body of mass 2,
// its centre at (0.5, 0, 0), its inertia 2 (2/5) r^2 = 0.2 about x and 0.2 + 2 (0.5)^2 = 0.7
// about y and z.
TEST(Joints, ADumbbellMovesAsTheRigidBodyItMakes)
{
  Dumbbell d;
  const Vec3 force(0.4, 0.0, 2.0), torque(0.3, 0.0, 0.0);
  d.bodies[1].force = force;
  d.bodies[0].torque = torque;
  const Vector v = d.step();
  const double h = d.params.h;
  const Vec3 lever(0.5, 0.0, 0.0); // the member from the centre of mass
  const Vec3 moment = torque + lever.cross(force);
  const Vec3 omega = h * Vec3(moment[0] / 0.2, moment[1] / 0.7, moment[2] / 0.7);
  const Vec3 v_cm = h * force / 2.0;
  const Vec3 v_member = v_cm + omega.cross(lever), v_hub = v_cm + omega.cross(-lever);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(v[k], v_hub[k], 1e-9) << k;
    EXPECT_NEAR(v[6 + k], v_member[k], 1e-9) << k;
    EXPECT_NEAR(v[3 + k], omega[k], 1e-9) << k;
    EXPECT_NEAR(v[9 + k], omega[k], 1e-9) << k;
  }
}

// A member off where the hub holds it moves back at SPOOK's stabilization speed, (4 / h)
// Upsilon of the error, in every direction, and the hub turns with it.
TEST(Joints, AJointRemovesItsErrorAtSpookSpeed)
{
  Dumbbell d;
  const Vec3 error(0.01, 0.02, -0.015);
  const Vector v = d.step(error);
  const SpookParams &p = d.params;
  const Vec3 hub_at_member =
      v.segment<3>(0) + Vec3(v.segment<3>(3)).cross(d.bodies[1].x - d.bodies[0].x);
  const Vec3 closing = Vec3(v.segment<3>(6)) - hub_at_member;
  const Vec3 expected = -4.0 / p.h * p.upsilon() * error;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(closing[k], expected[k], 1e-9 * expected.norm()) << k;
    EXPECT_NEAR(v[3 + k], v[9 + k], 1e-9 * expected.norm()) << k;
  }
  // momentum: no external force, so the two velocities balance
  EXPECT_NEAR((Vec3(v.segment<3>(0)) + Vec3(v.segment<3>(6))).norm(), 0.0, 1e-9);
}

// A joint's rows are bilateral in the step's cones and in the split recovery's (which moves a
// clump as one body), where an ordinary contact's friction and cohesion are dropped.
TEST(Joints, TheConesLeaveAJointUnbounded)
{
  Dumbbell d;
  d.bodies.push_back(Body{});
  d.bodies[2].x = Vec3(0.0, 0.99, 0.0);
  d.bodies[2].radius = 0.5;
  std::vector<Contact> contacts{joint_contact(d.bodies, 1, 0, Vec3(1, 0, 0), Vec3::Zero()),
                                sphere_sphere_contact(d.bodies, 2, 0)};
  contacts[1].pull = 3.0;
  for (Contact &c : contacts) c.compliance.fill(1e-10);
  const ContactSystem sys(d.bodies, contacts, 6, d.params);
  EXPECT_TRUE(sys.contacts()[0].is_joint());
  EXPECT_FALSE(sys.contacts()[1].is_joint());
  for (const Cones &cones : {Cones(sys), Cones::frictionless(sys)}) {
    double l[6] = {-5.0, 7.0, -3.0, 2.0, 4.0, -6.0};
    cones.project(l, 0);
    const double kept[6] = {-5.0, 7.0, -3.0, 2.0, 4.0, -6.0};
    for (int r = 0; r < 6; ++r) EXPECT_EQ(l[r], kept[r]) << r;
  }
  double m[6] = {-5.0, 7.0, -3.0, 2.0, 4.0, -6.0};
  Cones::frictionless(sys).project(m, 1);
  EXPECT_EQ(m[0], 0.0);
  for (int r = 1; r < 6; ++r) EXPECT_EQ(m[r], 0.0) << r;
}

// A clump's joints are one block of the sweeps (joint_blocks.hpp), solved exactly: on a system
// of one clump alone, one sweep gives the impulses of the dense solve of
// (G M^-1 G^T + Sigma) lambda = b, whatever the members' masses, offsets and errors.
TEST(Joints, OneSweepSolvesAClumpsJointsExactly)
{
  std::vector<Body> bodies(5);
  const Vec3 at[5] = {
      {0.3, -0.2, 0.1}, {1.3, 0.0, 0.1}, {0.2, 0.9, 0.0}, {-0.7, 0.1, 0.4}, {0.5, -0.6, 1.1}};
  for (int i = 0; i < 5; ++i) {
    bodies[i].x = at[i];
    bodies[i].radius = 0.4 + 0.05 * i;
    bodies[i].mass = 0.7 + 0.3 * i;
    bodies[i].force = Vec3(0.1 * i, -1.0, 0.2);
    bodies[i].torque = Vec3(0.0, 0.05 * i, -0.03);
  }
  SpookParams params;
  params.h = 1e-2;
  std::vector<Contact> contacts;
  for (int m = 1; m < 5; ++m) {
    const Vec3 error(0.01 * m, -0.004, 0.002 * m);
    contacts.push_back(joint_contact(bodies, m, 0, at[m] - at[0], error));
    contacts.back().compliance.fill(1e-8);
  }
  const ContactSystem sys(bodies, contacts, 6, params);
  const Vector b = spook_rhs(sys);
  const Eigen::MatrixXd A(assemble_A(sys));
  const Vector exact = A.ldlt().solve(b);
  Vector lambda = Vector::Zero(sys.contact_dofs());
  const PgsResult r =
      pgs(sys, serial_exchange(), Cones(sys), b, row_scales(sys), lambda, PgsControl{1, 0.0, 1000});
  EXPECT_EQ(r.sweeps, 1);
  EXPECT_LT((lambda - exact).norm(), 1e-10 * exact.norm()) << (lambda - exact).norm();
  // each joint solved alone against b (the first joint of a one-at-a-time sweep) is far off
  Vector one_at_a_time = Vector::Zero(sys.contact_dofs());
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Eigen::MatrixXd Acc = A.block(6 * c, 6 * c, 6, 6);
    one_at_a_time.segment<6>(6 * c) = Acc.ldlt().solve(Vector(b.segment<6>(6 * c)));
  }
  EXPECT_GT((one_at_a_time - exact).norm(), 1e-2 * exact.norm());
}
