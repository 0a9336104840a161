#include "fibre/solvers/anderson.hpp"

#include <algorithm>

namespace fibre {

double Anderson::mix(Vector &lambda, Vector &dv)
{
  const bool first = !started_;
  const int j = begin_mix(lambda.size(), first); // the new column
  measure(lambda, first, j);
  const double *f2 = &dots_[count_ + 2], *g2 = &dots_[count_ + 3];
  // A mix whose change exceeds the last one's crossed a kink of the cones (the sliding or
  // open set changed): the old differences describe another map, and kept they stall the
  // combination (measured: changes stuck at 1e-5 on a forming stiff pile). The history
  // starts again from this mix.
  const double change = *g2 > 0 ? std::sqrt(*f2 / *g2) : 0.0;
  const bool grew = change > change_;
  change_ = change;
  combined_ = false;
  if (first || grew) {
    count_ = 0;
    newest_ = -1;
    dv_prev_ = dv;
    x_ = lambda; // the next start is g
    return sigma_;
  }
  return combine_history(lambda, dv, j);
}

// The new column (-1 at the first mix, or the first after a restart).
int Anderson::begin_mix(Eigen::Index n, bool first)
{
  int j = -1;
  if (!first) {
    j = newest_ = (newest_ + 1) % memory_; // the oldest column gives way
    if (count_ < memory_) {
      ++count_;
      dF_.resize(count_), dG_.resize(count_), dDV_.resize(count_), dX2_.resize(count_);
    }
    dF_[j].resize(n), dG_[j].resize(n);
  } else { // the first mix, or after a restart (every process alike: a process without
           // contacts takes part in the sums below)
    started_ = true;
    f_prev_.resize(n);
    g_prev_.resize(n);
  }
  return j;
}

void Anderson::measure(const Vector &lambda, bool first, int j)
{
  // One pass in blocks that stay in cache: f = g - x, and after the first mix the new
  // columns dF_j, dG_j, then dF_j . f_prev, |dX_j|^2 (dX = dG - dF) and the Gram matrix's new
  // column dF_i . dF_j; |f|^2 and |g|^2 always. The dot products and the copies are Eigen's
  // (vectorized, several accumulators): a plain loop's single running sum is a chain of
  // dependent adds, and its possible aliasing kept it scalar.
  std::vector<double> &dots = dots_;
  dots.assign(count_ + 4, 0.0);
  double *f2 = &dots[count_ + 2], *g2 = &dots[count_ + 3];
  columns(dF_);
  double *fp = f_prev_.data(), *gp = g_prev_.data();
  const Eigen::Index n = lambda.size();
  const double *l = lambda.data(), *x = x_.data();
  for (Eigen::Index e0 = 0; e0 < n; e0 += kBlock) {
    const Eigen::Index len = std::min(n - e0, kBlock);
    const ConstMap l_block(l + e0, len);
    Map f_block(f_.data(), len);
    f_block = l_block - ConstMap(x + e0, len);
    *f2 += f_block.squaredNorm();
    *g2 += l_block.squaredNorm();
    if (!first) {
      double *df = dF_[j].data(), *dg = dG_[j].data();
      Map(df + e0, len) = f_block - ConstMap(fp + e0, len);
      Map(dg + e0, len) = l_block - ConstMap(gp + e0, len);
      const ConstMap df_block(df + e0, len), dg_block(dg + e0, len);
      dots[count_] += df_block.dot(ConstMap(fp + e0, len));
      dots[count_ + 1] += (dg_block - df_block).squaredNorm();
      for (int i = 0; i < count_; ++i) dots[i] += ConstMap(ptr_[i] + e0, len).dot(df_block);
    }
    Map(fp + e0, len) = f_block;
    Map(gp + e0, len) = l_block;
  }
  ex_.sum(dots.data(), count_ + 4);
}

// gamma from the Gram matrix's least squares, and the next start from the history.
double Anderson::combine_history(Vector &lambda, Vector &dv, int j)
{
  std::vector<double> &dots = dots_;
  // rhs_i = dF_i . f with f = f_prev + dF_j
  for (int i = 0; i < count_; ++i) {
    gram_(i, j) = gram_(j, i) = dots[i];
    rhs_[i] = i == j ? dots[count_] + dots[j] : rhs_[i] + dots[i];
  }
  dX2_[j] = dots[count_ + 1];
  for (int i = 0; i < count_; ++i)
    if (dX2_[i] > 0) sigma_ = std::min(sigma_, std::sqrt(gram_(i, i) / dX2_[i]));
  // a small Tikhonov term keeps nearly parallel columns from amplifying round-off
  const Eigen::MatrixXd h = gram_.topLeftCorner(count_, count_);
  const double shift = 1e-10 * h.trace() / count_;
  const Vector gamma =
      (h + shift * Eigen::MatrixXd::Identity(count_, count_)).ldlt().solve(rhs_.head(count_));
  combined_ = gamma.allFinite();
  if (!combined_) {
    restart();
    x_ = lambda;
    return sigma_;
  }
  // the velocities' new column dv - dv_prev in the same pass as their combination
  dDV_[j].resize(dv.size());
  combine(dDV_, gamma, dv, dv_prev_.data(), dDV_[j].data());
  combine(dG_, gamma, lambda, nullptr, nullptr, x_.data());
  return sigma_;
}

void Anderson::restart()
{
  count_ = 0;
  newest_ = -1;
  started_ = false;
  combined_ = false;
}

void Anderson::columns(const std::vector<Vector> &v)
{
  ptr_.resize(count_);
  for (int i = 0; i < count_; ++i) ptr_[i] = v[i].data();
}

void Anderson::combine(const std::vector<Vector> &v, const Vector &gamma, Vector &y,
                       double *previous, double *newest, double *copy)
{
  columns(v);
  double *out = y.data();
  const Eigen::Index n = y.size();
  for (Eigen::Index e0 = 0; e0 < n; e0 += kBlock) { // a block of y stays in cache
    const Eigen::Index e1 = std::min(n, e0 + kBlock);
    if (previous)
      for (Eigen::Index e = e0; e < e1; ++e) {
        newest[e] = out[e] - previous[e];
        previous[e] = out[e];
      }
    for (int i = 0; i < count_; ++i) {
      const double *p = ptr_[i], gi = gamma[i];
      for (Eigen::Index e = e0; e < e1; ++e) out[e] -= gi * p[e];
    }
    if (copy) std::copy(out + e0, out + e1, copy + e0);
  }
}

} // namespace fibre
