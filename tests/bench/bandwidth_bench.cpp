// The machine's streaming memory bandwidth: the bound of the normal filter's passes at scale
// (decision 51; docs/experiments/2026-12-04-scan-scale-speed-rounds.md, round 7). Reads (a sum) and copies over
// a working set far larger than the caches, on 1 and 2 threads; medians of 7 passes, GB/s
// (a copy counts its reads and its writes). Asserts nothing (never part of ctest).
//
//   bandwidth_bench [MIB]   working set per array (default 512)
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <vector>

namespace {

// GB/s of `passes` runs of body(lo, hi) split over `threads`, median.
template <class Body>
double median_gbs(std::size_t n, int threads, double bytes_per_item, const Body& body) {
  std::vector<double> rates;
  for (int pass = 0; pass < 7; ++pass) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) pool.emplace_back([&, t] { body(n * t / threads, n * (t + 1) / threads, t); });
    for (std::thread& th : pool) th.join();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    rates.push_back(bytes_per_item * static_cast<double>(n) / seconds / 1e9);
  }
  std::sort(rates.begin(), rates.end());
  return rates[rates.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const long mib = argc > 1 ? std::atol(argv[1]) : 512;
  if (mib < 1) {
    std::fprintf(stderr, "usage: bandwidth_bench [MIB >= 1]\n");
    return 2;
  }
  const std::size_t n = static_cast<std::size_t>(mib) * (std::size_t{1} << 20) / sizeof(std::int32_t);
  std::vector<std::int32_t> a(n, 1), b(n, 2);
  std::vector<std::int64_t> sums(64 * 16, 0);
  std::printf("working set %ld MiB per array; medians of 7 passes\n", mib);
  for (int threads : {1, 2}) {
    const double read = median_gbs(n, threads, 4.0, [&](std::size_t lo, std::size_t hi, int t) {
      std::uint32_t s = 0;  // wraps, never overflows
      for (std::size_t i = lo; i < hi; ++i) s += static_cast<std::uint32_t>(a[i]);
      sums[static_cast<std::size_t>(t) * 16] += s;  // keeps the loop
    });
    const double copy = median_gbs(n, threads, 8.0, [&](std::size_t lo, std::size_t hi, int) {
      for (std::size_t i = lo; i < hi; ++i) b[i] = a[i] + 1;
    });
    std::printf("%d thread%s: read %.1f GB/s, copy %.1f GB/s (reads and writes)\n", threads, threads > 1 ? "s" : "", read,
                copy);
  }
  return sums[0] == -1;  // never: uses the sums
}
