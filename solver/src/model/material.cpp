#include "fibre/model/material.hpp"

#include <algorithm>
#include <array>
#include <vector>
#include <cmath>

#include "fibre/core/text.hpp"

namespace fibre {

MaterialTable::MaterialTable(int ntypes)
    : ntypes_(ntypes), pairs_(std::size_t(ntypes) * std::size_t(ntypes))
{
}

PairCoefficients &MaterialTable::at(int i, int j)
{
  if (i > j) std::swap(i, j);
  return pairs_[std::size_t(i - 1) * std::size_t(ntypes_) + std::size_t(j - 1)];
}

const PairCoefficients &MaterialTable::at(int i, int j) const
{
  if (i > j) std::swap(i, j);
  return pairs_[std::size_t(i - 1) * std::size_t(ntypes_) + std::size_t(j - 1)];
}

int MaterialTable::add_type(const PairCoefficients &p)
{
  MaterialTable grown(ntypes_ + 1);
  for (int i = 1; i <= ntypes_; ++i)
    for (int j = i; j <= ntypes_; ++j) grown.at(i, j) = at(i, j);
  for (int i = 1; i <= ntypes_ + 1; ++i) grown.at(i, ntypes_ + 1) = p;
  *this = std::move(grown);
  return ntypes_;
}

std::string MaterialTable::mix()
{
  const auto geom = [](double a, double b) { return std::sqrt(a * b); };
  for (int i = 1; i <= ntypes_; ++i)
    for (int j = i + 1; j <= ntypes_; ++j) {
      PairCoefficients &p = at(i, j);
      if (p.set) continue;
      const PairCoefficients &a = at(i, i), &b = at(j, j);
      const std::string pair = std::to_string(i) + " " + std::to_string(j);
      if (!a.set || !b.set)
        return "types " + pair + ": no coefficients, and type " + std::to_string(a.set ? j : i) +
               " has none with itself to mix from";
      if (a.twist != b.twist) return "types " + pair + ": different twisting laws cannot mix";
      p.set = true;
      p.mu = geom(a.mu, b.mu);
      p.mu_roll = geom(a.mu_roll, b.mu_roll);
      p.twist = a.twist;
      p.twist_coeff = geom(a.twist_coeff, b.twist_coeff);
      // hertz/material stores 4/3 E_eff and 8 G_eff of the like pair; LAMMPS's E/nu mixing of
      // unlike materials is their harmonic mean. Other stiffnesses mix geometrically.
      const bool material = a.normal == NormalLaw::hertz_material;
      const auto stiff = [&](double x, double y) {
        return material ? (x > 0 && y > 0 ? 2.0 / (1.0 / x + 1.0 / y) : 0.0) : geom(x, y);
      };
      if (a.normal != b.normal || a.tangential != b.tangential || a.cohesion != b.cohesion)
        return "types " + pair + ": different normal, cohesion or tangential laws cannot mix";
      p.cohesion = a.cohesion;
      p.cohesion_energy = geom(a.cohesion_energy, b.cohesion_energy);
      p.normal = a.normal;
      p.tangential = a.tangential;
      p.cone_on_spring = a.cone_on_spring;
      p.k_n = stiff(a.k_n, b.k_n);
      p.k_t = stiff(a.k_t, b.k_t);
      p.k_roll = geom(a.k_roll, b.k_roll);
      p.k_twist = geom(a.k_twist, b.k_twist);
      p.gamma_roll = geom(a.gamma_roll, b.gamma_roll);
      p.gamma_twist = geom(a.gamma_twist, b.gamma_twist);
      p.tangential_damping = a.tangential_damping >= 0 && b.tangential_damping >= 0
                                 ? geom(a.tangential_damping, b.tangential_damping)
                                 : -1.0;
      if (a.viscous != b.viscous)
        return "types " + pair + ": different normal damping models cannot mix";
      p.viscous = a.viscous;
      p.viscous_coeff = geom(a.viscous_coeff, b.viscous_coeff);
      // LAMMPS mixes Tsuji's alpha; the rebound then follows from the mixed law
      p.limit_damping = a.limit_damping || b.limit_damping;
      if (a.damping_alpha >= 0 && b.damping_alpha >= 0) {
        p.damping_alpha = geom(a.damping_alpha, b.damping_alpha);
        p.restitution = rebound_restitution(p.normal, p.damping_alpha, p.limit_damping);
      } else {
        p.restitution = a.restitution >= 0 && b.restitution >= 0
                            ? restitution_from_tsuji(
                                  geom(tsuji_damping(a.restitution), tsuji_damping(b.restitution)))
                            : -1.0;
      }
    }
  return "";
}

double tsuji_damping(double e)
{
  static const double c[7] = {1.2728, -4.2783, 11.087, -22.348, 27.467, -18.022, 4.8218};
  double v = 0.0;
  for (int k = 6; k >= 0; --k) v = v * e + c[k];
  return v;
}

double restitution_from_tsuji(double alpha)
{
  // the fit falls monotonically on [0, 1]: bisection
  double lo = 0.0, hi = 1.0;
  if (!(alpha < tsuji_damping(lo))) return 0.0;
  if (!(alpha > tsuji_damping(hi))) return 1.0;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (tsuji_damping(mid) > alpha ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {

// The rebound of X'' = -X^p - beta X^q X' from X = 0 at X' = 1 (a damped normal law in units of
// its deepest overlap and approach speed), by RK4 until the overlap closes, or with
// limit_damping until the force vanishes; 0 where it never closes (overdamped).
// The powers are 1 or 3/2 and 0, 1/4 or 1/2. After max_steps steps of dt an overlap still open
// counts as overdamped.
double rebound(double p, double q, double beta, bool limit_damping, int max_steps = 1000000,
               double dt = 1e-4)
{
  const auto power = [](double x, double e) {
    return e == 0     ? 1.0
           : e == 1   ? x
           : e == 1.5 ? x * std::sqrt(x)
           : e == 0.5 ? std::sqrt(x)
                      : std::sqrt(std::sqrt(x));
  };
  const auto force = [&](double d, double v) {
    const double x = std::max(d, 0.0);
    const double f = power(x, p) + beta * power(x, q) * v;
    return limit_damping ? std::max(f, 0.0) : f;
  };
  // dt: a collision lasts about 3.2 (hertz), pi (hooke)
  double d = 0.0, v = 1.0;
  for (int k = 0; k < max_steps; ++k) {
    const double k1d = v, k1v = -force(d, v);
    const double k2d = v + 0.5 * dt * k1v, k2v = -force(d + 0.5 * dt * k1d, v + 0.5 * dt * k1v);
    const double k3d = v + 0.5 * dt * k2v, k3v = -force(d + 0.5 * dt * k2d, v + 0.5 * dt * k2v);
    const double k4d = v + dt * k3v, k4v = -force(d + dt * k3d, v + dt * k3v);
    const double d_next = d + dt / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d);
    const double v_next = v + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    if (k > 0 && d_next <= 0.0) { // the overlap closes within this step
      const double f = d / (d - d_next);
      return std::clamp(-(v + f * (v_next - v)), 0.0, 1.0);
    }
    if (limit_damping && v_next < 0.0 && force(d_next, v_next) <= 0.0)
      return std::clamp(-v_next, 0.0, 1.0); // no force left: the bodies part at this speed
    d = d_next;
    v = v_next;
  }
  return 0.0; // overdamped: the overlap never closes
}

// rebound(p, q, beta) on a log grid of beta, integrated once per law on first use: beta from
// 1e-4 (e within 1e-4 of 1) to 1e3 (overdamped), kTablePoints per decade.
constexpr double kBetaLo = -4.0, kBetaHi = 3.0;
constexpr int kTablePoints = 48;
constexpr double kTableDt = 2.5e-4;
constexpr int kTableSteps = 40000; // 10 units: three collision times

double tabulated_rebound(int law, double p, double q, bool limit_damping, double beta)
{
  static std::array<std::vector<double>, 8> tables;
  std::vector<double> &table = tables[std::size_t(law)];
  const int n = static_cast<int>((kBetaHi - kBetaLo) * kTablePoints);
  if (table.empty())
    for (int k = 0; k <= n; ++k)
      table.push_back(rebound(p, q, std::pow(10.0, kBetaLo + double(k) / kTablePoints),
                              limit_damping, kTableSteps, kTableDt));
  if (!(beta > 0)) return 1.0;
  const double at = (std::log10(beta) - kBetaLo) * kTablePoints;
  if (at <= 0) return 1.0 - (1.0 - table[0]) * beta / std::pow(10.0, kBetaLo);
  if (at >= n) return table[std::size_t(n)];
  const int k = static_cast<int>(at);
  const double f = at - k;
  return (1.0 - f) * table[std::size_t(k)] + f * table[std::size_t(k) + 1];
}

} // namespace

double rebound_restitution(NormalLaw law, double alpha, bool limit_damping)
{
  if (!(alpha >= 0)) return 0.0;
  // hooke F = k d + alpha sqrt(m k) d'; hertz F = k a d + alpha sqrt(m k a) d', a = sqrt(r d)
  return law == NormalLaw::hooke ? rebound(1.0, 0.0, alpha, limit_damping)
                                 : rebound(1.5, 0.25, alpha, limit_damping);
}

double viscous_restitution(const PairCoefficients &p, double m_eff, double r_eff, double v,
                           double reach)
{
  if (p.viscous == ViscousDamping::none || p.normal == NormalLaw::none || !(m_eff > 0) ||
      !(v > 0) || !(p.k_n > 0))
    return -1.0;
  // m d'' = -K d^pw - g d^q d': hooke K = k_n; hertz K = k_n sqrt(r_eff); the dashpot g is c,
  // c m_eff or c m_eff sqrt(r_eff) d^1/2 (normal_damper). In units of x0 = (m v^2 / K)^(1 /
  // (pw + 1)) and x0 / v it is X'' = -X^pw - beta X^q X' with beta = g x0^(q + 1) / (m v).
  const bool hooke = p.normal == NormalLaw::hooke;
  const double pw = hooke ? 1.0 : 1.5;
  const double stiffness = hooke ? p.k_n : p.k_n * std::sqrt(r_eff);
  const bool visco = p.viscous == ViscousDamping::viscoelastic;
  const double q = visco ? 0.5 : 0.0;
  double g = p.viscous_coeff;
  if (p.viscous != ViscousDamping::velocity) g *= m_eff;
  if (visco) g *= std::sqrt(r_eff);
  // The undamped law's deepest overlap is ((pw + 1) / 2)^(1 / (pw + 1)) x0. Where it reaches
  // the centres the law would pass the bodies through each other: the spring stores at most
  // the energy of the impact v_reach whose overlap just reaches them, the rest is lost, and
  // the bodies part at most at the rebound of v_reach.
  const double deepest = std::pow((pw + 1.0) / 2.0, 1.0 / (pw + 1.0));
  double speed = v;
  if (reach > 0 && deepest * std::pow(m_eff * v * v / stiffness, 1.0 / (pw + 1.0)) > reach)
    speed = std::sqrt(stiffness * std::pow(reach / deepest, pw + 1.0) / m_eff);
  const double x0 = std::pow(m_eff * speed * speed / stiffness, 1.0 / (pw + 1.0));
  const double beta = g * std::pow(x0, q + 1.0) / (m_eff * speed);
  const int law = (hooke ? 0 : 4) + (visco ? 2 : 0) + (p.limit_damping ? 1 : 0);
  return tabulated_rebound(law, pw, q, p.limit_damping, beta) * speed / v;
}

FrictionParams contact_friction(const PairCoefficients &p, double r_eff, double overlap)
{
  FrictionParams f;
  f.mu = p.mu;
  f.mu_roll = p.mu_roll;
  f.mu_twist = 0.0;
  if (p.twist == TwistLaw::sds && r_eff > 0)
    f.mu_twist = p.twist_coeff / r_eff;
  else if (p.twist == TwistLaw::marshall && r_eff > 0)
    f.mu_twist = 2.0 / 3.0 * p.mu * std::sqrt(std::max(overlap, 0.0) / r_eff);
  return f;
}

double law_overlap(const PairCoefficients &p, double r_eff, double f)
{
  if (p.normal == NormalLaw::none || !(p.k_n > 0) || !(f > 0)) return 0.0;
  if (p.normal == NormalLaw::hooke) return f / p.k_n;
  return r_eff > 0 ? std::cbrt(f * f / (p.k_n * p.k_n * r_eff)) : 0.0;
}

bool material_compliance(const PairCoefficients &p, double r_eff, double overlap, double last_force,
                         const std::array<double, kMaxRows> &rigid,
                         std::array<double, kMaxRows> &eps, std::array<bool, kMaxRows> &elastic)
{
  eps = rigid;
  elastic.fill(false);
  if (p.normal == NormalLaw::none || !(p.k_n > 0) || !(r_eff > 0)) return false;
  const bool hertz = p.normal != NormalLaw::hooke;
  const double d_now = std::max(overlap, 0.0);
  const double f_now = hertz ? p.k_n * std::sqrt(r_eff * d_now) * d_now : p.k_n * d_now;
  const double f = std::max(last_force, f_now);
  // the law's overlap at the reference load, and its contact radius; unloaded (f = 0), the
  // normal row stays rigid and the springs that need a contact radius vanish with a = 0
  double a = 0.0;
  if (f > 0) {
    const double d = law_overlap(p, r_eff, f);
    eps[0] = d / f;
    elastic[0] = true; // the gap is the law's overlap at the load
    a = std::sqrt(r_eff * d);
  }
  // the springs, each with its displacement in the rhs (Contact::spring)
  const double k_t = p.tangential == TangentialLaw::mindlin  ? p.k_t * a
                     : p.tangential == TangentialLaw::linear ? p.k_t
                                                             : 0.0;
  const double k_twist = p.twist == TwistLaw::marshall ? 0.5 * k_t * a * a
                         : p.twist == TwistLaw::sds    ? p.k_twist
                                                       : 0.0;
  const double k_roll = p.k_roll * r_eff * r_eff; // torque per unit angle
  const double stiffness[kMaxRows] = {0.0, k_t, k_t, k_twist, k_roll, k_roll};
  for (int r = 1; r < kMaxRows; ++r)
    if (stiffness[r] > 0) {
      eps[r] = 1.0 / stiffness[r];
      elastic[r] = true;
    }
  return true;
}

PairCoefficients contact_law(const PairCoefficients &p, double m_eff, double r_eff)
{
  if (!(p.hooke_velocity > 0 && p.hooke_y_eff > 0 && m_eff > 0 && r_eff > 0)) return p;
  PairCoefficients q = p;
  const double s = std::sqrt(r_eff), v = p.hooke_velocity, y = p.hooke_y_eff;
  q.k_n = 16.0 / 15.0 * s * y * std::pow(15.0 * m_eff * v * v / (16.0 * s * y), 0.2);
  if (q.tangential == TangentialLaw::linear) q.k_t = q.k_n;
  return q;
}

double collision_time(const PairCoefficients &p, double r_eff, double m_eff, double v)
{
  if (p.normal == NormalLaw::none || !(p.k_n > 0) || !(m_eff > 0)) return 0.0;
  if (p.normal == NormalLaw::hooke) return std::acos(-1.0) * std::sqrt(m_eff / p.k_n);
  if (!(r_eff > 0) || !(v > 0)) return 0.0;
  // t = 2 (d_max / v) int_0^1 dx / sqrt(1 - x^5/2), the integral 0.4 B(0.4, 0.5)
  static const double half_period = 0.4 * std::tgamma(0.4) * std::tgamma(0.5) / std::tgamma(0.9);
  const double K = p.k_n * std::sqrt(r_eff);
  const double d_max = std::pow(1.25 * m_eff * v * v / K, 0.4);
  return 2.0 * half_period * d_max / v;
}

PairCollisionTime shortest_collision_time(const MaterialTable &table, double r, double m, double v)
{
  PairCollisionTime shortest;
  for (int i = 1; i <= table.ntypes(); ++i)
    for (int j = i; j <= table.ntypes(); ++j) {
      const PairCoefficients p = contact_law(table.at(i, j), 0.5 * m, 0.5 * r);
      const double t_c = collision_time(p, 0.5 * r, 0.5 * m, v);
      if (t_c > 0 && (shortest.t_c == 0 || t_c < shortest.t_c)) shortest = {t_c, i, j};
    }
  return shortest;
}

double liggghts_hertz_damping(double e)
{
  const double ln = std::log(e), pi = std::acos(-1.0);
  return std::sqrt(5.0) * std::fabs(ln) / std::sqrt(ln * ln + pi * pi);
}

double liggghts_hooke_damping(double e)
{
  const double ln = std::log(e), pi = std::acos(-1.0);
  return 2.0 * std::fabs(ln) / std::sqrt(ln * ln + pi * pi);
}

double normal_damper(const PairCoefficients &p, double m_eff, double a, double k)
{
  if (p.damping_alpha >= 0) return p.damping_alpha * std::sqrt(m_eff * k);
  switch (p.viscous) {
  case ViscousDamping::velocity:
    return p.viscous_coeff;
  case ViscousDamping::mass_velocity:
    return p.viscous_coeff * m_eff;
  case ViscousDamping::viscoelastic:
    return p.viscous_coeff * m_eff * a;
  case ViscousDamping::none:
    break;
  }
  return -1.0;
}

double tangential_damper_time(const PairCoefficients &p, double gamma_n, double eps_t)
{
  if (!(p.tangential_damping >= 0 && gamma_n >= 0)) return -1.0;
  return p.tangential_damping * gamma_n * eps_t;
}

double spring_damping_time(const PairCoefficients &p, int r)
{
  if ((r == 4 || r == 5) && p.k_roll > 0 && p.gamma_roll > 0) return p.gamma_roll / p.k_roll;
  if (r == 3 && p.twist == TwistLaw::sds && p.k_twist > 0 && p.gamma_twist > 0)
    return p.gamma_twist / p.k_twist;
  return 0.0;
}

std::vector<std::string> MaterialTable::describe() const
{
  std::vector<std::string> lines;
  const auto g = format_g;
  for (int i = 1; i <= ntypes(); ++i)
    for (int j = i; j <= ntypes(); ++j) {
      const PairCoefficients &p = at(i, j);
      std::string line = std::to_string(i) + " " + std::to_string(j) + ": mu " + g(p.mu) +
                         ", mu_roll " + g(p.mu_roll) + ", twisting ";
      line += p.twist == TwistLaw::sds        ? "sds " + g(p.twist_coeff)
              : p.twist == TwistLaw::marshall ? std::string("marshall")
                                              : std::string("none");
      line += ", restitution " + (p.restitution >= 0 ? g(p.restitution) : std::string("none"));
      if (p.damping_alpha >= 0)
        line += " (the rebound of the damped Hertz or Hooke law, alpha " + g(p.damping_alpha) + ")";
      if (p.hooke_velocity > 0)
        line += ", hooke of Y_eff " + g(p.hooke_y_eff) + " at characteristicVelocity " +
                g(p.hooke_velocity) + " (k_n and k_t per contact)";
      if (p.cohesion != CohesionLaw::none)
        line += std::string(", cohesion ") +
                (p.cohesion == CohesionLaw::jkr   ? "jkr"
                 : p.cohesion == CohesionLaw::dmt ? "dmt"
                                                  : "sjkr") +
                " " + g(p.cohesion_energy);
      lines.push_back(line);
    }
  return lines;
}

} // namespace fibre
