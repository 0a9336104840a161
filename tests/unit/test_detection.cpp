// Contact detection without LAMMPS: the contact criterion, plane walls, region cutoffs and
// the one order of a step's contacts, against hand-computed cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <tuple>

#include "fibre/geometry/detection.hpp"

using namespace fibre;

namespace {

Body sphere(double r, const Vec3 &x, const Vec3 &v = Vec3::Zero(), const Vec3 &f = Vec3::Zero())
{
  Body b;
  b.mass = 2.0;
  b.radius = r;
  b.x = x;
  b.v = v;
  b.force = f;
  return b;
}

} // namespace

// Within 1% of the smaller radius a pair is a contact whatever its motion.
TEST(Detection, MarginMakesRestingNeighboursContacts)
{
  const Body a = sphere(0.5, Vec3(0, 0, 1)), b = sphere(0.25, Vec3(0, 0, 0));
  const Vec3 n = Vec3::UnitZ();
  EXPECT_TRUE(is_contact(a, &b, n, 0.0024, 1e-3, 2.0));  // below 0.01 * 0.25
  EXPECT_FALSE(is_contact(a, &b, n, 0.0026, 1e-3, 2.0)); // above, at rest
  EXPECT_TRUE(is_contact(a, &b, n, -0.1, 1e-3, 2.0));    // overlapping
}

// Beyond the margin a pair is a contact when it closes within (damping + 1) steps at its
// free-flight approach speed: v_rel + h (f_a / m_a - f_b / m_b) along -n.
TEST(Detection, ApproachWithinDampingPlusOneSteps)
{
  const double h = 0.01, d = 2.0, r = 0.5;
  const Vec3 n = Vec3::UnitZ(); // from b to a
  const Body b = sphere(r, Vec3::Zero());
  // approach 1 m/s: reach (d + 1) h * 1 = 0.03 beyond the margin 0.005
  const Body a = sphere(r, Vec3(0, 0, 1.1), Vec3(0, 0, -1.0));
  EXPECT_TRUE(is_contact(a, &b, n, 0.005 + 0.0299, h, d));
  EXPECT_FALSE(is_contact(a, &b, n, 0.005 + 0.0301, h, d));
  // separating: never, however close beyond the margin
  const Body away = sphere(r, Vec3(0, 0, 1.1), Vec3(0, 0, 1.0));
  EXPECT_FALSE(is_contact(away, &b, n, 0.006, h, d));
  // gravity over the step counts: at rest, f/m = -100 m/s^2 gives 1 m/s in one step
  const Body falling = sphere(r, Vec3(0, 0, 1.1), Vec3::Zero(), Vec3(0, 0, -200.0));
  EXPECT_TRUE(is_contact(falling, &b, n, 0.005 + 0.0299, h, d));
  // a wall (b == nullptr) counts only a's motion
  EXPECT_TRUE(is_contact(a, nullptr, n, 0.005 + 0.0299, h, d));
  // a moving wall or obstacle adds its own approach: a sphere at rest, the wall at 1 m/s
  // towards it, is found as the moving sphere is; moving away it is not
  const Body rest = sphere(r, Vec3(0, 0, 1.1));
  EXPECT_FALSE(is_contact(rest, nullptr, n, 0.005 + 0.0299, h, d));
  EXPECT_TRUE(is_contact(rest, nullptr, n, 0.005 + 0.0299, h, d, 0.0, 1.0));
  EXPECT_FALSE(is_contact(rest, nullptr, n, 0.005 + 0.0301, h, d, 0.0, 1.0));
  EXPECT_FALSE(is_contact(rest, nullptr, n, 0.006, h, d, 0.0, -1.0));
}

// pair_reach is the front ends' cheap test before a pair's gap: every pair that is_contact
// accepts lies within it, and for a head-on approach it is the exact bound.
TEST(Detection, PairReachBoundsEveryContact)
{
  const double h = 0.01, d = 2.0;
  // head-on at 1 m/s, radii 0.5 and 0.25: reach 0.75 + 0.0025 + 3 h * 1
  const Body b = sphere(0.25, Vec3::Zero());
  const Body a = sphere(0.5, Vec3(0, 0, 1), Vec3(0, 0, -1.0));
  EXPECT_DOUBLE_EQ(free_speed(a, h), 1.0);
  EXPECT_DOUBLE_EQ(pair_reach(0.5, 0.25, free_speed(a, h), free_speed(b, h), h, d),
                   0.75 + 0.0025 + 0.03);
  EXPECT_TRUE(is_contact(a, &b, Vec3::UnitZ(), 0.0025 + 0.0299, h, d));
  EXPECT_FALSE(is_contact(a, &b, Vec3::UnitZ(), 0.0025 + 0.0301, h, d));
  // free flight under a force counts: at rest, f/m = -100 m/s^2 gives 1 m/s over the step
  EXPECT_DOUBLE_EQ(free_speed(sphere(0.5, Vec3::Zero(), Vec3::Zero(), Vec3(0, 0, -200.0)), h), 1.0);
  // random pairs, motions, forces and kicks: no accepted pair lies beyond the reach
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0), r(0.1, 0.6);
  int accepted = 0;
  for (int k = 0; k < 20000; ++k) {
    const Body p = sphere(r(gen), Vec3::Zero(), 3.0 * Vec3(u(gen), u(gen), u(gen)),
                          300.0 * Vec3(u(gen), u(gen), u(gen)));
    const Vec3 dir = Vec3(u(gen), u(gen), u(gen)).normalized();
    const double kick = u(gen) > 0.5 ? 2.0 * (u(gen) + 1.0) : 0.0;
    const double rq = r(gen), dist = p.radius + rq + 0.3 * (u(gen) + 1.0) - 0.05;
    const Body q = sphere(rq, dist * dir, 3.0 * Vec3(u(gen), u(gen), u(gen)));
    Vec3 n;
    double gap = 0.0;
    sphere_sphere_gap(q, p, n, gap);
    if (!is_contact(q, &p, n, gap, h, d, kick)) continue;
    ++accepted;
    EXPECT_LT(dist, pair_reach(q.radius, p.radius, free_speed(q, h), free_speed(p, h), h, d, kick));
  }
  EXPECT_GT(accepted, 1000); // the test saw many contacts
}

TEST(Detection, PlaneWallsBothSidesWithinReach)
{
  WallSpec w;
  w.kind = WallKind::yplane;
  w.has_lo = w.has_hi = true;
  w.lo = -1.0;
  w.hi = 2.0;
  PlaneHit hits[2];
  // centre 0.3 above lo, radius 0.25: gap 0.05 < reach 0.1; hi is 1.7 away
  ASSERT_EQ(plane_hits(w, sphere(0.25, Vec3(5, -0.7, 3)), 0.1, hits), 1);
  EXPECT_EQ(hits[0].sub, 0);
  EXPECT_EQ(hits[0].normal, Vec3::UnitY());
  EXPECT_DOUBLE_EQ(hits[0].distance, 0.3);
  // a big sphere touches both
  ASSERT_EQ(plane_hits(w, sphere(1.6, Vec3(0, 0.5, 0)), 0.1, hits), 2);
  EXPECT_EQ(hits[1].sub, 1);
  EXPECT_EQ(hits[1].normal, -Vec3::UnitY());
  EXPECT_DOUBLE_EQ(hits[1].distance, 1.5);
  // a one-sided wall ignores the other side
  w.has_hi = false;
  EXPECT_EQ(plane_hits(w, sphere(1.6, Vec3(0, 0.5, 0)), 0.1, hits), 1);
  EXPECT_EQ(plane_hits(w, sphere(0.25, Vec3(0, 0.5, 0)), 0.1, hits), 0);
}

TEST(Detection, RegionCutoffCappedByTheSkin)
{
  const double h = 0.01, d = 2.0;
  EXPECT_DOUBLE_EQ(region_cutoff(sphere(0.5, Vec3::Zero()), h, d, 0.1), 0.505);
  // 2 m/s over 3 steps: 0.06 < skin
  EXPECT_DOUBLE_EQ(region_cutoff(sphere(0.5, Vec3::Zero(), Vec3(0, 2, 0)), h, d, 0.1),
                   0.505 + 0.06);
  EXPECT_DOUBLE_EQ(region_cutoff(sphere(0.5, Vec3::Zero(), Vec3(0, 20, 0)), h, d, 0.1),
                   0.505 + 0.1);
  // a moving wall's surface speed near the sphere widens it alike
  EXPECT_DOUBLE_EQ(region_cutoff(sphere(0.5, Vec3::Zero()), h, d, 0.1, 2.0), 0.505 + 0.06);
}

TEST(Detection, WallKeysAreNegativeAndDistinct)
{
  EXPECT_DOUBLE_EQ(wall_key(0, 0), -1.0);
  EXPECT_DOUBLE_EQ(wall_key(0, 1), -2.0);
  EXPECT_DOUBLE_EQ(wall_key(2, 5), -(2.0 * kWallKeyStride + 6.0));
  EXPECT_NE(wall_key(1, 0), wall_key(0, kWallKeyStride - 1));
}

// The order depends on the contacts only, not on the order they were found in.
TEST(Detection, SortIsIndependentOfInputOrder)
{
  std::vector<DetectedContact> found;
  for (long long a : {3, 1, 2})
    for (double partner : {-2.0, 7.0, 5.0}) {
      DetectedContact c;
      c.tag_a = a;
      c.partner = partner;
      c.contact.gap = 0.1 * a + partner;
      found.push_back(c);
    }
  std::vector<DetectedContact> shuffled = found;
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(7));
  const FoundContacts sorted = sort_contacts(std::move(found));
  const FoundContacts other = sort_contacts(std::move(shuffled));
  ASSERT_EQ(sorted.tags.size(), 9u);
  ASSERT_EQ(sorted.contacts.size(), 9u);
  for (std::size_t k = 0; k < sorted.tags.size(); ++k) {
    const ContactTag &t = sorted.tags[k];
    EXPECT_EQ(t.tag_a, other.tags[k].tag_a);
    EXPECT_EQ(t.partner, other.tags[k].partner);
    EXPECT_EQ(t.gap, sorted.contacts[k].gap); // each tag beside its contact
    EXPECT_EQ(t.gap, 0.1 * t.tag_a + t.partner);
    if (k > 0) {
      EXPECT_LE(sorted.tags[k - 1].tag_a, t.tag_a);
      if (sorted.tags[k - 1].tag_a == t.tag_a) {
        EXPECT_LT(sorted.tags[k - 1].partner, t.partner);
      }
    }
  }
  EXPECT_EQ(sorted.tags.front().tag_a, 1);
  EXPECT_EQ(sorted.tags.front().partner, -2.0);
}

// Dense tags (bucketed by tag) and sparse ones (a full sort) give the order of the keys.
TEST(Detection, SortOrdersByTagPartnerAndGap)
{
  for (const long long spread : {1LL, 1000000000LL}) {
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> tag(1, 60), partner(-3, 80);
    std::uniform_real_distribution<double> gap(-0.01, 0.01);
    std::vector<DetectedContact> found(700);
    for (DetectedContact &c : found) {
      c.tag_a = spread * tag(rng);
      c.partner = partner(rng);
      c.contact.gap = gap(rng);
    }
    std::vector<DetectedContact> expected = found;
    std::sort(expected.begin(), expected.end(), [](const auto &p, const auto &q) {
      return std::make_tuple(p.tag_a, p.partner, p.contact.gap) <
             std::make_tuple(q.tag_a, q.partner, q.contact.gap);
    });
    const FoundContacts sorted = sort_contacts(std::move(found));
    ASSERT_EQ(sorted.tags.size(), expected.size());
    for (std::size_t k = 0; k < sorted.tags.size(); ++k) {
      EXPECT_EQ(sorted.tags[k].tag_a, expected[k].tag_a)
          << "spread " << spread << ", contact " << k;
      EXPECT_EQ(sorted.tags[k].partner, expected[k].partner);
      EXPECT_EQ(sorted.contacts[k].gap, expected[k].contact.gap);
    }
  }
}

// Pairs given as compact records (DetectedPair) sort among the walls' full contacts as the
// same pairs given as full contacts (sphere_sphere_contact), each built bit for bit alike.
TEST(Detection, PairRecordsSortAsTheirContacts)
{
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Body> bodies(40);
  for (Body &b : bodies) {
    b.radius = 0.5 + 0.1 * u(rng);
    b.x = 2.0 * Vec3(u(rng), u(rng), u(rng));
  }
  std::vector<DetectedContact> walls, full;
  std::vector<DetectedPair> pairs;
  for (int a = 0; a < 40; ++a) {
    DetectedContact w;
    w.tag_a = a + 1;
    w.partner = wall_key(0, a % 2);
    w.contact = sphere_wall_contact(bodies, a, Vec3::UnitZ(), 0.4 + 0.01 * a);
    walls.push_back(w);
    for (int b = a + 1; b < 40; b += 7) {
      DetectedPair p;
      p.a = a;
      p.b = b;
      sphere_sphere_gap(bodies[a], bodies[b], p.normal, p.gap);
      p.tag_a = a + 1;
      p.partner = b + 1;
      p.key = b + 1;
      p.store = a;
      pairs.push_back(p);
      DetectedContact c;
      static_cast<ContactTag &>(c) = p;
      c.contact = sphere_sphere_contact(bodies, a, b, p.normal, p.gap);
      full.push_back(c);
    }
  }
  full.insert(full.end(), walls.begin(), walls.end());
  std::shuffle(pairs.begin(), pairs.end(), std::mt19937(3));
  const FoundContacts expected = sort_contacts(std::move(full));
  const FoundContacts sorted = sort_contacts(std::move(walls), std::move(pairs), &bodies);
  ASSERT_EQ(sorted.contacts.size(), expected.contacts.size());
  ASSERT_GT(sorted.contacts.size(), 100u);
  for (std::size_t k = 0; k < sorted.contacts.size(); ++k) {
    const Contact &c = sorted.contacts[k], &e = expected.contacts[k];
    EXPECT_EQ(sorted.tags[k].tag_a, expected.tags[k].tag_a) << "contact " << k;
    EXPECT_EQ(sorted.tags[k].partner, expected.tags[k].partner);
    EXPECT_EQ(sorted.tags[k].key, expected.tags[k].key);
    EXPECT_EQ(sorted.tags[k].store, expected.tags[k].store);
    EXPECT_EQ(sorted.tags[k].gap, expected.tags[k].gap);
    EXPECT_EQ(c.a, e.a);
    EXPECT_EQ(c.b, e.b);
    EXPECT_EQ(c.gap, e.gap);
    EXPECT_EQ(c.normal, e.normal);
    EXPECT_EQ(c.t1, e.t1);
    EXPECT_EQ(c.t2, e.t2);
    EXPECT_EQ(c.point, e.point);
  }
  std::vector<DetectedPair> alone(1);
  EXPECT_THROW(sort_contacts({}, std::move(alone)), std::invalid_argument);
}

TEST(Detection, WallNames)
{
  WallKind k;
  EXPECT_TRUE(parse("region", k));
  EXPECT_EQ(k, WallKind::region);
  EXPECT_TRUE(parse("mesh", k));
  EXPECT_EQ(k, WallKind::mesh);
  EXPECT_FALSE(parse("cylinder", k));
  EXPECT_EQ(choices<WallKind>(), "xplane|yplane|zplane|region|mesh|xcylinder|ycylinder|zcylinder");
  EXPECT_LT(mesh_key(0, 0), wall_key(1023, kWallKeyStride - 1));
  EXPECT_NE(mesh_key(0, 1), mesh_key(1, 0));
  EXPECT_EQ(mesh_key(2, 123456789), -(kMeshKeyBase + 123456789.0 * kWallKeyStride + 3));
}

// A cylinder wall holds the spheres inside it: the normal points to the axis, the distance is
// from the surface to the centre; beyond reach, or on the axis, no contact.
TEST(Detection, CylinderWallHoldsTheSpheresInside)
{
  WallSpec w;
  w.kind = WallKind::ycylinder; // axis along y through z = 1, x = 2 (the other coordinates z x)
  w.radius = 3.0;
  w.centre[0] = 1.0;
  w.centre[1] = 2.0;
  EXPECT_EQ(w.axis(), 1);
  EXPECT_TRUE(w.is_cylinder());
  EXPECT_FALSE(w.is_plane());
  Body b;
  b.radius = 0.5;
  b.x = Vec3(2.0, 7.0, 1.0 + 2.4); // 2.4 from the axis along z: 0.6 from the surface
  PlaneHit hit;
  ASSERT_EQ(cylinder_hit(w, b, 0.2, hit), 1);
  EXPECT_NEAR(hit.distance, 0.6, 1e-12);
  EXPECT_NEAR((hit.normal - Vec3(0, 0, -1)).norm(), 0.0, 1e-12);
  EXPECT_EQ(cylinder_hit(w, b, 0.05, hit), 0); // the gap 0.1 beyond reach
  b.x = Vec3(2.0 + 2.7 / std::sqrt(2.0), 0.0, 1.0 + 2.7 / std::sqrt(2.0)); // overlapping 0.2
  ASSERT_EQ(cylinder_hit(w, b, 0.0, hit), 1);
  EXPECT_NEAR(hit.distance - b.radius, -0.2, 1e-12);
  EXPECT_NEAR((hit.normal + Vec3(1, 0, 1) / std::sqrt(2.0)).norm(), 0.0, 1e-12);
  b.x = Vec3(2.0, 0.0, 1.0); // on the axis: no direction, far from the wall
  EXPECT_EQ(cylinder_hit(w, b, 1.0, hit), 0);
}
