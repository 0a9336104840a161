// Fibre-block corrections inside the projected Gauss-Seidel sweeps (issue #13): line
// relaxation along the contact chains. Each fibre (fibres.hpp), extended by one wall contact
// at each end body when it has one, is a block whose A_BB = G_B M^-1 G_B^T + Sigma_B is block
// tridiagonal. Before each sweep every block solves its linear sub-problem exactly, with the
// rows that the current impulses hold on a bound fixed (released contacts, cones on their
// boundary), projects the result, and keeps it when it lowers the step's quadratic energy. The
// sweep that follows then does the nonsmooth work contact by contact, as plain PGS does.
#pragma once

#include <vector>

#include "fibre/algebra/cones.hpp"
#include "fibre/core/system.hpp"
#include "fibre/precond/fibres.hpp"

namespace fibre {

class FibreBlocks {
 public:
  // Blocks over the owned bodies of `sys` (fibres never cross processes). `owners` maps a
  // periodic image to its body (Exchange::local_owners, empty when none). `impulses`
  // (normal impulse per contact, or null) is read for EdgeWeight::impulse.
  FibreBlocks(const ContactSystem &sys, const std::vector<int> &owners, const Cones &cones,
              EdgeWeight weight, const Vector *impulses);

  // One pass over the blocks against the rhs b, updating lambda (feasible on entry and on
  // return) and dv = M^-1 G^T lambda (local; contributions to ghosts included). Returns the
  // number of blocks whose correction was kept.
  int correct(const Vector &b, Vector &lambda, Vector &dv);

  int num_blocks() const { return static_cast<int>(start_.size()) - 1; }
  int num_contacts() const { return static_cast<int>(contacts_.size()); }

 private:
  using Mat = Mat6; // rows beyond sys.rows() are padded as decoupled identity rows
  void factor(int blk);
  bool update_mask(int blk, const Vector &lambda);
  void solve_block(int blk, const Vector &b, const Vector &lambda, const Vector &dv);
  double step_limit(int blk, const Vector &lambda) const;
  double best_step(int blk, const Vector &lambda, double alpha);
  void apply_step(int blk, Vector &lambda, Vector &dv) const;
  int body_of(int index) const { return owners_.empty() || index < 0 ? index : owners_[index]; }

  const ContactSystem &sys_;
  const std::vector<int> &owners_;
  const Cones &cones_;
  int rows_;
  std::vector<int> contacts_;        // block contacts in chain order, blocks concatenated
  std::vector<int> start_{0};        // block k: contacts_[start_[k] .. start_[k+1])
  std::vector<Mat> diag_, upper_;    // A_kk and A_k,k+1 per block contact (upper: 0 at ends)
  std::vector<Mat> inv_pivot_;       // the factor of the masked block: S_k^-1
  std::vector<Mat> lower_;           // and L_k = A_k,k-1 S_k-1^-1
  std::vector<unsigned char> mask_;  // 6 per block contact: 1 = row free in the factor
  std::vector<unsigned char> valid_; // per block: its factor matches mask_
  std::vector<Vec6> rho_, x_, step_, trial_; // correct()'s working storage, per block contact
};

} // namespace fibre
