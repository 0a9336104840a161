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

#include "fibre/model/material.hpp"
#include "pointers.h"

namespace fibre_lmp {

struct PairReading {
  fibre::MaterialTable table;     // empty when the style gave nothing usable
  std::vector<std::string> notes; // what the fix does not use, one line each
  // the deck's models that the fix does not carry (cohesion, wear, ...): a WARNING each
  std::vector<std::string> warnings;
  std::string failure;   // why nothing could be read ("" if it could)
  bool required = false; // the host defines its material here (LIGGGHTS): a failure is an error
  // The style's stiffnesses describe a material, so that 'compliance material' is the default:
  // pair granular and LIGGGHTS's material properties, not the gran/* styles, whose kn = 1 is
  // the common neighbour-list-only setting.
  bool material = false;
  // Whether walls take a type pair's cohesion (LIGGGHTS: no, fix wall/gran names its own models)
  bool wall_cohesion = true;
};

PairReading read_pair_coefficients(LAMMPS_NS::LAMMPS *lmp);

// The coefficients of a wall from the interaction words of the fix wall/gran (or
// wall/gran/region) it replaces, as that fix turns them into its law ("granular hertz/material
// E e nu tangential ...", "hooke/history kn kt gamman gammat xmu dampflag"): LAMMPS 29 Sep
// 2021's constants. `failure` says why they cannot be read ("" if they can); notes as above.
struct WallReading {
  fibre::PairCoefficients coefficients;
  std::vector<std::string> notes, warnings;
  std::string failure;
};
WallReading read_wall_interaction(const std::vector<std::string> &words);

} // namespace fibre_lmp

#endif
