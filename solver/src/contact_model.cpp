#include "fibre/contact_model.hpp"

#include <algorithm>

namespace fibre {

double effective_radius(const std::vector<Body> &bodies, const Contact &c)
{
  const double ra = bodies[c.a].radius;
  if (c.is_wall()) return ra;
  return effective_radius(ra, &bodies[c.b].radius);
}

double cone_coefficient(const FrictionParams &f, double r_eff, int cone)
{
  if (cone == 0) return f.mu;
  return (cone == 1 ? f.mu_twist : f.mu_roll) * r_eff;
}

void apply_contact_model(const ContactModel &model, double h, double m_min,
                         const std::vector<Body> &bodies, std::vector<Contact> &contacts)
{
  const ComplianceParams &p = model.compliance;
  double eps_n = p.eps_n, eps_t = p.eps_t;
  if (p.automatic) eps_n = eps_t = p.factor * h * h / m_min;
  for (Contact &c : contacts) {
    const double reff = effective_radius(bodies, c);
    c.compliance[0] = eps_n;
    c.compliance[1] = c.compliance[2] = eps_t;
    for (int r = 3; r < kMaxRows; ++r) c.compliance[r] = eps_t / (reff * reff);
    c.friction = model.friction;
    c.restitution = model.restitution;
    if (!model.per_type()) continue;
    const int ta = bodies[c.a].type;
    const int tb = !c.is_wall() ? bodies[c.b].type : c.wall_type > 0 ? c.wall_type : ta;
    if (ta < 1 || tb < 1 || ta > model.materials.ntypes() || tb > model.materials.ntypes())
      continue; // no type: the model's values
    const PairCoefficients &p = model.materials.at(ta, tb);
    const FrictionParams f = contact_friction(p, reff, std::max(-c.gap, 0.0));
    const TypedCoefficients &typed = model.typed;
    if (!typed.mu) c.friction.mu = f.mu;
    if (!typed.mu_roll) c.friction.mu_roll = f.mu_roll;
    if (!typed.mu_twist) c.friction.mu_twist = f.mu_twist;
    if (!typed.restitution && p.restitution >= 0) c.restitution = p.restitution;
  }
}

double external_speed_per_step(const std::vector<Body> &bodies, int num_owned, double h)
{
  double v = 0.0;
  for (int i = 0; i < num_owned; ++i) v = std::max(v, h * bodies[i].force.norm() / bodies[i].mass);
  return v;
}

} // namespace fibre
