// Time to solution of one contact system (one time step's linear solve): the fibre/tree
// preconditioned Krylov methods in both forms against MUMPS on the same assembled system and
// Eigen's ConjugateGradient with IncompleteCholesky on the assembled matrix.
//
// A plain program (not a Google Benchmark registration): each figure is the median of
// --repeat timed runs and every ratio is formed from figures of this one run.
//
// Target: ve_rel = ||dv - dv*||_2 / ||dv*||_2 <= 1e-6, the velocity error of thesis eq.
// 5.1.14 as tools/fibre_analyze measures it: dv = M^-1 G^T lambda (contact form) or the
// iterate itself (body form); dv* from MUMPS on the body form K plus one refinement step.
//
// What each time includes (everything a time step pays from the assembled rhs b onwards):
//   Krylov: preconditioner setup (fibres/forest + factorization), the body-form rhs
//     G^T Sigma^-1 b and lambda recovery where the form needs them, and exactly k* iterations,
//     k* = the first iteration with ve_rel <= 1e-6, found beforehand by a monitored run of
//     the same method (tolerance 0, so that both runs make the same iterates).
//   MUMPS: assembly of A (contact) or K (body), analysis, factorization and solve
//     (fibre::direct_solve on MPI_COMM_SELF).
//   Eigen CG+IC: assembly of A or K, IncompleteCholesky (Eigen defaults: AMD ordering,
//     automatic shift) and CG with the loosest tolerance of 1e-3, 1e-4, ... that reaches the
//     target (found beforehand).
//
// Usage: bench_direct_vs_krylov [--repeat R] [--heap N]... [--sys FILE]... [--no-default]
//   Default cases: heap_scene(1400) and heap_scene(5000) (bench_scenes.hpp, material
//   parameters), the LAMMPS pile (tests/data/pile400.dump) when found, and every system file
//   given with --sys (e.g. exports of examples/silo and examples/material).
#include <mpi.h>
#include <unistd.h>

#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <time.h>
#include <fstream>
#include <functional>
#include <numeric>
#include <string>
#include <thread>
#include <vector>

#include "bench_scenes.hpp"
#include "fibre/algebra/assembly.hpp"
#include "fibre/io/system_io.hpp"
#include "fibre/precond/preconditioner_family.hpp"
#include "fibre/solvers/direct.hpp"
#include "fibre/solvers/krylov.hpp"

using namespace fibre;

namespace {

constexpr double kTarget = 1e-6;

// Process CPU time: the machine is shared, and the wall clock counts the waits for a core.
// (All solvers here are serial; run with OMP_NUM_THREADS=1 so that a threaded BLAS under
// MUMPS does not add a second thread's time.)
double now()
{
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// The BLAS that MUMPS runs on, from the process's mappings.
std::string blas_library()
{
  std::ifstream maps("/proc/self/maps");
  std::string line, found = "?";
  while (std::getline(maps, line)) {
    const auto p = line.find('/');
    if (p == std::string::npos) continue;
    const std::string path = line.substr(p);
    if (path.find("blas") != std::string::npos) return path;
  }
  return found;
}

double median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}

double timed(int repeat, const std::function<void()> &f)
{
  std::vector<double> t;
  for (int i = 0; i < repeat; ++i) {
    const double t0 = now();
    f();
    t.push_back(now() - t0);
  }
  return median(t);
}

struct Reference {
  Vector dv;
  double norm = 0;
};

Reference reference(const ContactSystem &sys)
{
  Reference ref;
  ref.dv = refined_body_solution(sys);
  ref.norm = ref.dv.norm();
  return ref;
}

double ve_rel(const Reference &ref, const Vector &dv)
{
  return (dv - ref.dv).norm() / ref.norm;
}

struct Row {
  std::string name;
  double seconds = NAN;
  int iterations = -1;
  double ve = NAN;
  double setup = NAN; // preconditioner / factorization share, where separable
};

void print_rows(const std::vector<Row> &rows, double mumps_body, double mumps_contact)
{
  std::printf("  %-30s %10s %9s %6s %9s %12s %14s\n", "solver", "time ms", "setup ms", "iters",
              "ve_rel", "MUMPS(K)/t", "MUMPS(A)/t");
  for (const Row &r : rows) {
    char iters[16] = "-";
    if (r.iterations >= 0) std::snprintf(iters, sizeof iters, "%d", r.iterations);
    if (std::isnan(r.seconds)) {
      std::printf("  %-30s %10s %9s %6s %9.2e %12s %14s   (target not reached)\n", r.name.c_str(),
                  "-", "-", iters, r.ve, "-", "-");
      continue;
    }
    char setup[16] = "-";
    if (!std::isnan(r.setup)) std::snprintf(setup, sizeof setup, "%.3f", 1e3 * r.setup);
    std::printf("  %-30s %10.3f %9s %6s %9.2e %11.1fx %13.1fx\n", r.name.c_str(), 1e3 * r.seconds,
                setup, iters, r.ve, mumps_body / r.seconds, mumps_contact / r.seconds);
  }
}

// ---- Krylov in one form ----

Row krylov_row(const ContactSystem &sys, const Reference &ref, Form form, PrecondKind kind,
               Method method, int repeat, int max_iter)
{
  const Exchange &ex = serial_exchange();
  Row row;
  row.name = std::string(to_string(form)) + " " + to_string(kind) + " " + to_string(method);
  const auto op = make_operator(form, sys, ex);
  auto to_dv = [&](const Vector &x) {
    return form == Form::body ? Vector(x) : body_from_lambda(sys, ex, x);
  };
  PrecondOptions po;
  po.kind = kind;
  // Search: the first iteration with ve_rel <= target.
  {
    const auto P = make_preconditioner(form, sys, ex, po);
    const Vector rhs = form == Form::body ? body_rhs(sys, ex, sys.rhs()) : sys.rhs();
    StopControl stop;
    stop.tol = 0;
    stop.max_iter = max_iter;
    double best = INFINITY;
    stop.accept = [&](int, const Vector &x) {
      const double e = ve_rel(ref, to_dv(x));
      best = std::min(best, e);
      return e <= kTarget;
    };
    Vector x = Vector::Zero(op->size());
    const SolveResult r = krylov_solve(method, *op, *P, rhs, x, stop);
    row.ve = best;
    if (!(best <= kTarget)) {
      row.iterations = r.iterations;
      return row;
    }
    row.iterations = r.iterations;
  }
  // Timed: setup + rhs + k* iterations + lambda.
  std::vector<double> total, setup;
  Vector lambda, dv;
  for (int i = 0; i < repeat; ++i) {
    const double t0 = now();
    const auto P = make_preconditioner(form, sys, ex, po);
    const double t1 = now();
    const Vector rhs = form == Form::body ? body_rhs(sys, ex, sys.rhs()) : sys.rhs();
    StopControl stop;
    stop.tol = 0;
    stop.max_iter = row.iterations;
    Vector x = Vector::Zero(op->size());
    krylov_solve(method, *op, *P, rhs, x, stop);
    lambda = form == Form::body ? lambda_from_body(sys, ex, sys.rhs(), x) : x;
    total.push_back(now() - t0);
    dv = to_dv(x);
    setup.push_back(t1 - t0);
  }
  row.seconds = median(total);
  row.setup = median(setup);
  // The body form's velocities are its iterate (lambda_from_body amplifies the error by
  // 1 / Sigma, doc/design.md section 7); the contact form's are M^-1 G^T lambda.
  row.ve = ve_rel(ref, dv);
  return row;
}

// ---- MUMPS ----

Row mumps_row(const ContactSystem &sys, const Reference &ref, Form form, int repeat)
{
  const Exchange &ex = serial_exchange();
  Row row;
  row.name = std::string("MUMPS ") + (form == Form::body ? "K (body)" : "A (contact)");
  Vector lambda;
  row.seconds =
      timed(repeat, [&] { lambda = direct_solve(form, sys, ex, sys.rhs(), MPI_COMM_SELF); });
  row.ve = ve_rel(ref, body_from_lambda(sys, ex, lambda));
  return row;
}

// ---- Eigen CG + IncompleteCholesky on the assembled matrix ----

Row eigen_row(const ContactSystem &sys, const Reference &ref, Form form, int repeat)
{
  const Exchange &ex = serial_exchange();
  using CG = Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower | Eigen::Upper,
                                      Eigen::IncompleteCholesky<double>>;
  Row row;
  row.name = std::string("Eigen CG+IC ") + (form == Form::body ? "K (body)" : "A (contact)");
  auto solve = [&](double tol, int &iters) -> Vector {
    const SparseMatrix M = form == Form::body ? assemble_K(sys) : assemble_A(sys);
    const Vector rhs = form == Form::body ? body_rhs(sys, ex, sys.rhs()) : sys.rhs();
    CG cg;
    cg.setTolerance(tol);
    cg.setMaxIterations(5000);
    cg.compute(M);
    if (cg.info() != Eigen::Success) throw std::runtime_error("IncompleteCholesky failed");
    const Vector x = cg.solve(rhs);
    iters = static_cast<int>(cg.iterations());
    return form == Form::body ? x : body_from_lambda(sys, ex, x);
  };
  double tol = 1e-3;
  double best = INFINITY;
  int iters = 0;
  for (; tol >= 1e-15; tol /= 10) {
    const double e = ve_rel(ref, solve(tol, iters));
    best = std::min(best, e);
    if (e <= kTarget) break;
  }
  row.ve = best;
  row.iterations = iters;
  if (!(best <= kTarget)) return row;
  Vector dv;
  row.seconds = timed(repeat, [&] { dv = solve(tol, iters); });
  row.ve = ve_rel(ref, dv);
  row.name += " tol " + [&] {
    char b[16];
    std::snprintf(b, sizeof b, "%.0e", tol);
    return std::string(b);
  }();
  return row;
}

// ---- one case ----

void run_case(const std::string &name, const ContactSystem &sys, int repeat, bool all_methods)
{
  std::printf("\n== %s: %d bodies, %d contacts (%d walls), %d rows; contact form N = %ld, body "
              "form N = %ld\n",
              name.c_str(), sys.num_bodies(), sys.num_contacts(),
              int(std::count_if(sys.contacts().begin(), sys.contacts().end(),
                                [](const Contact &c) { return c.is_wall(); })),
              sys.rows(), long(sys.contact_dofs()), long(sys.body_dofs()));
  std::fflush(stdout);
  const Reference ref = reference(sys);
  std::vector<Row> rows;
  const Row mk = mumps_row(sys, ref, Form::body, repeat);
  const Row ma = mumps_row(sys, ref, Form::contact, repeat);
  rows.push_back(mk);
  rows.push_back(ma);
  rows.push_back(eigen_row(sys, ref, Form::body, repeat));
  rows.push_back(eigen_row(sys, ref, Form::contact, repeat));
  const std::vector<Method> methods =
      all_methods ? std::vector<Method>{Method::cg, Method::cr, Method::minres}
                  : std::vector<Method>{Method::cg};
  for (Form form : {Form::body, Form::contact})
    for (PrecondKind kind : {PrecondKind::tree, PrecondKind::fibre, PrecondKind::block})
      for (Method m : methods) {
        // The contact form stalls above the target on stiff systems (doc/design.md section 7):
        // give it room, but not forever.
        const int max_iter = form == Form::body ? 3000 : 1500;
        rows.push_back(krylov_row(sys, ref, form, kind, m, repeat, max_iter));
        std::fflush(stdout);
      }
  print_rows(rows, mk.seconds, ma.seconds);
  const Row *best = nullptr;
  for (const Row &r : rows)
    if (!std::isnan(r.seconds) && r.name.rfind("MUMPS", 0) != 0 && r.name.rfind("Eigen", 0) != 0 &&
        (!best || r.seconds < best->seconds))
      best = &r;
  if (best)
    std::printf("  fastest Krylov: %s, %.3f ms: %.1fx faster than MUMPS on K, %.1fx than MUMPS on "
                "A (target >= 10x at 5000 bodies)\n",
                best->name.c_str(), 1e3 * best->seconds, mk.seconds / best->seconds,
                ma.seconds / best->seconds);
  std::fflush(stdout);
}

} // namespace

int main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  int repeat = 5;
  bool defaults = true, all_methods = true;
  std::vector<int> heaps;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeat" && i + 1 < argc)
      repeat = std::atoi(argv[++i]);
    else if (a == "--heap" && i + 1 < argc)
      heaps.push_back(std::atoi(argv[++i]));
    else if (a == "--sys" && i + 1 < argc)
      files.push_back(argv[++i]);
    else if (a == "--no-default")
      defaults = false;
    else if (a == "--cg-only")
      all_methods = false;
    else {
      std::fprintf(stderr,
                   "usage: %s [--repeat R] [--heap N]... [--sys FILE]... [--no-default] "
                   "[--cg-only]\n",
                   argv[0]);
      MPI_Finalize();
      return 2;
    }
  }
  if (defaults && heaps.empty()) heaps = {1400, 5000};
  char host[256] = "?";
  gethostname(host, sizeof host);
  const std::time_t t = std::time(nullptr);
  char date[64];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&t));
  std::printf("bench_direct_vs_krylov: %s, host %s, %u hardware threads (all solvers serial: "
              "1 core, MUMPS on MPI_COMM_SELF), median of %d runs, process CPU time\n",
              date, host, std::thread::hardware_concurrency(), repeat);
  std::printf("BLAS under MUMPS: %s\n", blas_library().c_str());
  std::printf("target ve_rel = ||dv - dv*||_2 / ||dv*||_2 <= %.0e, dv* = MUMPS on K + one "
              "refinement step\n",
              kTarget);
  try {
    for (int n : heaps) {
      const ContactSystem sys = bench::heap_scene(n);
      run_case("heap_scene(" + std::to_string(n) + ")", sys, repeat, all_methods);
    }
#ifdef FIBRE_BENCH_DATA_DIR
    if (defaults) {
      const std::string dump = std::string(FIBRE_BENCH_DATA_DIR) + "/pile400.dump";
      if (std::ifstream(dump).good())
        run_case("LAMMPS pile400 (tests/data, SceneParams defaults)",
                 lammps_pile_scene(dump, SceneParams{}), repeat, all_methods);
    }
#endif
    for (const std::string &f : files) run_case(f, read_system_file(f), repeat, all_methods);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  MPI_Finalize();
  return 0;
}
