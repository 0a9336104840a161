/* ----------------------------------------------------------------------
   fix fibre_contact: nonsmooth, regularized (SPOOK) contact dynamics for granular spheres.

   Every step: x += dt v (initial_integrate); then, after all post_force fixes (gravity
   included), contacts are detected on the granular pair style's neighbor list and on the
   walls, the contact system is built and solved by the fibre solver library, and
   v += dt f/m + M^-1 G^T lambda (final_integrate). Documentation: doc/fix_fibre_contact.md
------------------------------------------------------------------------- */

#include "fix_fibre_contact.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>

#include "atom.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "fibre/system_io.hpp"
#include "fix_fibre_exchange.h"
#include "force.h"
#include "group.h"
#include "memory.h"
#include "modify.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "pair.h"
#include "region.h"
#include "update.h"
#include "utils.h"

using namespace LAMMPS_NS;
using namespace FixConst;

namespace {

constexpr int kLocalColumns = 8;
constexpr int kWallKeyStride = 1024;  // wall key = wall index * stride + sub-wall + 1
constexpr double kRestartFormat = 2.0;  // 2: 15 global values
// pairs closer than this fraction of the smaller radius are always contacts
constexpr double kContactMargin = 0.01;

bool to_double(const char *s, double &value)
{
  if (!s || !*s) return false;
  char *end = nullptr;
  errno = 0;
  value = std::strtod(s, &end);
  return end != s && *end == '\0' && errno == 0 && std::isfinite(value);
}

bool to_long(const char *s, long &value)
{
  if (!s || !*s) return false;
  char *end = nullptr;
  errno = 0;
  value = std::strtol(s, &end, 10);
  return end != s && *end == '\0' && errno == 0;
}

std::string fmt_g(double x)
{
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", x);
  return buf;
}

}  // namespace

/* ---------------------------------------------------------------------- */

FixFibreContact::FixFibreContact(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg)
{
  if (!atom->radius_flag || !atom->rmass_flag || !atom->omega_flag || !atom->torque_flag)
    error->all(FLERR, std::string("Fix fibre_contact requires atom attributes radius, rmass, "
                                  "omega and torque (use atom_style sphere)"));
  if (domain->dimension != 3)
    error->all(FLERR, std::string("Fix fibre_contact requires a 3d simulation (dimension 3)"));

  time_integrate = 1;
  vector_flag = 1;
  size_vector = V_SIZE;
  global_freq = 1;
  extvector = 0;
  local_flag = 1;
  size_local_rows = 0;
  size_local_cols = kLocalColumns;
  local_freq = 1;
  restart_global = 1;
  restart_peratom = 1;
  create_attribute = 1;
  comm_forward = fibre_lmp::LammpsExchange::kValuesPerAtom;
  comm_reverse = fibre_lmp::LammpsExchange::kValuesPerAtom;
  maxexchange = 1 + kMaxSlots * kSlotSize;

  // defaults by measurement (doc/fix_fibre_contact.md, "Solvers")
  opt_.form = fibre::Form::body;
  opt_.solver = fibre::Method::cg;
  opt_.precond.kind = fibre::PrecondKind::tree;
  opt_.precond.weight = fibre::EdgeWeight::z;
  // The projected Gauss-Seidel sweeps finish every step to a complementarity residual of
  // sweep_tol; linear solves tighter than tol 1e-4 and more than one active-set pass bought no
  // accuracy in the material and silo scenes, only time (doc page, "Why both").
  opt_.stop.tol = 1e-4;
  opt_.pass_tol = 1e-3;
  opt_.stop.max_iter = 200;
  opt_.friction = fibre::FrictionParams{};
  opt_.active_set_max = 1;
  opt_.sweeps = 50;
  opt_.sweep_tol = 1e-3;

  parse_args(narg, arg);

  exchange_ = std::make_unique<fibre_lmp::LammpsExchange>(lmp, this, world);

  // per-atom warm-start storage, migrating with the atoms and written to restart files
  grow_arrays(atom->nmax);
  atom->add_callback(Atom::GROW);
  atom->add_callback(Atom::RESTART);
  for (int i = 0; i < atom->nmax; ++i) nslot_[i] = 0;

  // this fix computes every contact force: switch the pair style's forces off
  if (force->pair) {
    pair_ = force->pair;
    pair_->compute_flag = 0;
    if (comm->me == 0)
      utils::logmesg(lmp, std::string("fix fibre_contact: switched off the force computation of "
                                      "pair style ") +
                              force->pair_style +
                              " (its neighbor list is the contact graph)\n");
  }
}

/* ---------------------------------------------------------------------- */

FixFibreContact::~FixFibreContact()
{
  if (copymode) return;
  atom->delete_callback(id, Atom::GROW);
  atom->delete_callback(id, Atom::RESTART);
  memory->destroy(nslot_);
  memory->destroy(slots_);
  memory->destroy(local_array_);
  if (pair_ && force && force->pair == pair_) pair_->compute_flag = 1;
}

/* ---------------------------------------------------------------------- */

int FixFibreContact::setmask()
{
  int mask = 0;
  mask |= INITIAL_INTEGRATE;
  mask |= FINAL_INTEGRATE;
  return mask;
}

/* ---------------------------------------------------------------------- */

void FixFibreContact::illegal(const std::string &expected, const char *got)
{
  std::string msg = "Illegal fix fibre_contact command: expected " + expected;
  if (got) msg += std::string(", got '") + got + "'";
  error->all(FLERR, msg);
}

double FixFibreContact::parse_number(int narg, char **arg, int iarg, const std::string &expected)
{
  if (iarg >= narg) illegal(expected);
  double value = 0.0;
  if (!to_double(arg[iarg], value)) illegal(expected, arg[iarg]);
  return value;
}

double FixFibreContact::parse_positive(int narg, char **arg, int iarg, const std::string &expected)
{
  const double value = parse_number(narg, arg, iarg, expected);
  if (!(value > 0.0)) illegal(expected, arg[iarg]);
  return value;
}

long FixFibreContact::parse_integer(int narg, char **arg, int iarg, const std::string &expected,
                                    long lo, long hi)
{
  if (iarg >= narg) illegal(expected);
  long value = 0;
  if (!to_long(arg[iarg], value) || value < lo || value > hi) illegal(expected, arg[iarg]);
  return value;
}

void FixFibreContact::parse_args(int narg, char **arg)
{
  int iarg = 3;
  while (iarg < narg) {
    const std::string key = arg[iarg];
    const char *val = iarg + 1 < narg ? arg[iarg + 1] : nullptr;

    if (key == "form") {
      const std::string e = "'form body|contact'";
      if (!val) illegal(e);
      if (!fibre::parse(val, opt_.form)) illegal(e, val);
      iarg += 2;
    } else if (key == "solver") {
      const std::string e = "'solver uzawa|cr|minres|direct'";
      if (!val) illegal(e);
      if (!fibre::parse(val, opt_.solver)) illegal(e, val);
      iarg += 2;
    } else if (key == "precond") {
      const std::string e = "'precond none|jacobi|block|fibre|tree'";
      if (!val) illegal(e);
      if (!fibre::parse(val, opt_.precond.kind)) illegal(e, val);
      iarg += 2;
    } else if (key == "weight") {
      const std::string e = "'weight z|straight|impulse'";
      if (!val) illegal(e);
      if (!fibre::parse(val, opt_.precond.weight)) illegal(e, val);
      iarg += 2;
    } else if (key == "tol") {
      const std::string e = "'tol <positive number>'";
      opt_.stop.tol = parse_positive(narg, arg, iarg + 1, e);
      iarg += 2;
    } else if (key == "pass_tol") {
      const std::string e = "'pass_tol <positive number>'";
      opt_.pass_tol = parse_positive(narg, arg, iarg + 1, e);
      iarg += 2;
    } else if (key == "maxiter") {
      const std::string e = "'maxiter <positive integer>'";
      opt_.stop.max_iter = static_cast<int>(parse_integer(narg, arg, iarg + 1, e, 1, 100000000));
      iarg += 2;
    } else if (key == "compliance") {
      const std::string e = "'compliance auto' or 'compliance <eps_n> <eps_t>' (positive numbers)";
      if (!val) illegal(e);
      if (std::strcmp(val, "auto") == 0) {
        compliance_auto_ = true;
        iarg += 2;
      } else {
        const double en = parse_positive(narg, arg, iarg + 1, e);
        const double et = parse_positive(narg, arg, iarg + 2, e);
        compliance_auto_ = false;
        compliance_n_ = en;
        compliance_t_ = et;
        iarg += 3;
      }
    } else if (key == "damping") {
      const std::string e = "'damping <positive number of steps>'";
      damping_ = parse_positive(narg, arg, iarg + 1, e);
      iarg += 2;
    } else if (key == "mu" || key == "mu_roll" || key == "mu_twist") {
      const std::string e = "'" + key + " <non-negative number>'";
      const double v = parse_number(narg, arg, iarg + 1, e);
      if (!(v >= 0.0)) illegal(e, val);
      if (key == "mu") opt_.friction.mu = v;
      else if (key == "mu_roll") opt_.friction.mu_roll = v;
      else opt_.friction.mu_twist = v;
      iarg += 2;
    } else if (key == "rows") {
      const std::string e = "'rows 3|6'";
      long v = 0;
      if (!val) illegal(e);
      if (!to_long(val, v) || (v != 3 && v != 6)) illegal(e, val);
      rows_ = static_cast<int>(v);
      iarg += 2;
    } else if (key == "active_set") {
      const std::string e = "'active_set <positive integer>'";
      opt_.active_set_max = static_cast<int>(parse_integer(narg, arg, iarg + 1, e, 1, 1000));
      iarg += 2;
    } else if (key == "sweeps") {
      const std::string e = "'sweeps <non-negative integer>'";
      opt_.sweeps = static_cast<int>(parse_integer(narg, arg, iarg + 1, e, 0, 100000));
      iarg += 2;
    } else if (key == "sweep_tol") {
      const std::string e = "'sweep_tol <positive number>'";
      opt_.sweep_tol = parse_positive(narg, arg, iarg + 1, e);
      iarg += 2;
    } else if (key == "wall") {
      const std::string e =
          "'wall xplane|yplane|zplane <lo|NULL> <hi|NULL>' or 'wall region <region-ID>'";
      if (!val) illegal(e);
      Wall w;
      const std::string kind = val;
      if (kind == "region") {
        if (iarg + 2 >= narg) illegal("'wall region <region-ID>'");
        w.kind = REGION;
        w.region_id = arg[iarg + 2];
        iarg += 3;
      } else if (kind == "xplane" || kind == "yplane" || kind == "zplane") {
        w.kind = kind == "xplane" ? XPLANE : kind == "yplane" ? YPLANE : ZPLANE;
        const std::string ep = "'wall " + kind + " <lo|NULL> <hi|NULL>'";
        if (iarg + 3 >= narg) illegal(ep);
        const char *lo = arg[iarg + 2], *hi = arg[iarg + 3];
        if (std::strcmp(lo, "NULL") != 0) {
          if (!to_double(lo, w.lo)) illegal(ep, lo);
          w.has_lo = true;
        }
        if (std::strcmp(hi, "NULL") != 0) {
          if (!to_double(hi, w.hi)) illegal(ep, hi);
          w.has_hi = true;
        }
        if (!w.has_lo && !w.has_hi) illegal(ep + " with at least one of lo and hi a number");
        if (w.has_lo && w.has_hi && !(w.lo < w.hi))
          illegal(ep + " with lo < hi", (std::string(lo) + " " + hi).c_str());
        iarg += 4;
      } else {
        illegal(e, val);
      }
      walls_.push_back(w);
    } else if (key == "export") {
      const std::string e = "'export <N> <file-prefix>' (N a positive integer)";
      long v = 0;
      if (!val) illegal(e);
      if (!to_long(val, v) || v < 1 || v > 2000000000L) illegal(e, val);
      if (iarg + 2 >= narg) illegal(e);
      export_every_ = static_cast<int>(v);
      export_prefix_ = arg[iarg + 2];
      iarg += 3;
    } else {
      illegal("a keyword (form, solver, precond, weight, tol, pass_tol, maxiter, compliance, "
              "damping, mu, mu_roll, mu_twist, rows, active_set, sweeps, sweep_tol, wall, export)",
              arg[iarg]);
    }
  }
  if (rows_ == 3 && (opt_.friction.mu_roll > 0.0 || opt_.friction.mu_twist > 0.0))
    error->all(FLERR, std::string("Illegal fix fibre_contact command: mu_roll and mu_twist need "
                                  "'rows 6' (rows 3 has no rotational rows)"));
}

/* ---------------------------------------------------------------------- */

void FixFibreContact::check_pair_style(bool at_init)
{
  if (!force->pair)
    error->all(FLERR, std::string("Fix fibre_contact requires a granular pair style for its "
                                  "neighbor list, e.g. 'pair_style gran/hooke 1.0 NULL 0.0 NULL "
                                  "0.0 0' and 'pair_coeff * *'"));
  const std::string style = force->pair_style ? force->pair_style : "";
  if (!utils::strmatch(style, "^gran"))
    error->all(FLERR, "Fix fibre_contact requires a granular pair style (gran/hooke, "
                      "gran/hooke/history, gran/hertz/history or granular) for its neighbor "
                      "list, not pair style '" + style + "'");
  if (at_init && force->pair->compute_flag)
    error->all(FLERR, std::string("Fix fibre_contact computes every contact force itself, but the "
                                  "pair style's force computation is on: define the pair style "
                                  "before fix fibre_contact and do not use 'pair_modify compute "
                                  "yes'"));
}

void FixFibreContact::init()
{
  if (utils::strmatch(update->integrate_style, "^respa"))
    error->all(FLERR, std::string("Fix fibre_contact does not support run_style respa"));
  check_pair_style(true);

  dtv_ = update->dt;

  for (Wall &w : walls_) {
    if (w.kind != REGION) continue;
    w.iregion = domain->find_region(w.region_id);
    if (w.iregion < 0)
      error->all(FLERR, "Region ID '" + w.region_id + "' for fix fibre_contact 'wall region' "
                        "does not exist");
    if (domain->regions[w.iregion]->dynamic)
      error->all(FLERR, "Fix fibre_contact does not support moving region '" + w.region_id +
                            "' (walls must be at rest)");
  }

  // another fix that moves the same atoms would integrate them twice
  for (int f = 0; f < modify->nfix; ++f) {
    Fix *other = modify->fix[f];
    if (other == this || !other->time_integrate) continue;
    int mine = 0;
    for (int i = 0; i < atom->nlocal; ++i)
      if ((atom->mask[i] & groupbit) && (atom->mask[i] & other->groupbit)) ++mine;
    int all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_SUM, world);
    if (all > 0 && comm->me == 0)
      error->warning(FLERR, std::string("Fix fibre_contact: fix ") + other->id + " (" +
                                other->style + ") also time-integrates " + std::to_string(all) +
                                " atoms of group " + group->names[igroup] +
                                ": they are moved twice per step");
  }

  if (comm->me == 0) {
    std::string msg = "fix fibre_contact: form " + std::string(fibre::to_string(opt_.form)) +
                      ", solver " + fibre::to_string(opt_.solver) + ", precond " +
                      fibre::to_string(opt_.precond.kind) + ", weight " +
                      fibre::to_string(opt_.precond.weight) + ", tol " + fmt_g(opt_.stop.tol) +
                      ", pass_tol " + fmt_g(opt_.pass_tol) + ", maxiter " +
                      std::to_string(opt_.stop.max_iter) + ", rows " + std::to_string(rows_) +
                      ", damping " + fmt_g(damping_) + ", mu " +
                      fmt_g(opt_.friction.mu) + ", mu_roll " + fmt_g(opt_.friction.mu_roll) +
                      ", mu_twist " + fmt_g(opt_.friction.mu_twist) + ", active_set " +
                      std::to_string(opt_.active_set_max) + ", sweeps " +
                      std::to_string(opt_.sweeps) + ", sweep_tol " + fmt_g(opt_.sweep_tol) +
                      ", compliance ";
    if (compliance_auto_)
      msg += "auto (" + fmt_g(compliance_factor_) + " dt^2 / m_min)";
    else
      msg += fmt_g(compliance_n_) + " " + fmt_g(compliance_t_);
    utils::logmesg(lmp, msg + "\n");
  }
}

/* ---------------------------------------------------------------------- */

void FixFibreContact::setup(int /*vflag*/)
{
  if (!force->pair || !force->pair->list)
    error->all(FLERR, std::string("Fix fibre_contact found no neighbor list of the pair style"));
  dtv_ = update->dt;
}

/* ---------------------------------------------------------------------- */

void FixFibreContact::reset_dt()
{
  dtv_ = update->dt;
}

/* ----------------------------------------------------------------------
   positions: x += dt v, with v the velocities after the last contact solve
------------------------------------------------------------------------- */

void FixFibreContact::initial_integrate(int /*vflag*/)
{
  double **x = atom->x;
  double **v = atom->v;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  for (int i = 0; i < nlocal; ++i)
    if (mask[i] & groupbit) {
      x[i][0] += dtv_ * v[i][0];
      x[i][1] += dtv_ * v[i][1];
      x[i][2] += dtv_ * v[i][2];
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
        error->one(FLERR, std::string("Fix fibre_contact: non-finite ") + what + " of atom " +
                              std::to_string(static_cast<long long>(atom->tag[i])) +
                              " at step " +
                              std::to_string(static_cast<long long>(update->ntimestep)));
  }
}

/* ----------------------------------------------------------------------
   bodies: owned group atoms sorted by tag, then ghost group atoms (sorted by tag and
   position), so that the system does not depend on the atoms' storage order
------------------------------------------------------------------------- */

void FixFibreContact::build_bodies(std::vector<fibre::Body> &bodies)
{
  const int nlocal = atom->nlocal;
  const int nall = nlocal + atom->nghost;
  const int *mask = atom->mask;
  const tagint *tag = atom->tag;
  double **x = atom->x;

  std::vector<int> owned, ghosts;
  for (int i = 0; i < nlocal; ++i)
    if (mask[i] & groupbit) owned.push_back(i);
  for (int i = nlocal; i < nall; ++i)
    if (mask[i] & groupbit) ghosts.push_back(i);
  std::sort(owned.begin(), owned.end(), [tag](int a, int b) { return tag[a] < tag[b]; });
  std::sort(ghosts.begin(), ghosts.end(), [tag, x](int a, int b) {
    if (tag[a] != tag[b]) return tag[a] < tag[b];
    for (int d = 0; d < 3; ++d)
      if (x[a][d] != x[b][d]) return x[a][d] < x[b][d];
    return a < b;
  });

  std::vector<int> body_atom(owned);
  body_atom.insert(body_atom.end(), ghosts.begin(), ghosts.end());
  const int nowned = static_cast<int>(owned.size());
  const int nbody = static_cast<int>(body_atom.size());
  exchange_->set_bodies(body_atom, nowned);

  atom_body_.assign(nall, -1);
  for (int k = 0; k < nbody; ++k) atom_body_[body_atom[k]] = k;

  // velocities and external forces of owned atoms, forwarded to their ghosts
  double **v = atom->v, **omega = atom->omega, **f = atom->f, **torque = atom->torque;
  fibre::Vector vel = fibre::Vector::Zero(6 * Eigen::Index(nbody));
  fibre::Vector frc = fibre::Vector::Zero(6 * Eigen::Index(nbody));
  for (int k = 0; k < nowned; ++k) {
    const int i = body_atom[k];
    for (int d = 0; d < 3; ++d) {
      vel[6 * k + d] = v[i][d];
      vel[6 * k + 3 + d] = omega[i][d];
      frc[6 * k + d] = f[i][d];
      frc[6 * k + 3 + d] = torque[i][d];
    }
  }
  exchange_->forward(vel);
  exchange_->forward(frc);

  bodies.assign(nbody, fibre::Body{});
  for (int k = 0; k < nbody; ++k) {
    const int i = body_atom[k];
    fibre::Body &b = bodies[k];
    b.mass = atom->rmass[i];
    b.radius = atom->radius[i];
    b.x = fibre::Vec3(x[i][0], x[i][1], x[i][2]);
    b.v = vel.segment<3>(6 * k);
    b.omega = vel.segment<3>(6 * k + 3);
    b.force = frc.segment<3>(6 * k);
    b.torque = frc.segment<3>(6 * k + 3);
  }
}

/* ----------------------------------------------------------------------
   a pair is a contact when it overlaps, when its gap is below 1% of the smaller radius
   (resting neighbours, no flicker), or when it could close within about (damping + 1)
   steps at its current approach speed (free flight over this step): SPOOK then brakes the
   approach before the spheres overlap. A contact with a positive gap never pulls: its
   impulse would be negative and the active set releases it
------------------------------------------------------------------------- */

bool FixFibreContact::approaching(const fibre::Body &a, const fibre::Body *b,
                                  const fibre::Vec3 &n, double gap) const
{
  const double rmin = b ? std::min(a.radius, b->radius) : a.radius;
  const double margin = kContactMargin * rmin;
  if (gap < margin) return true;
  fibre::Vec3 rel = a.v + (dtv_ / a.mass) * a.force;
  if (b) rel -= b->v + (dtv_ / b->mass) * b->force;
  const double approach = -n.dot(rel);
  return approach > 0.0 && gap < margin + (damping_ + 1.0) * dtv_ * approach;
}

/* ----------------------------------------------------------------------
   sphere-sphere contacts from the pair style's half neighbor list; every contact is kept
   by exactly one process: a pair of two owned atoms is listed once; with newton_pair on a
   pair with a ghost is listed on one process only; with newton_pair off it is listed on
   both and the process owning the atom with the smaller tag keeps it
------------------------------------------------------------------------- */

void FixFibreContact::detect_pair_contacts(const std::vector<fibre::Body> &bodies,
                                           std::vector<Found> &found)
{
  NeighList *list = force->pair->list;
  const int inum = list->inum;
  const int *ilist = list->ilist;
  const int *numneigh = list->numneigh;
  int **firstneigh = list->firstneigh;
  const int nlocal = atom->nlocal;
  const tagint *tag = atom->tag;
  double **x = atom->x;
  const double *radius = atom->radius;
  const bool newton_pair = force->newton_pair != 0;
  const double reach = neighbor->skin;  // pairs beyond radsum + skin are not in the list

  for (int ii = 0; ii < inum; ++ii) {
    const int i = ilist[ii];
    const int *jlist = firstneigh[i];
    const int jnum = numneigh[i];
    for (int jj = 0; jj < jnum; ++jj) {
      const int j = jlist[jj] & NEIGHMASK;
      const int bi = atom_body_[i], bj = atom_body_[j];
      if (bi < 0 && bj < 0) continue;
      if (tag[i] == tag[j]) continue;  // a periodic image of itself
      if (j >= nlocal && !newton_pair && tag[i] > tag[j]) continue;

      const double dx = x[i][0] - x[j][0], dy = x[i][1] - x[j][1], dz = x[i][2] - x[j][2];
      const double rsq = dx * dx + dy * dy + dz * dz;
      const double radsum = radius[i] + radius[j];
      if (rsq >= (radsum + reach) * (radsum + reach)) continue;
      const double dist = std::sqrt(rsq);

      // the atom with the smaller tag stores the warm start if it is owned here
      const int low = tag[i] < tag[j] ? i : j, high = low == i ? j : i;
      const int store = low < nlocal ? low : high;

      Found fc;
      if (bi >= 0 && bj >= 0) {
        const int a = tag[i] < tag[j] ? bi : bj, b = a == bi ? bj : bi;
        fc.contact = fibre::sphere_sphere_contact(bodies, a, b);
        if (!approaching(bodies[a], &bodies[b], fc.contact.normal, fc.contact.gap)) continue;
        fc.tag_a = tag[low];
        fc.partner = static_cast<double>(tag[high]);
      } else {
        // one atom is outside the group: a fixed spherical obstacle
        const int g = bi >= 0 ? i : j, o = g == i ? j : i;
        const double sign = g == i ? 1.0 : -1.0;
        fibre::Vec3 n(sign * dx, sign * dy, sign * dz);
        n = dist > 0.0 ? fibre::Vec3(n / dist) : fibre::Vec3::UnitZ();
        fc.contact = fibre::sphere_wall_contact(bodies, atom_body_[g], n, dist - radius[o]);
        if (!approaching(bodies[atom_body_[g]], nullptr, n, fc.contact.gap)) continue;
        fc.tag_a = tag[g];
        fc.partner = static_cast<double>(tag[o]);
      }
      fc.store_atom = store;
      found.push_back(fc);
    }
  }
}

/* ---------------------------------------------------------------------- */

void FixFibreContact::add_wall_contact(const std::vector<fibre::Body> &bodies, int body,
                                       const double *normal, double distance, int wall, int sub,
                                       std::vector<Found> &found)
{
  const fibre::Vec3 n(normal[0], normal[1], normal[2]);
  const double gap = distance - bodies[body].radius;
  if (!approaching(bodies[body], nullptr, n, gap)) return;
  Found fc;
  fc.contact = fibre::sphere_wall_contact(bodies, body, n, distance);
  const int i = exchange_->body_atom()[body];
  fc.tag_a = atom->tag[i];
  fc.partner = -static_cast<double>(wall * kWallKeyStride + sub + 1);
  fc.wall = wall;
  fc.store_atom = i;
  found.push_back(fc);
}

void FixFibreContact::detect_wall_contacts(const std::vector<fibre::Body> &bodies,
                                           std::vector<Found> &found)
{
  if (walls_.empty()) return;
  const int nowned = exchange_->num_owned();
  const double reach = neighbor->skin;
  for (int w = 0; w < static_cast<int>(walls_.size()); ++w) {
    const Wall &wall = walls_[w];
    if (wall.kind == REGION) {
      Region *region = domain->regions[wall.iregion];
      region->prematch();
      for (int k = 0; k < nowned; ++k) {
        const fibre::Body &b = bodies[k];
        const fibre::Vec3 vfree = b.v + (dtv_ / b.mass) * b.force;
        const double cutoff = b.radius * (1.0 + kContactMargin) +
                              std::min(reach, (damping_ + 1.0) * dtv_ * vfree.norm());
        const int nc = region->surface(b.x[0], b.x[1], b.x[2], cutoff);
        for (int c = 0; c < nc; ++c) {
          const Region::Contact &rc = region->contact[c];
          if (!(rc.r > 0.0)) continue;
          const double n[3] = {rc.delx / rc.r, rc.dely / rc.r, rc.delz / rc.r};
          add_wall_contact(bodies, k, n, rc.r, w, std::min(rc.iwall, kWallKeyStride - 1), found);
        }
      }
    } else {
      const int dim = static_cast<int>(wall.kind);
      for (int k = 0; k < nowned; ++k) {
        const fibre::Body &b = bodies[k];
        if (wall.has_lo) {
          double n[3] = {0.0, 0.0, 0.0};
          n[dim] = 1.0;
          const double distance = b.x[dim] - wall.lo;
          if (distance - b.radius < reach) add_wall_contact(bodies, k, n, distance, w, 0, found);
        }
        if (wall.has_hi) {
          double n[3] = {0.0, 0.0, 0.0};
          n[dim] = -1.0;
          const double distance = wall.hi - b.x[dim];
          if (distance - b.radius < reach) add_wall_contact(bodies, k, n, distance, w, 1, found);
        }
      }
    }
  }
}

/* ----------------------------------------------------------------------
   per-row compliance: eps_n on the normal row, eps_t on the tangential rows and
   eps_t / r_eff^2 on the rotational rows (r_eff = r_a r_b / (r_a + r_b), walls r_a)
------------------------------------------------------------------------- */

void FixFibreContact::set_compliance(std::vector<Found> &found,
                                     const std::vector<fibre::Body> &bodies)
{
  double eps_n = compliance_n_, eps_t = compliance_t_;
  if (compliance_auto_) eps_n = eps_t = compliance_factor_ * dtv_ * dtv_ / last_m_min_;
  for (Found &fc : found) {
    fibre::Contact &c = fc.contact;
    const double ra = bodies[c.a].radius;
    const double reff = c.is_wall() ? ra : ra * bodies[c.b].radius / (ra + bodies[c.b].radius);
    c.compliance[0] = eps_n;
    c.compliance[1] = c.compliance[2] = eps_t;
    for (int r = 3; r < fibre::kMaxRows; ++r) c.compliance[r] = eps_t / (reff * reff);
  }
}

/* ----------------------------------------------------------------------
   warm start: the impulses the same contact had last step, stored per atom
------------------------------------------------------------------------- */

void FixFibreContact::warm_start(const std::vector<Found> &found, int rows,
                                 fibre::Vector &warm) const
{
  const int nc = static_cast<int>(found.size());
  warm = fibre::Vector::Zero(Eigen::Index(rows) * nc);
  const tagint *tag = atom->tag;
  for (int c = 0; c < nc; ++c) {
    const Found &fc = found[c];
    const int s = fc.store_atom;
    const double key = tag[s] == fc.tag_a ? fc.partner : static_cast<double>(fc.tag_a);
    const double *slot = nullptr;
    for (int k = 0; k < nslot_[s]; ++k)
      if (slots_[s][k * kSlotSize] == key) {
        slot = &slots_[s][k * kSlotSize];
        break;
      }
    if (!slot) continue;
    const fibre::Vec3 force(slot[1], slot[2], slot[3]), moment(slot[4], slot[5], slot[6]);
    const fibre::Contact &k = fc.contact;
    const fibre::Vec3 dirs[3] = {k.normal, k.t1, k.t2};
    for (int r = 0; r < rows; ++r) {
      warm[Eigen::Index(rows) * c + r] =
          dtv_ * (r < 3 ? force.dot(dirs[r]) : moment.dot(dirs[r - 3]));
    }
  }
}

void FixFibreContact::store_impulses(const std::vector<Found> &found,
                                     const fibre::ContactSystem &sys, const fibre::Vector &lambda)
{
  const int nlocal = atom->nlocal;
  for (int i = 0; i < nlocal; ++i) nslot_[i] = 0;
  const int rows = sys.rows();
  const tagint *tag = atom->tag;
  for (int c = 0; c < static_cast<int>(found.size()); ++c) {
    const Found &fc = found[c];
    const fibre::Contact &k = fc.contact;
    const double *l = lambda.data() + Eigen::Index(rows) * c;
    if (!(l[0] > 0.0)) continue;  // released: nothing to remember
    const fibre::Vec3 force = (l[0] * k.normal + l[1] * k.t1 + l[2] * k.t2) / dtv_;
    fibre::Vec3 moment = fibre::Vec3::Zero();
    if (rows == 6) moment = (l[3] * k.normal + l[4] * k.t1 + l[5] * k.t2) / dtv_;
    const int s = fc.store_atom;
    if (nslot_[s] >= kMaxSlots) {
      ++overflow_count_;
      continue;
    }
    double *slot = &slots_[s][nslot_[s]++ * kSlotSize];
    slot[0] = tag[s] == fc.tag_a ? fc.partner : static_cast<double>(fc.tag_a);
    for (int d = 0; d < 3; ++d) {
      slot[1 + d] = force[d];
      slot[4 + d] = moment[d];
    }
  }
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

/* ---------------------------------------------------------------------- */

void FixFibreContact::fill_local_output(const std::vector<Found> &found,
                                        const fibre::Vector *lambda)
{
  const int nc = static_cast<int>(found.size());
  if (nc > maxlocal_) {
    maxlocal_ = std::max(nc, 2 * maxlocal_);
    memory->destroy(local_array_);
    memory->create(local_array_, maxlocal_, kLocalColumns, "fibre_contact:local");
  }
  array_local = local_array_;
  size_local_rows = nc;
  for (int c = 0; c < nc; ++c) {
    const Found &fc = found[c];
    double *row = local_array_[c];
    row[0] = static_cast<double>(fc.tag_a);
    row[1] = fc.partner > 0 ? fc.partner : 0.0;
    row[2] = fc.wall + 1;
    row[3] = fc.contact.gap;
    for (int d = 4; d < kLocalColumns; ++d) row[d] = 0.0;
    if (!lambda) continue;
    const double *l = lambda->data() + Eigen::Index(rows_) * c;
    row[4] = l[0];
    row[5] = std::hypot(l[1], l[2]);
    if (rows_ == 6) {
      row[6] = std::hypot(l[4], l[5]);
      row[7] = std::fabs(l[3]);
    }
  }
}

/* ---------------------------------------------------------------------- */

void FixFibreContact::export_system(const fibre::ContactSystem &sys,
                                    const std::vector<Found> &found, const fibre::Vector *lambda)
{
  const std::string base = export_prefix_ + "." +
                           std::to_string(static_cast<long long>(update->ntimestep)) + "." +
                           std::to_string(comm->me);
  try {
    fibre::write_system_file(base + ".sys", sys);
  } catch (std::exception &e) {
    error->one(FLERR, "Fix fibre_contact could not write export file " + base + ".sys: " +
                          e.what());
  }
  // the solution, with the atoms of every contact
  FILE *fp = std::fopen((base + ".lambda").c_str(), "w");
  if (!fp) error->one(FLERR, "Fix fibre_contact could not write export file " + base + ".lambda");
  const int rows = sys.rows();
  std::fprintf(fp, "# fibre_contact impulses, step %lld, process %d: %d contacts, %d rows each\n",
               static_cast<long long>(update->ntimestep), comm->me, sys.num_contacts(), rows);
  std::fprintf(fp, "# contact tag_a tag_b(0 = wall) wall(0 = none) lambda_0 .. lambda_%d\n",
               rows - 1);
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Found &fc = found[c];
    std::fprintf(fp, "%d %lld %lld %d", c, static_cast<long long>(fc.tag_a),
                 static_cast<long long>(fc.partner > 0 ? fc.partner : 0.0), fc.wall + 1);
    for (int r = 0; r < rows; ++r)
      std::fprintf(fp, " %.17g", lambda ? (*lambda)[Eigen::Index(rows) * c + r] : 0.0);
    std::fprintf(fp, "\n");
  }
  std::fclose(fp);
}

/* ---------------------------------------------------------------------- */

void FixFibreContact::report_solve(const fibre::StepResult &res)
{
  stats_[V_ITER] = res.total_iterations;
  stats_[V_RESID] = res.rel_residual;
  stats_[V_PASSES] = res.active_set_passes;
  stats_[V_CONVERGED] = res.converged ? 1.0 : 0.0;
  stats_[V_COMPLEMENTARITY] = res.complementarity;
  stats_[V_SWEEPS] = res.sweeps;

  double sums[3] = {double(res.fibres.num_fibres), double(res.fibres.contacts_in_fibres),
                    double(res.fibres.num_contacts)};
  MPI_Allreduce(MPI_IN_PLACE, sums, 3, MPI_DOUBLE, MPI_SUM, world);
  stats_[V_FIBRES] = sums[0];
  stats_[V_FIBRE_FRACTION] = sums[2] > 0 ? sums[1] / sums[2] : 0.0;
  double times[3] = {res.setup_seconds, res.solve_seconds, res.sweep_seconds};
  MPI_Allreduce(MPI_IN_PLACE, times, 3, MPI_DOUBLE, MPI_MAX, world);
  stats_[V_SETUP] = times[0];
  stats_[V_SOLVE] = times[1];
  stats_[V_SWEEP_TIME] = times[2];

  if (!res.converged) {
    ++nonconverged_total_;
    ++nonconverged_since_warning_;
    const bigint step = update->ntimestep;
    if (last_warning_step_ < 0 || step - last_warning_step_ >= 100) {
      if (comm->me == 0)
        error->warning(FLERR, "Fix fibre_contact: contact solve did not converge at step " +
                                  std::to_string(static_cast<long long>(step)) + " (" +
                                  fibre::to_string(res.reason) + ", " +
                                  std::to_string(res.iterations) + " iterations, relative "
                                  "residual " + fmt_g(res.rel_residual) + "); " +
                                  std::to_string(static_cast<long long>(
                                      nonconverged_since_warning_)) +
                                  " non-converged steps since the last warning, " +
                                  std::to_string(static_cast<long long>(nonconverged_total_)) +
                                  " in all");
      last_warning_step_ = step;
      nonconverged_since_warning_ = 0;
    }
  }
  stats_[V_NONCONVERGED] = static_cast<double>(nonconverged_total_);
}

/* ----------------------------------------------------------------------
   the SPOOK step: contacts, solve, velocities
------------------------------------------------------------------------- */

void FixFibreContact::final_integrate()
{
  check_finite("position", atom->x, 3);
  check_finite("force", atom->f, 3);
  check_finite("torque", atom->torque, 3);
  check_finite("velocity", atom->v, 3);
  check_finite("angular velocity", atom->omega, 3);

  std::vector<fibre::Body> bodies;
  build_bodies(bodies);

  std::vector<Found> found;
  detect_pair_contacts(bodies, found);
  detect_wall_contacts(bodies, found);
  std::sort(found.begin(), found.end(), [](const Found &p, const Found &q) {
    if (p.tag_a != q.tag_a) return p.tag_a < q.tag_a;
    if (p.partner != q.partner) return p.partner < q.partner;
    return p.contact.gap < q.contact.gap;
  });

  // global figures: contacts, wall contacts, deepest overlap, lightest atom
  double local_sum[2] = {double(found.size()), 0.0};
  double local_max[2] = {0.0, -1e300};
  for (const Found &fc : found) {
    if (fc.contact.is_wall()) local_sum[1] += 1.0;
    local_max[0] = std::max(local_max[0], -fc.contact.gap);
  }
  for (int k = 0; k < exchange_->num_owned(); ++k)
    local_max[1] = std::max(local_max[1], -bodies[k].mass);
  MPI_Allreduce(MPI_IN_PLACE, local_sum, 2, MPI_DOUBLE, MPI_SUM, world);
  MPI_Allreduce(MPI_IN_PLACE, local_max, 2, MPI_DOUBLE, MPI_MAX, world);
  stats_[V_CONTACTS] = local_sum[0];
  stats_[V_WALL_CONTACTS] = local_sum[1];
  stats_[V_OVERLAP] = local_max[0];
  if (local_max[1] > -1e300) last_m_min_ = -local_max[1];

  const bool do_export = export_every_ > 0 && update->ntimestep % export_every_ == 0;
  if (local_sum[0] == 0.0) {
    // nothing touches anywhere: free flight
    update_velocities(nullptr);
    for (int i = 0; i < atom->nlocal; ++i) nslot_[i] = 0;
    fill_local_output(found, nullptr);
    stats_[V_ITER] = stats_[V_RESID] = stats_[V_FIBRES] = stats_[V_FIBRE_FRACTION] = 0.0;
    stats_[V_PASSES] = stats_[V_SETUP] = stats_[V_SOLVE] = 0.0;
    stats_[V_CONVERGED] = 1.0;
    if (do_export) {
      fibre::ContactSystem empty(bodies, {}, rows_, fibre::SpookParams{dtv_, damping_},
                                 exchange_->num_owned());
      export_system(empty, found, nullptr);
    }
    check_finite("velocity", atom->v, 3);
    return;
  }

  set_compliance(found, bodies);
  fibre::Vector warm;
  warm_start(found, rows_, warm);

  std::vector<fibre::Contact> contacts;
  contacts.reserve(found.size());
  for (const Found &fc : found) contacts.push_back(fc.contact);

  fibre::SpookParams params;
  params.h = dtv_;
  params.damping = damping_;
  fibre::StepResult res;
  std::unique_ptr<fibre::ContactSystem> sys;
  try {
    sys = std::make_unique<fibre::ContactSystem>(std::move(bodies), std::move(contacts), rows_,
                                                 params, exchange_->num_owned());
    res = fibre::solve_step(*sys, *exchange_, opt_, &warm, world);
  } catch (std::exception &e) {
    error->one(FLERR, std::string("Fix fibre_contact: contact solver failed at step ") +
                          std::to_string(static_cast<long long>(update->ntimestep)) + ": " +
                          e.what());
  }

  // a non-finite solution is replaced by free flight for this step (the state stays finite)
  const int nowned = exchange_->num_owned();
  bool finite = res.dv.size() >= 6 * Eigen::Index(nowned) && res.lambda.allFinite() &&
                res.dv.head(6 * Eigen::Index(nowned)).allFinite();
  int bad = finite ? 0 : 1;
  MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT, MPI_MAX, world);
  if (bad) {
    res.converged = false;
    res.reason = fibre::StopReason::non_finite;
    res.lambda = fibre::Vector::Zero(sys->contact_dofs());
    if (comm->me == 0)
      error->warning(FLERR, "Fix fibre_contact: the contact solve at step " +
                                std::to_string(static_cast<long long>(update->ntimestep)) +
                                " gave non-finite impulses; the step ignores the contacts");
  }

  update_velocities(bad ? nullptr : &res.dv);
  store_impulses(found, *sys, res.lambda);
  fill_local_output(found, &res.lambda);
  report_solve(res);
  if (do_export) export_system(*sys, found, &res.lambda);

  if (overflow_count_ > 0 && !overflow_warned_ && comm->me == 0) {
    error->warning(FLERR, "Fix fibre_contact: more than " + std::to_string(kMaxSlots) +
                              " contacts stored on one atom; the rest start cold next step");
    overflow_warned_ = true;
  }

  check_finite("velocity", atom->v, 3);
  check_finite("angular velocity", atom->omega, 3);
}

/* ---------------------------------------------------------------------- */

double FixFibreContact::compute_vector(int n)
{
  if (n < 0 || n >= V_SIZE) return 0.0;
  return stats_[n];
}

/* ----------------------------------------------------------------------
   global restart state: counters and the last step's figures
------------------------------------------------------------------------- */

void FixFibreContact::write_restart(FILE *fp)
{
  double list[2 + V_SIZE];
  list[0] = kRestartFormat;
  list[1] = static_cast<double>(nonconverged_total_);
  for (int k = 0; k < V_SIZE; ++k) list[2 + k] = stats_[k];
  if (comm->me == 0) {
    const int size = static_cast<int>(sizeof(list));
    std::fwrite(&size, sizeof(int), 1, fp);
    std::fwrite(list, sizeof(double), 2 + V_SIZE, fp);
  }
}

void FixFibreContact::restart(char *buf)
{
  const double *list = reinterpret_cast<const double *>(buf);
  if (list[0] != kRestartFormat) {
    error->warning(FLERR, std::string("Fix fibre_contact: restart data of another format ignored"));
    return;
  }
  nonconverged_total_ = static_cast<bigint>(list[1]);
  for (int k = 0; k < V_SIZE; ++k) stats_[k] = list[2 + k];
}

/* ----------------------------------------------------------------------
   per-atom warm-start storage
------------------------------------------------------------------------- */

void FixFibreContact::grow_arrays(int nmax)
{
  memory->grow(nslot_, nmax, "fibre_contact:nslot");
  memory->grow(slots_, nmax, kMaxSlots * kSlotSize, "fibre_contact:slots");
  for (int i = nslot_max_; i < nmax; ++i) nslot_[i] = 0;
  nslot_max_ = nmax;
}

void FixFibreContact::copy_arrays(int i, int j, int /*delflag*/)
{
  nslot_[j] = nslot_[i];
  std::copy(slots_[i], slots_[i] + nslot_[i] * kSlotSize, slots_[j]);
}

void FixFibreContact::set_arrays(int i)
{
  nslot_[i] = 0;
}

int FixFibreContact::pack_exchange(int i, double *buf)
{
  int m = 0;
  buf[m++] = nslot_[i];
  for (int k = 0; k < nslot_[i] * kSlotSize; ++k) buf[m++] = slots_[i][k];
  return m;
}

int FixFibreContact::unpack_exchange(int nlocal, double *buf)
{
  int m = 0;
  const int n = std::min(kMaxSlots, std::max(0, static_cast<int>(buf[m++])));
  nslot_[nlocal] = n;
  for (int k = 0; k < n * kSlotSize; ++k) slots_[nlocal][k] = buf[m++];
  return m;
}

int FixFibreContact::pack_restart(int i, double *buf)
{
  // buf[0] = number of values including itself, as other fixes read it
  int m = 1;
  buf[m++] = nslot_[i];
  for (int k = 0; k < nslot_[i] * kSlotSize; ++k) buf[m++] = slots_[i][k];
  buf[0] = m;
  return m;
}

void FixFibreContact::unpack_restart(int nlocal, int nth)
{
  double **extra = atom->extra;
  int m = 0;
  for (int k = 0; k < nth; ++k) m += static_cast<int>(extra[nlocal][m]);
  const int count = static_cast<int>(extra[nlocal][m]);
  m++;
  int n = static_cast<int>(extra[nlocal][m++]);
  n = std::min(kMaxSlots, std::max(0, std::min(n, (count - 2) / kSlotSize)));
  nslot_[nlocal] = n;
  for (int k = 0; k < n * kSlotSize; ++k) slots_[nlocal][k] = extra[nlocal][m++];
}

int FixFibreContact::size_restart(int i)
{
  return 2 + nslot_[i] * kSlotSize;
}

int FixFibreContact::maxsize_restart()
{
  return 2 + kMaxSlots * kSlotSize;
}

/* ----------------------------------------------------------------------
   halo communication for the Exchange (6 values per atom)
------------------------------------------------------------------------- */

int FixFibreContact::pack_forward_comm(int n, int *list, double *buf, int /*pbc_flag*/,
                                       int * /*pbc*/)
{
  return exchange_->pack_forward(n, list, buf);
}

void FixFibreContact::unpack_forward_comm(int n, int first, double *buf)
{
  exchange_->unpack_forward(first, n, buf);
}

int FixFibreContact::pack_reverse_comm(int n, int first, double *buf)
{
  return exchange_->pack_reverse(first, n, buf);
}

void FixFibreContact::unpack_reverse_comm(int n, int *list, double *buf)
{
  exchange_->unpack_reverse(n, list, buf);
}

/* ---------------------------------------------------------------------- */

double FixFibreContact::memory_usage()
{
  double bytes = double(nslot_max_) * (sizeof(int) + sizeof(double) * kMaxSlots * kSlotSize);
  bytes += double(maxlocal_) * kLocalColumns * sizeof(double);
  bytes += double(atom_body_.capacity()) * sizeof(int);
  return bytes;
}
