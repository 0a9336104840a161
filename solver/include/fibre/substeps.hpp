// The contact solve of one step in substeps (ContactModel::substeps, doc/design.md section 2,
// "Substeps"): detection, the contact history and the reports stay at the step h, set by the
// motion, while the impulses, the bodies' velocities, the contacts' gaps and the elastic rows'
// springs advance in n substeps of h / n. At a step longer than the collision time t_c a
// collisional flow's contacts otherwise act as enduring ones (SPOOK relaxes a contact over
// d steps, not over t_c), and its heaps come out steeper; n substeps of about t_c / 3 give
// the law's heap at a fraction of the cost of n steps (the step's fixed work is done once).
#pragma once

#include <functional>
#include <vector>

#include "fibre/contact_model.hpp"
#include "fibre/exchange.hpp"
#include "fibre/spook.hpp"
#include "fibre/step_solver.hpp"

namespace fibre {

// The substeps of a step h: ContactModel::substeps where it is typed (> 0), else (automatic)
// the fewest whose length is at most substep_collisions times t_c, the shortest collision time
// of the material's type pairs (t_c <= 0: no elastic law, one substep), at most kMaxSubsteps.
inline constexpr int kMaxSubsteps = 1000;
int substeps_for(const ContactModel &model, double h, double t_c);

// What the substeps before the last one did. The caller builds the last substep's system from
// the bodies and contacts that run_substeps left, solves it as a plain step (its impulses and
// springs go to the contact history) and adds it in.
struct Substeps {
  int done = 0;      // substeps run (n - 1, or fewer where a solve gave no result)
  Vector dv;         // their contact velocity changes, summed (owned bodies and ghosts)
  Vector path;       // the bodies' velocities after each of them, summed (6 per body)
  Vector lambda;     // their impulses, summed (rows per contact)
  ContactWork work;  // their contacts' work, summed (this process's contacts)
  StepResult totals; // their sweeps, iterations and seconds, summed; converged if all were
};

// The solve of one substep's system from a warm start (a front end's: collective, it reports
// failures); a result without dv ends the substeps.
using SubstepSolve = std::function<StepResult(ContactSystem &, const Vector &warm)>;

// Runs substeps 1 .. n - 1 of length params.h (h / n) on `bodies` and `contacts` in place:
// each applies the contact model (compliances and restitution from the last substep's
// impulses), solves, and moves the bodies to their velocities after it, the gaps by
// params.h G v+ (normals and contact points held for the step) and the elastic rows to their
// advanced springs. `warm` is the first substep's warm start; on return it is the last run
// substep's impulses, the next one's warm start. num_owned: the bodies [0, num_owned) owned
// here (ContactSystem). Collective.
Substeps run_substeps(int n, const ContactModel &model, const SpookParams &params, double m_min,
                      const Exchange &ex, int num_owned, std::vector<Body> &bodies,
                      std::vector<Contact> &contacts, Vector &warm, const SubstepSolve &solve);

// Adds a later solve's counts and seconds to `into` (sweeps, iterations, seconds; the larger
// error estimate and complementarity residual; converged only if both were).
void add_solve(StepResult &into, const StepResult &more);

} // namespace fibre
