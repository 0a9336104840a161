#include "fibre/solvers/joint_blocks.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "fibre/algebra/contact_rows.hpp"
#include "fibre/core/exchange.hpp"

namespace fibre {

namespace {

constexpr int kRows = 6; // a joint's rows; blocks only where every contact has six

// Contact c's frame and levers (ContactKinematics: 15 numbers in a row).
const double *rows_of(const ContactSystem &sys, int c)
{
  return sys.kinematics(0).frame.data() + 15 * std::size_t(c);
}

} // namespace

JointBlocks::JointBlocks(const ContactSystem &sys, const std::vector<int> &owners,
                         const double *inv_mass, const std::vector<int> *list)
    : sys_(sys), owners_(owners), inv_mass_(inv_mass)
{
  const int count = list ? static_cast<int>(list->size()) : sys.num_contacts();
  const bool usable = sys.rows() == kRows && sys.row_mask().empty();
  std::unordered_map<int, std::size_t> block_of_hub;
  std::vector<std::vector<int>> joints;
  for (int k = 0; k < count; ++k) {
    const int c = list ? (*list)[k] : k;
    const Contact &contact = sys.contacts()[c];
    if (!usable || !contact.is_joint()) {
      others_.push_back(c);
      continue;
    }
    const auto [at, added] = block_of_hub.try_emplace(owner_of(owners, contact.b), joints.size());
    if (added) joints.emplace_back();
    joints[at->second].push_back(c);
  }
  // a block that cannot be factored goes back to the sweeps, its joints at the end
  for (const std::vector<int> &block : joints) {
    blocks_.emplace_back();
    if (factor_block(blocks_.back(), block)) continue;
    blocks_.pop_back();
    others_.insert(others_.end(), block.begin(), block.end());
  }
}

// Each joint's D_j and U_j from unit impulses and velocities, then the hub's response. False
// where the joints share a member, a D_j is not diagonal (the block is then not the sum above) or
// an inverse is not finite.
bool JointBlocks::factor_block(Block &block, const std::vector<int> &joints) const
{
  block.hub = owner_of(owners_, sys_.contacts()[joints[0]].b);
  const Vec6 hub_inv_mass(inv_mass_ + kRows * std::size_t(block.hub));
  Mat6 hub_matrix = Mat6::Zero(); // sum_j U_j^T D_j^-1 U_j
  const double zero[kRows] = {0, 0, 0, 0, 0, 0};
  for (const int c : joints) {
    const int a = owner_of(owners_, sys_.contacts()[c].a);
    for (const Joint &other : block.joints)
      if (other.member == a) return false;
    if (a == block.hub) return false;
    const double *q = rows_of(sys_, c);
    Mat6 member, hub_rows;
    for (int i = 0; i < kRows; ++i) {
      double unit[kRows] = {0, 0, 0, 0, 0, 0}, ya[kRows] = {0, 0, 0, 0, 0, 0};
      unit[i] = 1.0;
      contact_impulse<kRows>(q, q + 9, q + 12, unit, ya, nullptr);
      for (int d = 0; d < kRows; ++d) ya[d] *= inv_mass_[kRows * std::size_t(a) + d];
      contact_velocity<kRows>(q, q + 9, q + 12, ya, nullptr, member.col(i).data());
      member(i, i) += sys_.sigma()[kRows * Eigen::Index(c) + i];
      contact_velocity<kRows>(q, q + 9, q + 12, zero, unit, hub_rows.col(i).data());
    }
    const Vec6 diagonal = member.diagonal();
    if ((member - Mat6(diagonal.asDiagonal())).cwiseAbs().maxCoeff() >
        1e-12 * diagonal.cwiseAbs().maxCoeff())
      return false;
    const Joint joint{c, a, diagonal.cwiseInverse()};
    hub_matrix += hub_rows.transpose() * joint.member_inverse.asDiagonal() * hub_rows;
    if (!joint.member_inverse.allFinite()) return false;
    block.joints.push_back(joint);
  }
  const Mat6 hub = Mat6::Identity() + hub_inv_mass.asDiagonal() * hub_matrix;
  block.hub_response = hub.inverse() * hub_inv_mass.asDiagonal();
  return block.hub_response.allFinite();
}

// Per block: the members' answers y_j = D_j^-1 r_j, the hub's velocity change dw from
// sum_j U_j^T y_j, then each joint's impulse change y_j - D_j^-1 U_j dw.
void JointBlocks::solve(const Vector &b, Vector &lambda, Vector &dv, double norms[2],
                        double &joints) const
{
  const double *sigma = sys_.sigma().data();
  double *w = dv.data();
  const double zero[kRows] = {0, 0, 0, 0, 0, 0};
  std::vector<Vec6> y;
  for (const Block &block : blocks_) {
    y.resize(block.joints.size());
    double *w_hub = w + kRows * std::size_t(block.hub);
    double t[kRows] = {0, 0, 0, 0, 0, 0}, unused[kRows] = {0, 0, 0, 0, 0, 0};
    for (std::size_t j = 0; j < block.joints.size(); ++j) {
      const Joint &joint = block.joints[j];
      const double *q = rows_of(sys_, joint.contact);
      double u[kRows];
      contact_velocity<kRows>(q, q + 9, q + 12, w + kRows * std::size_t(joint.member), w_hub, u);
      const std::size_t at = kRows * std::size_t(joint.contact);
      for (int i = 0; i < kRows; ++i)
        y[j][i] = joint.member_inverse[i] * (b[at + i] - u[i] - sigma[at + i] * lambda[at + i]);
      contact_impulse<kRows>(q, q + 9, q + 12, y[j].data(), unused, t); // t += U_j^T y_j
    }
    const Vec6 dw = block.hub_response * Eigen::Map<const Vec6>(t);
    for (std::size_t j = 0; j < block.joints.size(); ++j) {
      const Joint &joint = block.joints[j];
      const double *q = rows_of(sys_, joint.contact);
      double u[kRows], delta[kRows], ya[kRows] = {0, 0, 0, 0, 0, 0};
      contact_velocity<kRows>(q, q + 9, q + 12, zero, dw.data(), u); // U_j dw
      const std::size_t at = kRows * std::size_t(joint.contact);
      for (int i = 0; i < kRows; ++i) {
        delta[i] = y[j][i] - joint.member_inverse[i] * u[i];
        lambda[at + i] += delta[i];
        norms[0] += delta[i] * delta[i];
        norms[1] += lambda[at + i] * lambda[at + i];
        joints += lambda[at + i] * lambda[at + i];
      }
      contact_impulse<kRows>(q, q + 9, q + 12, delta, ya, nullptr);
      double *w_member = w + kRows * std::size_t(joint.member);
      const double *m = inv_mass_ + kRows * std::size_t(joint.member);
      for (int d = 0; d < kRows; ++d) w_member[d] += m[d] * ya[d];
    }
    for (int d = 0; d < kRows; ++d) w_hub[d] += dw[d];
  }
}

} // namespace fibre
