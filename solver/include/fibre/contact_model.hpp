// The contact model that every front end shares (doc/design.md section 2): per-row compliance,
// the effective radius and the friction, rolling and twisting coefficients of a contact.
#pragma once

#include <vector>

#include "fibre/system.hpp"

namespace fibre {

// How stiff the rows are. auto: eps = factor dt^2 / m_min on every translational row, so that
// Sigma is a fixed small fraction of the lightest body's G M^-1 G^T entry whatever the step.
// fixed: eps_n on the normal row, eps_t on the tangential rows. The rotational rows take
// eps_t / r_eff^2 in both modes.
struct ComplianceParams {
  bool automatic = true;
  double eps_n = 0.0, eps_t = 0.0; // fixed mode
  double factor = 1e-2;            // automatic mode
};

// The model of one simulation: rows per contact, SPOOK damping, compliance and friction.
struct ContactModel {
  int rows = 6;         // 3: translational rows only; 6: with twisting and rolling
  double damping = 2.0; // SPOOK d = tau / h, in steps
  ComplianceParams compliance{};
  FrictionParams friction{}; // of every contact (one material)
};

// r_eff = ra rb / (ra + rb) for a pair, ra against a wall (b == nullptr).
inline double effective_radius(double ra, const double *rb)
{
  return rb ? ra * *rb / (ra + *rb) : ra;
}
double effective_radius(const std::vector<Body> &bodies, const Contact &c);

// Cone radius per unit normal impulse of cone k (0 Coulomb, 1 twisting, 2 rolling).
double cone_coefficient(const FrictionParams &f, double r_eff, int cone);

// Sets the per-row compliance and the friction coefficients of every contact (m_min: the
// lightest body of the simulation, read by automatic compliance only).
void apply_contact_model(const ContactModel &model, double h, double m_min,
                         const std::vector<Body> &bodies, std::vector<Contact> &contacts);

} // namespace fibre
