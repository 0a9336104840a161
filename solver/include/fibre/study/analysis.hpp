// Convergence and spectral analysis of one contact system, per form x Krylov method x
// preconditioner: the measurements of the thesis (sections 5-6: r_r, v_e, kappa_e, Tables 1-2,
// Figures 16-24) and of doc/design.md sections 4 and 7. fibre_analyze is its command line.
//
// The reference is direct (MUMPS):
// - dv* = M^-1 G^T lambda*, the velocity change of the exact solution, from the body form
//   K dv = G^T Sigma^-1 b (K = M + G^T Sigma^-1 G) plus one step of refinement. This is the
//   accurate way to the velocities: the contact form carries a 1/Sigma-sized lambda component
//   in null(G^T) that G^T must cancel in floating point (doc/design.md section 7).
// - lambda* from the contact form A lambda = b; its velocities are compared with dv*, so that
//   the attainable accuracy of the contact form shows.
//
// Every run starts from zero and goes on for maxiter iterations whatever its residual does
// (tolerance 0), recording per iteration, on the TRUE residual r = rhs - A x_k of its form:
//   rr = ||r||_2 / ||A||_F   (thesis eq. 5.1; A is K in the body form; Frobenius norm of the
//                             assembled matrix, the norm NumPy's norm(A) gives)
//   rb = ||r||_2 / ||rhs||_2
//   ve = ||dv_k - dv*||_2    (thesis eq. 5.1.14; contact form dv_k = M^-1 G^T lambda_k, body
//                             form dv_k = x_k), ve_rel = ve / ||dv*||_2.
// The Krylov methods' own histories carry the recursively updated residual instead, which in
// floating point can keep falling after the true residual has stalled.
//
// One process only (the reference and the dense spectra are serial).
#pragma once

#include <functional>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "fibre/algebra/operators.hpp"
#include "fibre/core/names.hpp"
#include "fibre/precond/fibres.hpp"
#include "fibre/precond/preconditioner_family.hpp"
#include "fibre/solvers/krylov.hpp"
#include "fibre/study/spectra.hpp"

namespace fibre {

constexpr int kReportIteration = 100;    // thesis Table 1: r_r and v_e at 100 iterations
constexpr double kVelocityTarget = 1e-6; // iterations to ve_rel <= this

// How the spectra are computed. automatic: dense up to 3000 unknowns; above that the
// body-space spectrum for the contact form without preconditioner (uniform Sigma), otherwise
// Lanczos (500 steps), dense after all when that does not converge and n <= 8000.
enum class KappaMethod { automatic, dense, lanczos };
template <> struct EnumNames<KappaMethod> {
  static constexpr EnumName<KappaMethod> table[] = {{KappaMethod::automatic, "auto"},
                                                    {KappaMethod::dense, "dense"},
                                                    {KappaMethod::lanczos, "lanczos"}};
};

// Combined preconditioners (combined_preconditioner.hpp), F = fibre, T = tree:
//   add_fibre_tree  P^-1 = (F^-1 + T^-1) / 2
//   mul_tree_fibre  symmetric multiplicative T, F, T
//   add_fibre_zs    (F_z^-1 + F_straight^-1) / 2 (two edge weights)
//   add_tree_zs     (T_z^-1 + T_straight^-1) / 2
enum class Combination { add_fibre_tree, mul_tree_fibre, add_fibre_zs, add_tree_zs };
template <> struct EnumNames<Combination> {
  static constexpr EnumName<Combination> table[] = {{Combination::add_fibre_tree, "add_fibre_tree"},
                                                    {Combination::mul_tree_fibre, "mul_tree_fibre"},
                                                    {Combination::add_fibre_zs, "add_fibre_zs"},
                                                    {Combination::add_tree_zs, "add_tree_zs"}};
};

struct AnalysisOptions {
  std::vector<Form> forms{Form::contact, Form::body};
  std::vector<Method> methods{Method::cg, Method::cr, Method::minres};
  std::vector<PrecondKind> preconds{PrecondKind::none, PrecondKind::jacobi, PrecondKind::block,
                                    PrecondKind::fibre, PrecondKind::tree};
  std::vector<Combination> combinations; // run after `preconds`
  EdgeWeight weight = EdgeWeight::z;     // of fibre and tree (impulse: from lambda*)
  int maxiter = 0;                       // 0: the system size of each form
  bool spectra = false;
  KappaMethod kappa_method = KappaMethod::automatic;
  int lanczos_steps = 0; // 0: the default of the kappa method
};

// ---- the system ----

struct AnalysisSystem {
  ContactSystem system;
  int ghosts = 0; // ghost bodies of the export, analysed as ordinary bodies
};

// The system as read, rebuilt with every compliance times `sigma_scale` (Sigma scales alike;
// b does not depend on it) and with every body owned: an export from one of several processes
// is analysed as the local system it is. Throws std::invalid_argument when Sigma is not finite.
AnalysisSystem prepare_system(const ContactSystem &read, double sigma_scale = 1.0);

// True when every row has the same Sigma (the body-space spectrum applies).
bool uniform_sigma(const ContactSystem &sys);

// What the analysis states about its input; active-row figures are 0 with no active row.
struct SystemSummary {
  int walls = 0;        // wall contacts
  long active_rows = 0; // rows not masked
  long masked_rows = 0;
  double sigma_min = 0, sigma_max = 0;
  double mean_diag = 0;  // mean diag(G M^-1 G^T) over active rows
  double mean_sigma = 0; // mean Sigma over active rows
  double rhs_norm = 0;
};
SystemSummary summarize(const ContactSystem &sys);

// ---- the direct reference ----

struct Reference {
  Vector dv; // dv* = M^-1 G^T lambda*, from the body form
  double dv_norm = 0;
  double refinement = 0;             // ||refinement correction|| / ||dv*||: accuracy estimate
  Vector lambda;                     // lambda* from the contact form
  double contact_velocity_error = 0; // ||M^-1 G^T lambda* - dv*|| / ||dv*||
  double seconds = 0;
};
Reference direct_reference(const ContactSystem &sys);

// ---- one form: operator, rhs, norms, preconditioners ----

struct PrecondEntry {
  PrecondKind kind = PrecondKind::none; // of a combination: not meaningful
  std::unique_ptr<Preconditioner> P;
  FibreStats stats; // fibre and tree
  double setup_seconds = 0;
  std::string name; // to_string(kind), or the combination's
  bool combined = false;
};

struct FormSetup {
  Form form = Form::contact;
  std::unique_ptr<LinearOperator> op;
  Vector rhs;
  double rhs_norm = 0;
  double norm_fro = 0; // ||A||_F of the assembled matrix: r_r divides by it
  double norm_2 = 0;   // ||A||_2 = lambda_max, Lanczos estimate (for comparison)
  int norm_2_steps = 0;
  int maxiter = 0;
  std::vector<PrecondEntry> preconds;
};

// `impulses`: normal impulse per contact for EdgeWeight::impulse (nullptr: z weights). The
// operator (and the combinations) refer to `sys`: it must outlive the setup.
FormSetup setup_form(Form form, const ContactSystem &sys, const AnalysisOptions &opt,
                     const Vector *impulses);

// ---- one Krylov run ----

struct IterationRow {
  int iteration = 0;
  double rr = 0, rb = 0, ve = 0, ve_rel = 0;
};

struct Run {
  Form form = Form::contact;
  Method method = Method::cg;
  std::string precond;
  SolveResult result;
  std::vector<IterationRow> rows; // one per history entry of `result`
  double seconds = 0;
};

Run run_krylov(const FormSetup &fs, const PrecondEntry &pe, Method method, const ContactSystem &sys,
               const Reference &ref);

// The row at kReportIteration, or the last one of a shorter run (nullptr: none).
const IterationRow *row_at_report(const Run &run);
// The row of smallest finite ve_rel (nullptr: none).
const IterationRow *best_velocity(const Run &run);
// The first iteration with ve_rel <= target, -1 if none.
int iterations_to(const Run &run, double target = kVelocityTarget);

// ---- spectra ----

struct SpectrumRun {
  Form form = Form::contact;
  PrecondKind kind = PrecondKind::none;
  std::string precond; // name
  Eigen::Index n = 0;
  Spectrum s;
  std::string method;   // how it was computed
  bool complete = true; // every eigenvalue (false: Lanczos Ritz values)
  double seconds = 0;
};

SpectrumRun compute_spectrum(const FormSetup &fs, const PrecondEntry &pe, const ContactSystem &sys,
                             KappaMethod how, int lanczos_steps = 0);

// ---- the whole analysis ----

struct Analysis {
  bool zero_rhs = false; // no Krylov runs, spectra only
  Reference reference;   // empty when zero_rhs
  std::vector<FormSetup> forms;
  std::vector<Run> runs; // per form, preconditioner and method, in that order
  std::vector<SpectrumRun> spectra;
};

// Optional hooks, called as the results come (a front end prints progress from them).
struct AnalysisProgress {
  std::function<void(const Analysis &)> reference; // after the reference (or zero_rhs)
  std::function<void(const FormSetup &)> form;
  std::function<void(const FormSetup &, const Run &)> run;
  std::function<void(const SpectrumRun &)> spectrum;
};

// Nothing is computed for a system without contacts. The forms' operators refer to `sys`: it
// must outlive the result.
Analysis analyze(const ContactSystem &sys, const AnalysisOptions &opt,
                 const AnalysisProgress &progress = {});

// ---- writers ----

// The histories: '#' comment lines (source, sigma_scale, per form size and norms), the header
// form,method,precond,iteration,rr,rb,ve,ve_rel, then one line per iteration of every run.
void write_history_csv(std::ostream &out, const Analysis &analysis, const std::string &source,
                       double sigma_scale);
// One spectrum: '#' comment lines, then the eigenvalues one per line (17 digits).
void write_spectrum(std::ostream &out, const SpectrumRun &run);
std::string spectrum_path(const std::string &prefix, const SpectrumRun &run);
// The kappa_e table: header, then one line per spectrum.
void write_kappa_csv(std::ostream &out, const std::vector<SpectrumRun> &runs);

} // namespace fibre
