// Preconditioned Krylov methods on a LinearOperator: CG (in the contact form the thesis's
// Uzawa, Algorithm 3), Conjugate Residual and MINRES. One loop skeleton each; the stop reasons
// and the stopping rule are in solver_control.hpp.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fibre/algebra/operators.hpp"
#include "fibre/precond/preconditioner.hpp"
#include "fibre/solvers/solver_control.hpp"

namespace fibre {

// Entry 0 is the initial guess. r is the recursively updated residual b - A x of every method
// (CG and CR carry it; MINRES carries it through A w_k alongside the Lanczos recurrence, at
// no extra operator application); after a restart it is the true residual.
struct IterationRecord {
  int iteration = 0;
  double rel_residual = 0;   // ||r|| / ||b||, operator inner product
  double rel_residual_A = 0; // ||r|| / ||A|| (thesis eq. 5.1) when norm_A > 0, else 0
  // ||r||_P / ||b||_P with ||r||_P^2 = r^T P^-1 r: the norm CR and MINRES minimise, hence
  // monotone for them (MINRES: its recurrence phibar; CR: r^T z; CG: r^T z).
  double rel_residual_P = 0;
  double velocity_error = 0; // from KrylovMonitor::velocity_error, else 0
};

// Optional per-iteration recording.
struct KrylovMonitor {
  bool record_history = false;
  double norm_A = 0; // the norm of A used for r_r (state which one where it is set)
  std::function<double(const Vector &x)> velocity_error; // e.g. v_e against MUMPS
};

struct SolveResult {
  StopReason reason = StopReason::max_iterations;
  int iterations = 0;
  double rel_residual = 0; // final TRUE ||b - A x|| / ||b|| (inf when not finite)
  int restarts = 0;        // restarts from the true residual (failed convergence checks)
  std::vector<IterationRecord> history;
  bool converged() const { return reason == StopReason::converged; }
};

// Solve A x = b; x holds the initial guess (warm start) and receives the solution. b == 0
// gives x = 0, converged in 0 iterations. When the updated residual meets tol, the true
// residual is computed (one extra product) and the method restarts from it if it does not.
// MINRES also checks when its estimate ||r||_P / ||b||_P meets tol while its updated residual
// has levelled off (no new minimum for 10 iterations): at the attainable accuracy the updated
// residual stops falling while the estimate goes on.
// cg: preconditioned CG; in the contact form CG on the Schur complement (thesis Algorithm 3,
// Uzawa).
// conjugate_residual: preconditioned CR, minimises ||r||_P over the Krylov space.
// minres: Paige-Saunders MINRES with an SPD preconditioner, minimises ||r||_P as well.
SolveResult cg(const LinearOperator &A, const Preconditioner &P, const Vector &b, Vector &x,
               const StopControl &stop, const KrylovMonitor *monitor = nullptr);
SolveResult conjugate_residual(const LinearOperator &A, const Preconditioner &P, const Vector &b,
                               Vector &x, const StopControl &stop,
                               const KrylovMonitor *monitor = nullptr);
SolveResult minres(const LinearOperator &A, const Preconditioner &P, const Vector &b, Vector &x,
                   const StopControl &stop, const KrylovMonitor *monitor = nullptr);

SolveResult krylov_solve(Method m, const LinearOperator &A, const Preconditioner &P,
                         const Vector &b, Vector &x, const StopControl &stop,
                         const KrylovMonitor *monitor = nullptr);

} // namespace fibre
