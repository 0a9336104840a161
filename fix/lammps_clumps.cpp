#include "lammps_clumps.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Geometry>

#include "atom.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "fix.h"
#include "host.h"

using namespace LAMMPS_NS;

namespace fibre_lmp {

namespace {

constexpr int kHub = 0, kOffset = 1, kOrientation = 4;

Eigen::Quaterniond orientation(const std::array<double, LammpsClumps::kValues> &s)
{
  return Eigen::Quaterniond(s[kOrientation], s[kOrientation + 1], s[kOrientation + 2],
                            s[kOrientation + 3]);
}

} // namespace

LammpsClumps::LammpsClumps(LAMMPS *lmp, Fix *fix, int groupbit)
    : Pointers(lmp), fix_(fix), groupbit_(groupbit)
{
}

void LammpsClumps::check() const
{
  if (!atom->molecule_flag)
    fail(error, FLERR,
         "Fix fibre_contact clumps molecule requires molecule IDs (atom_style with molecules, or "
         "fix property/atom mol ghost yes)");
  if (atom->map_style == 0)
    fail(error, FLERR,
         "Fix fibre_contact clumps molecule requires an atom map (atom_modify map array)");
}

long long LammpsClumps::molecule(int i) const
{
  return atom->molecule ? static_cast<long long>(atom->molecule[i]) : 0;
}

int LammpsClumps::pack(int i, double *buf) const
{
  std::copy(state_[i].begin(), state_[i].end(), buf);
  return kValues;
}

int LammpsClumps::unpack(int i, const double *buf)
{
  std::copy(buf, buf + kValues, state_[i].begin());
  return kValues;
}

int LammpsClumps::pack_forward(int n, const int *list, double *buf) const
{
  for (int k = 0; k < n; ++k)
    std::copy(state_[list[k]].begin(), state_[list[k]].end(), buf + kValues * k);
  return kValues * n;
}

void LammpsClumps::unpack_forward(int first, int n, const double *buf)
{
  for (int k = 0; k < n; ++k)
    std::copy(buf + kValues * k, buf + kValues * (k + 1), state_[first + k].begin());
}

void LammpsClumps::rotate(double dt)
{
  const tagint *tag = atom->tag;
  double **omega = atom->omega;
  for (int i = 0; i < atom->nlocal; ++i) {
    if (!(atom->mask[i] & groupbit_) || state_[i][kHub] != static_cast<double>(tag[i])) continue;
    const fibre::Vec3 w(omega[i][0], omega[i][1], omega[i][2]);
    const double angle = w.norm() * dt;
    if (!(angle > 0)) continue;
    Eigen::Quaterniond q =
        Eigen::Quaterniond(Eigen::AngleAxisd(angle, w.normalized())) * orientation(state_[i]);
    q.normalize();
    state_[i][kOrientation] = q.w();
    state_[i][kOrientation + 1] = q.x();
    state_[i][kOrientation + 2] = q.y();
    state_[i][kOrientation + 3] = q.z();
  }
}

int LammpsClumps::hub_of(int i) const
{
  const tagint hub = static_cast<tagint>(state_[i][kHub]);
  const int j = atom->map(hub);
  if (j < 0)
    fail_one(error, FLERR,
             "Fix fibre_contact clumps: atom " + std::to_string(atom->tag[i]) +
                 " cannot see its clump's first atom " + std::to_string(hub) +
                 " (lost, or beyond the halo: comm_modify cutoff must reach across a clump)");
  return domain->closest_image(i, j);
}

void LammpsClumps::forward(bool &forward_clumps)
{
  forward_clumps = true;
  fibre_forward_comm(comm, fix_, kValues);
  forward_clumps = false;
}

// New clumps: the hub of each is its molecule's atom of smallest tag, at the identity
// orientation; each member's offset is where it is now, in the hub's frame.
void LammpsClumps::set_up_new()
{
  const int nlocal = atom->nlocal;
  const tagint *tag = atom->tag;
  const auto fresh = [&](int i) {
    return (atom->mask[i] & groupbit_) && molecule(i) > 0 && state_[i][kHub] == 0.0;
  };
  long long top = 0;
  for (int i = 0; i < nlocal; ++i)
    if (fresh(i)) top = std::max(top, molecule(i));
  long long all_top = 0;
  MPI_Allreduce(&top, &all_top, 1, MPI_LONG_LONG, MPI_MAX, world);
  std::vector<long long> hub(all_top + 1, std::numeric_limits<long long>::max()),
      all_hub(all_top + 1);
  for (int i = 0; i < nlocal; ++i)
    if (fresh(i)) hub[molecule(i)] = std::min<long long>(hub[molecule(i)], tag[i]);
  MPI_Allreduce(hub.data(), all_hub.data(), static_cast<int>(all_hub.size()), MPI_LONG_LONG,
                MPI_MIN, world);
  std::vector<int> members;
  for (int i = 0; i < nlocal; ++i) {
    if (!fresh(i)) continue;
    const long long h = all_hub[molecule(i)];
    if (h == tag[i])
      state_[i] = {static_cast<double>(h), 0, 0, 0, 1, 0, 0, 0};
    else
      members.push_back(i);
    state_[i][kHub] = static_cast<double>(h);
  }
  bool unused = false;
  forward(unused); // the hubs' orientations to their ghosts
  double **x = atom->x;
  for (int i : members) {
    const int j = hub_of(i);
    const fibre::Vec3 d(x[i][0] - x[j][0], x[i][1] - x[j][1], x[i][2] - x[j][2]);
    const fibre::Vec3 rest = orientation(state_[j]).conjugate() * d;
    for (int k = 0; k < 3; ++k) state_[i][kOffset + k] = rest[k];
  }
}

void LammpsClumps::prepare(bool &forward_clumps)
{
  int any = 0, all = 0;
  for (int i = 0; i < atom->nlocal && !any; ++i)
    any = (atom->mask[i] & groupbit_) && molecule(i) > 0 && state_[i][kHub] == 0.0;
  MPI_Allreduce(&any, &all, 1, MPI_INT, MPI_MAX, world);
  if (all) set_up_new();
  forward(forward_clumps);
}

void LammpsClumps::joints(const std::vector<fibre::Body> &bodies, const std::vector<int> &atom_body,
                          std::vector<fibre::DetectedContact> &found) const
{
  const int nlocal = atom->nlocal;
  const tagint *tag = atom->tag;
  double **x = atom->x;
  for (int i = 0; i < nlocal; ++i) {
    const double hub = state_[i][kHub];
    if (atom_body[i] < 0 || hub == 0.0 || hub == static_cast<double>(tag[i])) continue;
    const int j = hub_of(i);
    if (atom_body[j] < 0)
      fail_one(error, FLERR,
               "Fix fibre_contact clumps: atom " + std::to_string(tag[i]) +
                   " is in the fix's group and its clump's first atom is not");
    const fibre::Vec3 rest(state_[i][kOffset], state_[i][kOffset + 1], state_[i][kOffset + 2]);
    const fibre::Vec3 axis = orientation(state_[j]) * rest;
    const fibre::Vec3 d(x[i][0] - x[j][0], x[i][1] - x[j][1], x[i][2] - x[j][2]);
    fibre::DetectedContact &fc = found.emplace_back();
    fc.contact = fibre::joint_contact(bodies, atom_body[i], atom_body[j], axis, d - axis);
    // the hub has the smaller tag; it keeps the warm start where it is owned here
    fc.tag_a = tag[j];
    fc.partner = static_cast<double>(tag[i]);
    fc.store = j < nlocal ? j : i;
    fc.key = fc.store == j ? fc.partner : static_cast<double>(fc.tag_a);
  }
}

} // namespace fibre_lmp
