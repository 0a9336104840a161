// The converged solution of one step's nonsmooth contact problem, and the accuracy of any other
// solution against it (doc/design.md section 4). Serial: the whole system on one process, every
// row active.
//
// The reference is found twice, by two different methods that must agree: projected
// Gauss-Seidel run to a complementarity residual of `target`, and a semismooth Newton method
// on the natural map of the cones, F(lambda) = lambda - P(lambda + D^-1 (b - A lambda)) = 0,
// with a generalized Jacobian solved by sparse LU and a backtracking line search on ||F||.
#pragma once

#include "fibre/algebra/cones.hpp"
#include "fibre/core/exchange.hpp"
#include "fibre/core/system.hpp"

namespace fibre {

// Relative 2-norm errors by group: the velocity change dv = M^-1 G^T lambda (translational and
// rotational parts), and the impulses (normal rows, Coulomb, rolling and twisting cones).
struct StepAccuracy {
  double dv_trans = 0, dv_rot = 0;
  double lambda_n = 0, lambda_t = 0, lambda_roll = 0, lambda_twist = 0;
  double velocity() const { return std::max(dv_trans, dv_rot); }
  double impulse() const; // the largest of the impulse groups that carry any impulse
};

// lambda against the reference ref (both rows per contact of sys), over all processes of `ex`
// (collective): the step's periodic images where it has them (ImageExchange), or the front
// ends' processes. The functions below are serial (one process).
StepAccuracy step_accuracy(const ContactSystem &sys, const Vector &lambda, const Vector &ref,
                           const Exchange &ex = serial_exchange());

struct NewtonResult {
  int iterations = 0;
  double complementarity = 0;
  bool converged = false;
};

// Semismooth Newton from lambda (in place) until the complementarity residual (cones.hpp) is
// at most target, or max_iter iterations. A step whose line search fails is replaced by ten
// projected Gauss-Seidel sweeps.
NewtonResult semismooth_newton(const ContactSystem &sys, const Cones &cones, const Vector &b,
                               Vector &lambda, double target, int max_iter,
                               const Exchange &ex = serial_exchange());

struct ReferenceOptions {
  double target = 1e-10;    // complementarity residual of both methods
  int max_sweeps = 2000000; // projected Gauss-Seidel
  int max_newton = 30;
};

struct Reference {
  Vector lambda;  // the Newton solution when it converged, else the sweeps'
  int sweeps = 0; // of projected Gauss-Seidel
  double complementarity_pgs = 0;
  NewtonResult newton;
  StepAccuracy agreement; // the sweeps' solution against Newton's
  bool confirmed() const; // both met the target and agree to 1e-6
};

// The sweeps start from `start` (for example the run's own impulses); Newton starts from the
// sweeps' iterate at a residual of 1e-6, and its end point must agree with theirs.
Reference nonsmooth_reference(const ContactSystem &sys, const Vector &start,
                              const ReferenceOptions &opt = {},
                              const Exchange &ex = serial_exchange());

} // namespace fibre
