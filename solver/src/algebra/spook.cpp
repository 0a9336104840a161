#include "fibre/algebra/spook.hpp"

#include <algorithm>
#include <cmath>

#include "fibre/algebra/cones.hpp"
#include "fibre/algebra/kernels.hpp"

namespace fibre {

namespace {

// G v of the bodies' velocities: the substep's, where next_substep gave it and no row is
// masked (ContactSystem::velocity_rows), else the product, computed into `own`.
const Vector &start_rows(const ContactSystem &sys, Vector &own)
{
  if (sys.row_mask().empty() && sys.velocity_rows().size() == sys.contact_dofs())
    return sys.velocity_rows();
  g_apply(sys, body_velocities(sys), own);
  return own;
}

// The rhs of tangential row r of contact k in the step its impact bounces: the slip vt leaves
// at -e_t vt (Contact::tangential_restitution), asked as the normal row's jump is.
double slip_rebound(const ContactSystem &sys, const Contact &k, Eigen::Index row, int r, double vt,
                    double ups, double b)
{
  const Vec3 &t = r == 1 ? k.t1 : k.t2;
  const auto weight = [&](int i) {
    const Vec3 arm = (k.point - sys.bodies()[i].x).cross(t);
    const double *w = &sys.inv_mass()[kBodyDofs * i];
    return w[0] + arm[0] * arm[0] * w[3] + arm[1] * arm[1] * w[4] + arm[2] * arm[2] * w[5];
  };
  const double w_tt = weight(k.a) + (k.is_wall() ? 0.0 : weight(k.b)); // G_t M^-1 G_t^T
  return (b - (ups + k.tangential_restitution) * vt) * (1.0 + sys.sigma()[row + r] / w_tt);
}

} // namespace

Vector body_velocities(const ContactSystem &sys)
{
  Vector v(sys.body_dofs());
  for (int i = 0; i < sys.num_bodies(); ++i) {
    v.segment<3>(6 * i) = sys.bodies()[i].v;
    v.segment<3>(6 * i + 3) = sys.bodies()[i].omega;
  }
  return v;
}

Vector spook_rhs(const ContactSystem &sys, const Vector *extra_dv)
{
  const SpookParams &p = sys.params();
  const double ups = p.upsilon();
  const Vector v = body_velocities(sys);
  Vector w = (1.0 - ups) * v + sys.external_velocity_change();
  if (extra_dv) w += *extra_dv;
  Vector b;
  g_apply(sys, w, b);
  b = -b;
  // G v, where a contact bounces or has its own damping (else empty)
  const bool needs_Gv =
      std::any_of(sys.contacts().begin(), sys.contacts().end(), [](const Contact &k) {
        return k.restitution > 0 || k.own_damping() || k.wall_moves() || k.implicit_normal;
      });
  Vector own;
  const Vector &Gv = needs_Gv ? start_rows(sys, own) : own;
  const int rows = sys.rows();
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    const Eigen::Index row = Eigen::Index(rows) * c; // normal row
    const double ups_c = p.upsilon(p.damping_of(k));
    double ups_r[kMaxRows]; // each row's Upsilon: the contact's but where a spring has its own
    for (int r = 0; r < rows; ++r)
      ups_r[r] = r > 0 && k.spring_damping[r] >= 0 ? p.upsilon(k.spring_damping[r]) : ups_c;
    if (k.own_damping()) // -(1 - Upsilon_r) G v on every row of the contact
      for (int r = 0; r < rows; ++r) b[row + r] += (ups_r[r] - ups) * Gv[row + r];
    // A moving wall is body b with a prescribed velocity, the same after the step:
    // -(1 - Upsilon) G v of the relative velocity, G_b w_b = -wall_rows.
    const std::array<double, kMaxRows> wall = wall_rows(k);
    if (k.wall_moves())
      for (int r = 0; r < rows; ++r) b[row + r] += (1.0 - ups_r[r]) * wall[r];
    // Row: G_n v+ + eps lambda_n = G_n (v + h M^-1 f) + b_n, so b_n = 0 is free flight and
    // Newton's law G_n v+ = -e vn (vn = G_n v) is b_n = b_n(no gap) - (Upsilon + e) vn.
    // A contact that bounces keeps its approach speed until the step in which it closes:
    // SPOOK alone would brake it a step early (b > 0 asks for more than free flight).
    const double vn = Gv.size() ? Gv[row] - wall[0] : 0.0; // relative normal velocity
    const double vn_free = ups_c * vn - b[row];            // the same after free flight
    const bool bounces = k.restitution > 0 && -vn > p.bounce_speed;
    const bool impact = bounces && k.gap + p.h * vn_free <= 0 && sys.row_active(row);
    const int joint_rows = k.is_joint() ? 3 : 1; // a joint's t1, t2 carry its error
    for (int r = 1; r < rows; ++r) {
      if (!sys.row_active(row + r)) continue;
      if (impact && r <= 2 && !std::isnan(k.tangential_restitution))
        b[row + r] = slip_rebound(sys, k, row, r, Gv[row + r] - wall[r], ups_r[r], b[row + r]);
      else if (k.elastic[r] || r < joint_rows)
        b[row + r] += p.spring_term(k.spring[r], ups_r[r]);
    }
    if (!sys.row_active(row)) continue;
    const double b_spook = b[row] + p.gap_term(k, ups_c);
    if (impact) {
      // The compliance would keep Sigma / (w + Sigma) of the jump, w = 1/m_a + 1/m_b the
      // row's G M^-1 G^T: ask for that much more (exact for an isolated contact).
      const double w_nn =
          sys.inv_mass()[kBodyDofs * k.a] + (k.is_wall() ? 0.0 : sys.inv_mass()[kBodyDofs * k.b]);
      const double jump = (b[row] - (ups_c + k.restitution) * vn) * (1.0 + sys.sigma()[row] / w_nn);
      b[row] = std::max(b_spook, jump);
    } else if (bounces && k.gap > 0) {
      // Free flight, but not through the contact within the step when other contacts stop
      // the partner: G_n v+ >= -gap / h.
      b[row] = std::max(std::min(b_spook, 0.0), -k.gap / p.h - vn_free);
    } else {
      // an implicit normal row keeps no memory of the approach speed
      b[row] = b_spook - (k.implicit_normal ? ups_c * vn : 0.0);
    }
  }
  return b;
}

Vector velocity_change(const ContactSystem &sys, const Exchange &ex, const Vector &lambda)
{
  Vector dv;
  gt_apply(sys, lambda, dv);
  ex.reverse_sum(dv);
  dv.array() *= sys.inv_mass().array();
  ex.forward(dv);
  return dv;
}

Vector velocities_after(const ContactSystem &sys, const Exchange &ex, const Vector &lambda)
{
  Vector v_plus = body_velocities(sys) + sys.external_velocity_change();
  if (lambda.size() == sys.contact_dofs()) v_plus += velocity_change(sys, ex, lambda);
  return v_plus;
}

Vector velocities_after_change(const ContactSystem &sys, const Exchange &ex, Vector dv)
{
  Vector v_plus = body_velocities(sys) + sys.external_velocity_change();
  if (dv.size() == v_plus.size()) {
    ex.forward(dv);
    v_plus += dv;
  }
  return v_plus;
}

ContactWork contact_work(const ContactSystem &sys, const Vector &Gv_plus, const Vector &lambda)
{
  ContactWork work;
  if (lambda.size() != sys.contact_dofs()) return work;
  Vector own;
  const Vector &Gv = start_rows(sys, own);
  const int rows = sys.rows();
  const std::array<double, kMaxRows> at_rest{};
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const std::array<double, kMaxRows> wall =
        sys.walls_move() ? wall_rows(sys.contacts()[c]) : at_rest;
    for (int r = 0; r < rows; ++r) {
      const Eigen::Index row = Eigen::Index(rows) * c + r;
      const double l = lambda[row];
      work.wall_work += l * wall[r];
      work.dissipation -= l * (0.5 * (Gv[row] + Gv_plus[row]) - wall[r]);
    }
  }
  return work;
}

std::vector<std::array<double, kMaxRows>> advance_springs(const ContactSystem &sys,
                                                          const Vector &v_plus,
                                                          const Vector &lambda,
                                                          const Vector *Gv_plus)
{
  const int rows = sys.rows(), nc = sys.num_contacts();
  std::vector<std::array<double, kMaxRows>> springs(nc);
  Vector own, own0;
  const Vector *Gv0 =
      nullptr; // G v at the step's start, for the springs with a damper of their own
  if (!Gv_plus) g_apply(sys, v_plus, own);
  const Vector &Gv = Gv_plus ? *Gv_plus : own;
  const double h = sys.params().h;
  const std::array<double, kMaxRows> at_rest{};
  for (int c = 0; c < nc; ++c) {
    const Contact &k = sys.contacts()[c];
    const Eigen::Index base = Eigen::Index(rows) * c;
    const std::array<double, kMaxRows> wall = sys.walls_move() ? wall_rows(k) : at_rest;
    if (k.penetration > 0) // what is left of it at the step's end (row 0: no spring)
      springs[c][0] = std::min(k.penetration, std::max(0.0, -(k.gap + h * (Gv[base] - wall[0]))));
    if (k.is_joint()) { // its error at the step's end (joint_contact)
      for (int r = 1; r < 3; ++r) springs[c][r] = k.spring[r] + h * Gv[base + r];
      continue;
    }
    if (!k.any_elastic()) continue;
    const double lambda_n = lambda.size() == sys.contact_dofs()
                                ? std::max(cone_load(lambda[base], h * k.pull), 0.0)
                                : 0.0;
    for (int cone = 0; cone < num_cones(rows); ++cone) {
      const Cone &rows_of = kCones[cone];
      if (!k.elastic[rows_of.first]) continue;
      Eigen::Vector2d xi = Eigen::Vector2d::Zero(), l = Eigen::Vector2d::Zero();
      Eigen::Vector2d w = Eigen::Vector2d::Zero(); // the rows' velocity at the step's end
      for (int i = 0; i < rows_of.size; ++i) {
        const int r = rows_of.first + i;
        w[i] = Gv[base + r] - wall[r];
        xi[i] = k.spring[r] + h * w[i];
        if (lambda.size() == sys.contact_dofs()) l[i] = lambda[base + r];
      }
      // The law's force, spring and damper together, -(xi + tau w) / eps, may not exceed the
      // cone's radius per unit time. A spring that pushes along the motion while its damper
      // holds the sum inside the cone is not at its limit: it unloads as the contact moves.
      // (Tested on the spring alone, that spring was put back at the cone every step and drove
      // a sphere back up an obstacle.)
      const double eps = k.compliance[rows_of.first];
      const double coeff = cone_coefficient(k.friction, sys.effective_radius(c), cone);
      const double limit = eps * coeff * lambda_n / h;
      const double tau = k.damper_time[rows_of.first];
      // (a load inside the cone by a margin far above round-off spares the square root)
      const Eigen::Vector2d load = xi + tau * w;
      if (!(load.squaredNorm() <= (1 - 1e-12) * limit * limit) && load.norm() > limit) {
        const double ln = l.norm(), xn = xi.norm();
        if (ln > 0)
          xi = -limit / ln * l;
        else if (xn > limit)
          xi *= limit / xn;
        // A spring with a damper of its own (SDS rolling, twisting) keeps, as LAMMPS's, the
        // cone's force less the damper's (tau w): the two together are the cone's. Where the
        // damper alone exceeds the cone, the spring then pushes along the motion. tau is the
        // law's gamma / k, not SPOOK's floored damping, which is no force of the law. On a row
        // that slows by s a step, SPOOK's next force is -k (xi + d h w - h (1 + 4 d) s / 4):
        // the spring keeps that last share back, or a rolling sphere falls short of the cone's
        // torque (by 13% at the decks' step).
        if (ln > 0 && tau > 0) {
          if (!Gv0) Gv0 = &start_rows(sys, own0);
          Eigen::Vector2d w0 = Eigen::Vector2d::Zero();
          for (int i = 0; i < rows_of.size; ++i)
            w0[i] = (*Gv0)[base + rows_of.first + i] - wall[rows_of.first + i];
          const double speed = w.norm();
          if (speed > 0) {
            const double d = sys.params().damping_of(k, rows_of.first);
            const double slowing = std::max(0.0, (w0 - w).dot(w) / speed);
            const double share = std::max(0.0, tau * speed - h * (1.0 + 4.0 * d) / 4.0 * slowing);
            xi -= share / speed * w;
          }
        }
      }
      for (int i = 0; i < rows_of.size; ++i) springs[c][rows_of.first + i] = xi[i];
    }
  }
  return springs;
}

} // namespace fibre
