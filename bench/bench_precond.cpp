// Preconditioner build (fibres or forest + factorization) and apply against the number of
// contacts, 1e3 .. 1e6, on heap_scene (bench_scenes.hpp: dense heap, ~3 contacts per body,
// material parameters), next to the Schur product of the same form in the same run. doc/design.md
// section 3 asks for O(contacts) to build and to apply: the `per_contact` counter stays flat.
//
// Targets (issue #7): linear growth (flat ns per contact); under 2 ms at 15,000 contacts (the
// 5,000-body silo); no more than the cost of 3 products of the operator (A in the contact form,
// K in the body form). After the benchmarks a table prints, per size, every build time, its ns
// per contact and its ratio to one product, from the figures of this run.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <thread>

#include "bench_scenes.hpp"
#include "fibre/algebra/operators.hpp"
#include "fibre/precond/preconditioner_family.hpp"

using namespace fibre;

namespace {

void counters(benchmark::State &state, const ContactSystem &sys)
{
  const double n = sys.num_contacts();
  state.counters["contacts"] = n;
  state.counters["bodies"] = sys.num_bodies();
  state.counters["per_contact"] = benchmark::Counter(
      n, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

template <Form F, PrecondKind K> void BM_Build(benchmark::State &state)
{
  const ContactSystem &sys = bench::cached_heap_scene(static_cast<int>(state.range(0)));
  PrecondOptions opt;
  opt.kind = K;
  for (auto _ : state) {
    auto P = make_preconditioner(F, sys, serial_exchange(), opt);
    benchmark::DoNotOptimize(P.get());
  }
  counters(state, sys);
}

template <Form F, PrecondKind K> void BM_Apply(benchmark::State &state)
{
  const ContactSystem &sys = bench::cached_heap_scene(static_cast<int>(state.range(0)));
  PrecondOptions opt;
  opt.kind = K;
  const auto P = make_preconditioner(F, sys, serial_exchange(), opt);
  const Vector r = Vector::Ones(F == Form::contact ? sys.contact_dofs() : sys.body_dofs());
  Vector z;
  for (auto _ : state) {
    P->apply(r, z);
    benchmark::DoNotOptimize(z.data());
  }
  counters(state, sys);
}

template <bool IsForest> void BM_Graph(benchmark::State &state)
{
  const ContactSystem &sys = bench::cached_heap_scene(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    if (IsForest) {
      Forest t = build_forest(sys, EdgeWeight::z, nullptr, true);
      benchmark::DoNotOptimize(t.order.data());
    } else {
      Fibres f = build_fibres(sys, EdgeWeight::z, nullptr, true);
      benchmark::DoNotOptimize(f.contacts.data());
    }
  }
  counters(state, sys);
}

template <Form F> void BM_Product(benchmark::State &state)
{
  const ContactSystem &sys = bench::cached_heap_scene(static_cast<int>(state.range(0)));
  const auto op = make_operator(F, sys, serial_exchange());
  const Vector x = Vector::Ones(op->size());
  Vector y;
  for (auto _ : state) {
    op->apply(x, y);
    benchmark::DoNotOptimize(y.data());
  }
  counters(state, sys);
}

void sizes(benchmark::internal::Benchmark *b)
{
  for (int n : {1000, 3000, 15000, 100000, 1000000}) b->Arg(n);
  b->Unit(benchmark::kMillisecond);
  b->MinTime(0.2);
}

// Keeps every run's time (per iteration, seconds) and contact count for the table.
class TableReporter : public benchmark::ConsoleReporter {
 public:
  struct Entry {
    double seconds;
    double contacts;
  };
  std::map<std::string, std::map<int, Entry>> runs; // name without the argument -> size
  void ReportRuns(const std::vector<Run> &reports) override
  {
    for (const Run &r : reports) {
      const std::string name = r.run_name.function_name;
      const int arg = std::stoi(r.run_name.args);
      const auto c = r.counters.find("contacts");
      // CPU time (the machine is shared: wall time includes waits for the core).
      runs[name][arg] = {r.GetAdjustedCPUTime() / 1e3, // ms -> s
                         c == r.counters.end() ? 0.0 : double(c->second)};
    }
    ConsoleReporter::ReportRuns(reports);
  }
};

} // namespace

BENCHMARK_TEMPLATE(BM_Graph, false)->Name("fibres")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Graph, true)->Name("forest")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Build, Form::contact, PrecondKind::block)
    ->Name("contact_block")
    ->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Build, Form::contact, PrecondKind::fibre)
    ->Name("contact_fibre")
    ->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Build, Form::contact, PrecondKind::tree)->Name("contact_tree")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Build, Form::body, PrecondKind::block)->Name("body_block")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Build, Form::body, PrecondKind::fibre)->Name("body_fibre")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Build, Form::body, PrecondKind::tree)->Name("body_tree")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Apply, Form::contact, PrecondKind::block)
    ->Name("apply_contact_block")
    ->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Apply, Form::contact, PrecondKind::fibre)
    ->Name("apply_contact_fibre")
    ->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Apply, Form::contact, PrecondKind::tree)
    ->Name("apply_contact_tree")
    ->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Apply, Form::body, PrecondKind::fibre)
    ->Name("apply_body_fibre")
    ->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Apply, Form::body, PrecondKind::tree)->Name("apply_body_tree")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Product, Form::contact)->Name("product_A")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Product, Form::body)->Name("product_K")->Apply(sizes);

int main(int argc, char **argv)
{
  benchmark::Initialize(&argc, argv);
  TableReporter rep;
  benchmark::RunSpecifiedBenchmarks(&rep);
  std::printf("\nPreconditioner build and apply, %u hardware threads (serial code), heap_scene:\n",
              std::thread::hardware_concurrency());
  std::printf("%-20s %9s %10s %10s %10s\n", "build", "contacts", "ms", "ns/contact", "/ product");
  for (const char *name :
       {"fibres", "forest", "contact_block", "contact_fibre", "contact_tree", "body_block",
        "body_fibre", "body_tree", "apply_contact_block", "apply_contact_fibre",
        "apply_contact_tree", "apply_body_fibre", "apply_body_tree", "product_A", "product_K"}) {
    const auto it = rep.runs.find(name);
    if (it == rep.runs.end()) continue;
    const bool body = std::string(name).find("body") != std::string::npos;
    const auto &prod = rep.runs[body ? "product_K" : "product_A"];
    for (const auto &[arg, e] : it->second) {
      const auto p = prod.find(arg);
      std::printf("%-20s %9.0f %10.3f %10.1f", name, e.contacts, 1e3 * e.seconds,
                  1e9 * e.seconds / e.contacts);
      if (p != prod.end() && std::string(name).rfind("product", 0) != 0)
        std::printf(" %9.2fx", e.seconds / p->second.seconds);
      std::printf("\n");
    }
  }
  std::printf("targets: build < 2 ms at ~15,000 contacts; build <= 3 products (%s column); "
              "ns/contact flat (linear growth)\n",
              "/ product: A for contact form, K for body form");
  benchmark::Shutdown();
  return 0;
}
