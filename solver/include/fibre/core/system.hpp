// Bodies, contacts and the SPOOK contact system (doc/design.md section 2, thesis 2.1-2.2).
//
// Plain data: a ContactSystem owns its bodies and contacts and the derived per-contact
// kinematics, Sigma and right-hand side. Nothing here knows about MPI or LAMMPS; bodies
// [0, num_owned) are owned by this process, the rest are halo copies (ghosts).
#pragma once

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace fibre {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vector = Eigen::VectorXd;

inline constexpr int kBodyDofs = 6; // (velocity, angular velocity)
inline constexpr int kMaxRows = 6;  // rows per contact: n, t1, t2, twist, roll1, roll2

// A rigid sphere. Inertia is (2/5) m r^2 (solid sphere).
struct Body {
  double mass = 1.0;
  double radius = 1.0;
  Vec3 x = Vec3::Zero();
  Vec3 v = Vec3::Zero();
  Vec3 omega = Vec3::Zero();
  Vec3 force = Vec3::Zero();  // external force (gravity, other fixes), held over the step
  Vec3 torque = Vec3::Zero(); // external torque
  int type = 0;               // the front end's atom type (1..ntypes), 0 when it has none
};

// The friction, rolling and twisting coefficients of one contact. A zero coefficient means no
// resistance: those rows carry no impulse. r_eff = ra rb / (ra + rb) for a pair, ra against a
// wall.
struct FrictionParams {
  double mu = 0.5;       // Coulomb: |lambda_t| <= mu lambda_n
  double mu_roll = 0.0;  // rolling: |lambda_roll| <= mu_roll r_eff lambda_n
  double mu_twist = 0.0; // twisting: |lambda_twist| <= mu_twist r_eff lambda_n
};

// One contact: body a against body b, or body a against a wall (b == -1).
struct Contact {
  int a = -1;
  int b = -1;                  // -1: wall
  Vec3 normal = Vec3::UnitZ(); // unit, pointing from b (or the wall) to a
  Vec3 t1 = Vec3::UnitX();     // tangent frame, orthonormal with normal
  Vec3 t2 = Vec3::UnitY();
  Vec3 point = Vec3::Zero();                 // contact point
  double gap = 0.0;                          // signed distance, negative = overlap
  std::array<double, kMaxRows> compliance{}; // per-row eps (1/stiffness)
  FrictionParams friction{};
  // Newton's impact law on the normal row: a contact that closes within the step at a speed
  // above SpookParams::bounce_speed separates at restitution times that speed. 0: plastic.
  double restitution = 0.0;
  // The law's tangential restitution (tangential_restitution), where the step resolves the
  // collision: in the step in which it bounces, the impact's slip leaves at minus this times
  // its approach, within the cone. NaN: none (the tangential rows' SPOOK target).
  double tangential_restitution = std::numeric_limits<double>::quiet_NaN();
  // A wall contact's partner type for per-type coefficients: an obstacle atom's type, or 0
  // for a wall (which takes the sphere's type).
  int wall_type = 0;
  // This contact's SPOOK damping d (steps), or < 0 for the system's (SpookParams::damping):
  // compliance material damps soft contacts critically.
  double damping = -1.0;
  // A moving wall or obstacle: its velocity at the contact point and its angular velocity
  // (zero for walls at rest). They enter the rhs as the velocity of body b (spook_rhs).
  Vec3 wall_v = Vec3::Zero();
  Vec3 wall_omega = Vec3::Zero();
  // A wall's radius of curvature at the contact: an obstacle sphere's radius (an atom outside
  // the fix's group), a region's as LAMMPS gives it to fix wall/gran/region (negative where
  // the surface is concave: -R inside a sphere, -2 R inside a cylinder), 0 for a flat wall.
  // The effective radius of the contact's Hertz, rolling and twisting laws is
  // ra wall_radius / (ra + wall_radius), as LAMMPS's.
  double wall_radius = 0.0;
  // Elastic rows (compliance material): a row whose compliance is the law's spring carries
  // its displacement at the step's start, in the contact frame, in the rhs as the normal row
  // carries the gap: rows 1, 2 the tangential displacement (length), 3 the twisting and 4, 5
  // the rolling angle. Without the displacement a compliance would be a viscosity. An elastic
  // normal row (row 0, its displacement the gap, spring[0] unused) is the law's spring: its
  // overlap is the load's, not an error, so max_recovery does not bound it (but its
  // penetration).
  std::array<bool, kMaxRows> elastic{};
  std::array<double, kMaxRows> spring{};
  // The part of an elastic normal row's overlap that no load explains (a start or an insertion
  // into other bodies, a jump in size): a penetration, whose gap term is bounded as a rigid
  // row's, so that it is removed no faster than max_recovery (nor than the law's spring at the
  // row's compliance pushes), where the spring alone would release the overlap's whole energy
  // within a few steps. It only shrinks (contact_model.cpp; the history keeps it). A rigid
  // normal row's penetration is its overlap, removed by the split recovery's displacement
  // (step/recovery.hpp); its velocity row asks only that it does not close.
  double penetration = 0.0;
  // Whether an elastic row's penetration is split (opened by the split recovery, its row asking
  // only that it does not close): set by the contact model when the penetration is first found
  // deep, kept by the history until it is shallow, never set on a penetration found shallow
  // (in a soft deep bed thousands are, and splitting them all each step both cost the
  // recovery's solve each step and took the load's overlap out of their springs).
  bool split = false;
  // An elastic normal row relaxed as the law's Kelvin-Voigt element (spring 1 / eps, dashpot
  // time tau) by implicit Euler, G v+ (h + tau) + eps lambda / h = -gap: SPOOK's row at
  // damping = 3/4 + tau / h without the memory Upsilon G v of the approach speed (spook_rhs).
  // It does not ring at any tau, where SPOOK's rings below 2 steps (design section 2).
  bool implicit_normal = false;
  // Cohesion (model/cohesion.hpp): the largest tension the normal row carries (a force; 0:
  // none), so that lambda_n >= -h pull and the friction cones' radii follow lambda_n + 2 h pull
  // (LAMMPS's |F_ne + 2 F_pulloff|); an elastic row's gap shift, so that it relaxes to the
  // law's force F(d) at its overlap (gap + gap_shift = -eps F(d)); and whether the history held
  // the contact (it pressed or pulled in the last step): a JKR contact that has touched holds
  // until its reach.
  double pull = 0.0;
  double gap_shift = 0.0;
  bool touched = false;
  // An elastic row's own SPOOK damping d (steps), or < 0 for the contact's: the pair style's
  // rolling and twisting dampers (a spring and a damper are SPOOK's compliance and damping
  // time). Rows 1..5; row 0 takes the contact's.
  std::array<double, kMaxRows> spring_damping{-1.0, -1.0, -1.0, -1.0, -1.0, -1.0};
  // The law's own damper of an elastic row, its time gamma / k (seconds; 0: none): a spring at
  // its cone keeps the cone's force less the damper's (advance_springs). Not in the system
  // file: the solve does not read it.
  std::array<double, kMaxRows> damper_time{};
  // Whether some row is damped otherwise than the system's SpookParams::damping.
  bool own_damping() const
  {
    bool own = damping >= 0;
    for (double d : spring_damping) own = own || d >= 0;
    return own;
  }
  bool any_elastic() const
  {
    for (bool e : elastic)
      if (e) return true;
    return false;
  }
  bool is_wall() const { return b < 0; }
  // A joint (joint_contact): its pull is infinite, so that every row is bilateral.
  bool is_joint() const { return std::isinf(pull); }
  bool wall_moves() const
  {
    return b < 0 && (wall_v != Vec3::Zero() || wall_omega != Vec3::Zero());
  }
};

// The rows of G times a moving wall's motion: (D wall_v, D wall_omega) for rows n, t1, t2,
// twist, roll1, roll2 (D the contact frame), the part of the relative velocity that the wall
// contributes with a minus sign. Zero for a pair or a wall at rest.
std::array<double, kMaxRows> wall_rows(const Contact &c);
// Contact k's gap after a step h at its normal row's velocity Gv_n, less a moving wall's
// (walls_move: ContactSystem::walls_move).
inline double gap_after(const Contact &k, double h, double Gv_n, bool walls_move)
{
  return k.gap + h * (Gv_n - (walls_move ? wall_rows(k)[0] : 0.0));
}

// r_eff = ra rb / (ra + rb) for a pair, ra against a wall (b == nullptr).
inline double effective_radius(double ra, const double *rb)
{
  return rb ? ra * *rb / (ra + *rb) : ra;
}
// A contact's: its wall's curvature radius (Contact::wall_radius) counts as rb where it has one.
double effective_radius(const std::vector<Body> &bodies, const Contact &c);

// A deterministic orthonormal completion (t1, t2) of the unit vector n.
void tangent_frame(const Vec3 &n, Vec3 &t1, Vec3 &t2);

// Contact between two spheres (a, b); point halfway through the overlap.
Contact sphere_sphere_contact(const std::vector<Body> &bodies, int a, int b);
// The same from the normal and gap that sphere_sphere_gap gave (the search has them already).
Contact sphere_sphere_contact(const std::vector<Body> &bodies, int a, int b, const Vec3 &normal,
                              double gap);
// Its normal (from b to a) and gap alone: the search rejects most candidate pairs on these
// before it builds a contact (its tangent frame cost 3.5% of a run when built for every pair).
void sphere_sphere_gap(const Body &a, const Body &b, Vec3 &normal, double &gap);
// Contact between sphere a and a wall: `normal` points from the wall into the sphere and
// `distance` is the centre's distance from the wall surface along it.
Contact sphere_wall_contact(const std::vector<Body> &bodies, int a, const Vec3 &normal,
                            double distance);

// A lock joint of a clump (rigid spheres held together): body a, a member, to body b, its hub,
// at a's centre. Every row is bilateral (pull = infinity: the cones bound nothing), rows n, t1,
// t2 hold a's centre on the hub and rows 3..5 turn both alike. `axis` is the member's rest
// offset from the hub, turned with the hub (its frame's normal: the rows keep their directions
// from step to step, and so do their warm starts); `error` is how far a's centre is from where
// the hub holds it. The normal row's gap and t1, t2's spring carry the error's components, so
// that SPOOK's stabilization removes it within a few steps (spook_rhs).
Contact joint_contact(const std::vector<Body> &bodies, int a, int b, const Vec3 &axis,
                      const Vec3 &error);

// Per-contact kinematics: G_a w_a = [D (v_a + omega_a x ra) ; D omega_a] with D the frame
// (rows n, t1, t2); G_b the same with minus sign and rb. This is thesis eq. 2.1.1 written
// with 15 numbers instead of two 6x6 blocks.
struct ContactKinematics {
  Mat3 frame; // rows: n, t1, t2
  Vec3 ra;    // p - x_a
  Vec3 rb;    // p - x_b (unused for walls)
};

// SPOOK parameters (doc/design.md section 2).
struct SpookParams {
  double h = 1e-3;      // time step
  double damping = 2.0; // d = tau / h, in steps (thesis uses tau = 2h)
  // The largest separation speed the gap term of the rhs may ask for, (4 / h) Upsilon |g| of
  // an overlap g < 0: deep overlaps are removed over several steps instead of launching the
  // bodies (Chrono's maximum penetration recovery speed). 0: unbounded.
  double max_recovery = 0.0;
  // Approach speeds at or below this are plastic whatever the contact's restitution (resting
  // contacts must not bounce on the speed gravity adds in a step).
  double bounce_speed = 0.0;
  // A rigid row's overlap is a penetration (step/recovery.hpp) beyond this many steps of
  // max_recovery (and what its load and the step's closing explain): kPenetrationStart
  // (contact_model.hpp) in a run's ordinary steps, kPenetrationFloor while penetrations are
  // being recovered. (An elastic row's split is its own: Contact::split.)
  double penetration_floor = 10.0;
  // A contact's damping: its own when set (Contact::damping >= 0), else the system's.
  double damping_of(const Contact &c) const { return c.damping >= 0 ? c.damping : damping; }
  // Row r's: its spring's own (Contact::spring_damping) where it has one, else the contact's.
  double damping_of(const Contact &c, int r) const
  {
    return r > 0 && c.spring_damping[r] >= 0 ? c.spring_damping[r] : damping_of(c);
  }
  // Whether contact c's penetration is removed by the split recovery's displacement
  // (step/recovery.hpp), not by its row's velocity: a rigid row's (the contact model sets it
  // beyond penetration_floor steps of max_recovery), and an elastic row's marked split
  // (Contact::split; shallower ones are pushed open by the row's bounded velocity, below).
  bool split_penetration(const Contact &c) const
  {
    if (!(c.penetration > 0)) return false;
    return !c.elastic[0] || c.split;
  }
  // The gap term of the normal row's rhs, -(4 / h) Upsilon g, bounded by max_recovery unless
  // the row is the material's spring (Contact::elastic[0]): bounding an elastic overlap would
  // bound the force the contact can carry, and a wedged sphere would stay deep in.
  // An elastic row's penetration (Contact::penetration) is bounded as a rigid row's overlap,
  // or, split, left out: the row asks only that it does not close.
  // The bound is (1 - Upsilon) max_recovery: the row keeps Upsilon of its speed from step to
  // step (spook_rhs), so that its speed approaches max_recovery from below, where a bound of
  // max_recovery itself gave (1 + 4 d) / (4 d) times it.
  double gap_term(double gap, double ups, bool elastic = false, double penetration = 0.0,
                  bool split = false) const
  {
    const double cap = (1.0 - ups) * max_recovery;
    const auto bounded = [cap](double term) { return cap > 0 && term > cap ? cap : term; };
    if (!elastic) return bounded(-4.0 / h * ups * (gap + penetration)); // recovery.hpp
    if (!(penetration > 0)) return -4.0 / h * ups * gap;
    if (split) return -4.0 / h * ups * (gap + penetration);
    return -4.0 / h * ups * (gap + penetration) + bounded(4.0 / h * ups * penetration);
  }
  double gap_term(double gap) const { return gap_term(gap, upsilon()); }
  // Contact c's: its gap with cohesion's shift, its elastic normal row and penetration.
  double gap_term(const Contact &c, double ups) const
  {
    return gap_term(c.gap + c.gap_shift, ups, c.elastic[0], c.penetration, split_penetration(c));
  }
  // The same term of an elastic row's displacement, unbounded (the cone bounds the spring).
  double spring_term(double displacement, double ups) const
  {
    return -4.0 / h * ups * displacement;
  }
  double upsilon(double d) const { return 1.0 / (1.0 + 4.0 * d); }
  double upsilon() const { return upsilon(damping); }
  // Sigma entry for compliance eps: 4 eps / (h^2 (1 + 4 d)).
  double sigma(double eps, double d) const { return 4.0 * eps / (h * h * (1.0 + 4.0 * d)); }
  double sigma(double eps) const { return sigma(eps, damping); }
};

class ContactSystem {
 public:
  ContactSystem() = default;
  // rows: 3 (translational only) or 6. num_owned: bodies [0, num_owned) are owned;
  // -1 means all. Computes kinematics, inverse masses and Sigma; the rhs is zero until
  // spook_rhs() or set_rhs() is called.
  ContactSystem(std::vector<Body> bodies, std::vector<Contact> contacts, int rows,
                const SpookParams &params, int num_owned = -1);

  int rows() const { return rows_; }
  int num_bodies() const { return static_cast<int>(bodies_.size()); }
  int num_owned_bodies() const { return num_owned_; }
  int num_contacts() const { return static_cast<int>(contacts_.size()); }
  Eigen::Index contact_dofs() const { return Eigen::Index(rows_) * num_contacts(); }
  Eigen::Index body_dofs() const { return Eigen::Index(kBodyDofs) * num_bodies(); }
  const SpookParams &params() const { return params_; }

  const std::vector<Body> &bodies() const { return bodies_; }
  const std::vector<Contact> &contacts() const { return contacts_; }
  const ContactKinematics &kinematics(int c) const { return kin_[c]; }
  // Names the kinematics: every system built gets its own; next_substep keeps it (and a copy
  // shares it). What the solves derive from the kinematics alone may be kept under it
  // (SweepCache).
  std::uint64_t kinematics_id() const { return kinematics_id_; }
  // Contact c's side a and side b of the diagonal of G M^-1 G^T, every row active (their sum
  // and Sigma are A_ii: diagonal_entries), and its effective radius (fibre::effective_radius).
  // Derived once per system: the substeps of a step share them.
  const std::array<Vec6, 2> &diagonal_sides(int c) const { return sides_[c]; }
  double effective_radius(int c) const { return r_eff_[c]; }
  const std::vector<double> &effective_radii() const { return r_eff_; }
  // Whether some contact's wall or obstacle moves (Contact::wall_moves): else every wall_rows
  // is zero, and the passes that would read them skip the contacts.
  bool walls_move() const { return walls_move_; }
  const Vector &inv_mass() const { return inv_mass_; } // diagonal of M^-1, 6 per body
  // h M^-1 (force, torque) of every body: the external forces' velocity change in a step.
  const Vector &external_velocity_change() const { return external_dv_; }
  // diagonal of M, 6 per body: an expression of inv_mass (1 / x), not a second vector
  auto mass() const { return inv_mass_.cwiseInverse(); }
  const Vector &sigma() const { return sigma_; } // diagonal of Sigma, rows per contact
  const Vector &rhs() const { return rhs_; }
  void set_rhs(const Vector &b) { rhs_ = b; }
  void set_rhs(Vector &&b) { rhs_ = std::move(b); }
  // The coefficients of contact c, or of every contact (they enter no derived quantity).
  void set_friction(int c, const FrictionParams &f) { contacts_[c].friction = f; }
  void set_friction(const FrictionParams &f);

  // Flat data for the matrix-free kernels (derived, kept in step with contacts and mask):
  // the two bodies of every contact (a, b; b = -1 for walls) as 2 ints per contact, 1 / Sigma
  // per row, and the row weights (1 active, 0 masked) per row, empty when no row is masked.
  const int *body_pairs() const { return pairs_.data(); }
  const Vector &inv_sigma() const { return inv_sigma_; }
  const Vector &row_weight() const { return row_weight_; }

  // Active-set support: a masked row has a zero Jacobian row, Sigma 1 and rhs 0, so it is
  // decoupled (its lambda solves to 0) while every block structure stays intact. A mask with
  // every row active is kept as none (empty): the kernels then skip the row weights.
  const std::vector<unsigned char> &row_mask() const { return mask_; }
  void set_row_mask(const std::vector<unsigned char> &active); // 1 = active row

  // The next substep of a step (substeps.hpp), in place: the bodies' velocities and the
  // contacts' gaps, springs, compliances and damping change; the bodies' positions, masses and
  // external forces and the contacts' bodies, frames and points do not, so the kinematics hold.
  // `edit` changes them; Sigma then follows the new compliances and damping. velocity_rows: G times
  // the new velocities, which the caller has (the last substep's G v+); taken over after the edit,
  // which may read it.
  template <typename Edit> void next_substep(Edit &&edit, Vector &&velocity_rows)
  {
    edit(bodies_, contacts_);
    compute_rows();
    velocity_rows_ = std::move(velocity_rows);
  }
  // The contacts' compliances and damping changed in place by `edit` (nothing else of them):
  // Sigma follows; the kinematics, the rhs and velocity_rows hold.
  template <typename Edit> void edit_compliances(Edit &&edit)
  {
    edit(contacts_);
    compute_rows();
  }
  // G v of the bodies' velocities, every row active, where known (a substep after the first:
  // next_substep), else empty.
  const Vector &velocity_rows() const { return velocity_rows_; }
  bool row_active(Eigen::Index row) const { return mask_.empty() || mask_[row] != 0; }

 private:
  void compute_derived(); // everything below from the bodies and contacts, then compute_rows
  void compute_rows();    // Sigma and the row weights, from the row mask

  int rows_ = 6;
  int num_owned_ = 0;
  SpookParams params_;
  std::vector<Body> bodies_;
  std::vector<Contact> contacts_;
  std::vector<ContactKinematics> kin_;
  std::uint64_t kinematics_id_ = 0;
  std::vector<std::array<Vec6, 2>> sides_;
  std::vector<double> r_eff_;
  bool walls_move_ = false;
  std::vector<unsigned char> mask_; // empty = all rows active
  Vector inv_mass_;
  Vector external_dv_;
  Vector sigma_;
  Vector inv_sigma_;
  Vector row_weight_;      // empty = all rows active
  std::vector<int> pairs_; // a, b per contact
  Vector rhs_;
  Vector velocity_rows_;
};

} // namespace fibre
