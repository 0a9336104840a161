// Projected Gauss-Seidel four contacts at a time: the contacts in groups of four that share
// no body, each group swept at once in the four lanes of AVX2's vectors. A sweep over the
// groups is a Gauss-Seidel sweep in the groups' order (within a group no contact sees another's
// update, as none moves another's bodies), so it converges as the one-at-a-time sweep does;
// only the order differs. The sweep's arithmetic was most of a stiff step's time
// (bench/README.md, "Sweeps four contacts at a time").
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "fibre/algebra/cones.hpp"
#include "fibre/core/system.hpp"

namespace fibre {

inline constexpr int kGroupLanes = 4;
using ContactGroup = std::array<int, kGroupLanes>; // contacts; -1 for an empty lane

struct ContactGroups {
  std::vector<ContactGroup> groups;
  // Contacts of a body against its own periodic image (`owners`): both sides are one body,
  // which one lane cannot update twice; they are swept one at a time after the groups.
  std::vector<int> singles;
};

// The contacts in groups, in their order: each joins the oldest of at most 16 open groups
// that holds neither of its bodies (a periodic image counts as its body, `owners` as
// Exchange::local_owners), and a group leaves when full or when a seventeenth is needed.
// Every contact (of `list`, in its order, where given) is in exactly one group or in
// `singles`.
ContactGroups group_contacts(const ContactSystem &sys, const std::vector<int> &owners,
                             const std::vector<int> *list = nullptr);

// Whether this build and processor run the grouped sweeps (x86-64 with AVX2 and FMA).
bool grouped_sweeps_available();

// The groups' data for the sweeps of one solve, packed lane by lane (each of a contact's
// numbers is one vector load): the rows of G, b, Sigma, the inverse row scales, the cones'
// coefficients and pull-off impulses (cohesion) and the bodies' inverse masses. Only where
// grouped_sweeps_available(). With `list`, the sweeps visit those contacts only (a colour phase of
// pgs.cpp).
class GroupedSweep {
 public:
  GroupedSweep(const ContactSystem &sys, const Cones &cones, const Vector &b,
               const double *inv_mass, const std::vector<Vec6> &inv_scale,
               const std::vector<int> &owners, const std::vector<int> *list = nullptr);
  // The same groups for a system of the same kinematics (ContactSystem::kinematics_id) and
  // masses: its rhs, Sigma, row scales and cones' coefficients (the next substep's).
  void refresh(const ContactSystem &sys, const Cones &cones, const Vector &b,
               const std::vector<Vec6> &inv_scale);
  // One sweep over the groups, as pgs.cpp's sweep over the same contacts one at a time:
  // lambda and dv updated, ||change||^2 and ||lambda||^2 added to norms. The singles are not
  // swept here.
  void sweep(Vector &lambda, Vector &dv, double norms[2]);
  const std::vector<int> &singles() const { return singles_; }

 private:
  int rows_;
  bool cohesive_ = false;    // Cones::cohesive(): the sweeps with the shifted normal bound
  std::vector<double> pack_; // kFields x kGroupLanes per group
  std::vector<int> contact_, body_a_, body_b_; // per lane; -1: empty lane, wall
  std::vector<int> singles_;
};

// The sweeps' groups that the solves of one system share while its kinematics hold (the
// substeps of a step: ContactSystem::next_substep): built by the first, refreshed by the next.
struct SweepCache {
  std::uint64_t kinematics = 0; // ContactSystem::kinematics_id of the groups; 0: none
  bool split_masses = false;    // packed with split inverse masses (pgs.cpp, mass splitting)
  std::vector<std::unique_ptr<GroupedSweep>> grouped;
};

} // namespace fibre
