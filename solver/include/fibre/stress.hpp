// The contacts' share of the virial (doc/design.md section 2): what `compute pressure` and
// `compute stress/atom` need from a solver that applies its contact forces as impulses.
#pragma once

#include <array>

#include "fibre/system.hpp"

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

} // namespace fibre
