// Report: Krylov iterations to a relative velocity error of 1e-6, per form x preconditioner x
// method, on the 400-sphere pile poured by native LAMMPS (tests/data/pile400.dump) with Sigma
// scaled relative to G M^-1 G^T (doc/design.md section 7).
//
// sigma_rel = sigma / mean(diag(G M^-1 G^T)) takes 1e-12 .. 1e-4. Two right-hand sides:
// the SPOOK rhs with its gap term (inconsistent gaps put part of b into null(G^T)), and the
// same rhs without the gap term (b = -G w, inside range(G)).
//
// Reference velocities: the body form K dv = G^T Sigma^-1 b solved by a sparse Cholesky of K
// assembled from the kernel blocks, plus one step of refinement with the matrix-free operator.
// When G has full column rank, cond(K) stays near kappa(G^T M^-1 G) whatever sigma is; the
// contact form instead carries a 1/sigma-sized lambda component in null(G^T) that G^T must
// cancel in floating point, so its velocities cannot be more accurate than about
// eps / sigma_rel * ||b_null|| / ||b|| (the MUMPS contact-form column shows that floor).
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "fibre/algebra/spook.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/precond/preconditioner_family.hpp"
#include "fibre/scenes.hpp"
#include "fibre/solvers/direct.hpp"
#include "fibre/solvers/krylov.hpp"

using namespace fibre;

namespace {

constexpr int kBodies = 400;
constexpr int kMaxIter = 2000;
constexpr double kTarget = 1e-6;
const double kSigmaRel[] = {1e-12, 1e-10, 1e-8, 1e-6, 1e-4};
const PrecondKind kPreconds[] = {PrecondKind::none, PrecondKind::jacobi, PrecondKind::block,
                                 PrecondKind::fibre, PrecondKind::tree};
const Method kMethods[] = {Method::cg, Method::cr, Method::minres};

using Sparse = Eigen::SparseMatrix<double>;

// K = M + G^T Sigma^-1 G from the body blocks of kernels.hpp.
Sparse assemble_body_matrix(const ContactSystem &sys)
{
  std::vector<Eigen::Triplet<double>> t;
  const std::vector<Mat6> diag = body_diagonal_blocks(sys);
  auto add = [&](int bi, int bj, const Mat6 &B) {
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c)
        if (B(r, c) != 0) t.emplace_back(6 * bi + r, 6 * bj + c, B(r, c));
  };
  for (int i = 0; i < sys.num_bodies(); ++i) add(i, i, diag[i]);
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    if (k.is_wall()) continue;
    const Mat6 B = body_coupling_block(sys, c);
    add(k.a, k.b, B);
    add(k.b, k.a, B.transpose());
  }
  Sparse K(sys.body_dofs(), sys.body_dofs());
  K.setFromTriplets(t.begin(), t.end());
  return K;
}

double mean_schur_diagonal(const ContactSystem &sys)
{
  double sum = 0;
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Mat6 D = diagonal_block(sys, c);
    for (int r = 0; r < sys.rows(); ++r) sum += D(r, r) - sys.sigma()[sys.rows() * c + r];
  }
  return sum / double(sys.contact_dofs());
}

struct Reference {
  Vector dv;
  double refinement = 0; // relative size of the refinement correction: accuracy estimate
};

Reference body_reference(const ContactSystem &sys, const Vector &b)
{
  Eigen::SimplicialLLT<Sparse> llt(assemble_body_matrix(sys));
  EXPECT_EQ(llt.info(), Eigen::Success);
  const Vector rhs = body_rhs(sys, serial_exchange(), b);
  Reference ref;
  ref.dv = llt.solve(rhs);
  BodySpaceOperator K(sys, serial_exchange());
  Vector Kdv;
  K.apply(ref.dv, Kdv);
  const Vector correction = llt.solve(rhs - Kdv);
  ref.dv += correction;
  ref.refinement = correction.norm() / ref.dv.norm();
  return ref;
}

// Share of b outside range(G): ||b - G x|| / ||b|| with x the least-squares fit.
double null_share(const ContactSystem &unit_sys, const Vector &b)
{
  // unit_sys has Sigma = I, so K - M = G^T G.
  Sparse GtG = assemble_body_matrix(unit_sys);
  for (int i = 0; i < unit_sys.body_dofs(); ++i) GtG.coeffRef(i, i) -= 1.0 / unit_sys.inv_mass()[i];
  Eigen::SimplicialLDLT<Sparse> ldlt(GtG);
  Vector Gtb;
  gt_apply(unit_sys, b, Gtb);
  const Vector x = ldlt.solve(Gtb);
  Vector Gx;
  g_apply(unit_sys, x, Gx);
  return (b - Gx).norm() / b.norm();
}

ContactSystem with_compliance(const std::vector<Body> &bodies, std::vector<Contact> contacts,
                              const SpookParams &sp, double eps)
{
  for (Contact &c : contacts) c.compliance.fill(eps);
  return ContactSystem(bodies, std::move(contacts), 6, sp);
}

struct Measured {
  int iterations = -1; // to the target, -1: not reached
  double best = 0;     // smallest velocity error seen
  double worst = 0;    // largest velocity error seen after iteration 0
  double rel_residual = 0;
  StopReason reason = StopReason::max_iterations;
};

Measured measure(const ContactSystem &sys, Form form, PrecondKind kind, Method m, const Vector &b,
                 const Vector &dv_ref)
{
  const auto A = make_operator(form, sys, serial_exchange());
  PrecondOptions popt;
  popt.kind = kind;
  const auto P = make_preconditioner(form, sys, serial_exchange(), popt);
  const double ref_norm = dv_ref.norm();
  Measured run;
  run.best = 1.0;
  auto velocity_error = [&](const Vector &x) {
    const Vector dv = form == Form::body ? x : body_from_lambda(sys, serial_exchange(), x);
    return (dv - dv_ref).norm() / ref_norm;
  };
  StopControl stop;
  stop.tol = 0; // the velocity error decides
  stop.max_iter = kMaxIter;
  stop.accept = [&](int, const Vector &x) {
    const double e = velocity_error(x);
    if (!std::isfinite(e)) return false;
    run.best = std::min(run.best, e);
    run.worst = std::max(run.worst, e);
    return e <= kTarget;
  };
  Vector x = Vector::Zero(A->size());
  const Vector rhs = form == Form::body ? body_rhs(sys, serial_exchange(), b) : b;
  const SolveResult res = krylov_solve(m, *A, *P, rhs, x, stop);
  EXPECT_TRUE(x.allFinite());
  if (res.converged()) run.iterations = res.iterations;
  run.reason = res.reason;
  run.rel_residual = res.rel_residual;
  return run;
}

std::string cell(const Measured &r)
{
  char buf[64];
  if (r.iterations >= 0)
    std::snprintf(buf, sizeof buf, "%d", r.iterations);
  else if (r.reason == StopReason::max_iterations)
    std::snprintf(buf, sizeof buf, ">%d (%.0e%s)", kMaxIter, r.best, r.worst > 1 ? "!" : "");
  else
    std::snprintf(buf, sizeof buf, "%s (%.0e%s)", to_string(r.reason), r.best,
                  r.worst > 1 ? "!" : "");
  return buf;
}

} // namespace

TEST(Report, ConvergenceToVelocityError)
{
  const auto t0 = std::chrono::steady_clock::now();
  SceneParams sp;
  const ContactSystem pile = lammps_pile_scene(FIBRE_TEST_DATA_DIR "/pile400.dump", sp);
  ASSERT_EQ(pile.num_bodies(), kBodies);
  const SpookParams &spook = pile.params();
  int walls = 0;
  for (const Contact &c : pile.contacts()) walls += c.is_wall();
  const int body_contacts = pile.num_contacts() - walls;
  // eps that gives Sigma = s: Sigma = 4 eps / (h^2 (1 + 4 d)).
  const double eps_per_sigma = spook.h * spook.h * (1 + 4 * spook.damping) / 4;
  const ContactSystem unit = with_compliance(pile.bodies(), pile.contacts(), spook, eps_per_sigma);
  const double mean_diag = mean_schur_diagonal(unit);
  std::vector<Contact> no_gap = pile.contacts();
  for (Contact &c : no_gap) c.gap = 0;
  const Vector b_gap = spook_rhs(unit);
  const Vector b_range = spook_rhs(ContactSystem(pile.bodies(), no_gap, 6, spook));
  std::printf("\nLAMMPS pile of %d spheres: %d contacts (%d on walls, %.2f body-body contacts per "
              "body), %ld contact rows, %ld body unknowns; mean diag(G M^-1 G^T) = %.4g\n",
              kBodies, pile.num_contacts(), walls, 2.0 * body_contacts / kBodies,
              long(pile.contact_dofs()), long(pile.body_dofs()), mean_diag);
  std::printf("Iterations to ||dv - dv*|| / ||dv*|| <= %.0e (cap %d; '>%d (e)' = best error "
              "reached, '!' = the error exceeded 1 on the way; a stop reason other than "
              "max_iterations is named).\n",
              kTarget, kMaxIter, kMaxIter);

  const struct {
    const char *name;
    const Vector &b;
  } rhs_cases[] = {{"SPOOK rhs with the gap term", b_gap},
                   {"rhs without the gap term (inside range(G))", b_range}};
  int body_misses_at_1e4 = 0;
  for (const auto &rc : rhs_cases) {
    const double share = null_share(unit, rc.b);
    std::printf("\n== %s: ||b - P_range(G) b|| / ||b|| = %.3g\n", rc.name, share);
    for (double s : kSigmaRel) {
      const ContactSystem sys =
          with_compliance(pile.bodies(), pile.contacts(), spook, s * mean_diag * eps_per_sigma);
      const Reference ref = body_reference(sys, rc.b);
      EXPECT_LT(ref.refinement, 1e-9) << "reference not converged at sigma_rel " << s;
      const Vector lc = direct_solve(Form::contact, sys, serial_exchange(), rc.b, MPI_COMM_SELF);
      const double mumps_contact =
          (body_from_lambda(sys, serial_exchange(), lc) - ref.dv).norm() / ref.dv.norm();
      std::printf("\nsigma_rel %.0e  (reference refinement %.1e; MUMPS contact-form velocity "
                  "error %.1e)\n",
                  s, ref.refinement, mumps_contact);
      std::printf("  %-8s %-7s %20s %20s %20s\n", "form", "precond", "cg", "cr", "minres");
      for (Form form : {Form::contact, Form::body})
        for (PrecondKind kind : kPreconds) {
          std::printf("  %-8s %-7s", to_string(form), to_string(kind));
          for (Method m : kMethods) {
            const Measured r = measure(sys, form, kind, m, rc.b, ref.dv);
            if (form == Form::body && s == 1e-4 && r.iterations < 0) ++body_misses_at_1e4;
            std::printf(" %20s", cell(r).c_str());
          }
          std::printf("\n");
        }
      std::fflush(stdout);
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("\nreport time %.1f s\n", seconds);
  // Sanity: at sigma_rel = 1e-4, cond(K) <= ~1 / sigma_rel, so every body-form run gets there.
  // Below that the scene's near-mechanisms (chains with one contact per body) set the pace.
  EXPECT_EQ(body_misses_at_1e4, 0);
}
