#include "deck_models.h"

#include "comm.h"
#include "error.h"
#include "fix.h"
#include "host.h"
#include "lammps.h"
#include "modify.h"

namespace fibre_lmp {

namespace {

// What is lost with a fix of this style beside fix fibre_contact ("" where nothing is).
std::string uncarried(const std::string &style)
{
  if (style == "wall/gran" || style == "wall/gran/region")
    return "computes wall forces of its own, which fix fibre_contact adds as external forces: "
           "the walls act twice. Delete it and give its interaction to the fix's wall keyword "
           "('wall <its interaction words> <its wall style>', LAMMPS; 'wall type T ...' or "
           "'wall mesh ID', LIGGGHTS)";
  if (starts_with(style.c_str(), "mesh/surface/stress"))
    return "takes its stress and wear from fix wall/gran's contact forces, which the conversion "
           "deletes: its stress and wear stay 0 (the walls' loads are fix fibre_contact's "
           "f_ID[w][1..6])";
  if (starts_with(style.c_str(), "heat/gran"))
    return "conducts heat through the pair style's contacts, whose force computation fix "
           "fibre_contact switches off: no heat flows between grains";
  return "";
}

} // namespace

void warn_uncarried_fixes(LAMMPS_NS::LAMMPS *lmp, const std::string &fix_id)
{
  if (lmp->comm->me != 0) return;
  for (int f = 0; f < lmp->modify->nfix; ++f) {
    const LAMMPS_NS::Fix *other = lmp->modify->fix[f];
    const std::string lost = uncarried(other->style);
    if (!lost.empty())
      warn(lmp->error, FLERR,
           "Fix " + fix_id + " (fibre_contact): fix " + other->id + " (" + other->style + ") " +
               lost);
  }
}

} // namespace fibre_lmp
