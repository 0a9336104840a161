#include "fibre/pgs.hpp"

#include <array>
#include <cmath>
#include <memory>

#include "fibre/contact_rows.hpp"
#include "fibre/fibre_blocks.hpp"
#include "fibre/spook.hpp"

namespace fibre {

void PgsResult::record(double change)
{
  last_change = change;
  changes.push_back(change);
  if (changes.size() > std::size_t(kRateWindow)) {
    const double first = changes[changes.size() - 1 - kRateWindow];
    contraction = first > 0 ? std::pow(change / first, 1.0 / kRateWindow) : 1.0;
  }
}

double PgsResult::error_estimate() const
{
  if (last_change == 0) return 0;
  if (!(contraction < 1)) return INFINITY;
  return last_change * contraction / (1 - contraction);
}

namespace {

// One sweep over the contacts in order: each moves to lambda_c + (b_c - G_c dv - Sigma_c
// lambda_c) / scale_c and is projected, and dv follows at once. Returns ||change||^2 and
// ||lambda||^2 (local). The rows of G are applied in their structured form (contact_rows.hpp).
template <int R>
void sweep(const ContactSystem &sys, const Cones &cones, const Vector &b,
           const std::vector<Vec6> &inv_scale, const std::vector<int> &owners, Vector &lambda,
           Vector &dv, double norms[2])
{
  const int nc = sys.num_contacts();
  const int *pairs = sys.body_pairs();
  const double *kin = nc > 0 ? sys.kinematics(0).frame.data() : nullptr;
  const double *inv_mass = sys.inv_mass().data(), *sigma = sys.sigma().data();
  double *l = lambda.data(), *w = dv.data();
  for (int c = 0; c < nc; ++c) {
    const double *q = kin + 15 * std::size_t(c);
    int ia = pairs[2 * std::size_t(c)], ib = pairs[2 * std::size_t(c) + 1];
    if (!owners.empty()) { // a periodic image moves with its body
      ia = owners[ia];
      if (ib >= 0) ib = owners[ib];
    }
    double *wa = w + 6 * std::size_t(ia), *wb = ib >= 0 ? w + 6 * std::size_t(ib) : nullptr;
    double u[6], old[6], delta[6] = {0, 0, 0, 0, 0, 0};
    contact_velocity<R>(q, q + 9, q + 12, wa, wb, u);
    double *lc = l + std::size_t(R) * c;
    const std::size_t at = std::size_t(R) * c;
    for (int i = 0; i < R; ++i) {
      old[i] = lc[i];
      lc[i] += (b[at + i] - u[i] - sigma[at + i] * old[i]) * inv_scale[c][i];
    }
    cones.project_rows<R>(lc, c);
    for (int i = 0; i < R; ++i) {
      delta[i] = lc[i] - old[i];
      norms[0] += delta[i] * delta[i];
      norms[1] += lc[i] * lc[i];
    }
    double ya[6] = {0, 0, 0, 0, 0, 0}, yb[6] = {0, 0, 0, 0, 0, 0};
    contact_impulse<R>(q, q + 9, q + 12, delta, ya, wb ? yb : nullptr);
    const double *ma = inv_mass + 6 * std::size_t(ia);
    for (int d = 0; d < 6; ++d) wa[d] += ma[d] * ya[d];
    if (wb) {
      const double *mb = inv_mass + 6 * std::size_t(ib);
      for (int d = 0; d < 6; ++d) wb[d] += mb[d] * yb[d];
    }
  }
}

} // namespace

PgsResult pgs(const ContactSystem &sys, const Exchange &ex, const Cones &cones, const Vector &b,
              const std::vector<Vec6> &scale, Vector &lambda, const PgsControl &control)
{
  PgsResult res;
  const int nc = sys.num_contacts(), rows = sys.rows();
  std::vector<Vec6> inv_scale(scale.size());
  for (std::size_t c = 0; c < scale.size(); ++c) inv_scale[c] = scale[c].cwiseInverse();
  // the blocks read their bound rows from feasible impulses
  if (control.fibre_blocks)
    for (int c = 0; c < nc; ++c) cones.project(lambda.data() + Eigen::Index(rows) * c, c);
  Vector dv = velocity_change(sys, ex, lambda);
  Vector dv_start, moved; // reused by every sweep
  // Impulses to fall back on when a sweep turns non-finite: a copy every kCheckpointSweeps
  // sweeps, not every sweep (stiff steps take hundreds), and every sweep for nonlinear CG,
  // whose direction is the sweep's change.
  constexpr int kCheckpointSweeps = 16;
  Vector lambda_start;
  double best = INFINITY;
  int since_best = 0;
  Vector direction, change; // nonlinear CG
  double last_change2 = 0;
  std::unique_ptr<FibreBlocks> blocks;
  if (control.fibre_blocks) {
    Vector normal(nc);
    for (int c = 0; c < nc; ++c) normal[c] = lambda[Eigen::Index(rows) * c];
    blocks =
        std::make_unique<FibreBlocks>(sys, ex.local_owners(), cones, control.block_weight, &normal);
  }
  const bool halo = ex.has_halo(); // else the round trip below is the identity
  for (int s = 0; s < control.max_sweeps; ++s) {
    // dv follows this process's updates; `moved` collects them for the other processes.
    if (halo) dv_start = dv;
    if (control.nonlinear_cg || s % kCheckpointSweeps == 0) lambda_start = lambda;
    if (blocks) blocks->correct(b, lambda, dv);
    double norms[2] = {0, 0}; // ||change||^2, ||lambda||^2
    if (rows == 6)
      sweep<6>(sys, cones, b, inv_scale, ex.local_owners(), lambda, dv, norms);
    else
      sweep<3>(sys, cones, b, inv_scale, ex.local_owners(), lambda, dv, norms);
    // Every process's updates on every body: the sum of the local changes, owners and ghosts.
    if (halo) {
      moved = dv - dv_start;
      ex.reverse_sum(moved);
      ex.forward(moved);
      dv = dv_start + moved;
    }
    ex.sum(norms, 2);
    ++res.sweeps;
    if (!std::isfinite(norms[0]) || !std::isfinite(norms[1])) {
      lambda = lambda_start;
      res.reason = StopReason::non_finite;
      return res;
    }
    res.record(norms[1] > 0 ? std::sqrt(norms[0] / norms[1]) : 0.0);
    res.reason = StopReason::max_iterations;
    // with a floor, a met estimate stops the sweeps at the floor: the changes of the sweeps
    // after it may fall to round-off, where the estimated rate means nothing
    if (control.accuracy > 0 && !(res.met_estimate <= control.accuracy) &&
        res.error_estimate() <= control.accuracy)
      res.met_estimate = res.error_estimate();
    const bool done = control.accuracy > 0 ? res.met_estimate <= control.accuracy &&
                                                 (res.sweeps >= control.min_sweeps || norms[0] == 0)
                                           : !(norms[0] > control.tol * control.tol * norms[1]);
    if (done) {
      res.reason = StopReason::converged;
      break;
    }
    if (res.last_change < best) {
      best = res.last_change;
      since_best = 0;
    } else if (++since_best >= control.stall_sweeps) {
      res.reason = StopReason::stagnation;
      break;
    }
    if (control.nonlinear_cg && s + 1 < control.max_sweeps) {
      change = lambda - lambda_start;
      const double beta = s > 0 ? norms[0] / last_change2 : 2.0;
      last_change2 = norms[0];
      if (beta > 1.0) {
        direction = change; // restart
      } else {
        direction *= beta;
        lambda += direction;
        dv += velocity_change(sys, ex, direction);
        direction += change;
      }
    }
  }
  if (control.nonlinear_cg) // the last step along the direction may have left the cones
    for (int c = 0; c < nc; ++c) cones.project(lambda.data() + Eigen::Index(rows) * c, c);
  return res;
}

} // namespace fibre
