// Spectra of the preconditioned operators and the effective condition number kappa_e
// (doc/design.md section 4, thesis section 5).
//
// kappa_e = lambda_1 / lambda_r over the eigenvalues of P^-1 A sorted descending,
// lambda_1 >= lambda_2 >= ... >= lambda_n > 0. The "largest gap" is the largest ratio
// lambda_i / lambda_{i+1} of consecutive eigenvalues (the first one on ties); r is the i
// where it occurs, so lambda_r is the last eigenvalue above the gap. A ratio, not a
// difference, because the gap of interest (null(G^T) at Sigma against the range of G in the
// contact form; free body motions at M against the constrained ones in the body form) spans
// decades. With all eigenvalues equal (or just one) there is no gap: kappa_e = kappa = 1.
// Without a clear gap the rule still picks the largest ratio, often at the isolated extremes of
// the spectrum; report the gap ratio with kappa_e so that such cases show.
//
// Three ways to get there:
// - dense_spectrum: every eigenvalue, from dense A and P^-1 formed by applying the operator
//   and the preconditioner to unit vectors, through the symmetric generalized problem
//   (Cholesky A = B B^T, eigenvalues of B^T P^-1 B). One process, O(n^3): up to a few
//   thousand unknowns, and cross-checks.
// - lanczos_spectrum: preconditioned Lanczos with full reorthogonalization, using only
//   applies and the operator's (global) inner product, so it scales and runs under MPI.
//   Sparse, unconverged Ritz values can pose as gaps: r then points at an unconverged value
//   and the iteration goes on. It is quick where the spectrum has a clear gap and moderate
//   kappa_e; without a gap kappa_e hinges on the finest detail at the bottom of the spectrum
//   and Lanczos needs about n steps (then the dense path is as fast).
// - body_space_spectrum: the contact-space A without preconditioner when Sigma = sigma I:
//   the nonzero spectrum of G M^-1 G^T is that of M^-1/2 G^T G M^-1/2 (6 per body instead
//   of rows() per contact), and A adds sigma to it; the rest of A's spectrum is sigma.
#pragma once

#include <cstdint>
#include <vector>

#include "fibre/algebra/operators.hpp"
#include "fibre/precond/preconditioner.hpp"

namespace fibre {

struct Spectrum {
  std::vector<double> eigenvalues; // descending: all (dense) or the Ritz values (Lanczos)
  std::vector<double> residuals;   // Lanczos: residual bounds (infinite: not computed)
  double lambda_max = 0;
  double lambda_min = 0; // Lanczos: the smallest Ritz value (an upper bound)
  int r = 0;             // eigenvalues[r] = lambda_r, the last above the largest gap
  double lambda_r = 0;
  double gap_ratio = 1; // lambda_r / (next eigenvalue below it); 1 with no gap
  double kappa = 1;     // lambda_max / lambda_min
  double kappa_e = 1;   // lambda_max / lambda_r
  int iterations = 0;   // Lanczos steps (0 for the dense paths)
  // Lanczos: converged = lambda_1 and lambda_r met the tolerance and kappa_e repeated over
  // two checks; certified = besides, the Ritz values at the gap and at the
  // bottom settled and no unresolved stretch of the spectrum can hide a larger gap (or an
  // invariant subspace was found). Dense paths: both true.
  bool converged = true;
  bool certified = true;
};

// kappa_e and friends from a list of positive eigenvalues in any order (sorted here).
// Throws std::invalid_argument on an empty list or a non-positive or non-finite entry.
Spectrum effective_condition(std::vector<double> eigenvalues);

// All eigenvalues of P^-1 A (one process; A.size() unit-vector applies of each).
Spectrum dense_spectrum(const LinearOperator &A, const Preconditioner &P);

struct LanczosOptions {
  int max_steps = 2000;  // also capped by the operator's global size
  int check_every = 10;  // steps between convergence checks
  double tol = 1e-4;     // relative residual of lambda_1 and lambda_r, and kappa_e drift
  double gap_tol = 1e-2; // relative residual of the Ritz values around the gap
  bool certify = false;  // run until certified (may take about n steps without a gap)
  std::uint64_t seed = 12345;
  const Vector *start = nullptr; // start vector (default: random; body form: ghosts zero)
};

Spectrum lanczos_spectrum(const LinearOperator &A, const Preconditioner &P,
                          const LanczosOptions &opt = {});
// The same on the operator of `form` over `sys`, with a start vector whose ghost entries are
// zero (body form).
Spectrum lanczos_spectrum(Form form, const ContactSystem &sys, const Exchange &ex,
                          const Preconditioner &P, const LanczosOptions &opt = {});

// Unpreconditioned contact-space spectrum through body space (one process). Throws
// std::invalid_argument unless Sigma is one value on every row.
Spectrum body_space_spectrum(const ContactSystem &sys);

} // namespace fibre
