// Synthetic contact systems for tests, benchmarks and reports: the thesis's 3x3 grid and
// polydisperse piles made by ballistic deposition. Real scenes come from the LAMMPS decks
// in examples/ through `fix fibre_contact export`.
#pragma once

#include <cstdint>

#include "fibre/system.hpp"

namespace fibre {

struct SceneParams {
  int rows = 6;
  SpookParams spook{};
  double compliance = 1e-8;          // eps on every row
  double contact_tolerance = 0.05;   // pairs with gap < tolerance * mean radius are contacts
  double max_overlap = 0.01;         // random overlap added to gaps, times the mean radius
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

}  // namespace fibre
