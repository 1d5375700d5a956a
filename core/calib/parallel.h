// Parallel loops whose results do not depend on the number of threads: work is cut into chunks
// whose boundaries depend only on the problem, every chunk writes its own slot, and callers
// reduce the slots in chunk order, so results are identical for any --threads N.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace selfcal::calib {

// Calls body(index) for index in [0, count) on up to `threads` threads (<= 1: inline).
template <typename Body>
void ParallelFor(std::size_t count, int threads, const Body& body) {
  const std::size_t workers =
      std::min<std::size_t>(count, threads > 1 ? static_cast<std::size_t>(threads) : 1);
  if (workers <= 1) {
    for (std::size_t i = 0; i < count; ++i) body(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  auto run = [&] {
    for (std::size_t i = next++; i < count; i = next++) body(i);
  };
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (std::size_t t = 1; t < workers; ++t) pool.emplace_back(run);
  run();
  for (auto& thread : pool) thread.join();
}

inline int DefaultThreadCount() {
  const unsigned hardware = std::thread::hardware_concurrency();
  return hardware == 0 ? 1 : static_cast<int>(hardware);
}

}  // namespace selfcal::calib
