// Sweeps (or solver work) to reach a velocity-change error of 1e-3 against the converged
// reference, on settled square-lattice piles of 10, 20 and 40 layers (5 x 5 columns of spheres
// of radius 0.5 touching their neighbours, on a floor, under gravity, mu 0.5): cold projected
// Gauss-Seidel (from zero), warm (from the converged impulses of the same pile under a 10%
// lighter load: a load change, as when grains land on a pile), the same two with nonlinear CG
// and with fibre-block corrections (fbgs), and the step solver's default (the tree-preconditioned
// pass, then the sweeps), warm. Each pile twice: its contacts numbered layer by layer from the
// floor (a sweep carries the load down in one pass) and shuffled. PGS needs about
// (chain length)^2 sweeps for a load to travel down a chain in a random order; the target is at
// most linear growth from 10 to 40 layers. A plain program; its table is in bench/README.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <vector>

#include "bench_scenes.hpp"
#include "fibre/algebra/operators.hpp"
#include "fibre/solvers/pgs.hpp"
#include "fibre/study/accuracy_study.hpp"
#include "fibre/study/nonsmooth_reference.hpp"

using namespace fibre;

namespace {

constexpr int kWidth = 5;
constexpr double kTarget = 1e-3;

// shuffled: the contacts in a random order (fixed seed) instead of layer by layer from the floor.
ContactSystem lattice_pile(int layers, double gravity, bool shuffled)
{
  std::vector<Body> bodies;
  for (int k = 0; k < layers; ++k)
    for (int j = 0; j < kWidth; ++j)
      for (int i = 0; i < kWidth; ++i) {
        Body b;
        b.radius = 0.5;
        b.mass = 4.0 / 3.0 * M_PI * 0.125;
        b.x = Vec3(i, j, 0.5 + k);
        b.force = Vec3(0, 0, -gravity * b.mass);
        bodies.push_back(b);
      }
  const auto index = [](int i, int j, int k) { return (k * kWidth + j) * kWidth + i; };
  std::vector<Contact> contacts;
  for (int k = 0; k < layers; ++k)
    for (int j = 0; j < kWidth; ++j)
      for (int i = 0; i < kWidth; ++i) {
        const int a = index(i, j, k);
        if (k == 0)
          contacts.push_back(sphere_wall_contact(bodies, a, Vec3::UnitZ(), 0.5));
        else
          contacts.push_back(sphere_sphere_contact(bodies, a, index(i, j, k - 1)));
        if (i > 0) contacts.push_back(sphere_sphere_contact(bodies, a, index(i - 1, j, k)));
        if (j > 0) contacts.push_back(sphere_sphere_contact(bodies, a, index(i, j - 1, k)));
      }
  if (shuffled) std::shuffle(contacts.begin(), contacts.end(), std::mt19937(7));
  const SceneParams p = bench::material_params();
  for (Contact &c : contacts) c.compliance.fill(p.compliance);
  return ContactSystem(bodies, contacts, 6, p.spook);
}

// The first count in 1, 2, 3, ... (up to limit) whose result meets the target.
int first_meeting(int limit, const std::function<double(int)> &error_after)
{
  for (int n = 1; n <= limit; n = n < 64 ? n + 1 : n + n / 8)
    if (error_after(n) <= kTarget) return n;
  return -1;
}

} // namespace

int main()
{
  std::printf("Settled %d x %d lattice piles: sweeps (or K-products) to a velocity error of %g\n",
              kWidth, kWidth, kTarget);
  std::printf("%9s %7s %7s %9s %9s %9s %9s %9s %9s %9s %16s\n", "order", "layers", "bodies",
              "contacts", "cold PGS", "warm PGS", "cold NNCG", "warm NNCG", "cold FBGS",
              "warm FBGS", "default (K-prod)");
  for (bool shuffled : {false, true})
    for (int layers : {10, 20, 40}) {
      const ContactSystem sys = lattice_pile(layers, 9.81, shuffled);
      const Vector b = spook_rhs(sys);
      const Cones cones(sys);
      const std::vector<Vec6> scale = row_scales(sys);
      const Vector zero = Vector::Zero(sys.contact_dofs());
      const Reference ref = nonsmooth_reference(sys, zero);
      const ContactSystem lighter = lattice_pile(layers, 0.9 * 9.81, shuffled);
      const Vector warm = nonsmooth_reference(lighter, zero).lambda;
      enum Kind { point, cg, blocks };
      const auto sweeps = [&](const Vector &start, Kind kind) {
        return first_meeting(200000, [&](int n) {
          Vector l = start;
          PgsControl control{n, 0.0, 1 << 30};
          control.nonlinear_cg = kind == cg;
          control.fibre_blocks = kind == blocks;
          pgs(sys, serial_exchange(), cones, b, scale, l, control);
          return step_accuracy(sys, l, ref.lambda).velocity();
        });
      };
      const double tk = k_product_seconds(sys, 51);
      const StepState state{sys, ref.lambda, warm, nullptr};
      double default_k = -1;
      for (int s = 0; s <= 200000; s = s < 8 ? s + 1 : s + s / 4) {
        StepOptions opt;
        opt.sweeps = s;
        opt.sweep_tol = 1e-14;
        opt.rescue_sweeps = 0; // sweep_tol 1e-14 would set it off
        const StudyRow row = measure_setting(state, opt, ref.lambda, tk, 1);
        if (row.error.velocity() <= kTarget) {
          default_k = row.k_products;
          break;
        }
      }
      std::printf("%9s %7d %7d %9d %9d %9d %9d %9d %9d %9d %16.0f%s\n",
                  shuffled ? "shuffled" : "layers", layers, sys.num_bodies(), sys.num_contacts(),
                  sweeps(zero, point), sweeps(warm, point), sweeps(zero, cg), sweeps(warm, cg),
                  sweeps(zero, blocks), sweeps(warm, blocks), default_k,
                  ref.confirmed() ? "" : "  (reference not confirmed)");
      std::fflush(stdout);
    }
  return 0;
}
