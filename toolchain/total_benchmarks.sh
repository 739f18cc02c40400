#!/usr/bin/env bash
# Regenerates the "Total and Theo family" section of BENCHMARKS.md (between its markers): MTOTDEV
# and Theo1 at octave taus on 10^5 phase points, gyrochar (tests/benchmarks/bench_total.cpp, exact
# and with the analysis' decimation plan) beside allantools (../shared/peers/allantools) on the
# same file in the same run; the decimated estimators against the exact ones on the reference sets;
# then 10^7 points of TOTDEV, MTOTDEV and TheoH with peak memory; then issue 23's RLG job (HOURS of
# 1 kHz counts, 120 by default: about 1 GB of counts and, on the analyzer's side, many minutes),
# and allantools beside it on the record's first 10^6 samples, extrapolated to the whole.
# allantools runs each tau in its own process with a time limit (TAU_LIMIT seconds, default 60);
# after one tau times out the longer ones (at least as much work) are not run, and the ratio is
# then a lower bound.
#   toolchain/total_benchmarks.sh      (about 15 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
limit=${TAU_LIMIT:-60}
peers=../shared/peers/allantools
for p in python3-numpy python3-scipy time; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || {
    echo "total_benchmarks.sh: installing $p" >&2; apt-get install -y -qq "$p" >/dev/null; }
done
cmake --preset perf >/dev/null  # build/perf: Release, GYROCHAR_BENCHMARKS=ON
cmake --build build/perf --target bench_total >/dev/null
data=build/perf/data
mkdir -p "$data"
file=$data/phase_1e5.txt
# 10^5 points of random-walk FM plus white PM (phase), seed 1.
[ -f "$file" ] || /usr/bin/python3 -c '
import numpy as np
r = np.random.default_rng(1)
x = np.cumsum(0.1 * r.standard_normal(100000)) + r.standard_normal(100000)
np.savetxt("'"$file"'", x, fmt="%.12e")'

ours_exact=$(build/perf/tests/bench_total octave "$file" 0)
ours_plan=$(build/perf/tests/bench_total octave "$file" 16)
seconds() { echo "$1" | awk -F, -v s="$2" -v m="$3" '$1 == s && $2 == m { print $3 }'; }

# allantools: one process per tau; prints the seconds of the call alone.
peer() {  # stat m
  PYTHONPATH=$peers timeout "$limit" /usr/bin/python3 -c '
import sys, time, numpy as np, allantools as at
x = np.loadtxt(sys.argv[1]); m = int(sys.argv[3]); f = getattr(at, sys.argv[2])
t = time.perf_counter(); f(x, rate=1.0, data_type="phase", taus=[float(m)]); print("%.6f" % (time.perf_counter() - t))
' "$file" "$1" "$2" 2>/dev/null || echo timeout
}

# Work of one tau in allantools' loops (its time is about proportional): MTOTDEV 6m terms for each
# of N - 3m + 1 sub-sequences, Theo1 m/2 terms for each of N - m starts.
work() { awk -v s="$1" -v m="$2" -v n=100000 'BEGIN { print (s == "mtotdev") ? (n - 3*m + 1) * 6 * m : (n - m) * m / 2 }'; }

table() {  # stat first_m last_m
  local stat=$1 m=$2 last=$3 stopped="" peer_sum=0 both_exact=0 both_plan=0 all_exact=0 all_plan=0 per_term="" rest=0
  echo "| m | allantools (s) | gyrochar exact (s) | gyrochar plan S = 16 (s) | allantools / exact |"
  echo "|---:|---:|---:|---:|---:|"
  while [ "$m" -le "$last" ]; do
    local e p a ratio="-"
    e=$(seconds "$ours_exact" "$stat" "$m"); p=$(seconds "$ours_plan" "$stat" "$m")
    if [ -n "$stopped" ]; then a="not run"; else a=$(peer "$stat" "$m"); fi
    all_exact=$(awk -v s="$all_exact" -v a="$e" 'BEGIN{print s + a}'); all_plan=$(awk -v s="$all_plan" -v a="$p" 'BEGIN{print s + a}')
    case "$a" in
      timeout|"not run")
        [ "$a" = timeout ] && a="> $limit"
        stopped=1
        rest=$(awk -v r="$rest" -v w="$(work "$stat" "$m")" 'BEGIN{print r + w}') ;;
      *)
        peer_sum=$(awk -v s="$peer_sum" -v a="$a" 'BEGIN{print s + a}')
        both_exact=$(awk -v s="$both_exact" -v a="$e" 'BEGIN{print s + a}'); both_plan=$(awk -v s="$both_plan" -v a="$p" 'BEGIN{print s + a}')
        per_term=$(awk -v a="$a" -v w="$(work "$stat" "$m")" 'BEGIN{print a / w}')
        ratio=$(awk -v a="$a" -v e="$e" 'BEGIN{printf "%.0f", a / e}') ;;
    esac
    printf "| %s | %s | %.4f | %.4f | %s |\n" "$m" "$a" "$e" "$p" "$ratio"
    m=$((m * 2))
  done
  echo
  awk -v a="$peer_sum" -v e="$both_exact" -v p="$both_plan" 'BEGIN{printf "Taus both ran: allantools %.1f s, gyrochar exact %.3f s (%.0fx faster), plan %.3f s (%.0fx).\n", a, e, a / e, p, a / p}'
  awk -v a="$peer_sum" -v r="$rest" -v c="$per_term" -v e="$all_exact" -v p="$all_plan" 'BEGIN{t = a + r * c;
    printf "Every octave tau: gyrochar exact %.2f s, plan %.3f s; allantools extrapolated from its time per term at the last tau it finished: %.0f s (%.1f h), %.0fx the exact, %.0fx the plan.\n", e, p, t, t / 3600, t / e, t / p}'
}

section=$(mktemp)
{
echo "<!-- total:begin -->"
echo "## Total and Theo family (toolchain/total_benchmarks.sh)"
echo
echo "Regenerated on $(date -u +%Y-%m-%d): $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), g++ $(g++ -dumpversion), Release build;"
echo "allantools $(PYTHONPATH=$peers /usr/bin/python3 -c 'import allantools; print(allantools.__version__)'), numpy $(/usr/bin/python3 -c 'import numpy; print(numpy.__version__)');"
echo "load average at the start $(cut -d' ' -f1-3 /proc/loadavg) (other jobs share the 2 cores: times scale with it)."
echo "10^5 phase points (random-walk FM plus white PM), octave taus, the computation alone (no file"
echo "reading) on both sides; allantools one process per tau, at most $limit s each (\"> $limit\": timed out,"
echo "\"not run\": a longer tau after a time-out; sums and ratios with a time-out are lower bounds)."
echo "gyrochar exact: every estimate exact; plan: exact up to 2^26 operations per tau, decimated with"
echo "S = 16 beyond (docs/total.md gives its error)."
echo
echo "### MTOTDEV"
echo
table mtotdev 1 33333
echo
echo "### Theo1"
echo
table theo1 2 99999
echo
echo "### The decimated estimators against the exact ones (S = 16)"
echo
echo "Relative difference of the deviation, and the same in units of the exact estimate's standard"
echo "uncertainty 1/sqrt(2 EDF) (SP 1065's white-FM EDF); block and stride in samples."
echo
for set in "phasedat/PHASE.DAT" "ocxo/ocxo_frequency.txt freq" "Keysight53230A_ti_noise_floor/tic_phase.txt"; do
  read -r path kind <<< "$set"
  echo "#### $path"
  echo
  build/perf/tests/bench_total decimation "../shared/refdata/$path" 16 $kind
  echo
done
echo "### 10^7 points: TOTDEV, MTOTDEV and TheoH (plan S = 16)"
echo
echo '```'
/usr/bin/time -v build/perf/tests/bench_total long 10000000 16 2> "$data/time_total.txt"
echo "wall time $(awk -F': ' '/Elapsed/{print $2}' "$data/time_total.txt"), maximum resident set $(awk -F': ' '/Maximum resident/{printf "%.0f MiB", $2 / 1024}' "$data/time_total.txt")"
echo '```'
echo
# The job of the project's issue 23: a simulated RLG counts record at 1 kHz (quantization, ARW,
# bias instability, rate random walk, ramp), HOURS long (120 by default: 4.32 10^8 samples, a
# counts file of about 4 GB; HOURS=12 for 4.32 10^7), through the analyzer with every total-family
# row it names. The rows' stride column says which are exact (1) and which decimated.
hours=${HOURS:-120}
echo "### The ${hours}-hour RLG job (1 kHz counts, gyrochar-analyze)"
echo
rlg=$data/rlg_${hours}h.txt
[ -f "$rlg" ] || build/perf/host_tools/gyrochar-sim --duration $((hours * 3600)) --tau0 0.001 --white-angle 1 \
    --arw 0.003 --bias-instability 0.005 --rrw 0.0005 --ramp 0.0001 --seed 1 --out "$rlg"
echo '```'
echo "record: $((hours * 3600000)) samples, $(du -h "$rlg" | cut -f1)"
/usr/bin/time -v build/perf/host_tools/gyrochar-analyze --type counts --tau0 0.001 --pulse-weight 1arcsec \
    --stats oadev,mdev,ohdev,totdev,mtotdev,theoh --fit ieee952 --fit-long-tau theoh --format csv "$rlg" \
    > "$data/rlg_rows.csv" 2> "$data/time_rlg.txt"
awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
  { n[$c["stat"]]++; if ($c["stride"] == 1) e[$c["stat"]]++ }
  END { for (s in n) printf "%s: %d rows, %d exact (stride 1)\n", s, n[s], e[s] }' "$data/rlg_rows.csv" | sort
echo "wall time $(awk -F': ' '/Elapsed/{print $2}' "$data/time_rlg.txt"), user $(awk -F': ' '/User time/{print $2}' "$data/time_rlg.txt") s, system $(awk -F': ' '/System time/{print $2}' "$data/time_rlg.txt") s, maximum resident set $(awk -F': ' '/Maximum resident/{printf "%.0f MiB", $2 / 1024}' "$data/time_rlg.txt")"
echo '```'
echo
# allantools cannot hold or finish the whole record: it runs on the record's first 10^6 samples, one
# tau at a time under the time limit, and its time is extrapolated from its cost per term
# (toolchain/allantools_cut.py); gyrochar-analyze runs on the same cut for comparison (Theo1 for
# TheoH, which allantools does not have).
cut=1000000
cutfile=$data/rlg_${hours}h_cut.txt
awk -v c=$cut '/^#/ { next } { print; if (++n == c) exit }' "$rlg" > "$cutfile"
/usr/bin/time -f "%e %U %S %M" -o "$data/time_cut.txt" build/perf/host_tools/gyrochar-analyze --type counts --tau0 0.001 \
    --pulse-weight 1arcsec --stats oadev,mdev,ohdev,totdev,mtotdev,theo1 --format csv "$cutfile" > /dev/null
echo "The first $cut samples of the record: gyrochar-analyze, every octave tau of oadev, mdev, ohdev, totdev,"
echo "mtotdev and theo1 exact, $(awk '{printf "%.2f s of wall, %.2f s of CPU, %.0f MiB", $1, $2 + $3, $4 / 1024}' "$data/time_cut.txt");"
echo "allantools at most $limit s a tau:"
echo
/usr/bin/python3 toolchain/allantools_cut.py "$peers" "$cutfile" 0.001 $cut $((hours * 3600000)) "$limit" \
    oadev,mdev,ohdev,totdev,mtotdev,theo1
echo "<!-- total:end -->"
} > "$section"

# Replace the section between the markers (or append it).
if grep -q '<!-- total:begin -->' BENCHMARKS.md; then
  awk -v f="$section" '/<!-- total:begin -->/{while ((getline l < f) > 0) print l; skip=1} /<!-- total:end -->/{skip=0; next} !skip' BENCHMARKS.md > BENCHMARKS.md.new
  mv BENCHMARKS.md.new BENCHMARKS.md
else
  { echo; cat "$section"; } >> BENCHMARKS.md
fi
rm -f "$section"
echo "total_benchmarks.sh: BENCHMARKS.md updated" >&2
