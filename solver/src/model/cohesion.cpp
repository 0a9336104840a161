#include "fibre/model/cohesion.hpp"

#include <algorithm>
#include <cmath>

namespace fibre {

namespace {

constexpr double kPi = 3.14159265358979323846;
// cohesive_restitution's integration: steps per Hertz collision time, and how many collision
// times an impact may last before it counts as held
constexpr int kImpactSteps = 200;
constexpr int kImpactCollisions = 20;

// The root of an increasing convex g on [lo, inf) with g(lo) < 0: doubling to a point right
// of the root, then Newton, which approaches it monotonically from the right.
template <class G, class D> double right_root(G g, D dg, double lo)
{
  double x = lo > 0 ? 2.0 * lo : 1.0;
  for (int k = 0; k < 200 && g(x) < 0; ++k) x *= 2.0;
  for (int k = 0; k < 100; ++k) {
    const double slope = dg(x);
    if (!(slope > 0)) break;
    const double step = g(x) / slope;
    x = std::max(x - step, lo);
    if (!(std::abs(step) > 1e-15 * x)) break;
  }
  return x;
}

// JKR in LAMMPS's form: E = E_eff = 3/4 k_n, the contact radius a >= a_b (a_b the pull-off
// point, where F = -3 pi gamma r and the contact breaks).
struct Jkr {
  double E, gamma, r;
  double a_break() const { return std::cbrt(9.0 * kPi * gamma * r * r / (4.0 * E)); }
  double overlap(double a) const { return a * a / r - 2.0 * std::sqrt(kPi * gamma * a / E); }
  double overlap_slope(double a) const { return 2.0 * a / r - std::sqrt(kPi * gamma / (E * a)); }
  double force(double a) const
  {
    return 4.0 * E * a * a * a / (3.0 * r) - 4.0 * std::sqrt(kPi * gamma * E * a * a * a);
  }
  double radius_at_overlap(double d) const
  {
    const double ab = a_break();
    if (!(d > overlap(ab))) return ab;
    return right_root([&](double a) { return overlap(a) - d; },
                      [&](double a) { return overlap_slope(a); }, ab);
  }
  // Newton from a nearby radius (an impact's last), on [a_b, inf)
  double radius_near(double d, double a0) const
  {
    const double ab = a_break();
    if (!(d > overlap(ab))) return ab;
    double a = std::max(a0, ab);
    for (int k = 0; k < 50; ++k) {
      const double step = (overlap(a) - d) / overlap_slope(a);
      a = std::max(a - step, ab);
      if (!(std::abs(step) > 1e-14 * a)) break;
    }
    return a;
  }
  double radius_at_force(double f) const
  {
    const double ab = a_break();
    if (!(f > force(ab))) return ab;
    return right_root(
        [&](double a) { return force(a) - f; },
        [&](double a) { return 4.0 * E * a * a / r - 6.0 * std::sqrt(kPi * gamma * E * a); }, ab);
  }
};

bool cohesive(const PairCoefficients &p, double r_eff)
{
  return p.cohesion != CohesionLaw::none && p.cohesion_energy > 0 && p.k_n > 0 && r_eff > 0 &&
         (p.normal == NormalLaw::hertz || p.normal == NormalLaw::hertz_material);
}

Jkr jkr_of(const PairCoefficients &p, double r_eff)
{
  return {0.75 * p.k_n, p.cohesion_energy, r_eff};
}

double hertz(const PairCoefficients &p, double r_eff, double d)
{
  return d > 0 ? p.k_n * std::sqrt(r_eff * d) * d : 0.0;
}

// sjkr: F = K d^1.5 - c d; its smallest force at d_m = (2c / 3K)^2.
double sjkr_c(const PairCoefficients &p, double r_eff)
{
  return 2.0 * kPi * r_eff * p.cohesion_energy;
}

} // namespace

double pull_off_force(const PairCoefficients &p, double r_eff)
{
  if (!cohesive(p, r_eff)) return 0.0;
  switch (p.cohesion) {
  case CohesionLaw::jkr:
    return 3.0 * kPi * p.cohesion_energy * r_eff;
  case CohesionLaw::dmt:
    return 4.0 * kPi * p.cohesion_energy * r_eff;
  case CohesionLaw::sjkr: {
    const double c = sjkr_c(p, r_eff), K = p.k_n * std::sqrt(r_eff);
    return 4.0 * c * c * c / (27.0 * K * K);
  }
  case CohesionLaw::none:
    break;
  }
  return 0.0;
}

double cohesive_reach(const PairCoefficients &p, double r_eff)
{
  if (!cohesive(p, r_eff) || p.cohesion != CohesionLaw::jkr) return 0.0;
  const Jkr law = jkr_of(p, r_eff);
  return std::max(-law.overlap(law.a_break()), 0.0);
}

double cohesive_force(const PairCoefficients &p, double r_eff, double overlap)
{
  if (!cohesive(p, r_eff)) return hertz(p, r_eff, overlap);
  switch (p.cohesion) {
  case CohesionLaw::jkr: {
    const Jkr law = jkr_of(p, r_eff);
    return law.force(law.radius_at_overlap(overlap));
  }
  case CohesionLaw::dmt:
    return hertz(p, r_eff, overlap) - pull_off_force(p, r_eff);
  case CohesionLaw::sjkr:
    return overlap > 0 ? hertz(p, r_eff, overlap) - sjkr_c(p, r_eff) * overlap : 0.0;
  case CohesionLaw::none:
    break;
  }
  return 0.0;
}

double cohesive_overlap(const PairCoefficients &p, double r_eff, double f)
{
  if (!cohesive(p, r_eff)) return law_overlap(p, r_eff, f);
  switch (p.cohesion) {
  case CohesionLaw::jkr: {
    const Jkr law = jkr_of(p, r_eff);
    return law.overlap(law.radius_at_force(f));
  }
  case CohesionLaw::dmt:
    return law_overlap(p, r_eff, f + pull_off_force(p, r_eff));
  case CohesionLaw::sjkr: {
    // u = sqrt(d): K u^3 - c u^2 = f on u >= u_m = 2c / 3K
    const double c = sjkr_c(p, r_eff), K = p.k_n * std::sqrt(r_eff), um = 2.0 * c / (3.0 * K);
    if (!(f > K * um * um * um - c * um * um)) return um * um;
    const double u = right_root([&](double x) { return K * x * x * x - c * x * x - f; },
                                [&](double x) { return 3.0 * K * x * x - 2.0 * c * x; }, um);
    return u * u;
  }
  case CohesionLaw::none:
    break;
  }
  return 0.0;
}

double cohesive_restitution(const PairCoefficients &p, double m_eff, double r_eff, double v)
{
  if (!cohesive(p, r_eff) || !(m_eff > 0) || !(v > 0)) return -1.0;
  const double t_c = collision_time(p, r_eff, m_eff, v);
  if (!(t_c > 0)) return -1.0;
  const Jkr jkr = jkr_of(p, r_eff);
  const bool is_jkr = p.cohesion == CohesionLaw::jkr;
  const double reach = cohesive_reach(p, r_eff), dt = t_c / kImpactSteps;
  double d = 0.0, u = v, a = is_jkr ? jkr.a_break() : 0.0;
  bool rebounds = false;
  for (int step = 0; step < kImpactCollisions * kImpactSteps; ++step) {
    double force;
    if (is_jkr) {
      a = jkr.radius_near(d, a);
      force = jkr.force(a);
    } else {
      a = d > 0 ? std::sqrt(r_eff * d) : 0.0;
      force = cohesive_force(p, r_eff, d);
    }
    const double damper = std::max(normal_damper(p, m_eff, a, p.k_n * a), 0.0);
    // semi-implicit Euler, the damper implicit
    u = (u - dt * force / m_eff) / (1.0 + dt * damper / m_eff);
    d += dt * u;
    if (u < 0 && d < -reach) return -u / v;
    if (rebounds && u > 0) return 0.0; // closing again within its reach: held
    rebounds = rebounds || u < 0;
  }
  return 0.0; // held: the contact's adhesion took the impact's energy
}

} // namespace fibre
