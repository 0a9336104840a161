// The direct solver (doc/design.md section 4): MUMPS on an assembled sparse SPD matrix,
// distributed over the ranks of an MPI communicator. It is the reference solution of the
// Krylov methods and a `solver` choice of its own.
//
// MUMPS stays behind this header (no dmumps_c.h here): the library links it privately.
#pragma once

#include <mpi.h>

#include <memory>
#include <stdexcept>
#include <vector>

#include "fibre/algebra/operators.hpp"

namespace fibre {

// A MUMPS failure; what() carries INFOG(1), INFOG(2) and their meaning.
class DirectSolverError : public std::runtime_error {
 public:
  DirectSolverError(const std::string &what, int infog1, int infog2)
      : std::runtime_error(what), infog1_(infog1), infog2_(infog2)
  {
  }
  int infog1() const { return infog1_; }
  int infog2() const { return infog2_; }

 private:
  int infog1_, infog2_;
};

// Distributed symmetric positive definite factorization (MUMPS, SYM = 1, distributed
// assembled input ICNTL(18) = 3). Every call is collective over the communicator.
//
// Entries: every rank passes its own triplets with GLOBAL 0-based indices. An off-diagonal
// pair (i, j)/(j, i) must be given once, in either triangle (it is moved to the upper one);
// duplicates, also across ranks, are summed. Right-hand sides are summed across ranks in the
// same way; each rank then asks for the solution entries it needs.
class DistributedCholesky {
 public:
  explicit DistributedCholesky(MPI_Comm comm);
  ~DistributedCholesky();
  DistributedCholesky(const DistributedCholesky &) = delete;
  DistributedCholesky &operator=(const DistributedCholesky &) = delete;

  // Analysis and numerical factorization of the global n x n matrix. Throws
  // DirectSolverError (e.g. not positive definite, out of memory) and std::invalid_argument
  // (indices out of range, sizes that MUMPS's 32-bit indices cannot hold).
  void factorize(long n, const std::vector<long> &rows, const std::vector<long> &cols,
                 const std::vector<double> &values);

  // Solves with the rhs whose entries (global index, value) are summed over all ranks and
  // returns the solution at `wanted` (global indices, any order, repeats allowed).
  std::vector<double> solve(const std::vector<long> &rhs_index,
                            const std::vector<double> &rhs_value, const std::vector<long> &wanted);

  long size() const { return n_; }
  bool factorized() const { return factorized_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  long n_ = 0;
  bool factorized_ = false;
};

// The direct solve of one contact system: returns lambda (rows per contact, this process's
// contacts) for A lambda = b, A = G M^-1 G^T + Sigma.
//
// One rank (MPI_COMM_SELF or a communicator of size 1): Form::contact factors A itself;
// Form::body factors K = M + G^T Sigma^-1 G, solves K dv = G^T Sigma^-1 b and returns
// lambda = Sigma^-1 (b - G dv).
// Several ranks: always the body form, distributed: the unknowns are the bodies in the
// numbering of global_body_index(); every rank adds its contacts' G^T Sigma^-1 G blocks (ghost
// bodies included) and its owned bodies' M. The contact form is solved this way too: both give
// the same lambda = Sigma^-1 (b - G dv), and contacts, unlike bodies, have no global numbering
// shared with the halo. Collective over `comm`; `ex` must span the same processes.
Vector direct_solve(Form form, const ContactSystem &sys, const Exchange &ex, const Vector &b,
                    MPI_Comm comm);

// The reference velocity change of tools and benchmarks (one process): dv* solving
// K dv = G^T Sigma^-1 rhs with MUMPS, plus one step of iterative refinement with the same
// factors. `refinement` (optional) receives ||correction|| / ||dv*||.
Vector refined_body_solution(const ContactSystem &sys, double *refinement = nullptr);

} // namespace fibre
