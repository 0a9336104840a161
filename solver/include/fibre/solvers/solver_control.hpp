// What every solver shares: the methods by name, the typed stop reasons (PETSc KSP style) and
// the stopping rule (deal.II SolverControl style), kept apart from the methods themselves.
#pragma once

#include <functional>

#include "fibre/core/names.hpp"
#include "fibre/core/system.hpp"

namespace fibre {

// The solvers of a step, siblings over one ContactSystem:
//   cg      preconditioned conjugate gradients, in the contact form on the Schur complement
//           (the thesis's Uzawa, Algorithm 3) or in the body form on K; "uzawa" is an alias;
//   cr      preconditioned conjugate residual;
//   minres  Paige-Saunders MINRES;
//   direct  MUMPS;
//   pgs     projected Gauss-Seidel on the nonsmooth problem alone (no linear pass);
//   nncg    the same sweeps accelerated by nonsmooth nonlinear CG (pgs.hpp);
//   fbgs    the same sweeps with fibre-block corrections (fibre_blocks.hpp);
//   apgd    accelerated projected gradient descent on the nonsmooth problem (apgd.hpp).
enum class Method { cg, cr, minres, direct, pgs, nncg, fbgs, apgd };
template <> struct EnumNames<Method> {
  static constexpr EnumName<Method> table[] = {
      {Method::cg, "cg"},          {Method::cr, "cr"},
      {Method::minres, "minres"},  {Method::direct, "direct"},
      {Method::pgs, "pgs"},        {Method::nncg, "nncg"},
      {Method::fbgs, "fbgs"},      {Method::apgd, "apgd"},
      {Method::cg, "uzawa", true}, {Method::direct, "mumps", true}};
};
inline bool is_krylov(Method m)
{
  return m == Method::cg || m == Method::cr || m == Method::minres;
}

// converged: the method's own test met its tolerance (Krylov: the TRUE relative residual,
//   or StopControl::accept; PGS: a sweep moved lambda by at most tol relative to |lambda|).
// max_iterations: the iteration (sweep) cap without convergence.
// breakdown: a zero or negative curvature / denominator (A or P not SPD, Lanczos exhausted).
// non_finite: NaN/Inf met; the result is the last finite iterate (the initial guess, or 0
//   when that was not finite either).
// stagnation: Krylov: the recursively updated residual (or MINRES's estimate) met tol but the
//   true one did not, kMaxResidualChecks times in a row without the true residual halving in
//   between (the attainable accuracy in floating point is above tol). PGS: the change per sweep
//   stopped falling for kStagnationSweeps sweeps while above tol.
enum class StopReason { converged, max_iterations, breakdown, non_finite, stagnation };
template <> struct EnumNames<StopReason> {
  static constexpr EnumName<StopReason> table[] = {{StopReason::converged, "converged"},
                                                   {StopReason::max_iterations, "max_iterations"},
                                                   {StopReason::breakdown, "breakdown"},
                                                   {StopReason::non_finite, "non_finite"},
                                                   {StopReason::stagnation, "stagnation"}};
};
inline constexpr int kMaxResidualChecks = 3;

// Stop when ||r|| / ||b|| <= tol (operator's inner product), or after max_iter iterations.
struct StopControl {
  double tol = 1e-6;
  int max_iter = 500;
  // Optional extra rule (deal.II SolverControl style), e.g. a velocity-change test
  // (doc/design.md section 4): called after every iteration k >= 1 with the iterate; true
  // stops the method with StopReason::converged whatever the residual. It must decide alike
  // on every process.
  std::function<bool(int k, const Vector &x)> accept;
};

} // namespace fibre
