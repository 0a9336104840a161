// Throughput of the matrix-free products (thesis 2.5.2) next to a plain memory copy measured
// in the same run: how close the Schur product gets to the machine's memory bandwidth.
//
// Bytes counted per product (the compulsory traffic of each pass, as if every array were
// streamed once per pass that uses it; r = rows per contact):
//   contact form y = G M^-1 G^T x + Sigma x:
//     per contact 2 x (kinematics 120 B + body indices 8 B) + 8 r (x, twice) + 8 r (y) +
//       8 r (Sigma) + 16 r (y update) = 256 + 48 r;
//     per body 48 (zero the body vector) + 96 (accumulate) + 96 + 48 (scale by M^-1, read
//       M^-1) + 48 (read by G) = 336.
//   body form y = M dv + G^T Sigma^-1 G dv runs the same passes in the other order and is
//     counted the same.
// The copy counts read and write (2 bytes per byte copied), as above.
#include <benchmark/benchmark.h>

#include <cstring>
#include <map>
#include <memory>
#include <vector>

#include "fibre/operators.hpp"
#include "fibre/scenes.hpp"

using namespace fibre;

namespace {

const ContactSystem &scene(int bodies)
{
  static std::map<int, std::unique_ptr<ContactSystem>> cache;
  auto &slot = cache[bodies];
  if (!slot) slot = std::make_unique<ContactSystem>(pile_scene(bodies, SceneParams{}));
  return *slot;
}

double product_bytes(const ContactSystem &sys)
{
  return double(sys.num_contacts()) * (256 + 48 * sys.rows()) + 336.0 * sys.num_bodies();
}

template <Form F> void BM_Product(benchmark::State &state)
{
  const ContactSystem &sys = scene(static_cast<int>(state.range(0)));
  const auto op = make_operator(F, sys, serial_exchange());
  const Vector x = Vector::Ones(op->size());
  Vector y;
  for (auto _ : state) {
    op->apply(x, y);
    benchmark::DoNotOptimize(y.data());
  }
  const double bytes = product_bytes(sys);
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes));
  state.counters["contacts"] = sys.num_contacts();
  state.counters["working_set_MB"] = bytes / 1e6;
}

// memcpy with the working set of the product on the scene of range(0) bodies (half its
// counted traffic, read and write making up the other half), or of 256 MiB for range(0) = 0:
// the bandwidth at the same cache level.
void BM_Copy(benchmark::State &state)
{
  const int bodies = static_cast<int>(state.range(0));
  const std::size_t n = bodies > 0 ? static_cast<std::size_t>(product_bytes(scene(bodies)) / 2)
                                   : std::size_t(256) << 20;
  std::vector<char> src(n, 1), dst(n, 0);
  for (auto _ : state) {
    std::memcpy(dst.data(), src.data(), n);
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * 2 * int64_t(n));
  state.counters["working_set_MB"] = 2.0 * n / 1e6;
}

void sizes(benchmark::internal::Benchmark *b)
{
  for (int n : {970, 9700, 97000}) b->Arg(n);
  b->Unit(benchmark::kMicrosecond);
}

void copy_sizes(benchmark::internal::Benchmark *b)
{
  for (int n : {970, 9700, 97000, 0}) b->Arg(n);
  b->Unit(benchmark::kMicrosecond);
}

}  // namespace

BENCHMARK_TEMPLATE(BM_Product, Form::contact)->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Product, Form::body)->Apply(sizes);
BENCHMARK(BM_Copy)->Apply(copy_sizes);

BENCHMARK_MAIN();
