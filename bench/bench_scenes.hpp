// Scenes for the benchmarks (header only, bench/ only).
//
// heap_scene(n): a dense, statically loaded heap of about n spheres with the material deck's
// parameters (examples/material: density 1, h = 4.43e-3, damping 2 steps, compliance 3e-6 on
// the translational rows and 2.4e-5 on the rotational ones, as exported by the fix). The spheres
// sit on a jittered face-centred cubic lattice (spacing s = 1) cut to a cone on the floor z = 0,
// radii uniform in [0.46, 0.5] s, so that about half of the 12 lattice neighbours touch
// (gap < 0.04 s): coordination about 6, i.e. about 3 contacts per body as in a pile at rest
// (15,000 contacts for 5,000 bodies). Unlike pile_scene (ballistic deposition, ~1 contact per
// body, quadratic to build), it is built in O(n) and so reaches 1e6 contacts. Velocities are
// small random ones; gravity is the external force.
#pragma once

#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <vector>

#include "fibre/algebra/spook.hpp"
#include "fibre/scenes.hpp"

namespace fibre::bench {

inline SceneParams material_params()
{
  SceneParams p;
  p.rows = 6;
  p.spook.h = 4.4343048699784296e-3;
  p.spook.damping = 2.0;
  p.compliance = 2.9484024521980215e-06;
  return p;
}

// FCC sites (spacing s = 1) inside the cone of height H and base radius 2 H.
inline std::vector<Vec3> heap_sites(double H)
{
  const double a = std::sqrt(2.0), R = 2.0 * H;
  const int cells = static_cast<int>(std::ceil(R / a)) + 1;
  const int zcells = static_cast<int>(std::ceil(H / a)) + 1;
  const double basis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  std::vector<Vec3> sites;
  for (int k = 0; k <= zcells; ++k)
    for (int j = -cells; j <= cells; ++j)
      for (int i = -cells; i <= cells; ++i)
        for (const auto &b : basis) {
          const double x = (i + b[0]) * a, y = (j + b[1]) * a, z = 0.5 + (k + b[2]) * a;
          if (z <= H * (1.0 - std::sqrt(x * x + y * y) / R)) sites.emplace_back(x, y, z);
        }
  return sites;
}

inline ContactSystem heap_scene(int n, std::uint64_t seed = 1)
{
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  // Cone holding about n FCC sites (4 per cell of side a = sqrt(2) s): pi (2H)^2 H / 3 = n a^3 / 4;
  // then two corrections of H for the lattice's discreteness.
  const double s = 1.0, a = std::sqrt(2.0) * s;
  double H = std::cbrt(3.0 * n * a * a * a / (4.0 * M_PI * 4.0));
  std::vector<Vec3> sites = heap_sites(H);
  for (int it = 0; it < 2 && !sites.empty(); ++it) {
    H *= std::cbrt(double(n) / double(sites.size()));
    sites = heap_sites(H);
  }
  std::vector<Body> bodies;
  for (const Vec3 &site : sites) {
    const double x = site.x(), y = site.y(), z = site.z();
    Body body;
    body.radius = s * (0.46 + 0.04 * uni(rng));
    body.mass = body.radius * body.radius * body.radius * 4.0 * M_PI / 3.0;
    const double jit = 0.005 * s;
    body.x = Vec3(x + jit * (2 * uni(rng) - 1), y + jit * (2 * uni(rng) - 1),
                  std::max(body.radius, z + jit * (2 * uni(rng) - 1)));
    body.v = Vec3(0.01 * (2 * uni(rng) - 1), 0.01 * (2 * uni(rng) - 1), 0.01 * (2 * uni(rng) - 1));
    body.force = Vec3(0, 0, -9.81 * body.mass);
    bodies.push_back(body);
  }
  SceneParams p = material_params();
  p.contact_tolerance = 0.04 / 0.48; // tolerance * mean radius = 0.04 s
  p.seed = seed;
  ContactSystem sys = packing_scene(std::move(bodies), {Plane{Vec3::UnitZ(), 0.0}}, p);
  // Rotational rows 8x softer, as in the material deck's export.
  std::vector<Contact> contacts = sys.contacts();
  for (Contact &c : contacts)
    for (int r = 3; r < kMaxRows; ++r) c.compliance[r] = 8.185 * p.compliance;
  ContactSystem out(sys.bodies(), std::move(contacts), p.rows, p.spook);
  out.set_rhs(spook_rhs(out));
  return out;
}

// Bodies for about `contacts` contacts in heap_scene.
inline int heap_bodies_for(int contacts)
{
  return std::max(8, contacts / 3);
}

// heap_scene for about `contacts` contacts, built once per count and kept for the program's
// life (the benchmarks of one size share it).
inline const ContactSystem &cached_heap_scene(int contacts)
{
  static std::map<int, std::unique_ptr<ContactSystem>> cache;
  auto &slot = cache[contacts];
  if (!slot) slot = std::make_unique<ContactSystem>(heap_scene(heap_bodies_for(contacts)));
  return *slot;
}

} // namespace fibre::bench
