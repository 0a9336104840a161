// Preconditioned Krylov methods on a LinearOperator: Uzawa (CG on the Schur complement,
// thesis Algorithm 3), Conjugate Residual and MINRES. One loop skeleton each, typed stop
// reasons (PETSc KSP style) and stopping rules kept apart from the method (deal.II style).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fibre/operators.hpp"
#include "fibre/preconditioner.hpp"

namespace fibre {

enum class StopReason { converged, max_iterations, breakdown, non_finite };
const char *to_string(StopReason r);

enum class Method { uzawa, cr, minres };
const char *to_string(Method m);
bool parse_method(const std::string &s, Method &m);

// Stop when ||r|| / ||b|| <= tol (operator's inner product), or after max_iter iterations.
struct StopControl {
  double tol = 1e-6;
  int max_iter = 500;
};

struct IterationRecord {
  int iteration = 0;
  double rel_residual = 0;    // ||r|| / ||b||
  double rel_residual_A = 0;  // ||r|| / ||A|| (thesis eq. 5.1) when norm_A > 0, else 0
  double velocity_error = 0;  // from KrylovMonitor::velocity_error, else 0
};

// Optional per-iteration recording. The residual r is the true or recursively updated
// residual of the method (documented per method).
struct KrylovMonitor {
  bool record_history = false;
  double norm_A = 0;  // the norm of A used for r_r (state which one where it is set)
  std::function<double(const Vector &x)> velocity_error;  // e.g. v_e against MUMPS
};

struct SolveResult {
  StopReason reason = StopReason::max_iterations;
  int iterations = 0;
  double rel_residual = 0;  // final ||r|| / ||b||
  std::vector<IterationRecord> history;
  bool converged() const { return reason == StopReason::converged; }
};

// Solve A x = b; x holds the initial guess (warm start) and receives the solution.
SolveResult uzawa(const LinearOperator &A, const Preconditioner &P, const Vector &b, Vector &x,
                  const StopControl &stop, const KrylovMonitor *monitor = nullptr);
SolveResult conjugate_residual(const LinearOperator &A, const Preconditioner &P, const Vector &b,
                               Vector &x, const StopControl &stop,
                               const KrylovMonitor *monitor = nullptr);
SolveResult minres(const LinearOperator &A, const Preconditioner &P, const Vector &b, Vector &x,
                   const StopControl &stop, const KrylovMonitor *monitor = nullptr);

SolveResult krylov_solve(Method m, const LinearOperator &A, const Preconditioner &P,
                         const Vector &b, Vector &x, const StopControl &stop,
                         const KrylovMonitor *monitor = nullptr);

}  // namespace fibre
