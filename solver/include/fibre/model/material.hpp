// Contact coefficients per pair of atom types, as a front end reads them from its pair style
// (LAMMPS's pair_coeff, LIGGGHTS's fix property/global): Coulomb, rolling and twisting
// friction and the coefficient of restitution, with the mixing rule for pairs of different
// types, and what one contact takes from them (doc/design.md section 2, "Material").
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fibre/core/system.hpp"

namespace fibre {

// How the twisting limit follows from the pair style's twisting model:
//   none      no twisting resistance;
//   sds       |torque| <= mu_tw F_n with mu_tw a length (LAMMPS twisting sds);
//   marshall  |torque| <= 2/3 a mu F_n with a = sqrt(r_eff overlap) the Hertz contact radius
//             (Marshall 2009, LAMMPS twisting marshall): vanishes for rigid contacts.
enum class TwistLaw { none, sds, marshall };

// The elastic laws of the pair style (`compliance material` linearizes the normal one):
//   normal      hooke F = k_n d; hertz F = k_n sqrt(r_eff d) d (hertz/material: k_n = 4/3 E_eff);
//   tangential  linear (k_t), mindlin (k_t a, a = sqrt(r_eff d) the contact radius);
//   rolling     sds: torque k_roll r_eff^2 per unit angle; twisting sds: k_twist per unit angle,
//               marshall: 0.5 k_t a^2 (mindlin).
enum class NormalLaw { none, hooke, hertz, hertz_material };
enum class TangentialLaw { none, linear, mindlin };
enum class ViscousDamping { none, velocity, mass_velocity, viscoelastic };
// Cohesion (cohesion.hpp): LAMMPS granular's jkr and dmt (surface energy gamma) and LIGGGHTS's
// sjkr (cohesion energy density k_c), each on the pair's Hertz law.
enum class CohesionLaw { none, jkr, dmt, sjkr };

struct PairCoefficients {
  bool set = false;
  double mu = 0.0;      // Coulomb
  double mu_roll = 0.0; // rolling: |torque| <= mu_roll r_eff F_n
  TwistLaw twist = TwistLaw::none;
  double twist_coeff = 0.0; // sds: mu_tw (length)
  // Newton's coefficient of restitution, or < 0 when the pair style's damping law has none
  // (a viscous damping): the contact is then plastic unless the front end's keyword says more.
  // With LAMMPS's damping tsuji it is the rebound of the pair style's own damped law
  // (rebound_restitution), not the e typed in pair_coeff.
  double restitution = -1.0;
  // The normal dashpot alpha sqrt(m_eff k_n a) of LAMMPS's damping tsuji (its coefficient) and
  // of LIGGGHTS's hertz (alpha = sqrt(5) |ln e| / sqrt(ln^2 e + pi^2)); < 0: none.
  double damping_alpha = -1.0;
  // LAMMPS's viscous normal damping models (pair granular's damping velocity, mass_velocity,
  // viscoelastic, the last its default): the dashpot c, c m_eff or c m_eff a (normal_damper).
  ViscousDamping viscous = ViscousDamping::none;
  double viscous_coeff = 0.0;
  bool limit_damping = false;         // LAMMPS's limit_damping: the normal force never pulls
  NormalLaw normal = NormalLaw::none; // none: no elastic constants (compliance auto)
  double k_n = 0.0;
  TangentialLaw tangential = TangentialLaw::none;
  double k_t = 0.0;
  double k_roll = 0.0;  // rolling sds, 0: none
  double k_twist = 0.0; // twisting sds
  // The SDS dampers (LAMMPS's gamma_roll, gamma_twist): with the spring a Kelvin-Voigt
  // element of damping time gamma / k (spring_damping_time).
  double gamma_roll = 0.0;
  double gamma_twist = 0.0;
  // The tangential dashpot as a multiple of the normal one (LAMMPS granular's x_gamma_t,
  // gran/*'s gamma_t / gamma_n: 0 with dampflag 0); < 0: not known, the tangential rows take
  // the normal row's damping (tangential_damper_time).
  double tangential_damping = -1.0;
  // LIGGGHTS's tangential history: its cone bounds the spring's force alone, and a sliding
  // contact has no tangential dashpot (LAMMPS's bounds the spring and dashpot together).
  bool cone_on_spring = false;
  // LIGGGHTS's hooke: the stiffnesses of each contact follow from its effective Young's
  // modulus and the deck's characteristicVelocity v_c (> 0), k_n = 16/15 sqrt(r_eff) Y_eff (15
  // m_eff v_c^2 / (16 sqrt(r_eff) Y_eff))^(1/5) and k_t = k_n (contact_law); k_n and k_t are
  // then 0 in the table.
  double hooke_y_eff = 0.0;
  double hooke_velocity = 0.0;
  // The pair style's cohesion: its law and its gamma (jkr, dmt) or k_c (sjkr).
  CohesionLaw cohesion = CohesionLaw::none;
  double cohesion_energy = 0.0;
};

// The coefficients of one contact of reduced mass m_eff and radius r_eff: p itself, or with
// LIGGGHTS hooke's stiffnesses for that contact.
PairCoefficients contact_law(const PairCoefficients &p, double m_eff, double r_eff);

// Symmetric table over types 1..ntypes.
class MaterialTable {
 public:
  MaterialTable() = default;
  explicit MaterialTable(int ntypes);
  int ntypes() const { return ntypes_; }
  bool empty() const { return ntypes_ == 0; }
  PairCoefficients &at(int i, int j);
  const PairCoefficients &at(int i, int j) const;
  // Pairs i != j that were not set get the geometric mean of (i, i) and (j, j) for every
  // coefficient (LAMMPS's rule for pair granular; the restitution through Tsuji's damping
  // coefficient, which is what LAMMPS mixes). Returns "" or what cannot be mixed (a type
  // without coefficients, or two twisting laws).
  std::string mix();
  // A new type T = ntypes() + 1 whose pair with every type, itself included, is p: a wall's own
  // material, which every sphere type meets alike. Returns T.
  int add_type(const PairCoefficients &p);
  // One line per type pair i <= j for the log: "1 1: mu 0.4, mu_roll 0.1, twisting sds 0.07,
  // restitution 0.3".
  std::vector<std::string> describe() const;

 private:
  int ntypes_ = 0;
  std::vector<PairCoefficients> pairs_;
};

// Tsuji's damping coefficient of a coefficient of restitution e in [0, 1] (the polynomial fit
// that LAMMPS's `damping tsuji` applies to hertz/material's e), and its inverse on [0, 1].
double tsuji_damping(double e);
double restitution_from_tsuji(double alpha);

// LIGGGHTS's hertz dashpot for a coefficient of restitution e in (0, 1), in the form
// alpha sqrt(m_eff k_n a) of normal_damper: alpha = sqrt(5) |ln e| / sqrt(ln^2 e + pi^2) (its
// gamma = 2 sqrt(5/6) |beta| sqrt(S m_eff) on S = 2 Y* a, 1.5 the secant). It rebounds at e.
double liggghts_hertz_damping(double e);
// LIGGGHTS's hooke dashpot sqrt(4 m_eff k_n / (1 + (pi / ln e)^2)) as alpha sqrt(m_eff k_n):
// alpha = 2 |ln e| / sqrt(ln^2 e + pi^2), the linear law's exact rebound e.
double liggghts_hooke_damping(double e);

// The coefficient of restitution that a head-on collision under LAMMPS's damped normal law
// gives: overlap d, hooke F = k d + alpha sqrt(m k) d', hertz F = k a d + alpha sqrt(m k a) d'
// with a = sqrt(r_eff d) (damping tsuji). The law is scale free, so this depends on alpha
// alone; it is integrated once in units m = k = v = 1 until the overlap closes, or with
// limit_damping until the force vanishes. Tsuji's fit names another e: LAMMPS's `hertz/material
// E 0.1 ...` rebounds at 0.234.
double rebound_restitution(NormalLaw law, double alpha, bool limit_damping = false);

// The coefficient of restitution of a head-on impact at approach speed v under the pair's
// normal law with LAMMPS's viscous dashpot (velocity c, mass_velocity c m_eff, viscoelastic
// c m_eff a), for reduced mass m_eff and effective radius r_eff: the law in units of its deepest
// overlap and approach speed has one parameter, whose rebound is integrated once per law on a
// grid and interpolated. -1 where p has no viscous damping or no normal law. reach (> 0): the
// overlap at which the centres meet (r_a + r_b, a wall's sphere r_a). An impact whose undamped
// deepest overlap would pass it is beyond the law (a soft contact passes the bodies through each
// other): its spring stores at most the energy of the impact v_reach that just reaches the
// centres, and the bodies part at e(v_reach) v_reach.
double viscous_restitution(const PairCoefficients &p, double m_eff, double r_eff, double v,
                           double reach = 0.0);

// The friction of one contact (radius r_eff, overlap >= 0) from its pair's coefficients:
// mu_twist per unit r_eff as FrictionParams keeps it.
FrictionParams contact_friction(const PairCoefficients &p, double r_eff, double overlap);

// The law's overlap under a normal load f (0 without a normal law or a load).
double law_overlap(const PairCoefficients &p, double r_eff, double f);

// `compliance material` (doc/design.md section 2, "Material"): the rows' compliances from the
// pair's elastic laws at the reference load F = max(the contact's last normal force, the law's
// force at its overlap). Normal row: the secant compliance d(F) / F, so that a contact at rest
// under a steady load overlaps by the law's d(F) and a native state at equilibrium is one here
// too; it is marked `elastic` (its gap term is the law's force, not bounded). Tangential, twisting
// and rolling rows: 1 / the law's spring at the contact radius a of d(F), marked `elastic` (they
// carry their displacement in the rhs, Contact::spring). Rows without a spring keep `rigid` (the
// automatic compliance). A contact with F = 0 (new, not overlapping) keeps `rigid` on its normal
// and Mindlin rows, whose laws need a load; the load-free springs (linear tangential, SDS rolling
// and twisting) are elastic from its first step, as the pair style's are from the first touch:
// an impact cannot load a soft spring within the collision. Returns false when p has no normal
// law.
bool material_compliance(const PairCoefficients &p, double r_eff, double overlap, double last_force,
                         const std::array<double, kMaxRows> &rigid,
                         std::array<double, kMaxRows> &eps, std::array<bool, kMaxRows> &elastic);

// How long the pair's elastic normal law holds two bodies of reduced mass m_eff together when
// they meet at approach speed v: pi sqrt(m_eff / k_n) for Hooke's law, and for Hertz's
// (F = K d^3/2, K = k_n sqrt(r_eff)) 2.94 d_max / v with the deepest overlap
// d_max = (5 m_eff v^2 / (4 K))^2/5. 0 where p has no normal law.
double collision_time(const PairCoefficients &p, double r_eff, double m_eff, double v);

// The shortest collision_time over the table's type pairs for two equal spheres of radius r
// and mass m meeting at speed v (r_eff r / 2, m_eff m / 2), and its pair i <= j; t_c 0 where
// no pair has a normal law. The step's ratio to it says whether the step resolves collisions
// (doc page, "Time step and stiff materials").
struct PairCollisionTime {
  double t_c = 0.0;
  int i = 0, j = 0;
};
PairCollisionTime shortest_collision_time(const MaterialTable &table, double r, double m, double v);

// The normal law's dashpot gamma_n (force per unit approach speed) of a contact of reduced mass
// m_eff, contact radius a and secant stiffness k (the normal row's 1 / eps), as LAMMPS damps
// it: tsuji alpha sqrt(m_eff k), velocity c, mass_velocity c m_eff, viscoelastic c m_eff a.
// < 0 where the pair has no damping law.
double normal_damper(const PairCoefficients &p, double m_eff, double a, double k);
// The damping time b_t / k_t of the tangential spring k_t = 1 / eps_t, its dashpot b_t the
// law's tangential_damping times the normal dashpot gamma_n (>= 0); < 0 where either is unknown.
double tangential_damper_time(const PairCoefficients &p, double gamma_n, double eps_t);

// The tangential coefficient of restitution of an impact at approach speed v and slip speed u
// (the contact point's, along the contact plane): e_t = -u+ / u after the pair's tangential
// spring (linear k_t or Mindlin's k_t a) and dashpot (tangential_damping times the normal one)
// have acted over the normal law's collision within the cone mu |F_n|, a spring beyond it set
// back to it, as LAMMPS's history is (Maw, Barber and Fawcett's impact). It depends on the
// impact's angle through chi = mu m_eff v / (m_t u); u = 0 sticks. m_t is the slip's reduced
// mass, 2/7 m_eff for two solid spheres. From 1 (an undamped spring as fast as the normal one
// reverses a slip that sticks) to -1; NaN where the law has no tangential spring, its dashpot
// is unknown or the overlap never closes. Integrated on a grid of the law's normal damping and
// chi, each point on first use, and interpolated.
double tangential_restitution(const PairCoefficients &p, double m_eff, double m_t, double r_eff,
                              double v, double u);

// The damping time (seconds) of row r's spring in the pair's law, gamma / k of the SDS rolling
// (rows 4, 5) and twisting (row 3) laws; 0 where the law has no damper of its own.
double spring_damping_time(const PairCoefficients &p, int r);

} // namespace fibre
