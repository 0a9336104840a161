#include "fibre/solvers/joint_blocks.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "fibre/algebra/contact_rows.hpp"

namespace fibre {

namespace {

constexpr int kRows = 6; // a joint's rows; blocks only where every contact has six

// Contact c's frame and levers (ContactKinematics: 15 numbers in a row).
const double *rows_of(const ContactSystem &sys, int c)
{
  return sys.kinematics(0).frame.data() + 15 * std::size_t(c);
}

int owner_of(const std::vector<int> &owners, int body)
{
  return owners.empty() || body < 0 ? body : owners[body];
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
// where the joints share a member (D is then not block diagonal) or an inverse is not finite.
bool JointBlocks::factor_block(Block &block, const std::vector<int> &joints) const
{
  block.hub = owner_of(owners_, sys_.contacts()[joints[0]].b);
  const Vec6 hub_inv_mass(inv_mass_ + kRows * std::size_t(block.hub));
  std::vector<int> members;
  Mat6 hub_matrix = Mat6::Zero(); // sum_j U_j^T D_j^-1 U_j
  bool finite = true;
  for (const int c : joints) {
    const int a = owner_of(owners_, sys_.contacts()[c].a);
    if (a == block.hub || std::find(members.begin(), members.end(), a) != members.end())
      return false;
    members.push_back(a);
    const double *q = rows_of(sys_, c);
    Joint joint{c, Mat6::Zero(), Mat6::Zero(), Mat6::Zero()};
    Mat6 member;
    const double zero[kRows] = {0, 0, 0, 0, 0, 0};
    for (int i = 0; i < kRows; ++i) {
      double unit[kRows] = {0, 0, 0, 0, 0, 0}, ya[kRows] = {0, 0, 0, 0, 0, 0};
      unit[i] = 1.0;
      contact_impulse<kRows>(q, q + 9, q + 12, unit, ya, nullptr);
      for (int d = 0; d < kRows; ++d) ya[d] *= inv_mass_[kRows * std::size_t(a) + d];
      contact_velocity<kRows>(q, q + 9, q + 12, ya, nullptr, member.col(i).data());
      member(i, i) += sys_.sigma()[kRows * Eigen::Index(c) + i];
      contact_velocity<kRows>(q, q + 9, q + 12, zero, unit, joint.hub_rows.col(i).data());
    }
    joint.member = member.inverse();
    joint.reduced = joint.member * joint.hub_rows;
    hub_matrix += joint.hub_rows.transpose() * joint.reduced;
    finite = finite && joint.reduced.allFinite();
    block.joints.push_back(joint);
  }
  const Mat6 hub = Mat6::Identity() + hub_inv_mass.asDiagonal() * hub_matrix;
  block.hub_response = hub.inverse() * hub_inv_mass.asDiagonal();
  return finite && block.hub_response.allFinite();
}

void JointBlocks::solve(const Vector &b, Vector &lambda, Vector &dv, double norms[2]) const
{
  const double *sigma = sys_.sigma().data();
  double *w = dv.data();
  std::vector<Vec6> delta;
  for (const Block &block : blocks_) {
    // the members' answers y_j = D_j^-1 r_j, the hub's velocity change, then each joint's
    delta.resize(block.joints.size());
    Vec6 t = Vec6::Zero();
    for (std::size_t j = 0; j < block.joints.size(); ++j) {
      const Joint &joint = block.joints[j];
      const double *q = rows_of(sys_, joint.contact);
      double u[kRows];
      contact_velocity<kRows>(q, q + 9, q + 12, w + kRows * std::size_t(member_of(joint)),
                              w + kRows * std::size_t(block.hub), u);
      const std::size_t at = kRows * std::size_t(joint.contact);
      Vec6 r;
      for (int i = 0; i < kRows; ++i) r[i] = b[at + i] - u[i] - sigma[at + i] * lambda[at + i];
      delta[j].noalias() = joint.member * r;
      t.noalias() += joint.hub_rows.transpose() * delta[j];
    }
    const Vec6 hub_dv = block.hub_response * t;
    for (std::size_t j = 0; j < block.joints.size(); ++j) {
      const Joint &joint = block.joints[j];
      delta[j].noalias() -= joint.reduced * hub_dv;
      const std::size_t at = kRows * std::size_t(joint.contact);
      for (int i = 0; i < kRows; ++i) {
        lambda[at + i] += delta[j][i];
        norms[0] += delta[j][i] * delta[j][i];
        norms[1] += lambda[at + i] * lambda[at + i];
      }
      double ya[kRows] = {0, 0, 0, 0, 0, 0};
      const double *q = rows_of(sys_, joint.contact);
      contact_impulse<kRows>(q, q + 9, q + 12, delta[j].data(), ya, nullptr);
      const std::size_t a = kRows * std::size_t(member_of(joint));
      for (int d = 0; d < kRows; ++d) w[a + d] += inv_mass_[a + d] * ya[d];
    }
    for (int d = 0; d < kRows; ++d) w[kRows * std::size_t(block.hub) + d] += hub_dv[d];
  }
}

int JointBlocks::member_of(const Joint &joint) const
{
  return owner_of(owners_, sys_.contacts()[joint.contact].a);
}

} // namespace fibre
