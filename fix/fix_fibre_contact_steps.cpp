/* ----------------------------------------------------------------------
   fix fibre_contact: the step's schedule (the substeps per step against the law's collision
   time, the bounce and impact speeds, the SPOOK parameters of a solve, and the substeps' path
   that the next step's positions follow). The step itself is in fix_fibre_contact.cpp.
------------------------------------------------------------------------- */

#include "fix_fibre_contact.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "fibre/core/text.hpp"
#include "fibre/step/substeps.hpp"
#include "host.h"
#include "lammps_exchange.h"

using namespace LAMMPS_NS;
using fibre_lmp::logmesg;

// The lightest body and the smallest radius of the group over all processes (automatic
// compliance and recovery speed); the last values stand while the group is empty. With them,
// in the same reduction, the largest free speed of the step (fastest_).
void FixFibreContact::smallest_body(const std::vector<fibre::Body> &bodies)
{
  double m[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                 0.0};
  for (int k = 0; k < exchange_->num_owned(); ++k) {
    m[0] = std::min(m[0], bodies[k].mass);
    m[1] = std::min(m[1], bodies[k].radius);
    m[2] = std::min(m[2], -fibre::free_speed(bodies[k], dtv_));
  }
  MPI_Allreduce(MPI_IN_PLACE, m, 3, MPI_DOUBLE, MPI_MIN, world);
  if (std::isfinite(m[0])) m_min_ = m[0];
  if (std::isfinite(m[1])) r_min_ = m[1];
  fastest_ = -m[2];
}

// Whether this solve is the first over several steps to meet a moving wall (on any process):
// from it on, such solves take substeps of at most kEveryMovingCollisions t_c (step_substeps),
// every one and not only those that meet the wall, since the grains a blade throws strike
// others in solves without it (LAMMPS's mixer with the substeps only there: highest grain
// 12.8 +- 2.9 over five seeds, against 10.6 +- 1.6 with them in every one and native's 11.5
// +- 0.7). Collective.
bool FixFibreContact::note_moving_walls(const std::vector<fibre::Contact> &contacts)
{
  if (moving_walls_met_ || !(h_ > dtv_)) return false;
  const bool local = std::any_of(contacts.begin(), contacts.end(),
                                 [](const fibre::Contact &c) { return c.wall_moves(); });
  moving_walls_met_ = exchange_->max(local ? 1.0 : 0.0) > 0.0;
  return moving_walls_met_;
}

// The contact solve's substeps this step (fibre::substeps_for: automatic from the law's
// shortest collision time for two spheres of the group's smallest radius and mass at 1 velocity
// unit), alike on every process. Logged once per step size and count, with the step against
// that collision time, the number that says whether the step resolves the collisions of a flow
// (doc page, "Time step and stiff materials"). A solve over several steps, once a solve has met
// a moving wall, takes substeps of at most kEveryMovingCollisions t_c (note_moving_walls).
int FixFibreContact::step_substeps()
{
  fibre::PairCollisionTime shortest{};
  if (settings_.model.compliance.material && m_min_ > 0 && r_min_ > 0)
    shortest = fibre::shortest_collision_time(settings_.model.materials, r_min_, m_min_, 1.0);
  settings_.model.collision_time = shortest.t_c;
  settings_.model.solve_step = h_;
  const fibre::ContactModel &model = settings_.model;
  const bool moving = moving_walls_met_ && h_ > dtv_;
  const double cap = moving ? fibre::kEveryMovingCollisions : INFINITY;
  const int n = fibre::substeps_for(model, h_, shortest.t_c, cap);
  if ((h_ == step_logged_ && n == substeps_logged_) || !(shortest.t_c > 0)) return n;
  step_logged_ = h_;
  substeps_logged_ = n;
  if (comm->me != 0) return n;
  const auto g = [](double x) { return fibre::format_g(x); };
  const double per = h_ / n / shortest.t_c;
  const std::string solve = h_ == dtv_ ? "the step " + g(dtv_)
                                       : "the contact solve's step " + g(h_) + " (" + g(h_ / dtv_) +
                                             " steps of " + g(dtv_) + ": contact_every)";
  std::string text =
      "fix fibre_contact: " + solve + " is " + g(h_ / shortest.t_c) +
      " collision times of the pair style's law (t_c " + g(shortest.t_c) +
      ": two spheres of the smallest radius " + g(r_min_) + " and mass " + g(m_min_) +
      " meeting at 1 velocity unit, type pair " + std::to_string(shortest.i) + " " +
      std::to_string(shortest.j) + "); the contact solve takes " + std::to_string(n) +
      (n == 1 ? " substep" : " substeps") + " of " + g(per) + " t_c (substeps " +
      (model.substeps > 0 ? std::to_string(model.substeps)
                          : "auto, at most " + g(std::min(model.substep_collisions, cap)) +
                                " t_c each" + (moving ? ": a moving wall met" : "")) +
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
  return v > 0 ? v : model.recovery_radii * r_min_ / h_;
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
  const fibre::SpookParams step{h_, settings_.model.damping};
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

// The SPOOK parameters of a solve of step h.
fibre::SpookParams FixFibreContact::step_params(const std::vector<fibre::Body> &bodies,
                                                double h) const
{
  const fibre::ContactModel &model = settings_.model;
  fibre::SpookParams p{h, model.damping, model.max_recovery(h, r_min_)};
  p.bounce_speed = bounce_speed(bodies, h);
  p.penetration_floor = recovering_ ? fibre::kPenetrationFloor : fibre::kPenetrationStart;
  return p;
}
