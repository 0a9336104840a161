#include "wall_materials.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "host.h"
#include "lammps.h"
#include "pair_coefficients.h"

namespace fibre_lmp {

namespace {

std::string wall_words(const fibre::WallSpec &w)
{
  std::string text = "wall";
  if (w.type > 0) text += " type " + std::to_string(w.type);
  for (const std::string &word : w.model) text += " " + word;
  return text + " " + fibre::to_string(w.kind);
}

} // namespace

std::vector<int> wall_material_types(LAMMPS_NS::LAMMPS *lmp,
                                     const std::vector<fibre::WallSpec> &walls,
                                     fibre::MaterialTable *table)
{
  LAMMPS_NS::Error *error = lmp->error;
  const bool me0 = lmp->comm->me == 0;
  std::vector<int> types(walls.size(), 0);
  for (std::size_t k = 0; k < walls.size(); ++k) {
    const fibre::WallSpec &w = walls[k];
    if (w.type == 0 && w.model.empty()) continue;
    const std::string key = "Fix fibre_contact '" + wall_words(w) + " ...': ";
    if (w.type > 0 && !w.model.empty())
      fail(error, FLERR, key + "give the wall either 'type <T>' or an interaction, not both");
    if (w.kind == fibre::WallKind::mesh)
      fail(error, FLERR, key + "a mesh wall takes its own type (fix mesh/surface ... type T)");
    if (w.type > lmp->atom->ntypes)
      fail(error, FLERR,
           key + "type " + std::to_string(w.type) + " is not an atom type (1 to " +
               std::to_string(lmp->atom->ntypes) + ")");
    if (!table) {
      if (me0)
        warn(error, FLERR,
             key + "the contacts do not take per-type coefficients ('coefficients fix', or a "
                   "pair style without them): the wall's material is not used");
      continue;
    }
    types[k] = w.type;
    if (w.model.empty()) continue;
    const WallReading reading = read_wall_interaction(w.model);
    if (!reading.failure.empty()) fail(error, FLERR, key + reading.failure);
    types[k] = table->add_type(reading.coefficients);
    if (!me0) continue;
    logmesg(lmp, "fix fibre_contact: " + wall_words(w) + ": the wall's material is type " +
                     std::to_string(types[k]) + " of the table: " + table->describe().back() +
                     "\n");
    for (const std::string &text : reading.warnings) warn(error, FLERR, key + text);
    for (const std::string &note : reading.notes)
      logmesg(lmp, "fix fibre_contact: " + wall_words(w) + ": " + note + "\n");
  }
  return types;
}

} // namespace fibre_lmp
