// Contact history per atom, without a front end: every atom keeps up to kMaxSlots of its
// contacts as (key, force, torque, springs) of the last step, in the world frame, so that they
// survive the contact frame's rotation, atom migration and restart files. The force and torque
// warm-start the solve; the springs are the elastic rows' displacements (Contact::spring).
// The front end calls grow, copy, clear, pack and unpack from its per-atom callbacks.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "fibre/core/system.hpp"
#include "fibre/geometry/detection.hpp"

namespace fibre {

class ContactHistory {
 public:
  static constexpr int kMaxSlots = 16;
  // key (the other side's tag, or a wall key), then force and torque (impulse / h) acting on
  // the contact's body a, then the tangential displacement (3), the rolling angle (3) and the
  // twisting angle (1), and the penetration left (Contact::penetration; negated where it is
  // split, Contact::split).
  static constexpr int kSlotSize = 15;
  static constexpr int kSpringSlot = 14; // files without the penetration
  static constexpr int kMaxPacked = 1 + kMaxSlots * kSlotSize;

  void grow(int nmax); // room for atoms [0, nmax); new atoms have no contacts
  int capacity() const { return static_cast<int>(count_.size()); }
  void clear(int i) { count_[i] = 0; }
  void copy(int from, int to);
  int packed_size(int i) const { return 1 + count_[i] * kSlotSize; }
  // buf <- [n, n slots]; returns the number of values written (packed_size).
  int pack(int i, double *buf) const;
  // Atom i <- [n, slots] from buf, trusting at most `available` values after n; returns the
  // number of values read. slot_size: the writer's (kWarmStartSlot: files without springs,
  // which read back with zero springs; kSpringSlot: without penetrations).
  static constexpr int kWarmStartSlot = 7;
  int unpack(int i, const double *buf, int available = kMaxSlots * kSlotSize,
             int slot_size = kSlotSize);
  double memory_bytes() const;

  // The step's warm start, rows per contact: lambda_r = h (F . d_r) with the stored force and
  // torque and this step's frame (zero for contacts not stored); tags[c] is contacts[c]'s.
  Vector warm_start(const std::vector<ContactTag> &tags, const std::vector<Contact> &contacts,
                    int rows, double h) const;
  // Contact::spring of every stored contact in this step's frame: the stored tangential and
  // rolling vectors turned into the new tangent plane with their length kept (LAMMPS's rule),
  // the twisting angle as it is; Contact::penetration and split, and Contact::touched (stored).
  void load_springs(const std::vector<ContactTag> &tags, std::vector<Contact> &contacts) const;
  // Replaces every stored contact by this step's pressing (cohesive ones: or pulling)
  // contacts, with their springs at the step's end (advance_springs, rows per contact, row 0
  // the penetration left; null: none). Returns how many did not fit (more than kMaxSlots on
  // one atom).
  long store(const std::vector<ContactTag> &tags, const std::vector<Contact> &contacts,
             const Vector &lambda, int rows, double h,
             const std::vector<std::array<double, kMaxRows>> *springs = nullptr);

 private:
  const double *find(int atom, double key) const;
  static void write_slot(double *slot, double key, const Contact &k, const double *l, int rows,
                         double h, const std::array<double, kMaxRows> *xi);
  const double *slots(int atom) const { return pool_.data() + first_[atom] * kSlotSize; }
  // Atom i's count_[i] slots start at slot first_[i] of pool_: the pool holds the stored
  // contacts and no more (a layout per atom sized to the most contacts on one atom was 8 slots
  // for each of LAMMPS's atom places, 40% of bench/scale's heap). store() builds a new pool
  // and frees the old; unpack appends; copy shares an atom's slots, which are never written
  // in place.
  std::vector<int> count_;
  std::vector<std::size_t> first_;
  std::vector<double> pool_;
};

} // namespace fibre
