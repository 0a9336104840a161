#include "fibre/pgs.hpp"

#include <array>
#include <cmath>

#include "fibre/kernels.hpp"
#include "fibre/spook.hpp"

namespace fibre {

PgsResult pgs(const ContactSystem &sys, const Exchange &ex, const Cones &cones, const Vector &b,
              const std::vector<Vec6> &scale, Vector &lambda, const PgsControl &control)
{
  PgsResult res;
  const int nc = sys.num_contacts(), rows = sys.rows();
  std::vector<std::array<Mat6, 2>> J(nc);
  for (int c = 0; c < nc; ++c) J[c] = {jacobian_block(sys, c, 0), jacobian_block(sys, c, 1)};
  const Vector &inv_mass = sys.inv_mass();
  const Vector &sigma = sys.sigma();
  Vector dv = velocity_change(sys, ex, lambda);
  Vector dv_start, moved, lambda_start; // reused by every sweep
  double best = INFINITY;
  int since_best = 0;
  Vector direction, change; // nonlinear CG
  double last_change2 = 0;
  for (int s = 0; s < control.max_sweeps; ++s) {
    // dv follows this process's updates; `moved` collects them for the other processes.
    dv_start = dv;
    lambda_start = lambda;
    double norms[2] = {0, 0}; // ||change||^2, ||lambda||^2
    for (int c = 0; c < nc; ++c) {
      const Contact &k = sys.contacts()[c];
      const Eigen::Index at = Eigen::Index(rows) * c, ia = 6 * Eigen::Index(k.a),
                         ib = 6 * Eigen::Index(k.b);
      Vec6 G_dv = J[c][0] * dv.segment<6>(ia);
      if (!k.is_wall()) G_dv += J[c][1] * dv.segment<6>(ib);
      Vec6 old = Vec6::Zero();
      old.head(rows) = lambda.segment(at, rows);
      for (int i = 0; i < rows; ++i)
        lambda[at + i] += (b[at + i] - G_dv[i] - sigma[at + i] * old[i]) / scale[c][i];
      cones.project(lambda.data() + at, c);
      Vec6 change = Vec6::Zero();
      change.head(rows) = lambda.segment(at, rows) - old.head(rows);
      dv.segment<6>(ia) += inv_mass.segment<6>(ia).cwiseProduct(J[c][0].transpose() * change);
      if (!k.is_wall())
        dv.segment<6>(ib) += inv_mass.segment<6>(ib).cwiseProduct(J[c][1].transpose() * change);
      norms[0] += change.squaredNorm();
      norms[1] += lambda.segment(at, rows).squaredNorm();
    }
    // Every process's updates on every body: the sum of the local changes, owners and ghosts.
    moved = dv - dv_start;
    ex.reverse_sum(moved);
    ex.forward(moved);
    dv = dv_start + moved;
    ex.sum(norms, 2);
    ++res.sweeps;
    if (!std::isfinite(norms[0]) || !std::isfinite(norms[1])) {
      lambda = lambda_start;
      res.reason = StopReason::non_finite;
      return res;
    }
    res.last_change = norms[1] > 0 ? std::sqrt(norms[0] / norms[1]) : 0.0;
    res.reason = StopReason::max_iterations;
    if (!(norms[0] > control.tol * control.tol * norms[1])) {
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
