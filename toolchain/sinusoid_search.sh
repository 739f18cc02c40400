#!/usr/bin/env bash
# The analyzer's sinusoid search on simulated gyros (docs/metrology.md, "The rate's PSD and its
# sinusoids"): how often it reports a sinusoid where none was simulated (white + flicker + random
# walk rate noise, one run per seed), and what it finds on a simulated sinusoid. Needs the host build.
#   toolchain/sinusoid_search.sh [SEEDS] [DURATION_S]     (defaults 40 seeds of 7200 s at tau0 0.01 s)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/host/host_tools
seeds=${1:-40}
duration=${2:-7200}
found=0
for seed in $(seq 1 "$seeds"); do
  n=$("$bin/gyrochar-sim" --duration "$duration" --tau0 0.01 --arw 0.02 --bias-instability 0.5 --rrw 0.5 --seed "$seed" |
      "$bin/gyrochar-analyze" --type counts --tau0 0.01 --pulse-weight 1 --fit ieee952 --format json - 2>/dev/null |
      python3 -c 'import json,sys; j=json.load(sys.stdin); print(len(j["psd"]["peaks"]))')
  [ "$n" -gt 0 ] && found=$((found + 1)) && echo "seed $seed: $n peak(s)" >&2
done
echo "pure noise (ARW 0.02 deg/sqrt(h), B 0.5 deg/h, K 0.5 deg/h/sqrt(h), ${duration} s): a sinusoid reported in $found of $seeds runs"
