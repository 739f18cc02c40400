#!/bin/bash
# Three gyrochard nodes on one virtual CAN bus (vcan0, the kernel's vcan driver), each fed by its
# own simulated gyro electronics (gyrochar-sim sending CounterInput frames), recorded by
# gyrochar-decode from the same bus. Verdict: every node decoded with no lost or incomplete report,
# and each node's decoded ADEV and MDEV equal gyrochar-analyze's on the counts its electronics sent.
source /bench/lib.sh

nodes=(17 18 19)
duration_s=30  # simulated gyro time per node: 3000 samples, sent at 3x real time

vcan_up vcan0
step "decoder and ${#nodes[@]} gyrochard nodes on vcan0"
start_nodes vcan0 vcan0 "${nodes[@]}"
step "gyro electronics: $duration_s s of counts per node"
feed_nodes vcan0 "$duration_s" 3 "${nodes[@]}"
step "reports after the last sample"
sleep 6
stop_nodes "${nodes[@]}"

step "link health"
gyrochar-bench link --jsonl /tmp/decoded.jsonl "${nodes[@]/#/--node=}" --min-reports 8 || fail "link health (above)"
step "decoded estimates against gyrochar-analyze on the same counts"
check_estimates 3000 "${nodes[@]}"
pass "${#nodes[@]} nodes on vcan0: every report complete, decoded ADEV/MDEV equal gyrochar-analyze on 3000 counts each"
