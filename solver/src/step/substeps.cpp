#include "fibre/step/substeps.hpp"

#include <algorithm>
#include <cmath>

#include "fibre/algebra/kernels.hpp"

namespace fibre {

int substeps_for(const ContactModel &model, double h, double t_c, double cap)
{
  if (model.substeps > 0) return model.substeps;
  if (!(t_c > 0) || !(h > 0)) return 1;
  const double n = std::ceil(h / (std::min(model.substep_collisions, cap) * t_c) - 1e-9);
  return static_cast<int>(std::clamp(n, 1.0, double(kMaxSubsteps)));
}

bool step_moves(const std::vector<Body> &bodies, const std::vector<Contact> &contacts,
                const SpookParams &step, double speed)
{
  // A closing contact's SPOOK row acts once free flight would close more than its gap term
  // allows, (4 / h) Upsilon g: within h / (4 Upsilon) of touching.
  const double reach = step.h / (4.0 * step.upsilon());
  for (const Contact &c : contacts) {
    const double vn = normal_approach(bodies, c);      // > 0 closing
    if (c.gap > 0 && !(c.gap <= reach * vn)) continue; // apart within the step: free flight
    if (relative_velocity(bodies, c).norm() > speed) return true;
  }
  return false;
}

StepOptions check_options(const StepOptions &step)
{
  StepOptions ref = step;
  ref.solver = Method::pgs;
  ref.accuracy = kCheckAccuracy;
  ref.sweeps = kCheckSweeps;
  ref.focus_sweeps = 0;
  ref.restart_sweeps = 0;
  ref.residual = true;
  return ref;
}

void add_solve(StepResult &into, const StepResult &more)
{
  into.total_iterations += more.total_iterations;
  into.active_set_passes += more.active_set_passes;
  into.sweeps += more.sweeps;
  into.sweep_equivalents += more.sweep_equivalents;
  into.converged = into.converged && more.converged;
  if (into.reason == StopReason::converged) into.reason = more.reason;
  into.rescued = into.rescued || more.rescued;
  into.slow_restarts += more.slow_restarts;
  into.restarted = into.restarted || more.restarted;
  into.error_estimate = std::max(into.error_estimate, more.error_estimate);
  into.complementarity = std::max(into.complementarity, more.complementarity);
  into.setup_seconds += more.setup_seconds;
  into.solve_seconds += more.solve_seconds;
  into.sweep_seconds += more.sweep_seconds;
  into.total_seconds += more.total_seconds;
}

Substeps run_substeps(int n, const ContactModel &model, const SpookParams &params, double m_min,
                      const Exchange &ex, int num_owned, std::vector<Body> bodies,
                      std::vector<Contact> contacts, Vector warm, const SubstepSolve &solve)
{
  Substeps out;
  const double h = params.h;
  const int rows = model.rows;
  apply_contact_model(model, params, m_min, bodies, contacts, &warm);
  out.system = ContactSystem(std::move(bodies), std::move(contacts), rows, params, num_owned);
  ContactSystem &sys = out.system;
  SweepCache cache;
  const bool walls_move = sys.walls_move();
  Vector Gv_plus; // G v+ of the last substep
  for (int sub = 1; sub <= n; ++sub) {
    const bool last = sub == n;
    if (sub > 1) { // the last substep's motion and springs, then the model at its impulses
      std::vector<std::array<double, kMaxRows>> springs;
      if (model.compliance.material) springs = advance_springs(sys, out.v_plus, warm, &Gv_plus);
      const Vector &v_plus = out.v_plus;
      const Vector &Gv = Gv_plus;
      sys.next_substep(
          [&](std::vector<Body> &b, std::vector<Contact> &c) {
            for (std::size_t k = 0; k < c.size(); ++k) {
              c[k].gap = gap_after(c[k], h, Gv[Eigen::Index(rows) * Eigen::Index(k)], walls_move);
              if (!springs.empty()) {
                c[k].spring = springs[k];
                c[k].penetration = springs[k][0];
                c[k].spring[0] = 0.0;
              } else if (c[k].is_joint()) { // its error, as advance_springs's
                for (int r = 1; r < 3; ++r)
                  c[k].spring[r] += h * Gv[Eigen::Index(rows) * Eigen::Index(k) + r];
              }
            }
            for (std::size_t i = 0; i < b.size(); ++i) {
              b[i].v = v_plus.segment<3>(6 * Eigen::Index(i));
              b[i].omega = v_plus.segment<3>(6 * Eigen::Index(i) + 3);
            }
            apply_contact_model(model, params, m_min, b, c, &warm, &sys.effective_radii());
          },
          std::move(Gv_plus));
    }
    StepResult res = solve(sys, warm, last, cache);
    const bool solved = res.dv.size() == sys.body_dofs();
    if (out.done == 0)
      out.totals = res;
    else
      add_solve(out.totals, res);
    ++out.done;
    out.result = std::move(res);
    if (!solved || last) out.warm = std::move(warm); // the last solve's
    if (!solved) break;
    const StepResult &r = out.result;
    out.v_plus = velocities_after_change(sys, ex, r.dv);
    g_apply(sys, out.v_plus, Gv_plus);
    if (last && model.compliance.material)
      out.springs = advance_springs(sys, out.v_plus, r.lambda, &Gv_plus);
    const ContactWork work = contact_work(sys, Gv_plus, r.lambda);
    out.work.wall_work += work.wall_work;
    out.work.dissipation += work.dissipation;
    if (out.done == 1) {
      out.dv = r.dv;
      out.path = out.v_plus;
      out.lambda = r.lambda;
    } else {
      out.dv += r.dv;
      out.path += out.v_plus;
      out.lambda += r.lambda;
    }
    if (!last) warm = std::move(out.result.lambda); // the next substep's; this one is not kept
  }
  return out;
}

} // namespace fibre
