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

// converged: ||b - A x|| / ||b|| <= tol, checked on the TRUE residual (or StopControl::accept).
// max_iterations: stop.max_iter iterations without convergence.
// breakdown: a zero or negative curvature / denominator (A or P not SPD, Lanczos exhausted).
// non_finite: NaN/Inf met; x is the last finite iterate (the initial guess, or 0 when that
//   was not finite either).
// stagnation: the recursively updated residual (or MINRES's estimate) met tol but the true one
//   did not, kMaxResidualChecks times in a row without the true residual halving in between
//   (the attainable accuracy in floating point is above tol).
enum class StopReason { converged, max_iterations, breakdown, non_finite, stagnation };
const char *to_string(StopReason r);
bool parse_stop_reason(const std::string &s, StopReason &r);
inline constexpr int kMaxResidualChecks = 3;

enum class Method { uzawa, cr, minres };
const char *to_string(Method m);
bool parse_method(const std::string &s, Method &m);  // "uzawa" (alias "cg"), "cr", "minres"

// Stop when ||r|| / ||b|| <= tol (operator's inner product), or after max_iter iterations.
struct StopControl {
  double tol = 1e-6;
  int max_iter = 500;
  // Optional extra rule (deal.II SolverControl style), e.g. a velocity-change test (design.md
  // section 4): called after every iteration k >= 1 with the iterate; true stops the method
  // with StopReason::converged whatever the residual. It must decide alike on every process.
  std::function<bool(int k, const Vector &x)> accept;
};

// Entry 0 is the initial guess. r is the recursively updated residual b - A x of every method
// (CG and CR carry it; MINRES carries it through A w_k alongside the Lanczos recurrence, at
// no extra operator application); after a restart it is the true residual.
struct IterationRecord {
  int iteration = 0;
  double rel_residual = 0;    // ||r|| / ||b||, operator inner product
  double rel_residual_A = 0;  // ||r|| / ||A|| (thesis eq. 5.1) when norm_A > 0, else 0
  // ||r||_P / ||b||_P with ||r||_P^2 = r^T P^-1 r: the norm CR and MINRES minimise, hence
  // monotone for them (MINRES: its recurrence phibar; CR: r^T z; CG: r^T z).
  double rel_residual_P = 0;
  double velocity_error = 0;  // from KrylovMonitor::velocity_error, else 0
};

// Optional per-iteration recording.
struct KrylovMonitor {
  bool record_history = false;
  double norm_A = 0;  // the norm of A used for r_r (state which one where it is set)
  std::function<double(const Vector &x)> velocity_error;  // e.g. v_e against MUMPS
};

struct SolveResult {
  StopReason reason = StopReason::max_iterations;
  int iterations = 0;
  double rel_residual = 0;  // final TRUE ||b - A x|| / ||b|| (inf when not finite)
  int restarts = 0;         // restarts from the true residual (failed convergence checks)
  std::vector<IterationRecord> history;
  bool converged() const { return reason == StopReason::converged; }
};

// Solve A x = b; x holds the initial guess (warm start) and receives the solution. b == 0
// gives x = 0, converged in 0 iterations. When the updated residual meets tol, the true
// residual is computed (one extra product) and the method restarts from it if it does not.
// MINRES also checks when its estimate ||r||_P / ||b||_P meets tol while its updated residual
// has levelled off (no new minimum for 10 iterations): at the attainable accuracy the updated
// residual stops falling while the estimate goes on.
// uzawa: preconditioned CG on the Schur complement (thesis Algorithm 3).
// conjugate_residual: preconditioned CR, minimises ||r||_P over the Krylov space.
// minres: Paige-Saunders MINRES with an SPD preconditioner, minimises ||r||_P as well.
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
