#!/usr/bin/env bash
# Runs every fuzz target on its seed corpus for SECONDS each (default 10: CI's smoke run).
# New inputs go to a scratch corpus under the build tree; the committed seeds stay as they are.
#   tests/fuzz/run.sh [SECONDS]        after: cmake --preset fuzz && cmake --build --preset fuzz
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-10}
status=0
for target in candump protocol datafile config checkpoint; do
  scratch=build/fuzz/corpus/$target
  mkdir -p "$scratch"
  echo "fuzz: $target for ${seconds}s" >&2
  if ! build/fuzz/tests/fuzz/fuzz_$target -max_total_time="$seconds" -print_final_stats=1 \
       -artifact_prefix=build/fuzz/crash-$target- "$scratch" tests/fuzz/corpus/$target 2> build/fuzz/$target.log; then
    echo "fuzz: $target FAILED, see build/fuzz/$target.log" >&2
    tail -n 30 build/fuzz/$target.log >&2
    status=1
  else
    grep -aE "stat::number_of_executed_units|stat::new_units_added" build/fuzz/$target.log | sed "s/^/fuzz: $target /" >&2
  fi
done
exit $status
