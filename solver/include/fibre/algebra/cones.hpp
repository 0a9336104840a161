// The feasible set of a contact's impulses (doc/design.md section 2): lambda_n >= 0, the
// Coulomb cone (rows 1, 2), the twisting cone (row 3) and the rolling cone (rows 4, 5), each
// of radius coefficient * lambda_n; the projection onto it, and the complementarity residual
// that says how far impulses are from solving the nonsmooth step.
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "fibre/core/exchange.hpp"
#include "fibre/core/system.hpp"
#include "fibre/model/contact_model.hpp"

namespace fibre {

struct Cone {
  int first, size; // first row within the contact, 1 or 2 rows
};
inline constexpr Cone kCones[3] = {{1, 2}, {3, 1}, {4, 2}};
inline int num_cones(int rows)
{
  return rows == 6 ? 3 : 1;
}

inline Eigen::Vector2d cone_values(const Vector &v, Eigen::Index base, const Cone &cone)
{
  Eigen::Vector2d t(v[base + cone.first], 0.0);
  if (cone.size == 2) t[1] = v[base + cone.first + 1];
  return t;
}

inline void set_cone(Vector &v, Eigen::Index base, const Cone &cone, const Eigen::Vector2d &t)
{
  v[base + cone.first] = t[0];
  if (cone.size == 2) v[base + cone.first + 1] = t[1];
}

// The cones of every contact of a system: coefficient (radius per unit normal impulse) per
// contact and cone, and the projection.
class Cones {
 public:
  explicit Cones(const ContactSystem &sys); // coefficients from each contact's friction
  // lambda_n >= 0 alone: every coefficient zero, no cohesion (the split recovery's problem); joints
  // stay bilateral
  static Cones frictionless(const ContactSystem &sys);
  int rows() const { return rows_; }
  // Whether some contact is cohesive (Contact::pull): its lambda_n may be negative.
  bool cohesive() const { return !pull_.empty(); }
  double pull(int c) const { return pull_.empty() ? 0.0 : pull_[c]; }
  double coeff(int c, int k) const { return coeff_[3 * std::size_t(c) + k]; }
  // lambda_n >= 0 and every cone (radius from the projected normal impulse); l points to
  // contact c's rows. Non-finite values project to 0. A cohesive contact's bound is
  // lambda_n >= -h pull and its radii follow lambda_n + 2 h pull.
  void project(double *l, int c) const
  {
    if (rows_ == 6)
      project_rows<6>(l, c);
    else
      project_rows<3>(l, c);
  }
  // The same for R = rows(), inline: the sweeps' hot path (a call per contact was a fifth of
  // a stiff run's time).
  template <int R> void project_rows(double *l, int c) const;

 private:
  int rows_;
  std::vector<double> coeff_;
  std::vector<double> pull_; // h Contact::pull per contact; empty: no cohesion
};

// Squared norms, one square root only for a cone outside.
template <int R> inline void Cones::project_rows(double *l, int c) const
{
  const double pull = pull_.empty() ? 0.0 : pull_[c];
  l[0] = l[0] > -pull ? l[0] : -pull; // also NaN -> the bound
  if (!std::isfinite(l[0])) l[0] = 0.0;
  const double load = cone_load(l[0], pull);
  const double *coeff = coeff_.data() + 3 * std::size_t(c);
  for (int k = 0; k < num_cones(R); ++k) {
    double *t = l + kCones[k].first;
    const bool pair = kCones[k].size == 2;
    const double radius = coeff[k] * load;
    const double tn2 = t[0] * t[0] + (pair ? t[1] * t[1] : 0.0);
    if (!(radius > 0) || !std::isfinite(tn2)) {
      t[0] = 0.0;
      if (pair) t[1] = 0.0;
    } else if (tn2 > radius * radius) {
      const double shrink = radius / std::sqrt(tn2);
      t[0] *= shrink;
      if (pair) t[1] *= shrink;
    }
  }
}

// Per-row scaling of the projected maps: A_ii for the normal row and the largest A_ii of each
// cone for all its rows. One scale per cone keeps the direction of the cone's step, so a fixed
// point has its friction along the slip (maximal dissipation). A full 6x6 block solve would
// not: it mixes the slip into the normal row, and projected sweeps with it converge to
// impulses whose friction is off the slip.
std::vector<Vec6> row_scales(const ContactSystem &sys);
// The same from the diagonal entries of A (diagonal_entries, per contact).
std::vector<Vec6> row_scales(const std::vector<Vec6> &diagonal, int rows);

// How far feasible impulses are from solving the contact problem A lambda = b with the cones:
// the step of the projected Jacobi map, || lambda - P(lambda + rho / scale) ||_2 / ||lambda||_2
// over all processes, with rho = b - A lambda. Zero exactly when lambda solves the step: active
// normal rows solved, released contacts not pressing, sticking cones without slip, sliding
// cones on their boundary against the slip. `sys` must have every row active.
double complementarity(const ContactSystem &sys, const Exchange &ex, const Cones &cones,
                       const Vector &b, const Vector &lambda, const std::vector<Vec6> &scale);

} // namespace fibre
