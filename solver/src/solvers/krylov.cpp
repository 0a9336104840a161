#include "fibre/solvers/krylov.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace fibre {

namespace {

// What the loop does after an iteration's bookkeeping.
enum class Next { iterate, restart, stop };

// Everything the three methods share: norms of b, the stop test with its true-residual
// check, history and the non-finite guard. The methods keep only their recurrences.
class KrylovState {
 public:
  KrylovState(const LinearOperator &A, const Preconditioner &P, const Vector &b, Vector &x,
              const StopControl &stop, const KrylovMonitor *monitor)
      : A_(A), b_(b), stop_(stop), monitor_(monitor), x0_(x)
  {
    if (b.size() != A.size()) throw std::invalid_argument("krylov: rhs size differs from A");
    if (x.size() != A.size()) x0_ = x = Vector::Zero(A.size());
    // A non-finite warm start is replaced by 0: x must stay finite whatever happens.
    if (!std::isfinite(A.dot(x, x))) x0_ = x = Vector::Zero(A.size());
    b_norm_ = A.norm(b);
    if (!std::isfinite(b_norm_)) {
      stop_now(StopReason::non_finite);
      return;
    }
    if (b_norm_ == 0) {
      x.setZero();
      stop_now(StopReason::converged);
      return;
    }
    Vector Pb;
    P.apply(b, Pb);
    const double bPb = A.dot(b, Pb);
    b_norm_P_ = bPb > 0 ? std::sqrt(bPb) : 0.0;
  }

  bool stopped() const { return stopped_; }

  // r = b - A x, reusing the one computed by the last convergence check of this x.
  void true_residual(const Vector &x, Vector &r)
  {
    if (!have_true_) compute_true(x);
    r = r_true_;
  }

  // Bookkeeping after iteration k (k = 0: the initial or restart residual, which is true).
  // r_norm: ||r|| of the (updated) residual; rPr: r^T P^-1 r as the method knows it;
  // trust_rPr: rPr is an estimate that may trigger the true-residual check (MINRES).
  Next step(int k, const Vector &x, double r_norm, double rPr, bool is_true, bool trust_rPr = false)
  {
    result_.iterations = k;
    have_true_ = is_true && have_true_;
    true_valid_ = is_true;
    if (is_true) true_norm_ = r_norm;
    const double rel = r_norm / b_norm_;
    record(k, x, rel, rPr);
    if (!std::isfinite(rel) || !std::isfinite(rPr)) return stop_now(StopReason::non_finite);
    if (k > 0 && stop_.accept && stop_.accept(k, x)) return stop_now(StopReason::converged);
    // MINRES's estimate counts once its updated residual has levelled off: no new minimum
    // for kLevelOff iterations (with a preconditioner the two norms differ).
    if (rel < best_rel_) {
      best_rel_ = rel;
      best_k_ = k;
    }
    const bool estimate_met = trust_rPr && k - best_k_ >= kLevelOff && b_norm_P_ > 0 &&
                              std::sqrt(rPr) <= stop_.tol * b_norm_P_;
    if (rel <= stop_.tol || estimate_met) {
      // Confirm on the true residual: the recursion drifts in floating point.
      if (!true_valid_) compute_true(x);
      if (true_norm_ / b_norm_ <= stop_.tol) return stop_now(StopReason::converged);
      if (!std::isfinite(true_norm_)) return stop_now(StopReason::non_finite);
      ++result_.restarts;
      stalled_checks_ = true_norm_ > 0.5 * last_check_norm_ ? stalled_checks_ + 1 : 0;
      last_check_norm_ = true_norm_;
      if (stalled_checks_ >= kMaxResidualChecks) return stop_now(StopReason::stagnation);
      if (k >= stop_.max_iter) return stop_now(StopReason::max_iterations);
      return Next::restart;
    }
    // Checked after convergence: at round-off level r^T P^-1 r is noise of either sign.
    if (rPr < 0) return stop_now(StopReason::breakdown); // P is not positive definite
    if (k >= stop_.max_iter) return stop_now(StopReason::max_iterations);
    return Next::iterate;
  }

  // A scalar that must be finite and positive (curvature, Lanczos norms).
  bool positive(double v)
  {
    if (!finite(v)) return false;
    if (v > 0) return true;
    stop_now(StopReason::breakdown);
    return false;
  }
  // A scalar about to enter x (step lengths) or the recurrences.
  bool finite(double v)
  {
    if (std::isfinite(v)) return true;
    stop_now(StopReason::non_finite);
    return false;
  }

  SolveResult finish(Vector &x)
  {
    // The scalar guards stop before anything non-finite enters x, so x is the last finite
    // iterate; this is the last line of defence (e.g. an operator returning Inf silently).
    if (!std::isfinite(A_.dot(x, x))) {
      x = x0_;
      true_valid_ = false;
      result_.reason = StopReason::non_finite;
    }
    double rel = 0;
    if (b_norm_ != 0) {
      if (std::isfinite(b_norm_) && !true_valid_) compute_true(x);
      rel = true_norm_ / b_norm_;
    }
    result_.rel_residual = std::isfinite(rel) ? rel : std::numeric_limits<double>::infinity();
    return result_;
  }

 private:
  Next stop_now(StopReason reason)
  {
    result_.reason = reason;
    stopped_ = true;
    return Next::stop;
  }

  void compute_true(const Vector &x)
  {
    A_.apply(x, r_true_);
    r_true_ = b_ - r_true_;
    true_norm_ = A_.norm(r_true_);
    have_true_ = true_valid_ = true;
  }

  void record(int k, const Vector &x, double rel, double rPr)
  {
    if (!monitor_ || !monitor_->record_history) return;
    IterationRecord rec;
    rec.iteration = k;
    rec.rel_residual = rel;
    rec.rel_residual_A = monitor_->norm_A > 0 ? rel * b_norm_ / monitor_->norm_A : 0.0;
    rec.rel_residual_P = b_norm_P_ > 0 && rPr >= 0 ? std::sqrt(rPr) / b_norm_P_ : 0.0;
    if (monitor_->velocity_error) rec.velocity_error = monitor_->velocity_error(x);
    result_.history.push_back(rec);
  }

  const LinearOperator &A_;
  const Vector &b_;
  const StopControl &stop_;
  const KrylovMonitor *monitor_;
  Vector x0_;               // finite fallback should x ever turn non-finite
  Vector r_true_;           // b - A x when have_true_
  bool have_true_ = false;  // r_true_ belongs to the current x
  bool true_valid_ = false; // true_norm_ belongs to the current x
  bool stopped_ = false;
  double b_norm_ = 0, b_norm_P_ = 0, true_norm_ = 0;
  double last_check_norm_ = std::numeric_limits<double>::infinity();
  int stalled_checks_ = 0; // failed checks in a row without the true residual halving
  static constexpr int kLevelOff = 10;
  double best_rel_ = std::numeric_limits<double>::infinity();
  int best_k_ = 0;
  SolveResult result_;
};

} // namespace

// Preconditioned CG on the Schur complement (thesis Algorithm 3, Uzawa with conjugate
// directions). rPr = r^T z with z = P^-1 r.
SolveResult cg(const LinearOperator &A, const Preconditioner &P, const Vector &b, Vector &x,
               const StopControl &stop, const KrylovMonitor *monitor)
{
  KrylovState s(A, P, b, x, stop, monitor);
  Vector r, z, p, Ap;
  double rz = 0;
  int k = 0;
  Next next = s.stopped() ? Next::stop : Next::restart;
  while (next != Next::stop) {
    if (next == Next::restart) {
      s.true_residual(x, r);
      P.apply(r, z);
      rz = A.dot(r, z);
      p = z;
      next = s.step(k, x, A.norm(r), rz, true);
      continue;
    }
    A.apply(p, Ap);
    const double pAp = A.dot(p, Ap);
    if (!s.positive(pAp)) break;
    const double alpha = rz / pAp;
    if (!s.finite(alpha)) break;
    x += alpha * p;
    r -= alpha * Ap;
    ++k;
    P.apply(r, z);
    const double rz_new = A.dot(r, z);
    next = s.step(k, x, A.norm(r), rz_new, false);
    if (next != Next::iterate) continue;
    const double beta = rz_new / rz;
    if (!s.finite(beta)) break;
    rz = rz_new;
    p = z + beta * p;
  }
  return s.finish(x);
}

// Preconditioned Conjugate Residual: CR on L^-1 A L^-T (P = L L^T) written in the original
// variables. It needs q = P^-1 A p besides A z; rPr = r^T z is what it minimises.
SolveResult conjugate_residual(const LinearOperator &A, const Preconditioner &P, const Vector &b,
                               Vector &x, const StopControl &stop, const KrylovMonitor *monitor)
{
  KrylovState s(A, P, b, x, stop, monitor);
  Vector r, z, p, Az, Ap, q;
  double zAz = 0;
  int k = 0;
  Next next = s.stopped() ? Next::stop : Next::restart;
  while (next != Next::stop) {
    if (next == Next::restart) {
      s.true_residual(x, r);
      P.apply(r, z);
      A.apply(z, Az);
      zAz = A.dot(z, Az);
      p = z;
      Ap = Az;
      next = s.step(k, x, A.norm(r), A.dot(r, z), true);
      if (next == Next::iterate && !s.positive(zAz)) break;
      continue;
    }
    P.apply(Ap, q);
    const double ApPAp = A.dot(Ap, q);
    if (!s.positive(ApPAp)) break;
    const double alpha = zAz / ApPAp;
    if (!s.finite(alpha)) break;
    x += alpha * p;
    r -= alpha * Ap;
    z -= alpha * q;
    ++k;
    next = s.step(k, x, A.norm(r), A.dot(r, z), false);
    if (next != Next::iterate) continue;
    A.apply(z, Az);
    const double zAz_new = A.dot(z, Az);
    if (!s.positive(zAz_new)) break;
    const double beta = zAz_new / zAz;
    zAz = zAz_new;
    p = z + beta * p;
    Ap = Az + beta * Ap;
  }
  return s.finish(x);
}

// MINRES (Paige and Saunders 1975) with an SPD preconditioner: preconditioned Lanczos
// (r1, r2 the last two unpreconditioned Lanczos vectors, y = P^-1 r2, v = y / beta), a
// Givens QR of the tridiagonal, and the search directions w. phibar, the recurrence's residual
// estimate, equals ||r||_P and decreases monotonically; the unpreconditioned residual r used by
// the stop test is carried along through A w (A v is the Lanczos product), so no extra
// operator application is needed.
SolveResult minres(const LinearOperator &A, const Preconditioner &P, const Vector &b, Vector &x,
                   const StopControl &stop, const KrylovMonitor *monitor)
{
  KrylovState s(A, P, b, x, stop, monitor);
  const Eigen::Index n = A.size();
  Vector r, r1, r2, y, v, Av, w, w1, w2, Aw, Aw1, Aw2;
  double beta = 0, oldb = 0, dbar = 0, epsln = 0, phibar = 0, cs = -1, sn = 0;
  int k = 0;
  Next next = s.stopped() ? Next::stop : Next::restart;
  while (next != Next::stop) {
    if (next == Next::restart) {
      s.true_residual(x, r);
      r1 = r;
      P.apply(r1, y);
      const double rPr = A.dot(r1, y);
      next = s.step(k, x, A.norm(r), rPr, true);
      if (next != Next::iterate) continue;
      beta = std::sqrt(rPr);
      if (!s.positive(beta)) break;
      r2 = r1;
      oldb = 0;
      dbar = 0;
      epsln = 0;
      phibar = beta;
      cs = -1;
      sn = 0;
      w.setZero(n);
      w2.setZero(n);
      Aw.setZero(n);
      Aw2.setZero(n);
      continue;
    }
    // Lanczos step.
    v = y / beta;
    A.apply(v, Av);
    y = Av;
    if (oldb > 0) y -= (beta / oldb) * r1;
    const double alpha = A.dot(v, y);
    y -= (alpha / beta) * r2;
    r1.swap(r2);
    r2 = y;
    P.apply(r2, y);
    oldb = beta;
    const double beta2 = A.dot(r2, y);
    if (!s.finite(alpha) || !s.finite(beta2)) break;
    // Negative beyond round-off: P is not positive definite. At round-off: Lanczos is done.
    if (beta2 < -1e-14 * oldb * oldb && !s.positive(beta2)) break;
    beta = std::sqrt(std::max(beta2, 0.0));
    // Apply the previous rotation, then the new one that annihilates beta.
    const double oldeps = epsln;
    const double delta = cs * dbar + sn * alpha;
    const double gbar = sn * dbar - cs * alpha;
    epsln = sn * beta;
    dbar = -cs * beta;
    const double gamma = std::hypot(gbar, beta);
    if (!s.positive(gamma)) break;
    cs = gbar / gamma;
    sn = beta / gamma;
    const double phi = cs * phibar;
    phibar = sn * phibar;
    if (!s.finite(phi)) break;
    // w_k = (v_k - oldeps w_{k-2} - delta w_{k-1}) / gamma, and A w_k alongside.
    w1.swap(w2);
    w2.swap(w);
    w = (v - oldeps * w1 - delta * w2) / gamma;
    Aw1.swap(Aw2);
    Aw2.swap(Aw);
    Aw = (Av - oldeps * Aw1 - delta * Aw2) / gamma;
    x += phi * w;
    r -= phi * Aw;
    ++k;
    next = s.step(k, x, A.norm(r), phibar * phibar, false, true);
    // beta == 0: the Krylov space is invariant, the next Lanczos vector does not exist.
    if (next == Next::iterate && !s.positive(beta)) break;
  }
  return s.finish(x);
}

SolveResult krylov_solve(Method m, const LinearOperator &A, const Preconditioner &P,
                         const Vector &b, Vector &x, const StopControl &stop,
                         const KrylovMonitor *monitor)
{
  switch (m) {
  case Method::cg:
    return cg(A, P, b, x, stop, monitor);
  case Method::cr:
    return conjugate_residual(A, P, b, x, stop, monitor);
  case Method::minres:
    return minres(A, P, b, x, stop, monitor);
  case Method::direct:
  case Method::pgs:
  case Method::nncg:
  case Method::fbgs:
  case Method::apgd:
    break;
  }
  throw std::invalid_argument(std::string("krylov_solve: ") + to_string(m) +
                              " is not a Krylov method");
}

} // namespace fibre
