// The contacts' share of the virial (doc/design.md section 2): what `compute pressure` and
// `compute stress/atom` need from a solver that applies its contact forces as impulses.
#pragma once

#include <array>
#include <vector>

#include "fibre/core/system.hpp"

namespace fibre {

using Virial = std::array<double, 6>; // xx, yy, zz, xy, xz, yz (LAMMPS's order)

// The virial of contact forces F = lambda / h: for a pair, r_ab (x) F_a with r_ab = x_a - x_b
// (LAMMPS's pair convention, also for the tangential forces); against a wall, the wall is a
// body at the contact's surface point q = x_a - (r_a + gap) n. `global` receives the sum over
// this process's contacts; `per_body` (6 per body, ghosts included, zeroed here) half of each
// pair's term on each body and a wall's whole term on its sphere, so that a reverse sum over
// processes gives every owned body its share.
void contact_virial(const ContactSystem &sys, const Vector &lambda, Virial &global,
                    Vector *per_body);

// The load on each wall from this process's contacts: force (x, y, z) and torque about the
// origin (x, y, z), the reaction to the spheres' contact forces lambda / h at the wall's
// surface point q = x_a - (r_a + gap) n, rolling and twisting torques included. wall_of[c] is
// contact c's wall index, or -1 for pairs and obstacles. `loads` is resized to num_walls and
// overwritten; the front end sums it over processes.
using WallLoad = std::array<double, 6>;
void wall_loads(const ContactSystem &sys, const Vector &lambda, const std::vector<int> &wall_of,
                int num_walls, std::vector<WallLoad> &loads);

} // namespace fibre
