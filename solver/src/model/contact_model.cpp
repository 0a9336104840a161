#include "fibre/model/contact_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "fibre/model/cohesion.hpp"

namespace fibre {

double cone_coefficient(const FrictionParams &f, double r_eff, int cone)
{
  if (cone == 0) return f.mu;
  return (cone == 1 ? f.mu_twist : f.mu_roll) * r_eff;
}

namespace {

// Where a solve's step is at most kResolvedCollision of the law's collision time, a tangential
// spring with a dashpot of its own keeps at most kSpringFloor steps of the normal row's critical
// damping as its floor (apply_pair).
constexpr double kResolvedCollision = 0.1;
constexpr double kSpringFloor = 5.0;

// The contact's reduced mass (the sphere's against a wall).
double effective_mass(const std::vector<Body> &bodies, const Contact &c)
{
  const double ma = bodies[c.a].mass;
  return c.is_wall() ? ma : ma * bodies[c.b].mass / (ma + bodies[c.b].mass);
}

} // namespace

bool ContactModel::resolves_collisions(double h) const
{
  return collision_time > 0 && std::max(h, solve_step) <= kResolvedCollision * collision_time;
}

double normal_approach(const std::vector<Body> &bodies, const Contact &c)
{
  const Vec3 vb = c.is_wall() ? c.wall_v : bodies[c.b].v;
  return -(bodies[c.a].v - vb).dot(c.normal);
}

Vec3 relative_velocity(const std::vector<Body> &bodies, const Contact &c)
{
  const Body &a = bodies[c.a];
  const Vec3 va = a.v + a.omega.cross(c.point - a.x);
  if (c.is_wall()) return va - c.wall_v;
  const Body &b = bodies[c.b];
  return va - (b.v + b.omega.cross(c.point - b.x));
}

namespace {

// Contact c's coefficients from its type pair's (pc), and with compliance material its rows'
// compliances, springs and damping.
// A contact that bounces within the step touches for the law's collision time t_c only, at a
// large step and a stiff material a fraction phi = t_c / h of the step: its springs and
// dampers act for t_c (stiffness phi^2 k and damping phi gamma give the collision's impulses
// k t_c^2 and gamma t_c). Over the whole step they took 1 / phi times the rolling resistance of
// every bounce. d is the rows' damping (steps) so far.
void shorten_to_collision(const PairCoefficients &pc, const SpookParams &params, double reff,
                          double m_eff, double approach, double d, int rows, Contact &c)
{
  const bool bounces =
      c.restitution > 0 && approach > params.bounce_speed && c.gap <= params.h * approach;
  if (!bounces) return;
  const double phi = collision_time(pc, reff, m_eff, approach) / params.h;
  if (!(phi > 0 && phi < 1)) return;
  for (int r = 1; r < rows; ++r)
    if (c.elastic[r]) {
      c.compliance[r] /= phi * phi;
      c.spring_damping[r] = (c.spring_damping[r] >= 0 ? c.spring_damping[r] : d) / phi;
    }
}

// Contact::penetration: the part of the overlap beyond what the contact's last load explains
// (the law's overlap at that force) and the closing within a step (twice its approach speed's,
// for the step's acceleration; as much where it opens: a bounce's overlap), where it is more than
// max_recovery removes in a step. A penetration only shrinks with the overlap, whatever the
// recovery's force; it is gone with it.
void track_penetration(const SpookParams &params, double explained_overlap, double overlap,
                       double approach, Contact &c)
{
  if (!(params.max_recovery > 0)) {
    c.penetration = 0.0;
    return;
  }
  if (c.penetration > 0) {
    c.penetration = std::min(c.penetration, overlap);
    return;
  }
  const double explained = explained_overlap + 2.0 * params.h * std::abs(approach);
  const double excess = overlap - explained;
  c.penetration = excess > params.h * params.max_recovery ? excess : 0.0;
}

// Contact::split of an elastic row's penetration: one found deeper than kPenetrationStart steps
// of max_recovery is split, and stays split while deeper than kPenetrationFloor steps (the
// recovery's displacement leaves up to a step of max_recovery in a crowded bed, which the row's
// velocity would remove at max_recovery where the bed has no room: at a floor of 1, spheres
// inserted into a bed reached 27 m/s; at 0.01, 4.6). One found shallower is never split: a
// soft deep bed holds thousands, and splitting them while another was recovered cost a
// recovery solve every step and took their loads' overlap out of their springs.
void mark_split(const SpookParams &params, bool known, Contact &c)
{
  const double step = params.h * params.max_recovery;
  c.split = known ? c.split && c.penetration > kPenetrationFloor * step
                  : c.penetration > kPenetrationStart * step;
}

// A rigid normal row's penetration (compliance auto, or a law without a stiffness): its whole
// overlap, where it is more than twice the row's at its last load (eps F: SPOOK's rows at rest
// overlap so), the step's closing and penetration_floor steps of recovery. The velocity
// solve then asks it not to close, and the split recovery (step/recovery.hpp) opens it by a
// displacement.
void rigid_penetration(const SpookParams &params, double overlap, double approach,
                       double last_force, Contact &c)
{
  c.penetration = 0.0; // not kept: the overlap and the load are all there is to go by
  if (!(params.max_recovery > 0) || c.elastic[0]) return;
  const double explained = 2.0 * c.compliance[0] * last_force +
                           2.0 * params.h * std::abs(approach) +
                           params.penetration_floor * params.h * params.max_recovery;
  if (overlap > explained) c.penetration = overlap;
}

// A cohesive contact (cohesion.hpp): one whose bodies overlap, or a JKR contact that has
// touched and is within its reach. Its normal row carries tension down to the pull-off force,
// whatever the compliance; an enduring one does not bounce.
void apply_cohesion(const PairCoefficients &pc, double reff, Contact &c)
{
  if (pc.cohesion == CohesionLaw::none) return;
  const bool holds = c.gap < 0 || (pc.cohesion == CohesionLaw::jkr && c.touched &&
                                   c.gap <= cohesive_reach(pc, reff));
  if (!holds) return;
  c.pull = pull_off_force(pc, reff);
  if (c.touched) c.restitution = 0.0;
}

// compliance material's normal row of a cohesive contact: the Hertz part's compliance at its
// load (the law's force plus twice the pull-off, LAMMPS's friction load) and the gap shift that
// makes the row relax to the law's force at the overlap. Returns the law's overlap at the last
// load, for the penetration.
double cohesive_row(const PairCoefficients &pc, double reff, double overlap, double last_force,
                    Contact &c)
{
  const std::array<double, kMaxRows> rigid = c.compliance;
  const double f = cohesive_force(pc, reff, -c.gap);
  material_compliance(pc, reff, overlap, std::max(cone_load(f, c.pull), c.pull), rigid,
                      c.compliance, c.elastic);
  c.gap_shift = -c.compliance[0] * f - c.gap;
  return cohesive_overlap(pc, reff, last_force);
}

// The restitution of an impact (no load in the last step) under compliance material, where
// it depends on the impact: a viscous dashpot's on its masses, radii and approach speed (the
// law's; under compliance auto the gran/* styles' kn is no material), and a cohesive law's,
// where the impact closes within the step, with the adhesion's work taken out (an integration
// per impact).
void impact_restitution(const ContactModel &model, const PairCoefficients &pc,
                        const SpookParams &params, double reff, const std::vector<Body> &bodies,
                        Contact &c)
{
  const double m_eff = effective_mass(bodies, c), approach = normal_approach(bodies, c);
  // Only a contact that approaches faster than bounce_speed bounces (spook_rhs); half of it
  // leaves room for the round-off between this approach and the rhs's G v. The rebound's
  // integration table costs a few powers a contact: 6% of a dense flow's step where every
  // contact took it.
  if (pc.restitution < 0 && !(c.pull > 0 && c.touched) && approach > 0.5 * params.bounce_speed) {
    const double reach = bodies[c.a].radius + (c.is_wall() ? 0.0 : bodies[c.b].radius);
    const double e = viscous_restitution(pc, m_eff, reff, approach, reach);
    if (e >= 0) c.restitution = e;
  }
  if (pc.cohesion != CohesionLaw::none && !c.touched && (!c.is_wall() || model.wall_cohesion) &&
      approach > params.bounce_speed && c.gap <= params.h * approach) {
    const double e = cohesive_restitution(pc, m_eff, reff, approach);
    if (e >= 0) c.restitution = e;
  }
}

// An impact that bounces within a step that resolves the collision: settled in that step, its
// tangential rows would stop the slip (a Mindlin spring is rigid without a load, and a one-step
// impact takes no dashpot), where the law's spring reverses it (doc/design.md, "Impacts at a
// deck's step"). It takes the law's tangential restitution instead.
void impact_slip(const PairCoefficients &pc, const SpookParams &params, double reff,
                 const std::vector<Body> &bodies, Contact &c)
{
  const double approach = normal_approach(bodies, c);
  if (!(c.restitution > 0 && approach > params.bounce_speed && c.gap <= params.h * approach))
    return;
  const Vec3 slip = relative_velocity(bodies, c);
  const double u = (slip - slip.dot(c.normal) * c.normal).norm();
  // the slip's reduced mass, 1 / m + r^2 / I of each solid sphere: 2/7 m_eff at any radii (one
  // table per law, where the lever's length at each contact's overlap made one per contact)
  const double m_eff = effective_mass(bodies, c);
  c.tangential_restitution =
      tangential_restitution(pc, m_eff, 2.0 / 7.0 * m_eff, reff, approach, u);
}

// compliance material's normal row of a contact without cohesion: its penetration and the
// law's compliance at its overlap and last force.
void elastic_row(const PairCoefficients &pc, const SpookParams &params, double reff, double overlap,
                 double force, double approach, Contact &c)
{
  const bool known = c.penetration > 0;
  track_penetration(params, law_overlap(pc, reff, force), overlap, approach, c);
  mark_split(params, known, c);
  // A deep new one is split as a rigid row's is: its whole overlap, so that its spring holds no
  // load's overlap in a cage the displacement cannot open (a sphere deposited into a bed then
  // pushed its cage apart at 11 m/s). The spring then carries what the contact closes from there.
  if (!known && c.split) c.penetration = overlap;
  const std::array<double, kMaxRows> rigid = c.compliance;
  // A penetration's row keeps the law's compliance at its overlap (its last force was the
  // recovery's), so that it leaves no faster than the law's spring would push it: a soft
  // material's overlap is removed slower than the recovery speed, as native's is.
  material_compliance(pc, reff, overlap, c.penetration > 0 ? 0.0 : force, rigid, c.compliance,
                      c.elastic);
}

void apply_pair(const ContactModel &model, const PairCoefficients &pc, const SpookParams &params,
                double reff, const std::vector<Body> &bodies, double last_normal, double last_raw,
                Contact &c)
{
  const double h = params.h;
  const double overlap = std::max(-c.gap, 0.0);
  const FrictionParams f = contact_friction(pc, reff, overlap);
  const TypedCoefficients &typed = model.typed;
  if (!typed.mu) c.friction.mu = f.mu;
  if (!typed.mu_roll) c.friction.mu_roll = f.mu_roll;
  if (!typed.mu_twist) c.friction.mu_twist = f.mu_twist;
  if (!typed.restitution && pc.restitution >= 0) c.restitution = pc.restitution;
  if (!c.is_wall() || model.wall_cohesion) apply_cohesion(pc, reff, c);
  if (!model.compliance.material) return;
  const bool cohesive = c.pull > 0;
  if (!model.typed.restitution && last_normal == 0)
    impact_restitution(model, pc, params, reff, bodies, c);
  const bool resolved = model.resolves_collisions(h);
  if (resolved && last_normal == 0) impact_slip(pc, params, reff, bodies, c);
  const int rows = model.rows;
  const double force = last_normal / h;
  if (cohesive) {
    const double explained = cohesive_row(pc, reff, overlap, last_raw / h, c);
    const bool known = c.penetration > 0;
    track_penetration(params, explained, overlap, normal_approach(bodies, c), c);
    mark_split(params, known, c);
  } else {
    elastic_row(pc, params, reff, overlap, force, normal_approach(bodies, c), c);
  }
  for (int r = rows; r < kMaxRows; ++r) c.elastic[r] = false;
  // A loaded contact's normal row is a Kelvin-Voigt element with the law's own dashpot (damping
  // time gamma_n / k), at least SPOOK's d, below which a contact stiffer than the step rings
  // (normal_relaxation spook, the default; law: see the end of this function). A
  // law without a dashpot is damped critically, tau = 2 sqrt(m_eff eps). Its springs keep at
  // least that critical damping (below). Bounces come from e.
  const double m_eff = effective_mass(bodies, c);
  double critical = 0.0;   // the normal row's, in steps
  double tau_n = INFINITY; // the normal row's damping time (seconds): the law's dashpot
  double gamma_n = -1.0;   // the law's normal dashpot, < 0: none
  if (c.elastic[0]) {
    const double eps = c.compliance[0];
    gamma_n = normal_damper(pc, m_eff, std::sqrt(reff * overlap), 1.0 / eps);
    critical = 2.0 * std::sqrt(m_eff * eps) / h;
    tau_n = gamma_n >= 0 ? gamma_n * eps : critical * h;
    if (tau_n / h > model.damping) c.damping = tau_n / h;
  }
  // The rolling and twisting springs take at least the contact's damping and the normal row's
  // critical damping: below it a pile at rest rocks on its rolling springs, and a sphere that
  // a bowl's rolling resistance stops rolls back up. The SDS springs carry the law's own damper
  // (SPOOK's damping time is the Kelvin-Voigt element's gamma / k) where that is longer. The
  // tangential springs keep that floor too, but where a solve's step resolves the collisions
  // and the law has a tangential dashpot (below).
  const double contact_d = std::max(model.damping, c.damping);
  const double floor = std::max(contact_d, critical);
  for (int r = 1; r <= 2 && r < rows; ++r) {
    if (!c.elastic[r]) continue;
    // At a step that resolves the collisions, a law's own tangential dashpot, at least SPOOK's
    // d and the critical floor up to kSpringFloor steps: there the whole floor damped an
    // undamped spring (dampflag 0) over some twenty steps, and LAMMPS's pour flow spun 24%
    // below native's (test_official_decks). At longer steps the floor is the scenes' (at 0.3
    // t_c a substep, lower floors threw a heavy sphere's bed 1.35 times native's fastest,
    // test_fault_ratios, and a taken-over pile rocked 1.03% of a diameter, test_fix_takeover;
    // the mixer's solves of 0.17 t_c in substeps of 0.04, contact_every, sank its bed 10.3%).
    const double tau_t = tangential_damper_time(pc, gamma_n, c.compliance[r]);
    if (tau_t >= 0 && resolved)
      c.spring_damping[r] = std::max({model.damping, tau_t / h, std::min(critical, kSpringFloor)});
    else if (floor > contact_d)
      c.spring_damping[r] = floor;
  }
  for (int r = 3; r < rows; ++r) {
    const double tau = spring_damping_time(pc, r);
    if (c.elastic[r] && tau > 0) {
      c.spring_damping[r] = std::max(floor, tau / h);
      c.damper_time[r] = tau;
    }
  }
  if (force == 0 && !(cohesive && c.touched)) // an impact, unless it approaches too slowly
    shorten_to_collision(pc, params, reff, m_eff, normal_approach(bodies, c), floor, rows, c);
  // normal_relaxation law: where SPOOK would floor the law's dashpot at `damping` steps (a
  // stiff flow's enduring contacts then relaxed over 2 h, many times the law's time:
  // examples/README.md, "The constraints' relaxation time at a large step"), the normal row is
  // the law's spring and dashpot by implicit Euler, which does not ring. Where the dashpot is
  // longer SPOOK resolves the law's swing (ContactSolver.LoadedHertzContactSwingsAsTheDampedLaw)
  // and implicit Euler would damp it. The other rows keep the contact's SPOOK damping.
  if (model.normal_relaxation == NormalRelaxation::law && c.elastic[0] &&
      tau_n < model.damping * h) {
    const double kept = params.damping_of(c);
    for (int r = 1; r < rows; ++r)
      if (c.spring_damping[r] < 0) c.spring_damping[r] = kept;
    c.damping = 0.75 + tau_n / h;
    c.implicit_normal = true;
  }
}

// A joint's rows, rigid (kJointCompliance) on the two spheres' inverse masses and inertias.
void hold_joint(const std::vector<Body> &bodies, double h, Contact &c)
{
  const Body &a = bodies[c.a], &b = bodies[c.b];
  const double w_t = 1.0 / a.mass + 1.0 / b.mass;
  const double w_r = 2.5 / (a.mass * a.radius * a.radius) + 2.5 / (b.mass * b.radius * b.radius);
  for (int r = 0; r < kMaxRows; ++r)
    c.compliance[r] = kJointCompliance * h * h * (r < 3 ? w_t : w_r);
}

} // namespace

void apply_contact_model(const ContactModel &model, const SpookParams &params, double m_min,
                         const std::vector<Body> &bodies, std::vector<Contact> &contacts,
                         const Vector *last, const std::vector<double> *r_eff)
{
  const double h = params.h;
  const ComplianceParams &p = model.compliance;
  double eps_n = p.eps_n, eps_t = p.eps_t;
  if (p.automatic || p.material) eps_n = eps_t = p.factor * h * h / m_min;
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    Contact &c = contacts[k];
    const double reff = r_eff ? (*r_eff)[k] : effective_radius(bodies, c);
    c.compliance[0] = eps_n;
    c.compliance[1] = c.compliance[2] = eps_t;
    for (int r = 3; r < kMaxRows; ++r) c.compliance[r] = eps_t / (reff * reff);
    if (c.is_joint()) { // rigid, bilateral, its error its own (joint_contact)
      hold_joint(bodies, h, c);
      continue;
    }
    c.friction = model.friction;
    c.restitution = model.restitution;
    c.tangential_restitution = std::numeric_limits<double>::quiet_NaN();
    c.elastic.fill(false);
    c.implicit_normal = false;
    c.damping = -1.0;
    c.spring_damping.fill(-1.0);
    c.damper_time.fill(0.0);
    c.pull = 0.0;
    c.gap_shift = 0.0;
    // The last normal impulse, none at round-off: a converged substep leaves 1e-16 where a
    // contact's trial impulse is zero, and such a load made the contact an enduring one,
    // without restitution and with the compliance of a vanishing load (0.1 where the rigid
    // row's is 1e-8), so that one impact bounced by Newton's law in the run and by the law's
    // spring in the converged step.
    const Eigen::Index normal = Eigen::Index(model.rows) * Eigen::Index(k);
    const double last_raw = last && last->size() > normal ? (*last)[normal] : 0.0;
    double last_normal = std::max(last_raw, 0.0);
    // a contact that carried a load within the step has touched (the history's, or a substep's)
    if (last_raw > 0.0 || last_raw < 0.0) c.touched = true;
    const double speed = std::abs(normal_approach(bodies, c)) + params.bounce_speed;
    if (last_normal <= kRoundoffLoad * effective_mass(bodies, c) * speed) last_normal = 0.0;
    const int ta = bodies[c.a].type;
    const int tb = !c.is_wall() ? bodies[c.b].type : c.wall_type > 0 ? c.wall_type : ta;
    const int ntypes = model.materials.ntypes();
    if (model.per_type() && ta >= 1 && tb >= 1 && ta <= ntypes && tb <= ntypes) {
      const PairCoefficients &pc = model.materials.at(ta, tb);
      if (pc.hooke_velocity > 0) // LIGGGHTS's hooke: this contact's own stiffnesses
        apply_pair(model, contact_law(pc, effective_mass(bodies, c), reff), params, reff, bodies,
                   last_normal, last_raw, c);
      else
        apply_pair(model, pc, params, reff, bodies, last_normal, last_raw, c);
    }
    // An impact is a contact that carried no load in the last step; an enduring one does not
    // bounce (without external forces bounce_speed is 0, and Newton's law on every contact of
    // a sheared pack threw its grains out of the cell).
    if (last_normal > 0.0) c.restitution = 0.0;
    if (!model.compliance.material)
      rigid_penetration(params, std::max(-c.gap, 0.0), normal_approach(bodies, c), last_normal / h,
                        c);
    // a spring's displacement lives on elastic rows only
    for (int r = 0; r < kMaxRows; ++r)
      if (!c.elastic[r]) c.spring[r] = 0.0;
  }
}

bool ContactModel::may_bounce() const
{
  if (restitution > 0) return true;
  if (!per_type() || typed.restitution) return false;
  for (int i = 1; i <= materials.ntypes(); ++i)
    for (int j = i; j <= materials.ntypes(); ++j)
      if (materials.at(i, j).restitution > 0 ||
          (compliance.material && materials.at(i, j).viscous != ViscousDamping::none))
        return true; // a viscous law rebounds under compliance material only (apply_pair)
  return false;
}

int ContactModel::rows_needed() const
{
  const bool pairs = per_type();
  bool rotational = (!pairs || typed.mu_roll) && friction.mu_roll > 0;
  rotational = rotational || ((!pairs || typed.mu_twist) && friction.mu_twist > 0);
  for (int i = 1; pairs && i <= materials.ntypes(); ++i)
    for (int j = i; j <= materials.ntypes(); ++j) {
      const PairCoefficients &p = materials.at(i, j);
      const bool twists = p.twist == TwistLaw::marshall ? p.mu > 0
                          : p.twist == TwistLaw::sds    ? p.twist_coeff > 0
                                                        : false;
      rotational = rotational || (!typed.mu_roll && p.mu_roll > 0) || (!typed.mu_twist && twists);
    }
  return rotational ? 6 : 3;
}

double external_speed_per_step(const std::vector<Body> &bodies, int num_owned, double h)
{
  double v = 0.0;
  for (int i = 0; i < num_owned; ++i) v = std::max(v, h * bodies[i].force.norm() / bodies[i].mass);
  return v;
}

} // namespace fibre
