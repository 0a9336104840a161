/* ----------------------------------------------------------------------
   The granular pair style's coefficients per type pair, for fix fibre_contact. Each front end
   has its own reader: fix/pair_coefficients.cpp (LAMMPS) and liggghts/property_materials.cpp
   (LIGGGHTS fix property/global).

   LAMMPS exposes them through no API here (doc/design.md section 5): the pair style's
   write_restart() record, written into memory, is read instead. Known layouts: pair_style
   granular of LAMMPS 29 Sep 2021 (Debian's package), and the gran/hooke, gran/hooke/history
   and gran/hertz/history styles (one global friction coefficient).
------------------------------------------------------------------------- */

#ifndef FIBRE_PAIR_COEFFICIENTS_H
#define FIBRE_PAIR_COEFFICIENTS_H

#include <string>
#include <vector>

#include "fibre/material.hpp"
#include "pointers.h"

namespace fibre_lmp {

struct PairReading {
  fibre::MaterialTable table;     // empty when the style gave nothing usable
  std::vector<std::string> notes; // what the fix does not use, one line each
  std::string failure;            // why nothing could be read ("" if it could)
  bool required = false; // the host defines its material here (LIGGGHTS): a failure is an error
  // The style's stiffnesses describe a material, so that 'compliance material' is the default:
  // pair granular and LIGGGHTS's material properties, not the gran/* styles, whose kn = 1 is
  // the common neighbour-list-only setting.
  bool material = false;
};

PairReading read_pair_coefficients(LAMMPS_NS::LAMMPS *lmp);

} // namespace fibre_lmp

#endif
