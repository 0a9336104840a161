// Synthetic contact systems for tests, benchmarks and reports: the thesis's 3x3 grid and
// polydisperse piles made by ballistic deposition. Test support (library fibre_scenes), not
// part of fibre_solver. Real scenes come from the LAMMPS decks in examples/ through
// `fix fibre_contact export`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fibre/core/system.hpp"

namespace fibre {

struct SceneParams {
  int rows = 6;
  SpookParams spook{};
  double compliance = 1e-8;        // eps on every row
  double contact_tolerance = 0.05; // pairs with gap < tolerance * mean radius are contacts
  double max_overlap = 0.01;       // random overlap added to gaps, times the mean radius
  std::uint64_t seed = 1;
};

// The thesis's 3x3 grid: 9 unit spheres in a square lattice in the x-z plane, touching
// neighbours: 12 contacts, no walls.
ContactSystem grid_scene(const SceneParams &p);

// n polydisperse spheres (radius 0.5..1.0) dropped one by one onto a floor at z = 0 in a
// square box sized for the count; contacts for every pair and floor gap within tolerance.
// Velocities are random (unit scale) and gravity (0, 0, -9.81 m) is the external force.
ContactSystem pile_scene(int n, const SceneParams &p);

// A lone contact between two spheres.
ContactSystem pair_scene(const SceneParams &p);

// A plane wall: points x with normal . x >= offset are inside (the normal points inward).
struct Plane {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
};

// Contacts of a given sphere packing: every pair and every plane with gap below
// p.contact_tolerance * mean radius (0 = overlapping only). Gaps are geometric (no
// random overlap is added). Velocities and forces are kept as given.
ContactSystem packing_scene(std::vector<Body> bodies, const std::vector<Plane> &walls,
                            const SceneParams &p);

// Spheres from a LAMMPS text dump with columns `id radius mass x y z vx vy vz`
// (and optionally omegax omegay omegaz). Throws std::runtime_error on a malformed file.
std::vector<Body> read_sphere_dump(const std::string &path, double gravity = 9.81);

// The 400-sphere Hertz pile poured by native LAMMPS (tests/data/in.pile400) in its 8 x 8 box:
// floor and four side walls.
ContactSystem lammps_pile_scene(const std::string &dump_path, const SceneParams &p);

} // namespace fibre
