#include "fibre/step/step_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "fibre/algebra/cones.hpp"
#include "fibre/algebra/kernels.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/core/text.hpp"
#include "fibre/solvers/apgd.hpp"
#include "fibre/solvers/direct.hpp"
#include "fibre/solvers/pgs.hpp"

namespace fibre {

std::string describe(const StepOptions &opt)
{
  const auto g = format_g;
  return std::string("form ") + to_string(opt.form) + ", solver " + to_string(opt.solver) +
         ", precond " + to_string(opt.precond.kind) + ", weight " + to_string(opt.precond.weight) +
         ", tol " + (opt.accuracy > 0 ? g(opt.accuracy) : std::string("none")) + ", linear_tol " +
         g(opt.stop.tol) + ", pass_tol " + g(opt.pass_tol) + ", maxiter " +
         std::to_string(opt.stop.max_iter) + ", active_set " + std::to_string(opt.active_set_max) +
         ", sweeps " + std::to_string(opt.sweeps) + ", sweep_tol " + g(opt.sweep_tol) +
         ", rescue_sweeps " + std::to_string(opt.rescue_sweeps) + ", min_sweeps " +
         std::to_string(opt.min_sweeps) + ", focus_sweeps " + std::to_string(opt.focus_sweeps) +
         ", anderson " + std::to_string(opt.anderson) +
         (opt.anderson > 0 ? ", anderson_period " + std::to_string(opt.anderson_period) +
                                 ", restart_sweeps " + g(opt.restart_sweeps)
                           : "") +
         (opt.sweep_cg ? ", sweep_cg yes" : "") + (opt.sweep_blocks ? ", sweep_blocks yes" : "") +
         (opt.sweep_groups ? "" : ", sweep_groups no");
}

namespace {

// One contact's place in the active set. A capped cone holds its impulse on the boundary,
// radius * dir, outside the solve. Releasing and capping may be undone kMaxReversals times per
// step and contact: redundant networks can otherwise make the loop cycle between two sets.
constexpr int kMaxReversals = 3;
struct ContactState {
  bool released = false;
  int reactivations = 0;
  bool capped[3] = {false, false, false};
  int uncaps[3] = {0, 0, 0};
  Eigen::Vector2d dir[3] = {Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(),
                            Eigen::Vector2d::Zero()};
};

// The active-set loop of doc/design.md section 2 around one linear solver, then the sweeps.
class StepSolver {
 public:
  StepSolver(ContactSystem &sys, const Exchange &ex, const StepOptions &opt, MPI_Comm comm,
             SweepCache *cache)
      : sys_(sys), ex_(ex), opt_(opt), comm_(comm), cache_(cache), rows_(sys.rows()),
        nc_(sys.num_contacts()), cones_(sys), state_(sweeps_only() ? 0 : nc_),
        all_rows_(sys.contact_dofs(), 1)
  {
  }

  StepResult run(const Vector *warm);

 private:
  Vector initial_impulses(const Vector *warm);
  void active_set_loop(Vector &lambda, StepResult &res);

  double coeff(int c, int k) const { return cones_.coeff(c, k); }
  bool sweeps_only() const
  {
    return opt_.solver == Method::pgs || opt_.solver == Method::nncg ||
           opt_.solver == Method::fbgs || opt_.solver == Method::apgd;
  }
  Eigen::Index base(int c) const { return Eigen::Index(rows_) * c; }
  std::vector<unsigned char> active_mask() const;
  Vector fixed_impulses(const Vector &lambda) const;
  Vector linear_solve(const Vector &b, const Vector &warm, const StopControl &stop, bool tight,
                      StepResult &res);
  int update_set(const Vector &lambda, const std::vector<unsigned char> &mask);
  void project(Vector &lambda) const;
  void finish(Vector &lambda, StepResult &res) const;
  void count_set(const Vector &lambda, StepResult &res) const;

  ContactSystem &sys_;
  const Exchange &ex_;
  const StepOptions &opt_;
  MPI_Comm comm_;
  SweepCache *cache_;
  const int rows_, nc_;
  const Cones cones_;
  std::vector<ContactState> state_; // the active-set loop's; none with the sweeps alone
  const std::vector<unsigned char> all_rows_;
  Vector b_full_;                // the rhs with every row active and no fixed impulses
  std::vector<Vec6> row_scales_; // the sweeps' and residuals' row scales, every row active
  std::vector<Vec6> diagonal_;   // A_ii per contact, every row active
  StopReason last_reason_ = StopReason::converged;
};

std::vector<unsigned char> StepSolver::active_mask() const
{
  std::vector<unsigned char> mask(all_rows_.size(), 0);
  for (int c = 0; c < nc_; ++c) {
    if (state_[c].released) continue;
    mask[base(c)] = 1;
    for (int k = 0; k < num_cones(rows_); ++k) {
      if (coeff(c, k) <= 0 || state_[c].capped[k]) continue;
      for (int i = 0; i < kCones[k].size; ++i) mask[base(c) + kCones[k].first + i] = 1;
    }
  }
  return mask;
}

// Impulses of the capped cones, from the newest normal impulse.
Vector StepSolver::fixed_impulses(const Vector &lambda) const
{
  Vector fixed = Vector::Zero(sys_.contact_dofs());
  for (int c = 0; c < nc_; ++c) {
    if (state_[c].released) continue;
    const double ln = std::max(lambda[base(c)], 0.0);
    for (int k = 0; k < num_cones(rows_); ++k)
      if (state_[c].capped[k])
        set_cone(fixed, base(c), kCones[k], coeff(c, k) * ln * state_[c].dir[k]);
  }
  return fixed;
}

// Solves the masked system A lambda = b in the chosen form and returns lambda.
// A loose solve (tight false) that misses its tol does not count as a failed solve: the
// passes after it go on from its iterate.
Vector StepSolver::linear_solve(const Vector &b, const Vector &warm, const StopControl &stop,
                                bool tight, StepResult &res)
{
  SolveResult sr;
  Vector lambda;
  // Non-finite data (a body with NaN velocity) reach no solver: the warm start stands.
  if (ex_.max(b.allFinite() ? 0.0 : 1.0) > 0) {
    sr.reason = StopReason::non_finite;
    sr.rel_residual = std::numeric_limits<double>::infinity();
    lambda = warm;
  } else if (opt_.solver == Method::direct) {
    const auto t0 = Clock::now();
    lambda = direct_solve(opt_.form, sys_, ex_, b, comm_);
    res.solve_seconds += seconds_since(t0);
    ContactSpaceOperator A(sys_, ex_);
    Vector Alambda;
    A.apply(lambda, Alambda);
    const double b_norm = A.norm(b);
    sr.reason = lambda.allFinite() ? StopReason::converged : StopReason::non_finite;
    if (ex_.max(sr.reason == StopReason::non_finite ? 1.0 : 0.0) > 0) {
      sr.reason = StopReason::non_finite;
      lambda = warm;
    }
    sr.iterations = 0;
    sr.rel_residual = b_norm > 0 ? A.norm(b - Alambda) / b_norm : 0.0;
  } else {
    const auto t0 = Clock::now();
    PrecondOptions popt = opt_.precond;
    Vector last_normal;
    if (popt.kind != PrecondKind::none && popt.weight == EdgeWeight::impulse && !popt.impulses) {
      // The warm start's normal impulses stand in for the last step's.
      last_normal = Vector::Zero(nc_);
      for (int c = 0; c < nc_; ++c) last_normal[c] = warm[base(c)];
      popt.impulses = &last_normal;
    }
    const auto P = make_preconditioner(opt_.form, sys_, ex_, popt, &res.fibres);
    res.setup_seconds += seconds_since(t0);
    const auto t1 = Clock::now();
    const auto A = make_operator(opt_.form, sys_, ex_);
    const Method m = opt_.solver;
    if (opt_.form == Form::contact) {
      lambda = warm;
      sr = krylov_solve(m, *A, *P, b, lambda, stop);
    } else {
      Vector dv = body_from_lambda(sys_, ex_, warm);
      sr = krylov_solve(m, *A, *P, body_rhs(sys_, ex_, b), dv, stop);
      lambda = lambda_from_body(sys_, ex_, b, dv);
    }
    res.solve_seconds += seconds_since(t1);
  }
  last_reason_ = sr.reason;
  res.iterations = sr.iterations;
  res.total_iterations += sr.iterations;
  res.rel_residual = sr.rel_residual;
  if (!sr.converged() && res.converged && (tight || sr.reason == StopReason::non_finite)) {
    res.converged = false;
    res.reason = sr.reason;
  }
  return lambda;
}

// Decides the next active set from the pass's lambda (active rows solved, capped rows fixed).
// Rows outside the solve are judged by their trial impulse lambda + rho / A_ii, rho the row's
// residual of the full system (the row equation solved for that row alone): it
// re-activates released contacts that would press again and un-caps cones that would stick.
// A capped cone takes its direction from the newest trial impulse, i.e. against the slip the
// pass left, so that friction dissipates; the magnitude follows l_n.
// Returns the number of local changes wanted (a reversal over budget counts but is not done).
int StepSolver::update_set(const Vector &lambda, const std::vector<unsigned char> &mask)
{
  Vector G_dv;
  g_apply(sys_, velocity_change(sys_, ex_, lambda), G_dv);
  const Vector rho = b_full_ - G_dv - sys_.sigma().cwiseProduct(lambda);
  // One Gauss-Seidel step per row outside the solve: lambda + rho / A_ii. Dividing by Sigma
  // alone (tiny) would only see the sign of rho and never find a cone's interior.
  Vector value = lambda;
  for (int c = 0; c < nc_; ++c) {
    const Vec6 &D = diagonal_[c];
    for (int r = 0; r < rows_; ++r) {
      const Eigen::Index row = base(c) + r;
      if (!mask[row]) value[row] += rho[row] / D[r];
    }
  }

  int changes = 0;
  for (int c = 0; c < nc_; ++c) {
    ContactState &st = state_[c];
    const double ln = value[base(c)];
    if (st.released && ln > 0) {
      ++changes; // also when blocked: the set is then not settled, only frozen
      if (st.reactivations < kMaxReversals) {
        ++st.reactivations;
        st.released = false;
      }
    } else if (!st.released && !(ln > 0)) {
      ++changes;
      st.released = true;
    }
    if (st.released) {
      for (bool &capped : st.capped) capped = false;
      continue;
    }
    for (int k = 0; k < num_cones(rows_); ++k) {
      const double radius = coeff(c, k) * ln;
      if (!(radius > 0)) continue;
      const Eigen::Vector2d t = cone_values(value, base(c), kCones[k]);
      const double tn = t.norm();
      if (tn > radius) {
        st.dir[k] = t / tn; // against the slip the pass left
        changes += !st.capped[k];
        st.capped[k] = true;
      } else if (st.capped[k] && tn < radius * (1 - 1e-9)) {
        // The hysteresis keeps round-off from flipping a cone that sits on its boundary.
        ++changes;
        if (st.uncaps[k] < kMaxReversals) {
          ++st.uncaps[k];
          st.capped[k] = false;
        }
      }
    }
  }
  return changes;
}

// Projection: lambda_n >= 0 and every cone, capped cones on their boundary along the slip
// direction with the final normal impulse.
void StepSolver::project(Vector &lambda) const
{
  const bool tracked = !state_.empty();
  for (int c = 0; c < nc_; ++c) {
    const double ln = lambda[base(c)];
    if ((tracked && state_[c].released) || !(ln > 0)) {
      lambda.segment(base(c), rows_).setZero();
      continue;
    }
    for (int k = 0; k < num_cones(rows_); ++k) {
      const Cone &cone = kCones[k];
      const double radius = coeff(c, k) * ln;
      Eigen::Vector2d t = cone_values(lambda, base(c), cone);
      if (tracked && state_[c].capped[k]) {
        t = radius * state_[c].dir[k];
      } else {
        // inside by a margin far above round-off: no square root (most cones stick)
        const double squared = t.squaredNorm();
        if (squared <= (1 - 1e-12) * radius * radius) continue;
        const double tn = std::sqrt(squared);
        if (tn <= radius) continue;
        t = tn > 0 && std::isfinite(tn) ? Eigen::Vector2d(t * (radius / tn))
                                        : Eigen::Vector2d::Zero();
      }
      set_cone(lambda, base(c), cone, t);
    }
  }
}

// Projected Gauss-Seidel on the full system while the impulses are not accurate enough:
// they finish what the active-set loop leaves (an unsettled set, caps from a lagged l_n, a
// loose last pass), or do the whole solve (Method::pgs).
void StepSolver::finish(Vector &lambda, StepResult &res) const
{
  const auto t_sweep = Clock::now();
  const std::vector<Vec6> &scale = row_scales_;
  res.sweeps = 0;
  res.sweep_equivalents = 0;
  const bool accuracy = opt_.accuracy > 0;
  // Under the accuracy rule the sweeps run whatever the residual, and measure it after.
  if (!accuracy || opt_.sweeps <= 0) {
    res.complementarity = complementarity(sys_, ex_, cones_, b_full_, lambda, scale);
    res.error_estimate = res.complementarity;
  }
  if (opt_.sweeps > 0 && (accuracy || res.complementarity > opt_.sweep_tol)) {
    PgsControl control{opt_.sweeps, opt_.sweep_tol};
    control.accuracy = opt_.accuracy;
    // Under the accuracy rule only the cap ends a step that has not converged: on a stiff
    // pile the change per sweep can stop falling for a thousand sweeps while a wedged sphere
    // works its way out, and then fall to the tol (bench/README.md, "The stiff decks'
    // stagnating steps").
    if (accuracy) control.stall_sweeps = std::max(opt_.sweeps, 1);
    control.min_sweeps = opt_.min_sweeps;
    control.focus_sweeps = opt_.focus_sweeps;
    control.anderson = opt_.anderson;
    control.anderson_period = opt_.anderson_period;
    control.restart_sweeps = opt_.restart_sweeps;
    control.grouped = opt_.sweep_groups;
    control.nonlinear_cg = opt_.sweep_cg || opt_.solver == Method::nncg;
    control.fibre_blocks = opt_.sweep_blocks || opt_.solver == Method::fbgs;
    control.block_weight = opt_.precond.weight;
    control.cache = cache_;
    // the residual decides the rescue and the restart, except under the accuracy rule with a
    // sweeps-only solver
    const bool measured = opt_.residual || !accuracy || !sweeps_only();
    const auto sweep = [&]() {
      const PgsResult pr = opt_.solver == Method::apgd
                               ? apgd(sys_, ex_, cones_, b_full_, scale, lambda, control)
                               : pgs(sys_, ex_, cones_, b_full_, scale, lambda, control);
      res.sweeps += pr.sweeps;
      res.sweep_equivalents += nc_ > 0 ? double(pr.visits) / nc_ : 0.0;
      res.sweep_reason = pr.reason;
      res.slow_restarts += pr.slow_restarts;
      res.error_estimate = pr.reported_estimate();
      res.complementarity =
          measured ? complementarity(sys_, ex_, cones_, b_full_, lambda, scale) : kNotMeasured;
    };
    sweep();
    // far from sweep_tol at the cap: sweep on (collective: every process sees the residual);
    // with a sweeps-only solver the sweeps are the whole solve the user asked for
    if (!sweeps_only() && !accuracy && res.sweep_reason == StopReason::max_iterations &&
        opt_.rescue_sweeps > res.sweeps && res.complementarity > kRescueFactor * opt_.sweep_tol) {
      control.max_sweeps = opt_.rescue_sweeps - res.sweeps;
      res.rescued = true;
      sweep();
    }
  }
  res.sweep_seconds = seconds_since(t_sweep);
}

// Released contacts and rows on a cone boundary of feasible impulses.
void StepSolver::count_set(const Vector &lambda, StepResult &res) const
{
  double counts[2] = {0, 0};
  for (int c = 0; c < nc_; ++c) {
    const double ln = lambda[base(c)];
    if (!(ln > 0)) {
      counts[0] += 1;
      continue;
    }
    for (int k = 0; k < num_cones(rows_); ++k) {
      const double radius = coeff(c, k) * ln;
      if (radius > 0 && cone_values(lambda, base(c), kCones[k]).norm() >= radius * (1 - 1e-12))
        counts[1] += kCones[k].size;
    }
  }
  ex_.sum(counts, 2);
  res.released = static_cast<int>(counts[0]);
  res.capped = static_cast<int>(counts[1]);
}

// The warm start when every process has a usable one (the decision is global: the solves are
// collective), else zero. Its trial impulses give the first set: contacts that opened since the
// last step start released and sliding cones start capped against the slip. (Capping the cones
// whose warm impulse lies on the boundary instead gave 2-6x deeper overlaps in the material
// scene.)
Vector StepSolver::initial_impulses(const Vector *warm)
{
  const Eigen::Index n = sys_.contact_dofs();
  const bool warm_ok = warm && warm->size() == n && warm->allFinite();
  const bool use_warm = ex_.max(warm_ok ? 0.0 : 1.0) == 0.0;
  Vector lambda = use_warm ? *warm : Vector::Zero(n);
  if (use_warm && !sweeps_only()) update_set(lambda, std::vector<unsigned char>(n, 0));
  return lambda;
}

// The bounded active-set loop: each pass solves the current set's rows, then the set follows
// the pass's impulses.
void StepSolver::active_set_loop(Vector &lambda, StepResult &res)
{
  const Eigen::Index n = sys_.contact_dofs();
  // Passes that only decide the set solve to pass_tol; once the set has settled (or at the
  // last pass) one solve to tol follows, warm-started from the loose one.
  const int max_passes = std::max(1, opt_.active_set_max);
  bool tight = !(opt_.pass_tol > opt_.stop.tol) || opt_.solver == Method::direct;
  double last_changes = std::numeric_limits<double>::infinity();
  for (int pass = 0; pass < max_passes; ++pass) {
    if (pass == max_passes - 1) tight = true;
    StopControl stop = opt_.stop;
    if (!tight) stop.tol = opt_.pass_tol;
    // Capped cones enter the rhs as a fixed velocity change, computed with every row active.
    const Vector fixed = fixed_impulses(lambda);
    const Vector extra_dv = velocity_change(sys_, ex_, fixed);
    const std::vector<unsigned char> mask = active_mask();
    sys_.set_row_mask(mask);
    const Vector b = spook_rhs(sys_, &extra_dv);
    sys_.set_rhs(b);
    Vector warm_active = lambda;
    for (Eigen::Index row = 0; row < n; ++row)
      if (!mask[row]) warm_active[row] = 0.0;
    const Vector solved = linear_solve(b, warm_active, stop, tight, res);
    ++res.active_set_passes;
    lambda = solved + fixed; // disjoint rows
    sys_.set_row_mask(all_rows_);
    if (last_reason_ == StopReason::non_finite) break;
    const int changes = update_set(lambda, mask);
    // Settled: the same set, and caps (newest l_n) that moved by no more than cap_tol relative
    // to the largest impulse. The caps converge linearly (a fixed-point iteration on l_n).
    double drift[2] = {(fixed_impulses(lambda) - fixed).lpNorm<Eigen::Infinity>(),
                       lambda.lpNorm<Eigen::Infinity>()};
    ex_.max(drift, 2);
    const double global_changes = ex_.sum(static_cast<double>(changes));
    if (global_changes == 0 && drift[0] <= opt_.cap_tol * drift[1]) {
      // A loose solve may have met tol anyway (every process sees the same global residual).
      if (tight || res.rel_residual <= opt_.stop.tol) {
        res.set_settled = true;
        break;
      }
      tight = true;
    }
    // Loose solves decide the set only while it improves: near the end their error (in the
    // body form amplified by Sigma^-1 in lambda) would flip rows that sit near a boundary.
    if (global_changes >= last_changes) tight = true;
    last_changes = global_changes;
  }
}

StepResult StepSolver::run(const Vector *warm)
{
  const auto t_start = Clock::now();
  StepResult res;
  sys_.set_row_mask(all_rows_);
  b_full_ = spook_rhs(sys_);
  diagonal_.resize(nc_);
  for (int c = 0; c < nc_; ++c) diagonal_[c] = diagonal_entries(sys_, c);
  row_scales_ = row_scales(diagonal_, rows_);
  Vector lambda = initial_impulses(warm);
  // After a linear pass, the projected warm start and its residual: the step never ends worse
  // than the sweeps alone would leave it from there (and the sweeps alone start there).
  Vector start;
  double start_residual = 0.0;
  if (!sweeps_only()) {
    start = lambda;
    project(start);
    start_residual = complementarity(sys_, ex_, cones_, b_full_, start, row_scales_);
    active_set_loop(lambda, res);
  }
  // Feasible impulses, then projected Gauss-Seidel sweeps while they are not accurate enough.
  // (Projecting an unsettled pass alone could zero a tensile impulse that balances large
  // compressive ones and kick the bodies between them: 29 m/s in one silo step.)
  project(lambda);
  if (last_reason_ != StopReason::non_finite) finish(lambda, res);
  // A pass whose projection the sweeps could not repair (a jammed pack under a moving wall:
  // residual 1.45 from a warm start at 0.04, bodies thrown at 70 m/s): sweep from the warm
  // start instead, and keep the better of the two.
  if (!sweeps_only() && !(res.complementarity <= std::max(start_residual, opt_.sweep_tol))) {
    StepResult again = res;
    finish(start, again);
    res.sweeps += again.sweeps;
    res.sweep_equivalents += again.sweep_equivalents;
    res.sweep_seconds += again.sweep_seconds;
    if (!(again.complementarity >= res.complementarity)) {
      lambda = std::move(start);
      res.complementarity = again.complementarity;
      res.error_estimate = again.error_estimate;
      res.sweep_reason = again.sweep_reason;
      res.restarted = true;
    }
  }
  // The step's own target: its accuracy (tol); else sweep_tol, within kRescueFactor of it after
  // a linear pass. Sweeps that stopped moving above it stagnated.
  const bool missed = opt_.accuracy > 0 ? !(res.error_estimate <= opt_.accuracy)
                      : sweeps_only()
                          ? res.complementarity > opt_.sweep_tol
                          : opt_.sweeps > 0 && res.complementarity > kRescueFactor * opt_.sweep_tol;
  if (missed && res.converged) {
    res.converged = false;
    res.reason =
        res.sweep_reason == StopReason::converged ? StopReason::stagnation : res.sweep_reason;
  }
  if (opt_.residual) count_set(lambda, res);
  sys_.set_rhs(std::move(b_full_));
  res.dv = body_from_lambda(sys_, ex_, lambda);
  res.lambda = std::move(lambda);
  res.total_seconds = seconds_since(t_start);
  return res;
}

} // namespace

StepResult solve_step(ContactSystem &sys, const Exchange &ex, const StepOptions &opt,
                      const Vector *warm, MPI_Comm comm, SweepCache *cache)
{
  StepSolver solver(sys, ex, opt, comm, cache);
  return solver.run(warm);
}

} // namespace fibre
