// Report: kappa_e (doc/design.md section 4) of every preconditioner on pile_scene(400), in both
// forms, ordered as measured. Compare with the prototype table of doc/design.md section 7.
//
// Sigma = 1e-8 as in that table (t = 1e-8; the compliance is chosen to give it): null(G^T)
// then sits far below the range of G, which is the gap kappa_e is about. Lanczos (capped)
// is tried first and kept when it converged; otherwise the dense path decides.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "fibre/precond/preconditioner_family.hpp"
#include "fibre/scenes.hpp"
#include "fibre/study/spectra.hpp"

using namespace fibre;

namespace {

struct Row {
  PrecondKind kind;
  Spectrum s;
  std::string method;
  double seconds;
};

// Eigenvalues per decade, low to high: "1e-8:12 1e-7:0 ...".
std::string decades(const std::vector<double> &ev)
{
  if (ev.empty()) return "";
  const int lo = static_cast<int>(std::floor(std::log10(ev.back())));
  const int hi = static_cast<int>(std::floor(std::log10(ev.front())));
  std::vector<int> count(hi - lo + 1, 0);
  for (double e : ev) ++count[static_cast<int>(std::floor(std::log10(e))) - lo];
  std::string s;
  for (int d = lo; d <= hi; ++d)
    s += (d > lo ? " " : "") + std::string("1e") + std::to_string(d) + ":" +
         std::to_string(count[d - lo]);
  return s;
}

Row measure(Form form, PrecondKind kind, const ContactSystem &sys)
{
  PrecondOptions opt;
  opt.kind = kind;
  const auto t0 = std::chrono::steady_clock::now();
  const auto P = make_preconditioner(form, sys, serial_exchange(), opt);
  LanczosOptions lo;
  lo.max_steps = 150; // beyond this the dense path is cheaper here
  Row row{kind, lanczos_spectrum(form, sys, serial_exchange(), *P, lo), "", 0};
  if (row.s.converged) {
    row.method = "lanczos " + std::to_string(row.s.iterations);
  } else {
    row.s = dense_spectrum(*make_operator(form, sys, serial_exchange()), *P);
    row.method = "dense";
  }
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return row;
}

} // namespace

TEST(Report, KappaEffectiveOnPile400)
{
  SceneParams p;
  p.compliance = 1e-8 * p.spook.h * p.spook.h * (1.0 + 4.0 * p.spook.damping) / 4.0;
  const ContactSystem sys = pile_scene(400, p);
  int walls = 0;
  for (const Contact &c : sys.contacts()) walls += c.is_wall();
  std::printf("\nkappa_e on pile_scene(400): %d bodies, %d contacts (%d on walls), %d rows each,"
              " Sigma = %.3g\n",
              sys.num_bodies(), sys.num_contacts(), walls, sys.rows(), sys.sigma()[0]);
  std::printf("kappa_e = lambda_1 / lambda_r, r = last eigenvalue above the largest ratio of\n"
              "consecutive sorted eigenvalues of P^-1 A (see spectra.hpp)\n");
  for (Form form : {Form::contact, Form::body}) {
    std::vector<Row> rows;
    for (PrecondKind k : {PrecondKind::none, PrecondKind::jacobi, PrecondKind::block,
                          PrecondKind::fibre, PrecondKind::tree})
      rows.push_back(measure(form, k, sys));
    std::stable_sort(rows.begin(), rows.end(),
                     [](const Row &a, const Row &b) { return a.s.kappa_e < b.s.kappa_e; });
    const long n = form == Form::contact ? long(sys.contact_dofs()) : long(sys.body_dofs());
    std::printf("\n%s form (n = %ld), best first:\n", to_string(form), n);
    std::printf("  %-7s %12s %12s %11s %11s %10s  %-12s %6s\n", "precond", "kappa_e", "kappa",
                "lambda_1", "lambda_r", "gap", "method", "s");
    for (const Row &r : rows) {
      std::printf("  %-7s %12.4g %12.4g %11.4g %11.4g %10.3g  %-12s %6.2f\n", to_string(r.kind),
                  r.s.kappa_e, r.s.kappa, r.s.lambda_max, r.s.lambda_r, r.s.gap_ratio,
                  r.method.c_str(), r.seconds);
      EXPECT_GE(r.s.kappa_e, 1.0);
      EXPECT_LE(r.s.kappa_e, r.s.kappa * (1 + 1e-12));
    }
    for (const Row &r : rows)
      if (r.method == "dense")
        std::printf("  %-7s eigenvalues per decade: %s\n", to_string(r.kind),
                    decades(r.s.eigenvalues).c_str());
  }
  std::fflush(stdout);
}
