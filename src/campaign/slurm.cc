#include "rotorguard/campaign/slurm.h"

#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>

#include "rotorguard/core/error.h"

namespace rotorguard::campaign {

namespace fs = std::filesystem;

namespace {

/// `text` quoted for a POSIX shell.
std::string ShellQuote(const std::string& text) {
  std::string q = "'";
  for (const char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

std::string SlurmArrayScript(const Campaign& campaign, const SlurmScriptOptions& o) {
  if (campaign.file.empty()) {
    throw std::invalid_argument(
        fmt::format("campaign '{}' has no spec file for the tasks to run; write it as a "
                    "spec (docs/campaigns.md)",
                    campaign.name));
  }
  if (o.shards < 1 || o.shards > campaign.trials) {
    ThrowValidation("SlurmScriptOptions", "shards", o.shards,
                    fmt::format("a count in [1, {}] (the campaign's trials)", campaign.trials));
  }
  if (o.cpus_per_task < 1 || o.cpus_per_task > 256) {
    ThrowValidation("SlurmScriptOptions", "cpus_per_task", o.cpus_per_task, "a count in [1, 256]");
  }
  if (o.out_dir.empty()) ThrowValidation("SlurmScriptOptions", "out_dir", "''", "the results folder");
  if (o.rotorguard.empty()) ThrowValidation("SlurmScriptOptions", "rotorguard", "''", "the program's path");
  for (const auto& [field, v] : {std::pair{"partition", &o.partition}, std::pair{"time_limit", &o.time_limit}}) {
    if (v->find_first_of(" \t\n'\"\\$`") != std::string::npos) {
      ThrowValidation("SlurmScriptOptions", field, fmt::format("'{}'", *v), "a Slurm name without spaces or quotes");
    }
  }
  const std::string out = fs::absolute(o.out_dir).lexically_normal().string();
  if (out.find_first_of(" \t\n%") != std::string::npos) {
    ThrowValidation("SlurmScriptOptions", "out_dir", fmt::format("'{}'", o.out_dir),
                    "a folder without spaces or '%' (an #SBATCH line cannot quote them)");
  }
  const std::string spec_path = fs::absolute(campaign.file).lexically_normal().string();
  std::string s = fmt::format(
      "#!/bin/bash\n"
      "# rotorguard campaign '{name}' (spec {hash}): {trials} trials in {n} shards, one per array task.\n"
      "# Submit: sbatch {script}\n"
      "# Each task resumes its shard, so resubmitting this script, or only the failed tasks\n"
      "# (sbatch --array=<their ids> {script}), is safe. When all are done:\n"
      "#   {exe} campaign merge {outq}\n"
      "#SBATCH --job-name=rg-{name}\n"
      "#SBATCH --array=0-{last}\n"
      "#SBATCH --cpus-per-task={cpus}\n"
      "#SBATCH --output={out}/slurm-%A_%a.out\n",
      fmt::arg("name", campaign.name), fmt::arg("hash", campaign.hash), fmt::arg("trials", campaign.trials),
      fmt::arg("n", o.shards), fmt::arg("script", ShellQuote(out + "/campaign.sbatch")),
      fmt::arg("exe", ShellQuote(o.rotorguard)), fmt::arg("outq", ShellQuote(out)), fmt::arg("last", o.shards - 1),
      fmt::arg("cpus", o.cpus_per_task), fmt::arg("out", out));
  if (!o.partition.empty()) s += "#SBATCH --partition=" + o.partition + "\n";
  if (!o.time_limit.empty()) s += "#SBATCH --time=" + o.time_limit + "\n";
  s += fmt::format(
      "set -euo pipefail\n"
      "exec {} campaign run {} --out {} --shard \"${{SLURM_ARRAY_TASK_ID}}/{}\" "
      "--jobs \"${{SLURM_CPUS_PER_TASK:-{}}}\" --resume --quiet\n",
      ShellQuote(o.rotorguard), ShellQuote(spec_path), ShellQuote(out), o.shards, o.cpus_per_task);
  return s;
}

}  // namespace rotorguard::campaign
