// Projected Gauss-Seidel (nonlinear Gauss-Seidel) on the nonsmooth contact problem
// A lambda = b with the cones of cones.hpp: a sibling of the Krylov methods and MUMPS over the
// same ContactSystem. Each contact in turn moves to lambda_c + rho_c / scale_c with its current
// residual and is projected; the body velocities follow every update.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "fibre/algebra/cones.hpp"
#include "fibre/core/exchange.hpp"
#include "fibre/precond/fibres.hpp"
#include "fibre/solvers/solver_control.hpp"
#include "fibre/solvers/sweep_groups.hpp"

namespace fibre {

// Stop when a sweep moves lambda by at most tol relative to |lambda| (2-norms over all
// processes), or, with accuracy > 0, when the estimated remaining error of the impulses
// (PgsResult::error_estimate) is at most accuracy instead; or after max_sweeps sweeps.
// Stagnation: no new smallest change for stall_sweeps sweeps in a row.
struct PgsControl {
  int max_sweeps = 50;
  double tol = 1e-3;
  int stall_sweeps = 1000;
  // Nonsmooth nonlinear CG (Silcowitz, Niebe and Erleben 2010): the sweep's change is a
  // descent direction, and beta = |r_k+1|^2 / |r_k|^2 of the previous direction is added to it
  // (restarted when beta > 1); one extra G^T product per sweep.
  bool nonlinear_cg = false;
  // Fibre-block corrections before every sweep (fibre_blocks.hpp), the fibres built with
  // block_weight from the starting impulses.
  bool fibre_blocks = false;
  EdgeWeight block_weight = EdgeWeight::impulse;
  // Focused sweeps: after each full sweep, this many sweeps visit only the contacts that it
  // moved by at least 1e-3 of its mean change^2 (together at least 99.9% of its change^2).
  // The first sweep is full, then every (focus_sweeps + 1)-th counted from min_sweeps, and the
  // stopping rules are tested on full sweeps only (0: every sweep is full). Not with
  // nonlinear CG or fibre blocks. Most of a step's change is in a few contacts (the new
  // impacts, a sliding region), and the sweeps between full ones spend nothing on the rest.
  int focus_sweeps = 0;
  // Anderson acceleration (Walker and Ni 2011, type II) over this many sweeps (0: off): a sweep
  // is a fixed-point map g = G(x), and the next sweep starts from g less the combination of the
  // last differences of g whose differences of f = G(x) - x best cancel f (least squares). On a
  // settled stiff pile the sweeps' error lies in a few slow modes of the whole pile, which the
  // combination removes together. Not with focused sweeps, nonlinear CG or fibre blocks.
  int anderson = 0;
  // Anderson's map is this many sweeps: a mix after every anderson_period sweeps. A mix costs
  // about as much as a sweep (its vectors are memory traffic); mixing after every other sweep
  // gave the same accuracy for less (doc/design.md section 8).
  int anderson_period = 1;
  // Sweeps four contacts at a time (sweep_groups.hpp) where the processor has AVX2 and FMA:
  // the full sweeps and each colour phase, not the focused sweeps' lists.
  bool grouped = true;
  double accuracy = 0; // the error-estimate rule (0: off)
  // The error-estimate rule stops no sooner than this: a rule met before stops the sweeps
  // here (and a full sweep that changes nothing, or only by round-off, at once).
  int min_sweeps = 0;
  // The groups of the sweeps kept from one solve of a system's kinematics to the next (the
  // substeps of a step) and rebuilt for other kinematics; null: built for this solve alone.
  SweepCache *cache = nullptr;
  // A slow solve starts again once (0: never): from probe_sweeps sweeps on, with Anderson and
  // the accuracy rule, where PgsResult::predicted_sweeps exceeds restart_sweeps, the sweeps
  // start afresh from the last sweep's impulses (plain sweeps to min_sweeps, a new history).
  // Anderson's combination can settle into a cycle that a fresh history leaves (a LIGGGHTS
  // heap's step: 1,735 sweeps, restarted 193; bench/README.md, "Slow steps start again").
  double restart_sweeps = 0;
  int probe_sweeps = 30;
};

inline constexpr int kRateWindow = 5;
inline constexpr double kAndersonSafety = 2.0;
// Anderson's sweeps without a new smallest change after which the sweeps go on plain, from
// the best checkpointed sweep (at most stall_sweeps).
inline constexpr int kAndersonStallSweeps = 200;

struct PgsResult {
  StopReason reason = StopReason::max_iterations;
  int sweeps = 0;
  // Contacts visited over all sweeps (this process's): a sweep's cost is its visits, so
  // visits / contacts is the cost in full sweeps (focused sweeps visit fewer).
  long long visits = 0;
  double last_change = 0; // of the last (full) sweep, relative to |lambda|
  // The sweeps contract the error by about `contraction` per sweep (the geometric mean of the
  // ratios of successive changes over the last kRateWindow sweeps; with focused sweeps, from
  // the full sweep at least that far back), so the impulses' remaining relative error is
  // about last_change * contraction / (1 - contraction): infinite while the changes do not
  // fall.
  double contraction = 1;
  // Anderson acceleration: the estimate of I - J's smallest singular value (J the Jacobian of
  // Anderson's map, PgsControl::anderson_period sweeps) from the history, infinite without
  // one; -1 without acceleration. The estimate is then
  // kAndersonSafety * mixed_change / singular_value, mixed_change the last mix's change over
  // its sweeps relative to |lambda|.
  double singular_value = -1;
  double mixed_change = 0;
  std::vector<double> changes;  // per sweep (iteration)
  std::vector<int> full_sweeps; // the full sweeps' indices in `changes`
  // One more sweep's change: changes follows, and for a full sweep (every plain one)
  // last_change and contraction. A focused sweep's change leaves out the contacts it skips.
  void record(double change, bool full = true);
  // Forget the rate: the sweeps from here on are another iteration (Anderson given up).
  void restart_rate()
  {
    full_sweeps.clear();
    contraction = 1;
    singular_value = -1;
  }
  // Clumps (joint_blocks.hpp): |lambda| over the contacts' |lambda|, the joints left out (1
  // without joints; 1.27 to 1.58 on a heap of V clumps). The joints carry the clumps' internal
  // loads and are solved exactly given the contacts each sweep, so the contacts' error is the
  // solve's: the estimate is the impulses' remaining error relative to the contacts' |lambda|,
  // bounded by |delta lambda| / |lambda_contacts| (the joints' share of the change counted).
  double contact_scale = 1;
  double error_estimate() const;   // contact_scale * impulse_estimate()
  double impulse_estimate() const; // relative to all of lambda
  // The estimate when the accuracy rule was first met (infinite if never). The sweeps after it
  // (PgsControl::min_sweeps) only reduce the error, but their changes may fall to round-off,
  // where the estimate is undefined: the step reports the smaller of the two.
  double met_estimate = INFINITY;
  double reported_estimate() const { return std::min(error_estimate(), met_estimate); }
  bool converged() const { return reason == StopReason::converged; }
  // The sweeps still needed to bring the estimate to `accuracy`, from how fast the full sweeps'
  // changes fell over their last kPredictSweeps (infinite where they did not fall; 0 where the
  // estimate is met; -1 before there are that many).
  double predicted_sweeps(double accuracy) const;
  int slow_restarts = 0; // the solve started again (PgsControl::restart_sweeps)
  // Another solve from where this one ended: its sweeps follow this one's.
  void append(PgsResult then);
};

inline constexpr int kPredictSweeps = 10; // even: Anderson mixes after every other sweep

// Sweeps from lambda (feasible or not; it is projected contact by contact). `sys` must have
// every row active; `scale` comes from row_scales(sys). In parallel each process sweeps its
// own contacts, and the bodies that several processes' contacts move get the sum of their
// changes (Exchange::Halo). With the halo's two process colours a sweep is two phases, and the
// contacts on shared bodies are swept only in their process's colour's phase (a halo exchange
// ends each phase): where the processes that share a body differ in colour, one process's
// Gauss-Seidel sweep in another order. A body whose contacts n processes of one colour sweep
// (any n processes without colours) is split into n copies of mass m / n, one on each, whose
// velocity changes are summed after the phase (mass splitting, Tonge, Benevolenskiy and
// Pfeiffer 2012). Without either each process would correct a shared body by all that its own
// contacts ask, and together they overshoot (block Jacobi: 458 sweeps a step against 15 on one
// process).
// A sweep that produces non-finite values stops with StopReason::non_finite, its impulses
// back at the last checkpoint (at most 16 sweeps back; the start for the first 16).
PgsResult pgs(const ContactSystem &sys, const Exchange &ex, const Cones &cones, const Vector &b,
              const std::vector<Vec6> &scale, Vector &lambda, const PgsControl &control);

} // namespace fibre
