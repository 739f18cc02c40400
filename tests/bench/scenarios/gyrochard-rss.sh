#!/bin/bash
# gyrochard's memory in steady state (steady-state RSS and zero allocations after
# start-up): one gyrochard node on vcan0, fed by its simulated gyro electronics in real time
# (tau0 0.01 s: 100 CounterInput frames/s) and reporting every second, with tests/bench's
# malloc_count.so preloaded (it counts every malloc, calloc, realloc and aligned allocation).
# Figures from /proc/PID/status (VmRSS, VmHWM), /proc/PID/statm and /proc/PID/stat (minor page
# faults) at start + 5 s and at the end, 40 s later.
# Verdict: between the two samples gyrochard made no heap allocation, VmRSS did not grow and
# VmHWM did not move; every report was complete (it did its work meanwhile).
source /bench/lib.sh

node=53
run_s=40

vcan_up vcan0
start decode gyrochar-decode --interface vcan0 --rate-unit native --jsonl /tmp/decoded.jsonl --view none
wait_socket decode
start "gyrochard-$node" env LD_PRELOAD=/usr/lib/malloc_count.so MALLOC_COUNT_FILE=/tmp/malloc-count \
  gyrochard --source can-counter --can-interface vcan0 --node "$node" --counter-node $((node + 112)) \
  --tau0 "$bench_tau0" --octaves 16
pid=${bench_pid[gyrochard-$node]}
( feed_nodes vcan0 $((run_s + 10)) 1 "$node" ) > /tmp/feed.log 2>&1 &
feeder=$!
sleep 5
running "gyrochard-$node" || fail "gyrochard stopped at start"
[ -s /tmp/malloc-count ] || fail "malloc_count.so made no /tmp/malloc-count: not preloaded?"
figures() {  # label: VmRSS, VmHWM, statm, minor faults, allocations so far
  echo "$1 $(proc_kib "$pid" VmRSS) $(proc_kib "$pid" VmHWM) $(minor_faults "$pid") $(od -An -tu8 /tmp/malloc-count | tr -d ' ') $(cat "/proc/$pid/statm" | tr ' ' ,)"
}
read -r _ rss0 hwm0 flt0 alloc0 statm0 <<< "$(figures start)"
step "start + 5 s: VmRSS $rss0 KiB, VmHWM $hwm0 KiB, statm $statm0 (pages), $flt0 minor faults, $alloc0 allocations since exec"
sleep "$run_s"
read -r _ rss1 hwm1 flt1 alloc1 statm1 <<< "$(figures end)"
step "start + $((run_s + 5)) s: VmRSS $rss1 KiB, VmHWM $hwm1 KiB, statm $statm1 (pages), $flt1 minor faults, $alloc1 allocations since exec"
wait "$feeder" || fail "the gyro electronics failed: $(cat /tmp/feed.log)"
stop decode
stop "gyrochard-$node"
[ "$status" -eq 0 ] || fail "gyrochard exited with $status on SIGTERM"
figure_text="VmRSS $rss0 -> $rss1 KiB, VmHWM $hwm0 -> $hwm1 KiB, $((flt1 - flt0)) minor faults, $((alloc1 - alloc0)) allocations in $run_s s"
echo "bench: gyrochard-rss figures: $figure_text"
[ "$alloc1" -eq "$alloc0" ] || fail "gyrochard allocated $((alloc1 - alloc0)) times after start-up ($figure_text)"
[ "$rss1" -le "$rss0" ] || fail "VmRSS grew ($figure_text)"
[ "$hwm1" -eq "$hwm0" ] || fail "VmHWM grew ($figure_text)"
gyrochar-bench link --jsonl /tmp/decoded.jsonl --node "$node" --min-reports $((run_s - 5)) || fail "link health (above)"
pass "$figure_text"
