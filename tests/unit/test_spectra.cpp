// Spectra and kappa_e: the gap rule on known lists, the dense path on operators with a known
// spectrum, Lanczos against known spectra and against the dense path on contact systems, and
// the body-space route for the unpreconditioned contact form.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "fibre/algebra/kernels.hpp"
#include "fibre/precond/preconditioner_family.hpp"
#include "fibre/scenes.hpp"
#include "fibre/study/spectra.hpp"
#include "reference.hpp"

using namespace fibre;

namespace {

// A dense symmetric matrix as an operator or a preconditioner (z = M r).
class DenseOperator final : public LinearOperator {
 public:
  explicit DenseOperator(Eigen::MatrixXd M) : M_(std::move(M)) {}
  Eigen::Index size() const override { return M_.rows(); }
  void apply(const Vector &x, Vector &y) const override { y = M_ * x; }
  double dot(const Vector &x, const Vector &y) const override { return x.dot(y); }

 private:
  Eigen::MatrixXd M_;
};

class DensePreconditioner final : public Preconditioner {
 public:
  explicit DensePreconditioner(Eigen::MatrixXd M) : M_(std::move(M)) {}
  void apply(const Vector &r, Vector &z) const override { z = M_ * r; }
  std::string name() const override { return "dense"; }

 private:
  Eigen::MatrixXd M_;
};

// A diagonal operator/preconditioner for large known spectra.
class DiagonalOperator final : public LinearOperator {
 public:
  explicit DiagonalOperator(Vector d) : d_(std::move(d)) {}
  Eigen::Index size() const override { return d_.size(); }
  void apply(const Vector &x, Vector &y) const override { y = d_.cwiseProduct(x); }
  double dot(const Vector &x, const Vector &y) const override { return x.dot(y); }

 private:
  Vector d_;
};

class DiagonalPreconditioner final : public Preconditioner {
 public:
  explicit DiagonalPreconditioner(Vector d) : d_(std::move(d)) {}
  void apply(const Vector &r, Vector &z) const override { z = d_.cwiseProduct(r); }
  std::string name() const override { return "diagonal"; }

 private:
  Vector d_;
};

// Independent jacobi and block preconditioners from the kernels' blocks (one process).
class BlockInverse final : public Preconditioner {
 public:
  BlockInverse(Form form, const ContactSystem &sys, bool scalar)
  {
    if (form == Form::contact) {
      width_ = sys.rows();
      for (int c = 0; c < sys.num_contacts(); ++c) add(diagonal_block(sys, c), scalar);
    } else {
      width_ = kBodyDofs;
      for (const Mat6 &K : body_diagonal_blocks(sys)) add(K, scalar);
    }
  }
  void apply(const Vector &r, Vector &z) const override
  {
    z.resize(r.size());
    for (std::size_t k = 0; k < inv_.size(); ++k)
      z.segment(width_ * Eigen::Index(k), width_) =
          inv_[k] * r.segment(width_ * Eigen::Index(k), width_);
  }
  std::string name() const override { return "test-block"; }

 private:
  void add(const Mat6 &B, bool scalar)
  {
    const Eigen::MatrixXd b = B.topLeftCorner(width_, width_);
    inv_.push_back(scalar ? Eigen::MatrixXd(b.diagonal().cwiseInverse().asDiagonal())
                          : Eigen::MatrixXd(b.inverse()));
  }
  int width_ = 6;
  std::vector<Eigen::MatrixXd> inv_;
};

Eigen::MatrixXd random_orthogonal(int n, std::mt19937 &rng)
{
  std::normal_distribution<double> g;
  Eigen::MatrixXd X(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) X(i, j) = g(rng);
  return Eigen::HouseholderQR<Eigen::MatrixXd>(X).householderQ();
}

// The pile for the Lanczos-against-dense checks. Sanitizer builds (-O1, instrumented Eigen)
// check memory safety, not numerics, and would take many minutes at this size.
#if defined(__SANITIZE_ADDRESS__)
constexpr int kPile = 60;
#else
constexpr int kPile = 200;
#endif

// The design's t = 1e-8: the compliance that makes Sigma = 1e-8 for the default SPOOK step.
SceneParams design_sigma_params()
{
  SceneParams p;
  p.compliance = 1e-8 * p.spook.h * p.spook.h * (1.0 + 4.0 * p.spook.damping) / 4.0;
  return p;
}

std::unique_ptr<Preconditioner> local_preconditioner(const std::string &kind, Form form,
                                                     const ContactSystem &sys)
{
  if (kind == "none") return std::make_unique<IdentityPreconditioner>();
  return std::make_unique<BlockInverse>(form, sys, kind == "jacobi");
}

} // namespace

TEST(Spectra, GapRuleOnKnownLists)
{
  // Two groups: the largest ratio is 80 / 1e-3, so lambda_r = 80 (index 2).
  Spectrum s = effective_condition({1e-3, 100.0, 9e-4, 80.0, 90.0});
  EXPECT_EQ(s.r, 2);
  EXPECT_DOUBLE_EQ(s.lambda_r, 80.0);
  EXPECT_DOUBLE_EQ(s.kappa_e, 1.25);
  EXPECT_DOUBLE_EQ(s.kappa, 100.0 / 9e-4);
  EXPECT_DOUBLE_EQ(s.gap_ratio, 8e4);
  EXPECT_EQ(s.eigenvalues, (std::vector<double>{100.0, 90.0, 80.0, 1e-3, 9e-4}));
  // Ties go to the first (largest) ratio; equal eigenvalues have no gap at all.
  s = effective_condition({1.0, 4.0, 2.0});
  EXPECT_EQ(s.r, 0);
  EXPECT_DOUBLE_EQ(s.kappa_e, 1.0);
  s = effective_condition({3.0, 3.0, 3.0});
  EXPECT_DOUBLE_EQ(s.gap_ratio, 1.0);
  EXPECT_DOUBLE_EQ(s.kappa_e, 1.0);
  EXPECT_DOUBLE_EQ(effective_condition({5.0}).kappa_e, 1.0);
  // An outlier at the bottom: the gap is above it, kappa_e is the bulk's condition number.
  s = effective_condition({10.0, 8.0, 6.0, 4.0, 2.0, 1e-6});
  EXPECT_DOUBLE_EQ(s.kappa_e, 5.0);
  EXPECT_THROW(effective_condition({}), std::invalid_argument);
  EXPECT_THROW(effective_condition({1.0, -1.0}), std::invalid_argument);
  EXPECT_THROW(effective_condition({1.0, std::nan("")}), std::invalid_argument);
}

TEST(Spectra, DenseRecoversAKnownPreconditionedSpectrum)
{
  // A = Q diag(d) Q^T and P^-1 = Q diag(e) Q^T commute: P^-1 A has eigenvalues d_i e_i.
  std::mt19937 rng(3);
  const int n = 40;
  const Eigen::MatrixXd Q = random_orthogonal(n, rng);
  std::uniform_real_distribution<double> u(0.5, 2.0);
  Vector d(n), e(n);
  std::vector<double> expected;
  for (int i = 0; i < n; ++i) {
    d[i] = (i < 10 ? 1e-6 : 1.0) * u(rng) * (1 + i); // a null-like cluster of ten
    e[i] = u(rng);
    expected.push_back(d[i] * e[i]);
  }
  const DenseOperator A(Q * d.asDiagonal() * Q.transpose());
  const DensePreconditioner P(Q * e.asDiagonal() * Q.transpose());
  const Spectrum s = dense_spectrum(A, P);
  const Spectrum ref = effective_condition(expected);
  ASSERT_EQ(s.eigenvalues.size(), expected.size());
  for (int i = 0; i < n; ++i)
    EXPECT_NEAR(s.eigenvalues[i], ref.eigenvalues[i], 1e-10 * ref.eigenvalues[0]) << i;
  EXPECT_EQ(s.r, ref.r);
  EXPECT_EQ(s.r, n - 11); // the last eigenvalue above the cluster
  EXPECT_NEAR(s.kappa_e, ref.kappa_e, 1e-10 * ref.kappa_e);
}

TEST(Spectra, DenseMatchesANonsymmetricEigensolver)
{
  // Non-commuting SPD A and P^-1: compare with the eigenvalues of the product itself.
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  const int n = 30;
  Eigen::MatrixXd X(n, n), Y(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) X(i, j) = g(rng), Y(i, j) = g(rng);
  const Eigen::MatrixXd A = X * X.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
  const Eigen::MatrixXd Pinv = Y * Y.transpose() + Eigen::MatrixXd::Identity(n, n);
  const Spectrum s = dense_spectrum(DenseOperator(A), DensePreconditioner(Pinv));
  Eigen::EigenSolver<Eigen::MatrixXd> es(Pinv * A, false);
  std::vector<double> ref;
  for (int i = 0; i < n; ++i) {
    EXPECT_LT(std::abs(es.eigenvalues()[i].imag()), 1e-8 * std::abs(es.eigenvalues()[i]));
    ref.push_back(es.eigenvalues()[i].real());
  }
  std::sort(ref.begin(), ref.end(), std::greater<double>());
  for (int i = 0; i < n; ++i) EXPECT_NEAR(s.eigenvalues[i], ref[i], 1e-9 * ref[0]) << i;
}

TEST(Spectra, LanczosFindsAClearGapLongBeforeN)
{
  // 1500 eigenvalues spread over [1e-6, 3e-6] (the null-space cluster) and 500 over
  // [0.1, 10], with a diagonal preconditioner: P^-1 A = diag(d e), known exactly.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = 2000;
  Vector d(n), e(n);
  std::vector<double> expected;
  for (int i = 0; i < n; ++i) {
    d[i] = i < 1500 ? 1e-6 * (1 + 2 * u(rng)) : 0.1 + 9.9 * u(rng);
    e[i] = 0.8 + 0.4 * u(rng);
    expected.push_back(d[i] * e[i]);
  }
  const Spectrum ref = effective_condition(expected);
  ASSERT_GT(ref.gap_ratio, 1e4);
  const DiagonalOperator A(d);
  const DiagonalPreconditioner P(e);
  const Spectrum s = lanczos_spectrum(A, P);
  EXPECT_TRUE(s.converged);
  EXPECT_LT(s.iterations, n / 5);
  EXPECT_NEAR(s.lambda_max, ref.lambda_max, 1e-6 * ref.lambda_max);
  EXPECT_NEAR(s.lambda_r, ref.lambda_r, 1e-4 * ref.lambda_r);
  EXPECT_NEAR(s.kappa_e, ref.kappa_e, 1e-4 * ref.kappa_e);
  // Ritz values at both ends: the top one and one inside the cluster.
  EXPECT_LE(s.eigenvalues.back(), 3.6e-6);
  // Certification waits for the bottom of the cluster too, and is then exact.
  LanczosOptions strict;
  strict.certify = true;
  const Spectrum c = lanczos_spectrum(A, P, strict);
  EXPECT_TRUE(c.certified);
  EXPECT_GE(c.iterations, s.iterations);
  EXPECT_NEAR(c.kappa_e, ref.kappa_e, 1e-8 * ref.kappa_e);
  EXPECT_NEAR(c.lambda_min, ref.lambda_min, 1e-3 * ref.lambda_min);
}

TEST(Spectra, LanczosMatchesDenseOnPilesBothForms)
{
  // Sigma = 1e-8 as in doc/design.md section 7: null(G^T) sits far below the range of G.
  const ContactSystem sys = pile_scene(kPile, design_sigma_params());
  for (Form form : {Form::contact, Form::body}) {
    const auto op = make_operator(form, sys, serial_exchange());
    for (const char *kind : {"none", "jacobi", "block"}) {
      const auto P = local_preconditioner(kind, form, sys);
      const Spectrum dense = dense_spectrum(*op, *P);
      const Spectrum lanczos = lanczos_spectrum(form, sys, serial_exchange(), *P);
      EXPECT_TRUE(lanczos.converged) << to_string(form) << " " << kind;
      EXPECT_NEAR(lanczos.kappa_e, dense.kappa_e, 0.05 * dense.kappa_e)
          << to_string(form) << " " << kind << ": lanczos " << lanczos.kappa_e << " after "
          << lanczos.iterations << " steps, dense " << dense.kappa_e;
      EXPECT_NEAR(lanczos.lambda_max, dense.lambda_max, 1e-6 * dense.lambda_max);
      EXPECT_GT(dense.kappa_e, 1.0);
    }
  }
}

TEST(Spectra, LanczosMatchesDenseForTheLibraryPreconditioners)
{
  // fibre and tree come from make_preconditioner (preconditioner_family.cpp).
  const ContactSystem sys = pile_scene(kPile, design_sigma_params());
  for (Form form : {Form::contact, Form::body})
    for (PrecondKind kind : {PrecondKind::block, PrecondKind::fibre, PrecondKind::tree}) {
      PrecondOptions opt;
      opt.kind = kind;
      const auto P = make_preconditioner(form, sys, serial_exchange(), opt);
      const auto op = make_operator(form, sys, serial_exchange());
      const Spectrum dense = dense_spectrum(*op, *P);
      const Spectrum lanczos = lanczos_spectrum(form, sys, serial_exchange(), *P);
      EXPECT_NEAR(lanczos.kappa_e, dense.kappa_e, 0.05 * dense.kappa_e)
          << to_string(form) << " " << to_string(kind);
    }
}

TEST(Spectra, BodySpaceRouteMatchesDenseContactSpectrum)
{
  for (const SceneParams &p : {SceneParams{}, design_sigma_params()}) {
    const ContactSystem sys = pile_scene(80, p);
    const Spectrum body = body_space_spectrum(sys);
    // Reference: the eigenvalues of the dense A of reference.hpp.
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(test::dense_A(sys), Eigen::EigenvaluesOnly);
    const Vector &ev = es.eigenvalues();
    const Spectrum ref = effective_condition(std::vector<double>(ev.data(), ev.data() + ev.size()));
    ASSERT_EQ(body.eigenvalues.size(), ref.eigenvalues.size());
    for (std::size_t i = 0; i < ref.eigenvalues.size(); ++i)
      EXPECT_NEAR(body.eigenvalues[i], ref.eigenvalues[i], 1e-11 * ref.eigenvalues[0]) << i;
    EXPECT_NEAR(body.kappa_e, ref.kappa_e, 1e-6 * ref.kappa_e);
    EXPECT_EQ(body.r, ref.r);
  }
  // Masked rows have Sigma = 1: no longer one value on every row.
  ContactSystem masked = pile_scene(20, SceneParams{});
  std::vector<unsigned char> mask(masked.contact_dofs(), 1);
  mask[0] = 0;
  masked.set_row_mask(mask);
  EXPECT_THROW(body_space_spectrum(masked), std::invalid_argument);
}
