// Clumps for fix fibre_contact (keyword clumps molecule): the spheres of one molecule move as
// one rigid body. Each sphere stays a body of the step; every member of a clump is held to the
// clump's hub (its atom of smallest tag) by a lock joint (fibre::joint_contact), solved with the
// contacts, and pairs within a clump are no contacts. The clump's inertia is its spheres', as
// fix rigid/small's; a clump split over processes needs nothing beyond the halo, which must
// reach across a clump (comm_modify cutoff), as rigid/small's.
//
// Per atom: the hub's tag (0 before the clump is set up), the member's rest offset from the hub
// in the hub's frame, and the hub's orientation (a unit quaternion, turned with the hub's angular
// velocity each step). They migrate with the atoms; a restart sets the clumps up again from the
// positions it holds.
#pragma once

#include <array>
#include <vector>

#include "fibre/core/system.hpp"
#include "fibre/geometry/detection.hpp"
#include "pointers.h"

namespace LAMMPS_NS {
class Fix;
}

namespace fibre_lmp {

class LammpsClumps : protected LAMMPS_NS::Pointers {
 public:
  static constexpr int kValues = 8; // hub tag, offset (3), orientation (4)
  LammpsClumps(LAMMPS_NS::LAMMPS *lmp, LAMMPS_NS::Fix *fix, int groupbit);

  // Errors where the atoms cannot carry clumps (no molecule IDs, no atom map); from init().
  void check() const;
  void grow(int nmax) { state_.resize(std::max<std::size_t>(state_.size(), nmax), {}); }
  void copy(int i, int j) { state_[j] = state_[i]; }
  void clear(int i) { state_[i] = {}; }
  int pack(int i, double *buf) const;
  int unpack(int i, const double *buf);
  int pack_forward(int n, const int *list, double *buf) const;
  void unpack_forward(int first, int n, const double *buf);

  // Turns each owned hub's orientation by its angular velocity over dt.
  void rotate(double dt);
  // Before a step's detection: sets up the clumps of atoms that have none yet (collective) and
  // sends the hubs' state to the ghosts (forward_clumps: the fix's forward comm is this one's).
  void prepare(bool &forward_clumps);
  // Whether atoms i and j are of one clump: no contact between them.
  bool same(int i, int j) const { return molecule(i) > 0 && molecule(i) == molecule(j); }
  // The step's joints: one per owned member (atom_body: the body of each local atom, -1
  // outside the group).
  void joints(const std::vector<fibre::Body> &bodies, const std::vector<int> &atom_body,
              std::vector<fibre::DetectedContact> &found) const;

 private:
  long long molecule(int i) const;
  int hub_of(int i) const; // the local image of i's hub nearest i
  void set_up_new();
  void forward(bool &forward_clumps);

  LAMMPS_NS::Fix *fix_;
  int groupbit_;
  std::vector<std::array<double, kValues>> state_;
};

} // namespace fibre_lmp
