#include "fibre/precond/fibre_blocks.hpp"

#include <algorithm>
#include <cmath>

#include "fibre/algebra/contact_rows.hpp"
#include "fibre/algebra/kernels.hpp"

namespace fibre {

FibreBlocks::FibreBlocks(const ContactSystem &sys, const std::vector<int> &owners,
                         const Cones &cones, EdgeWeight weight, const Vector *impulses)
    : sys_(sys), owners_(owners), cones_(cones), rows_(sys.rows())
{
  const Fibres fibres = build_fibres(sys, weight, impulses, false);
  // The first wall contact of every owned body: it extends a fibre that ends there, so a
  // column's load reaches the floor within the block.
  std::vector<int> wall_of(std::size_t(sys.num_bodies()), -1);
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &contact = sys.contacts()[c];
    const int a = body_of(contact.a);
    if (contact.is_wall() && a >= 0 && a < sys.num_owned_bodies() && wall_of[a] < 0) wall_of[a] = c;
  }
  // Bodies that touch another process's body: the other process moves them within the same
  // sweep (block Jacobi), and an exact block solve on both sides would overshoot. The blocks
  // stop short of them.
  std::vector<unsigned char> interface(std::size_t(sys.num_bodies()), 0);
  for (const Contact &contact : sys.contacts()) {
    const int a = body_of(contact.a), bb = body_of(contact.b);
    if (a >= sys.num_owned_bodies() && bb >= 0) interface[bb] = 1;
    if (bb >= sys.num_owned_bodies() && a >= 0) interface[a] = 1;
  }
  const auto close_block = [&]() {
    if (int(contacts_.size()) - start_.back() >= 2)
      start_.push_back(int(contacts_.size()));
    else
      contacts_.resize(std::size_t(start_.back()));
  };
  for (int f = 0; f < fibres.num_fibres(); ++f) {
    const int b0 = fibres.body_start[f];
    for (int k = fibres.contact_start[f]; k < fibres.contact_start[f + 1]; ++k) {
      // contact k joins the fibre's bodies j and j + 1
      const int j = b0 + (k - fibres.contact_start[f]);
      const int from = fibres.bodies[j], to = fibres.bodies[j + 1];
      if (interface[from] || interface[to]) {
        close_block();
        continue;
      }
      if (int(contacts_.size()) == start_.back() && wall_of[from] >= 0)
        contacts_.push_back(wall_of[from]);
      contacts_.push_back(fibres.contacts[k]);
      const bool last = k + 1 == fibres.contact_start[f + 1];
      if (last && wall_of[to] >= 0) contacts_.push_back(wall_of[to]);
    }
    close_block();
  }
  const std::size_t n = contacts_.size();
  diag_.assign(n, Mat::Identity());
  upper_.assign(n, Mat::Zero());
  inv_pivot_.assign(n, Mat::Identity());
  lower_.assign(n, Mat::Zero());
  mask_.assign(6 * n, 0);
  for (std::vector<Vec6> *v : {&rho_, &x_, &step_, &trial_}) v->assign(n, Vec6::Zero());
  valid_.assign(std::size_t(num_blocks()), 0);
  // A_kk and A_k,k+1 as the contact-form preconditioners form them (kernels.hpp).
  for (int blk = 0; blk < num_blocks(); ++blk)
    for (int k = start_[blk]; k < start_[blk + 1]; ++k) {
      diag_[k] = diagonal_block(sys, contacts_[k]);
      if (k + 1 < start_[blk + 1]) upper_[k] = coupling_block(sys, contacts_[k], contacts_[k + 1]);
    }
}

// Block LDL^T of the masked block (masked rows and columns replaced by the identity):
// S_1 = A_11, L_k = A_k,k-1 S_k-1^-1, S_k = A_kk - L_k A_k-1,k.
void FibreBlocks::factor(int blk)
{
  valid_[blk] = 2; // failed until it succeeds
  Mat pivot;
  for (int k = start_[blk]; k < start_[blk + 1]; ++k) {
    const unsigned char *m = &mask_[6 * std::size_t(k)];
    Mat d = diag_[k];
    for (int i = 0; i < 6; ++i)
      if (!m[i]) {
        d.row(i).setZero();
        d.col(i).setZero();
        d(i, i) = 1.0;
      }
    if (k > start_[blk]) {
      Mat u = upper_[k - 1]; // A_k-1,k
      const unsigned char *mp = &mask_[6 * std::size_t(k - 1)];
      for (int i = 0; i < 6; ++i) {
        if (!mp[i]) u.row(i).setZero();
        if (!m[i]) u.col(i).setZero();
      }
      lower_[k] = u.transpose() * inv_pivot_[k - 1];
      d -= lower_[k] * u;
    }
    Eigen::LLT<Mat> llt(d);
    if (llt.info() != Eigen::Success) return;
    inv_pivot_[k] = llt.solve(Mat::Identity());
  }
  valid_[blk] = 1;
}

// Block blk's mask: the rows the current impulses hold on a bound stay fixed (released
// contacts, cones on their boundary, rows without a cone). Returns whether a row is free; a
// changed mask needs a new factorization.
bool FibreBlocks::update_mask(int blk, const Vector &lambda)
{
  const int R = rows_;
  const int k0 = start_[blk], k1 = start_[blk + 1];
  // The rows the current impulses hold on a bound stay fixed: released contacts, cones on
  // their boundary (their magnitude follows lambda_n in the sweep), rows without a cone.
  bool changed = false, any_free = false;
  for (int k = k0; k < k1; ++k) {
    const int c = contacts_[k];
    const double *l = lambda.data() + Eigen::Index(R) * c;
    unsigned char m[6] = {0, 0, 0, 0, 0, 0};
    if (l[0] > 0) {
      m[0] = 1;
      for (int j = 0; j < num_cones(R); ++j) {
        const Cone &cone = kCones[j];
        const double radius = cones_.coeff(c, j) * l[0];
        double t2 = l[cone.first] * l[cone.first];
        if (cone.size == 2) t2 += l[cone.first + 1] * l[cone.first + 1];
        const bool free = radius > 0 && std::sqrt(t2) < radius * (1 - 1e-9);
        for (int i = 0; i < cone.size; ++i) m[cone.first + i] = free;
      }
    }
    for (int i = 0; i < 6; ++i) {
      changed |= mask_[6 * std::size_t(k) + i] != m[i];
      mask_[6 * std::size_t(k) + i] = m[i];
      any_free |= m[i] != 0;
    }
  }
  if (changed) valid_[blk] = 0;
  return any_free;
}

// rho and the masked solve x of block blk.
void FibreBlocks::solve_block(int blk, const Vector &b, const Vector &lambda, const Vector &dv)
{
  const int R = rows_;
  const double *sigma = sys_.sigma().data();
  std::vector<Vec6> &rho = rho_, &x = x_;
  const int k0 = start_[blk], k1 = start_[blk + 1];
  // rho = b - G dv - Sigma lambda on the block's rows (the full residual: it enters the
  // energy on every row), then the masked solve A_BB x = rho (forward, then back).
  for (int k = k0; k < k1; ++k) {
    const int c = contacts_[k];
    const ContactKinematics &q = sys_.kinematics(c);
    const Contact &contact = sys_.contacts()[c];
    const int a = body_of(contact.a), bb = body_of(contact.b);
    double u[6] = {0, 0, 0, 0, 0, 0};
    contact_velocity<6>(q.frame.data(), q.ra.data(), q.rb.data(), dv.data() + 6 * Eigen::Index(a),
                        bb >= 0 ? dv.data() + 6 * Eigen::Index(bb) : nullptr, u);
    rho[k].setZero();
    for (int i = 0; i < R; ++i) {
      const Eigen::Index row = Eigen::Index(R) * c + i;
      rho[k][i] = b[row] - u[i] - sigma[row] * lambda[row];
    }
    Vec6 y = rho[k];
    if (k > k0) y -= lower_[k] * x[k - 1]; // x holds y of the previous contact here
    for (int i = 0; i < 6; ++i)
      if (!mask_[6 * std::size_t(k) + i]) y[i] = 0.0;
    x[k] = y;
  }
  for (int k = k1 - 1; k >= k0; --k) {
    Vec6 y = x[k];
    if (k + 1 < k1) y -= upper_[k] * x[k + 1];
    for (int i = 0; i < 6; ++i)
      if (!mask_[6 * std::size_t(k) + i]) y[i] = 0.0;
    x[k] = inv_pivot_[k] * y;
  }
}

// Two candidate steps, each projected: the full solve, and the solve cut back to where it
// first leaves the free rows' bounds (a descent direction of the masked quadratic, so the
// cut step lowers the energy unless the sliding cones' rescaling undoes it). The lower of
// the two energies -rho . step + step . A_BB step / 2 is kept when it is negative.
// The step along x at which block blk first leaves the free rows' bounds (at most 1).
double FibreBlocks::step_limit(int blk, const Vector &lambda) const
{
  const int R = rows_;
  const std::vector<Vec6> &x = x_;
  const int k0 = start_[blk], k1 = start_[blk + 1];
  double alpha = 1.0;
  for (int k = k0; k < k1; ++k) {
    const int c = contacts_[k];
    const double *l = lambda.data() + Eigen::Index(R) * c;
    const unsigned char *m = &mask_[6 * std::size_t(k)];
    if (!m[0]) continue;
    if (x[k][0] < 0) alpha = std::min(alpha, -l[0] / x[k][0]);
    for (int j = 0; j < num_cones(R); ++j) {
      const Cone &cone = kCones[j];
      if (!m[cone.first]) continue;
      const double mu = cones_.coeff(c, j);
      Eigen::Vector2d t(l[cone.first], cone.size == 2 ? l[cone.first + 1] : 0.0);
      Eigen::Vector2d d(x[k][cone.first], cone.size == 2 ? x[k][cone.first + 1] : 0.0);
      // |t + a d|^2 - mu^2 (l_n + a x_n)^2 = qa a^2 + qb a + qc, qc < 0 inside the cone
      const double qa = d.squaredNorm() - mu * mu * x[k][0] * x[k][0];
      const double qb = 2 * (t.dot(d) - mu * mu * l[0] * x[k][0]);
      const double qc = t.squaredNorm() - mu * mu * l[0] * l[0];
      const double disc = qb * qb - 4 * qa * qc;
      if (qa == 0) {
        if (qb > 0) alpha = std::min(alpha, -qc / qb);
      } else if (disc >= 0) {
        const double r1 = (-qb + std::sqrt(disc)) / (2 * qa);
        const double r2 = (-qb - std::sqrt(disc)) / (2 * qa);
        const double r = r1 > 0 && (r2 <= 0 || r1 < r2) ? r1 : r2;
        if (r > 0) alpha = std::min(alpha, r);
      }
    }
  }
  return alpha;
}

// The lower energy of the two projected candidates (the full step and the cut one), its step
// in step_.
double FibreBlocks::best_step(int blk, const Vector &lambda, double alpha)
{
  const int R = rows_;
  std::vector<Vec6> &rho = rho_, &x = x_, &step = step_, &trial = trial_;
  const int k0 = start_[blk], k1 = start_[blk + 1];
  double energy = INFINITY;
  for (double a : {1.0, alpha}) {
    if (!(a > 0)) continue;
    double e = 0;
    for (int k = k0; k < k1; ++k) {
      const int c = contacts_[k];
      double l[6] = {0, 0, 0, 0, 0, 0};
      for (int i = 0; i < R; ++i) l[i] = lambda[Eigen::Index(R) * c + i] + a * x[k][i];
      cones_.project(l, c);
      trial[k].setZero();
      for (int i = 0; i < R; ++i) trial[k][i] = l[i] - lambda[Eigen::Index(R) * c + i];
      e -= rho[k].dot(trial[k]);
    }
    for (int k = k0; k < k1; ++k) {
      Vec6 a_step = diag_[k] * trial[k];
      if (k + 1 < k1) a_step += upper_[k] * trial[k + 1];
      if (k > k0) a_step += upper_[k - 1].transpose() * trial[k - 1];
      e += 0.5 * trial[k].dot(a_step);
    }
    if (e < energy) {
      energy = e;
      for (int k = k0; k < k1; ++k) step[k] = trial[k];
    }
    if (alpha >= 1.0) break;
  }
  return energy;
}

// lambda and dv take block blk's step.
void FibreBlocks::apply_step(int blk, Vector &lambda, Vector &dv) const
{
  const int R = rows_;
  const double *inv_mass = sys_.inv_mass().data();
  const std::vector<Vec6> &step = step_;
  const int k0 = start_[blk], k1 = start_[blk + 1];
  for (int k = k0; k < k1; ++k) {
    const int c = contacts_[k];
    const ContactKinematics &q = sys_.kinematics(c);
    const Contact &contact = sys_.contacts()[c];
    const int a = body_of(contact.a), bb = body_of(contact.b);
    for (int i = 0; i < R; ++i) lambda[Eigen::Index(R) * c + i] += step[k][i];
    double ya[6] = {0, 0, 0, 0, 0, 0}, yb[6] = {0, 0, 0, 0, 0, 0};
    contact_impulse<6>(q.frame.data(), q.ra.data(), q.rb.data(), step[k].data(), ya,
                       bb >= 0 ? yb : nullptr);
    for (int d = 0; d < 6; ++d) dv[6 * Eigen::Index(a) + d] += inv_mass[6 * a + d] * ya[d];
    if (bb >= 0)
      for (int d = 0; d < 6; ++d) dv[6 * Eigen::Index(bb) + d] += inv_mass[6 * bb + d] * yb[d];
  }
}

int FibreBlocks::correct(const Vector &b, Vector &lambda, Vector &dv)
{
  int kept = 0;
  for (int blk = 0; blk < num_blocks(); ++blk) {
    if (!update_mask(blk, lambda)) continue;
    if (valid_[blk] == 0) factor(blk);
    if (valid_[blk] != 1) continue;
    solve_block(blk, b, lambda, dv);
    if (!(best_step(blk, lambda, step_limit(blk, lambda)) < 0)) continue;
    ++kept;
    apply_step(blk, lambda, dv);
  }
  return kept;
}

} // namespace fibre
