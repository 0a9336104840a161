// Report: fibres (thesis Algorithm 4) per edge weight, the spanning forest, and the setup and
// apply times of the preconditioners against the number of contacts.
//
// Scenes: pile_scene(400) and pile_scene(2000) (ballistic deposition), and the 400-sphere pile
// poured by native LAMMPS (tests/data/pile400.dump, doc/design.md section 7). For the impulse
// weight, the normal impulses come from a solve of the step (body form, tree preconditioner).
// Times are the best of several runs (steady clock) on whatever machine runs the report.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>

#include "fibre/precond/preconditioner_family.hpp"
#include "fibre/scenes.hpp"
#include "fibre/solvers/krylov.hpp"

using namespace fibre;

namespace {

const EdgeWeight kWeights[] = {EdgeWeight::z, EdgeWeight::straight, EdgeWeight::impulse};

int wall_contacts(const ContactSystem &sys)
{
  int n = 0;
  for (const Contact &k : sys.contacts()) n += k.is_wall();
  return n;
}

// Normal impulses of the step: lambda from the body form (doc/design.md section 7).
Vector normal_impulses(const ContactSystem &sys)
{
  const Exchange &ex = serial_exchange();
  BodySpaceOperator K(sys, ex);
  PrecondOptions opt;
  opt.kind = PrecondKind::tree;
  const auto P = make_preconditioner(Form::body, sys, ex, opt);
  const Vector rhs = body_rhs(sys, ex, sys.rhs());
  Vector dv = Vector::Zero(sys.body_dofs());
  StopControl stop;
  stop.tol = 1e-10;
  stop.max_iter = 2000;
  krylov_solve(Method::cg, K, *P, rhs, dv, stop);
  const Vector lambda = lambda_from_body(sys, ex, sys.rhs(), dv);
  Vector ln(sys.num_contacts());
  for (int c = 0; c < sys.num_contacts(); ++c) ln[c] = lambda[Eigen::Index(sys.rows()) * c];
  return ln;
}

double mean_length(const FibreStats &s)
{
  return s.num_fibres > 0 ? double(s.contacts_in_fibres) / s.num_fibres : 0.0;
}

int longest(const FibreStats &s)
{
  for (int k = static_cast<int>(s.length_histogram.size()) - 1; k > 0; --k)
    if (s.length_histogram[k] > 0) return k;
  return 0;
}

void fibre_table(const std::string &name, const ContactSystem &sys)
{
  const Vector impulses = normal_impulses(sys);
  std::printf("\n%s: %d bodies, %d contacts (%d body-body, %d wall)\n", name.c_str(),
              sys.num_bodies(), sys.num_contacts(), sys.num_contacts() - wall_contacts(sys),
              wall_contacts(sys));
  std::printf("  %-9s %7s %9s %8s %8s %9s | %6s %8s %9s\n", "weight", "fibres", "mean len",
              "longest", "in fibre", "covered", "trees", "edges", "covered");
  for (EdgeWeight w : kWeights) {
    const Fibres f = build_fibres(sys, w, &impulses, true);
    const Forest t = build_forest(sys, w, &impulses, true);
    const FibreStats &s = f.stats;
    std::printf("  %-9s %7d %9.2f %8d %8d %8.1f%% | %6d %8d %8.1f%%\n", to_string(w), s.num_fibres,
                mean_length(s), longest(s), s.contacts_in_fibres, 100 * s.covered_fraction(),
                t.stats.num_fibres, t.num_edges, 100 * t.stats.covered_fraction());
    EXPECT_GT(s.num_fibres, 0);
    EXPECT_GT(s.covered_fraction(), 0.0);
    EXPECT_LE(s.covered_fraction(), 1.0);
    EXPECT_GE(t.stats.covered_fraction(), s.covered_fraction()); // the forest holds the fibres
  }
  // Where fibres lie: share of fibre contacts whose normal is within 30 degrees of vertical.
  for (EdgeWeight w : kWeights) {
    const Fibres f = build_fibres(sys, w, &impulses, true);
    int vertical = 0;
    for (int c : f.contacts) vertical += std::abs(sys.contacts()[c].normal.z()) > 0.866;
    double load = 0, all_load = 0;
    for (int c : f.contacts) load += impulses[c];
    int bb = 0;
    for (int c = 0; c < sys.num_contacts(); ++c)
      if (!sys.contacts()[c].is_wall()) {
        all_load += impulses[c];
        ++bb;
      }
    std::printf("  %-9s near-vertical fibre contacts %5.1f%%, mean normal impulse on fibres "
                "%.3g (all body-body %.3g)\n",
                to_string(w), f.contacts.empty() ? 0.0 : 100.0 * vertical / f.contacts.size(),
                f.contacts.empty() ? 0.0 : load / f.contacts.size(), bb ? all_load / bb : 0.0);
  }
}

template <class F> double best_ms(F f, int reps)
{
  double best = 1e300;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    best = std::min(
        best,
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

} // namespace

TEST(ReportPreconditioners, FibreStatistics)
{
  SceneParams p;
  fibre_table("pile_scene(400)", pile_scene(400, p));
  fibre_table("pile_scene(2000)", pile_scene(2000, p));
  const std::string dump = FIBRE_TEST_DATA_DIR "/pile400.dump";
  if (std::ifstream(dump).good()) fibre_table("LAMMPS pile400", lammps_pile_scene(dump, p));
}

TEST(ReportPreconditioners, SetupAndApplyTimes)
{
  const PrecondKind kinds[] = {PrecondKind::block, PrecondKind::fibre, PrecondKind::tree};
  std::printf("\nSetup / apply time (ms, best of runs) vs contacts, z weight\n");
  std::printf("  %8s %8s", "bodies", "contacts");
  for (Form form : {Form::contact, Form::body})
    for (PrecondKind k : kinds)
      std::printf(" %15s", (std::string(to_string(form)) + "/" + to_string(k)).c_str());
  std::printf("\n");
  for (int n : {400, 2000, 8000}) {
    const ContactSystem sys = pile_scene(n, SceneParams{});
    std::printf("  %8d %8d", sys.num_bodies(), sys.num_contacts());
    for (Form form : {Form::contact, Form::body})
      for (PrecondKind k : kinds) {
        PrecondOptions opt;
        opt.kind = k;
        const int reps = n <= 2000 ? 20 : 5;
        const double setup =
            best_ms([&] { make_preconditioner(form, sys, serial_exchange(), opt); }, reps);
        const auto P = make_preconditioner(form, sys, serial_exchange(), opt);
        const Vector r = Vector::Ones(form == Form::contact ? sys.contact_dofs() : sys.body_dofs());
        Vector z;
        const double apply = best_ms([&] { P->apply(r, z); }, reps);
        std::printf(" %7.3f/%7.3f", setup, apply);
        EXPECT_TRUE(z.allFinite());
      }
    std::printf("\n");
  }
}
