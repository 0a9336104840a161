// One SPOOK step's contact solve: the orchestration of the sibling solvers. A linear pass
// (Krylov with a preconditioner in either form, or MUMPS) inside the bounded active-set loop
// for lambda_n >= 0 and the cones (doc/design.md section 2), then projected Gauss-Seidel
// (pgs.hpp) to finish; or projected Gauss-Seidel alone (Method::pgs). This is what the front
// ends call every step.
#pragma once

#include <mpi.h>

#include <string>

#include "fibre/model/contact_model.hpp"
#include "fibre/precond/preconditioner_family.hpp"
#include "fibre/solvers/krylov.hpp"
#include "fibre/solvers/pgs.hpp"

namespace fibre {

// The sweeps' cap when the step has an accuracy (tol) and `sweeps` was not typed, and when it
// has none (tol none: a fast step).
inline constexpr int kAccuracySweeps = 2000;
inline constexpr int kFastSweeps = 50;

// The one home of the step's defaults, measured on the material and silo scenes
// (doc/design.md section 8, bench/README.md section 7, doc/fix_fibre_contact.md "Solvers").
// Front ends override only what the user typed. The default step is projected Gauss-Seidel to
// an accuracy of 1e-4: warm-started from the last step's accurate impulses it was the
// cheapest way to a velocity error of 1e-3, about as fast end to end as the linear pass with
// 50 sweeps, and at 1e-3 the sweeps held an arch that clogged a silo (bench/README.md).
struct StepOptions {
  Form form = Form::body;
  Method solver = Method::pgs;
  PrecondOptions precond{PrecondKind::tree, EdgeWeight::z, nullptr};
  // The last (tight) linear pass solves to tol: tighter solves bought no accuracy once the
  // sweeps finish the step, only time.
  StopControl stop{1e-4, 200, {}};
  int active_set_max = 1; // K: passes of the active-set loop
  // The loop has settled when the set stops changing and the capped impulses (mu l_n along
  // the slip direction, from the newest l_n) move by at most cap_tol * max |lambda|.
  double cap_tol = 1e-6;
  // Passes before the set settles only decide the set: while the number of changes falls they
  // solve to this relative residual (when larger than stop.tol); the settled set, and the last
  // pass, are solved to stop.tol.
  double pass_tol = 1e-3;
  // The loop's projected impulses are finished by at most this many projected Gauss-Seidel
  // sweeps on the full system (0: none), as long as their complementarity residual exceeds
  // sweep_tol; the sweeps stop when one moves lambda by at most sweep_tol relative to |lambda|.
  // With solver pgs the sweeps are the whole solve.
  int sweeps = kAccuracySweeps;
  double sweep_tol = 1e-3;
  // A step whose sweeps end at their cap more than kRescueFactor times above sweep_tol (a
  // jammed pack: a grain pinched between a moving blade and a wall was thrown at 1.7 m/s)
  // sweeps on, up to this many sweeps in all (0: no rescue). Only such steps pay for it. A step
  // still that far above sweep_tol after it counts as not converged. Not with solver pgs or
  // nncg, whose sweeps are the whole solve.
  int rescue_sweeps = 500;
  // The sweeps accelerated by nonsmooth nonlinear CG (always with solver nncg).
  bool sweep_cg = false;
  // Fibre-block corrections before every sweep (always with solver fbgs).
  bool sweep_blocks = false;
  // The step's accuracy (keyword tol; 0: none). When set, the sweeps stop only when their
  // estimate of the impulses' remaining relative error (StepResult::error_estimate) is at most
  // this, after at most `sweeps` sweeps; sweep_tol and the rescue then play no part, and a step
  // that ends above it counts as not converged.
  double accuracy = 1e-4;
  // With the accuracy rule, at least this many sweeps: on static piles the rule stops after
  // 6, where the impulses are within it but the rotations only within 3e-3 to 7e-3 of the
  // converged step; 10 sweeps bring them within 1e-3 (bench/README.md, "A floor of sweeps").
  int min_sweeps = 10;
  // Focused sweeps (PgsControl::focus_sweeps): between full sweeps, this many visit only the
  // contacts that the last full sweep moved (0: every sweep is full). Three cut the sweeps'
  // visits by 11 to 46% at the same or a smaller error against the converged step
  // (bench/README.md, "Focused sweeps"), but they move the heaps and a plugged silo's deepest
  // sphere beyond their checks, so they are not the default yet.
  int focus_sweeps = 0;
  // Anderson acceleration of the sweeps over this many sweeps (PgsControl::anderson; 0: off),
  // from the floor's last sweep on. On eleven exported steps from E = 1e5 to 1e8 it took 0.17
  // to 0.91 of plain sweeps' time at errors within 1.18 times theirs against the converged
  // step (bench/README.md, "Anderson acceleration"). Plain sweeps only: solver nncg, apgd and
  // fbgs, sweep_cg, sweep_blocks and focus_sweeps turn it off unless it was typed.
  int anderson = 3;
  // Anderson's map is this many sweeps (PgsControl::anderson_period): with a mix after every
  // second sweep a solve cost 0.68 to 0.90 of a mix after every sweep, at the same or smaller
  // errors against the converged step (bench/README.md, "Anderson every other sweep").
  int anderson_period = 2;
  // A solve of Anderson's sweeps that, from sweep 30 on, predicts more than this many sweeps
  // still to the accuracy starts again once from its impulses (PgsControl::restart_sweeps; 0:
  // never). On the shipped slow states it took the sweeps of a LIGGGHTS heap's step from 1,735
  // to 193 and of a take-over's cold start from 483 to 409, and left the others within 1%
  // (bench/README.md, "Slow steps start again").
  double restart_sweeps = 200;
  // Full sweeps four contacts at a time, in groups that share no body (PgsControl::grouped,
  // sweep_groups.hpp; where the processor has AVX2 and FMA): the same sweeps in another order,
  // at half the time a sweep (bench/README.md, "Sweeps four contacts at a time").
  bool sweep_groups = true;
  // Whether the result reports its complementarity residual (StepResult::complementarity) and
  // counts its released and capped rows. Without, it counts nothing and measures the residual
  // only where the residual decides the solve (not under the accuracy rule with a sweeps-only
  // solver). The substeps before a step's last go without: only the last one is reported, and
  // the residual and the counts cost two products with G, a pass over the cones and a sum.
  bool residual = true;
};

inline constexpr double kRescueFactor = 10.0;
inline constexpr double kNotMeasured = -1.0; // StepResult::complementarity not measured

// The settings as one line, "name value, name value, ..." (PETSc KSPView style): the front
// ends log it, and the doc page's defaults are this line for StepOptions{}.
std::string describe(const StepOptions &opt);

// Counts (released, capped) are global over all processes; so are the Krylov figures.
struct StepResult {
  Vector lambda;      // final, feasible impulses (rows per contact)
  Vector dv;          // velocity change from the contacts, M^-1 G^T lambda (owned bodies)
  int iterations = 0; // Krylov iterations of the last linear solve (0 for direct)
  int total_iterations = 0;
  double rel_residual = 0; // of the last linear solve: true ||b - A x|| / ||b|| in its form
  StopReason reason = StopReason::converged; // first failed solve's reason, else converged
  // every linear solve converged, and the step ended within kRescueFactor of sweep_tol (of it
  // with solver pgs or nncg), or, with a step accuracy, its error estimate within it
  bool converged = true;
  int active_set_passes = 0; // linear solves done (1 .. active_set_max)
  bool set_settled = false;  // the active set and its caps settled (see cap_tol)
  // (both 0 when not counted: StepOptions::residual)
  int released = 0; // contacts with zero impulse at the end (lambda_n < 0)
  int capped = 0;   // friction/rolling/twisting rows on their cone boundary
  // Relative residual of the contact conditions at the final lambda (see complementarity()
  // in cones.cpp): 0 for an exact solution of the nonsmooth step, -1 where it was not
  // measured (StepOptions::residual).
  double complementarity = 0;
  int sweeps = 0; // projected Gauss-Seidel sweeps done after the loop, rescue included
  // Their cost in full sweeps: contacts visited over this process's contacts (focused sweeps
  // visit fewer; PgsResult::visits).
  double sweep_equivalents = 0;
  bool rescued = false;  // the sweeps went on past opt.sweeps (StepOptions::rescue_sweeps)
  int slow_restarts = 0; // the sweeps started again (StepOptions::restart_sweeps)
  // The linear passes left the step worse than its warm start (complementarity residual), so
  // the sweeps started again from the warm start and their result was kept.
  bool restarted = false;
  StopReason sweep_reason = StopReason::converged; // of the sweeps (converged when none ran)
  // The impulses' remaining relative error as the sweeps estimate it (PgsResult): infinite
  // when they did not contract, the complementarity residual when none ran.
  double error_estimate = 0;
  FibreStats fibres;        // of the last pass's preconditioner
  double setup_seconds = 0; // preconditioner builds
  double solve_seconds = 0; // linear solves (direct: analysis, factorization and solve)
  double sweep_seconds = 0; // projected Gauss-Seidel sweeps and the residuals around them
  double total_seconds = 0; // the whole call
};

// Solves the contact problem of `sys`. Its bodies must hold the step's velocities and
// external forces, complete on ghosts; the rhs (spook_rhs) and the row mask are set here,
// and on return every row is active again and the rhs is the full spook_rhs(sys).
// Collective: every process calls it once per step (it may hold no contacts).
// `warm` (optional, rows per contact) is the warm start; every row's trial impulse from it
// (lambda + rho / A_ii) gives the first set: released contacts and capped cones.
// `comm` is the communicator the direct solver (MUMPS) runs on; the body numbering across
// processes comes from global_body_index(). MUMPS failures propagate as DirectSolverError.
// A solve that does not converge, or non-finite data, still gives finite lambda and dv
// (converged = false). With Method::pgs there is no linear pass: `converged` then says whether
// the sweeps met sweep_tol.
//
// The active-set loop (doc/design.md section 2): each pass solves the rows of the current set
// with the capped cones' impulses in the rhs; contacts with lambda_n < 0 are released, cones
// that leave their radius are capped along the solved direction. Rows outside the solve are
// judged by their trial impulse (lambda + rho / sigma with rho the row's residual): released
// contacts that would press again come back, capped cones that would stick are freed, at
// most 3 times per contact and cone in a step (anti-cycling). A projection then makes lambda
// feasible (lambda_n >= 0, every cone), and projected Gauss-Seidel sweeps follow while the
// complementarity residual exceeds sweep_tol: in piles the set rarely settles, and the sweeps
// are what makes the step's friction hold (StepResult::complementarity).
// `cache`: the sweeps' groups kept between the solves of one system's substeps (SweepCache).
StepResult solve_step(ContactSystem &sys, const Exchange &ex, const StepOptions &opt,
                      const Vector *warm, MPI_Comm comm, SweepCache *cache = nullptr);

} // namespace fibre
