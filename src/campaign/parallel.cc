#include "rotorguard/campaign/parallel.h"

#include <algorithm>
#include <atomic>
#include <mutex>
#include <thread>
#include <vector>

namespace rotorguard::campaign {

void ParallelFor(int total, int jobs, const std::function<void(int)>& task,
                 const std::function<void(int, int)>& progress) {
  std::atomic<int> next{0}, done{0};
  std::mutex progress_mutex;
  const auto worker = [&] {
    for (int i = next++; i < total; i = next++) {
      task(i);
      const int d = ++done;
      if (progress) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        progress(d, total);
      }
    }
  };
  std::vector<std::thread> pool;
  for (int j = 1; j < std::max(1, jobs); ++j) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

}  // namespace rotorguard::campaign
