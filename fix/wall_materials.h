// The walls' own materials for fix fibre_contact: a wall typed 'type T' takes the pair (sphere
// type, T); one given fix wall/gran's interaction words gets a type of its own in the table,
// whose pair with every sphere type is that fix's law (fibre_lmp::read_wall_interaction).
#pragma once

#include <vector>

#include "fibre/geometry/detection.hpp"
#include "fibre/model/material.hpp"
#include "pointers.h"

namespace fibre_lmp {

// Per wall the partner type of its contacts (0: the sphere's own type). table: the deck's
// per-type coefficients, grown by one type per wall with interaction words; nullptr when the
// contacts do not take per-type coefficients (the walls' materials are then warned unused).
// Errors name the wall keyword.
std::vector<int> wall_material_types(LAMMPS_NS::LAMMPS *lmp,
                                     const std::vector<fibre::WallSpec> &walls,
                                     fibre::MaterialTable *table);

} // namespace fibre_lmp
