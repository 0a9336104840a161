#include "fibre/detection.hpp"

#include <cmath>

#include <algorithm>

namespace fibre {

double free_approach(const Body &a, const Body *b, const Vec3 &n, double h)
{
  Vec3 rel = a.v + (h / a.mass) * a.force;
  if (b) rel -= b->v + (h / b->mass) * b->force;
  return -n.dot(rel);
}

bool is_contact(const Body &a, const Body *b, const Vec3 &n, double gap, double h, double damping,
                double kick, double wall_approach)
{
  const double rmin = b ? std::min(a.radius, b->radius) : a.radius;
  const double margin = kContactMargin * rmin + (damping + 1.0) * h * kick;
  if (gap < margin) return true;
  const double approach = free_approach(a, b, n, h) + wall_approach;
  return approach > 0.0 && gap < margin + (damping + 1.0) * h * approach;
}

double free_speed(const Body &b, double h)
{
  return (b.v + (h / b.mass) * b.force).norm();
}

double region_cutoff(const Body &b, double h, double damping, double skin, double wall_speed)
{
  return b.radius * (1.0 + kContactMargin) +
         std::min(skin, (damping + 1.0) * h * (free_speed(b, h) + wall_speed));
}

double WallSpec::offset(double t) const
{
  if (motion != WallMotion::wiggle || motion_axis != axis()) return 0.0;
  return amplitude * std::sin(2.0 * M_PI * t / period);
}

Vec3 WallSpec::velocity(double t) const
{
  Vec3 v = Vec3::Zero();
  if (motion == WallMotion::wiggle)
    v[motion_axis] = amplitude * 2.0 * M_PI / period * std::cos(2.0 * M_PI * t / period);
  else if (motion == WallMotion::shear)
    v[motion_axis] = shear_speed;
  return v;
}

int plane_hits(const WallSpec &wall, const Body &b, double reach, PlaneHit hits[2], double t)
{
  const int dim = wall.axis();
  const double shift = wall.offset(t);
  int n = 0;
  if (wall.has_lo) {
    const double distance = b.x[dim] - (wall.lo + shift);
    if (distance - b.radius < reach) {
      hits[n] = PlaneHit{Vec3::Zero(), distance, 0};
      hits[n++].normal[dim] = 1.0;
    }
  }
  if (wall.has_hi) {
    const double distance = wall.hi + shift - b.x[dim];
    if (distance - b.radius < reach) {
      hits[n] = PlaneHit{Vec3::Zero(), distance, 1};
      hits[n++].normal[dim] = -1.0;
    }
  }
  return n;
}

void sort_contacts(std::vector<DetectedContact> &found)
{
  // Sort compact keys, then move each contact once: a Contact is a few hundred bytes, so
  // swapping them in the sort was 4% of a step, and reading the keys out of them in every
  // comparison missed the cache.
  struct Key {
    long long tag_a;
    double partner, gap;
    std::size_t index;
  };
  std::vector<Key> keys(found.size());
  for (std::size_t i = 0; i < found.size(); ++i)
    keys[i] = {found[i].tag_a, found[i].partner, found[i].contact.gap, i};
  std::sort(keys.begin(), keys.end(), [](const Key &p, const Key &q) {
    if (p.tag_a != q.tag_a) return p.tag_a < q.tag_a;
    if (p.partner != q.partner) return p.partner < q.partner;
    return p.gap < q.gap;
  });
  std::vector<DetectedContact> sorted;
  sorted.reserve(found.size());
  for (const Key &k : keys) sorted.push_back(std::move(found[k.index]));
  found.swap(sorted);
}

} // namespace fibre
