/* ----------------------------------------------------------------------
   fix fibre_contact: nonsmooth, regularized (SPOOK) contact dynamics for granular spheres.

   Every step: x += dt v (initial_integrate); then, after all post_force fixes (gravity
   included), final_integrate detects the contacts, builds the contact system, solves it with
   the fibre solver library, applies v += dt f/m + M^-1 G^T lambda and reports. The parts:
   fibre::Settings (keywords and defaults), LammpsDetection (bodies and contacts),
   fibre::ContactHistory (warm starts per atom), FibreOutput (vector, local array, exports),
   LammpsExchange (halo communication). Documentation: doc/fix_fibre_contact.md
------------------------------------------------------------------------- */

#include "fix_fibre_contact.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <string>
#include <vector>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "atom.h"
#include "comm.h"
#include "compute.h"
#include "domain.h"
#include "error.h"
#include "fibre_detect.h"
#include "fibre/nonsmooth_reference.hpp"
#include "fibre/spook.hpp"
#include "fibre/stress.hpp"
#include "fibre/substeps.hpp"
#include "fibre/text.hpp"
#include "fibre_output.h"
#include "pair_coefficients.h"
#include "deck_models.h"
#include "wall_materials.h"
#include "force.h"
#include "group.h"
#include "host.h"
#include "lammps_exchange.h"
#include "modify.h"
#include "neighbor.h"
#include "pair.h"
#include "update.h"

using namespace LAMMPS_NS;
using namespace FixConst;
using fibre_lmp::fail;
using fibre_lmp::fail_one;
using fibre_lmp::FibreOutput;
using fibre_lmp::logmesg;
using fibre_lmp::starts_with;
using fibre_lmp::warn;

/* ---------------------------------------------------------------------- */

namespace {

// Each step allocates and frees its buffers (impulses, rows, residuals: hundreds of kB to a few
// MB). With glibc's defaults the freed memory went back to the system and every step faulted
// it in again: 40% of the material deck's time (bench/README.md section 4). Freed memory up to
// 256 MB stays with the process, and blocks below 64 MB come from the heap.
void keep_step_memory()
{
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
#endif
}

} // namespace

FixFibreContact::FixFibreContact(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg)
{
  keep_step_memory();
  if (!atom->radius_flag || !atom->rmass_flag || !atom->omega_flag || !atom->torque_flag)
    fail(error, FLERR,
         "Fix fibre_contact requires atom attributes radius, rmass, "
         "omega and torque (use atom_style sphere)");
  if (domain->dimension != 3)
    fail(error, FLERR, "Fix fibre_contact requires a 3d simulation (dimension 3)");

  time_integrate = 1;
  vector_flag = 1;
  size_vector = fibre_lmp::V_SIZE;
  global_freq = 1;
  // intensive but for the cumulative energies (thermo_modify norm divides those by atoms)
  extvector = -1;
  extlist = new int[fibre_lmp::V_SIZE]();
  extlist[fibre_lmp::V_WALL_WORK] = extlist[fibre_lmp::V_DISSIPATION] = 1;
  local_flag = 1;
  size_local_rows = 0;
  size_local_cols = FibreOutput::kLocalColumns;
  local_freq = 1;
  restart_global = 1;
  restart_peratom = 1;
  create_attribute = 1;
  comm_forward = fibre_lmp::LammpsExchange::kValuesPerAtom;
  comm_reverse = fibre_lmp::LammpsExchange::kValuesPerAtom;
#ifdef FIBRE_HOST_LIGGGHTS
  comm->maxexchange_fix =
      std::max(comm->maxexchange_fix, fibre::ContactHistory::kMaxPacked + kPendingValues);
#else
  maxexchange = fibre::ContactHistory::kMaxPacked + kPendingValues;
#endif
  // the contact forces' virial enters compute pressure and compute stress/atom
#ifdef FIBRE_HOST_LIGGGHTS
  virial_flag = 1;
#else
  virial_global_flag = virial_peratom_flag = 1;
  thermo_virial = 1;
#endif

  try {
    settings_ = fibre::parse_settings(std::vector<std::string>(arg + 3, arg + narg));
  } catch (fibre::SettingsError &e) {
    fail(error, FLERR, std::string("Illegal fix fibre_contact command: ") + e.what());
  }
  // the load on each wall: f_ID[w][1..6], force and torque about the origin
  if (!settings_.walls.empty()) {
    array_flag = 1;
    size_array_rows = static_cast<int>(settings_.walls.size());
    size_array_cols = 6;
    extarray = 1;
  }

  time_origin_ = simulated_time(); // moving planes start their motion here, as fix wall/gran's
  exchange_ = std::make_unique<fibre_lmp::LammpsExchange>(lmp, this, world);
  detection_ = std::make_unique<fibre_lmp::LammpsDetection>(lmp, groupbit, *exchange_);
  output_ = std::make_unique<FibreOutput>(lmp);

  // per-atom warm-start storage, migrating with the atoms and written to restart files
  grow_arrays(atom->nmax);
  atom->add_callback(fibre_lmp::kGrowCallback);
  atom->add_callback(fibre_lmp::kRestartCallback);

  // this fix computes every contact force: switch the pair style's forces off
  std::string style;
  if (Pair *gran = fibre_lmp::granular_pair(lmp, style)) {
    pair_ = gran;
    pair_owner_ = force->pair;
    pair_->compute_flag = 0;
    if (comm->me == 0)
      logmesg(lmp, "fix fibre_contact: switched off the force computation of pair style " + style +
                       " (its neighbor list is the contact graph)\n");
  }
}

/* ---------------------------------------------------------------------- */

double FixFibreContact::simulated_time() const
{
  return update->atime + (update->ntimestep - update->atimestep) * update->dt;
}

/* ---------------------------------------------------------------------- */

FixFibreContact::~FixFibreContact()
{
#ifndef FIBRE_HOST_LIGGGHTS
  if (copymode) return;
#endif
  delete[] extlist;
  atom->delete_callback(id, fibre_lmp::kGrowCallback);
  atom->delete_callback(id, fibre_lmp::kRestartCallback);
  if (pair_ && force && force->pair == pair_owner_) pair_->compute_flag = 1;
}

/* ---------------------------------------------------------------------- */

int FixFibreContact::setmask()
{
  return INITIAL_INTEGRATE | POST_FORCE | FINAL_INTEGRATE;
}

/* ----------------------------------------------------------------------
   the forces come in final_integrate; here only whether this step tallies the virial
------------------------------------------------------------------------- */

void FixFibreContact::post_force(int vflag)
{
  start_virial(vflag);
}

void FixFibreContact::start_virial(int vflag)
{
#ifdef FIBRE_HOST_LIGGGHTS
  if (vflag)
    v_setup(vflag);
  else
    evflag = vflag_global = vflag_atom = 0;
#else
  v_init(vflag);
#endif
}

/* ----------------------------------------------------------------------
   the walls' loads over all processes (collective)
------------------------------------------------------------------------- */

void FixFibreContact::tally_wall_loads(const fibre::ContactSystem &sys,
                                       const std::vector<fibre::DetectedContact> &found,
                                       const fibre::Vector &lambda)
{
  const int nwalls = static_cast<int>(settings_.walls.size());
  if (nwalls == 0) return;
  std::vector<int> wall_of(found.size());
  for (std::size_t c = 0; c < found.size(); ++c) wall_of[c] = found[c].wall;
  std::vector<fibre::WallLoad> loads;
  fibre::wall_loads(sys, lambda, wall_of, nwalls, loads);
  exchange_->sum(loads.empty() ? nullptr : loads[0].data(), 6 * nwalls);
  output_->set_wall_loads(loads);
}

/* ----------------------------------------------------------------------
   the contact forces' virial, global (this process's contacts) and per owned atom
------------------------------------------------------------------------- */

void FixFibreContact::tally_virial(const fibre::ContactSystem &sys, const fibre::Vector &lambda)
{
  fibre::Virial global;
  fibre::Vector per_body;
  fibre::contact_virial(sys, lambda, global, vflag_atom ? &per_body : nullptr);
  if (vflag_global)
    for (int i = 0; i < 6; ++i) virial[i] += global[i];
  if (!vflag_atom) return;
  exchange_->reverse_sum(per_body);
  const std::vector<int> &body_atom = exchange_->body_atom();
  for (int k = 0; k < exchange_->num_owned(); ++k)
    for (int i = 0; i < 6; ++i) vatom[body_atom[k]][i] += per_body[6 * k + i];
}

/* ---------------------------------------------------------------------- */

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

void FixFibreContact::init()
{
  if (starts_with(update->integrate_style, "respa"))
    fail(error, FLERR, "Fix fibre_contact does not support run_style respa");
#ifndef FIBRE_HOST_LIGGGHTS
  // The halo's reverse sum is LAMMPS's variable-size reverse comm (fix/lammps_compat.h), which
  // LAMMPS 29 Sep 2021 has for comm_style brick only.
  if (comm->style != 0)
    fail(error, FLERR,
         "Fix fibre_contact requires comm_style brick (this LAMMPS has no "
         "variable-size reverse communication for comm_style tiled)");
#endif
  check_pair_style(true);
  dtv_ = update->dt;
  warn_double_integration();
  fibre_lmp::warn_uncarried_fixes(lmp, id);
  warn_pair_computes();
  warn_short_damping();
  check_neighbor_updates();
  read_coefficients();
  // the walls' own materials: types of the table (the deck's walls are not edited)
  std::vector<fibre::WallSpec> walls = settings_.walls;
  fibre::ContactModel &model = settings_.model;
  const std::vector<int> types =
      fibre_lmp::wall_material_types(lmp, walls, model.per_type() ? &model.materials : nullptr);
  for (std::size_t k = 0; k < walls.size(); ++k) walls[k].type = types[k];
  detection_->init_walls(walls);
  if (comm->me == 0) logmesg(lmp, "fix fibre_contact: " + fibre::describe(settings_) + "\n");
}

/* ---------------------------------------------------------------------- */

void FixFibreContact::setup(int vflag)
{
  start_virial(vflag); // no contact forces before the run's first step: a zero virial
  first_step_ = true;
  detection_->start_moving_walls();
  std::string style;
  const Pair *gran = fibre_lmp::granular_pair(lmp, style);
  if (!gran || !gran->list)
    fail(error, FLERR, "Fix fibre_contact found no neighbor list of the pair style");
  dtv_ = update->dt;
}

void FixFibreContact::reset_dt()
{
  dtv_ = update->dt;
}

/* ----------------------------------------------------------------------
   positions: x += dt v, with v the velocities after the last contact solve, after the last
   step's substeps' displacement beyond it (follow_substeps)
------------------------------------------------------------------------- */

void FixFibreContact::initial_integrate(int /*vflag*/)
{
  double **x = atom->x, **v = atom->v;
  const int *mask = atom->mask;
  for (int i = 0; i < atom->nlocal; ++i)
    if (mask[i] & groupbit)
      for (int d = 0; d < 3; ++d) {
        x[i][d] += pending_[i][d];
        pending_[i][d] = 0.0;
        x[i][d] += dtv_ * v[i][d];
      }
}

// Between runs the positions take the substeps' displacement in: the next run's first step
// adds dt v only, and write_restart, write_data or a changed step may come between.
void FixFibreContact::post_run()
{
  double **x = atom->x;
  for (int i = 0; i < atom->nlocal; ++i)
    for (int d = 0; d < 3; ++d) {
      x[i][d] += pending_[i][d];
      pending_[i][d] = 0.0;
    }
}

/* ---------------------------------------------------------------------- */

void FixFibreContact::check_finite(const char *what, double **array, int nvalues) const
{
  const int *mask = atom->mask;
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

// The lightest body and the smallest radius of the group over all processes (automatic
// compliance and recovery speed); the last values stand while the group is empty.
void FixFibreContact::smallest_body(const std::vector<fibre::Body> &bodies)
{
  double m[2] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  for (int k = 0; k < exchange_->num_owned(); ++k) {
    m[0] = std::min(m[0], bodies[k].mass);
    m[1] = std::min(m[1], bodies[k].radius);
  }
  MPI_Allreduce(MPI_IN_PLACE, m, 2, MPI_DOUBLE, MPI_MIN, world);
  if (std::isfinite(m[0])) m_min_ = m[0];
  if (std::isfinite(m[1])) r_min_ = m[1];
}

// Where the step is well below the longest that one substep allows (substep_collisions t_c):
// that step, and the factor in steps it would save. The fix's cost is per step, nearly
// independent of its length, so the factor is about its speed-up.
std::string FixFibreContact::step_advice(double t_c) const
{
  const fibre::ContactModel &model = settings_.model;
  const double longest = model.substep_collisions * t_c;
  if (model.substeps > 0 || !(dtv_ < 0.5 * longest)) return "";
  const auto g = [](double x) { return fibre::format_g(x); };
  return ". This deck could take a step of up to " + g(longest) + " (one substep of " +
         g(model.substep_collisions) + " t_c), " + g(longest / dtv_) +
         " times this one, which takes that many times fewer steps: give 'timestep " + g(longest) +
         "' (or a round step below it) and scale the deck's step counts (run, thermo, dump, "
         "fix print, insertion every) by the same factor; fix move and wall wiggle follow time, "
         "variables written in steps (step, elapsed) must be written in time, and LAMMPS's fix "
         "pour keeps the interval in steps it took from the step in force when it was defined";
}

// The contact solve's substeps this step (fibre::substeps_for: automatic from the law's
// shortest collision time for two spheres of the group's smallest radius and mass at 1 velocity
// unit), alike on every process. Logged once per step size and count, with the step against
// that collision time, the number that says whether the step resolves the collisions of a flow
// (doc page, "Time step and stiff materials").
int FixFibreContact::step_substeps()
{
  const fibre::ContactModel &model = settings_.model;
  fibre::PairCollisionTime shortest{};
  if (model.compliance.material && m_min_ > 0 && r_min_ > 0)
    shortest = fibre::shortest_collision_time(model.materials, r_min_, m_min_, 1.0);
  const int n = fibre::substeps_for(model, dtv_, shortest.t_c);
  if ((dtv_ == step_logged_ && n == substeps_logged_) || !(shortest.t_c > 0)) return n;
  step_logged_ = dtv_;
  substeps_logged_ = n;
  if (comm->me != 0) return n;
  const auto g = [](double x) { return fibre::format_g(x); };
  const double per = dtv_ / n / shortest.t_c;
  std::string text =
      "fix fibre_contact: the step " + g(dtv_) + " is " + g(dtv_ / shortest.t_c) +
      " collision times of the pair style's law (t_c " + g(shortest.t_c) +
      ": two spheres of the smallest radius " + g(r_min_) + " and mass " + g(m_min_) +
      " meeting at 1 velocity unit, type pair " + std::to_string(shortest.i) + " " +
      std::to_string(shortest.j) + "); the contact solve takes " + std::to_string(n) +
      (n == 1 ? " substep" : " substeps") + " of " + g(per) + " t_c (substeps " +
      (model.substeps > 0 ? std::to_string(model.substeps)
                          : "auto, at most " + g(model.substep_collisions) + " t_c each") +
      ")";
  if (per > 0.34)
    text += ". Substeps longer than about a third of t_c let a collisional flow's contacts act "
            "as enduring ones, and its heaps and flows come out steeper and less mobile than the "
            "law's";
  text += step_advice(shortest.t_c);
  logmesg(lmp, text + " (doc page, \"Time step and stiff materials\")\n");
  return n;
}

// Approach speeds at or below this are plastic (ContactModel::bounce_speed); the automatic rule
// reads the external forces of every process.
double FixFibreContact::bounce_speed(const std::vector<fibre::Body> &bodies, double h) const
{
  const fibre::ContactModel &model = settings_.model;
  if (!model.may_bounce() || model.bounce_speed >= 0) return std::max(model.bounce_speed, 0.0);
  const double v = impact_speed(bodies, h);
  // Without external forces every approach would bounce, the new contacts of a sheared pack
  // too (it threw grains out of the shear cell): then the automatic overlap recovery speed of
  // the step (of a substep it would keep a head-on pair at 1 m/s from bouncing at 16 substeps).
  return v > 0 ? v : model.recovery_radii * r_min_ / dtv_;
}

// The speed above which a contact moves (step_moves) or bounces (bounce_speed): bounce_steps
// times the largest speed the external forces add to a body in h (0 without external forces),
// over every process.
double FixFibreContact::impact_speed(const std::vector<fibre::Body> &bodies, double h) const
{
  double v = fibre::external_speed_per_step(bodies, exchange_->num_owned(), h);
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_DOUBLE, MPI_MAX, world);
  return settings_.model.bounce_steps * v;
}

// Whether some contact of any process moves within the step (fibre::step_moves) at more than
// the impact speed of a substep hs.
bool FixFibreContact::step_moves(const std::vector<fibre::Body> &bodies,
                                 const std::vector<fibre::Contact> &contacts, double hs) const
{
  const double speed = impact_speed(bodies, hs);
  const fibre::SpookParams step{dtv_, settings_.model.damping};
  int moves = fibre::step_moves(bodies, contacts, step, speed) ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &moves, 1, MPI_INT, MPI_MAX, world);
  return moves != 0;
}

// With substeps the positions follow the substeps' velocities, x_{n+1} = x_n + hs sum_k v_k,
// so that the gaps the substeps moved are the gaps the next step detects. initial_integrate
// adds dtv v_final and the rest, kept until then (path: the sum of the n substeps'
// velocities, the final one's last), so that dumps and computes between steps see x_n. A
// body at rest or in free flight of one velocity moves as without.
void FixFibreContact::follow_substeps(const fibre::Vector &path, int n, double hs)
{
  double **v = atom->v;
  const std::vector<int> &body_atom = exchange_->body_atom();
  for (int k = 0; k < exchange_->num_owned(); ++k) {
    const int i = body_atom[k];
    for (int d = 0; d < 3; ++d) pending_[i][d] = hs * path[6 * k + d] - n * hs * v[i][d];
  }
}

// At the first step of a run: overlaps deeper than kDeepOverlap of the smaller diameter are
// removed at the recovery speed, over many steps; say so.
void FixFibreContact::warn_deep_overlaps(const std::vector<fibre::Body> &bodies,
                                         const std::vector<fibre::DetectedContact> &found,
                                         double max_recovery)
{
  double deepest = 0.0;
  for (const fibre::DetectedContact &fc : found) {
    const fibre::Contact &c = fc.contact;
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
             (max_recovery > 0 ? fibre::format_g(max_recovery) +
                                     " at most (and no faster than the material's spring)"
                               : "none (SPOOK removes any overlap within a few steps)"));
}

/* ----------------------------------------------------------------------
   the contact solve; a non-finite solution is replaced by free flight for this step (the
   state stays finite)
------------------------------------------------------------------------- */

fibre::StepResult FixFibreContact::solve(fibre::ContactSystem &sys, const fibre::Vector &warm,
                                         const fibre::StepOptions &opt, fibre::SweepCache *cache)
{
  fibre::StepResult res;
  try {
    res = fibre::solve_step(sys, *exchange_, opt, &warm, world, cache);
  } catch (std::exception &e) {
    fail_one(error, FLERR,
             std::string("Fix fibre_contact: contact solver failed at step ") +
                 std::to_string(static_cast<long long>(update->ntimestep)) + ": " + e.what());
  }
  const Eigen::Index owned = 6 * Eigen::Index(exchange_->num_owned());
  const bool finite =
      res.dv.size() >= owned && res.lambda.allFinite() && res.dv.head(owned).allFinite();
  int bad = finite ? 0 : 1;
  MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT, MPI_MAX, world);
  if (bad) {
    res.converged = false;
    res.reason = fibre::StopReason::non_finite;
    res.lambda = fibre::Vector::Zero(sys.contact_dofs());
    res.dv.resize(0);
    if (comm->me == 0)
      warn(error, FLERR,
           "Fix fibre_contact: the contact solve at step " +
               std::to_string(static_cast<long long>(update->ntimestep)) +
               " gave non-finite impulses; the step ignores the contacts");
  }
  return res;
}

/* ----------------------------------------------------------------------
   the step's check (keyword check): its substeps again from the same start, converged, and
   the run's summed impulses and velocity change against theirs
------------------------------------------------------------------------- */

void FixFibreContact::check_step(const fibre::Substeps &steps, int substeps,
                                 const fibre::SpookParams &params, std::vector<fibre::Body> bodies,
                                 std::vector<fibre::Contact> contacts, fibre::Vector warm)
{
  if (steps.result.dv.size() != steps.system.body_dofs()) return; // the run's solve failed
  const fibre::StepOptions converged = fibre::check_options(settings_.step);
  const fibre::Substeps ref = fibre::run_substeps(
      substeps, settings_.model, params, m_min_, *exchange_, exchange_->num_owned(),
      std::move(bodies), std::move(contacts), std::move(warm),
      [this, &converged](fibre::ContactSystem &s, const fibre::Vector &w, bool,
                         fibre::SweepCache &cache) { return solve(s, w, converged, &cache); });
  if (ref.result.dv.size() != ref.system.body_dofs() || ref.lambda.size() != steps.lambda.size())
    return; // solve() has warned
  const fibre::StepAccuracy errors =
      fibre::step_accuracy(steps.system, steps.lambda, ref.lambda, *exchange_);
  output_->report_check(errors, ref.totals.converged, ref.totals.sweeps);
}

/* ----------------------------------------------------------------------
   v += dt f / m + dv, omega += dt torque / I + domega for the owned group atoms
------------------------------------------------------------------------- */

void FixFibreContact::update_velocities(const fibre::Vector *dv)
{
  double **v = atom->v, **omega = atom->omega, **f = atom->f, **torque = atom->torque;
  const double *rmass = atom->rmass, *radius = atom->radius;
  const std::vector<int> &body_atom = exchange_->body_atom();
  for (int k = 0; k < exchange_->num_owned(); ++k) {
    const int i = body_atom[k];
    const double m = rmass[i];
    const double inertia = 0.4 * m * radius[i] * radius[i];
    for (int d = 0; d < 3; ++d) {
      v[i][d] += dtv_ * f[i][d] / m;
      omega[i][d] += dtv_ * torque[i][d] / inertia;
      if (dv) {
        v[i][d] += (*dv)[6 * k + d];
        omega[i][d] += (*dv)[6 * k + 3 + d];
      }
    }
  }
}

/* ----------------------------------------------------------------------
   the SPOOK step: detect, build, solve, apply, report
------------------------------------------------------------------------- */

void FixFibreContact::final_integrate()
{
  check_finite("position", atom->x, 3);
  check_finite("force", atom->f, 3);
  check_finite("torque", atom->torque, 3);
  check_finite("velocity", atom->v, 3);
  check_finite("angular velocity", atom->omega, 3);

  const fibre::ContactModel &model = settings_.model;
  std::vector<fibre::Body> bodies = detection_->bodies();
  detection_->set_wall_time(simulated_time() - time_origin_);
  smallest_body(bodies);
  // the contact solve runs in substeps of hs (fibre/substeps.hpp); detection keeps the step.
  // Detection reaches as far as impacts may kick the bodies where they bounce, and with
  // substeps also where they do not: a sphere that a plastic impact kicks in the step's first
  // substep moves on at its new speed in the others (without, a stiff pour blew up).
  int substeps = step_substeps();
  double hs = dtv_ / substeps;
  std::vector<fibre::DetectedContact> found =
      detection_->contacts(bodies, dtv_, model.damping, model.may_bounce() || substeps > 1);
  const auto params_of = [&](double h) {
    fibre::SpookParams p{h, model.damping, model.max_recovery(h, r_min_)};
    p.bounce_speed = bounce_speed(bodies, h);
    return p;
  };
  fibre::SpookParams params = params_of(hs);
  if (first_step_) warn_deep_overlaps(bodies, found, params.max_recovery);
  first_step_ = false;
  const bool any = output_->count_contacts(found) > 0;
  const bool do_export =
      settings_.export_every > 0 && update->ntimestep % settings_.export_every == 0;

  // build and solve (a step without contacts anywhere is free flight: an empty system)
  std::vector<fibre::Contact> contacts;
  contacts.reserve(found.size());
  for (const fibre::DetectedContact &fc : found) contacts.push_back(fc.contact);
  fibre::Substeps steps;
  if (any) {
    fibre::Vector warm = history_.warm_start(found, model.rows, hs);
    history_.load_springs(found, contacts);
    // a step in which nothing moves takes one solve (substep_when moving)
    if (substeps > 1 && model.substep_moving_only && !step_moves(bodies, contacts, hs)) {
      substeps = 1;
      hs = dtv_;
      params = params_of(hs);
      warm = history_.warm_start(found, model.rows, hs);
    }
    const bool check = settings_.check_every > 0 && update->ntimestep % settings_.check_every == 0;
    std::vector<fibre::Body> bodies_at_start;
    std::vector<fibre::Contact> contacts_at_start;
    fibre::Vector warm_at_start;
    if (check) {
      bodies_at_start = bodies;
      contacts_at_start = contacts;
      warm_at_start = warm;
    }
    fibre::StepOptions inner = settings_.step;
    inner.residual = false; // only the last substep's residual is reported
    steps = fibre::run_substeps(substeps, model, params, m_min_, *exchange_, exchange_->num_owned(),
                                std::move(bodies), std::move(contacts), std::move(warm),
                                [this, &inner](fibre::ContactSystem &s, const fibre::Vector &w,
                                               bool last, fibre::SweepCache &cache) {
                                  return solve(s, w, last ? settings_.step : inner, &cache);
                                });
    if (check)
      check_step(steps, substeps, params, std::move(bodies_at_start), std::move(contacts_at_start),
                 std::move(warm_at_start));
  } else {
    steps.system = fibre::ContactSystem(std::move(bodies), std::move(contacts), model.rows, params,
                                        exchange_->num_owned());
  }
  const fibre::ContactSystem &sys = steps.system;
  const fibre::StepResult &res = steps.result;

  // apply: the step's impulses and velocity change are the substeps' sums
  const bool solved = any && res.dv.size() == sys.body_dofs();
  const bool substepped = solved && steps.done > 1;
  update_velocities(solved ? &steps.dv : nullptr);
  // the loads and the virial of the step's mean force (sys's step is a substep's)
  const fibre::Vector lambda_mean =
      substepped ? fibre::Vector(steps.lambda / double(steps.done)) : res.lambda;
  tally_wall_loads(sys, found, lambda_mean);
  if (evflag) // this step's virial is wanted (post_force)
    tally_virial(sys, lambda_mean.size() ? lambda_mean : fibre::Vector::Zero(sys.contact_dofs()));
  // the energy the moving walls put in and the contacts take out
  if (solved) {
    if (substepped) follow_substeps(steps.path, steps.done, hs);
    output_->add_work(steps.work);
  }
  // the history: the last substep's impulses and (compliance material) its springs
  overflow_count_ += history_.store(found, res.lambda, model.rows, hs, atom->nlocal,
                                    steps.springs.empty() ? nullptr : &steps.springs);

  // report
  output_->fill_local(found, solved ? &steps.lambda : nullptr, model.rows, array_local,
                      size_local_rows);
  if (steps.done > 1) {
    fibre::StepResult all = steps.totals;
    all.iterations = res.iterations;
    all.rel_residual = res.rel_residual;
    all.fibres = res.fibres;
    output_->report_solve(all);
  } else {
    output_->report_solve(res);
  }
  output_->report_substeps(any ? steps.done : 0);
  if (do_export) // with substeps, the last one's system and warm start
    output_->export_step(settings_.export_prefix, sys, found, any ? &res.lambda : nullptr,
                         steps.warm, exchange_->local_owners());
  if (overflow_count_ > 0 && !overflow_warned_ && comm->me == 0) {
    warn(error, FLERR,
         "Fix fibre_contact: more than " + std::to_string(fibre::ContactHistory::kMaxSlots) +
             " contacts stored on one atom; the rest start cold next step");
    overflow_warned_ = true;
  }
  check_finite("velocity", atom->v, 3);
  check_finite("angular velocity", atom->omega, 3);
}

/* ---------------------------------------------------------------------- */

double FixFibreContact::compute_vector(int n)
{
  return output_->stat(n);
}

double FixFibreContact::compute_array(int wall, int column)
{
  return output_->wall_load(wall, column);
}

void FixFibreContact::write_restart(FILE *fp)
{
  output_->write_restart(fp);
}

void FixFibreContact::restart(char *buf)
{
  output_->read_restart(buf);
}

/* ----------------------------------------------------------------------
   per-atom warm-start storage: fibre::ContactHistory
------------------------------------------------------------------------- */

void FixFibreContact::grow_arrays(int nmax)
{
  history_.grow(nmax);
  pending_.resize(std::max<std::size_t>(pending_.size(), nmax), {0.0, 0.0, 0.0});
}

void FixFibreContact::copy_arrays(int i, int j, int /*delflag*/)
{
  history_.copy(i, j);
  pending_[j] = pending_[i];
}

void FixFibreContact::set_arrays(int i)
{
  history_.clear(i);
  pending_[i] = {0.0, 0.0, 0.0};
}

// [the history, the pending displacement]
int FixFibreContact::pack_exchange(int i, double *buf)
{
  const int m = history_.pack(i, buf);
  std::copy(pending_[i].begin(), pending_[i].end(), buf + m);
  return m + kPendingValues;
}

int FixFibreContact::unpack_exchange(int nlocal, double *buf)
{
  const int m = history_.unpack(nlocal, buf);
  std::copy(buf + m, buf + m + kPendingValues, pending_[nlocal].begin());
  return m + kPendingValues;
}

// [number of values including itself, as other fixes read it; the history; the pending
// displacement] (a restart written within a run, after a step with substeps)
int FixFibreContact::pack_restart(int i, double *buf)
{
  int m = 1 + history_.pack(i, buf + 1);
  std::copy(pending_[i].begin(), pending_[i].end(), buf + m);
  m += kPendingValues;
  buf[0] = m;
  return m;
}

void FixFibreContact::unpack_restart(int nlocal, int nth)
{
  const double *extra = atom->extra[nlocal];
  int m = 0;
  for (int k = 0; k < nth; ++k) m += static_cast<int>(extra[m]);
  const int count = static_cast<int>(extra[m]);
  const int n = static_cast<int>(extra[m + 1]);
  using fibre::ContactHistory;
  // older restart files: 14 values per slot (no penetration), before that no pending
  // displacement, and before the springs 7 values per slot
  int slot = ContactHistory::kSlotSize;
  bool pending = true;
  if (n > 0 && count - 2 - kPendingValues == n * ContactHistory::kSpringSlot) {
    slot = ContactHistory::kSpringSlot;
  } else if (count - 2 - kPendingValues != n * ContactHistory::kSlotSize) {
    pending = false;
    if (n > 0 && count - 2 == n * ContactHistory::kWarmStartSlot)
      slot = ContactHistory::kWarmStartSlot;
    else
      slot = ContactHistory::kSpringSlot;
  }
  const int values = count - 2 - (pending ? kPendingValues : 0);
  history_.unpack(nlocal, extra + m + 1, values, slot);
  pending_[nlocal] = {0.0, 0.0, 0.0};
  if (pending)
    std::copy(extra + m + count - kPendingValues, extra + m + count, pending_[nlocal].begin());
}

int FixFibreContact::size_restart(int i)
{
  return 1 + history_.packed_size(i) + kPendingValues;
}

int FixFibreContact::maxsize_restart()
{
  return 1 + fibre::ContactHistory::kMaxPacked + kPendingValues;
}

/* ----------------------------------------------------------------------
   halo communication for the Exchange (6 values per atom)
------------------------------------------------------------------------- */

int FixFibreContact::FIBRE_PACK_FORWARD(int n, int *list, double *buf, int /*pbc_flag*/,
                                        int * /*pbc*/)
{
  return fibre_lmp::packed_count(exchange_->pack_forward(n, list, buf),
                                 fibre_lmp::LammpsExchange::kValuesPerAtom);
}

void FixFibreContact::FIBRE_UNPACK_FORWARD(int n, int first, double *buf)
{
  exchange_->unpack_forward(first, n, buf);
}

int FixFibreContact::pack_reverse_comm(int n, int first, double *buf)
{
  return fibre_lmp::packed_count(exchange_->pack_reverse(first, n, buf),
                                 fibre_lmp::LammpsExchange::kValuesPerAtom);
}

void FixFibreContact::unpack_reverse_comm(int n, int *list, double *buf)
{
  exchange_->unpack_reverse(n, list, buf);
}

#ifndef FIBRE_HOST_LIGGGHTS
// The variable-size reverse comm's buffers (fix/lammps_compat.h): LAMMPS sizes none for a
// fix's reverse comm under `newton off`.
int FixFibreContact::pack_reverse_comm_size(int n, int /*first*/)
{
  return n * fibre_lmp::LammpsExchange::kValuesPerAtom;
}
#endif

/* ---------------------------------------------------------------------- */

double FixFibreContact::memory_usage()
{
  return history_.memory_bytes() + output_->memory_bytes() +
         double(pending_.capacity()) * sizeof(pending_[0]);
}
