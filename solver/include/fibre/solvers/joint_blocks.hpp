// The lock joints of each clump (joint_contact) solved together and exactly inside the sweeps:
// block Gauss-Seidel, a clump's joints one block. Swept one joint at a time, a clump's joints
// hand its load on through the hub one member at a time, and a heap of clumps took 150 to 260
// sweeps a step where spheres take 10 to 20. Solved as a block given the other contacts'
// impulses, the clump answers them as one rigid body within each sweep. A joint is bilateral
// (its cones bound nothing), so a block is one linear solve of G_J M^-1 G_J^T + Sigma_J, J the
// block's rows. Every joint of a block shares the hub and no other body, so that matrix is
// block diagonal (each joint's member and Sigma) plus the hub's part, U W U^T (U the rows of the
// hub, W its inverse mass): the solve takes the hub's velocity change from a 6x6 system and each
// joint's impulse from its member's diagonal (Woodbury): a few dozen numbers a joint, where a
// dense factor of order 6 a joint spent most of a heap's step in its triangular solves.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "fibre/core/system.hpp"

namespace fibre {

class JointBlocks {
 public:
  // The joints among `list` (every contact where null) in blocks, one per hub (a joint's body
  // b; a periodic image counts as its body, `owners` as Exchange::local_owners), with the
  // sweeps' inverse masses (pgs.cpp's, split where bodies are shared). Only for six rows a
  // contact and no masked row; a block that does not have this structure or cannot be inverted
  // stays out (its joints are swept one at a time).
  JointBlocks(const ContactSystem &sys, const std::vector<int> &owners, const double *inv_mass,
              const std::vector<int> *list);
  bool empty() const { return blocks_.empty(); }
  // The contacts of `list` (or all) that no block holds, in their order.
  const std::vector<int> &others() const { return others_; }
  // Each block's impulses moved to solve its rows exactly against the current dv, and dv
  // follows; ||change||^2 and ||lambda||^2 of the blocks' rows added to norms, as a sweep does,
  // and ||lambda||^2 to joints.
  void solve(const Vector &b, Vector &lambda, Vector &dv, double norms[2], double &joints) const;

 private:
  // Joint j's member part D_j = G_a M_a^-1 G_a^T + Sigma_j is diagonal (the joint's point is
  // the member's centre, a sphere's inverse mass is isotropic and the frame orthonormal): its
  // inverse is six numbers, and U_j is applied in its structured form (contact_rows.hpp). The
  // sweeps visit every joint tens of times a step, and a dense 6x6 inverse and two 6x6
  // products a joint made them memory-bound.
  struct Joint {
    int contact, member;
    Vec6 member_inverse; // the diagonal of D_j^-1
  };
  struct Block {
    int hub;
    std::vector<Joint> joints;
    Mat6 hub_response; // (I + W sum_j U_j^T D_j^-1 U_j)^-1 W: the hub's dv from sum_j U_j^T y_j
  };
  bool factor_block(Block &block, const std::vector<int> &joints) const;

  const ContactSystem &sys_;
  const std::vector<int> &owners_;
  const double *inv_mass_;
  std::vector<Block> blocks_;
  std::vector<int> others_;
};

} // namespace fibre
