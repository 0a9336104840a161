#include "fibre/core/system.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace fibre {

void tangent_frame(const Vec3 &n, Vec3 &t1, Vec3 &t2)
{
  // Project the coordinate axis least aligned with n: well conditioned and deterministic.
  const Vec3 e = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  t1 = (e - e.dot(n) * n).normalized();
  t2 = n.cross(t1);
}

void sphere_sphere_gap(const Body &A, const Body &B, Vec3 &normal, double &gap)
{
  const Vec3 d = A.x - B.x;
  const double dist = d.norm();
  normal = dist > 0 ? Vec3(d / dist) : Vec3::UnitZ();
  gap = dist - A.radius - B.radius;
}

Contact sphere_sphere_contact(const std::vector<Body> &bodies, int a, int b)
{
  Vec3 normal;
  double gap = 0.0;
  sphere_sphere_gap(bodies.at(a), bodies.at(b), normal, gap);
  return sphere_sphere_contact(bodies, a, b, normal, gap);
}

Contact sphere_sphere_contact(const std::vector<Body> &bodies, int a, int b, const Vec3 &normal,
                              double gap)
{
  const Body &B = bodies.at(b);
  Contact c;
  c.a = a;
  c.b = b;
  c.normal = normal;
  c.gap = gap;
  tangent_frame(c.normal, c.t1, c.t2);
  c.point = B.x + c.normal * (B.radius + 0.5 * c.gap);
  return c;
}

Contact sphere_wall_contact(const std::vector<Body> &bodies, int a, const Vec3 &normal,
                            double distance)
{
  const Body &A = bodies.at(a);
  Contact c;
  c.a = a;
  c.b = -1;
  c.normal = normal.normalized();
  tangent_frame(c.normal, c.t1, c.t2);
  c.gap = distance - A.radius;
  c.point = A.x - c.normal * (A.radius + 0.5 * c.gap);
  return c;
}

Contact joint_contact(const std::vector<Body> &bodies, int a, int b, const Vec3 &axis,
                      const Vec3 &error)
{
  Contact c;
  c.a = a;
  c.b = b;
  const double length = axis.norm();
  c.normal = length > 0 ? Vec3(axis / length) : Vec3::UnitZ();
  tangent_frame(c.normal, c.t1, c.t2);
  c.point = bodies.at(a).x;
  c.gap = c.normal.dot(error);
  c.spring[1] = c.t1.dot(error);
  c.spring[2] = c.t2.dot(error);
  c.pull = std::numeric_limits<double>::infinity();
  c.friction = {1.0, 1.0, 1.0};
  return c;
}

double effective_radius(const std::vector<Body> &bodies, const Contact &c)
{
  const double ra = bodies[c.a].radius;
  // a wall's curvature radius R: > 0 convex, < 0 concave (LAMMPS's region contacts), 0 flat
  const double R = c.wall_radius;
  if (c.is_wall()) return R > 0 || R < -ra ? effective_radius(ra, &R) : ra;
  return effective_radius(ra, &bodies[c.b].radius);
}

std::array<double, kMaxRows> wall_rows(const Contact &c)
{
  std::array<double, kMaxRows> w{};
  if (!c.wall_moves()) return w;
  const Vec3 *frame[3] = {&c.normal, &c.t1, &c.t2};
  for (int r = 0; r < 3; ++r) w[r] = frame[r]->dot(c.wall_v);
  // rotational rows in the kernels' order: twist about n, then rolling about t1 and t2
  for (int r = 0; r < 3; ++r) w[3 + r] = frame[r]->dot(c.wall_omega);
  return w;
}

ContactSystem::ContactSystem(std::vector<Body> bodies, std::vector<Contact> contacts, int rows,
                             const SpookParams &params, int num_owned)
    : rows_(rows), params_(params), bodies_(std::move(bodies)), contacts_(std::move(contacts))
{
  if (rows_ != 3 && rows_ != 6) throw std::invalid_argument("rows must be 3 or 6");
  if (!(params_.h > 0)) throw std::invalid_argument("time step h must be positive");
  if (!(params_.damping >= 0)) throw std::invalid_argument("damping must be non-negative");
  num_owned_ = num_owned < 0 ? num_bodies() : num_owned;
  if (num_owned_ > num_bodies()) throw std::invalid_argument("more owned bodies than bodies");
  for (int c = 0; c < num_contacts(); ++c) {
    const Contact &k = contacts_[c];
    if (k.a < 0 || k.a >= num_bodies() || k.b >= num_bodies() || k.a == k.b)
      throw std::invalid_argument("contact " + std::to_string(c) + " has invalid bodies");
    for (int r = 0; r < rows_; ++r)
      if (!(k.compliance[r] > 0))
        throw std::invalid_argument("contact " + std::to_string(c) +
                                    " needs positive compliance on every row");
  }
  for (const Body &b : bodies_)
    if (!(b.mass > 0) || !(b.radius > 0))
      throw std::invalid_argument("bodies need positive mass and radius");
  rhs_ = Vector::Zero(contact_dofs());
  compute_derived();
}

void ContactSystem::compute_derived()
{
  const int nb = num_bodies(), nc = num_contacts();
  inv_mass_.resize(Eigen::Index(kBodyDofs) * nb);
  for (int i = 0; i < nb; ++i) {
    const Body &b = bodies_[i];
    const double inertia = 0.4 * b.mass * b.radius * b.radius;
    inv_mass_.segment<3>(6 * i).setConstant(1.0 / b.mass);
    inv_mass_.segment<3>(6 * i + 3).setConstant(1.0 / inertia);
  }
  external_dv_.resize(Eigen::Index(kBodyDofs) * nb);
  for (int i = 0; i < nb; ++i) {
    external_dv_.segment<3>(6 * i) = params_.h * bodies_[i].force;
    external_dv_.segment<3>(6 * i + 3) = params_.h * bodies_[i].torque;
  }
  external_dv_.array() *= inv_mass_.array();
  kin_.resize(nc);
  sigma_.resize(contact_dofs());
  pairs_.resize(std::size_t(2) * nc);
  for (int c = 0; c < nc; ++c) {
    const Contact &k = contacts_[c];
    pairs_[2 * std::size_t(c)] = k.a;
    pairs_[2 * std::size_t(c) + 1] = k.is_wall() ? -1 : k.b;
    ContactKinematics &q = kin_[c];
    q.frame.row(0) = k.normal.transpose();
    q.frame.row(1) = k.t1.transpose();
    q.frame.row(2) = k.t2.transpose();
    q.ra = k.point - bodies_[k.a].x;
    q.rb = k.is_wall() ? Vec3::Zero() : Vec3(k.point - bodies_[k.b].x);
  }
  static std::atomic<std::uint64_t> next_id{0};
  kinematics_id_ = ++next_id;
  sides_.resize(nc);
  r_eff_.resize(nc);
  walls_move_ = false;
  for (int c = 0; c < nc; ++c) {
    const Contact &k = contacts_[c];
    const ContactKinematics &q = kin_[c];
    walls_move_ = walls_move_ || k.wall_moves();
    for (int side = 0; side < 2; ++side) {
      Vec6 &d = sides_[c][side];
      d.setZero();
      if (side == 1 && k.is_wall()) continue;
      const double *m = inv_mass_.data() + 6 * std::size_t(side == 0 ? k.a : k.b);
      const Vec3 &lever = side == 0 ? q.ra : q.rb;
      for (int i = 0; i < 3; ++i) {
        const Vec3 n = q.frame.row(i).transpose(), t = lever.cross(n);
        d[i] = n[0] * n[0] * m[0] + n[1] * n[1] * m[1] + n[2] * n[2] * m[2] + t[0] * t[0] * m[3] +
               t[1] * t[1] * m[4] + t[2] * t[2] * m[5];
        d[i + 3] = n[0] * n[0] * m[3] + n[1] * n[1] * m[4] + n[2] * n[2] * m[5];
      }
    }
    r_eff_[c] = fibre::effective_radius(bodies_, k);
  }
  compute_rows();
}

void ContactSystem::compute_rows()
{
  for (int c = 0; c < num_contacts(); ++c) {
    const Contact &k = contacts_[c];
    for (int r = 0; r < rows_; ++r) {
      const Eigen::Index row = Eigen::Index(rows_) * c + r;
      sigma_[row] =
          row_active(row) ? params_.sigma(k.compliance[r], params_.damping_of(k, r)) : 1.0;
    }
  }
  inv_sigma_ = sigma_.cwiseInverse();
  if (mask_.empty()) {
    row_weight_.resize(0);
  } else {
    row_weight_.resize(contact_dofs());
    for (Eigen::Index row = 0; row < contact_dofs(); ++row)
      row_weight_[row] = mask_[row] ? 1.0 : 0.0;
  }
}

void ContactSystem::set_friction(const FrictionParams &f)
{
  for (Contact &c : contacts_)
    if (!c.is_joint()) c.friction = f; // a joint's cones stay unbounded
}

void ContactSystem::set_row_mask(const std::vector<unsigned char> &active)
{
  if (static_cast<Eigen::Index>(active.size()) != contact_dofs())
    throw std::invalid_argument("row mask size differs from the number of contact rows");
  const bool all_active =
      std::all_of(active.begin(), active.end(), [](unsigned char m) { return m != 0; });
  if (all_active && mask_.empty()) return; // nothing changes
  if (all_active)
    mask_.clear();
  else
    mask_ = active;
  compute_rows();
  for (Eigen::Index row = 0; row < contact_dofs(); ++row)
    if (!row_active(row)) rhs_[row] = 0.0;
}

} // namespace fibre
