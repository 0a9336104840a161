/* ----------------------------------------------------------------------
   fix fibre_contact: per-atom state (the contact history and the pending displacement of the
   last step's substeps) that migrates with its atoms and goes into restart files, and the
   Exchange's halo communication. The step itself is in fix_fibre_contact.cpp.
------------------------------------------------------------------------- */

#include "fix_fibre_contact.h"

#include <algorithm>

#include "atom.h"
#include "fibre_output.h"
#include "host.h"
#include "lammps_clumps.h"
#include "lammps_exchange.h"

using namespace LAMMPS_NS;

/* ----------------------------------------------------------------------
   per-atom warm-start storage: fibre::ContactHistory
------------------------------------------------------------------------- */

void FixFibreContact::grow_arrays(int nmax)
{
  history_.grow(nmax);
  pending_.resize(std::max<std::size_t>(pending_.size(), nmax), {0.0, 0.0, 0.0});
  if (clumps_) clumps_->grow(nmax);
}

void FixFibreContact::copy_arrays(int i, int j, int /*delflag*/)
{
  history_.copy(i, j);
  pending_[j] = pending_[i];
  if (clumps_) clumps_->copy(i, j);
}

void FixFibreContact::set_arrays(int i)
{
  history_.clear(i);
  pending_[i] = {0.0, 0.0, 0.0};
  if (clumps_) clumps_->clear(i);
}

// [the history, the pending displacement, the clump's state]
int FixFibreContact::pack_exchange(int i, double *buf)
{
  const int m = history_.pack(i, buf);
  std::copy(pending_[i].begin(), pending_[i].end(), buf + m);
  return m + kPendingValues + (clumps_ ? clumps_->pack(i, buf + m + kPendingValues) : 0);
}

int FixFibreContact::unpack_exchange(int nlocal, double *buf)
{
  const int m = history_.unpack(nlocal, buf);
  std::copy(buf + m, buf + m + kPendingValues, pending_[nlocal].begin());
  return m + kPendingValues + (clumps_ ? clumps_->unpack(nlocal, buf + m + kPendingValues) : 0);
}

// [number of values including itself, as other fixes read it; the history; the pending
// displacement] (a restart written within a run, after a step with substeps)
int FixFibreContact::pack_restart(int i, double *buf)
{
  int m = 1 + history_.pack(i, buf + 1);
  std::copy(pending_[i].begin(), pending_[i].end(), buf + m);
  m += kPendingValues;
  buf[0] = m;
  return m;
}

void FixFibreContact::unpack_restart(int nlocal, int nth)
{
  const double *extra = atom->extra[nlocal];
  int m = 0;
  for (int k = 0; k < nth; ++k) m += static_cast<int>(extra[m]);
  const int count = static_cast<int>(extra[m]);
  const int n = static_cast<int>(extra[m + 1]);
  using fibre::ContactHistory;
  // older restart files: 14 values per slot (no penetration), before that no pending
  // displacement, and before the springs 7 values per slot
  int slot = ContactHistory::kSlotSize;
  bool pending = true;
  if (n > 0 && count - 2 - kPendingValues == n * ContactHistory::kSpringSlot) {
    slot = ContactHistory::kSpringSlot;
  } else if (count - 2 - kPendingValues != n * ContactHistory::kSlotSize) {
    pending = false;
    if (n > 0 && count - 2 == n * ContactHistory::kWarmStartSlot)
      slot = ContactHistory::kWarmStartSlot;
    else
      slot = ContactHistory::kSpringSlot;
  }
  const int values = count - 2 - (pending ? kPendingValues : 0);
  history_.unpack(nlocal, extra + m + 1, values, slot);
  pending_[nlocal] = {0.0, 0.0, 0.0};
  if (clumps_) clumps_->clear(nlocal); // set up again from the restart's positions
  if (pending)
    std::copy(extra + m + count - kPendingValues, extra + m + count, pending_[nlocal].begin());
}

int FixFibreContact::size_restart(int i)
{
  return 1 + history_.packed_size(i) + kPendingValues;
}

int FixFibreContact::maxsize_restart()
{
  return 1 + fibre::ContactHistory::kMaxPacked + kPendingValues;
}

/* ----------------------------------------------------------------------
   halo communication for the Exchange (6 values per atom)
------------------------------------------------------------------------- */

int FixFibreContact::FIBRE_PACK_FORWARD(int n, int *list, double *buf, int /*pbc_flag*/,
                                        int * /*pbc*/)
{
  if (forward_clumps_)
    return fibre_lmp::packed_count(clumps_->pack_forward(n, list, buf),
                                   fibre_lmp::LammpsClumps::kValues);
  return fibre_lmp::packed_count(exchange_->pack_forward(n, list, buf),
                                 fibre_lmp::LammpsExchange::kValuesPerAtom);
}

void FixFibreContact::FIBRE_UNPACK_FORWARD(int n, int first, double *buf)
{
  if (forward_clumps_) return clumps_->unpack_forward(first, n, buf);
  exchange_->unpack_forward(first, n, buf);
}

int FixFibreContact::pack_reverse_comm(int n, int first, double *buf)
{
  return fibre_lmp::packed_count(exchange_->pack_reverse(first, n, buf),
                                 fibre_lmp::LammpsExchange::kValuesPerAtom);
}

void FixFibreContact::unpack_reverse_comm(int n, int *list, double *buf)
{
  exchange_->unpack_reverse(n, list, buf);
}

#ifndef FIBRE_HOST_LIGGGHTS
// The variable-size reverse comm's buffers (fix/lammps_compat.h): LAMMPS sizes none for a
// fix's reverse comm under `newton off`.
int FixFibreContact::pack_reverse_comm_size(int n, int /*first*/)
{
  return n * fibre_lmp::LammpsExchange::kValuesPerAtom;
}
#endif

/* ---------------------------------------------------------------------- */

double FixFibreContact::memory_usage()
{
  return history_.memory_bytes() + output_->memory_bytes() +
         double(pending_.capacity()) * sizeof(pending_[0]);
}
