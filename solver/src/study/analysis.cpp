#include "fibre/study/analysis.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <stdexcept>

#include "fibre/algebra/assembly.hpp"
#include "fibre/algebra/kernels.hpp"
#include "fibre/core/text.hpp"
#include "fibre/precond/combined_preconditioner.hpp"
#include "fibre/solvers/direct.hpp"

namespace fibre {

namespace {

// KappaMethod::automatic: dense spectra up to kDenseMaxSize unknowns (O(n^3) time, three
// n x n matrices in memory); above that Lanczos with at most kAutoLanczosSteps steps, and the
// dense path after all when Lanczos does not converge and n <= kDenseFallbackSize (about 2
// minutes at 6,000).
constexpr Eigen::Index kDenseMaxSize = 3000;
constexpr Eigen::Index kDenseFallbackSize = 8000;
constexpr int kAutoLanczosSteps = 500;
constexpr int kNormLanczosSteps = 60; // Lanczos steps for the ||A||_2 estimate

} // namespace

// ---- the system ----

AnalysisSystem prepare_system(const ContactSystem &read, double sigma_scale)
{
  std::vector<Contact> contacts = read.contacts();
  for (Contact &c : contacts)
    for (double &eps : c.compliance) eps *= sigma_scale;
  AnalysisSystem out{ContactSystem(read.bodies(), std::move(contacts), read.rows(), read.params()),
                     read.num_bodies() - read.num_owned_bodies()};
  ContactSystem &sys = out.system;
  if (!sys.sigma().allFinite()) throw std::invalid_argument("Sigma is not finite");
  if (!read.row_mask().empty()) sys.set_row_mask(read.row_mask());
  sys.set_rhs(read.rhs());
  return out;
}

bool uniform_sigma(const ContactSystem &sys)
{
  const Vector &s = sys.sigma();
  if (s.size() == 0) return false;
  return ((s.array() - s[0]).abs() <= 1e-12 * s[0]).all();
}

SystemSummary summarize(const ContactSystem &sys)
{
  SystemSummary out;
  out.rhs_norm = sys.rhs().norm();
  for (const Contact &c : sys.contacts()) out.walls += c.is_wall();
  double diag_sum = 0, sigma_sum = 0;
  double sigma_min = INFINITY, sigma_max = 0;
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Mat6 D = diagonal_block(sys, c);
    for (int r = 0; r < sys.rows(); ++r) {
      const Eigen::Index row = Eigen::Index(sys.rows()) * c + r;
      if (!sys.row_active(row)) continue;
      const double s = sys.sigma()[row];
      ++out.active_rows;
      diag_sum += D(r, r) - s;
      sigma_sum += s;
      sigma_min = std::min(sigma_min, s);
      sigma_max = std::max(sigma_max, s);
    }
  }
  out.masked_rows = long(sys.contact_dofs()) - out.active_rows;
  if (out.active_rows > 0) {
    out.sigma_min = sigma_min;
    out.sigma_max = sigma_max;
    out.mean_diag = diag_sum / double(out.active_rows);
    out.mean_sigma = sigma_sum / double(out.active_rows);
  }
  return out;
}

// ---- the direct reference ----

Reference direct_reference(const ContactSystem &sys)
{
  const auto t0 = Clock::now();
  const Exchange &ex = serial_exchange();
  Reference ref;
  ref.dv = refined_body_solution(sys, &ref.refinement);
  ref.dv_norm = ref.dv.norm();
  ref.lambda = direct_solve(Form::contact, sys, ex, sys.rhs(), MPI_COMM_SELF);
  const Vector dv_contact = body_from_lambda(sys, ex, ref.lambda);
  ref.contact_velocity_error =
      ref.dv_norm > 0 ? (dv_contact - ref.dv).norm() / ref.dv_norm : dv_contact.norm();
  ref.seconds = seconds_since(t0);
  return ref;
}

// ---- one form ----

FormSetup setup_form(Form form, const ContactSystem &sys, const AnalysisOptions &opt,
                     const Vector *impulses)
{
  const Exchange &ex = serial_exchange();
  FormSetup fs;
  fs.form = form;
  fs.op = make_operator(form, sys, ex);
  fs.rhs = form == Form::body ? body_rhs(sys, ex, sys.rhs()) : sys.rhs();
  fs.rhs_norm = fs.op->norm(fs.rhs);
  fs.norm_fro = (form == Form::body ? assemble_K(sys) : assemble_A(sys)).norm();
  LanczosOptions lo;
  lo.max_steps = kNormLanczosSteps;
  const Spectrum top = lanczos_spectrum(form, sys, ex, IdentityPreconditioner(), lo);
  fs.norm_2 = top.lambda_max;
  fs.norm_2_steps = top.iterations;
  fs.maxiter = opt.maxiter > 0 ? opt.maxiter : static_cast<int>(fs.op->size());
  auto build = [&](PrecondKind kind, EdgeWeight weight, FibreStats *stats) {
    PrecondOptions po;
    po.kind = kind;
    po.weight = weight;
    po.impulses = impulses;
    return make_preconditioner(form, sys, ex, po, stats);
  };
  for (PrecondKind kind : opt.preconds) {
    PrecondEntry e;
    e.kind = kind;
    e.name = to_string(kind);
    const auto t0 = Clock::now();
    e.P = build(kind, opt.weight, &e.stats);
    e.setup_seconds = seconds_since(t0);
    fs.preconds.push_back(std::move(e));
  }
  for (Combination combo : opt.combinations) {
    PrecondEntry e;
    e.kind = PrecondKind::tree;
    e.name = to_string(combo);
    e.combined = true;
    const auto t0 = Clock::now();
    switch (combo) {
    case Combination::add_fibre_tree:
      e.P = std::make_unique<AveragePreconditioner>(build(PrecondKind::fibre, opt.weight, nullptr),
                                                    build(PrecondKind::tree, opt.weight, nullptr),
                                                    e.name);
      break;
    case Combination::mul_tree_fibre:
      e.P = std::make_unique<SymmetricProductPreconditioner>(
          *fs.op, build(PrecondKind::tree, opt.weight, nullptr),
          build(PrecondKind::fibre, opt.weight, nullptr), e.name);
      break;
    case Combination::add_fibre_zs:
    case Combination::add_tree_zs: {
      const PrecondKind kind =
          combo == Combination::add_fibre_zs ? PrecondKind::fibre : PrecondKind::tree;
      e.P = std::make_unique<AveragePreconditioner>(
          build(kind, EdgeWeight::z, nullptr), build(kind, EdgeWeight::straight, nullptr), e.name);
      break;
    }
    }
    e.setup_seconds = seconds_since(t0);
    fs.preconds.push_back(std::move(e));
  }
  return fs;
}

// ---- one Krylov run ----

Run run_krylov(const FormSetup &fs, const PrecondEntry &pe, Method method, const ContactSystem &sys,
               const Reference &ref)
{
  const Exchange &ex = serial_exchange();
  Run run;
  run.form = fs.form;
  run.method = method;
  run.precond = pe.name;
  Vector Ax, dv;
  KrylovMonitor monitor;
  monitor.record_history = true;
  monitor.norm_A = fs.norm_fro;
  // Called once per history entry, with its iterate: every measurement is taken here.
  monitor.velocity_error = [&](const Vector &x) {
    fs.op->apply(x, Ax);
    const double r = fs.op->norm(fs.rhs - Ax);
    dv = fs.form == Form::body ? x : body_from_lambda(sys, ex, x);
    IterationRow row;
    row.rr = r / fs.norm_fro;
    row.rb = r / fs.rhs_norm;
    row.ve = (dv - ref.dv).norm();
    row.ve_rel = ref.dv_norm > 0 ? row.ve / ref.dv_norm : NAN;
    run.rows.push_back(row);
    return row.ve;
  };
  StopControl stop;
  stop.tol = 0; // run the full maxiter iterations: the histories are the point
  stop.max_iter = fs.maxiter;
  Vector x = Vector::Zero(fs.op->size());
  const auto t0 = Clock::now();
  run.result = krylov_solve(method, *fs.op, *pe.P, fs.rhs, x, stop, &monitor);
  run.seconds = seconds_since(t0);
  if (run.rows.size() != run.result.history.size())
    throw std::logic_error("Krylov history and measurements differ in length");
  for (std::size_t i = 0; i < run.rows.size(); ++i)
    run.rows[i].iteration = run.result.history[i].iteration;
  return run;
}

const IterationRow *row_at_report(const Run &run)
{
  for (const IterationRow &r : run.rows)
    if (r.iteration == kReportIteration) return &r;
  return run.rows.empty() ? nullptr : &run.rows.back();
}

const IterationRow *best_velocity(const Run &run)
{
  const IterationRow *best = nullptr;
  for (const IterationRow &r : run.rows)
    if (std::isfinite(r.ve_rel) && (!best || r.ve_rel < best->ve_rel)) best = &r;
  return best;
}

int iterations_to(const Run &run, double target)
{
  for (const IterationRow &r : run.rows)
    if (r.ve_rel <= target) return r.iteration;
  return -1;
}

// ---- spectra ----

SpectrumRun compute_spectrum(const FormSetup &fs, const PrecondEntry &pe, const ContactSystem &sys,
                             KappaMethod how, int lanczos_steps)
{
  SpectrumRun run;
  run.form = fs.form;
  run.kind = pe.kind;
  run.precond = pe.name;
  run.n = fs.op->size();
  const auto t0 = Clock::now();
  const bool automatic = how == KappaMethod::automatic;
  const bool body_space = fs.form == Form::contact && pe.kind == PrecondKind::none &&
                          !pe.combined && uniform_sigma(sys) && sys.body_dofs() <= kDenseMaxSize;
  if (how == KappaMethod::dense || (automatic && run.n <= kDenseMaxSize)) {
    run.s = dense_spectrum(*fs.op, *pe.P);
    run.method = "dense";
  } else if (automatic && body_space) {
    run.s = body_space_spectrum(sys);
    run.method = "body-space";
  } else {
    LanczosOptions lo;
    if (automatic) lo.max_steps = kAutoLanczosSteps;
    if (lanczos_steps > 0) lo.max_steps = lanczos_steps;
    run.s = lanczos_spectrum(fs.form, sys, serial_exchange(), *pe.P, lo);
    run.complete = false;
    run.method = "lanczos " + std::to_string(run.s.iterations) +
                 (run.s.certified   ? " certified"
                  : run.s.converged ? " converged"
                                    : " NOT converged");
    if (automatic && !run.s.converged && run.n <= kDenseFallbackSize) {
      run.s = dense_spectrum(*fs.op, *pe.P);
      run.complete = true;
      run.method = "dense (" + run.method + ")";
    }
  }
  run.seconds = seconds_since(t0);
  return run;
}

// ---- the whole analysis ----

Analysis analyze(const ContactSystem &sys, const AnalysisOptions &opt,
                 const AnalysisProgress &progress)
{
  Analysis an;
  if (sys.num_contacts() == 0) return an;
  an.zero_rhs = sys.rhs().norm() == 0;
  Vector impulses;
  if (!an.zero_rhs) {
    an.reference = direct_reference(sys);
    impulses.resize(sys.num_contacts());
    for (int c = 0; c < sys.num_contacts(); ++c) impulses[c] = an.reference.lambda[sys.rows() * c];
  }
  if (progress.reference) progress.reference(an);
  const Vector *impulse_ptr = an.zero_rhs ? nullptr : &impulses;

  for (Form form : opt.forms) {
    an.forms.push_back(setup_form(form, sys, opt, impulse_ptr));
    if (progress.form) progress.form(an.forms.back());
  }
  if (!an.zero_rhs)
    for (const FormSetup &fs : an.forms)
      for (const PrecondEntry &pe : fs.preconds)
        for (Method m : opt.methods) {
          an.runs.push_back(run_krylov(fs, pe, m, sys, an.reference));
          if (progress.run) progress.run(fs, an.runs.back());
        }
  if (opt.spectra)
    for (const FormSetup &fs : an.forms)
      for (const PrecondEntry &pe : fs.preconds) {
        an.spectra.push_back(compute_spectrum(fs, pe, sys, opt.kappa_method, opt.lanczos_steps));
        if (progress.spectrum) progress.spectrum(an.spectra.back());
      }
  return an;
}

// ---- writers ----

void write_history_csv(std::ostream &out, const Analysis &analysis, const std::string &source,
                       double sigma_scale)
{
  out.precision(10);
  out << "# fibre_analyze " << source << ": rr = ||r|| / ||A||_F with the true "
      << "residual r, rb = ||r|| / ||rhs||, ve = ||dv - dv*||, ve_rel = ve / ||dv*||\n";
  out << "# sigma_scale " << sigma_scale << "\n";
  for (const FormSetup &fs : analysis.forms)
    out << "# size " << to_string(fs.form) << ' ' << fs.op->size() << " norm_fro " << fs.norm_fro
        << " norm_2 " << fs.norm_2 << '\n';
  out << "form,method,precond,iteration,rr,rb,ve,ve_rel\n";
  for (const Run &run : analysis.runs)
    for (const IterationRow &r : run.rows)
      out << to_string(run.form) << ',' << to_string(run.method) << ',' << run.precond << ','
          << r.iteration << ',' << r.rr << ',' << r.rb << ',' << r.ve << ',' << r.ve_rel << '\n';
}

std::string spectrum_path(const std::string &prefix, const SpectrumRun &run)
{
  return prefix + "_" + to_string(run.form) + "_" + run.precond + ".csv";
}

void write_spectrum(std::ostream &out, const SpectrumRun &run)
{
  out.precision(17);
  out << "# fibre_analyze spectrum: form " << to_string(run.form) << ", precond " << run.precond
      << (run.precond == "none" ? " (A)" : " (P^-1 A)") << ", n " << run.n << "\n";
  out << "# method " << run.method << (run.complete ? " (all eigenvalues)" : " (Ritz values only)")
      << "\n";
  out << "# kappa_e " << run.s.kappa_e << " kappa " << run.s.kappa << " lambda_1 "
      << run.s.lambda_max << " lambda_r " << run.s.lambda_r << " above_gap " << run.s.r + 1
      << " gap_ratio " << run.s.gap_ratio << "\n";
  for (double e : run.s.eigenvalues) out << e << '\n';
}

void write_kappa_csv(std::ostream &out, const std::vector<SpectrumRun> &runs)
{
  out.precision(10);
  out << "form,precond,n,kappa_e,kappa,lambda_1,lambda_r,above_gap,gap_ratio,method,complete\n";
  for (const SpectrumRun &r : runs)
    out << to_string(r.form) << ',' << r.precond << ',' << r.n << ',' << r.s.kappa_e << ','
        << r.s.kappa << ',' << r.s.lambda_max << ',' << r.s.lambda_r << ',' << r.s.r + 1 << ','
        << r.s.gap_ratio << ',' << r.method << ',' << (r.complete ? 1 : 0) << '\n';
}

} // namespace fibre
