// fibre_analyze: convergence histories and spectra of one contact system, per form x Krylov
// method x preconditioner: the measurements of the thesis (sections 5-6: r_r, v_e, kappa_e,
// Tables 1-2, Figures 16-24) and of design.md sections 4 and 7.
//
// Input is a system file as `fix fibre_contact export N prefix` writes it (system_io.hpp).
// The reference is direct (MUMPS):
// - dv* = M^-1 G^T lambda*, the velocity change of the exact solution, from the body form
//   K dv = G^T Sigma^-1 b (K = M + G^T Sigma^-1 G) plus one step of refinement. This is the
//   accurate way to the velocities: the contact form carries a 1/Sigma-sized lambda component
//   in null(G^T) that G^T must cancel in floating point (design.md section 7).
// - lambda* from the contact form A lambda = b (direct_solve); its velocities are compared
//   with dv* and printed, so that the attainable accuracy of the contact form shows.
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
#include <mpi.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "fibre/assembly.hpp"
#include "fibre/direct.hpp"
#include "fibre/krylov.hpp"
#include "fibre/preconditioner_family.hpp"
#include "fibre/spectra.hpp"
#include "fibre/system_io.hpp"

using namespace fibre;

namespace {

constexpr int kReportIteration = 100;     // thesis Table 1: r_r and v_e at 100 iterations
constexpr double kVelocityTarget = 1e-6;  // iterations to ve_rel <= this
// --kappa auto: dense spectra up to kDenseMaxSize unknowns (O(n^3) time, three n x n matrices
// in memory); above that Lanczos with at most kAutoLanczosSteps steps, and the dense path after
// all when Lanczos does not converge and n <= kDenseFallbackSize (about 2 minutes at 6,000).
constexpr Eigen::Index kDenseMaxSize = 3000;
constexpr Eigen::Index kDenseFallbackSize = 8000;
constexpr int kAutoLanczosSteps = 500;
constexpr int kNormLanczosSteps = 60;  // Lanczos steps for the ||A||_2 estimate

const char *const kUsage =
    R"(usage: fibre_analyze SYSTEM_FILE [options]

Reads a contact system (the file `fix fibre_contact export N prefix` writes), solves it with
MUMPS for the reference, then runs every Krylov method x preconditioner on the contact form
A lambda = b (A = G M^-1 G^T + Sigma) and/or the body form K dv = G^T Sigma^-1 b
(K = M + G^T Sigma^-1 G), recording per iteration on the true residual r:
  rr = ||r|| / ||A||_F (thesis r_r, eq. 5.1), rb = ||r|| / ||b||,
  ve = ||M^-1 G^T (lambda* - lambda)|| (thesis v_e; body form ||dv* - dv||), ve_rel = ve / ||dv*||.

options:
  --form contact|body|both     the form(s) to solve (default both)
  --methods LIST               comma-separated, from cg,cr,minres (uzawa: cg) (default all)
  --precond LIST               comma-separated, from none,jacobi,block,fibre,tree (default all)
  --weight z|straight|impulse  edge weight of the fibre and tree preconditioners (default z);
                               impulse uses the normal impulses of the direct solution
  --maxiter N                  iterations per run (default: the form's system size N)
  --csv OUT.csv                write the histories: form,method,precond,iteration,rr,rb,ve,ve_rel
  --spectra OUT_PREFIX         write the eigenvalues of A and P^-1 A, one per line, to
                               OUT_PREFIX_<form>_<precond>.csv, the kappa_e table to
                               OUT_PREFIX_kappa.csv, and print kappa_e
  --kappa dense|lanczos|auto   how to compute the spectra (default auto: dense up to 3000
                               unknowns; above that the body-space spectrum for the contact
                               form without preconditioner, otherwise Lanczos (500 steps),
                               dense after all when that does not converge and n <= 8000);
                               without --spectra it prints the kappa_e table, writes no files
  --lanczos-steps N            most Lanczos steps of --kappa lanczos (default 2000; auto: 500)
  --sigma-scale S              multiply Sigma (every compliance) by S > 0 (default 1)
  --combine LIST               add combined preconditioners (multipreconditioning), from
                               add_fibre_tree  P^-1 = (F^-1 + T^-1) / 2 (fibre and tree)
                               mul_tree_fibre  symmetric multiplicative T, F, T:
                                               z = T r; z += F (r - A z); z += T (r - A z)
                               add_fibre_zs    (F_z^-1 + F_straight^-1) / 2 (two weights)
                               add_tree_zs     (T_z^-1 + T_straight^-1) / 2 (two weights)
                               run after the --precond list, named as above
  -h, --help                   print this text

exit status: 0 done, 1 the computation failed, 2 bad arguments or unreadable input
)";

// Bad command line (exit 2, with a pointer to --help).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// Unreadable or malformed input, unwritable output (exit 2).
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class KappaMethod { automatic, dense, lanczos };

struct Options {
  std::string system_file;
  std::vector<Form> forms{Form::contact, Form::body};
  std::vector<Method> methods{Method::cg, Method::cr, Method::minres};
  std::vector<PrecondKind> preconds{PrecondKind::none, PrecondKind::jacobi, PrecondKind::block,
                                    PrecondKind::fibre, PrecondKind::tree};
  EdgeWeight weight = EdgeWeight::z;
  int maxiter = 0;  // 0: the system size of each form
  std::string csv_path;
  std::string spectra_prefix;
  bool kappa = false;  // compute the spectra (--spectra or --kappa)
  KappaMethod kappa_method = KappaMethod::automatic;
  int lanczos_steps = 0;  // 0: the default of the kappa method
  double sigma_scale = 1.0;
  std::vector<std::string> combos;  // --combine
  bool help = false;
};

// ---- command line ----

std::vector<std::string> split_list(const std::string &option, const std::string &value)
{
  std::vector<std::string> items;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = value.find(',', start);
    const std::string item = value.substr(start, comma - start);
    if (item.empty()) throw UsageError(option + ": empty entry in list '" + value + "'");
    items.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return items;
}

// Parses a comma-separated list of T's names, dropping repeats and keeping the order.
template <class T, class Valid>
std::vector<T> parse_list(const std::string &option, const std::string &value, Valid valid,
                          const char *allowed)
{
  std::vector<T> out;
  for (const std::string &item : split_list(option, value)) {
    T v{};
    if (!fibre::parse(item, v) || !valid(v))
      throw UsageError(option + ": unknown entry '" + item + "' (allowed: " + allowed + ")");
    if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
  }
  return out;
}

int parse_positive_int(const std::string &option, const std::string &value)
{
  errno = 0;
  char *end = nullptr;
  const long v = std::strtol(value.c_str(), &end, 10);
  if (value.empty() || *end != '\0' || errno == ERANGE || v < 1 || v > INT_MAX)
    throw UsageError(option + " needs a positive integer, got '" + value + "'");
  return static_cast<int>(v);
}

double parse_positive_real(const std::string &option, const std::string &value)
{
  errno = 0;
  char *end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v) || !(v > 0))
    throw UsageError(option + " needs a positive finite number, got '" + value + "'");
  return v;
}

Options parse_args(int argc, char **argv)
{
  Options opt;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      opt.help = true;
      return opt;
    }
    if (arg.size() < 2 || arg.compare(0, 2, "--") != 0) {
      if (!arg.empty() && arg[0] == '-') throw UsageError("unknown option '" + arg + "'");
      positional.push_back(arg);
      continue;
    }
    // --name value or --name=value
    std::string value;
    bool have_value = false;
    if (const std::size_t eq = arg.find('='); eq != std::string::npos) {
      value = arg.substr(eq + 1);
      arg.resize(eq);
      have_value = true;
    }
    const char *const known[] = {"--form",   "--methods", "--precond", "--weight",     "--maxiter",
                                 "--csv",    "--spectra", "--kappa",   "--sigma-scale",
                                 "--combine", "--lanczos-steps"};
    if (std::find(std::begin(known), std::end(known), arg) == std::end(known))
      throw UsageError("unknown option '" + arg + "'");
    if (!have_value) {
      if (i + 1 >= argc) throw UsageError(arg + " needs a value");
      value = argv[++i];
    }
    if (arg == "--form") {
      if (value == "both") {
        opt.forms = {Form::contact, Form::body};
      } else {
        Form f;
        if (!parse(value, f))
          throw UsageError("--form: unknown form '" + value + "' (allowed: contact, body, both)");
        opt.forms = {f};
      }
    } else if (arg == "--methods") {
      opt.methods = parse_list<Method>(arg, value, is_krylov, "cg, cr, minres");
    } else if (arg == "--precond") {
      opt.preconds = parse_list<PrecondKind>(arg, value, [](PrecondKind) { return true; },
                                             "none, jacobi, block, fibre, tree");
    } else if (arg == "--weight") {
      if (!parse(value, opt.weight))
        throw UsageError("--weight: unknown weight '" + value +
                         "' (allowed: z, straight, impulse)");
    } else if (arg == "--maxiter") {
      opt.maxiter = parse_positive_int(arg, value);
    } else if (arg == "--csv") {
      if (value.empty()) throw UsageError("--csv needs a file name");
      opt.csv_path = value;
    } else if (arg == "--spectra") {
      if (value.empty()) throw UsageError("--spectra needs a file prefix");
      opt.spectra_prefix = value;
      opt.kappa = true;
    } else if (arg == "--kappa") {
      if (value == "auto") opt.kappa_method = KappaMethod::automatic;
      else if (value == "dense") opt.kappa_method = KappaMethod::dense;
      else if (value == "lanczos") opt.kappa_method = KappaMethod::lanczos;
      else
        throw UsageError("--kappa: unknown method '" + value +
                         "' (allowed: dense, lanczos, auto)");
      opt.kappa = true;
    } else if (arg == "--sigma-scale") {
      opt.sigma_scale = parse_positive_real(arg, value);
    } else if (arg == "--lanczos-steps") {
      opt.lanczos_steps = parse_positive_int(arg, value);
    } else if (arg == "--combine") {
      opt.combos.clear();
      for (const std::string &item : split_list(arg, value)) {
        if (item != "add_fibre_tree" && item != "mul_tree_fibre" && item != "add_fibre_zs" &&
            item != "add_tree_zs")
          throw UsageError("--combine: unknown entry '" + item +
                           "' (allowed: add_fibre_tree, mul_tree_fibre, add_fibre_zs, "
                           "add_tree_zs)");
        if (std::find(opt.combos.begin(), opt.combos.end(), item) == opt.combos.end())
          opt.combos.push_back(item);
      }
    }
  }
  if (positional.empty()) throw UsageError("no system file given");
  if (positional.size() > 1) throw UsageError("more than one system file given");
  opt.system_file = positional.front();
  return opt;
}

// ---- formatting ----

std::string format(const char *fmt, double v)
{
  if (std::isnan(v)) return "nan";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

std::string sci(double v) { return format("%.2e", v); }

double seconds_since(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::ofstream open_output(const std::string &path)
{
  std::ofstream out(path);
  if (!out) throw InputError("cannot write '" + path + "'");
  out.precision(10);
  return out;
}

// ---- the system ----

// The system as read, rebuilt with every compliance times `scale` (Sigma scales alike; b does
// not depend on it) and with every body owned: an export from one of several processes is
// analysed as the local system it is, its ghost bodies taken as ordinary bodies.
ContactSystem prepare_system(const ContactSystem &read, double scale)
{
  std::vector<Contact> contacts = read.contacts();
  for (Contact &c : contacts)
    for (double &eps : c.compliance) eps *= scale;
  ContactSystem sys(read.bodies(), std::move(contacts), read.rows(), read.params());
  if (!sys.sigma().allFinite()) throw std::invalid_argument("Sigma is not finite");
  if (!read.row_mask().empty()) sys.set_row_mask(read.row_mask());
  sys.set_rhs(read.rhs());
  return sys;
}

ContactSystem load_system(const Options &opt, int &ghosts)
{
  ContactSystem read;
  try {
    read = read_system_file(opt.system_file);
  } catch (const std::exception &e) {
    throw InputError(e.what());
  }
  ghosts = read.num_bodies() - read.num_owned_bodies();
  try {
    return prepare_system(read, opt.sigma_scale);
  } catch (const std::invalid_argument &e) {
    // e.g. a compliance that the scale takes to 0 or to infinity
    throw InputError("--sigma-scale " + format("%g", opt.sigma_scale) + ": " + e.what());
  }
}

bool uniform_sigma(const ContactSystem &sys)
{
  const Vector &s = sys.sigma();
  if (s.size() == 0) return false;
  return ((s.array() - s[0]).abs() <= 1e-12 * s[0]).all();
}

void describe(const ContactSystem &sys, const Options &opt, int ghosts)
{
  int walls = 0;
  for (const Contact &c : sys.contacts()) walls += c.is_wall();
  std::printf("system %s\n", opt.system_file.c_str());
  std::printf("  %d bodies, %d contacts (%d on walls), %d rows per contact\n", sys.num_bodies(),
              sys.num_contacts(), walls, sys.rows());
  if (ghosts > 0)
    std::printf("  note: %d ghost bodies (a one-process export of a parallel run) are analysed "
                "as ordinary bodies of this local system\n",
                ghosts);
  if (sys.num_contacts() == 0) return;
  long active = 0;
  double diag_sum = 0, sigma_min = INFINITY, sigma_max = 0, sigma_sum = 0;
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Mat6 D = diagonal_block(sys, c);
    for (int r = 0; r < sys.rows(); ++r) {
      const Eigen::Index row = Eigen::Index(sys.rows()) * c + r;
      if (!sys.row_active(row)) continue;
      const double s = sys.sigma()[row];
      ++active;
      diag_sum += D(r, r) - s;
      sigma_sum += s;
      sigma_min = std::min(sigma_min, s);
      sigma_max = std::max(sigma_max, s);
    }
  }
  std::printf("  contact form: N = %ld (A = G M^-1 G^T + Sigma); body form: N = %ld "
              "(K = M + G^T Sigma^-1 G)\n",
              long(sys.contact_dofs()), long(sys.body_dofs()));
  std::printf("  h = %g, damping %g steps; %ld active rows (%ld masked)\n", sys.params().h,
              sys.params().damping, active, long(sys.contact_dofs()) - active);
  if (active > 0) {
    const double mean_diag = diag_sum / double(active);
    std::printf("  Sigma in [%.4g, %.4g] (compliance scale %g), mean diag(G M^-1 G^T) = %.4g, "
                "mean Sigma / that = %.3g\n",
                sigma_min, sigma_max, opt.sigma_scale, mean_diag,
                sigma_sum / double(active) / mean_diag);
  }
  std::printf("  ||b|| = %.4g\n", sys.rhs().norm());
}

// ---- the direct reference ----

struct Reference {
  Vector dv;               // dv* = M^-1 G^T lambda*, from the body form
  double dv_norm = 0;
  double refinement = 0;   // ||refinement correction|| / ||dv*||: accuracy estimate
  Vector lambda;           // lambda* from the contact form
  double contact_velocity_error = 0;  // ||M^-1 G^T lambda* - dv*|| / ||dv*||
};

Reference direct_reference(const ContactSystem &sys)
{
  const Exchange &ex = serial_exchange();
  Reference ref;
  ref.dv = refined_body_solution(sys, &ref.refinement);
  ref.dv_norm = ref.dv.norm();
  ref.lambda = direct_solve(Form::contact, sys, ex, sys.rhs(), MPI_COMM_SELF);
  const Vector dv_contact = body_from_lambda(sys, ex, ref.lambda);
  ref.contact_velocity_error = ref.dv_norm > 0 ? (dv_contact - ref.dv).norm() / ref.dv_norm
                                               : dv_contact.norm();
  return ref;
}

// ---- one form: operator, rhs, norms, preconditioners ----

struct PrecondEntry {
  PrecondKind kind;
  std::unique_ptr<Preconditioner> P;
  FibreStats stats;
  double setup_seconds = 0;
  std::string name;      // to_string(kind), or the --combine entry
  bool combined = false;
};

// ---- multipreconditioning (--combine) ----

// P^-1 = (P1^-1 + P2^-1) / 2: symmetric positive definite when both are.
class AveragePreconditioner final : public Preconditioner {
 public:
  AveragePreconditioner(std::unique_ptr<Preconditioner> a, std::unique_ptr<Preconditioner> b,
                        std::string name)
      : a_(std::move(a)), b_(std::move(b)), name_(std::move(name))
  {
  }
  void apply(const Vector &r, Vector &z) const override
  {
    a_->apply(r, z);
    b_->apply(r, tmp_);
    z = 0.5 * (z + tmp_);
  }
  std::string name() const override { return name_; }

 private:
  std::unique_ptr<Preconditioner> a_, b_;
  std::string name_;
  mutable Vector tmp_;
};

// Symmetric multiplicative combination (outer O, inner I), as a symmetric Gauss-Seidel sweep
// over the two preconditioners:
//   z = O r; z += I (r - A z); z += O (r - A z)
// symmetric; two more operator applies per use.
class SymmetricProductPreconditioner final : public Preconditioner {
 public:
  SymmetricProductPreconditioner(const LinearOperator &A, std::unique_ptr<Preconditioner> outer,
                                 std::unique_ptr<Preconditioner> inner, std::string name)
      : A_(A), outer_(std::move(outer)), inner_(std::move(inner)), name_(std::move(name))
  {
  }
  void apply(const Vector &r, Vector &z) const override
  {
    outer_->apply(r, z);
    A_.apply(z, Az_);
    res_ = r - Az_;
    inner_->apply(res_, tmp_);
    z += tmp_;
    A_.apply(z, Az_);
    res_ = r - Az_;
    outer_->apply(res_, tmp_);
    z += tmp_;
  }
  std::string name() const override { return name_; }

 private:
  const LinearOperator &A_;
  std::unique_ptr<Preconditioner> outer_, inner_;
  std::string name_;
  mutable Vector Az_, res_, tmp_;
};

struct FormSetup {
  Form form;
  std::unique_ptr<LinearOperator> op;
  Vector rhs;
  double rhs_norm = 0;
  double norm_fro = 0;  // ||A||_F of the assembled matrix: r_r divides by it
  double norm_2 = 0;    // ||A||_2 = lambda_max, Lanczos estimate (printed for comparison)
  int norm_2_steps = 0;
  int maxiter = 0;
  std::vector<PrecondEntry> preconds;
};

FormSetup setup_form(Form form, const ContactSystem &sys, const Options &opt,
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
  for (PrecondKind kind : opt.preconds) {
    PrecondOptions po;
    po.kind = kind;
    po.weight = opt.weight;
    po.impulses = impulses;
    PrecondEntry e{kind, nullptr, {}, 0, to_string(kind), false};
    const auto t0 = std::chrono::steady_clock::now();
    e.P = make_preconditioner(form, sys, ex, po, &e.stats);
    e.setup_seconds = seconds_since(t0);
    fs.preconds.push_back(std::move(e));
  }
  auto build = [&](PrecondKind kind, EdgeWeight weight) {
    PrecondOptions po;
    po.kind = kind;
    po.weight = weight;
    po.impulses = impulses;
    return make_preconditioner(form, sys, ex, po, nullptr);
  };
  for (const std::string &combo : opt.combos) {
    PrecondEntry e{PrecondKind::tree, nullptr, {}, 0, combo, true};
    const auto t0 = std::chrono::steady_clock::now();
    if (combo == "add_fibre_tree")
      e.P = std::make_unique<AveragePreconditioner>(build(PrecondKind::fibre, opt.weight),
                                                    build(PrecondKind::tree, opt.weight), combo);
    else if (combo == "mul_tree_fibre")
      e.P = std::make_unique<SymmetricProductPreconditioner>(
          *fs.op, build(PrecondKind::tree, opt.weight), build(PrecondKind::fibre, opt.weight),
          combo);
    else if (combo == "add_fibre_zs")
      e.P = std::make_unique<AveragePreconditioner>(
          build(PrecondKind::fibre, EdgeWeight::z), build(PrecondKind::fibre, EdgeWeight::straight),
          combo);
    else  // add_tree_zs
      e.P = std::make_unique<AveragePreconditioner>(
          build(PrecondKind::tree, EdgeWeight::z), build(PrecondKind::tree, EdgeWeight::straight),
          combo);
    e.setup_seconds = seconds_since(t0);
    fs.preconds.push_back(std::move(e));
  }
  return fs;
}

void describe_form(const FormSetup &fs, const Options &opt)
{
  std::printf("\n== %s form: N = %ld, maxiter %d\n", to_string(fs.form), long(fs.op->size()),
              fs.maxiter);
  std::printf("  r_r = ||r|| / ||%s||_F with ||%s||_F = %.6g (Frobenius norm of the assembled "
              "matrix); ||%s||_2 ~ %.6g (largest Ritz value, %d Lanczos steps)\n",
              fs.form == Form::body ? "K" : "A", fs.form == Form::body ? "K" : "A", fs.norm_fro,
              fs.form == Form::body ? "K" : "A", fs.norm_2, fs.norm_2_steps);
  std::printf("  ||rhs|| = %.6g%s\n", fs.rhs_norm,
              fs.form == Form::body ? " (G^T Sigma^-1 b)" : "");
  for (const PrecondEntry &e : fs.preconds) {
    std::printf("  precond %-7s setup %.3f s", e.name.c_str(), e.setup_seconds);
    if (!e.combined && (e.kind == PrecondKind::fibre || e.kind == PrecondKind::tree))
      std::printf("; %s weight: %d %s covering %d of %d body-body contacts (%.1f%%)",
                  to_string(opt.weight), e.stats.num_fibres,
                  e.kind == PrecondKind::fibre ? "fibres" : "trees", e.stats.contacts_in_fibres,
                  e.stats.num_contacts, 100.0 * e.stats.covered_fraction());
    std::printf("\n");
  }
}

// ---- one Krylov run ----

struct IterationRow {
  int iteration = 0;
  double rr = 0, rb = 0, ve = 0, ve_rel = 0;
};

struct Run {
  Method method;
  std::string precond;
  SolveResult result;
  std::vector<IterationRow> rows;
  double seconds = 0;
};

Run run_krylov(const FormSetup &fs, const PrecondEntry &pe, Method method,
               const ContactSystem &sys, const Reference &ref)
{
  const Exchange &ex = serial_exchange();
  Run run{method, pe.name, {}, {}, 0};
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
  stop.tol = 0;  // run the full maxiter iterations: the histories are the point
  stop.max_iter = fs.maxiter;
  Vector x = Vector::Zero(fs.op->size());
  const auto t0 = std::chrono::steady_clock::now();
  run.result = krylov_solve(method, *fs.op, *pe.P, fs.rhs, x, stop, &monitor);
  run.seconds = seconds_since(t0);
  if (run.rows.size() != run.result.history.size())
    throw std::logic_error("Krylov history and measurements differ in length");
  for (std::size_t i = 0; i < run.rows.size(); ++i)
    run.rows[i].iteration = run.result.history[i].iteration;
  return run;
}

// The record at kReportIteration, or the last one when the run stopped earlier (nullptr: none).
const IterationRow *row_at_report(const Run &run)
{
  for (const IterationRow &r : run.rows)
    if (r.iteration == kReportIteration) return &r;
  return run.rows.empty() ? nullptr : &run.rows.back();
}

void print_run_header()
{
  std::printf("  %-7s %-6s %6s %-14s %9s %9s %9s %10s %14s %8s %7s\n", "precond", "method",
              "iters", "stop", "r_r@100", "rb@100", "v_e@100", "ve_rel@100", "best ve_rel(k)",
              "to_1e-6", "s");
}

void print_run(const Run &run)
{
  const IterationRow *at = row_at_report(run);
  const bool early = at && at->iteration != kReportIteration;
  const char *mark = early ? "*" : "";
  std::string to_target = "-";
  const IterationRow *best = nullptr;
  for (const IterationRow &r : run.rows) {
    if (to_target == "-" && r.ve_rel <= kVelocityTarget) to_target = std::to_string(r.iteration);
    if (std::isfinite(r.ve_rel) && (!best || r.ve_rel < best->ve_rel)) best = &r;
  }
  const std::string best_s =
      best ? sci(best->ve_rel) + "(" + std::to_string(best->iteration) + ")" : "-";
  std::printf("  %-7s %-6s %6d %-14s %9s %9s %9s %10s %14s %8s %7.2f\n", run.precond.c_str(),
              to_string(run.method), run.result.iterations, to_string(run.result.reason),
              at ? (sci(at->rr) + mark).c_str() : "-", at ? (sci(at->rb) + mark).c_str() : "-",
              at ? (sci(at->ve) + mark).c_str() : "-",
              at ? (sci(at->ve_rel) + mark).c_str() : "-", best_s.c_str(), to_target.c_str(),
              run.seconds);
  std::fflush(stdout);
}

void write_run_csv(std::ostream &csv, Form form, const Run &run)
{
  for (const IterationRow &r : run.rows)
    csv << to_string(form) << ',' << to_string(run.method) << ',' << run.precond << ','
        << r.iteration << ',' << r.rr << ',' << r.rb << ',' << r.ve << ',' << r.ve_rel << '\n';
}

// ---- spectra ----

struct SpectrumRun {
  Form form;
  PrecondKind kind;
  std::string precond;  // name
  Eigen::Index n = 0;
  Spectrum s;
  std::string method;  // how it was computed
  bool complete = true;  // every eigenvalue (false: Lanczos Ritz values)
  double seconds = 0;
};

SpectrumRun compute_spectrum(const FormSetup &fs, const PrecondEntry &pe,
                             const ContactSystem &sys, KappaMethod how, int lanczos_steps)
{
  SpectrumRun run;
  run.form = fs.form;
  run.kind = pe.kind;
  run.precond = pe.name;
  run.n = fs.op->size();
  const auto t0 = std::chrono::steady_clock::now();
  const bool automatic = how == KappaMethod::automatic;
  const bool body_space = fs.form == Form::contact && pe.kind == PrecondKind::none &&
                          !pe.combined &&
                          uniform_sigma(sys) && sys.body_dofs() <= kDenseMaxSize;
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

void write_spectrum_file(const std::string &prefix, const SpectrumRun &run)
{
  const std::string path =
      prefix + "_" + to_string(run.form) + "_" + run.precond + ".csv";
  std::ofstream out = open_output(path);
  out.precision(17);
  out << "# fibre_analyze spectrum: form " << to_string(run.form) << ", precond "
      << run.precond << (run.precond == "none" ? " (A)" : " (P^-1 A)") << ", n "
      << run.n << "\n";
  out << "# method " << run.method
      << (run.complete ? " (all eigenvalues)" : " (Ritz values only)") << "\n";
  out << "# kappa_e " << run.s.kappa_e << " kappa " << run.s.kappa << " lambda_1 "
      << run.s.lambda_max << " lambda_r " << run.s.lambda_r << " above_gap " << run.s.r + 1
      << " gap_ratio " << run.s.gap_ratio << "\n";
  for (double e : run.s.eigenvalues) out << e << '\n';
  if (!out) throw InputError("cannot write '" + path + "'");
}

void print_kappa_table(const std::vector<SpectrumRun> &runs)
{
  std::printf("\n== kappa_e = lambda_1 / lambda_r of A (none) and P^-1 A; r = the last "
              "eigenvalue above the largest ratio of consecutive sorted eigenvalues\n");
  std::printf("   dense: all eigenvalues; body-space: the exact spectrum of A through "
              "M^-1/2 G^T G M^-1/2 (uniform Sigma); lanczos: Ritz values\n"
              "   (lambda_1 and lambda_r converged, the count above the gap unknown: '-')\n");
  std::printf("  %-8s %-7s %6s %11s %11s %11s %11s %9s %9s  %-34s %7s\n", "form", "precond", "n",
              "kappa_e", "kappa", "lambda_1", "lambda_r", "above_gap", "gap", "method", "s");
  for (const SpectrumRun &r : runs) {
    const std::string above = r.complete ? std::to_string(r.s.r + 1) : "-";
    std::printf("  %-8s %-7s %6ld %11.4g %11.4g %11.4g %11.4g %9s %9.3g  %-34s %7.2f\n",
                to_string(r.form), r.precond.c_str(), long(r.n), r.s.kappa_e, r.s.kappa,
                r.s.lambda_max, r.s.lambda_r, above.c_str(), r.s.gap_ratio, r.method.c_str(),
                r.seconds);
  }
  std::fflush(stdout);
}

void write_kappa_csv(std::ostream &out, const std::vector<SpectrumRun> &runs)
{
  out.precision(10);
  out << "form,precond,n,kappa_e,kappa,lambda_1,lambda_r,above_gap,gap_ratio,method,complete\n";
  for (const SpectrumRun &r : runs)
    out << to_string(r.form) << ',' << r.precond << ',' << r.n << ',' << r.s.kappa_e
        << ',' << r.s.kappa << ',' << r.s.lambda_max << ',' << r.s.lambda_r << ',' << r.s.r + 1
        << ',' << r.s.gap_ratio << ',' << r.method << ',' << (r.complete ? 1 : 0) << '\n';
}

// ---- the whole analysis ----

int analyze(const Options &opt)
{
  const auto t_start = std::chrono::steady_clock::now();
  int ghosts = 0;
  const ContactSystem sys = load_system(opt, ghosts);
  // Outputs are opened before the long computation so that a bad path fails at once.
  std::ofstream csv, kappa_csv;
  if (!opt.csv_path.empty()) csv = open_output(opt.csv_path);
  if (!opt.spectra_prefix.empty()) kappa_csv = open_output(opt.spectra_prefix + "_kappa.csv");

  describe(sys, opt, ghosts);
  if (sys.num_contacts() == 0) {
    std::printf("no contacts: nothing to analyse\n");
    return 0;
  }
  const bool zero_rhs = sys.rhs().norm() == 0;
  Reference ref;
  Vector impulses;
  if (!zero_rhs) {
    const auto t0 = std::chrono::steady_clock::now();
    ref = direct_reference(sys);
    std::printf("  reference (MUMPS, %.2f s): dv* from the body form, ||dv*|| = %.6g, "
                "refinement %.1e; contact-form lambda* gives ||M^-1 G^T lambda* - dv*|| / "
                "||dv*|| = %.2e\n",
                seconds_since(t0), ref.dv_norm, ref.refinement, ref.contact_velocity_error);
    impulses.resize(sys.num_contacts());
    for (int c = 0; c < sys.num_contacts(); ++c) impulses[c] = ref.lambda[sys.rows() * c];
  } else {
    std::printf("  the right-hand side is zero: no Krylov runs, spectra only\n");
  }
  if (opt.weight == EdgeWeight::impulse)
    std::printf("  impulse weight: normal impulses of the direct solution lambda*%s\n",
                zero_rhs ? " (zero rhs: falls back to z)" : "");
  const Vector *impulse_ptr = zero_rhs ? nullptr : &impulses;

  if (csv.is_open()) {
    csv << "# fibre_analyze " << opt.system_file << ": rr = ||r|| / ||A||_F with the true "
        << "residual r, rb = ||r|| / ||rhs||, ve = ||dv - dv*||, ve_rel = ve / ||dv*||\n";
    csv << "# sigma_scale " << opt.sigma_scale << "\n";
  }
  std::vector<FormSetup> forms;
  for (Form form : opt.forms) {
    forms.push_back(setup_form(form, sys, opt, impulse_ptr));
    const FormSetup &fs = forms.back();
    describe_form(fs, opt);
    if (csv.is_open())
      csv << "# size " << to_string(form) << ' ' << fs.op->size() << " norm_fro " << fs.norm_fro
          << " norm_2 " << fs.norm_2 << '\n';
  }
  if (csv.is_open()) csv << "form,method,precond,iteration,rr,rb,ve,ve_rel\n";

  if (!zero_rhs) {
    for (const FormSetup &fs : forms) {
      std::printf("\n== %s form runs (x0 = 0, %d iterations unless the method breaks down; "
                  "@100: at iteration 100, '*' = at the last iteration of a shorter run; "
                  "to_1e-6: first iteration with ve_rel <= 1e-6)\n",
                  to_string(fs.form), fs.maxiter);
      print_run_header();
      for (const PrecondEntry &pe : fs.preconds)
        for (Method m : opt.methods) {
          const Run run = run_krylov(fs, pe, m, sys, ref);
          print_run(run);
          if (csv.is_open()) write_run_csv(csv, fs.form, run);
        }
    }
    if (csv.is_open()) {
      csv.flush();
      if (!csv) throw InputError("cannot write '" + opt.csv_path + "'");
    }
  }

  if (opt.kappa) {
    std::vector<SpectrumRun> spectra;
    for (const FormSetup &fs : forms)
      for (const PrecondEntry &pe : fs.preconds) {
        spectra.push_back(compute_spectrum(fs, pe, sys, opt.kappa_method, opt.lanczos_steps));
        if (!opt.spectra_prefix.empty())
          write_spectrum_file(opt.spectra_prefix, spectra.back());
      }
    print_kappa_table(spectra);
    if (kappa_csv.is_open()) {
      write_kappa_csv(kappa_csv, spectra);
      if (!kappa_csv) throw InputError("cannot write '" + opt.spectra_prefix + "_kappa.csv'");
    }
  }
  std::printf("\ntotal %.1f s\n", seconds_since(t_start));
  return 0;
}

// MPI for MUMPS: initialised once, finalised on every way out of main.
struct MpiSession {
  MpiSession(int *argc, char ***argv) { MPI_Init(argc, argv); }
  ~MpiSession() { MPI_Finalize(); }
  MpiSession(const MpiSession &) = delete;
  MpiSession &operator=(const MpiSession &) = delete;
};

}  // namespace

int main(int argc, char **argv)
{
  Options opt;
  try {
    opt = parse_args(argc, argv);
  } catch (const UsageError &e) {
    std::fprintf(stderr, "fibre_analyze: %s\n(run 'fibre_analyze --help' for the usage)\n",
                 e.what());
    return 2;
  }
  if (opt.help) {
    std::fputs(kUsage, stdout);
    return 0;
  }
  MpiSession mpi(&argc, &argv);
  int nprocs = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &nprocs);
  if (nprocs != 1) {
    std::fprintf(stderr, "fibre_analyze: run on one process (got %d)\n", nprocs);
    return 2;
  }
  try {
    return analyze(opt);
  } catch (const InputError &e) {
    std::fflush(stdout);
    std::fprintf(stderr, "fibre_analyze: %s\n", e.what());
    return 2;
  } catch (const std::exception &e) {
    std::fflush(stdout);
    std::fprintf(stderr, "fibre_analyze: error: %s\n", e.what());
    return 1;
  }
}
