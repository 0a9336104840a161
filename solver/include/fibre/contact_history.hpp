// Warm-start history per atom, without a front end: every atom keeps up to kMaxSlots of its
// contacts as (key, force, torque) of the last step, in the world frame, so that they survive
// the contact frame's rotation, atom migration and restart files. The front end calls grow,
// copy, clear, pack and unpack from its per-atom callbacks.
#pragma once

#include <vector>

#include "fibre/detection.hpp"
#include "fibre/system.hpp"

namespace fibre {

class ContactHistory {
 public:
  static constexpr int kMaxSlots = 16;
  // key (the other side's tag, or a wall key), then force and torque (impulse / h) acting on
  // the contact's body a.
  static constexpr int kSlotSize = 7;
  static constexpr int kMaxPacked = 1 + kMaxSlots * kSlotSize;

  void grow(int nmax); // room for atoms [0, nmax); new atoms have no contacts
  int capacity() const { return static_cast<int>(count_.size()); }
  void clear(int i) { count_[i] = 0; }
  void copy(int from, int to);
  int packed_size(int i) const { return 1 + count_[i] * kSlotSize; }
  // buf <- [n, n slots]; returns the number of values written (packed_size).
  int pack(int i, double *buf) const;
  // Atom i <- [n, slots] from buf, trusting at most `available` values after n; returns the
  // number of values read.
  int unpack(int i, const double *buf, int available = kMaxSlots * kSlotSize);
  double memory_bytes() const;

  // The step's warm start, rows per contact: lambda_r = h (F . d_r) with the stored force and
  // torque and this step's frame (zero for contacts not stored).
  Vector warm_start(const std::vector<DetectedContact> &found, int rows, double h) const;
  // Replaces every stored contact of atoms [0, nlocal) by this step's pressing contacts.
  // Returns how many did not fit (more than kMaxSlots on one atom).
  long store(const std::vector<DetectedContact> &found, const Vector &lambda, int rows, double h,
             int nlocal);

 private:
  const double *find(int atom, double key) const;
  std::vector<int> count_;
  std::vector<double> slots_; // kMaxSlots * kSlotSize per atom
};

} // namespace fibre
