#include "fibre/solvers/apgd.hpp"

#include <cmath>

#include "fibre/algebra/kernels.hpp"
#include "fibre/algebra/spook.hpp"

namespace fibre {

namespace {

// The problem in the scaled variables: f(l) = l.A l / 2 - b.l, gradient A l - b.
struct Problem {
  const ContactSystem &sys;
  const Exchange &ex;
  const Cones &cones;
  const Vector &b;
  Vector inv_scale; // per row

  Vector product(const Vector &l) const // A l
  {
    Vector out;
    g_apply(sys, velocity_change(sys, ex, l), out);
    return out + sys.sigma().cwiseProduct(l);
  }
  double dot(const Vector &x, const Vector &y) const { return ex.sum(x.dot(y)); }
  double energy(const Vector &l, const Vector &Al) const { return dot(l, 0.5 * Al - b); }
  // P(l - t D^-1 g), D the row scales
  Vector step(const Vector &l, const Vector &g, double t) const
  {
    Vector out = l - t * inv_scale.cwiseProduct(g);
    const int rows = sys.rows();
    for (int c = 0; c < sys.num_contacts(); ++c)
      cones.project(out.data() + Eigen::Index(rows) * c, c);
    return out;
  }
  // the complementarity residual at l, from its gradient
  double residual(const Vector &l, const Vector &g) const
  {
    const Vector moved = step(l, g, 1.0) - l;
    const double n[2] = {ex.sum(moved.squaredNorm()), ex.sum(l.squaredNorm())};
    return n[1] > 0 ? std::sqrt(n[0] / n[1]) : std::sqrt(n[0]);
  }
};

} // namespace

PgsResult apgd(const ContactSystem &sys, const Exchange &ex, const Cones &cones, const Vector &b,
               const std::vector<Vec6> &scale, Vector &lambda, const PgsControl &control)
{
  const int rows = sys.rows(), nc = sys.num_contacts();
  Problem pr{sys, ex, cones, b, Vector(sys.contact_dofs())};
  for (int c = 0; c < nc; ++c)
    for (int i = 0; i < rows; ++i) pr.inv_scale[Eigen::Index(rows) * c + i] = 1.0 / scale[c][i];
  for (int c = 0; c < nc; ++c) cones.project(lambda.data() + Eigen::Index(rows) * c, c);

  PgsResult res;
  Vector x = lambda, Ax = pr.product(x), y = x, Ay = Ax;
  res.last_change = pr.residual(x, Ax - b);
  Vector best = x;
  double best_residual = res.last_change;
  // In the scaled variables the diagonal of D^-1 A is about 1: L starts there and adapts.
  double L = 1.0, theta = 1.0;
  // the residual rule on the best iterate, which is what is returned
  const auto done = [&] {
    return control.accuracy > 0 ? res.error_estimate() <= control.accuracy
                                : best_residual <= control.tol;
  };
  for (int it = 0; it < control.max_sweeps && !done(); ++it) {
    const Vector gy = Ay - b;
    const double fy = pr.energy(y, Ay);
    Vector xn, Axn;
    for (int tries = 0; tries < 60; ++tries) { // backtracking on the scaled quadratic bound
      xn = pr.step(y, gy, 1.0 / L);
      Axn = pr.product(xn);
      const Vector d = xn - y;
      const double bound = fy + pr.dot(gy, d) + 0.5 * L * pr.dot(d, d.cwiseQuotient(pr.inv_scale));
      if (pr.energy(xn, Axn) <= bound) break;
      L *= 2.0;
    }
    ++res.sweeps;
    const double theta_next = 0.5 * (-theta * theta + theta * std::sqrt(theta * theta + 4.0));
    const double beta = theta * (1.0 - theta) / (theta * theta + theta_next);
    const Vector gx = Axn - b;
    // adaptive restart (O'Donoghue and Candes): momentum against the descent
    if (pr.dot(gy, xn - x) > 0) {
      y = xn;
      Ay = Axn;
      theta = 1.0;
    } else {
      y = xn + beta * (xn - x);
      Ay = Axn + beta * (Axn - Ax);
      theta = theta_next;
    }
    x = std::move(xn);
    Ax = std::move(Axn);
    L *= 0.9;
    res.record(pr.residual(x, gx));
    if (!std::isfinite(res.last_change)) {
      res.reason = StopReason::non_finite;
      break;
    }
    if (res.last_change < best_residual) {
      best_residual = res.last_change;
      best = x;
    }
  }
  lambda = best;
  res.last_change = best_residual;
  if (res.reason != StopReason::non_finite)
    res.reason = done() ? StopReason::converged : StopReason::max_iterations;
  return res;
}

} // namespace fibre
