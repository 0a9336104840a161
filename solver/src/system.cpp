#include "fibre/system.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "fibre/exchange.hpp"
#include "fibre/kernels.hpp"

namespace fibre {

void tangent_frame(const Vec3 &n, Vec3 &t1, Vec3 &t2)
{
  // Project the coordinate axis least aligned with n: well conditioned and deterministic.
  const Vec3 e = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  t1 = (e - e.dot(n) * n).normalized();
  t2 = n.cross(t1);
}

Contact sphere_sphere_contact(const std::vector<Body> &bodies, int a, int b)
{
  const Body &A = bodies.at(a), &B = bodies.at(b);
  const Vec3 d = A.x - B.x;
  const double dist = d.norm();
  Contact c;
  c.a = a;
  c.b = b;
  c.normal = dist > 0 ? Vec3(d / dist) : Vec3::UnitZ();
  tangent_frame(c.normal, c.t1, c.t2);
  c.gap = dist - A.radius - B.radius;
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
  mass_ = inv_mass_.cwiseInverse();
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
    for (int r = 0; r < rows_; ++r) {
      const Eigen::Index row = Eigen::Index(rows_) * c + r;
      sigma_[row] = row_active(row) ? params_.sigma(k.compliance[r]) : 1.0;
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

void ContactSystem::set_row_mask(const std::vector<unsigned char> &active)
{
  if (static_cast<Eigen::Index>(active.size()) != contact_dofs())
    throw std::invalid_argument("row mask size differs from the number of contact rows");
  mask_ = active;
  compute_derived();
  for (Eigen::Index row = 0; row < contact_dofs(); ++row)
    if (!row_active(row)) rhs_[row] = 0.0;
}

void ContactSystem::permute(const std::vector<int> &new_body, const std::vector<int> &new_contact)
{
  const int nb = num_bodies(), nc = num_contacts();
  if (static_cast<int>(new_body.size()) != nb || static_cast<int>(new_contact.size()) != nc)
    throw std::invalid_argument("permutation sizes differ from the system");
  std::vector<Body> bodies(nb);
  std::vector<char> seen(nb, 0);
  for (int i = 0; i < nb; ++i) {
    const int j = new_body[i];
    if (j < 0 || j >= nb || seen[j]) throw std::invalid_argument("body map is not a permutation");
    if ((i < num_owned_) != (j < num_owned_))
      throw std::invalid_argument("body permutation mixes owned and ghost bodies");
    seen[j] = 1;
    bodies[j] = bodies_[i];
  }
  std::vector<Contact> contacts(nc);
  std::vector<unsigned char> mask(mask_.empty() ? 0 : mask_.size());
  Vector rhs(contact_dofs());
  std::vector<char> cseen(nc, 0);
  for (int c = 0; c < nc; ++c) {
    const int d = new_contact[c];
    if (d < 0 || d >= nc || cseen[d])
      throw std::invalid_argument("contact map is not a permutation");
    cseen[d] = 1;
    Contact k = contacts_[c];
    k.a = new_body[k.a];
    if (!k.is_wall()) k.b = new_body[k.b];
    contacts[d] = k;
    rhs.segment(Eigen::Index(rows_) * d, rows_) = rhs_.segment(Eigen::Index(rows_) * c, rows_);
    for (int r = 0; r < rows_ && !mask.empty(); ++r)
      mask[std::size_t(rows_) * d + r] = mask_[std::size_t(rows_) * c + r];
  }
  bodies_ = std::move(bodies);
  contacts_ = std::move(contacts);
  mask_ = std::move(mask);
  rhs_ = std::move(rhs);
  compute_derived();
}

Vector body_velocities(const ContactSystem &sys)
{
  Vector v(sys.body_dofs());
  for (int i = 0; i < sys.num_bodies(); ++i) {
    v.segment<3>(6 * i) = sys.bodies()[i].v;
    v.segment<3>(6 * i + 3) = sys.bodies()[i].omega;
  }
  return v;
}

Vector external_velocity_change(const ContactSystem &sys)
{
  Vector dv(sys.body_dofs());
  const double h = sys.params().h;
  for (int i = 0; i < sys.num_bodies(); ++i) {
    dv.segment<3>(6 * i) = h * sys.bodies()[i].force;
    dv.segment<3>(6 * i + 3) = h * sys.bodies()[i].torque;
  }
  return dv.cwiseProduct(sys.inv_mass());
}

Vector spook_rhs(const ContactSystem &sys, const Vector *extra_dv)
{
  const SpookParams &p = sys.params();
  const double ups = p.upsilon();
  Vector w = (1.0 - ups) * body_velocities(sys) + external_velocity_change(sys);
  if (extra_dv) w += *extra_dv;
  Vector b;
  g_apply(sys, w, b);
  b = -b;
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Eigen::Index row = Eigen::Index(sys.rows()) * c;  // normal row
    if (sys.row_active(row)) b[row] -= 4.0 / p.h * ups * sys.contacts()[c].gap;
  }
  return b;
}

Vector impulse_velocity_change(const ContactSystem &sys, const Vector &lambda)
{
  Vector dv;
  gt_apply(sys, lambda, dv);
  return dv.cwiseProduct(sys.inv_mass());
}

std::vector<long> global_body_index(const Exchange &ex, int num_owned, int num_bodies,
                                    long &total)
{
  const long offset = ex.exclusive_prefix_sum(num_owned);
  total = static_cast<long>(ex.sum(static_cast<double>(num_owned)));
  // Carry the ids through a per-body vector (doubles hold integers below 2^53 exactly).
  Vector ids = Vector::Zero(Eigen::Index(kBodyDofs) * num_bodies);
  for (int i = 0; i < num_owned; ++i) ids[6 * i] = static_cast<double>(offset + i);
  ex.forward(ids);
  std::vector<long> index(num_bodies);
  for (int i = 0; i < num_bodies; ++i) index[i] = static_cast<long>(ids[6 * i]);
  return index;
}

const Exchange &serial_exchange()
{
  static const SerialExchange ex;
  return ex;
}

}  // namespace fibre
