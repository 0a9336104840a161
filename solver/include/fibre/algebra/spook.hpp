// The SPOOK step around the contact solve (doc/design.md section 2): the right-hand side from
// the step's velocities and external forces, and the velocity change of given impulses.
#pragma once

#include <array>
#include <vector>

#include "fibre/core/exchange.hpp"
#include "fibre/core/system.hpp"

namespace fibre {

// Per-body velocity vector (v, omega) stacked, 6 per body.
Vector body_velocities(const ContactSystem &sys);

// b = -(4/h) Upsilon g - (1 - Upsilon) G v - G (h M^-1 f_ext + extra_dv), g the gap on normal
// rows and the spring's displacement on elastic rows.
// extra_dv (optional, 6 per body) is a velocity change from impulses held fixed outside the
// solve (capped friction rows); it must be complete on ghosts as well.
Vector spook_rhs(const ContactSystem &sys, const Vector *extra_dv = nullptr);

// The velocity change of impulses lambda: dv = M^-1 G^T lambda, summed over all processes and
// complete on owned bodies and ghosts. The one place this product is written.
Vector velocity_change(const ContactSystem &sys, const Exchange &ex, const Vector &lambda);

// v+ = v + h M^-1 f + M^-1 G^T lambda, the velocities after the step, complete on ghosts.
// Collective (velocity_change). lambda may be empty (no contacts): free flight.
Vector velocities_after(const ContactSystem &sys, const Exchange &ex, const Vector &lambda);
// The same from the step's velocity change dv = M^-1 G^T lambda on the owned bodies
// (StepResult::dv; empty: free flight), forwarded to the ghosts: no second product.
Vector velocities_after_change(const ContactSystem &sys, const Exchange &ex, Vector dv);

// The step's work of the contact impulses, this process's contacts (sum over processes):
// `wall_work` is done on the bodies by moving walls and obstacles, lambda . (G_b w_b) with w_b
// the wall's velocity; `dissipation` is lambda . the relative velocity at the step's mean
// velocity (v + v+) / 2, with a minus sign: the energy the contacts take out (dissipated, or
// stored in compliant rows). Their kinetic energy change is wall_work - dissipation, exactly,
// since the impulses change v linearly. Gv_plus: G v+, v+ = velocities_after(sys, ex, lambda).
struct ContactWork {
  double wall_work = 0.0;
  double dissipation = 0.0;
};
ContactWork contact_work(const ContactSystem &sys, const Vector &Gv_plus, const Vector &lambda);

// The elastic rows' displacements at the step's end, rows per contact in each contact's frame
// (Contact::spring): spring + h G v+ on every elastic row, with v+ = v + h M^-1 f + M^-1 G^T
// lambda the velocities after the step, ghosts included. On a cone at its limit the spring
// keeps only the displacement whose force the cone carries, -eps lambda / h (LAMMPS's history
// rescaling), so that a sliding contact snaps back by its elastic part only; a spring with a
// damper of its own (Contact::damper_time tau = gamma / k: SDS rolling and twisting) keeps that
// less the damper's share, tau G v+, as LAMMPS's SDS laws do, less what SPOOK's row already
// takes from its slowing. Zero on rows that are not elastic. Row 0 carries what is left of
// the contact's penetration (Contact::penetration). v_plus: velocities_after(sys, ex,
// lambda). Gv_plus: G v_plus where the caller has it.
std::vector<std::array<double, kMaxRows>> advance_springs(const ContactSystem &sys,
                                                          const Vector &v_plus,
                                                          const Vector &lambda,
                                                          const Vector *Gv_plus = nullptr);

} // namespace fibre
