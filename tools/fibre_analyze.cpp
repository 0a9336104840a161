// fibre_analyze: the command line of fibre/analysis.hpp. Convergence histories and spectra of
// one contact system, per form x Krylov method x preconditioner (thesis sections 5-6: r_r,
// v_e, kappa_e); analysis.hpp states what is measured and how. This file parses the
// arguments, reads the system, calls the library and prints.
//
// Input is a system file as `fix fibre_contact export N prefix` writes it (system_io.hpp).
#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "fibre/core/text.hpp"
#include "fibre/io/system_io.hpp"
#include "fibre/study/analysis.hpp"

using namespace fibre;

namespace {

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

struct Options {
  std::string system_file;
  AnalysisOptions analysis;
  std::string csv_path;
  std::string spectra_prefix;
  double sigma_scale = 1.0;
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
                          const std::string &allowed)
{
  std::vector<T> out;
  for (const std::string &item : split_list(option, value)) {
    T v{};
    if (!parse(item, v) || !valid(v))
      throw UsageError(option + ": unknown entry '" + item + "' (allowed: " + allowed + ")");
    if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
  }
  return out;
}
template <class T> std::vector<T> parse_list(const std::string &option, const std::string &value)
{
  return parse_list<T>(
      option, value, [](T) { return true; }, choices<T>());
}

int parse_positive_int(const std::string &option, const std::string &value)
{
  long v = 0;
  if (!to_long(value, v) || v < 1 || v > INT_MAX)
    throw UsageError(option + " needs a positive integer, got '" + value + "'");
  return static_cast<int>(v);
}

double parse_positive_real(const std::string &option, const std::string &value)
{
  double v = 0;
  if (!to_double(value, v) || !(v > 0))
    throw UsageError(option + " needs a positive finite number, got '" + value + "'");
  return v;
}

template <class E>
E parse_one(const std::string &option, const char *what, const std::string &value)
{
  E v{};
  if (!parse(value, v))
    throw UsageError(option + ": unknown " + what + " '" + value + "' (allowed: " + choices<E>() +
                     ")");
  return v;
}

Options parse_args(int argc, char **argv)
{
  Options opt;
  AnalysisOptions &an = opt.analysis;
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
    const char *const known[] = {"--form",        "--methods", "--precond",      "--weight",
                                 "--maxiter",     "--csv",     "--spectra",      "--kappa",
                                 "--sigma-scale", "--combine", "--lanczos-steps"};
    if (std::find(std::begin(known), std::end(known), arg) == std::end(known))
      throw UsageError("unknown option '" + arg + "'");
    if (!have_value) {
      if (i + 1 >= argc) throw UsageError(arg + " needs a value");
      value = argv[++i];
    }
    if (arg == "--form") {
      if (value == "both") {
        an.forms = {Form::contact, Form::body};
      } else {
        Form f;
        if (!parse(value, f))
          throw UsageError("--form: unknown form '" + value + "' (allowed: " + choices<Form>() +
                           "|both)");
        an.forms = {f};
      }
    } else if (arg == "--methods") {
      an.methods = parse_list<Method>(arg, value, is_krylov, "cg|cr|minres");
    } else if (arg == "--precond") {
      an.preconds = parse_list<PrecondKind>(arg, value);
    } else if (arg == "--weight") {
      an.weight = parse_one<EdgeWeight>(arg, "weight", value);
    } else if (arg == "--maxiter") {
      an.maxiter = parse_positive_int(arg, value);
    } else if (arg == "--csv") {
      if (value.empty()) throw UsageError("--csv needs a file name");
      opt.csv_path = value;
    } else if (arg == "--spectra") {
      if (value.empty()) throw UsageError("--spectra needs a file prefix");
      opt.spectra_prefix = value;
      an.spectra = true;
    } else if (arg == "--kappa") {
      an.kappa_method = parse_one<KappaMethod>(arg, "method", value);
      an.spectra = true;
    } else if (arg == "--sigma-scale") {
      opt.sigma_scale = parse_positive_real(arg, value);
    } else if (arg == "--lanczos-steps") {
      an.lanczos_steps = parse_positive_int(arg, value);
    } else if (arg == "--combine") {
      an.combinations = parse_list<Combination>(arg, value);
    }
  }
  if (positional.empty()) throw UsageError("no system file given");
  if (positional.size() > 1) throw UsageError("more than one system file given");
  opt.system_file = positional.front();
  return opt;
}

// ---- input and output ----

std::string sci(double v)
{
  if (std::isnan(v)) return "nan";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2e", v);
  return buf;
}

std::ofstream open_output(const std::string &path)
{
  std::ofstream out(path);
  if (!out) throw InputError("cannot write '" + path + "'");
  return out;
}

void check_written(std::ofstream &out, const std::string &path)
{
  out.flush();
  if (!out) throw InputError("cannot write '" + path + "'");
}

AnalysisSystem load_system(const Options &opt)
{
  ContactSystem read;
  try {
    read = read_system_file(opt.system_file);
  } catch (const std::exception &e) {
    throw InputError(e.what());
  }
  try {
    return prepare_system(read, opt.sigma_scale);
  } catch (const std::invalid_argument &e) {
    // e.g. a compliance that the scale takes to 0 or to infinity
    throw InputError("--sigma-scale " + format_g(opt.sigma_scale) + ": " + e.what());
  }
}

// ---- printing ----

void describe(const AnalysisSystem &in, const Options &opt)
{
  const ContactSystem &sys = in.system;
  const SystemSummary s = summarize(sys);
  std::printf("system %s\n", opt.system_file.c_str());
  std::printf("  %d bodies, %d contacts (%d on walls), %d rows per contact\n", sys.num_bodies(),
              sys.num_contacts(), s.walls, sys.rows());
  if (in.ghosts > 0)
    std::printf("  note: %d ghost bodies (a one-process export of a parallel run) are analysed "
                "as ordinary bodies of this local system\n",
                in.ghosts);
  if (sys.num_contacts() == 0) return;
  std::printf("  contact form: N = %ld (A = G M^-1 G^T + Sigma); body form: N = %ld "
              "(K = M + G^T Sigma^-1 G)\n",
              long(sys.contact_dofs()), long(sys.body_dofs()));
  std::printf("  h = %g, damping %g steps; %ld active rows (%ld masked)\n", sys.params().h,
              sys.params().damping, s.active_rows, s.masked_rows);
  if (s.active_rows > 0)
    std::printf("  Sigma in [%.4g, %.4g] (compliance scale %g), mean diag(G M^-1 G^T) = %.4g, "
                "mean Sigma / that = %.3g\n",
                s.sigma_min, s.sigma_max, opt.sigma_scale, s.mean_diag, s.mean_sigma / s.mean_diag);
  std::printf("  ||b|| = %.4g\n", s.rhs_norm);
}

void describe_reference(const Analysis &an, EdgeWeight weight)
{
  const Reference &ref = an.reference;
  if (!an.zero_rhs)
    std::printf("  reference (MUMPS, %.2f s): dv* from the body form, ||dv*|| = %.6g, "
                "refinement %.1e; contact-form lambda* gives ||M^-1 G^T lambda* - dv*|| / "
                "||dv*|| = %.2e\n",
                ref.seconds, ref.dv_norm, ref.refinement, ref.contact_velocity_error);
  else
    std::printf("  the right-hand side is zero: no Krylov runs, spectra only\n");
  if (weight == EdgeWeight::impulse)
    std::printf("  impulse weight: normal impulses of the direct solution lambda*%s\n",
                an.zero_rhs ? " (zero rhs: falls back to z)" : "");
}

void describe_form(const FormSetup &fs, EdgeWeight weight)
{
  const char *A = fs.form == Form::body ? "K" : "A";
  std::printf("\n== %s form: N = %ld, maxiter %d\n", to_string(fs.form), long(fs.op->size()),
              fs.maxiter);
  std::printf("  r_r = ||r|| / ||%s||_F with ||%s||_F = %.6g (Frobenius norm of the assembled "
              "matrix); ||%s||_2 ~ %.6g (largest Ritz value, %d Lanczos steps)\n",
              A, A, fs.norm_fro, A, fs.norm_2, fs.norm_2_steps);
  std::printf("  ||rhs|| = %.6g%s\n", fs.rhs_norm,
              fs.form == Form::body ? " (G^T Sigma^-1 b)" : "");
  for (const PrecondEntry &e : fs.preconds) {
    std::printf("  precond %-7s setup %.3f s", e.name.c_str(), e.setup_seconds);
    if (!e.combined && (e.kind == PrecondKind::fibre || e.kind == PrecondKind::tree))
      std::printf("; %s weight: %d %s covering %d of %d body-body contacts (%.1f%%)",
                  to_string(weight), e.stats.num_fibres,
                  e.kind == PrecondKind::fibre ? "fibres" : "trees", e.stats.contacts_in_fibres,
                  e.stats.num_contacts, 100.0 * e.stats.covered_fraction());
    std::printf("\n");
  }
  std::fflush(stdout);
}

void print_run_header(const FormSetup &fs)
{
  std::printf("\n== %s form runs (x0 = 0, %d iterations unless the method breaks down; "
              "@100: at iteration 100, '*' = at the last iteration of a shorter run; "
              "to_1e-6: first iteration with ve_rel <= 1e-6)\n",
              to_string(fs.form), fs.maxiter);
  std::printf("  %-7s %-6s %6s %-14s %9s %9s %9s %10s %14s %8s %7s\n", "precond", "method", "iters",
              "stop", "r_r@100", "rb@100", "v_e@100", "ve_rel@100", "best ve_rel(k)", "to_1e-6",
              "s");
}

void print_run(const Run &run)
{
  const IterationRow *at = row_at_report(run);
  const char *mark = at && at->iteration != kReportIteration ? "*" : "";
  const int to = iterations_to(run);
  const std::string to_target = to >= 0 ? std::to_string(to) : "-";
  const IterationRow *best = best_velocity(run);
  const std::string best_s =
      best ? sci(best->ve_rel) + "(" + std::to_string(best->iteration) + ")" : "-";
  auto cell = [&](double IterationRow::*field) {
    return at ? sci(at->*field) + mark : std::string("-");
  };
  std::printf("  %-7s %-6s %6d %-14s %9s %9s %9s %10s %14s %8s %7.2f\n", run.precond.c_str(),
              to_string(run.method), run.result.iterations, to_string(run.result.reason),
              cell(&IterationRow::rr).c_str(), cell(&IterationRow::rb).c_str(),
              cell(&IterationRow::ve).c_str(), cell(&IterationRow::ve_rel).c_str(), best_s.c_str(),
              to_target.c_str(), run.seconds);
  std::fflush(stdout);
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

// ---- the whole analysis ----

int analyze(const Options &opt)
{
  const auto t_start = Clock::now();
  const AnalysisSystem in = load_system(opt);
  const ContactSystem &sys = in.system;
  // Outputs are opened before the long computation so that a bad path fails at once.
  std::ofstream csv, kappa_csv;
  const std::string kappa_path = opt.spectra_prefix + "_kappa.csv";
  if (!opt.csv_path.empty()) csv = open_output(opt.csv_path);
  if (!opt.spectra_prefix.empty()) kappa_csv = open_output(kappa_path);

  describe(in, opt);
  if (sys.num_contacts() == 0) {
    std::printf("no contacts: nothing to analyse\n");
    return 0;
  }
  const EdgeWeight weight = opt.analysis.weight;
  AnalysisProgress progress;
  progress.reference = [&](const Analysis &an) { describe_reference(an, weight); };
  progress.form = [&](const FormSetup &fs) { describe_form(fs, weight); };
  const FormSetup *table = nullptr; // the form whose run table is open
  progress.run = [&](const FormSetup &fs, const Run &run) {
    if (table != &fs) print_run_header(fs);
    table = &fs;
    print_run(run);
  };
  progress.spectrum = [&](const SpectrumRun &run) {
    if (opt.spectra_prefix.empty()) return;
    const std::string path = spectrum_path(opt.spectra_prefix, run);
    std::ofstream out = open_output(path);
    write_spectrum(out, run);
    check_written(out, path);
  };
  const Analysis an = analyze(sys, opt.analysis, progress);
  if (csv.is_open()) {
    write_history_csv(csv, an, opt.system_file, opt.sigma_scale);
    check_written(csv, opt.csv_path);
  }
  if (opt.analysis.spectra) {
    print_kappa_table(an.spectra);
    if (kappa_csv.is_open()) {
      write_kappa_csv(kappa_csv, an.spectra);
      check_written(kappa_csv, kappa_path);
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

} // namespace

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
