// The Krylov methods against dense direct solutions (reference.hpp), judged on the velocities
// M^-1 G^T lambda they produce, plus their contracts: monotone residuals, warm starts, honest
// residuals, typed stop reasons.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fibre/precond/preconditioner_family.hpp"
#include "fibre/scenes.hpp"
#include "fibre/solvers/krylov.hpp"
#include "reference.hpp"

using namespace fibre;

namespace {

using fibre::test::rel_diff;

const Method kMethods[] = {Method::cg, Method::cr, Method::minres};
const PrecondKind kPreconds[] = {PrecondKind::none, PrecondKind::jacobi, PrecondKind::block,
                                 PrecondKind::fibre, PrecondKind::tree};
const Form kForms[] = {Form::contact, Form::body};

// The dense reference of one system: lambda* = A^-1 b and dv* = M^-1 G^T lambda*, and the
// body form's own dense solution K^-1 G^T Sigma^-1 b.
struct Reference {
  test::Dense G, Minv;
  Vector sigma, b, lambda, dv, dv_body;

  explicit Reference(const ContactSystem &sys)
      : G(test::dense_G(sys)), Minv(test::dense_Minv(sys)), sigma(test::dense_sigma(sys)),
        b(sys.rhs())
  {
    lambda = test::dense_A(sys).llt().solve(b);
    dv = velocities(lambda);
    const Vector rhs = G.transpose() * b.cwiseQuotient(sigma);
    dv_body = test::dense_K(sys).llt().solve(rhs);
  }
  Vector velocities(const Vector &l) const { return Minv * (G.transpose() * l); }
};

// A scene per fixture use; the pile has walls, a few hundred contacts and the gap term in b.
ContactSystem scene(int which)
{
  SceneParams p;
  if (which == 0) return grid_scene(p);
  p.seed = 7;
  return pile_scene(100, p);
}

// A plain symmetric matrix as an operator, for contracts that need no contact system.
class DenseOperator final : public LinearOperator {
 public:
  explicit DenseOperator(test::Dense M) : M_(std::move(M)) {}
  Eigen::Index size() const override { return M_.rows(); }
  void apply(const Vector &x, Vector &y) const override { y = M_ * x; }
  double dot(const Vector &x, const Vector &y) const override { return x.dot(y); }

 private:
  test::Dense M_;
};

// Wraps an operator and poisons its n-th product with a NaN.
class PoisonedOperator final : public LinearOperator {
 public:
  PoisonedOperator(const LinearOperator &A, int poison_at) : A_(A), poison_at_(poison_at) {}
  Eigen::Index size() const override { return A_.size(); }
  void apply(const Vector &x, Vector &y) const override
  {
    A_.apply(x, y);
    if (++calls_ == poison_at_) y[0] = std::numeric_limits<double>::quiet_NaN();
  }
  double dot(const Vector &x, const Vector &y) const override { return A_.dot(x, y); }

 private:
  const LinearOperator &A_;
  int poison_at_;
  mutable int calls_ = 0;
};

} // namespace

TEST(Krylov, Names)
{
  for (Method m : kMethods) {
    Method back;
    ASSERT_TRUE(parse(to_string(m), back));
    EXPECT_EQ(back, m);
  }
  Method m;
  EXPECT_TRUE(parse("cg", m));
  EXPECT_EQ(m, Method::cg);
  EXPECT_FALSE(parse("gmres", m));
  for (StopReason r : {StopReason::converged, StopReason::max_iterations, StopReason::breakdown,
                       StopReason::non_finite, StopReason::stagnation}) {
    StopReason back;
    ASSERT_TRUE(parse(to_string(r), back));
    EXPECT_EQ(back, r);
  }
  StopReason r;
  EXPECT_FALSE(parse("done", r));
}

// Every method x preconditioner x form reaches the dense solution's velocities.
TEST(Krylov, AllCombinationsReachDirectVelocities)
{
  for (int which : {0, 1}) {
    const ContactSystem sys = scene(which);
    const Reference ref(sys);
    for (Form form : kForms) {
      const auto A = make_operator(form, sys, serial_exchange());
      const Vector b = form == Form::contact ? ref.b : body_rhs(sys, serial_exchange(), ref.b);
      for (PrecondKind kind : kPreconds) {
        PrecondOptions popt;
        popt.kind = kind;
        const auto P = make_preconditioner(form, sys, serial_exchange(), popt);
        for (Method m : kMethods) {
          SCOPED_TRACE(std::string(which ? "pile " : "grid ") + to_string(form) + " " +
                       to_string(kind) + " " + to_string(m));
          // Near each form's attainable accuracy (contact ~1e-13, body ~1e-15 here).
          StopControl stop;
          stop.tol = form == Form::contact ? 1e-11 : 1e-13;
          stop.max_iter = 5000;
          Vector x = Vector::Zero(A->size());
          const SolveResult res = krylov_solve(m, *A, *P, b, x, stop);
          EXPECT_EQ(res.reason, StopReason::converged);
          EXPECT_LE(res.rel_residual, stop.tol);
          Vector lambda = x;
          if (form == Form::body) {
            lambda = lambda_from_body(sys, serial_exchange(), ref.b, x);
            EXPECT_LT(rel_diff(x, ref.dv), 1e-8) << "body dv against the dual dv*";
          }
          EXPECT_LT(rel_diff(ref.velocities(lambda), ref.dv), 1e-8);
        }
      }
    }
  }
}

// The reported residual is the true one, recomputed here with the dense A.
TEST(Krylov, ReportedResidualIsTrue)
{
  const ContactSystem sys = scene(1);
  const test::Dense Ad = test::dense_A(sys);
  const ContactSpaceOperator A(sys, serial_exchange());
  const IdentityPreconditioner P;
  for (Method m : kMethods) {
    SCOPED_TRACE(to_string(m));
    StopControl stop;
    stop.tol = 1e-14;
    stop.max_iter = 7;
    Vector x = Vector::Zero(A.size());
    const SolveResult res = krylov_solve(m, A, P, sys.rhs(), x, stop);
    EXPECT_EQ(res.reason, StopReason::max_iterations);
    EXPECT_EQ(res.iterations, 7);
    const double truth = (sys.rhs() - Ad * x).norm() / sys.rhs().norm();
    EXPECT_NEAR(res.rel_residual, truth, 1e-10 * truth);
  }
}

// CR and MINRES minimise ||r||_P: its history never grows; unpreconditioned, that is ||r||.
TEST(Krylov, CrAndMinresResidualsAreMonotone)
{
  const ContactSystem sys = scene(1);
  for (Form form : kForms) {
    const auto A = make_operator(form, sys, serial_exchange());
    const Vector b =
        form == Form::contact ? sys.rhs() : body_rhs(sys, serial_exchange(), sys.rhs());
    for (PrecondKind kind : kPreconds) {
      PrecondOptions popt;
      popt.kind = kind;
      const auto P = make_preconditioner(form, sys, serial_exchange(), popt);
      for (Method m : {Method::cr, Method::minres}) {
        SCOPED_TRACE(std::string(to_string(form)) + " " + to_string(kind) + " " + to_string(m));
        StopControl stop;
        stop.tol = 1e-10;
        stop.max_iter = 3000;
        KrylovMonitor mon;
        mon.record_history = true;
        Vector x = Vector::Zero(A->size());
        const SolveResult res = krylov_solve(m, *A, *P, b, x, stop, &mon);
        ASSERT_EQ(res.reason, StopReason::converged);
        ASSERT_GE(res.history.size(), std::size_t(res.iterations) + 1);
        EXPECT_DOUBLE_EQ(res.history[0].rel_residual, 1.0); // x0 = 0
        EXPECT_NEAR(res.history[0].rel_residual_P, 1.0, 1e-12);
        // Up to the first restart from the true residual (a restart entry repeats its
        // iteration number and may legitimately sit above the updated residual).
        std::size_t k = 1;
        for (; k < res.history.size() && res.history[k].iteration > res.history[k - 1].iteration;
             ++k) {
          EXPECT_LE(res.history[k].rel_residual_P, res.history[k - 1].rel_residual_P * (1 + 1e-12))
              << "iteration " << k;
          if (kind == PrecondKind::none) {
            EXPECT_LE(res.history[k].rel_residual, res.history[k - 1].rel_residual * (1 + 1e-12))
                << "iteration " << k;
          }
        }
        EXPECT_LT(res.history[k - 1].rel_residual, 1e-9); // the checked stretch is the run
      }
    }
  }
}

// CG's residual is not monotone, but it must agree with the updated residual recorded.
TEST(Krylov, HistoryRecordsVelocityErrorAndNormA)
{
  const ContactSystem sys = scene(0);
  const Reference ref(sys);
  const ContactSpaceOperator A(sys, serial_exchange());
  const IdentityPreconditioner P;
  KrylovMonitor mon;
  mon.record_history = true;
  mon.norm_A = 2.0;
  mon.velocity_error = [&](const Vector &l) { return rel_diff(ref.velocities(l), ref.dv); };
  StopControl stop;
  stop.tol = 1e-12;
  stop.max_iter = 1000;
  for (Method m : kMethods) {
    Vector x = Vector::Zero(A.size());
    const SolveResult res = krylov_solve(m, A, P, ref.b, x, stop, &mon);
    ASSERT_TRUE(res.converged());
    ASSERT_GE(res.history.size(), 2u);
    EXPECT_DOUBLE_EQ(res.history[0].velocity_error, 1.0);
    EXPECT_LT(res.history.back().velocity_error, 1e-9);
    for (const IterationRecord &rec : res.history)
      EXPECT_NEAR(rec.rel_residual_A, rec.rel_residual * ref.b.norm() / 2.0, 1e-12 * ref.b.norm());
  }
}

// Starting from the exact solution costs at most one iteration.
TEST(Krylov, WarmStartFromSolution)
{
  const ContactSystem sys = scene(1);
  const Reference ref(sys);
  for (Form form : kForms) {
    const auto A = make_operator(form, sys, serial_exchange());
    const Vector b = form == Form::contact ? ref.b : body_rhs(sys, serial_exchange(), ref.b);
    PrecondOptions popt;
    const auto P = make_preconditioner(form, sys, serial_exchange(), popt);
    for (Method m : kMethods) {
      SCOPED_TRACE(std::string(to_string(form)) + " " + to_string(m));
      StopControl stop;
      stop.tol = 1e-8;
      Vector x = form == Form::contact ? ref.lambda : ref.dv_body;
      const SolveResult res = krylov_solve(m, *A, *P, b, x, stop);
      EXPECT_EQ(res.reason, StopReason::converged);
      EXPECT_LE(res.iterations, 1);
      // And the same solve from zero needs many.
      Vector x0 = Vector::Zero(A->size());
      EXPECT_GT(krylov_solve(m, *A, *P, b, x0, stop).iterations, 5);
    }
  }
}

TEST(Krylov, ZeroRhsGivesZero)
{
  const ContactSystem sys = scene(0);
  const ContactSpaceOperator A(sys, serial_exchange());
  const IdentityPreconditioner P;
  for (Method m : kMethods) {
    Vector x = Vector::Ones(A.size());
    const SolveResult res = krylov_solve(m, A, P, Vector::Zero(A.size()), x, StopControl{});
    EXPECT_EQ(res.reason, StopReason::converged);
    EXPECT_EQ(res.iterations, 0);
    EXPECT_EQ(x.norm(), 0.0);
  }
}

TEST(Krylov, NonFiniteStopsAndKeepsXFinite)
{
  const ContactSystem sys = scene(1);
  const ContactSpaceOperator A(sys, serial_exchange());
  const IdentityPreconditioner P;
  for (Method m : kMethods) {
    SCOPED_TRACE(to_string(m));
    // NaN in b: nothing to do, the warm start survives.
    Vector b = sys.rhs();
    b[3] = std::numeric_limits<double>::quiet_NaN();
    Vector x = Vector::Constant(A.size(), 0.25);
    SolveResult res = krylov_solve(m, A, P, b, x, StopControl{});
    EXPECT_EQ(res.reason, StopReason::non_finite);
    EXPECT_TRUE(x.allFinite());
    EXPECT_EQ(x, Vector::Constant(A.size(), 0.25));
    // Inf in b.
    b[3] = std::numeric_limits<double>::infinity();
    res = krylov_solve(m, A, P, b, x, StopControl{});
    EXPECT_EQ(res.reason, StopReason::non_finite);
    EXPECT_TRUE(x.allFinite());
    // A NaN appearing mid-solve: stop at once, x finite.
    for (int poison_at : {2, 6}) {
      const PoisonedOperator bad(A, poison_at);
      Vector y = Vector::Zero(A.size());
      res = krylov_solve(m, bad, P, sys.rhs(), y, StopControl{});
      EXPECT_EQ(res.reason, StopReason::non_finite);
      EXPECT_TRUE(y.allFinite());
      EXPECT_LE(res.iterations, poison_at);
    }
    // A non-finite warm start is replaced by zero.
    Vector z = Vector::Zero(A.size());
    z[0] = std::numeric_limits<double>::quiet_NaN();
    StopControl stop;
    stop.max_iter = 5000;
    res = krylov_solve(m, A, P, sys.rhs(), z, stop);
    EXPECT_TRUE(z.allFinite());
    EXPECT_TRUE(res.converged());
  }
}

TEST(Krylov, BreakdownOnIndefiniteForCgButMinresSolvesIt)
{
  // Symmetric indefinite: CG meets p^T A p <= 0; MINRES handles indefinite matrices.
  const int n = 12;
  test::Dense M = test::Dense::Zero(n, n);
  for (int i = 0; i < n; ++i) M(i, i) = i % 3 == 0 ? -1.0 - i : 1.0 + i;
  M(0, 1) = M(1, 0) = 0.5;
  const DenseOperator A(M);
  const IdentityPreconditioner P;
  Vector b = Vector::Zero(n);
  b[0] = 1.0; // (b, A b) < 0: CG breaks down on its first step
  Vector x = Vector::Zero(n);
  SolveResult res = cg(A, P, b, x, StopControl{});
  EXPECT_EQ(res.reason, StopReason::breakdown);
  EXPECT_TRUE(x.allFinite());
  b = Vector::LinSpaced(n, 1.0, 2.0);
  x.setZero();
  StopControl stop;
  stop.tol = 1e-12;
  res = minres(A, P, b, x, stop);
  EXPECT_EQ(res.reason, StopReason::converged);
  EXPECT_LT(rel_diff(x, M.lu().solve(b)), 1e-10);
}

TEST(Krylov, AcceptRuleStopsEarly)
{
  const ContactSystem sys = scene(1);
  const ContactSpaceOperator A(sys, serial_exchange());
  const IdentityPreconditioner P;
  StopControl stop;
  stop.tol = 1e-14;
  stop.accept = [](int k, const Vector &) { return k >= 4; };
  Vector x = Vector::Zero(A.size());
  const SolveResult res = minres(A, P, sys.rhs(), x, stop);
  EXPECT_EQ(res.reason, StopReason::converged);
  EXPECT_EQ(res.iterations, 4);
  EXPECT_GT(res.rel_residual, 1e-14); // the reported residual stays honest
}

// Both forms give the same velocities, on a rhs with the gap term, dense and iterative.
TEST(Krylov, FormsAgreeOnVelocities)
{
  for (int which : {0, 1}) {
    ContactSystem sys = scene(which);
    const Reference ref(sys);
    if (which == 1) { // the pile's overlaps put the gap term into b
      double gaps = 0;
      for (const Contact &c : sys.contacts()) gaps += std::abs(c.gap);
      EXPECT_GT(gaps, 0.0);
    }
    EXPECT_LT(rel_diff(ref.dv_body, ref.dv), 1e-10);
    const auto Ac = make_operator(Form::contact, sys, serial_exchange());
    const auto Ab = make_operator(Form::body, sys, serial_exchange());
    PrecondOptions popt;
    const auto Pc = make_preconditioner(Form::contact, sys, serial_exchange(), popt);
    const auto Pb = make_preconditioner(Form::body, sys, serial_exchange(), popt);
    StopControl stop;
    stop.tol = 1e-12;
    stop.max_iter = 5000;
    Vector lambda = Vector::Zero(Ac->size()), dv = Vector::Zero(Ab->size());
    ASSERT_TRUE(minres(*Ac, *Pc, ref.b, lambda, stop).converged());
    ASSERT_TRUE(minres(*Ab, *Pb, body_rhs(sys, serial_exchange(), ref.b), dv, stop).converged());
    EXPECT_LT(rel_diff(dv, ref.velocities(lambda)), 1e-9);
    // lambda recovered from dv carries Sigma^-1 (b - G dv): one digit is lost on the way.
    EXPECT_LT(rel_diff(ref.velocities(lambda_from_body(sys, serial_exchange(), ref.b, dv)),
                       ref.velocities(lambda)),
              1e-8);
  }
}
