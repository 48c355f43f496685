#!/usr/bin/env bash
# scripts/fuzz.sh BUILD_DIR SECONDS [TARGET...]: runs the libFuzzer binary of BUILD_DIR (make fuzz)
# on each target (all by default) for SECONDS, its corpus in BUILD_DIR/corpus/TARGET seeded from
# the repository's seeds, and prints per target the inputs run, the coverage reached and whether it
# found anything. A finding stops that target and leaves its input as BUILD_DIR/crash-* (or leak-,
# timeout-, oom-); the script exits 1 when any target found one.
set -euo pipefail
dir=$1
seconds=$2
shift 2
fuzzer="$dir/tests/fuzz/rotorguard_libfuzzer"
[ -x "$fuzzer" ] || { echo "fuzz.sh: no $fuzzer; run make fuzz" >&2; exit 2; }
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  mapfile -t targets < <(ROTORGUARD_FUZZ_TARGET=list "$fuzzer" 2>&1 | sed -n 's/^target: //p')
fi
status=0
# Seconds an input may take: a scenario's validation plans its mission, and an assembly's plan
# takes tens of seconds under the sanitizers and the coverage instrumentation.
timeout=${FUZZ_INPUT_TIMEOUT:-120}
export ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
for t in "${targets[@]}"; do
  corpus="$dir/corpus/$t"
  mkdir -p "$corpus"
  while read -r seed; do cp -n "$seed" "$corpus/seed-$(basename "$(dirname "$seed")")-$(basename "$seed")" 2>/dev/null || true; done \
    < <(ROTORGUARD_FUZZ_TARGET=$t ROTORGUARD_FUZZ_SEEDS=1 "$fuzzer" 2>/dev/null)
  log="$dir/fuzz-$t.log"
  if ROTORGUARD_FUZZ_TARGET=$t "$fuzzer" "$corpus" -max_total_time="$seconds" -timeout="$timeout" -rss_limit_mb=4096 \
       -artifact_prefix="$dir/" -print_final_stats=1 > "$log" 2>&1; then
    verdict="no finding"
  else
    verdict="FINDING (see $log)"
    status=1
  fi
  # A run stopped early (a finding in the seeds) may have printed no coverage yet.
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 || true)
  ft=$(grep -o 'ft: [0-9]*' "$log" | tail -1 || true)
  printf '%-14s %10s inputs in %s s, %s, %s, corpus %s files: %s\n' "$t" "${runs:-?}" "$seconds" "${cov:-cov: ?}" \
    "${ft:-ft: ?}" "$(ls "$corpus" | wc -l)" "$verdict"
done
exit $status
