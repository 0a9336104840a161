// Warm-start history per atom without LAMMPS: storage bookkeeping (grow, copy, clear,
// pack/unpack as migration and restart use them) and the impulse <-> force conversion, which
// must give back the same impulses in the same frame and the right ones in a rotated frame.
#include <gtest/gtest.h>

#include <cmath>

#include "fibre/model/contact_history.hpp"

using namespace fibre;

namespace {

DetectedContact contact_on(int store, double key, const Vec3 &normal)
{
  DetectedContact fc;
  fc.store = store;
  fc.key = key;
  fc.contact.normal = normal.normalized();
  tangent_frame(fc.contact.normal, fc.contact.t1, fc.contact.t2);
  return fc;
}

std::vector<ContactTag> tags_of(const std::vector<DetectedContact> &found)
{
  return std::vector<ContactTag>(found.begin(), found.end());
}

std::vector<Contact> contacts_of(const std::vector<DetectedContact> &found)
{
  std::vector<Contact> contacts;
  for (const DetectedContact &fc : found) contacts.push_back(fc.contact);
  return contacts;
}

} // namespace

TEST(ContactHistory, StoreThenWarmStartGivesTheImpulsesBack)
{
  const double h = 1e-3;
  ContactHistory hist;
  hist.grow(4);
  std::vector<DetectedContact> found = {contact_on(0, 7.0, Vec3(0, 0, 1)),
                                        contact_on(0, -3.0, Vec3(1, 1, 0)),
                                        contact_on(2, 9.0, Vec3(0.3, -0.2, 1))};
  Vector lambda(18);
  for (int k = 0; k < 18; ++k) lambda[k] = 0.1 * (k + 1);
  EXPECT_EQ(hist.store(tags_of(found), contacts_of(found), lambda, 6, h), 0);
  const Vector warm = hist.warm_start(tags_of(found), contacts_of(found), 6, h);
  EXPECT_LT((warm - lambda).norm(), 1e-14 * lambda.norm());
  // released contacts (lambda_n <= 0) are not remembered
  lambda[6] = 0.0;
  hist.store(tags_of(found), contacts_of(found), lambda, 6, h);
  const Vector warm2 = hist.warm_start(tags_of(found), contacts_of(found), 6, h);
  EXPECT_EQ(warm2.segment(6, 6).norm(), 0.0);
  EXPECT_LT((warm2.head(6) - lambda.head(6)).norm(), 1e-14);
}

// The force is stored in the world frame: after the contact turns by 90 degrees the warm
// start is the same force seen in the new frame.
TEST(ContactHistory, WarmStartFollowsTheWorldFrame)
{
  const double h = 0.01;
  ContactHistory hist;
  hist.grow(1);
  std::vector<DetectedContact> found = {contact_on(0, 5.0, Vec3::UnitZ())};
  Vector lambda = Vector::Zero(3);
  lambda[0] = 2.0; // along +z
  hist.store(tags_of(found), contacts_of(found), lambda, 3, h);
  found[0] = contact_on(0, 5.0, Vec3::UnitX());
  const Vector warm = hist.warm_start(tags_of(found), contacts_of(found), 3, h);
  EXPECT_NEAR(warm[0], 0.0, 1e-15); // the normal row sees no force now
  const Contact &k = found[0].contact;
  EXPECT_NEAR(warm[1], 2.0 * k.t1.z(), 1e-15);
  EXPECT_NEAR(warm[2], 2.0 * k.t2.z(), 1e-15);
  EXPECT_NEAR(warm.norm(), 2.0, 1e-14);
}

TEST(ContactHistory, PackUnpackCopyAndClear)
{
  ContactHistory hist;
  hist.grow(3);
  std::vector<DetectedContact> found = {contact_on(1, 4.0, Vec3::UnitZ()),
                                        contact_on(1, 6.0, Vec3::UnitY())};
  Vector lambda = Vector::Ones(6);
  hist.store(tags_of(found), contacts_of(found), lambda, 3, 1.0);
  EXPECT_EQ(hist.packed_size(1), 1 + 2 * ContactHistory::kSlotSize);
  double buf[ContactHistory::kMaxPacked];
  EXPECT_EQ(hist.pack(1, buf), hist.packed_size(1));
  EXPECT_EQ(buf[0], 2.0);
  // migration: unpack into another atom, then the warm start reads it there
  EXPECT_EQ(hist.unpack(2, buf), hist.packed_size(1));
  for (DetectedContact &fc : found) fc.store = 2;
  EXPECT_LT((hist.warm_start(tags_of(found), contacts_of(found), 3, 1.0) - lambda).norm(), 1e-15);
  // a restart record cut short keeps only whole slots
  EXPECT_EQ(hist.unpack(0, buf, ContactHistory::kSlotSize + 3), 1 + ContactHistory::kSlotSize);
  EXPECT_EQ(hist.packed_size(0), 1 + ContactHistory::kSlotSize);
  // a corrupt count is clamped
  buf[0] = 1e9;
  EXPECT_EQ(hist.unpack(0, buf, 2 * ContactHistory::kSlotSize), 1 + 2 * ContactHistory::kSlotSize);
  buf[0] = -4;
  EXPECT_EQ(hist.unpack(0, buf), 1);
  hist.copy(2, 0);
  EXPECT_EQ(hist.packed_size(0), hist.packed_size(2));
  hist.clear(0);
  EXPECT_EQ(hist.packed_size(0), 1);
  // growing keeps what is stored
  hist.grow(100);
  EXPECT_EQ(hist.packed_size(2), 1 + 2 * ContactHistory::kSlotSize);
  EXPECT_EQ(hist.packed_size(99), 1);
}

TEST(ContactHistory, OverflowIsCountedNotStored)
{
  ContactHistory hist;
  hist.grow(1);
  std::vector<DetectedContact> found;
  for (int k = 0; k < ContactHistory::kMaxSlots + 3; ++k)
    found.push_back(contact_on(0, 10.0 + k, Vec3::UnitZ()));
  const Vector lambda = Vector::Ones(3 * Eigen::Index(found.size()));
  EXPECT_EQ(hist.store(tags_of(found), contacts_of(found), lambda, 3, 1.0), 3);
  EXPECT_EQ(hist.packed_size(0), ContactHistory::kMaxPacked);
  const Vector warm = hist.warm_start(tags_of(found), contacts_of(found), 3, 1.0);
  EXPECT_EQ(warm.tail(9).norm(), 0.0); // the last three start cold
  EXPECT_LT((warm.head(3 * ContactHistory::kMaxSlots) - lambda.head(3 * ContactHistory::kMaxSlots))
                .norm(),
            1e-14);
}

// The layout grows with the most contacts one atom stores: an atom with 11 contacts, stored
// after others with few, and one unpacked with 12, keep every impulse of every atom.
TEST(ContactHistory, RoomGrowsWithTheMostContactsOnOneAtom)
{
  const double h = 1e-3;
  ContactHistory hist;
  hist.grow(3);
  const double before = hist.memory_bytes();
  std::vector<DetectedContact> found = {contact_on(0, 1.0, Vec3(0, 0, 1)),
                                        contact_on(2, 2.0, Vec3(1, 0, 1))};
  for (int k = 0; k < 11; ++k) found.push_back(contact_on(1, 10.0 + k, Vec3(k, 1, 2)));
  const int n = static_cast<int>(found.size());
  Vector lambda(6 * n);
  for (int k = 0; k < 6 * n; ++k) lambda[k] = 0.01 * (k + 1);
  EXPECT_EQ(hist.store(tags_of(found), contacts_of(found), lambda, 6, h), 0);
  EXPECT_GT(hist.memory_bytes(), before);
  EXPECT_LT((hist.warm_start(tags_of(found), contacts_of(found), 6, h) - lambda).norm(),
            1e-14 * lambda.norm());
  // atom 1's twelve values per slot travel to a new atom 2 whose history had one contact
  std::vector<double> buf(ContactHistory::kMaxPacked);
  EXPECT_EQ(hist.pack(1, buf.data()), 1 + 11 * ContactHistory::kSlotSize);
  ContactHistory other;
  other.grow(3);
  EXPECT_EQ(other.unpack(2, buf.data()), 1 + 11 * ContactHistory::kSlotSize);
  std::vector<DetectedContact> moved(found.begin() + 2, found.end());
  for (DetectedContact &fc : moved) fc.store = 2;
  EXPECT_LT(
      (other.warm_start(tags_of(moved), contacts_of(moved), 6, h) - lambda.tail(6 * 11)).norm(),
      1e-14 * lambda.norm());
}

// The history holds the stored contacts, not room for the most contacts on every atom: one
// atom with 12 contacts among 100,000 atom places costs the per-atom index and its 12 slots.
// Migration's copy shares slots that the next store rebuilds.
TEST(ContactHistory, MemoryFollowsTheStoredContacts)
{
  const int places = 100000;
  ContactHistory hist;
  hist.grow(places);
  std::vector<DetectedContact> found;
  for (int k = 0; k < 12; ++k) found.push_back(contact_on(7, 10.0 + k, Vec3(k, 1, 2)));
  const Vector lambda = Vector::Ones(3 * 12);
  EXPECT_EQ(hist.store(tags_of(found), contacts_of(found), lambda, 3, 1.0), 0);
  const double index = places * (sizeof(int) + sizeof(std::size_t));
  EXPECT_LE(hist.memory_bytes(), index + 2 * 12 * ContactHistory::kSlotSize * sizeof(double));
  hist.copy(7, places - 1); // atom 7 moves to the last place
  hist.clear(7);
  for (DetectedContact &fc : found) fc.store = places - 1;
  EXPECT_LT((hist.warm_start(tags_of(found), contacts_of(found), 3, 1.0) - lambda).norm(), 1e-15);
  EXPECT_EQ(hist.store(tags_of(found), contacts_of(found), 2.0 * lambda, 3, 1.0), 0);
  EXPECT_LT((hist.warm_start(tags_of(found), contacts_of(found), 3, 1.0) - 2.0 * lambda).norm(),
            1e-14);
  EXPECT_EQ(hist.packed_size(7), 1);
}
