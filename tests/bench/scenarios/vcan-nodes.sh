#!/bin/bash
# Three gyrochard nodes on one virtual CAN bus (vcan0, the kernel's vcan driver), each fed by its
# own simulated gyro electronics (gyrochar-sim sending CounterInput frames), recorded by
# gyrochar-decode from the same bus, while remote (RTR) frames with the first node's report
# identifiers cross the bus (a request carries no data: the decoder must not take it for a
# report's frame). Verdict: every node decoded with no lost or incomplete report, and each node's
# decoded ADEV and MDEV equal gyrochar-analyze's on the counts its electronics sent.
source /bench/lib.sh

nodes=(17 18 19)
duration_s=30  # simulated gyro time per node: 3000 samples, sent at 3x real time

vcan_up vcan0
step "decoder and ${#nodes[@]} gyrochard nodes on vcan0"
start_nodes vcan0 vcan0 "${nodes[@]}"
step "gyro electronics: $duration_s s of counts per node, remote frames beside them"
( for k in $(seq 20); do
    cansend vcan0 14FF40$(printf %02X "${nodes[0]}")#R8 && cansend vcan0 18FF41$(printf %02X "${nodes[0]}")#R8
    sleep 0.4
  done ) &
remote=$!
feed_nodes vcan0 "$duration_s" 3 "${nodes[@]}"
wait "$remote" || fail "cansend of the remote frames failed"
step "reports after the last sample"
sleep 6
stop_nodes "${nodes[@]}"

step "link health"
gyrochar-bench link --jsonl /tmp/decoded.jsonl "${nodes[@]/#/--node=}" --min-reports 8 || fail "link health (above)"
step "decoded estimates against gyrochar-analyze on the same counts"
check_estimates 3000 "${nodes[@]}"
pass "${#nodes[@]} nodes on vcan0: every report complete, decoded ADEV/MDEV equal gyrochar-analyze on 3000 counts each"
