#include "fibre/pgs.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include "fibre/contact_rows.hpp"
#include "fibre/fibre_blocks.hpp"
#include "fibre/spook.hpp"

namespace fibre {

void PgsResult::record(double change, bool full)
{
  changes.push_back(change);
  if (!full) return; // focused sweeps: the rate and the estimate follow the full ones
  last_change = change;
  const int s = static_cast<int>(changes.size()) - 1;
  // the latest full sweep at least kRateWindow sweeps back (plain sweeps: exactly that far)
  for (auto at = full_sweeps.rbegin(); at != full_sweeps.rend(); ++at)
    if (*at <= s - kRateWindow) {
      const double first = changes[*at];
      contraction = first > 0 ? std::pow(change / first, 1.0 / (s - *at)) : 1.0;
      break;
    }
  full_sweeps.push_back(s);
}

double PgsResult::error_estimate() const
{
  if (last_change == 0) return 0;
  if (!(contraction < 1)) return INFINITY;
  return last_change * contraction / (1 - contraction);
}

namespace {

// One sweep over the contacts `list` (in order; all of them when null, else `count`): each
// moves to lambda_c + (b_c - G_c dv - Sigma_c lambda_c) / scale_c and is projected, and dv
// follows at once. Adds ||change||^2 and ||lambda||^2 (local) of the contacts it visits to
// norms; with `changes`, it stores each one's change^2 there. The rows of G are applied in
// their structured form (contact_rows.hpp).
template <int R>
void sweep(const ContactSystem &sys, const Cones &cones, const Vector &b,
           const std::vector<Vec6> &inv_scale, const std::vector<int> &owners, const int *list,
           int count, Vector &lambda, Vector &dv, double norms[2], double *changes)
{
  const int *pairs = sys.body_pairs();
  const double *kin = sys.num_contacts() > 0 ? sys.kinematics(0).frame.data() : nullptr;
  const double *inv_mass = sys.inv_mass().data(), *sigma = sys.sigma().data();
  double *l = lambda.data(), *w = dv.data();
  for (int k = 0; k < count; ++k) {
    const int c = list ? list[k] : k;
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
    double change2 = 0;
    for (int i = 0; i < R; ++i) {
      delta[i] = lc[i] - old[i];
      change2 += delta[i] * delta[i];
      norms[1] += lc[i] * lc[i];
    }
    norms[0] += change2;
    if (changes) changes[c] = change2;
    if (change2 == 0) continue; // an open contact that stays open moves no body
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

// The contacts that a full sweep moved by at least kFocusShare of its mean change^2: those
// left out moved by less than kFocusShare of the sweep's change^2 together.
constexpr double kFocusShare = 1e-3;
void focus_list(const std::vector<double> &changes, double total, std::vector<int> &list)
{
  list.clear();
  const double floor = changes.empty() ? 0.0 : kFocusShare * total / double(changes.size());
  for (std::size_t c = 0; c < changes.size(); ++c)
    if (changes[c] >= floor) list.push_back(static_cast<int>(c));
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
  const bool focus = control.focus_sweeps > 0 && !control.nonlinear_cg && !blocks;
  std::vector<double> contact_changes(focus ? nc : 0);
  std::vector<int> focus_contacts;
  for (int s = 0; s < control.max_sweeps; ++s) {
    // dv follows this process's updates; `moved` collects them for the other processes.
    if (halo) dv_start = dv;
    if (control.nonlinear_cg || s % kCheckpointSweeps == 0) lambda_start = lambda;
    if (blocks) blocks->correct(b, lambda, dv);
    double norms[2] = {0, 0}; // ||change||^2, ||lambda||^2
    // focused: the first sweep is full, then every (P + 1)-th counted from min_sweeps (so the
    // rules can stop where plain sweeps would); the P between visit the focus list
    const int period = control.focus_sweeps + 1;
    const bool full =
        !focus || s == 0 || ((s + 1 - control.min_sweeps) % period + period) % period == 0;
    const int *list = full ? nullptr : focus_contacts.data();
    const int count = full ? nc : static_cast<int>(focus_contacts.size());
    double *changes = full && focus ? contact_changes.data() : nullptr;
    if (rows == 6)
      sweep<6>(sys, cones, b, inv_scale, ex.local_owners(), list, count, lambda, dv, norms,
               changes);
    else
      sweep<3>(sys, cones, b, inv_scale, ex.local_owners(), list, count, lambda, dv, norms,
               changes);
    if (changes) focus_list(contact_changes, norms[0], focus_contacts);
    res.visits += count;
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
    res.record(norms[1] > 0 ? std::sqrt(norms[0] / norms[1]) : 0.0, full);
    res.reason = StopReason::max_iterations;
    // with a floor, a met estimate stops the sweeps at the floor: the changes of the sweeps
    // after it may fall to round-off, where the estimated rate means nothing
    if (control.accuracy > 0 && !(res.met_estimate <= control.accuracy) &&
        res.error_estimate() <= control.accuracy)
      res.met_estimate = res.error_estimate();
    // A full sweep that moves lambda by round-off only has converged as far as doubles go: its
    // changes may then repeat exactly (a rate of 1, an infinite estimate; a solved column under
    // focused sweeps swept on into stagnation).
    constexpr double kRoundOff = 64 * std::numeric_limits<double>::epsilon();
    const bool still = full && res.last_change <= kRoundOff; // 0 too: a sweep that changes nothing
    if (still && control.accuracy > 0)
      res.met_estimate = std::min(res.met_estimate, res.last_change);
    const bool done = control.accuracy > 0 ? res.met_estimate <= control.accuracy &&
                                                 (res.sweeps >= control.min_sweeps || still)
                                           : !(norms[0] > control.tol * control.tol * norms[1]);
    if (done && full) {
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
