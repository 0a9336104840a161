// Accelerated projected gradient descent (APGD; Nesterov, as Mazhar, Heyn, Negrut and Tasora
// 2015 apply it to granular contact): a sibling of projected Gauss-Seidel over the same
// ContactSystem and cones. Every iteration is one product with A = G M^-1 G^T + Sigma and one
// projection per contact, so it parallelizes without the sweeps' order. The gradient is scaled
// by the sweeps' row scales (the cheapest preconditioner that keeps the projection per contact).
#pragma once

#include <vector>

#include "fibre/algebra/cones.hpp"
#include "fibre/core/exchange.hpp"
#include "fibre/solvers/pgs.hpp"

namespace fibre {

// Iterates from lambda (projected first) for at most control.max_sweeps iterations, until the
// step of the scaled projected map || lambda - P(lambda + rho / scale) || / || lambda || (the
// complementarity residual of cones.hpp) is at most control.tol. The result is the iterate
// with the smallest such residual; PgsResult counts iterations as sweeps.
PgsResult apgd(const ContactSystem &sys, const Exchange &ex, const Cones &cones, const Vector &b,
               const std::vector<Vec6> &scale, Vector &lambda, const PgsControl &control);

} // namespace fibre
