#include "fibre/model/contact_history.hpp"

#include <algorithm>

namespace fibre {

void ContactHistory::grow(int nmax)
{
  if (nmax > capacity()) relayout(nmax, per_atom_);
}

// Room for atoms [0, nmax) with `per_atom` slots each, the stored slots kept.
void ContactHistory::relayout(int nmax, int per_atom)
{
  const int old = capacity();
  const std::size_t stride = std::size_t(per_atom) * kSlotSize;
  std::unique_ptr<double[]> room(new double[std::size_t(nmax) * stride]); // not filled
  for (int i = 0; i < std::min(old, nmax); ++i)
    std::copy(slots(i), slots(i) + count_[i] * kSlotSize, room.get() + std::size_t(i) * stride);
  slots_ = std::move(room);
  per_atom_ = per_atom;
  count_.resize(nmax, 0);
}

// Room for n slots on every atom (at most kMaxSlots): the layout grows with the most contacts
// one atom stores, so that a deck whose atoms store few keeps a small history.
void ContactHistory::reserve_slots(int n)
{
  if (n > per_atom_) relayout(capacity(), std::min(kMaxSlots, std::max(n, per_atom_ + 2)));
}

void ContactHistory::copy(int from, int to)
{
  count_[to] = count_[from];
  std::copy(slots(from), slots(from) + count_[from] * kSlotSize, slots(to));
}

int ContactHistory::pack(int i, double *buf) const
{
  buf[0] = count_[i];
  std::copy(slots(i), slots(i) + count_[i] * kSlotSize, buf + 1);
  return packed_size(i);
}

int ContactHistory::unpack(int i, const double *buf, int available, int slot_size)
{
  slot_size = std::clamp(slot_size, 1, kSlotSize);
  const int n = std::min(
      {kMaxSlots, std::max(0, static_cast<int>(buf[0])), std::max(0, available) / slot_size});
  reserve_slots(n);
  count_[i] = n;
  double *dst = slots(i);
  for (int k = 0; k < n; ++k, dst += kSlotSize) {
    std::copy(buf + 1 + k * slot_size, buf + 1 + (k + 1) * slot_size, dst);
    std::fill(dst + slot_size, dst + kSlotSize, 0.0);
  }
  return 1 + n * slot_size;
}

double ContactHistory::memory_bytes() const
{
  return double(count_.capacity()) * sizeof(int) +
         double(capacity()) * per_atom_ * kSlotSize * sizeof(double);
}

const double *ContactHistory::find(int atom, double key) const
{
  const double *slot = slots(atom);
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

namespace {

// v turned into the plane normal to n, its length kept.
Vec3 into_plane(const Vec3 &v, const Vec3 &n)
{
  const Vec3 p = v - v.dot(n) * n;
  const double lp = p.norm();
  return lp > 0 ? Vec3(v.norm() / lp * p) : Vec3::Zero();
}

} // namespace

void ContactHistory::load_springs(const std::vector<DetectedContact> &found,
                                  std::vector<Contact> &contacts) const
{
  for (std::size_t c = 0; c < found.size(); ++c) {
    Contact &k = contacts[c];
    k.spring.fill(0.0);
    k.penetration = 0.0;
    const double *slot = find(found[c].store, found[c].key);
    k.touched = slot != nullptr;
    if (!slot) continue;
    const Vec3 tangential = into_plane(Vec3(slot[7], slot[8], slot[9]), k.normal);
    const Vec3 rolling = into_plane(Vec3(slot[10], slot[11], slot[12]), k.normal);
    k.spring[1] = tangential.dot(k.t1);
    k.spring[2] = tangential.dot(k.t2);
    k.spring[3] = slot[13];
    k.spring[4] = rolling.dot(k.t1);
    k.spring[5] = rolling.dot(k.t2);
    k.penetration = slot[14];
  }
}

long ContactHistory::store(const std::vector<DetectedContact> &found, const Vector &lambda,
                           int rows, double h, int nlocal,
                           const std::vector<std::array<double, kMaxRows>> *springs)
{
  std::fill(count_.begin(), count_.begin() + nlocal, 0);
  long overflow = 0;
  for (int c = 0; c < static_cast<int>(found.size()); ++c) {
    const DetectedContact &fc = found[c];
    const Contact &k = fc.contact;
    const double *l = lambda.data() + Eigen::Index(rows) * c;
    // released: nothing to remember, but a penetration that opens faster than it must (a
    // cohesive contact that pulls has lambda_n < 0)
    const double penetration = springs ? (*springs)[c][0] : 0.0;
    if (!(l[0] > 0.0 || l[0] < 0.0) && !(penetration > 0.0)) continue;
    const Vec3 force = (l[0] * k.normal + l[1] * k.t1 + l[2] * k.t2) / h;
    Vec3 moment = Vec3::Zero();
    if (rows == 6) moment = (l[3] * k.normal + l[4] * k.t1 + l[5] * k.t2) / h;
    const int s = fc.store;
    if (count_[s] >= kMaxSlots) {
      ++overflow;
      continue;
    }
    reserve_slots(count_[s] + 1);
    double *slot = slots(s) + std::size_t(count_[s]++) * kSlotSize;
    slot[0] = fc.key;
    Vec3 tangential = Vec3::Zero(), rolling = Vec3::Zero();
    double twisting = 0.0;
    if (springs) {
      const std::array<double, kMaxRows> &xi = (*springs)[c];
      tangential = xi[1] * k.t1 + xi[2] * k.t2;
      rolling = xi[4] * k.t1 + xi[5] * k.t2;
      twisting = xi[3];
    }
    for (int d = 0; d < 3; ++d) {
      slot[1 + d] = force[d];
      slot[4 + d] = moment[d];
      slot[7 + d] = tangential[d];
      slot[10 + d] = rolling[d];
    }
    slot[13] = twisting;
    slot[14] = penetration;
  }
  return overflow;
}

} // namespace fibre
