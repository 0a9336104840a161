/* ----------------------------------------------------------------------
   fix fibre_contact: what it checks and says about a deck (the pair style and its
   coefficients, fixes that would integrate twice, neighbour updates, non-finite input, deep
   overlaps and the step it could take). The step itself is in fix_fibre_contact.cpp.
------------------------------------------------------------------------- */

#include "fix_fibre_contact.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "atom.h"
#include "comm.h"
#include "compute.h"
#include "error.h"
#include "fibre/core/text.hpp"
#include "force.h"
#include "group.h"
#include "host.h"
#include "modify.h"
#include "neighbor.h"
#include "pair.h"
#include "pair_coefficients.h"
#include "update.h"

using namespace LAMMPS_NS;
using fibre_lmp::fail;
using fibre_lmp::fail_one;
using fibre_lmp::logmesg;
using fibre_lmp::warn;

void FixFibreContact::check_pair_style(bool at_init)
{
  if (!force->pair)
    fail(error, FLERR,
         "Fix fibre_contact requires a granular pair style for its "
         "neighbor list, e.g. 'pair_style gran/hooke 1.0 NULL 0.0 NULL "
         "0.0 0' and 'pair_coeff * *'");
  std::string style;
  Pair *gran = fibre_lmp::granular_pair(lmp, style);
  if (!gran)
    fail(error, FLERR,
         "Fix fibre_contact requires a granular pair style (gran/hooke, "
         "gran/hooke/history, gran/hertz/history or granular, alone or as the one granular "
         "sub-style of pair_style hybrid or hybrid/overlay) for its neighbor list, not pair "
         "style '" +
             style + "'");
  if (at_init && gran->compute_flag)
    fail(error, FLERR,
         "Fix fibre_contact computes every contact force itself, but the "
         "pair style's force computation is on: define the pair style "
         "before fix fibre_contact and do not use 'pair_modify compute "
         "yes'");
}

// The friction and restitution coefficients per type pair from the pair style (coefficients
// pair): logged with what the fix does not use; without usable ones, the keywords' values.
// Untyped, the compliance is the material's where the pair style is one.
void FixFibreContact::read_coefficients()
{
  fibre::ContactModel &model = settings_.model;
  model.materials = fibre::MaterialTable();
  if (!model.typed.compliance) model.compliance.material = false;
  if (model.coefficients != fibre::CoefficientSource::pair) return;
  const fibre_lmp::PairReading reading = fibre_lmp::read_pair_coefficients(lmp);
  if (!reading.failure.empty() && reading.required)
    fail(error, FLERR,
         "Fix fibre_contact reads the material from the deck: " + reading.failure +
             " (or give 'coefficients fix' to take the fix's mu, mu_roll, mu_twist and "
             "restitution)");
  if (!reading.failure.empty()) {
    if (comm->me == 0)
      warn(error, FLERR,
           "Fix fibre_contact: cannot read the pair style's coefficients (" + reading.failure +
               "); every contact takes the fix's mu, mu_roll, mu_twist and "
               "restitution");
    return;
  }
  model.materials = reading.table;
  model.wall_cohesion = reading.wall_cohesion;
  if (!model.typed.compliance) model.compliance.material = reading.material;
  if (comm->me != 0) return;
  for (const std::string &text : reading.warnings) warn(error, FLERR, "Fix fibre_contact: " + text);
  bool frictionless = !model.typed.mu;
  for (int i = 1; i <= reading.table.ntypes(); ++i)
    for (int j = i; j <= reading.table.ntypes(); ++j)
      frictionless = frictionless && reading.table.at(i, j).mu == 0.0;
  if (frictionless)
    warn(error, FLERR,
         "Fix fibre_contact: the pair style's friction coefficient "
         "is 0 for every type pair, so every contact is "
         "frictionless (give the fix's mu keyword, or "
         "'coefficients fix', to set it)");
  std::string text = "fix fibre_contact: coefficients from pair style " +
                     std::string(force->pair_style) +
                     " (types i j; walls take i i, or their own material";
  const fibre::TypedCoefficients &t = model.typed;
  if (t.mu || t.mu_roll || t.mu_twist || t.restitution)
    text += std::string("; overridden by the fix's") + (t.mu ? " mu" : "") +
            (t.mu_roll ? " mu_roll" : "") + (t.mu_twist ? " mu_twist" : "") +
            (t.restitution ? " restitution" : "");
  text += "):\n";
  for (const std::string &line : reading.table.describe()) text += "  " + line + "\n";
  for (const std::string &note : reading.notes) text += "  note: " + note + "\n";
  logmesg(lmp, text);
}

// Computes that read the pair style's own forces see none: its force computation is off.
// compute stress/atom and compute pressure are right (this fix tallies its virial); these are
// not.
void FixFibreContact::warn_pair_computes()
{
  if (comm->me != 0) return;
  for (int i = 0; i < modify->ncompute; ++i) {
    const std::string style = modify->compute[i]->style;
    if (style == "pair/local" || style == "contact/atom" || style == "pair")
      warn(error, FLERR,
           "Fix fibre_contact: compute " + std::string(modify->compute[i]->id) + " (" + style +
               ") reads the pair style, whose forces are switched off: it sees "
               "no contact forces (fix fibre_contact's local array f_" +
               id + " has them)");
  }
}

// Below 2 steps SPOOK's damping lets a contact stiffer than the step rings (doc page,
// "Regularization"): a settled pile keeps moving and spheres are thrown off it.
void FixFibreContact::warn_short_damping()
{
  const double d = settings_.model.damping;
  if (comm->me == 0 && d < 2.0)
    warn(error, FLERR,
         "Fix fibre_contact: damping " + fibre::format_g(d) +
             " is below 2 steps: a contact stiffer than the time step can resolve rings "
             "instead of coming to rest (damping 2, the default, damps it critically)");
}

// Another fix that moves the same atoms would integrate them twice.
void FixFibreContact::warn_double_integration()
{
  for (int f = 0; f < modify->nfix; ++f) {
    Fix *other = modify->fix[f];
    if (other == this || !other->time_integrate) continue;
    int mine = 0;
    for (int i = 0; i < atom->nlocal; ++i)
      if ((atom->mask[i] & groupbit) && (atom->mask[i] & other->groupbit)) ++mine;
    int all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_SUM, world);
    if (all > 0 && comm->me == 0)
      warn(error, FLERR,
           std::string("Fix fibre_contact: fix ") + other->id + " (" + other->style +
               ") also time-integrates " + std::to_string(all) + " atoms of group " +
               group->names[igroup] + ": they are moved twice per step");
  }
}

// The contacts come from the pair style's neighbor list. At this fix's steps an atom moves
// much further per step than under soft contacts, and a list kept for `delay` steps (10 by
// default in Debian's LAMMPS) or built only every N steps misses pairs that close between its
// builds: two spheres closing at 0.2 diameters a step passed through each other
// (tests/e2e/test_fix_collision.py). So the list is checked every step.
void FixFibreContact::check_neighbor_updates()
{
  if (neighbor->every == 1 && neighbor->delay == 0 && neighbor->dist_check) return;
  if (comm->me == 0)
    warn(error, FLERR,
         "Fix fibre_contact: neigh_modify every " + std::to_string(neighbor->every) + " delay " +
             std::to_string(neighbor->delay) + " check " + (neighbor->dist_check ? "yes" : "no") +
             " can miss contacts between neighbor list builds (spheres then pass through each "
             "other); the fix sets every 1 delay 0 check yes");
  neighbor->every = 1;
  neighbor->delay = 0;
  neighbor->dist_check = 1;
}

void FixFibreContact::check_finite(const char *what, double **array, int nvalues) const
{
  const int *mask = atom->mask;
  // x * 0 is 0 for finite x and NaN otherwise: one branch-free pass (it ran nine times a
  // step, 5% of a flow's time), and the atom named only when the sum is not 0
  // (LAMMPS's per-atom arrays are contiguous: memory->create)
  // Four sums: one waited on each addition's latency (6% of a stream of free grains' step).
  const int n = atom->nlocal;
  const double *values = n > 0 ? array[0] : nullptr;
  const auto zero = [&](int i) {
    const double *v = values + 3 * std::size_t(i);
    return (mask[i] & groupbit) ? v[0] * 0.0 + v[1] * 0.0 + v[2] * 0.0 : 0.0;
  };
  double sum = 0.0;
  if (nvalues == 3) {
    double sums[4] = {0.0, 0.0, 0.0, 0.0};
    int i = 0;
    for (; i + 4 <= n; i += 4)
      for (int k = 0; k < 4; ++k) sums[k] += zero(i + k);
    for (; i < n; ++i) sums[0] += zero(i);
    sum = (sums[0] + sums[1]) + (sums[2] + sums[3]);
  } else {
    sum = 1.0; // the naming loop below
  }
  if (sum == 0.0) return;
  for (int i = 0; i < atom->nlocal; ++i) {
    if (!(mask[i] & groupbit)) continue;
    for (int d = 0; d < nvalues; ++d)
      if (!std::isfinite(array[i][d]))
        fail_one(error, FLERR,
                 std::string("Fix fibre_contact: non-finite ") + what + " of atom " +
                     std::to_string(static_cast<long long>(atom->tag[i])) + " at step " +
                     std::to_string(static_cast<long long>(update->ntimestep)));
  }
}

// Where the step is well below the longest that one substep allows (substep_collisions t_c):
// that step, and the factor in steps it would save. The fix's cost is per step, nearly
// independent of its length, so the factor is about its speed-up.
std::string FixFibreContact::step_advice(double t_c) const
{
  const fibre::ContactModel &model = settings_.model;
  const double longest = model.substep_collisions * t_c;
  if (model.substeps > 0 || settings_.contact_every != 1 || !(dtv_ < 0.5 * longest)) return "";
  const auto g = [](double x) { return fibre::format_g(x); };
  const int every = fibre::steps_per_solve(t_c, dtv_);
  const std::string solves =
      every > 1 ? ". This deck's contacts could be solved once every " + std::to_string(every) +
                      " steps (" + g(fibre::kEveryCollisions) +
                      " t_c), that many times fewer solves: give 'contact_every auto' (no other "
                      "edit). Or it"
                : ". This deck";
  return solves + " could take a step of up to " + g(longest) + ", " + g(longest / dtv_) +
         " times this one, which takes that many times fewer steps: give 'timestep " + g(longest) +
         "' (or a round step below it) and scale the deck's step counts (run, thermo, dump, "
         "fix print, insertion every) by the same factor; fix move and wall wiggle follow time, "
         "variables written in steps (step, elapsed) must be written in time, and LAMMPS's fix "
         "pour keeps the interval in steps it took from the step in force when it was defined";
}

// At the first step of a run: overlaps deeper than kDeepOverlap of the smaller diameter are
// removed at the recovery speed, over many steps; say so.
void FixFibreContact::warn_deep_overlaps(const std::vector<fibre::Body> &bodies,
                                         const std::vector<fibre::Contact> &contacts,
                                         double max_recovery)
{
  double deepest = 0.0;
  for (const fibre::Contact &c : contacts) {
    const double rmin =
        c.is_wall() ? bodies[c.a].radius : std::min(bodies[c.a].radius, bodies[c.b].radius);
    deepest = std::max(deepest, -c.gap / (2.0 * rmin));
  }
  MPI_Allreduce(MPI_IN_PLACE, &deepest, 1, MPI_DOUBLE, MPI_MAX, world);
  if (deepest > kDeepOverlap && comm->me == 0)
    warn(error, FLERR,
         "Fix fibre_contact: the run starts with overlaps of up to " +
             fibre::format_g(100.0 * deepest) +
             "% of a diameter; they are removed at recovery_speed " +
             (max_recovery > 0
                  ? fibre::format_g(max_recovery) +
                        " at most: by a displacement that adds no velocity where deeper than " +
                        fibre::format_g(fibre::kPenetrationStart) +
                        " steps of it, else by the contacts (no faster than the material's "
                        "spring)"
                  : "none (SPOOK removes any overlap within a few steps)"));
}

// A sphere that moves farther in a step than the neighbor skin may meet spheres that the
// list, built at most a step ago, does not hold: it may pass through them. Said once a run.
void FixFibreContact::warn_skin()
{
  const double skin = neighbor->skin, move = fastest_ * h_;
  if (skin_warned_ || !(move > skin) || !(fastest_ > 0)) return;
  skin_warned_ = true;
  if (comm->me != 0) return;
  const auto g = [](double v) { return fibre::format_g(v); };
  warn(error, FLERR,
       "Fix fibre_contact: a sphere moves " + g(move) + " in a step (speed " + g(fastest_) +
           "), more than the neighbor skin " + g(skin) +
           ": the neighbor list holds no pair farther apart than their radii and the skin, so "
           "such a sphere may pass through others within a step; raise the skin ('neighbor " +
           g(1.5 * move) + " bin') or lower the step (below " + g(skin / fastest_) + ")");
}
