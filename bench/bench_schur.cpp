// Throughput of the matrix-free products (thesis 2.5.2) against a STREAM-like measurement of
// the memory bandwidth taken in the same run, on heap_scene (bench_scenes.hpp) from 1e3 to 1e6
// contacts. The 1e6-contact products (about 180 to 450 MB of data) and the STREAM arrays
// (3 x 128 MiB) are far larger than the last-level cache (32 MiB here), so those figures are
// memory bandwidth; the small sizes run from cache.
//
// Bytes counted per product: the compulsory traffic of the layout (every array the product
// needs, streamed once per pass that reads it; body vectors are gathered and scattered by
// index, and counted once per body), r = rows per contact = 6:
//   body form y = M x + G^T Sigma^-1 G x, one fused pass over the contacts:
//     per contact  kinematics 120 B (frame, ra, rb) + body pair 8 B + 1/Sigma 8r B = 176 B;
//     per body     x 48 + M^-1 48 + y 48 = 144 B.
//   contact form y = G (M^-1 (G^T x)) + Sigma x, two passes over the contacts:
//     per contact  pass 1: kinematics 120 + pair 8 + x 8r; pass 2: kinematics 120 + pair 8 +
//                  x 8r + Sigma 8r + y 8r: 448 B;
//     per body     work written, scaled by M^-1 (read 48) and read back: 48 x 4 = 192 B.
// STREAM triad a = b + s c counts 24 B per element (two reads, one write), as STREAM does.
// After the benchmarks a table prints every product's GB/s and its fraction of the triad's.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bench_scenes.hpp"
#include "fibre/algebra/operators.hpp"

using namespace fibre;

namespace {

double product_bytes(const ContactSystem &sys, Form form)
{
  const double r = sys.rows();
  if (form == Form::body) return sys.num_contacts() * (128 + 8 * r) + 144.0 * sys.num_bodies();
  return sys.num_contacts() * (256 + 32 * r) + 192.0 * sys.num_bodies();
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
  const double bytes = product_bytes(sys, F);
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes));
  state.counters["contacts"] = sys.num_contacts();
  state.counters["B_per_contact"] = bytes / sys.num_contacts();
  state.counters["working_set_MB"] = bytes / 1e6;
}

// STREAM triad and copy on arrays of range(0) MiB each.
void BM_Triad(benchmark::State &state)
{
  const std::size_t n = (std::size_t(state.range(0)) << 20) / sizeof(double);
  std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
  const double s = 3.0;
  for (auto _ : state) {
    double *__restrict pa = a.data();
    const double *__restrict pb = b.data(), *__restrict pc = c.data();
    for (std::size_t i = 0; i < n; ++i) pa[i] = pb[i] + s * pc[i];
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * 24.0 * double(n)));
}

void BM_Copy(benchmark::State &state)
{
  const std::size_t n = (std::size_t(state.range(0)) << 20) / sizeof(double);
  std::vector<double> a(n, 0.0), b(n, 1.0);
  for (auto _ : state) {
    double *__restrict pa = a.data();
    const double *__restrict pb = b.data();
    for (std::size_t i = 0; i < n; ++i) pa[i] = pb[i];
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * 16.0 * double(n)));
}

void sizes(benchmark::internal::Benchmark *b)
{
  for (int n : {1000, 15000, 100000, 1000000}) b->Arg(n);
  b->Unit(benchmark::kMicrosecond);
  b->MinTime(0.3);
}

class TableReporter : public benchmark::ConsoleReporter {
 public:
  std::map<std::string, double> gbps; // full name -> GB/s
  std::map<std::string, double> contacts;
  void ReportRuns(const std::vector<Run> &reports) override
  {
    for (const Run &r : reports) {
      // Rates are per second of CPU time (the machine is shared: wall time includes waits).
      const std::string name = r.run_name.function_name + "/" + r.run_name.args;
      const auto b = r.counters.find("bytes_per_second");
      if (b != r.counters.end()) gbps[name] = double(b->second) / 1e9; // bytes per CPU second
      const auto c = r.counters.find("contacts");
      if (c != r.counters.end()) contacts[name] = double(c->second);
    }
    ConsoleReporter::ReportRuns(reports);
  }
};

} // namespace

BENCHMARK(BM_Triad)->Name("stream_triad")->Arg(128)->Unit(benchmark::kMillisecond)->MinTime(0.5);
BENCHMARK(BM_Copy)->Name("stream_copy")->Arg(128)->Unit(benchmark::kMillisecond)->MinTime(0.5);
BENCHMARK_TEMPLATE(BM_Product, Form::body)->Name("product_K")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Product, Form::contact)->Name("product_A")->Apply(sizes);

int main(int argc, char **argv)
{
  benchmark::Initialize(&argc, argv);
  TableReporter rep;
  benchmark::RunSpecifiedBenchmarks(&rep);
  const auto triad = rep.gbps.find("stream_triad/128");
  std::printf("\nProducts against STREAM triad (3 x 128 MiB, one core; %u hardware threads):\n",
              std::thread::hardware_concurrency());
  if (triad == rep.gbps.end()) return 0;
  std::printf("  stream_triad %.2f GB/s", triad->second);
  const auto copy = rep.gbps.find("stream_copy/128");
  if (copy != rep.gbps.end()) std::printf(", stream_copy %.2f GB/s", copy->second);
  std::printf("\n  %-22s %9s %9s %10s\n", "product", "contacts", "GB/s", "of triad");
  for (const auto &[name, g] : rep.gbps) {
    if (name.rfind("product", 0) != 0) continue;
    std::printf("  %-22s %9.0f %9.2f %9.0f%%\n", name.c_str(), rep.contacts[name], g,
                100.0 * g / triad->second);
  }
  std::printf("  target: >= 50%% of the triad bandwidth at the memory-resident size (1e6 "
              "contacts)\n");
  benchmark::Shutdown();
  return 0;
}
