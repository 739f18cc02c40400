#!/bin/bash
# bench: can-controllers
# A bus fault on the emulated SJA1000 bus: while a gyrochard node reports on can0 (its gyro
# electronics sending from can1, gyrochar-decode recording from can1), can0 is taken down for 5 s
# and brought up again. Verdict: gyrochard keeps running through it and stops cleanly; the decoder
# shows the gap (lost reports, the node offline) and then complete reports again, with no
# restart of the node's session; the node counted the counter frames it missed as a sample gap.
source /bench/lib.sh

node=49
down_s=5

can_up can0 500000
can_up can1 500000
step "decoder on can1, gyrochard node $node on can0, electronics on can1: 30 s in real time"
start_nodes can0 can1 "$node"
( feed_nodes can1 30 1 "$node" ) > /tmp/feed.log 2>&1 &
feeder=$!
sleep 8
step "bus fault: can0 down for $down_s s"
ip link set can0 down
sleep "$down_s"
running "gyrochard-$node" || fail "gyrochard stopped while can0 was down"
ip link set can0 up
step "can0 up again: $(ip -details link show can0 | grep -o 'can state [A-Z-]* ([^)]*)')"
wait "$feeder" || fail "the gyro electronics failed: $(cat /tmp/feed.log)"
cat /tmp/feed.log
sleep 3
running "gyrochard-$node" || fail "gyrochard stopped after the bus fault"
stop_nodes "$node"
grep -E '"event":"(offline|online)"' /tmp/decoded.jsonl || true

step "link health: the gap and the recovery"
gyrochar-bench link --jsonl /tmp/decoded.jsonl --node "$node" --expect-gap --min-reports 5 || fail "link health (above)"
gaps=$(grep '"type":"report"' /tmp/decoded.jsonl | tail -n 1 | grep -o '"sample_gaps":[0-9]*' | cut -d: -f2)
[ "${gaps:-0}" -ge 1 ] || fail "the node counted no sample gap although its counter frames were lost while can0 was down"
pass "can0 down $down_s s: gyrochard kept running, the decoder showed the gap and resumed; $gaps sample gap(s) counted by the node"
