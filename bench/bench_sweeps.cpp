// Cost of one projected Gauss-Seidel sweep against one body-form product K x, per contact, on
// heap_scene (bench_scenes.hpp) from 1e3 to 1e6 contacts, both measured in the same run; the
// closing table prints ns per contact and the sweep's cost in K-product equivalents (the unit
// of the accuracy-cost curves, bench/README.md). Target: <= 20 ns per contact per sweep.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <string>

#include "bench_scenes.hpp"
#include "fibre/algebra/operators.hpp"
#include "fibre/solvers/pgs.hpp"

using namespace fibre;

namespace {

void BM_Sweep(benchmark::State &state)
{
  const ContactSystem &sys = bench::cached_heap_scene(static_cast<int>(state.range(0)));
  const Cones cones(sys);
  const std::vector<Vec6> scale = row_scales(sys);
  const Vector b = spook_rhs(sys);
  Vector lambda = Vector::Zero(sys.contact_dofs());
  pgs(sys, serial_exchange(), cones, b, scale, lambda, PgsControl{20, 0.0, 1 << 30}); // warm
  for (auto _ : state) {
    // 10 sweeps per call: the velocity change of the start is computed once per call
    pgs(sys, serial_exchange(), cones, b, scale, lambda, PgsControl{10, 0.0, 1 << 30});
    benchmark::ClobberMemory();
  }
  state.counters["contacts"] = sys.num_contacts();
  state.counters["per_contact"] =
      benchmark::Counter(10.0 * sys.num_contacts(), benchmark::Counter::kIsIterationInvariantRate |
                                                        benchmark::Counter::kInvert);
}

void BM_ProductK(benchmark::State &state)
{
  const ContactSystem &sys = bench::cached_heap_scene(static_cast<int>(state.range(0)));
  const BodySpaceOperator K(sys, serial_exchange());
  const Vector x = Vector::Random(sys.body_dofs());
  Vector y;
  for (auto _ : state) {
    K.apply(x, y);
    benchmark::ClobberMemory();
  }
  state.counters["contacts"] = sys.num_contacts();
  state.counters["per_contact"] =
      benchmark::Counter(sys.num_contacts(), benchmark::Counter::kIsIterationInvariantRate |
                                                 benchmark::Counter::kInvert);
}

void sizes(benchmark::internal::Benchmark *b)
{
  for (int n : {1000, 15000, 100000, 1000000}) b->Arg(n);
  b->Unit(benchmark::kMicrosecond);
  b->MinTime(0.3);
}

class TableReporter : public benchmark::ConsoleReporter {
 public:
  std::map<std::string, std::map<std::string, double>> per_contact; // size -> name -> s
  void ReportRuns(const std::vector<Run> &reports) override
  {
    for (const Run &r : reports) {
      const auto c = r.counters.find("per_contact");
      if (c != r.counters.end())
        per_contact[r.run_name.args][r.run_name.function_name] = double(c->second);
    }
    ConsoleReporter::ReportRuns(reports);
  }
};

} // namespace

BENCHMARK(BM_Sweep)->Name("sweep_pgs")->Apply(sizes);
BENCHMARK(BM_ProductK)->Name("product_K")->Apply(sizes);

int main(int argc, char **argv)
{
  benchmark::Initialize(&argc, argv);
  TableReporter rep;
  benchmark::RunSpecifiedBenchmarks(&rep);
  std::printf("\nOne sweep against one K product (CPU time per contact, the same run):\n");
  std::printf("  %10s %14s %14s %12s\n", "contacts", "sweep ns/c", "K ns/c", "sweep / K");
  for (const auto &[size, t] : rep.per_contact) {
    const auto s = t.find("sweep_pgs"), k = t.find("product_K");
    if (s == t.end() || k == t.end()) continue;
    std::printf("  %10s %14.1f %14.1f %12.2f\n", size.c_str(), 1e9 * s->second, 1e9 * k->second,
                s->second / k->second);
  }
  std::printf("  target: <= 20 ns per contact per sweep\n");
  benchmark::Shutdown();
  return 0;
}
