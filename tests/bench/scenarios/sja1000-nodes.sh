#!/bin/bash
# bench: can-controllers
# Two emulated SJA1000 controllers (QEMU kvaser_pci, the kernel's sja1000 driver) on one emulated
# bus at 500 kbit/s: two gyrochard nodes report on can0; their simulated gyro electronics send
# CounterInput frames from can1 and gyrochar-decode records from can1, so every frame crosses the
# controllers. Verdict: as vcan-nodes (every report complete, estimates equal gyrochar-analyze's),
# and the controllers stayed error active.
source /bench/lib.sh

nodes=(33 34)
duration_s=30  # 3000 samples per node, sent at 3x real time

can_up can0 500000
can_up can1 500000
step "decoder on can1, ${#nodes[@]} gyrochard nodes on can0 ($(ip -details link show can0 | grep -o 'bitrate [0-9]*'))"
start_nodes can0 can1 "${nodes[@]}"
step "gyro electronics on can1: $duration_s s of counts per node"
feed_nodes can1 "$duration_s" 3 "${nodes[@]}"
step "reports after the last sample"
sleep 6
stop_nodes "${nodes[@]}"
for dev in can0 can1; do
  state=$(ip -details link show "$dev" | grep -o 'can state [A-Z-]* ([^)]*)')
  echo "bench: $dev: $state"
  [[ "$state" == "can state ERROR-ACTIVE "* ]] || fail "$dev left error active: $state"
done

step "link health"
gyrochar-bench link --jsonl /tmp/decoded.jsonl "${nodes[@]/#/--node=}" --min-reports 8 || fail "link health (above)"
step "decoded estimates against gyrochar-analyze on the same counts"
check_estimates 3000 "${nodes[@]}"
pass "${#nodes[@]} nodes on can0 -> can1 at 500 kbit/s: every report complete, decoded ADEV/MDEV equal gyrochar-analyze"
