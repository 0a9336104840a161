#include "fibre/study/spectra.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

#include "fibre/algebra/assembly.hpp"

namespace fibre {

Spectrum effective_condition(std::vector<double> eigenvalues)
{
  if (eigenvalues.empty()) throw std::invalid_argument("effective_condition: no eigenvalues");
  for (double e : eigenvalues)
    if (!(e > 0) || !std::isfinite(e))
      throw std::invalid_argument("effective_condition: eigenvalue " + std::to_string(e) +
                                  " is not positive and finite");
  std::sort(eigenvalues.begin(), eigenvalues.end(), std::greater<double>());
  Spectrum s;
  const int n = static_cast<int>(eigenvalues.size());
  s.lambda_max = eigenvalues.front();
  s.lambda_min = eigenvalues.back();
  s.kappa = s.lambda_max / s.lambda_min;
  s.r = n - 1;
  for (int i = 0; i + 1 < n; ++i) {
    const double ratio = eigenvalues[i] / eigenvalues[i + 1];
    if (ratio > s.gap_ratio) {
      s.gap_ratio = ratio;
      s.r = i;
    }
  }
  s.lambda_r = eigenvalues[s.r];
  s.kappa_e = s.lambda_max / s.lambda_r;
  s.eigenvalues = std::move(eigenvalues);
  return s;
}

Spectrum dense_spectrum(const LinearOperator &A, const Preconditioner &P)
{
  const Eigen::Index n = A.size();
  if (n == 0) throw std::invalid_argument("dense_spectrum: empty operator");
  Eigen::MatrixXd Ad(n, n), Pd(n, n);
  Vector e = Vector::Zero(n), y, z;
  for (Eigen::Index j = 0; j < n; ++j) {
    e[j] = 1.0;
    A.apply(e, y);
    P.apply(e, z);
    Ad.col(j) = y;
    Pd.col(j) = z;
    e[j] = 0.0;
  }
  // Both are symmetric up to rounding; the solvers read one triangle.
  Ad = 0.5 * (Ad + Ad.transpose()).eval();
  Pd = 0.5 * (Pd + Pd.transpose()).eval();
  // The symmetric generalized problem: with A = B B^T (Cholesky), eig(P^-1 A) =
  // eig(B^T P^-1 B). A is sparse and its sparse Cholesky stays sparse (the contact graph is
  // nearly a forest), while P^-1 of the fibre and tree preconditioners is dense per fibre or
  // tree. So B is sparse, the products are cheap, and only the eigenvalue solve is O(n^3).
  Eigen::SimplicialLLT<SparseMatrix> llt(Ad.sparseView(0.0, 0.0));
  if (llt.info() != Eigen::Success)
    throw std::runtime_error("dense_spectrum: the operator is not positive definite");
  const SparseMatrix L = llt.matrixL();
  const SparseMatrix B = llt.permutationPinv() * L;
  const Eigen::MatrixXd PB = Pd * B;
  const Eigen::MatrixXd C = SparseMatrix(B.transpose()) * PB;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(C, Eigen::EigenvaluesOnly);
  if (es.info() != Eigen::Success) throw std::runtime_error("dense_spectrum: eigensolver failed");
  const Vector &ev = es.eigenvalues();
  return effective_condition(std::vector<double>(ev.data(), ev.data() + ev.size()));
}

namespace {

// Solves (T - shift I) x = x in place for a symmetric tridiagonal T (diagonal a, off-diagonal
// b), by Gaussian elimination with partial pivoting (rows swap where the subdiagonal wins).
// Exactly zero pivots are nudged: inverse iteration wants the near-singular solve.
void shifted_tridiagonal_solve(const std::vector<double> &a, const std::vector<double> &b,
                               double shift, double tiny, std::vector<double> &x)
{
  const int n = static_cast<int>(a.size());
  std::vector<double> d(n), dl(b), du(b), du2(std::max(n - 2, 0), 0.0);
  std::vector<char> swapped(std::max(n - 1, 0), 0);
  for (int i = 0; i < n; ++i) d[i] = a[i] - shift;
  for (int i = 0; i + 1 < n; ++i) {
    if (std::abs(d[i]) >= std::abs(dl[i])) {
      if (d[i] == 0.0) d[i] = tiny;
      const double f = dl[i] / d[i];
      dl[i] = f;
      d[i + 1] -= f * du[i];
    } else {
      const double f = d[i] / dl[i];
      d[i] = dl[i];
      dl[i] = f;
      const double t = du[i];
      du[i] = d[i + 1];
      d[i + 1] = t - f * d[i + 1];
      if (i + 2 < n) {
        du2[i] = du[i + 1];
        du[i + 1] = -f * du[i + 1];
      }
      swapped[i] = 1;
    }
  }
  if (d[n - 1] == 0.0) d[n - 1] = tiny;
  for (int i = 0; i + 1 < n; ++i) {
    if (swapped[i]) {
      const double t = x[i];
      x[i] = x[i + 1];
      x[i + 1] = t - dl[i] * x[i];
    } else {
      x[i + 1] -= dl[i] * x[i];
    }
  }
  x[n - 1] /= d[n - 1];
  if (n > 1) x[n - 2] = (x[n - 2] - du[n - 2] * x[n - 1]) / d[n - 2];
  for (int i = n - 3; i >= 0; --i) x[i] = (x[i] - du[i] * x[i + 1] - du2[i] * x[i + 2]) / d[i];
}

// |last component| of the unit eigenvector of T for the eigenvalue theta (inverse iteration).
double last_component(const std::vector<double> &a, const std::vector<double> &b, double theta,
                      double tiny)
{
  const int n = static_cast<int>(a.size());
  std::vector<double> x(n, 1.0);
  for (int it = 0; it < 3; ++it) {
    shifted_tridiagonal_solve(a, b, theta, tiny, x);
    double norm = 0;
    for (double v : x) norm += v * v;
    norm = std::sqrt(norm);
    if (!(norm > 0) || !std::isfinite(norm)) return 1.0; // give up: counts as unconverged
    for (double &v : x) v /= norm;
  }
  return std::abs(x[n - 1]);
}

// Ritz values of the Lanczos matrix T_m with their residual bounds |beta_{m+1} s_m|, and
// kappa_e over them. `converged`: lambda_1 and lambda_r meet opt.tol, and the largest gap lies
// between two Ritz values that meet opt.gap_tol with only such values below it, so that no
// unresolved part of the spectrum can hide a larger gap below lambda_r.
Spectrum ritz_check(const std::vector<double> &alpha, const std::vector<double> &beta,
                    double beta_next, const LanczosOptions &opt, bool *is_certified)
{
  const int m = static_cast<int>(alpha.size());
  Vector diag = Eigen::Map<const Vector>(alpha.data(), m);
  Vector sub = Eigen::Map<const Vector>(beta.data(), m - 1);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
  es.computeFromTridiagonal(diag, sub, Eigen::EigenvaluesOnly);
  std::vector<double> theta(es.eigenvalues().data(), es.eigenvalues().data() + m);
  std::sort(theta.begin(), theta.end(), std::greater<double>());
  const double scale = std::max(std::abs(theta.front()), std::abs(theta.back()));
  const double tiny = std::max(scale, 1e-300) * 1e-15;
  // Rounding can leave Ritz values of an SPD pencil at or below zero: they end the list.
  const int positive = static_cast<int>(
      std::find_if(theta.begin(), theta.end(), [](double x) { return !(x > 0); }) - theta.begin());
  if (positive == 0) throw std::runtime_error("lanczos_spectrum: no positive Ritz value");
  Spectrum s = effective_condition(std::vector<double>(theta.begin(), theta.begin() + positive));
  // Residuals only where the decision needs them (each costs O(m)); the rest stay infinite.
  std::vector<double> res(m, std::numeric_limits<double>::infinity());
  auto residual = [&](int i) {
    if (std::isinf(res[i]))
      res[i] = std::abs(beta_next) * last_component(alpha, beta, theta[i], tiny);
    return res[i];
  };
  auto settled = [&](int i) { return residual(i) <= opt.gap_tol * theta[i]; };
  const double slack = (1 + opt.gap_tol) * (1 + opt.gap_tol);
  // The values kappa_e is made of.
  const bool ok =
      positive == m && residual(0) <= opt.tol * theta[0] && residual(s.r) <= opt.tol * theta[s.r];
  bool certified = ok && (s.r + 1 == m || (settled(s.r + 1) && settled(m - 1)));
  // Certified: no unresolved stretch can hide a larger ratio. Below lambda_r every Ritz value
  // is settled, or the gap beats the whole span below it; above it likewise, with the span
  // kappa_e. (Between consecutive Ritz values there is always an eigenvalue, but a Ritz value
  // may sit inside a true gap until it settles.)
  if (certified && s.r + 1 < m) {
    bool below = s.gap_ratio >= slack * theta[s.r + 1] / theta[m - 1];
    for (int i = m - 1; i > s.r && !below; --i)
      if (!settled(i))
        break;
      else if (i == s.r + 1)
        below = true;
    certified = below;
  }
  if (certified && s.r > 1) {
    bool above = s.gap_ratio >= slack * s.kappa_e;
    for (int i = 1; i < s.r && !above; ++i)
      if (!settled(i))
        break;
      else if (i == s.r - 1)
        above = true;
    certified = above;
  }
  if (is_certified) *is_certified = certified;
  s.eigenvalues = std::move(theta);
  s.residuals = std::move(res);
  s.converged = ok;
  return s;
}

} // namespace

Spectrum lanczos_spectrum(const LinearOperator &A, const Preconditioner &P,
                          const LanczosOptions &opt)
{
  const Eigen::Index n = A.size();
  // Global dimension through the operator's own inner product (owned entries only).
  const double global_n = A.dot(Vector::Ones(n), Vector::Ones(n));
  const int max_steps = static_cast<int>(std::min<double>(opt.max_steps, global_n));
  if (max_steps < 1) throw std::invalid_argument("lanczos_spectrum: empty operator");
  Vector r;
  if (opt.start) {
    if (opt.start->size() != n) throw std::invalid_argument("lanczos_spectrum: start size");
    r = *opt.start;
  } else {
    std::mt19937_64 rng(opt.seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    r.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) r[i] = u(rng);
  }
  // Lanczos on L^T A L (P^-1 = L L^T) carried in the residual space: q_j = L^-T v_j and
  // w_j = P^-1 q_j, so that v_i^T v_j = w_i^T q_j and only P^-1 is ever applied.
  std::vector<Vector> Q, W;
  std::vector<double> alpha, beta;
  Vector z, u;
  P.apply(r, z);
  double b = std::sqrt(std::max(A.dot(r, z), 0.0));
  if (!(b > 0)) throw std::invalid_argument("lanczos_spectrum: zero start vector");
  Spectrum last;
  double prev_kappa = -1;
  int next_check = std::max(opt.check_every, 1);
  for (int j = 0; j < max_steps; ++j) {
    Q.push_back(r / b);
    W.push_back(z / b);
    A.apply(W[j], u);
    const double a = A.dot(W[j], u);
    u -= a * Q[j];
    if (j > 0) u -= beta.back() * Q[j - 1];
    // Full reorthogonalization, twice (classical Gram-Schmidt in the P^-1 inner product).
    for (int pass = 0; pass < 2; ++pass)
      for (int i = 0; i <= j; ++i) u -= A.dot(W[i], u) * Q[i];
    alpha.push_back(a);
    P.apply(u, z);
    const double b_next = std::sqrt(std::max(A.dot(u, z), 0.0));
    const bool last_step = j + 1 == max_steps;
    // An invariant subspace: its Ritz values are exact, nothing more to find.
    const bool breakdown = !(b_next > 1e-14 * std::max(std::abs(a), b));
    // Checks cost O(m^2): space them out geometrically once m is large.
    const bool check = j + 1 >= next_check;
    if (check) next_check = j + 1 + std::max(opt.check_every, (j + 1) / 10);
    if (check || last_step || breakdown) {
      bool certified = false;
      last = ritz_check(alpha, beta, breakdown ? 0.0 : b_next, opt, &certified);
      last.iterations = j + 1;
      // Uncertified results must repeat over two checks: a Ritz value may still be moving
      // through a gap. (Not the gap ratio: the Ritz values below the gap need not settle.)
      const bool stable =
          prev_kappa > 0 && std::abs(last.kappa_e - prev_kappa) <= opt.tol * last.kappa_e;
      prev_kappa = last.converged ? last.kappa_e : -1;
      last.certified = certified || breakdown;
      if (breakdown) last.converged = true;
      if (last.certified || (!opt.certify && last.converged && stable)) break;
      last.converged = false;
    }
    if (last_step) break;
    beta.push_back(b_next);
    r = u;
    b = b_next;
  }
  return last;
}

Spectrum lanczos_spectrum(Form form, const ContactSystem &sys, const Exchange &ex,
                          const Preconditioner &P, const LanczosOptions &opt)
{
  const auto op = make_operator(form, sys, ex);
  if (opt.start) return lanczos_spectrum(*op, P, opt);
  std::mt19937_64 rng(opt.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vector start = Vector::Zero(op->size());
  const Eigen::Index live =
      form == Form::body ? Eigen::Index(kBodyDofs) * sys.num_owned_bodies() : op->size();
  for (Eigen::Index i = 0; i < live; ++i) start[i] = u(rng);
  LanczosOptions o = opt;
  o.start = &start;
  return lanczos_spectrum(*op, P, o);
}

Spectrum body_space_spectrum(const ContactSystem &sys)
{
  const Vector &sigma = sys.sigma();
  if (sigma.size() == 0) throw std::invalid_argument("body_space_spectrum: no contacts");
  const double s0 = sigma[0];
  for (Eigen::Index i = 0; i < sigma.size(); ++i)
    if (std::abs(sigma[i] - s0) > 1e-12 * s0)
      throw std::invalid_argument("body_space_spectrum needs one Sigma value on every row");
  // X = G M^-1/2: X X^T = G M^-1 G^T (contact space), X^T X its body-space twin.
  const SparseMatrix X = assemble_G(sys) * sys.inv_mass().cwiseSqrt().asDiagonal();
  const Eigen::MatrixXd B = Eigen::MatrixXd(SparseMatrix(X.transpose() * X));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(B, Eigen::EigenvaluesOnly);
  if (es.info() != Eigen::Success)
    throw std::runtime_error("body_space_spectrum: eigensolver failed");
  std::vector<double> mu(es.eigenvalues().data(), es.eigenvalues().data() + B.rows());
  std::sort(mu.begin(), mu.end(), std::greater<double>());
  // The contact-space matrix has the min(m, N) largest of these and zeros for the rest.
  const std::size_t m = static_cast<std::size_t>(sys.contact_dofs());
  mu.resize(m, 0.0);
  for (double &x : mu) x = std::max(x, 0.0) + s0;
  return effective_condition(std::move(mu));
}

} // namespace fibre
