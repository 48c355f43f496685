#pragma once
/// Monte Carlo campaigns on one machine: independent trials spread over threads. Each trial's
/// seed is derived from the campaign's seed and the trial's index (TrialSeed), never from the
/// thread that runs it, so the results do not depend on the number of jobs.
#include <functional>

namespace rotorguard::campaign {

/// Runs task(i) for every i in [0, total) on `jobs` threads (the caller's among them), taking
/// indices in order, and calls progress(done, total) after each, one call at a time. A task must
/// not throw (a trial records its own failure).
void ParallelFor(int total, int jobs, const std::function<void(int)>& task,
                 const std::function<void(int, int)>& progress = {});

}  // namespace rotorguard::campaign
