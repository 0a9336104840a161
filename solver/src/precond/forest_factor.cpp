#include "fibre/precond/forest_factor.hpp"

namespace fibre::forest {

namespace {

#if defined(__clang__)
#define FIBRE_UNROLL _Pragma("unroll")
#elif defined(__GNUC__)
#define FIBRE_UNROLL _Pragma("GCC unroll 6")
#else
#define FIBRE_UNROLL
#endif

// ---- 6x6 kernels (fully unrolled: every index below is a compile-time constant) ----
//
// D = L Delta L^T in place (packed): L unit lower below the diagonal, 1 / Delta on it. No
// square roots: on these tiny blocks the sqrt/divide chain is the cost of a Cholesky.
inline void ldlt6(double *a)
{
  double delta[kB];
  FIBRE_UNROLL
  for (int j = 0; j < kB; ++j) {
    double t[kB]; // L_jk Delta_k
    double d = a[at(j, j)];
    FIBRE_UNROLL
    for (int k = 0; k < j; ++k) {
      t[k] = a[at(j, k)] * delta[k];
      d -= t[k] * a[at(j, k)];
    }
    if (!(d > 0)) throw std::runtime_error("preconditioner block is not positive definite");
    delta[j] = d;
    const double inv = 1.0 / d;
    a[at(j, j)] = inv;
    FIBRE_UNROLL
    for (int i = j + 1; i < kB; ++i) {
      double s = a[at(i, j)];
      FIBRE_UNROLL
      for (int k = 0; k < j; ++k) s -= a[at(i, k)] * t[k];
      a[at(i, j)] = s * inv;
    }
  }
}

// x = L^-1 x (unit lower).
inline void unit_lower_solve6(const double *l, double *x)
{
  FIBRE_UNROLL
  for (int i = 1; i < kB; ++i) {
    double s = x[i];
    FIBRE_UNROLL
    for (int k = 0; k < i; ++k) s -= l[at(i, k)] * x[k];
    x[i] = s;
  }
}

// x = L^-T x (unit upper).
inline void unit_upper_solve6(const double *l, double *x)
{
  FIBRE_UNROLL
  for (int i = kB - 2; i >= 0; --i) {
    double s = x[i];
    FIBRE_UNROLL
    for (int k = i + 1; k < kB; ++k) s -= l[at(k, i)] * x[k];
    x[i] = s;
  }
}

class ForestPreconditioner final : public Preconditioner {
 public:
  ForestPreconditioner(std::string name, ForestFactor factor, Eigen::Index size, bool covers_all)
      : name_(std::move(name)), factor_(std::move(factor)), size_(size), covers_all_(covers_all)
  {
  }
  // Not reentrant: one preconditioner serves one solve at a time (work_ is shared).
  void apply(const Vector &r, Vector &z) const override
  {
    if (covers_all_)
      z.resize(size_);
    else
      z.setZero(size_);
    factor_.solve(r, z, work_);
  }
  std::string name() const override { return name_; }

 private:
  std::string name_;
  ForestFactor factor_;
  Eigen::Index size_;
  bool covers_all_; // every entry belongs to a node (false: ghost bodies, left zero)
  mutable std::vector<double> work_;
};

class DiagonalPreconditioner final : public Preconditioner {
 public:
  explicit DiagonalPreconditioner(Vector inv_diag) : inv_diag_(std::move(inv_diag)) {}
  void apply(const Vector &r, Vector &z) const override { z = inv_diag_.cwiseProduct(r); }
  std::string name() const override { return "jacobi"; }

 private:
  Vector inv_diag_;
};

} // namespace

void ForestFactor::factor()
{
  for (int n = 0; n < nodes(); ++n) {
    double *l = l_.get() + std::size_t(kPacked) * n;
    ldlt6(l);
    const int p = parent_[n];
    if (p < 0) continue;
    double *v = w_.get() + std::size_t(kBlock) * wslot_[n];
    // V = L^-1 B on whole rows.
    FIBRE_UNROLL
    for (int i = 1; i < kB; ++i) {
      FIBRE_UNROLL
      for (int k = 0; k < i; ++k) {
        const double lik = l[at(i, k)];
        FIBRE_UNROLL
        for (int j = 0; j < kB; ++j) v[kB * i + j] -= lik * v[kB * k + j];
      }
    }
    // D_p -= B^T D_n^-1 B = sign_n V^T Delta^-1 V, in the parent's signed storage.
    double sv[kBlock];
    const double s = double(sign_[n] * sign_[p]);
    FIBRE_UNROLL
    for (int k = 0; k < kB; ++k) {
      FIBRE_UNROLL
      for (int j = 0; j < kB; ++j) sv[kB * k + j] = s * l[at(k, k)] * v[kB * k + j];
    }
    double *dp = l_.get() + std::size_t(kPacked) * p;
    FIBRE_UNROLL
    for (int b = 0; b < kB; ++b) {
      FIBRE_UNROLL
      for (int a = b; a < kB; ++a) {
        double t = 0;
        FIBRE_UNROLL
        for (int k = 0; k < kB; ++k) t += sv[kB * k + a] * v[kB * k + b];
        dp[at(a, b)] -= t;
      }
    }
  }
}

void ForestFactor::solve(const Vector &r, Vector &z, std::vector<double> &work) const
{
  const int nn = nodes();
  work.resize(std::size_t(kB) * nn);
  double *u = work.data();
  const double *rd = r.data();
  // Forward: u_n = Delta_n^-1 L_n^-1 y_n, then y_p -= sign_n V_n^T u_n.
  for (int n = 0; n < nn; ++n) {
    double *un = u + kB * n;
    if (offset_[n] >= 0)
      for (int i = 0; i < kB; ++i) un[i] = i < dim_ ? rd[offset_[n] + i] : 0.0;
    else
      for (int i = 0; i < kB; ++i) un[i] = 0.0;
  }
  for (int n = 0; n < nn; ++n) {
    double *un = u + kB * n;
    const double *l = l_.get() + std::size_t(kPacked) * n;
    unit_lower_solve6(l, un);
    FIBRE_UNROLL
    for (int i = 0; i < kB; ++i) un[i] *= l[at(i, i)];
    const int p = parent_[n];
    if (p < 0) continue;
    const double *v = w_.get() + std::size_t(kBlock) * wslot_[n];
    double *up = u + kB * p;
    const double s = sign_[n];
    FIBRE_UNROLL
    for (int k = 0; k < kB; ++k) {
      const double f = s * un[k];
      FIBRE_UNROLL
      for (int j = 0; j < kB; ++j) up[j] -= f * v[kB * k + j];
    }
  }
  // Backward, roots first: x_n = sign_n L_n^-T (u_n - Delta_n^-1 V_n x_p), in place.
  double *zd = z.data();
  for (int n = nn - 1; n >= 0; --n) {
    double *un = u + kB * n;
    const double *l = l_.get() + std::size_t(kPacked) * n;
    const int p = parent_[n];
    if (p >= 0) {
      const double *v = w_.get() + std::size_t(kBlock) * wslot_[n];
      const double *xp = u + kB * p;
      FIBRE_UNROLL
      for (int k = 0; k < kB; ++k) {
        double t = 0;
        FIBRE_UNROLL
        for (int j = 0; j < kB; ++j) t += v[kB * k + j] * xp[j];
        un[k] -= l[at(k, k)] * t;
      }
    }
    unit_upper_solve6(l, un);
    if (sign_[n] < 0)
      for (int k = 0; k < kB; ++k) un[k] = -un[k];
    if (offset_[n] >= 0)
      for (int i = 0; i < dim_; ++i) zd[offset_[n] + i] = un[i];
  }
}

std::unique_ptr<Preconditioner> finish(const char *name, ForestFactor f, Eigen::Index size,
                                       bool covers_all)
{
  f.factor();
  return std::make_unique<ForestPreconditioner>(name, std::move(f), size, covers_all);
}

std::unique_ptr<Preconditioner> diagonal(Vector inv_diag)
{
  return std::make_unique<DiagonalPreconditioner>(std::move(inv_diag));
}

#undef FIBRE_UNROLL

} // namespace fibre::forest
