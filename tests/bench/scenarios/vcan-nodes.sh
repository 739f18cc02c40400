#!/bin/bash
# Three gyrochard nodes on one virtual CAN bus (vcan0, the kernel's vcan driver), each fed by its
# own simulated gyro electronics (gyrochar-sim sending CounterInput frames), recorded by
# gyrochar-decode from the same bus. Verdict: every node decoded with no lost or incomplete report,
# and each node's decoded ADEV and MDEV equal gyrochar-analyze's on the counts its electronics sent.
source /bench/lib.sh

nodes=(17 18 19)           # gyrochard addresses; their electronics are node + 112 (0x81..0x83)
tau0=0.01
duration_s=30              # simulated gyro time per node
speed=3                    # frames at 3x real time: 10 s of sending
samples=$(awk -v d="$duration_s" -v t="$tau0" 'BEGIN { printf "%d", d / t + 0.5 }')

vcan_up vcan0
step "decoder and ${#nodes[@]} gyrochard nodes on vcan0"
start decode gyrochar-decode --interface vcan0 --rate-unit native --csv /tmp/decoded.csv --jsonl /tmp/decoded.jsonl --view none
for node in "${nodes[@]}"; do
  start "gyrochard-$node" gyrochard --source can-counter --can-interface vcan0 --node "$node" \
    --counter-node $((node + 112)) --tau0 "$tau0" --octaves 16
done
sleep 2
for node in "${nodes[@]}"; do running "gyrochard-$node" || fail "gyrochard node $node stopped at start"; done

step "gyro electronics: $duration_s s of counts per node at ${speed}x real time"
for node in "${nodes[@]}"; do
  start "sim-$node" gyrochar-sim --duration "$duration_s" --tau0 "$tau0" --white-angle 2 --arw 0.003 --seed "$node" \
    --can vcan0 --can-node $((node + 112)) --speed "$speed" --out "/tmp/counts-$node.txt"
done
for node in "${nodes[@]}"; do
  finish "sim-$node"
  [ "$status" -eq 0 ] || fail "gyrochar-sim for node $node exited with $status"
  cat "/tmp/sim-$node.log"
done
step "reports after the last sample"
sleep 6
stop decode
[ "$status" -eq 0 ] || fail "gyrochar-decode exited with $status"
for node in "${nodes[@]}"; do
  stop "gyrochard-$node"
  [ "$status" -eq 0 ] || fail "gyrochard node $node exited with $status on SIGTERM"
done
tail -n 4 /tmp/decode.log

step "link health"
link_args=()
for node in "${nodes[@]}"; do link_args+=(--node "$node"); done
gyrochar-bench link --jsonl /tmp/decoded.jsonl "${link_args[@]}" --min-reports 8 || fail "link health (above)"

step "decoded estimates against gyrochar-analyze on the same counts"
for node in "${nodes[@]}"; do
  gyrochar-analyze --type counts --tau0 "$tau0" --pulse-weight 1arcsec --rate-unit deg/s --stride-factor 8 \
    --format csv "/tmp/counts-$node.txt" > "/tmp/analyzed-$node.csv"
  gyrochar-bench estimates --jsonl /tmp/decoded.jsonl --csv /tmp/decoded.csv --node "$node" --samples "$samples" \
    --analyzed "/tmp/analyzed-$node.csv" || fail "node $node: decoded estimates differ from gyrochar-analyze (above)"
done
pass "${#nodes[@]} nodes on vcan0: every report complete, decoded ADEV/MDEV equal gyrochar-analyze on $samples counts each"
