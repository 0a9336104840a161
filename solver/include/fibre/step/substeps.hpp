// The contact solve of one step in substeps (ContactModel::substeps, doc/design.md section 2,
// "Substeps"): detection, the contact history and the reports stay at the step h, set by the
// motion, while the impulses, the bodies' velocities, the contacts' gaps and the elastic rows'
// springs advance in n substeps of h / n. At a step longer than the collision time t_c a
// collisional flow's contacts otherwise act as enduring ones (SPOOK relaxes a contact over
// d steps, not over t_c), and its heaps come out steeper; n substeps of about t_c / 3 give
// the law's heap at a fraction of the cost of n steps (the step's fixed work is done once).
#pragma once

#include <cmath>
#include <functional>
#include <vector>

#include "fibre/algebra/spook.hpp"
#include "fibre/core/exchange.hpp"
#include "fibre/model/contact_model.hpp"
#include "fibre/step/step_solver.hpp"

namespace fibre {

// The substeps of a step h: ContactModel::substeps where it is typed (> 0), else (automatic)
// the fewest whose length is at most substep_collisions (and at most `cap`) times t_c, the
// shortest collision time of the material's type pairs (t_c <= 0: no elastic law, one
// substep), at most kMaxSubsteps.
inline constexpr int kMaxSubsteps = 1000;
int substeps_for(const ContactModel &model, double h, double t_c, double cap = INFINITY);

// Whether some contact moves within the step (step.h, SPOOK's damping step.damping): its
// surfaces slide, roll, press or part at more than `speed` where they touch or will within the
// reach of the contact's SPOOK row, h (1 + 4 d) / 4 of their approach speed. A step without
// (a pile at rest, spheres in free flight) has no collision for substeps to resolve
// (substep_when moving). Local: a front end takes the answer of every process.
bool step_moves(const std::vector<Body> &bodies, const std::vector<Contact> &contacts,
                const SpookParams &step, double speed);

// What a step's substeps did: the last one's system and solve, and the sums over all.
struct Substeps {
  // The last substep's system (its bodies at that substep's start) and solve; the step's
  // contact history takes its impulses and springs. A solve without dv ended the substeps (a
  // front end's failure): then the step ignores its contacts, and nothing below it is set.
  ContactSystem system;
  StepResult result;
  Vector warm;   // the last substep's warm start
  Vector v_plus; // the bodies' velocities after it (owned bodies and ghosts)
  std::vector<std::array<double, kMaxRows>> springs; // its advanced springs (compliance material)
  int done = 0;                                      // substeps run
  Vector dv;         // the contacts' velocity changes, summed (owned bodies and ghosts)
  Vector path;       // the bodies' velocities after each substep, summed (6 per body)
  Vector lambda;     // the impulses, summed (rows per contact)
  ContactWork work;  // the contacts' work, summed (this process's contacts)
  StepResult totals; // sweeps, iterations and seconds, summed; converged if all were
};

// The solve of one substep's system from a warm start (a front end's: collective, it reports
// failures); `last`: the step's last substep; `cache`: the sweeps' groups, kept from substep to
// substep (solve_step). A result without dv ends the substeps.
using SubstepSolve =
    std::function<StepResult(ContactSystem &, const Vector &warm, bool last, SweepCache &cache)>;

// Runs the n substeps of length params.h (h / n) on one system built from `bodies` and
// `contacts`: each applies the contact model (compliances and restitution from the last
// substep's impulses), solves, and, before the last, moves the bodies to their velocities after
// it, the gaps by params.h G v+ (normals and contact points held for the step) and the elastic
// rows to their advanced springs. `warm` is the first substep's warm start, the last
// substep's impulses the next one's. num_owned: the bodies [0, num_owned) owned here
// (ContactSystem). Collective. With n = 1 it is the plain step.
Substeps run_substeps(int n, const ContactModel &model, const SpookParams &params, double m_min,
                      const Exchange &ex, int num_owned, std::vector<Body> bodies,
                      std::vector<Contact> contacts, Vector warm, const SubstepSolve &solve);

// The reference of a step's check (Settings::check_every, keyword check): the step's own
// options, its substeps' sweeps run on to an error estimate of kCheckAccuracy, at most
// kCheckSweeps a substep. run_substeps with these from the step's start gives the converged
// step, against which step_accuracy (nonsmooth_reference.hpp) measures the run's summed
// impulses: the substeps share the step's G and M.
inline constexpr double kCheckAccuracy = 1e-10;
inline constexpr int kCheckSweeps = 20000;
StepOptions check_options(const StepOptions &step);

// Adds a later solve's counts and seconds to `into` (sweeps, iterations, seconds; the larger
// error estimate and complementarity residual; converged only if both were).
void add_solve(StepResult &into, const StepResult &more);

} // namespace fibre
