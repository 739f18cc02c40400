#!/bin/bash
# The CAN interface vanishes and comes back, as a USB adapter re-plugged: while gyrochard counts
# quadrature edges on a gpio-sim chip (the bench driver plays 30 s of sim counts, as in
# gpio-quadrature) and reports on vcan0, `ip link del vcan0`, 5 s, then a new vcan0 (a new
# interface index) is made and set up. gyrochard and gyrochar-decode keep their sockets (bound to
# every CAN interface, hal/linux/socketcan.cpp) and find vcan0 again by name.
# Verdict: gyrochard kept running and stops cleanly; it counted the fault (TxDroppedFrames > 0)
# and no sample gap; the decoder, surviving the vanish, shows the gap (reports lost, offline) and
# then complete reports of the same session; the counts stayed exact across it (decoded ADEV and
# MDEV equal gyrochar-analyze's on the played sample stream), so gyrochard kept accumulating.
source /bench/lib.sh

bench_tau0=0.2
node=67
gone_s=5

vcan_up vcan0
old_index=$(cat /sys/class/net/vcan0/ifindex)
gpio_sim_up 2
step "gpio-sim chip $gpio_chip; gyrochard node $node reports on vcan0 (index $old_index)"
# The vanish, in the background: once the decoder has 8 reports, vcan0 goes for $gone_s s.
(
  trap - ERR
  set +e
  tries=0
  until [ "$(grep -c '"type":"report"' /tmp/decoded.jsonl 2> /dev/null)" -ge 8 ]; do
    ((++tries <= 300)) || { echo "no 8 reports within 30 s"; exit 1; }
    sleep 0.1
  done
  step "ip link del vcan0"
  ip link del vcan0 || exit 1
  sleep "$gone_s"
  ip link add dev vcan0 type vcan && ip link set vcan0 up || exit 1
  step "vcan0 is back, index $(cat /sys/class/net/vcan0/ifindex)"
) > /tmp/vanish.log 2>&1 &
vanisher=$!
quadrature_node "$node" 30 0
wait "$vanisher" || fail "the vanish did not happen: $(cat /tmp/vanish.log)"
cat /tmp/vanish.log
new_index=$(cat /sys/class/net/vcan0/ifindex)
[ "$new_index" != "$old_index" ] || fail "the new vcan0 has the old index $old_index: the scenario tests nothing"

step "link health: the gap and the recovery"
gyrochar-bench link --jsonl /tmp/decoded.jsonl --node "$node" --expect-gap --min-reports 5 || fail "link health (above)"
last=$(grep '"type":"report"' /tmp/decoded.jsonl | tail -n 1)
dropped=$(grep -o '"tx_dropped_frames":[0-9]*' <<< "$last" | cut -d: -f2)
gaps=$(grep -o '"sample_gaps":[0-9]*' <<< "$last" | cut -d: -f2)
lost=$(grep -o '"reports_lost":[0-9]*' <<< "$last" | cut -d: -f2)
session=$(grep -o '"session":[0-9]*' <<< "$last" | cut -d: -f2)
[ "${dropped:-0}" -ge 1 ] || fail "gyrochard counted no dropped frame although vcan0 was gone for $gone_s s"
[ "${gaps:-1}" -eq 0 ] || fail "gyrochard counted $gaps sample gaps: its quadrature input does not depend on CAN"
[ "${session:-1}" -eq 0 ] || fail "the decoder saw a restart (session $session)"
step "decoded estimates against gyrochar-analyze on the played counts"
check_estimates "$samples" "$node"
pass "vcan0 gone $gone_s s (index $old_index -> $new_index): gyrochard counted $dropped dropped frames and no sample gap, resumed on the new vcan0; the decoder saw $lost reports lost and the same session; counts exact over $samples samples"
