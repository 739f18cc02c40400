#!/usr/bin/env bash
# Regenerates BENCHMARKS.md in two parts:
#   core: accumulator throughput beside the textbook batch estimators (Google Benchmark),
#         instructions per sample on x86-64 (callgrind), aarch64 and Cortex-M4 (QEMU's execution
#         trace) with a Cortex-M4 cycle estimate, the state size, the Cortex-M section sizes;
#   tools: the analyzer's reader, gyrochar-analyze beside allantools (../shared/peers/allantools)
#         on the same files in the same run, the decoder, gyrochard on the QEMU bench.
#   toolchain/benchmarks.sh              (about 50 minutes on 2 cores, most of it allantools)
#   toolchain/benchmarks.sh --analyzer   only the analyzer sections, on stdout
#   toolchain/benchmarks.sh --core       only the core sections and targets, on stdout
#   toolchain/benchmarks.sh --fit        only the IEEE-952 fit's section, on stdout
set -euo pipefail
cd "$(dirname "$0")/.."
# allantools runs on Debian's numpy and scipy (Debian's python3, not another one on PATH);
# libdeflate-tools is the gzip decompressor the reader's zlib is compared with.
for p in valgrind time libbenchmark-dev python3-numpy python3-scipy libdeflate-tools \
         qemu-user-static g++-aarch64-linux-gnu gcc-arm-none-eabi libnewlib-arm-none-eabi; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || {
    echo "benchmarks.sh: installing $p" >&2; apt-get install -y -qq "$p" >/dev/null; }
done
cmake --preset perf >/dev/null  # build/perf: Release, GYROCHAR_BENCHMARKS=ON
if [ "${1:-}" = --analyzer ]; then
  cmake --build build/perf --target gyrochar-analyze gyrochar-sim bench_datafile >/dev/null
elif [ "${1:-}" = --fit ]; then
  cmake --build build/perf --target gyrochar-analyze >/dev/null
elif [ "${1:-}" = --core ]; then
  cmake --build build/perf --target bench_pyramid bench_per_sample core_test_characterizer_alloc >/dev/null
else
  cmake --build build/perf >/dev/null
fi
peers=../shared/peers/allantools
out=BENCHMARKS.md
data=build/perf/data
mkdir -p "$data"

# Counts files of the simulated gyro: n samples of about 3600 pulses (a turning gyro: 5 bytes a line).
counts_file() {
  local f=$data/counts_$1.txt
  [ -f "$f" ] || build/perf/host_tools/gyrochar-sim --duration $(($1 / 100)) --tau0 0.01 --rate 360000 --arw 0.003 \
      --white-angle 3 --out "$f"
  echo "$f"
}

# One process under /usr/bin/time and a time limit: prints "wall cpu rss_mib" (cpu = user + sys),
# or "- - -" when it did not finish; its stdout goes to $2.
measure() {
  local limit=$1 out=$2; shift 2
  if timeout "$limit" /usr/bin/time -f "%e %U %S %M" -o "$data/time.txt" "$@" > "$out" 2>/dev/null; then
    awk '{printf "%.2f %.2f %d\n", $1, $2 + $3, $4 / 1024}' "$data/time.txt"
  else
    echo "- - -"
  fi
}

# Instructions a command executes (callgrind; its standard output discarded).
callgrind() { valgrind --tool=callgrind --callgrind-out-file=/dev/null "$@" 2>&1 >/dev/null | awk '/refs/{gsub(",","",$4); print $4}'; }

# The run of median wall time among `runs` lines of "wall cpu rss_mib" on stdin ("- - -": not
# finished, counted as the slowest).
median_run() {
  awk '{ print ($1 == "-" ? "inf" : $1), $0 }' | sort -g | cut -d' ' -f2- |
    awk '{ line[NR] = $0 } END { print line[int((NR + 1) / 2)] }'
}

# One row: gyrochar-analyze with $3 beside allantools with taus $4 on n = $1 samples, limit $2 s,
# each run $5 times (default 1; the two alternate) and the median run of each kept: this
# machine's speed moves by tens of percent from one minute to the next.
side_by_side() {
  local n=$1 limit=$2 ours=$3 taus=$4 runs=${5:-1} f g a k
  f=$(counts_file "$n")
  # allantools once per file and tau list (its median run, kept for the other rows of that file),
  # with at most 16 GiB of address space, so that it stops with MemoryError rather than take the machine.
  local theirs=$data/theirs_${n}_$taus fresh=no
  [ -f "$theirs.time" ] || fresh=yes
  : > "$data/ours.runs"
  [ $fresh = yes ] && : > "$theirs.runs"
  for ((k = 0; k < runs; ++k)); do
    measure "$limit" "$data/ours.txt" build/perf/host_tools/gyrochar-analyze --type counts \
        --tau0 0.01 --pulse-weight 1 --stats oadev,mdev,ohdev $ours --format csv "$f" >> "$data/ours.runs"
    [ $fresh = yes ] && measure "$limit" "$theirs.txt" bash -c "ulimit -v 16777216; exec /usr/bin/python3 \
        toolchain/allantools_job.py $peers $f 0.01 oadev,mdev,ohdev $taus" >> "$theirs.runs"
  done
  [ $fresh = yes ] && median_run < "$theirs.runs" > "$theirs.time"
  read -r gw gc gr <<< "$(median_run < "$data/ours.runs")"
  if [ "$gw" = - ]; then g="did not finish in $limit s"; else g="$gw s, CPU $gc s, $gr MiB, $(($(wc -l < "$data/ours.txt") - 1)) rows"; fi
  read -r aw ac ar < "$theirs.time"
  cp "$theirs.txt" "$data/theirs.txt"
  if [ "$aw" = - ]; then a="did not finish in $limit s: $(sed 's/^allantools: //' "$data/theirs.txt")"; else a="$aw s, CPU $ac s, $ar MiB"; fi
  local ratio=-
  if [ "$gw" != - ] && [ "$aw" != - ] && ! grep -q "out of memory" "$data/theirs.txt"; then
    ratio=$(awk -v gw="$gw" -v gc="$gc" -v aw="$aw" -v ac="$ac" 'BEGIN{printf "%.1fx (CPU %.1fx)", aw / gw, ac / gc}')
  elif grep -q "out of memory" "$data/theirs.txt"; then
    a="$(sed 's/^allantools: //' "$data/theirs.txt")"
  fi
  local opt=${ours// /_}
  echo "$n ${opt:-default} $gw $gc $aw $ac $gr $ar" >> "$data/rows.txt"  # for analyzer_targets
  echo "| $n | $(du -h "$f" | cut -f1) | \`${ours:-(defaults)}\` | $g | $a | $ratio |"
}

analyzer_sections() {
: > "$data/rows.txt"
echo "## The analyzer's reader (Google Benchmark)"
echo
echo "\`build/perf/tests/bench_datafile\`: 4 000 000 values from the page cache, bytes of text per CPU"
echo "second: counts of four digits (integer fast path), the same gzip'd (zlib's inflate in the loop;"
echo "libdeflate, measured below, is faster but cannot stream), phase values as %.9e (std::from_chars)."
echo
echo '```'
(cd "$data" && ../tests/bench_datafile --benchmark_min_time=1 2>/dev/null | grep -E "^(Benchmark|Read|-)") | tee "$data/reader.txt"
echo '```'
f=$(counts_file 10000000)
[ -f "$f.gz" ] || gzip -kf "$f"
z=$(measure 600 /dev/null gzip -dc "$f.gz" | cut -d' ' -f2)
d=$(measure 600 /dev/null libdeflate-gunzip -c "$f.gz" | cut -d' ' -f2)
echo
echo "Decompressing the 10^7-sample counts file ($(du -h "$f.gz" | cut -f1) gzip'd): gzip -dc (zlib) CPU $z s,"
echo "libdeflate-gunzip (Debian libdeflate-tools) CPU $d s. libdeflate decompresses a whole member into"
echo "memory at once; the reader streams with zlib so that its memory stays 1.3 MiB whatever the file."
echo
echo "## gyrochar-analyze beside allantools"
echo
echo "The same counts file, in the same run: gyrochar-analyze (the whole job: read once, then OADEV,"
echo "MDEV and OHDEV with EDF, confidence intervals and noise identification) and allantools"
echo "$(sed -n 's/.*"version": "\(.*\)".*/\1/p' $peers/allantools/allantools_info.json) on Debian's numpy $(/usr/bin/python3 -c 'import numpy; print(numpy.__version__)')"
echo "(\`toolchain/allantools_job.py\`: np.loadtxt, phase as the cumulative sum once, then oadev, mdev"
echo "and ohdev on it). Process wall time, CPU time (user + sys) and peak RSS; the ratio is allantools'"
echo "time over gyrochar-analyze's. The default stride factor is full: every tau up to N/4 fully"
echo "overlapped, as allantools; its taus are summed on every core ($(nproc) here; \`--threads 1\`: one)."
echo "Each figure is the median run of five (10^7 samples; allantools' five alternate with the default"
echo "row's), three (10^8, and --taus all up to 10^5) or one: this machine's speed moves by tens of"
echo "percent from one minute to the next."
echo
echo "| samples | file | options | gyrochar-analyze | allantools | ratio |"
echo "|---|---|---|---|---|---|"
side_by_side 10000000 1800 "" octave 5
side_by_side 10000000 1800 "--threads 1" octave 5
side_by_side 10000000 1800 "--stride-factor 8" octave 5
side_by_side 100000000 3600 "" octave 3
side_by_side 100000000 3600 "--threads 1" octave 3
side_by_side 100000000 3600 "--stride-factor 8" octave 3
echo
echo "Every m (\`--taus all\`, Stable32's \"all tau\"; allantools' taus=\"all\"), at most 10 minutes each:"
echo
echo "| samples | file | options | gyrochar-analyze | allantools | ratio |"
echo "|---|---|---|---|---|---|"
side_by_side 10000 600 "--taus all" all 3
side_by_side 100000 600 "--taus all" all 3
side_by_side 1000000 600 "--taus all" all
echo
echo "At 10^4 samples gyrochar's time is the read-out, on one core: the exact EDF, interval and noise"
echo "identification of each of the N/2.6 taus (covariance sums over each tau's terms, which allantools"
echo "does not compute): 96 % of the instructions by callgrind, the sums 2 %. At 10^6 the sums (each"
echo "tau over the whole record, on every core) take most of the time."
}

# The IEEE-952 fit with model selection on a real 10^6-sample record: the analyzer with and without
# --fit ieee952 (median of three runs; instructions by callgrind, repeatable).
fit_section() {
local record=../shared/refdata/real-imu/adis16405_run1_gyro_x.txt.gz
local args=(--type freq --unit deg/s --tau0 0.01)
echo "## The IEEE-952 fit with model selection"
echo
echo "\`gyrochar-analyze ${args[*]} [--fit ieee952]\` on a real record of 10^6 samples"
echo "(../shared/refdata/real-imu/adis16405_run1_gyro_x.txt.gz): the fit of both curves and of each"
echo "alone, each with its model selection (docs/metrology.md). Median run of three; instructions by"
echo "callgrind (one thread)."
echo
echo "| job | wall (s) | CPU (s) | instructions |"
echo "|---|---:|---:|---:|"
local plain fitted
for fit in "" "--fit ieee952"; do
  local runs
  runs=$(for r in 1 2 3; do measure 600 /dev/null build/perf/host_tools/gyrochar-analyze "${args[@]}" $fit "$record"; done | median_run)
  local instructions
  instructions=$(callgrind build/perf/host_tools/gyrochar-analyze "${args[@]}" --threads 1 $fit "$record")
  echo "| analyze${fit:+ $fit} | $(echo "$runs" | cut -d' ' -f1) | $(echo "$runs" | cut -d' ' -f2) | $instructions |"
  if [ -z "$fit" ]; then plain="$runs $instructions"; else fitted="$runs $instructions"; fi
done
echo
echo "$plain $fitted" | awk '{ printf "The fit adds %.2f s of wall time, %.2f s of CPU time and %.3g instructions (target: at most 1 s).\n", $5 - $1, $6 - $2, $8 - $4 }'
}

core_sections() {
echo "## Accumulator throughput (Google Benchmark)"
echo
echo "40 octave taus, ADEV+MDEV+HDEV per tau, counts of about 1000 pulses; PerSample = add_increment()"
echo "one count at a time, Block = add_increments() over the whole series, FullStride = every tau"
echo "up to N/3 fully overlapped (S >= largest m), Batch = the textbook fully overlapped estimators,"
echo "O(N) per tau, whole series in memory."
echo
echo '```'
build/perf/tests/bench_pyramid --benchmark_min_time=0.5 2>/dev/null | grep -E "^(Benchmark|PerSample|Block|FullStride|Batch|-)" | tee "$data/pyramid.txt"
echo '```'
echo
echo "## Instructions per sample"
echo
echo "\`per_sample N [block]\` (tests/benchmarks/per_sample.cpp: 40 octaves, S = 8, add_increment() per count,"
echo "or add_increments() over 4096 of them) counted with N and with 0 counts; the difference over N."
echo "x86-64: callgrind on the Release build."
echo "aarch64 (the board: -O2, as its preset) and Cortex-M4 (-Os, the MCU preset's flags): QEMU user"
echo "mode with one instruction per translation block and the execution log (\`-singlestep -d exec,nochain\`,"
echo "one line per executed instruction; on x86-64 it gives callgrind's count to the instruction)."
echo "Cortex-M4 cycles: each executed instruction costed by tests/benchmarks/cortex_m_cycles.py."
echo
isa=build/isa
mkdir -p "$isa"
qemu_trace() { "$1" -singlestep -d exec,nochain "${@:2}" 2>&1 >/dev/null | grep -c '^Trace'; }
# The presets' flags; the kernels' loops vectorized as core/CMakeLists.txt asks.
kernels="block_kernel noise_id"
per_sample="tests/benchmarks/per_sample.cpp $(ls core/src/*.cpp | grep -v -e block_kernel -e noise_id)"
vectorize="-ftree-loop-vectorize -fvect-cost-model=dynamic"
m4="-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 -fno-exceptions -fno-rtti -Os -DNDEBUG -std=c++20 -Wno-psabi -Icore/include"
m4="$m4 -DGYROCHAR_ASSERT_MODE=0"  # GYROCHAR_ASSERT as the MCU presets build it: off
for k in $kernels; do
  aarch64-linux-gnu-g++ -std=c++20 -O2 -DNDEBUG -Icore/include $vectorize -c core/src/$k.cpp -o $isa/${k}_aarch64.o
  arm-none-eabi-g++ $m4 $vectorize -c core/src/$k.cpp -o $isa/${k}_m4.o
done
aarch64-linux-gnu-g++ -std=c++20 -O2 -DNDEBUG -static -Icore/include $per_sample $(printf "$isa/%s_aarch64.o " $kernels) \
    -o $isa/per_sample_aarch64
arm-none-eabi-g++ $m4 tests/benchmarks/thumb_linux_start.s $per_sample $(printf "$isa/%s_m4.o " $kernels) -nostartfiles \
    --specs=nosys.specs --specs=nano.specs -Wl,--gc-sections -o $isa/per_sample_m4 2>/dev/null
n=2000000
x86=$(( ($(callgrind build/perf/tests/bench_per_sample $n) - $(callgrind build/perf/tests/bench_per_sample 0)) / n ))
x86_block=$(( ($(callgrind build/perf/tests/bench_per_sample $n block) - $(callgrind build/perf/tests/bench_per_sample 0 block)) / n ))
n=20000
arm64=$(( ($(qemu_trace qemu-aarch64-static $isa/per_sample_aarch64 $n) - $(qemu_trace qemu-aarch64-static $isa/per_sample_aarch64 0)) / n ))
arm64_block=$(( ($(qemu_trace qemu-aarch64-static $isa/per_sample_aarch64 $n block) - $(qemu_trace qemu-aarch64-static $isa/per_sample_aarch64 0 block)) / n ))
n=2000
for k in 0 $n; do qemu-arm-static -singlestep -d exec,nochain $isa/per_sample_m4 $k 2> $isa/m4_$k.trace > /dev/null; done
m4=$(python3 tests/benchmarks/cortex_m_cycles.py $isa/per_sample_m4 $isa/m4_0.trace $isa/m4_$n.trace $n)
m4_cycles=$(echo "$m4" | awk '{print $4}')
rm -f $isa/m4_*.trace
echo "| target | instructions per sample: add_increment() | add_increments(), 4096 a call |"
echo "|---|---|---|"
echo "| x86-64 (callgrind, 2*10^6 counts) | $x86 | $x86_block |"
echo "| aarch64 (QEMU, 2*10^4 counts) | $arm64 | $arm64_block |"
echo "| Cortex-M4 (QEMU, 2000 counts) | $m4 | |"
echo
echo "(Both include the test's own generator of the counts, a 16-bit LFSR: about 8 instructions.)"
echo
echo "Cortex-M4 load: $(awk -v c=$m4_cycles 'BEGIN{printf "%.1f M cycles/s at 1 kHz sampling (%.0f %% of a 168 MHz core), %.0f M cycles/s at 10 kHz (%.0f %%)", c*1e3/1e6, c*1e3/168e4, c*1e4/1e6, c*1e4/168e4}')."
echo
echo "## State size"
echo
state=$(build/perf/tests/core_test_characterizer_alloc --gtest_filter='*StateSize*' | grep sizeof)
echo "$state."
echo
echo "## Freestanding core on Cortex-M (MCU example: 40-octave S = 8 characterizer and its read-out)"
echo
echo '```'
for mcu in cortex-m4 cortex-m7; do
  cmake --preset "$mcu" >/dev/null && cmake --build --preset "$mcu" >/dev/null
  echo "$mcu: $(arm-none-eabi-size build/$mcu/firmware/mcu/gyrochar-mcu-example | tail -1 | awk '{print "text " $1 ", data " $2 ", bss " $3 " bytes"}')"
done
echo '```'
}

core_targets() {
rate() { awk -v b="$1" '$1 == b { for (i = 1; i <= NF; ++i) if ($i ~ /^items_per_second=/) { sub(/items_per_second=/, "", $i); print $i } }' "$data/pyramid.txt"; }
met() { awk -v v="$1" -v t="$2" -v dir="$3" 'BEGIN { ok = dir == "max" ? v + 0 <= t + 0 : v + 0 >= t + 0; print ok ? "met" : "**missed**" }'; }
block=$(rate Block/8/10000000 | tr -d M/s)
state_bytes=$(echo "$state" | sed 's/.*) = \([0-9]*\) bytes.*/\1/')
echo "## Against the targets"
echo
echo "Core, one run on this machine:"
echo
echo "- Block API >= 150 M samples/s at S = 8, 40 octaves, one core: $(met "$block" 150 min) (${block} M/s)."
echo "- Per-sample path <= 200 instructions (moonshot 80): $(met "$x86" 200 max) on x86-64 ($x86),"
echo "  $(met "$arm64" 200 max) on aarch64 ($arm64); through the block API $x86_block and $arm64_block."
echo "- State <= 16 KiB (40 octaves, S = 8): $(met "$state_bytes" 16384 max) ($state_bytes bytes with the decimated series"
echo "  and the noise identification sums)."
echo "- FullStride: $(rate FullStride/10000000) at 10^7 counts, beside Batch at $(rate Batch/10000000)."
echo
}

# The analyzer's targets from this run's rows (rows.txt: n options wall cpu allantools_wall allantools_cpu
# rss_mib allantools_rss_mib; options with _ for spaces, "default" for none).
analyzer_targets() {
row() { awk -v n="$1" -v o="$2" '$1 == n && $2 == o' "$data/rows.txt"; }
ratio() { row "$1" "$2" | awk '$3 != "-" && $5 != "-" { printf "%.1fx by wall time (%s s against %s s), %.1fx by CPU time (%s s against %s s)", $5 / $3, $3, $5, $6 / $4, $4, $6 }'; }
met_at() { row "$1" "$2" | awk -v t="$3" '$3 != "-" && $5 != "-" { print (($5 / $3 >= t && $6 / $4 >= t) ? "met" : ($5 / $3 >= t ? "met by wall time, **missed** by CPU time" : "**missed**")) }'; }
mbs=$(awk '/^ReadCounts /{ for (i = 1; i <= NF; ++i) if ($i ~ /^bytes_per_second=/) { sub(/bytes_per_second=/, "", $i); print $i } }' "$data/reader.txt")
echo "## Against the analyzer's targets"
echo
echo "From the rows above (this run, this machine; the default sums the taus on every core):"
echo
echo "- Reading >= 300 MB/s: $(awk -v v="${mbs%M/s}" 'BEGIN { print (v + 0 >= 300 ? "met" : "**missed**") }') ($mbs of counts text per CPU second)."
echo "- Whole job >= 20x allantools at 10^7, default settings: $(met_at 10000000 default 20), $(ratio 10000000 default);"
echo "  one thread: $(ratio 10000000 --threads_1)."
echo "- 10^8 samples, the same or better: $(ratio 100000000 default); one thread: $(ratio 100000000 --threads_1)."
echo "- --stride-factor full (the default) >= 10x allantools: $(met_at 10000000 default 10)."
echo "- --taus all beside allantools' taus=\"all\": 10^4 $(ratio 10000 --taus_all); 10^5 $(ratio 100000 --taus_all);"
echo "  10^6: $(row 1000000 --taus_all | awk '{ print ($3 == "-" ? "gyrochar did not finish" : "gyrochar " $3 " s (CPU " $4 " s)") ", " ($5 == "-" ? "allantools did not finish in 600 s" : "allantools " $5 " s") }')."
echo
}

if [ "${1:-}" = --core ]; then
  core_sections
  core_targets
  exit 0
fi
if [ "${1:-}" = --fit ]; then
  fit_section
  exit 0
fi
if [ "${1:-}" = --analyzer ]; then
  analyzer_sections
  analyzer_targets
  exit 0
fi

{
echo "# Benchmarks"
echo
echo "Regenerated by \`toolchain/benchmarks.sh\` on $(date -u +%Y-%m-%d): $(nproc) cores,"
echo "$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(free -g | awk '/Mem:/{print $2}') GiB, g++ $(g++ -dumpversion), Release build."
echo "The machine is shared (other jobs may run): throughput figures are indicative; instruction"
echo "counts (callgrind) are repeatable."
echo
core_sections
echo
analyzer_sections
echo
fit_section
echo
echo "## Decoder (gyrochar-decode's pipeline)"
echo
echo "A candump log of 10^7 frames (4 nodes, 32 taus, one report per second each), read in blocks,"
echo "parsed and decoded in one process (\`build/perf/tests/bench_decode 10000000\`):"
echo
echo '```'
build/perf/tests/bench_decode 10000000
echo '```'
echo
echo "## gyrochard on the board (QEMU bench)"
echo
echo "One gyrochard node on vcan0 under Debian's kernel in QEMU, fed 100 CounterInput frames/s,"
echo "reporting every second, malloc_count.so preloaded; /proc figures at start + 5 s and 40 s later"
echo "(\`toolchain/bench/run.sh gyrochard-rss\`, docs/bench.md; the bench must be assembled):"
echo
rss_log=build/bench/logs/gyrochard-rss.log
if [ -s build/bench/kernel/vmlinuz ]; then
  toolchain/bench/run.sh gyrochard-rss > /dev/null 2>&1 || true
fi
echo '```'
if [ -s "$rss_log" ]; then
  tr -d '\r' < "$rss_log" | grep -a -E 'start \+ [0-9]+ s: VmRSS|gyrochard-rss figures' | sed 's/^bench: //'
else
  echo "(bench not assembled: toolchain/bench/build.sh)"
fi
echo '```'
echo
core_targets
echo "Tools:"
echo
rss() { awk -v n="$1" '$1 == n && $2 == "--stride-factor_8" { print $7 }' "$data/rows.txt"; }
echo "- gyrochar-analyze peak RSS independent of file length at a fixed stride factor: $([ "$(rss 10000000)" = "$(rss 100000000)" ] && echo met || echo '**missed**')"
echo "  ($(rss 10000000) MiB at 10^7 and $(rss 100000000) MiB at 10^8 samples with \`--stride-factor 8\`; the default, full,"
echo "  holds the counts at 4 bytes a value: see the rows above)."
echo "- gyrochard steady-state RSS and zero allocations after start-up: met on the QEMU bench (above:"
echo "  no allocation, no new page, RSS and HWM unchanged over 40 s)."
echo
analyzer_targets
} > "$out.new"
# The total and Theo family's section is toolchain/total_benchmarks.sh's: kept as it was.
[ -f "$out" ] && sed -n '/<!-- total:begin -->/,/<!-- total:end -->/p' "$out" | sed '1s/^/\n/' >> "$out.new"
mv "$out.new" "$out"
echo "benchmarks.sh: wrote $out" >&2
