// Anderson acceleration of the sweeps (PgsControl::anderson). The sweeps from the start x
// (PgsControl::anderson_period of them) give g = G(x) and f = g - x; with the differences dF,
// dG of the last `memory` pairs (f, g), the next start is g - dG gamma, gamma = argmin
// |f - dF gamma|. dv is linear in lambda, so the start's velocities combine the same way from
// the stored differences of the sweeps' dv. The Gram matrix dF^T dF and dF^T f are kept up to
// date with one new column a mix.
#pragma once

#include <cmath>
#include <vector>

#include "fibre/core/exchange.hpp"
#include "fibre/core/system.hpp"

namespace fibre {

class Anderson {
 public:
  Anderson(int memory, const Exchange &ex) : memory_(memory), ex_(ex) {}

  // The start of the sweeps that the next mix combines (the mixes set it after the first).
  bool has_start() const { return has_start_; }
  void start(const Vector &lambda)
  {
    x_ = lambda;
    has_start_ = true;
  }

  // `lambda`, `dv` = g and its velocities; on return they hold the next start. Returns the
  // smallest ratio |dF_i| / |dX_i| over the history (dX the differences of the starts): near
  // the solution dF = (J - I) dX, so it estimates the smallest singular value of I - J, and
  // g's error is about |f| over it (infinite without a history: the next start is then g).
  double mix(Vector &lambda, Vector &dv);

  // Whether the last mix combined: lambda is then not the last sweep's impulses.
  bool combined() const { return combined_; }
  // The last mix's g (the sweeps' impulses, feasible) and its |f| / |g|.
  const Vector &sweep_result() const { return g_prev_; }
  double change() const { return change_; }

  // Forget the history (the next mix starts a new one; the start stays).
  void restart();

 private:
  int begin_mix(Eigen::Index n, bool first);
  void measure(const Vector &lambda, bool first, int j);
  double combine_history(Vector &lambda, Vector &dv, int j);
  // the columns' data in ptr_
  void columns(const std::vector<Vector> &v);
  // y -= sum_i gamma_i v_i in one pass; with `previous`, first the newest column
  // v_newest = y - previous and previous = y; with `copy`, copy = the result
  void combine(const std::vector<Vector> &v, const Vector &gamma, Vector &y, double *previous,
               double *newest, double *copy = nullptr);

  using Map = Eigen::Map<Vector>;
  using ConstMap = Eigen::Map<const Vector>;
  static constexpr Eigen::Index kBlock = 512;
  int memory_;
  const Exchange &ex_;
  std::vector<const double *> ptr_;
  int count_ = 0, newest_ = -1;
  double sigma_ = INFINITY;  // the smallest over the whole solve: restarts keep it
  double change_ = INFINITY; // the last mix's |f| / |g|
  bool combined_ = false, started_ = false, has_start_ = false;
  std::vector<Vector> dF_, dG_, dDV_;
  std::vector<double> dX2_, dots_;
  Vector x_, f_prev_, g_prev_, dv_prev_;
  Vector f_ = Vector(kBlock);
  Eigen::MatrixXd gram_ = Eigen::MatrixXd::Zero(memory_, memory_);
  Vector rhs_ = Vector::Zero(memory_);
};

} // namespace fibre
