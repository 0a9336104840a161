#include "fibre/geometry/detection.hpp"

#include <cmath>

#include <algorithm>
#include <stdexcept>

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

int cylinder_hit(const WallSpec &wall, const Body &b, double reach, PlaneHit &hit)
{
  const int a = wall.axis(), i = (a + 1) % 3, j = (a + 2) % 3;
  const double dx = b.x[i] - wall.centre[0], dy = b.x[j] - wall.centre[1];
  const double rho = std::sqrt(dx * dx + dy * dy);
  const double distance = wall.radius - rho;
  if (!(rho > 0.0) || !(distance - b.radius < reach)) return 0;
  hit = PlaneHit{Vec3::Zero(), distance, 0};
  hit.normal[i] = -dx / rho;
  hit.normal[j] = -dy / rho;
  return 1;
}

FoundContacts sort_contacts(std::vector<DetectedContact> &&found, std::vector<DetectedPair> &&pairs,
                            const std::vector<Body> *bodies)
{
  // Sort compact keys, then move each contact once: a Contact is a few hundred bytes, so
  // swapping them in the sort was 4% of a step, and reading the keys out of them in every
  // comparison missed the cache. Keys from n_found on are pairs.
  struct Key {
    long long tag_a;
    double partner, gap;
    std::size_t index;
  };
  const auto before = [](const Key &p, const Key &q) {
    if (p.tag_a != q.tag_a) return p.tag_a < q.tag_a;
    if (p.partner != q.partner) return p.partner < q.partner;
    return p.gap < q.gap;
  };
  if (!pairs.empty() && !bodies)
    throw std::invalid_argument("sort_contacts: pairs without their bodies");
  const std::size_t n_found = found.size(), n = n_found + pairs.size();
  std::vector<Key> keys(n);
  for (std::size_t i = 0; i < n_found; ++i)
    keys[i] = {found[i].tag_a, found[i].partner, found[i].contact.gap, i};
  for (std::size_t i = 0; i < pairs.size(); ++i)
    keys[n_found + i] = {pairs[i].tag_a, pairs[i].partner, pairs[i].gap, n_found + i};
  long long lo = n ? keys[0].tag_a : 0, hi = lo;
  for (const Key &k : keys) {
    lo = std::min(lo, k.tag_a);
    hi = std::max(hi, k.tag_a);
  }
  // Tags are dense on a process (its atoms and their ghosts): bucket the keys by tag_a, then
  // order each bucket (a sphere's few contacts) by insertion. A sparse range: a full sort.
  const unsigned long long range = static_cast<unsigned long long>(hi - lo) + 1;
  if (range <= 4 * n + 1024) {
    std::vector<std::size_t> first(range + 1, 0);
    for (const Key &k : keys) ++first[std::size_t(k.tag_a - lo) + 1];
    for (std::size_t t = 1; t <= range; ++t) first[t] += first[t - 1];
    std::vector<Key> bucketed(n);
    std::vector<std::size_t> fill(first.begin(), first.end() - 1);
    for (const Key &k : keys) bucketed[fill[std::size_t(k.tag_a - lo)]++] = k;
    for (std::size_t t = 0; t < range; ++t)
      for (std::size_t i = first[t] + 1; i < first[t + 1]; ++i)
        for (std::size_t j = i; j > first[t] && before(bucketed[j], bucketed[j - 1]); --j)
          std::swap(bucketed[j], bucketed[j - 1]);
    keys.swap(bucketed);
  } else {
    std::sort(keys.begin(), keys.end(), before);
  }
  FoundContacts sorted;
  sorted.contacts.reserve(n);
  sorted.tags.reserve(n);
  for (const Key &k : keys) {
    if (k.index < n_found) {
      const DetectedContact &fc = found[k.index];
      sorted.contacts.push_back(fc.contact);
      sorted.tags.push_back(fc);
      sorted.tags.back().gap = fc.contact.gap;
    } else {
      const DetectedPair &fp = pairs[k.index - n_found];
      sorted.contacts.push_back(sphere_sphere_contact(*bodies, fp.a, fp.b, fp.normal, fp.gap));
      sorted.tags.push_back(fp);
    }
  }
  return sorted;
}

} // namespace fibre
