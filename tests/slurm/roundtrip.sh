#!/usr/bin/env bash
# The campaign engine on real cluster engines (docs/campaigns.md): a single-node Slurm brought up
# on this machine (scripts/local-slurm.sh) runs a campaign as a job array, GNU parallel runs it as
# local shards, and each merged summary must equal, byte for byte, the one of a plain local run.
# Usage: roundtrip.sh ROTORGUARD SOURCE_DIR. Exit 77 (skipped) without root or without the tools.
set -euo pipefail
rg=$(realpath "$1")
src=$(realpath "$2")
for tool in sbatch slurmctld slurmd munged parallel; do
  command -v "$tool" >/dev/null || { echo "skipped: $tool not installed (scripts/install-deps.sh)"; exit 77; }
done
[ "$(id -u)" -eq 0 ] || { echo "skipped: a local slurmd needs root"; exit 77; }

work=$(mktemp -d -t rotorguard-slurm.XXXXXX)
chmod 0755 "$work"  # munged (user munge) lives below it
cleanup() { "$src/scripts/local-slurm.sh" stop "$work/cluster" || true; rm -rf "$work"; }
trap cleanup EXIT

cat > "$work/spec.yaml" <<SPEC
name: slurm_roundtrip
scenario: $src/configs/scenarios/hover_motor_stop_nominal.yaml
seed: 11
repeats: 2
grid:
  duration_s: [3.0]
  faults.0.rotor: [0, 1, 2]
random:
  faults.0.onset.at_time_s: {uniform: [1.0, 2.0]}
SPEC

# The reference: one local run.
"$rg" campaign run "$work/spec.yaml" --out "$work/local" --jobs 2 --quiet
"$rg" campaign merge "$work/local" > /dev/null

# Slurm: three array tasks.
export SLURM_CONF
if ! started=$("$src/scripts/local-slurm.sh" start "$work/cluster"); then
  # A machine that cannot host the daemons (no resolvable host name, ports taken) is not a failure
  # of the product: say why and skip.
  tail -n 20 "$work/cluster"/*.log "$work/cluster/munge/munged.log" 2>/dev/null || true
  echo "skipped: the local Slurm did not come up on this machine"
  exit 77
fi
SLURM_CONF=$(sed -n 's/^SLURM_CONF=//p' <<< "$started")
"$rg" campaign slurm "$work/spec.yaml" --shards 3 --out "$work/slurm"
timeout 300 sbatch --wait "$work/slurm/campaign.sbatch"
ls "$work/slurm"/results.shard-{0,1,2}.jsonl > /dev/null
"$rg" campaign merge "$work/slurm" > /dev/null
cmp "$work/local/summary.json" "$work/slurm/summary.json"
cmp "$work/local/summary.md" "$work/slurm/summary.md"
# Resubmitting is safe: every task finds its shard done and the summary stays the same.
timeout 300 sbatch --wait "$work/slurm/campaign.sbatch"
"$rg" campaign merge "$work/slurm" > /dev/null
cmp "$work/local/summary.json" "$work/slurm/summary.json"

# GNU parallel: four shards as local processes (the --sshloginfile recipe of docs/campaigns.md
# without the ssh).
parallel --halt now,fail=1 "$rg" campaign run "$work/spec.yaml" --out "$work/parallel" --shard {}/4 --quiet ::: 0 1 2 3
"$rg" campaign merge "$work/parallel" > /dev/null
cmp "$work/local/summary.json" "$work/parallel/summary.json"
echo "slurm and GNU parallel summaries equal the local run's"
