#include "fibre/model/contact_history.hpp"

#include <algorithm>
#include <cmath>

namespace fibre {

void ContactHistory::grow(int nmax)
{
  if (nmax <= capacity()) return;
  count_.resize(nmax, 0);
  first_.resize(nmax, 0);
}

void ContactHistory::copy(int from, int to)
{
  count_[to] = count_[from];
  first_[to] = first_[from];
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
  count_[i] = n;
  first_[i] = pool_.size() / kSlotSize;
  pool_.resize(pool_.size() + std::size_t(n) * kSlotSize, 0.0);
  double *dst = pool_.data() + first_[i] * kSlotSize;
  for (int k = 0; k < n; ++k, dst += kSlotSize)
    std::copy(buf + 1 + k * slot_size, buf + 1 + (k + 1) * slot_size, dst);
  return 1 + n * slot_size;
}

double ContactHistory::memory_bytes() const
{
  return double(count_.capacity()) * sizeof(int) + double(first_.capacity()) * sizeof(std::size_t) +
         double(pool_.capacity()) * sizeof(double);
}

const double *ContactHistory::find(int atom, double key) const
{
  const double *slot = slots(atom);
  for (int k = 0; k < count_[atom]; ++k, slot += kSlotSize)
    if (slot[0] == key) return slot;
  return nullptr;
}

Vector ContactHistory::warm_start(const std::vector<ContactTag> &tags,
                                  const std::vector<Contact> &contacts, int rows, double h) const
{
  const int nc = static_cast<int>(tags.size());
  Vector warm = Vector::Zero(Eigen::Index(rows) * nc);
  for (int c = 0; c < nc; ++c) {
    const double *slot = find(tags[c].store, tags[c].key);
    if (!slot) continue;
    const Vec3 force(slot[1], slot[2], slot[3]), moment(slot[4], slot[5], slot[6]);
    const Contact &k = contacts[c];
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

void ContactHistory::load_springs(const std::vector<ContactTag> &tags,
                                  std::vector<Contact> &contacts) const
{
  for (std::size_t c = 0; c < tags.size(); ++c) {
    Contact &k = contacts[c];
    if (k.is_joint()) continue; // its error is its own (joint_contact)
    k.spring.fill(0.0);
    k.penetration = 0.0;
    k.split = false;
    const double *slot = find(tags[c].store, tags[c].key);
    k.touched = slot != nullptr;
    if (!slot) continue;
    const Vec3 tangential = into_plane(Vec3(slot[7], slot[8], slot[9]), k.normal);
    const Vec3 rolling = into_plane(Vec3(slot[10], slot[11], slot[12]), k.normal);
    k.spring[1] = tangential.dot(k.t1);
    k.spring[2] = tangential.dot(k.t2);
    k.spring[3] = slot[13];
    k.spring[4] = rolling.dot(k.t1);
    k.spring[5] = rolling.dot(k.t2);
    k.penetration = std::abs(slot[14]);
    k.split = slot[14] < 0;
  }
}

namespace {

// Whether contact c leaves anything to remember: it pressed or pulled, or a penetration is left
// to open no faster than it must (a cohesive contact that pulls has lambda_n < 0).
bool to_store(const Vector &lambda, int rows, int c,
              const std::vector<std::array<double, kMaxRows>> *springs)
{
  const double l0 = lambda[Eigen::Index(rows) * c];
  return l0 > 0.0 || l0 < 0.0 || (springs && (*springs)[c][0] > 0.0);
}

} // namespace

// slot <- contact k's force and torque on body a, its springs in the world frame, the
// penetration left.
void ContactHistory::write_slot(double *slot, double key, const Contact &k, const double *l,
                                int rows, double h, const std::array<double, kMaxRows> *xi)
{
  const Vec3 force = (l[0] * k.normal + l[1] * k.t1 + l[2] * k.t2) / h;
  Vec3 moment = Vec3::Zero();
  if (rows == 6) moment = (l[3] * k.normal + l[4] * k.t1 + l[5] * k.t2) / h;
  slot[0] = key;
  Vec3 tangential = Vec3::Zero(), rolling = Vec3::Zero();
  double twisting = 0.0;
  if (xi) {
    tangential = (*xi)[1] * k.t1 + (*xi)[2] * k.t2;
    rolling = (*xi)[4] * k.t1 + (*xi)[5] * k.t2;
    twisting = (*xi)[3];
  }
  for (int d = 0; d < 3; ++d) {
    slot[1 + d] = force[d];
    slot[4 + d] = moment[d];
    slot[7 + d] = tangential[d];
    slot[10 + d] = rolling[d];
  }
  slot[13] = twisting;
  slot[14] = xi ? (k.split ? -(*xi)[0] : (*xi)[0]) : 0.0; // a split penetration negative
}

long ContactHistory::store(const std::vector<ContactTag> &tags,
                           const std::vector<Contact> &contacts, const Vector &lambda, int rows,
                           double h, const std::vector<std::array<double, kMaxRows>> *springs)
{
  // count each atom's slots (the first kMaxSlots in the contacts' order), then lay them out
  std::fill(count_.begin(), count_.end(), 0);
  const int nc = static_cast<int>(tags.size());
  std::vector<char> kept(nc, 0);
  long overflow = 0;
  for (int c = 0; c < nc; ++c) {
    if (!to_store(lambda, rows, c, springs)) continue;
    const int s = tags[c].store;
    if (count_[s] >= kMaxSlots) {
      ++overflow;
      continue;
    }
    ++count_[s];
    kept[c] = 1;
  }
  std::size_t total = 0;
  for (int i = 0; i < capacity(); ++i) {
    first_[i] = total;
    total += count_[i];
  }
  std::vector<double> pool(total * kSlotSize);
  std::vector<int> filled(count_.size(), 0);
  for (int c = 0; c < nc; ++c) {
    if (!kept[c]) continue;
    const int s = tags[c].store;
    double *slot = pool.data() + (first_[s] + filled[s]++) * kSlotSize;
    write_slot(slot, tags[c].key, contacts[c], lambda.data() + Eigen::Index(rows) * c, rows, h,
               springs ? &(*springs)[c] : nullptr);
  }
  pool_ = std::move(pool); // the old pool freed: no second one held through the next solve
  return overflow;
}

} // namespace fibre
