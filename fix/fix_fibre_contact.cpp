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
#include "fibre/algebra/spook.hpp"
#include "fibre/core/text.hpp"
#include "fibre/model/stress.hpp"
#include "fibre/step/recovery.hpp"
#include "fibre/step/substeps.hpp"
#include "fibre/study/nonsmooth_reference.hpp"
#include "fibre_output.h"
#include "pair_coefficients.h"
#include "deck_models.h"
#include "wall_materials.h"
#include "force.h"
#include "group.h"
#include "host.h"
#include "lammps_clumps.h"
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

// Each step allocates and frees its buffers (contacts, impulses, rows: hundreds of bytes a
// contact). With glibc's defaults the freed memory went back to the system and every step
// faulted it in again: the material deck took 1.8x as long (bench/README.md, "The step's
// memory"); with blocks above 64 MB mapped, a million spheres spent 12% of a step in page faults.
// Blocks below 1 GB come from the heap, and freed memory up to 2 GB stays with the process.
void keep_step_memory()
{
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 1 << 30);
  mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
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
  if (settings_.clumps) {
    clumps_ = std::make_unique<fibre_lmp::LammpsClumps>(lmp, this, groupbit);
    comm_forward = std::max(comm_forward, fibre_lmp::LammpsClumps::kValues);
#ifdef FIBRE_HOST_LIGGGHTS
    comm->maxexchange_fix += fibre_lmp::LammpsClumps::kValues;
#else
    maxexchange += fibre_lmp::LammpsClumps::kValues;
#endif
  }
  if (comm->me == 0)
    for (const std::string &note : settings_.notes)
      warn(error, FLERR, "Fix fibre_contact: " + note);
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
  detection_->set_clumps(clumps_.get());
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
                                       const std::vector<fibre::ContactTag> &tags,
                                       const fibre::Vector &lambda)
{
  const int nwalls = static_cast<int>(settings_.walls.size());
  if (nwalls == 0) return;
  std::vector<int> wall_of(tags.size());
  for (std::size_t c = 0; c < tags.size(); ++c) wall_of[c] = tags[c].wall;
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
  const bool atoms = evflag && vflag_atom;
  fibre::contact_virial(sys, lambda, global, atoms ? &per_body : nullptr);
  for (int i = 0; i < 6; ++i) held_virial_[i] = global[i];
  if (evflag && vflag_global)
    for (int i = 0; i < 6; ++i) virial[i] += global[i];
  if (!atoms) return;
  exchange_->reverse_sum(per_body);
  const std::vector<int> &body_atom = exchange_->body_atom();
  for (int k = 0; k < exchange_->num_owned(); ++k)
    for (int i = 0; i < 6; ++i) vatom[body_atom[k]][i] += per_body[6 * k + i];
}

/* ---------------------------------------------------------------------- */

void FixFibreContact::init()
{
  if (starts_with(update->integrate_style, "respa"))
    fail(error, FLERR, "Fix fibre_contact does not support run_style respa");
  check_pair_style(true);
  if (clumps_) clumps_->check();
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
  // rows auto: the rotational rows where a law rolls or twists, and for the clumps' joints
  if (model.rows_auto) model.rows = clumps_ ? 6 : model.rows_needed();
  detection_->init_walls(walls);
  detection_->set_materials(model.per_type() ? &model.materials : nullptr);
  if (comm->me == 0) logmesg(lmp, "fix fibre_contact: " + fibre::describe(settings_) + "\n");
}

/* ---------------------------------------------------------------------- */

void FixFibreContact::setup(int vflag)
{
  start_virial(vflag); // no contact forces before the run's first step: a zero virial
  first_step_ = true;
  skin_warned_ = false;
  detection_->start_moving_walls();
  std::string style;
  const Pair *gran = fibre_lmp::granular_pair(lmp, style);
  if (!gran || !gran->list)
    fail(error, FLERR, "Fix fibre_contact found no neighbor list of the pair style");
  dtv_ = h_ = update->dt;
  next_solve_ = 0; // a run starts with a solve
}

void FixFibreContact::reset_dt()
{
  dtv_ = h_ = update->dt;
  next_solve_ = 0;
}

/* ----------------------------------------------------------------------
   positions: x += dt v, with v the velocities after the last contact solve, after the last
   step's substeps' displacement beyond it (follow_substeps)
------------------------------------------------------------------------- */

void FixFibreContact::initial_integrate(int /*vflag*/)
{
  // another fix's or command's non-finite values, named before the move spreads them (LAMMPS
  // would stop on "Non-numeric atom coords" without naming the atom)
  check_finite("position", atom->x, 3);
  check_finite("velocity", atom->v, 3);
  double **x = atom->x, **v = atom->v;
  const int *mask = atom->mask;
  for (int i = 0; i < atom->nlocal; ++i)
    if (mask[i] & groupbit)
      for (int d = 0; d < 3; ++d) {
        x[i][d] += pending_[i][d];
        pending_[i][d] = 0.0;
        x[i][d] += dtv_ * v[i][d];
      }
  if (clumps_) clumps_->rotate(dtv_);
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

// contact_every: the solve's impulses are applied at its step and the external forces f at
// every step, so the positions of the `every` steps sum dt v+ less dt^2 f / m (every - 1) ...
// 1: they take that in (pending_), and end where SPOOK's step every dt puts them,
// x + every dt v+ (without, a sphere resting on a floor rose by that each solve and fell back
// through its contact, which took the energy of the fall out).
void FixFibreContact::follow_solve_step(int every)
{
  double **f = atom->f;
  const double *rmass = atom->rmass;
  const double shift = 0.5 * every * (every - 1) * dtv_ * dtv_;
  const std::vector<int> &body_atom = exchange_->body_atom();
  for (int k = 0; k < exchange_->num_owned(); ++k) {
    const int i = body_atom[k];
    for (int d = 0; d < 3; ++d) pending_[i][d] += shift * f[i][d] / rmass[i];
  }
}

// A step between contact solves (contact_every): the external forces only; the virial is the
// last solve's mean contact forces' (global only). Moving regions difference their motion
// every step (LAMMPS's set_velocity divides the motion since its last call by dt).
void FixFibreContact::hold_step()
{
  update_velocities(nullptr);
  detection_->start_moving_walls();
  if (evflag && vflag_global)
    for (int i = 0; i < 6; ++i) virial[i] += held_virial_[i];
}

// The steps from this contact solve to the next (contact_every): N, or under auto
// fibre::steps_per_solve of the law's shortest collision time (1 without one: rigid rows). Alike on
// every process (m_min_ and r_min_ are global).
int FixFibreContact::solve_interval() const
{
  if (settings_.contact_every > 0) return settings_.contact_every;
  const fibre::ContactModel &model = settings_.model;
  if (!model.compliance.material || !(m_min_ > 0 && r_min_ > 0)) return 1;
  return fibre::steps_per_solve(
      fibre::shortest_collision_time(model.materials, r_min_, m_min_, 1.0).t_c, dtv_);
}

// Deep penetrations: opened by a displacement that the next step's move takes, not by a
// velocity (fibre/step/recovery.hpp); the elastic rows' history keeps what is left of theirs.
// Whether there were any.
bool FixFibreContact::recover_penetrations(fibre::Substeps &steps)
{
  // After a displacement without room the next solves wait 1, 2, 4 ... kRecoveryWait steps (the
  // penetrations stay split): a loaded bed's penetration without room cost a solve over every
  // contact at every step.
  if (recovery_wait_ > 0) {
    const long split = fibre::split_penetrations(steps.system, *exchange_);
    output_->report_split(split);
    if (split > 0) --recovery_wait_;
    return split > 0;
  }
  fibre::Vector dx;
  const fibre::Recovery recovery =
      fibre::recovery_displacement(steps.system, *exchange_, steps.v_plus, h_, dx);
  output_->report_split(recovery.split);
  if (recovery.outcome == fibre::Recovery::Outcome::none) return false;
  const bool no_room = recovery.outcome == fibre::Recovery::Outcome::refused;
  recovery_backoff_ = no_room ? std::min(std::max(2 * recovery_backoff_, 1), kRecoveryWait) : 0;
  recovery_wait_ = recovery_backoff_;
  if (no_room && !jammed_warned_) {
    if (comm->me == 0)
      warn(error, FLERR,
           "Fix fibre_contact: penetrations have no room to open (a jammed pack: more spheres "
           "than their walls hold, or an over-compressed packing); they stay as they are, "
           "without load, until there is room (doc page, \"Overlaps at the start\")");
    jammed_warned_ = true;
  }
  fibre::take_opening(steps.system, dx, steps.springs);
  const std::vector<int> &body_atom = exchange_->body_atom();
  for (int k = 0; k < exchange_->num_owned(); ++k)
    for (int d = 0; d < 3; ++d) pending_[body_atom[k]][d] += dx[6 * k + d];
  return true;
}

/* ----------------------------------------------------------------------
   the SPOOK step: detect, build, solve, apply, report
------------------------------------------------------------------------- */

// The contact solve of a step with contacts somewhere: warm start and springs from the
// history, the substeps (one solve where nothing moves: substep_when moving) and the step's
// check. found's contacts go into the system. substeps and hs come back as solved.
fibre::Substeps FixFibreContact::solve_contacts(std::vector<fibre::Body> bodies,
                                                fibre::FoundContacts &found, int &substeps,
                                                double &hs)
{
  const fibre::ContactModel &model = settings_.model;
  std::vector<fibre::Contact> contacts = std::move(found.contacts);
  found.contacts.clear();
  fibre::SpookParams params = step_params(bodies, hs);
  fibre::Vector warm = history_.warm_start(found.tags, contacts, model.rows, hs);
  history_.load_springs(found.tags, contacts);
  if (substeps > 1 && model.substep_moving_only && !step_moves(bodies, contacts, hs)) {
    substeps = 1;
    hs = h_;
    params = step_params(bodies, hs);
    warm = history_.warm_start(found.tags, contacts, model.rows, hs);
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
  fibre::Substeps steps =
      fibre::run_substeps(substeps, model, params, m_min_, *exchange_, exchange_->num_owned(),
                          std::move(bodies), std::move(contacts), std::move(warm),
                          [this, &inner](fibre::ContactSystem &s, const fibre::Vector &w, bool last,
                                         fibre::SweepCache &cache) {
                            return solve(s, w, last ? settings_.step : inner, &cache);
                          });
  if (check)
    check_step(steps, substeps, params, std::move(bodies_at_start), std::move(contacts_at_start),
               std::move(warm_at_start));
  return steps;
}

// The step's report: the local array, the solve's figures, the export and the history's
// overflow.
void FixFibreContact::report_step(const fibre::Substeps &steps,
                                  const std::vector<fibre::ContactTag> &tags, bool any, bool solved)
{
  const fibre::StepResult &res = steps.result;
  output_->fill_local(tags, solved ? &steps.lambda : nullptr, settings_.model.rows, array_local,
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
  if (settings_.export_every > 0 && update->ntimestep % settings_.export_every == 0)
    output_->export_step(settings_.export_prefix, steps.system, tags, any ? &res.lambda : nullptr,
                         steps.warm, exchange_->local_owners());
  if (overflow_count_ > 0 && !overflow_warned_ && comm->me == 0) {
    warn(error, FLERR,
         "Fix fibre_contact: more than " + std::to_string(fibre::ContactHistory::kMaxSlots) +
             " contacts stored on one atom; the rest start cold next step");
    overflow_warned_ = true;
  }
}

void FixFibreContact::final_integrate()
{
  check_finite("position", atom->x, 3);
  check_finite("force", atom->f, 3);
  check_finite("torque", atom->torque, 3);
  check_finite("velocity", atom->v, 3);
  check_finite("angular velocity", atom->omega, 3);

  if (update->ntimestep < next_solve_) { // contact_every: the last solve's impulses hold
    hold_step();
    return;
  }
  output_->release_local(array_local, size_local_rows);
  const fibre::ContactModel &model = settings_.model;
  std::vector<fibre::Body> bodies = detection_->bodies();
  detection_->set_wall_time(simulated_time() - time_origin_);
  smallest_body(bodies);
  const int every = solve_interval();
  h_ = every * dtv_;
  next_solve_ = update->ntimestep + every;
  // the contact solve runs in substeps of hs (fibre/substeps.hpp); detection keeps the step.
  // Detection reaches as far as impacts may kick the bodies where they bounce, and with
  // substeps also where they do not: a sphere that a plastic impact kicks in the step's first
  // substep moves on at its new speed in the others (without, a stiff pour blew up).
  int substeps = step_substeps();
  double hs = h_ / substeps;
  const double recovery = model.max_recovery(hs, r_min_); // step_params's, without its sums
  // (compliance material: the elastic rows' penetrations are split once the contact model has
  // found them, so detection reaches further while they are recovered)
  const bool reach = !model.compliance.material || recovering_;
  if (clumps_) clumps_->prepare(forward_clumps_);
  fibre::FoundContacts found =
      detection_->contacts(bodies, h_, model.damping, model.may_bounce() || substeps > 1,
                           reach ? hs * recovery : 0.0, recovering_);
  if (note_moving_walls(found.contacts)) {
    substeps = step_substeps();
    hs = h_ / substeps;
  }
  if (first_step_) warn_deep_overlaps(bodies, found.contacts, recovery);
  warn_skin();
  first_step_ = false;
  const bool any = output_->count_contacts(found.contacts) > 0;

  // build and solve (a step without contacts anywhere is free flight: an empty system)
  fibre::Substeps steps;
  if (any) {
    steps = solve_contacts(std::move(bodies), found, substeps, hs);
  } else {
    const fibre::SpookParams params = step_params(bodies, hs);
    steps.system = fibre::ContactSystem(std::move(bodies), std::move(found.contacts), model.rows,
                                        params, exchange_->num_owned());
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
  tally_wall_loads(sys, found.tags, lambda_mean);
  // this step's virial is wanted (post_force), or the steps' to the next solve
  if (evflag || next_solve_ > update->ntimestep + 1)
    tally_virial(sys, lambda_mean.size() ? lambda_mean : fibre::Vector::Zero(sys.contact_dofs()));
  // a step without a solve recovers nothing (f_ID[22] 0)
  recovering_ = false;
  output_->report_split(0);
  if (solved) {
    if (substepped) follow_substeps(steps.path, steps.done, hs);
    if (every > 1) follow_solve_step(every);
    recovering_ = recover_penetrations(steps);
    output_->add_work(steps.work); // the energy the moving walls put in and the contacts take out
  }
  // the history: the last substep's impulses and (compliance material) its springs
  overflow_count_ += history_.store(found.tags, sys.contacts(), res.lambda, model.rows, hs,
                                    steps.springs.empty() ? nullptr : &steps.springs);
  report_step(steps, found.tags, any, solved);
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
