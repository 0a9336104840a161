// Matrix-free kernels on a ContactSystem (thesis 2.5.2): G is never formed.
//
// Contact-space vectors have rows() entries per contact; body-space vectors have 6 entries
// per body (owned bodies first, then ghosts). Every kernel here is local: it touches only
// this process's data; the operators in operators.hpp add the halo exchange.
#pragma once

#include "fibre/core/system.hpp"

namespace fibre {

// out = G w (local: w must be complete on ghosts).
void g_apply(const ContactSystem &sys, const Vector &w, Vector &out);
// out = G^T lambda, accumulated per body (local: ghosts hold partial sums).
void gt_apply(const ContactSystem &sys, const Vector &lambda, Vector &out);

// Fused local products for the operators: out = G w + Sigma x, and out = G^T Sigma^-1 G w
// accumulated per body (w complete on ghosts; ghosts of out hold partial sums).
void g_sigma_apply(const ContactSystem &sys, const Vector &w, const Vector &x, Vector &out);
void gt_sigma_inv_g_apply(const ContactSystem &sys, const Vector &w, Vector &out);

// The Jacobian block of contact c for its body a (side 0) or b (side 1): rows() x 6, padded
// with zero rows to 6x6. Masked rows are zero.
Mat6 jacobian_block(const ContactSystem &sys, int c, int side);

// Diagonal 6x6 block of A for contact c: sum over its bodies of G_cj M_j^-1 G_cj^T + Sigma_c.
// Rows/columns beyond rows() are identity.
Mat6 diagonal_block(const ContactSystem &sys, int c);
// Its diagonal alone, from the rows' structure (about 10x cheaper than the block): what the
// sweeps' row scales and the active set's trial impulses need every step. split_a, split_b
// multiply the bodies' inverse masses (the sweeps' mass splitting across processes, pgs.hpp).
Vec6 diagonal_entries(const ContactSystem &sys, int c, double split_a = 1.0, double split_b = 1.0);
// Coupling block A_cd = sum over bodies j shared by c and d of G_cj M_j^-1 G_dj^T
// (rows() x rows() in the top-left corner, zero elsewhere). Zero if they share no body.
Mat6 coupling_block(const ContactSystem &sys, int c, int d);

// Body-space blocks of K = M + G^T Sigma^-1 G.
// Diagonal block of body i: M_i + sum over contacts c at i of G_ci^T Sigma_c^-1 G_ci.
// Contacts on ghost bodies contribute only locally.
std::vector<Mat6> body_diagonal_blocks(const ContactSystem &sys);
// Off-diagonal block K_ab = G_ca^T Sigma_c^-1 G_cb of a body-body contact c.
Mat6 body_coupling_block(const ContactSystem &sys, int c);

} // namespace fibre
