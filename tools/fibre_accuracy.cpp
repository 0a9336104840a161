// fibre_accuracy: the command line of fibre/accuracy_study.hpp. Replays one exported step with
// solver settings and prints each setting's error against the step's converged reference and
// its cost in K-product equivalents.
#include <mpi.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fibre/algebra/spook.hpp"
#include "fibre/core/text.hpp"
#include "fibre/frontend/settings.hpp"
#include "fibre/solvers/pgs.hpp"
#include "fibre/study/accuracy_study.hpp"

using namespace fibre;

namespace {

const char *const kUsage =
    R"(usage: fibre_accuracy STATE [options]

STATE is the prefix of a step that `fix fibre_contact export N prefix` wrote: STATE.sys (the
system) and STATE.lambda (the run's impulses and the warm start its solve began from). The tool
computes the step's converged nonsmooth solution twice (projected Gauss-Seidel and semismooth
Newton, to a complementarity residual of --target) and checks that they agree; then it replays
the step from the warm start with every setting and prints, against the reference, the relative
errors of the velocity change (translational, rotational) and of the impulses (normal, friction,
rolling, twisting), with the cost in K-product equivalents (the solve's time over one product
with K = M + G^T Sigma^-1 G, timed in the same run).

options:
  --setting "KEYWORDS"  fix fibre_contact solver keywords (form, solver, precond, weight, tol,
                        linear_tol, pass_tol, maxiter, active_set, sweeps, sweep_tol),
                        repeatable; the
                        empty string is the defaults. Without --setting: a standard grid.
  --repeat N            time each setting N times, keep the fastest (default 3)
  --target X            complementarity residual of the reference (default 1e-10)
  --csv FILE            also write the table as CSV
  --newton-basin        instead of the table: how far the exact semismooth Newton method
                        (nonsmooth_reference.hpp: sparse LU, line search) gets in 8 iterations
                        from the warm start and from projected Gauss-Seidel iterates at
                        complementarity residuals 1e-2, 1e-3 and 1e-4
  --help                this text
)";

const std::vector<std::string> kGrid = {
    "",
    "tol 1e-2",
    "tol 1e-4",
    "solver cg tol none",
    "solver cg tol 1e-3",
    "solver cg tol none sweeps 0",
    "solver cg tol none sweeps 200 sweep_tol 1e-4",
    "solver cg tol none active_set 10 sweeps 0",
    "solver cg tol none linear_tol 1e-8 active_set 10 sweeps 200 sweep_tol 1e-4",
    "solver pgs tol none sweeps 50 sweep_tol 1e-12",
    "solver pgs tol none sweeps 500 sweep_tol 1e-12",
    "solver pgs tol none sweeps 2000 sweep_tol 1e-12",
};

struct Options {
  std::string state, csv;
  std::vector<std::string> settings;
  int repeat = 3;
  double target = 1e-10;
  bool newton_basin = false;
};

std::vector<std::string> words(const std::string &text)
{
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

bool parse_args(int argc, char **argv, Options &opt)
{
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    long n = 0;
    if (a == "--help") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a == "--setting" && has) {
      opt.settings.push_back(argv[++i]);
    } else if (a == "--repeat" && has && to_long(argv[i + 1], n) && n > 0) {
      opt.repeat = static_cast<int>(n);
      ++i;
    } else if (a == "--target" && has && to_double(argv[i + 1], opt.target) && opt.target > 0) {
      ++i;
    } else if (a == "--newton-basin") {
      opt.newton_basin = true;
    } else if (a == "--csv" && has) {
      opt.csv = argv[++i];
    } else if (a.rfind("--", 0) != 0 && opt.state.empty()) {
      opt.state = a;
    } else {
      std::fprintf(stderr, "fibre_accuracy: bad argument '%s' (--help: the usage)\n", a.c_str());
      return false;
    }
  }
  if (opt.state.empty()) std::fprintf(stderr, "fibre_accuracy: no STATE (--help: the usage)\n");
  if (opt.settings.empty()) opt.settings = kGrid;
  return !opt.state.empty();
}

void print_row(const char *name, const StudyRow &r, std::FILE *csv)
{
  const StepAccuracy &e = r.error;
  std::printf("%-50s %9.3g %8.1f %6d %6d %6.1f %9.2e %9.2e %9.2e %9.2e %9.2e %9.2e %9.2e %9.2e\n",
              name, r.seconds, r.k_products, r.iterations, r.sweeps, r.sweep_equivalents,
              r.complementarity, r.error_estimate, e.dv_trans, e.dv_rot, e.lambda_n, e.lambda_t,
              e.lambda_roll, e.lambda_twist);
  if (csv)
    std::fprintf(csv, "\"%s\",%.6g,%.6g,%d,%d,%d,%.6g,%.6g,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n",
                 name, r.seconds, r.k_products, r.iterations, r.passes, r.sweeps, r.complementarity,
                 r.error_estimate, r.converged ? 1 : 0, e.dv_trans, e.dv_rot, e.lambda_n,
                 e.lambda_t, e.lambda_roll, e.lambda_twist, r.sweep_equivalents);
}

// Where Newton converges: it is the reference's second method, and a candidate to finish a
// step, but only if it converges from where a cheap solver leaves the impulses.
void newton_basin(const StepState &state)
{
  const ContactSystem &sys = state.sys;
  const Exchange &ex = state.exchange();
  const Cones cones(sys);
  const Vector b = spook_rhs(sys);
  const std::vector<Vec6> scale = row_scales(sys);
  std::printf("exact semismooth Newton, complementarity residual after each iteration:\n");
  for (const double start : {0.0, 1e-2, 1e-3, 1e-4}) {
    Vector lambda = state.warm;
    for (int c = 0; c < sys.num_contacts(); ++c) cones.project(lambda.data() + sys.rows() * c, c);
    int sweeps = 0;
    double r = complementarity(sys, ex, cones, b, lambda, scale);
    while (start > 0 && r > start && sweeps < 100000) {
      pgs(sys, ex, cones, b, scale, lambda, PgsControl{10, 0.0, 1 << 30});
      sweeps += 10;
      r = complementarity(sys, ex, cones, b, lambda, scale);
    }
    std::printf("from the warm start + %5d sweeps (%.1e):", sweeps, r);
    for (int it = 0; it < 8; ++it) {
      const NewtonResult nr = semismooth_newton(sys, cones, b, lambda, 1e-10, 1, ex);
      std::printf(" %.1e", nr.complementarity);
      if (nr.converged) break;
    }
    std::printf("\n");
  }
}

int run(const Options &opt)
{
  const StepState state = read_step_state(opt.state);
  const ContactSystem &sys = state.sys;
  std::printf("state %s: %d bodies, %d contacts, %d rows each\n", opt.state.c_str(),
              sys.num_bodies(), sys.num_contacts(), sys.rows());
  if (opt.newton_basin) {
    newton_basin(state);
    return 0;
  }
  const auto t0 = Clock::now();
  const Reference ref = nonsmooth_reference(
      sys, state.lambda, ReferenceOptions{opt.target, 2000000, 30}, state.exchange());
  if (state.images) std::printf("periodic images: from %s.images\n", opt.state.c_str());
  std::printf("reference (%.1f s): projected Gauss-Seidel %d sweeps, residual %.2e; semismooth "
              "Newton %d iterations, residual %.2e%s\n",
              seconds_since(t0), ref.sweeps, ref.complementarity_pgs, ref.newton.iterations,
              ref.newton.complementarity, ref.newton.converged ? "" : " (not converged)");
  std::printf("the two agree to %.2e in velocity, %.2e in impulses: %s\n", ref.agreement.velocity(),
              ref.agreement.impulse(), ref.confirmed() ? "confirmed" : "NOT confirmed");
  const double tk = k_product_seconds(sys);
  std::printf("one K product: %.3g s\n\n", tk);
  // full: the sweeps' cost in full sweeps (focused sweeps visit fewer contacts)
  std::printf("%-50s %9s %8s %6s %6s %6s %9s %9s %9s %9s %9s %9s %9s %9s\n", "setting", "seconds",
              "K-prods", "iters", "sweeps", "full", "residual", "estimate", "dv_trans", "dv_rot",
              "lam_n", "lam_t", "lam_roll", "lam_twist");
  std::FILE *csv = opt.csv.empty() ? nullptr : std::fopen(opt.csv.c_str(), "w");
  if (!opt.csv.empty() && !csv) throw std::runtime_error("cannot write " + opt.csv);
  if (csv)
    std::fprintf(
        csv,
        "setting,seconds,k_products,iterations,passes,sweeps,complementarity,error_estimate,"
        "converged,dv_trans,dv_rot,lambda_n,lambda_t,lambda_roll,lambda_twist,sweep_equivalents\n");
  StudyRow run_row;
  run_row.setting = "the run's own solve (export)";
  run_row.error = step_accuracy(sys, state.lambda, ref.lambda, state.exchange());
  print_row("(the run's own impulses)", run_row, nullptr);
  run_row.error = step_accuracy(sys, state.warm, ref.lambda, state.exchange());
  print_row("(the warm start alone)", run_row, nullptr);
  for (const std::string &text : opt.settings) {
    const Settings s = parse_settings(words(text));
    const StudyRow row = measure_setting(state, s.step, ref.lambda, tk, opt.repeat);
    print_row(text.empty() ? "(defaults)" : text.c_str(), row, csv);
  }
  if (csv) std::fclose(csv);
  return ref.confirmed() ? 0 : 3;
}

} // namespace

int main(int argc, char **argv)
{
  Options opt;
  if (!parse_args(argc, argv, opt)) return 2;
  MPI_Init(&argc, &argv);
  int rc = 0;
  try {
    rc = run(opt);
  } catch (const SettingsError &e) {
    std::fprintf(stderr, "fibre_accuracy: --setting: %s\n", e.what());
    rc = 2;
  } catch (const std::exception &e) {
    std::fprintf(stderr, "fibre_accuracy: %s\n", e.what());
    rc = 1;
  }
  MPI_Finalize();
  return rc;
}
