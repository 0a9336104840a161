// One SPOOK step's contact solve: preconditioner setup, linear solve in either form, and the
// bounded active-set loop for lambda_n >= 0, Coulomb friction and rolling/twisting
// resistance (design.md section 2). This is what the LAMMPS fix calls every step.
#pragma once

#include <mpi.h>

#include <string>

#include "fibre/krylov.hpp"
#include "fibre/preconditioners.hpp"

namespace fibre {

enum class SolverKind { uzawa, cr, minres, direct };
const char *to_string(SolverKind s);
bool parse_solver(const std::string &s, SolverKind &k);

struct FrictionParams {
  double mu = 0.5;        // Coulomb: |lambda_t| <= mu lambda_n
  double mu_roll = 0.0;   // rolling: |lambda_roll| <= mu_roll r_eff lambda_n
  double mu_twist = 0.0;  // twisting: |lambda_twist| <= mu_twist r_eff lambda_n
};

struct StepOptions {
  Form form = Form::body;
  SolverKind solver = SolverKind::minres;
  PrecondOptions precond{};
  StopControl stop{};
  FrictionParams friction{};
  int active_set_max = 5;  // K: passes of the active-set loop
};

struct StepResult {
  Vector lambda;          // final, feasible impulses (rows per contact)
  Vector dv;              // velocity change from the contacts, M^-1 G^T lambda (owned bodies)
  int iterations = 0;     // Krylov iterations of the last linear solve
  int total_iterations = 0;
  double rel_residual = 0;  // of the last linear solve
  StopReason reason = StopReason::converged;
  bool converged = true;    // every linear solve converged
  int active_set_passes = 0;
  int released = 0;         // contacts released (lambda_n < 0)
  int capped = 0;           // friction rows capped on their cone
  FibreStats fibres;
  double setup_seconds = 0;
  double solve_seconds = 0;
};

// Solves the contact problem of `sys`. Its bodies must hold the step's velocities and
// external forces, complete on ghosts; the rhs (spook_rhs) and the row mask are set here.
// `warm` (optional, rows per contact) is the warm start. `comm` is the communicator the
// direct solver (MUMPS) runs on; the body numbering across processes comes from
// global_body_index().
StepResult solve_step(ContactSystem &sys, const Exchange &ex, const StepOptions &opt,
                      const Vector *warm, MPI_Comm comm);

}  // namespace fibre
