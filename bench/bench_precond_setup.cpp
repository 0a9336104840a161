// Setup (and apply) time of the preconditioners against the number of contacts: design.md
// section 3 asks for O(contacts) to build and to apply. Scenes: pile_scene(n) with n bodies,
// about 1.03 n contacts (1e3 .. 1e5). The `contacts` counter and `per_contact` (time per
// contact) make the growth visible: linear setup keeps per_contact flat.
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "fibre/preconditioner_family.hpp"
#include "fibre/scenes.hpp"

using namespace fibre;

namespace {

// Scenes are built once per size (the deposition is quadratic in n).
const ContactSystem &scene(int bodies)
{
  static std::map<int, std::unique_ptr<ContactSystem>> cache;
  auto &slot = cache[bodies];
  if (!slot) slot = std::make_unique<ContactSystem>(pile_scene(bodies, SceneParams{}));
  return *slot;
}

void contact_counters(benchmark::State &state, const ContactSystem &sys)
{
  const double n = sys.num_contacts();
  state.counters["contacts"] = n;
  state.counters["per_contact"] = benchmark::Counter(
      n, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

template <Form F, PrecondKind K> void BM_Setup(benchmark::State &state)
{
  const ContactSystem &sys = scene(static_cast<int>(state.range(0)));
  PrecondOptions opt;
  opt.kind = K;
  for (auto _ : state) {
    auto P = make_preconditioner(F, sys, serial_exchange(), opt);
    benchmark::DoNotOptimize(P.get());
  }
  contact_counters(state, sys);
}

template <Form F, PrecondKind K> void BM_Apply(benchmark::State &state)
{
  const ContactSystem &sys = scene(static_cast<int>(state.range(0)));
  PrecondOptions opt;
  opt.kind = K;
  const auto P = make_preconditioner(F, sys, serial_exchange(), opt);
  const Vector r = Vector::Ones(F == Form::contact ? sys.contact_dofs() : sys.body_dofs());
  Vector z;
  for (auto _ : state) {
    P->apply(r, z);
    benchmark::DoNotOptimize(z.data());
  }
  contact_counters(state, sys);
}

void BM_BuildFibres(benchmark::State &state)
{
  const ContactSystem &sys = scene(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    Fibres f = build_fibres(sys, EdgeWeight::z, nullptr, true);
    benchmark::DoNotOptimize(f.contacts.data());
  }
  contact_counters(state, sys);
}

void BM_BuildForest(benchmark::State &state)
{
  const ContactSystem &sys = scene(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    Forest t = build_forest(sys, EdgeWeight::z, nullptr, true);
    benchmark::DoNotOptimize(t.order.data());
  }
  contact_counters(state, sys);
}

// Bodies for about 1e3, 3e3, 1e4, 3e4 and 1e5 contacts.
void sizes(benchmark::internal::Benchmark *b)
{
  for (int n : {970, 2900, 9700, 29000, 97000}) b->Arg(n);
  b->Unit(benchmark::kMillisecond);
}

}  // namespace

BENCHMARK(BM_BuildFibres)->Apply(sizes);
BENCHMARK(BM_BuildForest)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Setup, Form::contact, PrecondKind::block)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Setup, Form::contact, PrecondKind::fibre)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Setup, Form::contact, PrecondKind::tree)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Setup, Form::body, PrecondKind::block)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Setup, Form::body, PrecondKind::fibre)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Setup, Form::body, PrecondKind::tree)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Apply, Form::contact, PrecondKind::block)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Apply, Form::contact, PrecondKind::fibre)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Apply, Form::contact, PrecondKind::tree)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Apply, Form::body, PrecondKind::fibre)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Apply, Form::body, PrecondKind::tree)->Apply(sizes);

BENCHMARK_MAIN();
