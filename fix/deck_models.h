// The deck's fixes whose models fix fibre_contact does not carry: each gets a WARNING that
// names it and what to change (a model never drops silently).
#pragma once

#include <string>

#include "pointers.h"

namespace fibre_lmp {

// Call from the fix's init() on every process; rank 0 writes the warnings.
void warn_uncarried_fixes(LAMMPS_NS::LAMMPS *lmp, const std::string &fix_id);

} // namespace fibre_lmp
