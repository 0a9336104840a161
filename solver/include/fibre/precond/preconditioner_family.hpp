// The preconditioner family of doc/design.md section 3 in both forms, and its factory.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "fibre/algebra/operators.hpp"
#include "fibre/precond/fibres.hpp"
#include "fibre/precond/preconditioner.hpp"

namespace fibre {

// What each kind inverts exactly (all symmetric positive definite; setup and apply are
// O(contacts), factors in flat arrays, no global matrix is formed):
//   contact form (rows() entries per contact, A = G M^-1 G^T + Sigma):
//     jacobi  diag(A);
//     block   the rows x rows diagonal block of A of every contact;
//     fibre   the principal submatrix of A on the contacts of every fibre (block tridiagonal,
//             block Thomas / LDL^T), diagonal blocks for contacts in no fibre;
//     tree    the principal submatrix of A on the spanning forest's contacts and all wall
//             contacts, by leaves-first elimination of the tree-shaped augmented system
//             [-M -G^T; -G Sigma] (bodies and contacts as nodes); diagonal blocks elsewhere.
//             Round-off grows like eps ||A|| / Sigma, as for any factorization of A.
//   body form (6 entries per body, K = M + G^T Sigma^-1 G; owned bodies only, ghost entries of
//   the result are 0; the diagonal blocks are summed over processes through the Exchange):
//     jacobi  diag(K);  block  the 6x6 body blocks;
//     fibre   the body blocks and K(i, j) for consecutive bodies of a fibre (chords dropped);
//     tree    the body blocks and K(i, parent(i)) of the spanning forest (Cholesky, no fill).
// Fibres and forests use this process's contacts; contact-form chains may pass through ghost
// bodies, body-form ones never do. apply() is not reentrant (it uses a work vector).
enum class PrecondKind { none, jacobi, block, fibre, tree };
template <> struct EnumNames<PrecondKind> {
  static constexpr EnumName<PrecondKind> table[] = {{PrecondKind::none, "none"},
                                                    {PrecondKind::jacobi, "jacobi"},
                                                    {PrecondKind::block, "block"},
                                                    {PrecondKind::fibre, "fibre"},
                                                    {PrecondKind::tree, "tree"}};
};

struct PrecondOptions {
  PrecondKind kind = PrecondKind::block;
  EdgeWeight weight = EdgeWeight::z;
  // Last step's normal impulse per contact (size num_contacts), for EdgeWeight::impulse.
  const Vector *impulses = nullptr;
};

// Builds the preconditioner for `form` on `sys`. For fibre/tree the fibres or forest are
// built here from this process's own contacts; `stats` (optional) receives their figures
// (for tree: the trees of the forest, read as fibres; zero for the other kinds). In body form
// every process must call this (the diagonal blocks take collective exchanges). Throws
// std::runtime_error if a pivot block is not positive definite (non-finite input).
std::unique_ptr<Preconditioner> make_preconditioner(Form form, const ContactSystem &sys,
                                                    const Exchange &ex, const PrecondOptions &opt,
                                                    FibreStats *stats = nullptr);

} // namespace fibre
