// fibre::Exchange on LAMMPS halo communication (see lammps_exchange.h).
#include "lammps_exchange.h"

#include <algorithm>
#include <unordered_map>

#include "atom.h"
#include "comm.h"
#include "fix.h"
#include "lammps.h"

namespace fibre_lmp {

LammpsExchange::LammpsExchange(LAMMPS_NS::LAMMPS *lmp, LAMMPS_NS::Fix *fix, MPI_Comm world)
    : lmp_(lmp), fix_(fix), world_(world)
{
}

void LammpsExchange::set_bodies(const std::vector<int> &body_atom, int num_owned)
{
  body_atom_ = body_atom;
  num_owned_ = num_owned;
  // a ghost with the tag of an owned body is its periodic image on this process
  const LAMMPS_NS::tagint *tag = lmp_->atom->tag;
  std::unordered_map<LAMMPS_NS::tagint, int> owned;
  for (int k = 0; k < num_owned; ++k) owned.emplace(tag[body_atom[k]], k);
  local_owners_.resize(body_atom.size());
  for (int k = 0; k < static_cast<int>(body_atom.size()); ++k) {
    const auto it = k < num_owned ? owned.end() : owned.find(tag[body_atom[k]]);
    local_owners_[k] = it == owned.end() ? k : it->second;
  }
  has_halo_ = lmp_->comm->nprocs > 1 || body_atom.size() > std::size_t(num_owned);
}

void LammpsExchange::resize_halo() const
{
  const std::size_t nall = std::size_t(lmp_->atom->nlocal + lmp_->atom->nghost);
  if (halo_.size() < kValuesPerAtom * nall) halo_.resize(kValuesPerAtom * nall);
}

void LammpsExchange::forward(fibre::Vector &body_vec) const
{
  if (!has_halo_) return;
  resize_halo();
  const int nbody = static_cast<int>(body_atom_.size());
  for (int k = 0; k < num_owned_; ++k) {
    double *dst = &halo_[std::size_t(kValuesPerAtom) * body_atom_[k]];
    for (int d = 0; d < kValuesPerAtom; ++d) dst[d] = body_vec[kValuesPerAtom * k + d];
  }
  fibre_forward_comm(lmp_->comm, fix_, kValuesPerAtom);
  for (int k = num_owned_; k < nbody; ++k) {
    const double *src = &halo_[std::size_t(kValuesPerAtom) * body_atom_[k]];
    for (int d = 0; d < kValuesPerAtom; ++d) body_vec[kValuesPerAtom * k + d] = src[d];
  }
}

void LammpsExchange::reverse_sum(fibre::Vector &body_vec) const
{
  if (!has_halo_) return;
  resize_halo();
  const std::size_t nall = std::size_t(lmp_->atom->nlocal + lmp_->atom->nghost);
  std::fill(halo_.begin(), halo_.begin() + kValuesPerAtom * nall, 0.0);
  const int nbody = static_cast<int>(body_atom_.size());
  for (int k = num_owned_; k < nbody; ++k) {
    double *dst = &halo_[std::size_t(kValuesPerAtom) * body_atom_[k]];
    for (int d = 0; d < kValuesPerAtom; ++d) {
      dst[d] = body_vec[kValuesPerAtom * k + d];
      body_vec[kValuesPerAtom * k + d] = 0.0;
    }
  }
  fibre_reverse_comm(lmp_->comm, fix_, kValuesPerAtom);
  for (int k = 0; k < num_owned_; ++k) {
    const double *src = &halo_[std::size_t(kValuesPerAtom) * body_atom_[k]];
    for (int d = 0; d < kValuesPerAtom; ++d) body_vec[kValuesPerAtom * k + d] += src[d];
  }
}

void LammpsExchange::sum(double *values, int n) const
{
  if (n > 0) MPI_Allreduce(MPI_IN_PLACE, values, n, MPI_DOUBLE, MPI_SUM, world_);
}

void LammpsExchange::max(double *values, int n) const
{
  if (n > 0) MPI_Allreduce(MPI_IN_PLACE, values, n, MPI_DOUBLE, MPI_MAX, world_);
}

long LammpsExchange::exclusive_prefix_sum(long local) const
{
  long result = 0;
  MPI_Exscan(&local, &result, 1, MPI_LONG, MPI_SUM, world_);
  int rank = 0;
  MPI_Comm_rank(world_, &rank);
  return rank == 0 ? 0 : result; // MPI_Exscan leaves rank 0's result undefined
}

int LammpsExchange::pack_forward(int n, const int *list, double *buf) const
{
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const double *src = &halo_[std::size_t(kValuesPerAtom) * list[i]];
    for (int d = 0; d < kValuesPerAtom; ++d) buf[m++] = src[d];
  }
  return m;
}

void LammpsExchange::unpack_forward(int first, int n, const double *buf) const
{
  resize_halo();
  int m = 0;
  for (int i = first; i < first + n; ++i) {
    double *dst = &halo_[std::size_t(kValuesPerAtom) * i];
    for (int d = 0; d < kValuesPerAtom; ++d) dst[d] = buf[m++];
  }
}

int LammpsExchange::pack_reverse(int first, int n, double *buf) const
{
  int m = 0;
  for (int i = first; i < first + n; ++i) {
    const double *src = &halo_[std::size_t(kValuesPerAtom) * i];
    for (int d = 0; d < kValuesPerAtom; ++d) buf[m++] = src[d];
  }
  return m;
}

void LammpsExchange::unpack_reverse(int n, const int *list, const double *buf) const
{
  int m = 0;
  for (int i = 0; i < n; ++i) {
    double *dst = &halo_[std::size_t(kValuesPerAtom) * list[i]];
    for (int d = 0; d < kValuesPerAtom; ++d) dst[d] += buf[m++];
  }
}

} // namespace fibre_lmp
