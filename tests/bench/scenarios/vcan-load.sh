#!/bin/bash
# bench: timeout 540
# The decoder under load (vcan0, the kernel's vcan driver): 8 gyrochard nodes, each fed by its own
# simulated gyro electronics, plus a flood of unrelated frames (can-utils' cangen, random 11-bit
# identifiers, lengths and data) on the same bus; gyrochar-decode records from vcan0.
# The nodes report once a second for 2 minutes of bus time (the load of the issue; compressed
# 4x, a report every 0.25 s, the decoder's socket overflowed, see docs/bench.md).
# Verdict: the decoder's socket dropped nothing (SO_RXQ_OVFL total 0, from its summary), every
# node's reports are complete (none lost, none incomplete, no offline event: gyrochar-bench link).
# Then the margin, measured, not judged: fresh decoders for 8 s each while the flood steps up to
# as fast as cangen can send; the figures (flood rate, drops, the decoder's CPU share) are printed.
source /bench/lib.sh

nodes=(81 82 83 84 85 86 87 88)
bench_tau0=0.05  # 20 CounterInput frames/s per node
duration_s=120
flood_gap_ms=1  # cangen -g: at most 1000 frames/s

vcan_up vcan0
step "decoder and ${#nodes[@]} gyrochard nodes on vcan0, a report a second"
start_nodes vcan0 vcan0 "${nodes[@]}"
start flood cangen vcan0 -g "$flood_gap_ms"
frames0=$(rx_packets vcan0)
ticks0=$(cpu_ticks "${bench_pid[decode]}")
t0=$(uptime_s)
step "gyro electronics: $duration_s s of counts per node, in real time, flood at cangen -g $flood_gap_ms"
feed_nodes vcan0 "$duration_s" 1 "${nodes[@]}" > /dev/null
sleep 2  # reports after the last sample
t1=$(uptime_s)
frames1=$(rx_packets vcan0)
ticks1=$(cpu_ticks "${bench_pid[decode]}")
stop flood
stop decode
[ "$status" -eq 0 ] || fail "gyrochar-decode exited with $status"
tail -n $((${#nodes[@]} + 1)) /tmp/decode.log
drops=$(socket_drops /tmp/decode.log)
[ -n "$drops" ] || fail "the decoder printed no socket counters: $(tail -n 3 /tmp/decode.log)"
rate=$(awk -v f="$((frames1 - frames0))" -v a="$t0" -v b="$t1" 'BEGIN { printf "%.0f", f / (b - a) }')
share=$(awk -v c="$((ticks1 - ticks0))" -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", c / (b - a) }')
reports=$(grep -c '"type":"report"' /tmp/decoded.jsonl)
step "load: $((frames1 - frames0)) frames in $(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }') s ($rate frames/s on vcan0), decoder CPU $share %, $reports reports decoded, socket drops $drops"
[ "$drops" -eq 0 ] || fail "the decoder's socket dropped $drops frames (SO_RXQ_OVFL) at $rate frames/s"

step "link health of the ${#nodes[@]} nodes"
min_reports=$((duration_s - 8))
gyrochar-bench link --jsonl /tmp/decoded.jsonl "${nodes[@]/#/--node=}" --min-reports "$min_reports" ||
  fail "link health (above)"

# The margin: the nodes keep reporting (input lost: same frames per report), the flood steps up.
step "margin: a fresh decoder for 8 s at each flood rate"
margin=""
best=0
# cangen -g G -c C: C frames every G ms (the guest's timers make -g 1 about 600 frames/s; -g 0: as
# fast as it can send)
for flood in "-g 1 -c 4" "-g 1 -c 16" "-g 0"; do
  start decode gyrochar-decode --interface vcan0 --view none
  wait_socket decode
  # shellcheck disable=SC2086
  start flood cangen vcan0 $flood
  f0=$(rx_packets vcan0)
  c0=$(cpu_ticks "${bench_pid[decode]}")
  a=$(uptime_s)
  sleep 8
  b=$(uptime_s)
  f1=$(rx_packets vcan0)
  c1=$(cpu_ticks "${bench_pid[decode]}")
  stop flood
  stop decode
  d=$(socket_drops /tmp/decode.log)
  r=$(awk -v f="$((f1 - f0))" -v a="$a" -v b="$b" 'BEGIN { printf "%.0f", f / (b - a) }')
  s=$(awk -v c="$((c1 - c0))" -v a="$a" -v b="$b" 'BEGIN { printf "%.1f", c / (b - a) }')
  step "margin: cangen $flood: $r frames/s on vcan0, decoder CPU $s %, socket drops ${d:-?}"
  margin="$margin; $flood: $r/s, CPU $s %, drops ${d:-?}"
  [ "${d:-1}" -ne 0 ] || [ "$r" -le "$best" ] || best=$r
done
for node in "${nodes[@]}"; do
  stop "gyrochard-$node"
  [ "$status" -eq 0 ] || fail "gyrochard node $node exited with $status on SIGTERM"
done
pass "${#nodes[@]} nodes x $duration_s reports + flood, $rate frames/s: 0 socket drops, every report complete, decoder CPU $share %; no drop up to $best frames/s (x$(awk -v a="$best" -v b="$rate" 'BEGIN { printf "%.1f", a / b }')): margin${margin}"
