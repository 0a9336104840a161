#include "fibre/study/nonsmooth_reference.hpp"

#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <vector>

#include "fibre/algebra/assembly.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/solvers/pgs.hpp"

namespace fibre {

namespace {

double rel(double err2, double ref2)
{
  if (!(ref2 > 0)) return std::sqrt(err2) > 0 ? 1.0 : 0.0;
  return std::sqrt(err2 / ref2);
}

// Row group of row r of a contact: 0 normal, 1 Coulomb, 2 twisting, 3 rolling.
int group_of(int r)
{
  return r == 0 ? 0 : r < 3 ? 1 : r == 3 ? 2 : 3;
}

// P(z) and its generalized Jacobian, one rows x rows block per contact.
void project_with_jacobian(const Cones &cones, const Vector &z, Vector &p,
                           std::vector<Eigen::Triplet<double>> &jp)
{
  const int rows = cones.rows();
  const Eigen::Index nc = z.size() / rows;
  p = z;
  jp.clear();
  for (Eigen::Index c = 0; c < nc; ++c) {
    const Eigen::Index at = rows * c;
    cones.project(p.data() + at, static_cast<int>(c));
    const double zn = z[at];
    if (!(zn > 0)) continue; // released: P = 0 around z
    jp.emplace_back(at, at, 1.0);
    for (int k = 0; k < num_cones(rows); ++k) {
      const Cone &cone = kCones[k];
      const double coeff = cones.coeff(static_cast<int>(c), k), radius = coeff * zn;
      if (!(radius > 0)) continue;
      const Eigen::Vector2d t = cone_values(z, at, cone);
      const double tn = cone.size == 2 ? t.norm() : std::abs(t[0]);
      if (tn <= radius) { // sticking: P = identity on the cone
        for (int i = 0; i < cone.size; ++i)
          jp.emplace_back(at + cone.first + i, at + cone.first + i, 1.0);
        continue;
      }
      // sliding: P = radius t / |t|
      const Eigen::Vector2d u = t / tn;
      for (int i = 0; i < cone.size; ++i) {
        jp.emplace_back(at + cone.first + i, at, coeff * u[i]);
        for (int j = 0; j < cone.size; ++j) {
          const double d = (radius / tn) * ((i == j ? 1.0 : 0.0) - u[i] * u[j]);
          if (d != 0.0) jp.emplace_back(at + cone.first + i, at + cone.first + j, d);
        }
      }
    }
  }
}

double merit(const SparseMatrix &A, const Vector &b, const Vector &inv_scale, const Cones &cones,
             const Vector &lambda, Vector *F = nullptr, Vector *z = nullptr)
{
  const Vector trial = lambda + inv_scale.cwiseProduct(b - A * lambda);
  Vector p = trial;
  const int rows = cones.rows();
  for (Eigen::Index c = 0; c < p.size() / rows; ++c)
    cones.project(p.data() + rows * c, static_cast<int>(c));
  const Vector f = lambda - p;
  if (F) *F = f;
  if (z) *z = trial;
  return f.norm();
}

} // namespace

double StepAccuracy::impulse() const
{
  return std::max({lambda_n, lambda_t, lambda_roll, lambda_twist});
}

StepAccuracy step_accuracy(const ContactSystem &sys, const Vector &lambda, const Vector &ref,
                           const Exchange &ex)
{
  const Vector dv = velocity_change(sys, ex, lambda), dv_ref = velocity_change(sys, ex, ref);
  double e[2][2] = {{0, 0}, {0, 0}}; // [trans/rot][err2, ref2]
  for (int i = 0; i < sys.num_owned_bodies(); ++i)
    for (int d = 0; d < 6; ++d) {
      const double x = dv[6 * i + d], y = dv_ref[6 * i + d];
      e[d / 3][0] += (x - y) * (x - y);
      e[d / 3][1] += y * y;
    }
  double g[4][2] = {{0, 0}, {0, 0}, {0, 0}, {0, 0}};
  const int rows = sys.rows();
  for (Eigen::Index i = 0; i < lambda.size(); ++i) {
    const int k = group_of(static_cast<int>(i % rows));
    g[k][0] += (lambda[i] - ref[i]) * (lambda[i] - ref[i]);
    g[k][1] += ref[i] * ref[i];
  }
  ex.sum(&e[0][0], 4);
  ex.sum(&g[0][0], 8);
  // A group whose reference is (numerically) empty, such as twisting with mu_twist 0, is
  // measured against the normal impulses instead of against its own round-off.
  const double floor2 = 1e-24 * g[0][1];
  StepAccuracy a;
  a.dv_trans = rel(e[0][0], e[0][1]);
  a.dv_rot = rel(e[1][0], std::max(e[1][1], 1e-24 * e[0][1]));
  a.lambda_n = rel(g[0][0], g[0][1]);
  a.lambda_t = rel(g[1][0], std::max(g[1][1], floor2));
  a.lambda_twist = rel(g[2][0], std::max(g[2][1], floor2));
  a.lambda_roll = rel(g[3][0], std::max(g[3][1], floor2));
  return a;
}

NewtonResult semismooth_newton(const ContactSystem &sys, const Cones &cones, const Vector &b,
                               Vector &lambda, double target, int max_iter, const Exchange &ex)
{
  NewtonResult res;
  const SparseMatrix A = assemble_A(sys, ex.local_owners());
  const std::vector<Vec6> scale = row_scales(sys);
  const int rows = sys.rows();
  Vector inv_scale(lambda.size());
  for (Eigen::Index i = 0; i < lambda.size(); ++i) inv_scale[i] = 1.0 / scale[i / rows][i % rows];
  const SparseMatrix DinvA = inv_scale.asDiagonal() * A;
  SparseMatrix I(lambda.size(), lambda.size());
  I.setIdentity();
  std::vector<Eigen::Triplet<double>> jp;
  Vector F, z, p, step;
  for (;;) {
    const double m = merit(A, b, inv_scale, cones, lambda, &F, &z);
    res.complementarity = lambda.norm() > 0 ? m / lambda.norm() : m;
    if (res.complementarity <= target) {
      res.converged = true;
      return res;
    }
    if (res.iterations >= max_iter) return res;
    ++res.iterations;
    project_with_jacobian(cones, z, p, jp);
    SparseMatrix JP(lambda.size(), lambda.size());
    JP.setFromTriplets(jp.begin(), jp.end());
    const SparseMatrix J = I - JP + SparseMatrix(JP * DinvA);
    Eigen::SparseLU<SparseMatrix> lu(J);
    bool moved = false;
    if (lu.info() == Eigen::Success) {
      step = lu.solve(-F);
      for (double t = 1.0; t > 1e-6 && step.allFinite(); t *= 0.5) {
        const Vector trial = lambda + t * step;
        if (merit(A, b, inv_scale, cones, trial) < (1.0 - 1e-4 * t) * m) {
          lambda = trial;
          moved = true;
          break;
        }
      }
    }
    if (!moved) { // no descent: projected Gauss-Seidel makes progress instead
      pgs(sys, ex, cones, b, scale, lambda, PgsControl{10, 0.0, 1000});
    }
  }
}

bool Reference::confirmed() const
{
  return complementarity_pgs <= 1e-9 && newton.converged && agreement.velocity() < 1e-6 &&
         agreement.impulse() < 1e-6;
}

Reference nonsmooth_reference(const ContactSystem &sys, const Vector &start,
                              const ReferenceOptions &opt, const Exchange &ex)
{
  Reference ref;
  const Cones cones(sys);
  const Vector b = spook_rhs(sys);
  const std::vector<Vec6> scale = row_scales(sys);
  Vector pgs_lambda = start;
  for (int c = 0; c < sys.num_contacts(); ++c) cones.project(pgs_lambda.data() + sys.rows() * c, c);
  // Sweeps in rounds, until the residual (not only the change per sweep) meets the target.
  // Newton starts where the sweeps passed 1e-6: close enough for its local convergence, far
  // enough that agreeing with the sweeps' end point is a check of that point.
  Vector newton_lambda;
  while (ref.sweeps < opt.max_sweeps) {
    const PgsResult r = pgs(sys, ex, cones, b, scale, pgs_lambda,
                            PgsControl{std::min(500, opt.max_sweeps - ref.sweeps), 1e-15, 1 << 30});
    ref.sweeps += r.sweeps;
    ref.complementarity_pgs = complementarity(sys, ex, cones, b, pgs_lambda, scale);
    if (newton_lambda.size() == 0 && ref.complementarity_pgs <= 1e-6) newton_lambda = pgs_lambda;
    if (ref.complementarity_pgs <= opt.target || r.reason == StopReason::non_finite) break;
  }
  if (newton_lambda.size() == 0) newton_lambda = pgs_lambda;
  ref.newton = semismooth_newton(sys, cones, b, newton_lambda, opt.target, opt.max_newton, ex);
  // Newton's iterate is feasible only in the limit: its projection is the answer
  for (int c = 0; c < sys.num_contacts(); ++c)
    cones.project(newton_lambda.data() + sys.rows() * c, c);
  ref.agreement = step_accuracy(sys, pgs_lambda, newton_lambda, ex);
  ref.lambda = ref.newton.converged ? newton_lambda : pgs_lambda;
  return ref;
}

} // namespace fibre
