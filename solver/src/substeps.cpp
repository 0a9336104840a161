#include "fibre/substeps.hpp"

#include <algorithm>
#include <cmath>

#include "fibre/kernels.hpp"

namespace fibre {

int substeps_for(const ContactModel &model, double h, double t_c)
{
  if (model.substeps > 0) return model.substeps;
  if (!(t_c > 0) || !(h > 0)) return 1;
  const double n = std::ceil(h / (model.substep_collisions * t_c) - 1e-9);
  return static_cast<int>(std::clamp(n, 1.0, double(kMaxSubsteps)));
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
  into.restarted = into.restarted || more.restarted;
  into.error_estimate = std::max(into.error_estimate, more.error_estimate);
  into.complementarity = std::max(into.complementarity, more.complementarity);
  into.setup_seconds += more.setup_seconds;
  into.solve_seconds += more.solve_seconds;
  into.sweep_seconds += more.sweep_seconds;
  into.total_seconds += more.total_seconds;
}

Substeps run_substeps(int n, const ContactModel &model, const SpookParams &params, double m_min,
                      const Exchange &ex, int num_owned, std::vector<Body> &bodies,
                      std::vector<Contact> &contacts, Vector &warm, const SubstepSolve &solve)
{
  Substeps out;
  const double h = params.h;
  const int rows = model.rows;
  for (int sub = 1; sub < n; ++sub) {
    std::vector<Contact> modelled = contacts; // the model rewrites compliances and restitution
    apply_contact_model(model, params, m_min, bodies, modelled, &warm);
    ContactSystem sys(bodies, std::move(modelled), rows, params, num_owned);
    StepResult res = solve(sys, warm);
    if (res.dv.size() != sys.body_dofs()) break;
    const Vector v_plus = velocities_after_change(sys, ex, res.dv);
    std::vector<std::array<double, kMaxRows>> springs;
    if (model.compliance.material) springs = advance_springs(sys, v_plus, res.lambda);
    const ContactWork work = contact_work(sys, v_plus, res.lambda);
    out.work.wall_work += work.wall_work;
    out.work.dissipation += work.dissipation;
    Vector Gv;
    g_apply(sys, v_plus, Gv);
    for (std::size_t c = 0; c < contacts.size(); ++c) {
      const Contact &k = sys.contacts()[c];
      contacts[c].gap += h * (Gv[Eigen::Index(rows) * Eigen::Index(c)] - wall_rows(k)[0]);
      if (!springs.empty()) contacts[c].spring = springs[c];
    }
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      bodies[i].v = v_plus.segment<3>(6 * Eigen::Index(i));
      bodies[i].omega = v_plus.segment<3>(6 * Eigen::Index(i) + 3);
    }
    if (out.done == 0) {
      out.dv = res.dv;
      out.path = v_plus;
      out.lambda = res.lambda;
      out.totals = res;
    } else {
      out.dv += res.dv;
      out.path += v_plus;
      out.lambda += res.lambda;
      add_solve(out.totals, res);
    }
    warm = res.lambda;
    ++out.done;
  }
  return out;
}

} // namespace fibre
