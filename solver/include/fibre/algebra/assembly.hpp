// Explicit assembly of the contact system's matrices. This is the only place where G is
// formed: the solvers are matrix-free (kernels.hpp); the assembled matrices serve MUMPS, the
// spectra, Matrix Market export and tests.
//
// Everything is local to this process: columns cover its bodies (owned, then ghosts), rows its
// contacts. On one process that is the whole system.
#pragma once

#include <Eigen/Sparse>
#include <vector>

#include "fibre/core/system.hpp"

namespace fibre {

using SparseMatrix = Eigen::SparseMatrix<double>; // column major

// G: rows() rows per contact, 6 columns per body (thesis eq. 2.1.1); masked rows are empty.
SparseMatrix assemble_G(const ContactSystem &sys);

// Diagonals of M^-1 (6 per body) and of Sigma (rows() per contact; 1 on masked rows).
Vector assemble_inv_mass(const ContactSystem &sys);
Vector assemble_sigma(const ContactSystem &sys);

// A = G M^-1 G^T + Sigma, both triangles stored. With `owners` (Exchange::local_owners(): a
// body per local body, empty for none) a periodic image's columns of G are its body's, so the
// contacts on a body and on its image couple as they do through the one body.
SparseMatrix assemble_A(const ContactSystem &sys, const std::vector<int> &owners = {});

// K = M + G^T Sigma^-1 G, both triangles stored. M enters on owned bodies only, so ghost
// rows and columns hold this process's contact terms alone (partial sums for the owner).
SparseMatrix assemble_K(const ContactSystem &sys);

// b = -(4/h) Upsilon g - (1 - Upsilon) G v - h G M^-1 f_ext with the assembled G (doc/design.md
// section 2), Upsilon per contact (Contact::damping), moving walls as body b with a prescribed
// velocity (+ (1 - Upsilon) wall_rows); g enters on active normal rows only. No
// restitution: spook_rhs's impact law is not assembled here.
Vector assemble_rhs(const ContactSystem &sys);

// The upper triangle (row <= col) of a symmetric matrix as triplets, for MUMPS (SYM = 1).
void upper_triplets(const SparseMatrix &S, std::vector<long> &rows, std::vector<long> &cols,
                    std::vector<double> &values);

} // namespace fibre
