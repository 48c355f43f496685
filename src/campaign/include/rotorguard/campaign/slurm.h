#pragma once
/// Campaigns on a Slurm cluster: one job-array task per shard (docs/campaigns.md, "Slurm").
#include <string>

#include "rotorguard/campaign/campaign.h"

namespace rotorguard::campaign {

struct SlurmScriptOptions {
  int shards = 1;          ///< array tasks, one shard each, in [1, trials]
  int cpus_per_task = 1;   ///< --cpus-per-task, and each task's --jobs, in [1, 256]
  std::string out_dir;     ///< the results folder (made absolute in the script)
  std::string rotorguard;  ///< the program each task runs (absolute path)
  std::string partition;   ///< "" for the cluster's default
  std::string time_limit;  ///< Slurm's --time ("" for the partition's default)
};

/// An `sbatch --array` script: task i runs `campaign run SPEC --shard i/N --resume` into the
/// results folder, so resubmitting the script, or only its failed tasks, is safe. Throws
/// std::invalid_argument naming a bad option.
std::string SlurmArrayScript(const Campaign& campaign, const SlurmScriptOptions& options);

}  // namespace rotorguard::campaign
