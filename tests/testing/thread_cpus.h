#pragma once
// The CPUs the calling thread may run on, for tests of the runtime's CPU pinning.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <vector>

namespace rotorguard::testing {

inline std::vector<int> AllowedCpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  EXPECT_EQ(pthread_getaffinity_np(pthread_self(), sizeof(set), &set), 0);
  std::vector<int> cpus;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (CPU_ISSET(c, &set)) cpus.push_back(c);
  }
  return cpus;
}

}  // namespace rotorguard::testing
