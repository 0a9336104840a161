// The contact model that every front end shares (doc/design.md section 2): per-row compliance,
// the effective radius and the friction, rolling and twisting coefficients of a contact.
#pragma once

#include <vector>

#include "fibre/core/names.hpp"
#include "fibre/core/system.hpp"
#include "fibre/model/material.hpp"

namespace fibre {

// How stiff the rows are. auto: eps = factor dt^2 / m_min on every translational row, so that
// Sigma is a fixed small fraction of the lightest body's G M^-1 G^T entry whatever the step.
// fixed: eps_n on the normal row, eps_t on the tangential rows. The rotational rows take
// eps_t / r_eff^2 in both modes.
// material: from the pair style's elastic laws where it has them (material_compliance()),
// else automatic. Untyped, the front end chooses material when its pair style is a material
// (PairReading::material), else automatic.
struct ComplianceParams {
  bool automatic = true;
  bool material = false;
  double eps_n = 0.0, eps_t = 0.0; // fixed mode
  double factor = 1e-2;            // automatic mode
};

// Where the friction and restitution coefficients come from: the pair style's coefficients
// per type pair (`materials`, filled by the front end), or the model's own values for every
// contact. Keywords the user typed override the pair style's values for every pair.
enum class CoefficientSource { pair, fix };
template <> struct EnumNames<CoefficientSource> {
  static constexpr EnumName<CoefficientSource> table[] = {{CoefficientSource::pair, "pair"},
                                                          {CoefficientSource::fix, "fix"}};
};
// How the normal row of a loaded material contact (compliance material) relaxes where the
// law's dashpot is shorter than `damping` steps: spook, over `damping` steps; law, the pair
// style's spring and dashpot by implicit Euler (Contact::implicit_normal), which does not ring
// at any dashpot time (examples/README.md, "The normal rows by implicit Euler").
enum class NormalRelaxation { law, spook };
template <> struct EnumNames<NormalRelaxation> {
  static constexpr EnumName<NormalRelaxation> table[] = {{NormalRelaxation::law, "law"},
                                                         {NormalRelaxation::spook, "spook"}};
};
struct TypedCoefficients {
  bool mu = false, mu_roll = false, mu_twist = false, restitution = false, compliance = false;
};

// The model of one simulation: rows per contact, SPOOK damping, compliance and friction.
struct ContactModel {
  int rows = 6; // 3: translational rows only; 6: with twisting and rolling
  // rows auto (the default): the front end sets rows from rows_needed() once the pair style's
  // coefficients are read; false once 'rows 3|6' is typed.
  bool rows_auto = true;
  double damping = 2.0; // SPOOK d = tau / h, in steps
  ComplianceParams compliance{};
  FrictionParams friction{}; // of every contact (one material)
  // The largest speed at which overlaps are removed (SpookParams::max_recovery): > 0 a speed,
  // 0 unbounded, < 0 (the default) automatic: recovery_radii radii of the smallest sphere per
  // step, so that an overlap of 10% of a radius closes over 10 steps whatever the units.
  double recovery_speed = -1.0;
  double recovery_radii = 0.01;
  double max_recovery(double h, double r_min) const
  {
    return recovery_speed >= 0 ? recovery_speed : recovery_radii * r_min / h;
  }
  // Newton's coefficient of restitution of every contact (0: plastic, the SPOOK default), and
  // the approach speed below which contacts stay plastic (SpookParams::bounce_speed): >= 0 a
  // speed, < 0 (the default) automatic, bounce_steps times the largest speed that the external
  // forces add to a body in one step.
  double restitution = 0.0;
  double bounce_speed = -1.0;
  double bounce_steps = 2.0;
  // The contact solve's substeps per step (substeps.hpp): > 0 that many, 0 (the default)
  // automatic, the fewest of at most substep_collisions shortest collision times of the
  // material's law (one where the step is that short already, or there is no law).
  int substeps = 0;
  double substep_collisions = 0.33;
  // The law's shortest collision time at 1 velocity unit (the front end sets it each step, as
  // substeps auto reads it), 0: unknown, and the contact solve's step before its substeps (0:
  // the step's). A solve's step of at most kResolvedCollision of it resolves the collisions:
  // the tangential springs take the law's dashpot and impacts its tangential restitution
  // (apply_pair).
  double collision_time = 0.0;
  double solve_step = 0.0;
  bool resolves_collisions(double h) const;
  // Whether a step in which no contact moves (step_moves: a pile at rest) takes one solve
  // instead of its substeps (keyword substep_when moving; always, the default: every step).
  bool substep_moving_only = false;
  CoefficientSource coefficients = CoefficientSource::pair;
  NormalRelaxation normal_relaxation = NormalRelaxation::spook;
  TypedCoefficients typed{};
  MaterialTable materials; // empty: the pair style gave none (or coefficients fix)
  // Whether wall contacts (walls and obstacles) take their type pair's cohesion.
  bool wall_cohesion = true;
  bool per_type() const { return coefficients == CoefficientSource::pair && !materials.empty(); }
  // Whether any contact can have a restitution above 0 (the keyword or a type pair's).
  bool may_bounce() const;
  // The rows a contact needs: 6 where some contact can carry a rolling or twisting impulse (the
  // model's or a type pair's mu_roll or twisting law), else 3: without one the rotational rows
  // would carry only zeros.
  int rows_needed() const;
};

// The automatic bounce speed's scale: max over bodies of h |f| / m (local; a front end takes
// the maximum over processes).
double external_speed_per_step(const std::vector<Body> &bodies, int num_owned, double h);

// Cone radius per unit normal impulse of cone k (0 Coulomb, 1 twisting, 2 rolling).
double cone_coefficient(const FrictionParams &f, double r_eff, int cone);
// The normal load the cones' radii follow: lambda_n, and a cohesive contact's lambda_n + 2 pull
// (pull its pull-off impulse, or force with a force: LAMMPS's |F_ne + 2 F_pulloff|).
inline double cone_load(double lambda_n, double pull)
{
  return lambda_n + 2.0 * pull;
}

// A last normal impulse at most this times m_eff (|v_n| + bounce_speed) is round-off, no load.
inline constexpr double kRoundoffLoad = 1e-9;

// A rigid row's overlap is a penetration (SpookParams::penetration_floor) beyond kPenetration-
// Start steps of max_recovery: the overlaps of a start that the log warns of (5% of a diameter,
// 10 steps of the automatic recovery speed); shallower ones are removed by the rows' bounded
// velocities. While penetrations are being recovered, beyond kPenetrationFloor of a step: the
// recovery's displacement leaves overlaps of up to a step of max_recovery in a crowded bed,
// which the rows' velocities would remove at max_recovery where the bed has no room (at a
// floor of 1, spheres inserted into a bed reached 27 m/s; at 0.01, 4.6). An elastic row's
// penetration is split when found beyond kPenetrationStart steps and stays split down to
// kPenetrationFloor (Contact::split).
inline constexpr double kPenetrationStart = 10.0;
inline constexpr double kPenetrationFloor = 0.01;
// A joint's compliance, h^2 times this of its rows' inverse mass (its Sigma about 1e-7 of
// G M^-1 G^T): rigid whatever the material. At the material's own compliance (the incline test's
// soft gran/hooke 1.0) a clump held on a slope by friction crept at 2% of g h a step.
inline constexpr double kJointCompliance = 1e-6;

// Contact c's bodies' approach speed along the normal (> 0 closing; a wall at its own
// velocity).
double normal_approach(const std::vector<Body> &bodies, const Contact &c);
// The velocity of a's surface relative to b's (or the wall's) at the contact point.
Vec3 relative_velocity(const std::vector<Body> &bodies, const Contact &c);

// Sets the per-row compliance, the friction coefficients and the restitution of every contact
// (m_min: the lightest body of the simulation, read by automatic compliance only). With
// per-type coefficients a pair takes those of its bodies' types, a wall contact those of its
// sphere's type with itself, and typed keywords override them.
// `last` (optional, rows per contact) holds each contact's impulses of the last step, for
// compliance material's reference load; a contact that carried a normal impulse then is an
// enduring contact, not an impact, and gets no restitution; one at round-off (kRoundoffLoad)
// counts as none. `params` gives the step h and the bounce speed: an impact that bounces has
// its springs for its collision time only.
// `r_eff` (optional): the contacts' effective radii, where the caller has them
// (ContactSystem::effective_radii).
void apply_contact_model(const ContactModel &model, const SpookParams &params, double m_min,
                         const std::vector<Body> &bodies, std::vector<Contact> &contacts,
                         const Vector *last = nullptr, const std::vector<double> *r_eff = nullptr);

} // namespace fibre
