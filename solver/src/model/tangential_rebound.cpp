#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "fibre/model/material.hpp"

namespace fibre {

namespace {

// An impact in units of the normal law's deepest overlap x0, approach speed v and time x0 / v:
// X'' = -f_n, f_n = X^p + beta X^q X' (the normal law, never negative with limit_damping), and
// the slip U (in units of its approach) against the tangential spring S and dashpot,
// U' = f_t = -k_t X^s S - c_t beta X^q U, S' = U, from X = S = 0, X' = U = 1. The cone holds
// |f_t| <= chi |f_n|, chi = mu m_eff v / (m_t u) the cone's radius in the slip's units; a spring
// beyond it is set back to the cone, as LAMMPS's history is.
struct SlipLaw {
  double p = 1.0, q = 0.0, s = 0.0; // normal, dashpot and tangential spring powers
  bool limit = false;
  bool spring_cone = false;    // LIGGGHTS's cone (PairCoefficients::cone_on_spring)
  double k_t = 0.0, c_t = 0.0; // the slip's stiffness at X = 1, its dashpot per normal one
  bool operator==(const SlipLaw &o) const
  {
    return p == o.p && q == o.q && s == o.s && limit == o.limit && spring_cone == o.spring_cone &&
           k_t == o.k_t && c_t == o.c_t;
  }
};

// -U when the overlap closes (or with limit_damping when the normal force vanishes), by Heun's
// method with the cone applied at each step's start; NaN where the overlap never closes (no
// rebound, so no slip's rebound either). chi infinite: the slip sticks.
double slip_rebound(const SlipLaw &law, double beta, double chi)
{
  const auto power = [](double x, double e) { // the laws' powers: 0, 1/4, 1/2, 1, 3/2
    return e == 0     ? 1.0
           : e == 1   ? x
           : e == 1.5 ? x * std::sqrt(x)
           : e == 0.5 ? std::sqrt(x)
                      : std::sqrt(std::sqrt(x));
  };
  using State = std::array<double, 4>; // X, X', S, U
  const auto normal = [&](double x, double v) {
    const double f = power(x, law.p) + beta * power(x, law.q) * v;
    return law.limit ? std::max(f, 0.0) : f;
  };
  // the tangential force and the spring it leaves, within the cone
  const auto tangential = [&](const State &z, double &spring) {
    const double x = std::max(z[0], 0.0), k = law.k_t * power(x, law.s);
    const double damper = law.c_t * beta * power(x, law.q) * z[3];
    const double bound = chi * std::abs(normal(x, z[1]));
    if (law.spring_cone) { // the spring alone against the cone, no dashpot where it slides
      if (!(std::abs(k * spring) > bound)) return -k * spring - damper;
      if (k > 0) spring = std::copysign(bound / k, spring);
      return -std::copysign(bound, spring);
    }
    const double f = -k * spring - damper;
    if (!(std::abs(f) > bound)) return f;
    const double g = std::copysign(bound, f);
    if (k > 0) spring = -(g + damper) / k;
    return g;
  };
  const auto rate = [&](const State &z) {
    double spring = z[2];
    const double f_t = tangential(z, spring);
    return State{z[1], -normal(std::max(z[0], 0.0), z[1]), z[3], f_t};
  };
  // a collision lasts about pi; the step resolves the slip's period and both dashpots
  const double dt = 5e-4 / (1.0 + std::sqrt(law.k_t) + beta * (1.0 + law.c_t));
  const int steps = static_cast<int>(10.0 / dt);
  State z{0.0, 1.0, 0.0, 1.0};
  for (int k = 0; k < steps; ++k) {
    tangential(z, z[2]); // the spring set back to the cone
    const State k1 = rate(z);
    State m;
    for (int i = 0; i < 4; ++i) m[i] = z[i] + dt * k1[i];
    const State k2 = rate(m);
    State next;
    for (int i = 0; i < 4; ++i) next[i] = z[i] + 0.5 * dt * (k1[i] + k2[i]);
    if (k > 0 && next[0] <= 0.0) { // the overlap closes within this step
      const double f = z[0] / (z[0] - next[0]);
      return std::clamp(-(z[3] + f * (next[3] - z[3])), -1.0, 1.0);
    }
    if (law.limit && next[1] < 0.0 && normal(next[0], next[1]) <= 0.0)
      return std::clamp(-next[3], -1.0, 1.0);
    z = next;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// slip_rebound of one law on a grid of beta (the rebound's decades) and chi (kChiLo to kChiHi
// decades, then the slip that sticks), each point integrated on first use; a few laws a run
// (one per type pair and stiffness ratio).
constexpr double kBetaLo = -4.0, kBetaHi = 3.0, kChiLo = -2.0, kChiHi = 3.0;
constexpr int kBetaPoints = 24, kChiPoints = 32; // per decade
constexpr int kBetas = static_cast<int>((kBetaHi - kBetaLo) * kBetaPoints) + 1;
constexpr int kChis = static_cast<int>((kChiHi - kChiLo) * kChiPoints) + 2; // the last: sticks
constexpr int kKtPoints = 32;           // a decade of Hooke-Mindlin's k_t
constexpr std::size_t kMaxTables = 128; // beyond, each impact is integrated (some ms)

// A law's constants to 30 bits: the same pair's k_t and c_t, computed at another speed, differ
// in their last bits only.
double snap(double x)
{
  int e = 0;
  const double m = std::frexp(x, &e);
  return std::ldexp(std::round(std::ldexp(m, 30)), e - 30);
}

struct SlipTable {
  SlipLaw law;
  std::vector<double> e; // NaN: not integrated yet, infinite: never closes
};

double grid_point(SlipTable &t, int i, int j)
{
  double &e = t.e[std::size_t(i) * kChis + std::size_t(j)];
  if (std::isnan(e)) {
    const double beta = std::pow(10.0, kBetaLo + double(i) / kBetaPoints);
    const double chi = j == kChis - 1 ? INFINITY : std::pow(10.0, kChiLo + double(j) / kChiPoints);
    e = slip_rebound(t.law, beta, chi);
    if (std::isnan(e)) e = INFINITY;
  }
  return e;
}

// Where x lies on a grid from lo decades, n points a decade, count points: its cell and the
// fraction within it.
double grid_at(double x, double lo, int n, int count, int &cell)
{
  const double at = std::clamp((std::log10(std::max(x, 1e-300)) - lo) * n, 0.0, double(count - 1));
  cell = std::min(static_cast<int>(at), count - 2);
  return at - cell;
}

double tabulated_slip_rebound(const SlipLaw &law, double beta, double chi)
{
  static std::vector<SlipTable> tables;
  auto it =
      std::find_if(tables.begin(), tables.end(), [&](const SlipTable &t) { return t.law == law; });
  if (it == tables.end()) {
    if (tables.size() >= kMaxTables) return slip_rebound(law, beta, chi);
    tables.push_back({law, std::vector<double>(std::size_t(kBetas) * kChis, std::nan(""))});
    it = tables.end() - 1;
  }
  int i = 0, j = kChis - 1;
  const double fb = grid_at(beta, kBetaLo, kBetaPoints, kBetas, i);
  double fc = 0.0;
  if (chi < std::pow(10.0, kChiHi)) fc = grid_at(chi, kChiLo, kChiPoints, kChis - 1, j);
  const int j1 = std::min(j + 1, kChis - 1);
  const double e00 = grid_point(*it, i, j), e10 = grid_point(*it, i + 1, j);
  const double e01 = grid_point(*it, i, j1), e11 = grid_point(*it, i + 1, j1);
  if (std::isinf(e00) || std::isinf(e10) || std::isinf(e01) || std::isinf(e11))
    return std::numeric_limits<double>::quiet_NaN();
  return (1.0 - fb) * ((1.0 - fc) * e00 + fc * e01) + fb * ((1.0 - fc) * e10 + fc * e11);
}

} // namespace

double tangential_restitution(const PairCoefficients &p, double m_eff, double m_t, double r_eff,
                              double v, double u)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const bool mindlin = p.tangential == TangentialLaw::mindlin;
  if (p.normal == NormalLaw::none || !(p.k_n > 0) || !(p.k_t > 0) || !(m_eff > 0) || !(m_t > 0) ||
      !(r_eff > 0) || !(v > 0) || !(p.tangential_damping >= 0) ||
      (!mindlin && p.tangential != TangentialLaw::linear))
    return nan;
  SlipLaw law;
  const bool hooke = p.normal == NormalLaw::hooke;
  law.p = hooke ? 1.0 : 1.5;
  const double K = hooke ? p.k_n : p.k_n * std::sqrt(r_eff);
  const double x0 = std::pow(m_eff * v * v / K, 1.0 / (law.p + 1.0)), t0 = x0 / v;
  // the dashpot at the deepest overlap x0, in units of m_eff / t0, and its power of X
  const double a0 = std::sqrt(r_eff * x0);
  const double gamma = normal_damper(p, m_eff, a0, K * std::pow(x0, law.p - 1.0));
  const double beta = gamma > 0 ? gamma * t0 / m_eff : 0.0;
  law.q = p.damping_alpha >= 0                        ? 0.5 * (law.p - 1.0)
          : p.viscous == ViscousDamping::viscoelastic ? 0.5
                                                      : 0.0;
  law.limit = p.limit_damping;
  law.spring_cone = p.cone_on_spring;
  law.s = mindlin ? 0.5 : 0.0;
  law.c_t = snap(p.tangential_damping * m_eff / m_t);
  const double chi = u > 0 ? p.mu * m_eff * v / (m_t * u) : INFINITY;
  const double k_t = (mindlin ? p.k_t * a0 : p.k_t) * t0 * t0 / m_t;
  if (!(hooke && mindlin)) {
    law.k_t = snap(k_t); // the same at every impact of the pair
    return tabulated_slip_rebound(law, beta, chi);
  }
  // Hooke's normal law with Mindlin's spring: k_t grows with the impact's overlap, so between
  // the tables of a grid of kKtPoints a decade (a bounded number of laws)
  int cell = 0;
  const double f = grid_at(k_t, -6.0, kKtPoints, 12 * kKtPoints + 1, cell);
  law.k_t = std::pow(10.0, -6.0 + double(cell) / kKtPoints);
  const double lo = tabulated_slip_rebound(law, beta, chi);
  law.k_t = std::pow(10.0, -6.0 + double(cell + 1) / kKtPoints);
  return (1.0 - f) * lo + f * tabulated_slip_rebound(law, beta, chi);
}

} // namespace fibre
