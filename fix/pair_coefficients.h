/* ----------------------------------------------------------------------
   The granular pair style's coefficients per type pair, for fix fibre_contact.

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
};

PairReading read_pair_coefficients(LAMMPS_NS::LAMMPS *lmp);

// One line per type pair i <= j for the log: "1 1: mu 0.4, mu_roll 0.1, twisting sds 0.07,
// restitution 0.3".
std::vector<std::string> describe_table(const fibre::MaterialTable &table);

} // namespace fibre_lmp

#endif
