#include "fibre/contact_history.hpp"

#include <algorithm>

namespace fibre {

void ContactHistory::grow(int nmax)
{
  if (nmax <= capacity()) return;
  count_.resize(nmax, 0);
  slots_.resize(std::size_t(nmax) * kMaxSlots * kSlotSize, 0.0);
}

void ContactHistory::copy(int from, int to)
{
  count_[to] = count_[from];
  const double *src = &slots_[std::size_t(from) * kMaxSlots * kSlotSize];
  std::copy(src, src + count_[from] * kSlotSize, &slots_[std::size_t(to) * kMaxSlots * kSlotSize]);
}

int ContactHistory::pack(int i, double *buf) const
{
  buf[0] = count_[i];
  const double *src = &slots_[std::size_t(i) * kMaxSlots * kSlotSize];
  std::copy(src, src + count_[i] * kSlotSize, buf + 1);
  return packed_size(i);
}

int ContactHistory::unpack(int i, const double *buf, int available)
{
  const int n = std::min(
      {kMaxSlots, std::max(0, static_cast<int>(buf[0])), std::max(0, available) / kSlotSize});
  count_[i] = n;
  std::copy(buf + 1, buf + 1 + n * kSlotSize, &slots_[std::size_t(i) * kMaxSlots * kSlotSize]);
  return 1 + n * kSlotSize;
}

double ContactHistory::memory_bytes() const
{
  return double(count_.capacity()) * sizeof(int) + double(slots_.capacity()) * sizeof(double);
}

const double *ContactHistory::find(int atom, double key) const
{
  const double *slot = &slots_[std::size_t(atom) * kMaxSlots * kSlotSize];
  for (int k = 0; k < count_[atom]; ++k, slot += kSlotSize)
    if (slot[0] == key) return slot;
  return nullptr;
}

Vector ContactHistory::warm_start(const std::vector<DetectedContact> &found, int rows,
                                  double h) const
{
  const int nc = static_cast<int>(found.size());
  Vector warm = Vector::Zero(Eigen::Index(rows) * nc);
  for (int c = 0; c < nc; ++c) {
    const double *slot = find(found[c].store, found[c].key);
    if (!slot) continue;
    const Vec3 force(slot[1], slot[2], slot[3]), moment(slot[4], slot[5], slot[6]);
    const Contact &k = found[c].contact;
    const Vec3 dirs[3] = {k.normal, k.t1, k.t2};
    for (int r = 0; r < rows; ++r)
      warm[Eigen::Index(rows) * c + r] = h * (r < 3 ? force.dot(dirs[r]) : moment.dot(dirs[r - 3]));
  }
  return warm;
}

long ContactHistory::store(const std::vector<DetectedContact> &found, const Vector &lambda,
                           int rows, double h, int nlocal)
{
  std::fill(count_.begin(), count_.begin() + nlocal, 0);
  long overflow = 0;
  for (int c = 0; c < static_cast<int>(found.size()); ++c) {
    const DetectedContact &fc = found[c];
    const Contact &k = fc.contact;
    const double *l = lambda.data() + Eigen::Index(rows) * c;
    if (!(l[0] > 0.0)) continue; // released: nothing to remember
    const Vec3 force = (l[0] * k.normal + l[1] * k.t1 + l[2] * k.t2) / h;
    Vec3 moment = Vec3::Zero();
    if (rows == 6) moment = (l[3] * k.normal + l[4] * k.t1 + l[5] * k.t2) / h;
    const int s = fc.store;
    if (count_[s] >= kMaxSlots) {
      ++overflow;
      continue;
    }
    double *slot = &slots_[(std::size_t(s) * kMaxSlots + count_[s]++) * kSlotSize];
    slot[0] = fc.key;
    for (int d = 0; d < 3; ++d) {
      slot[1 + d] = force[d];
      slot[4 + d] = moment[d];
    }
  }
  return overflow;
}

} // namespace fibre
