#!/bin/bash
# Lost edges on the GPIO quadrature input: as gpio-quadrature, but every 10th interval the bench
# driver also makes the kernel drop one edge on line A. It runs SCHED_FIFO and toggles A 17 times
# without sleeping, so gyrochard cannot read in between and the per-line event buffer of the GPIO
# uAPI v1 (16 events, what libgpiod 1.6 uses) drops the 17th; the toggle that brings A back then
# shows gyrochard an event that changes nothing. Verdict: gyrochard counted exactly one lost edge
# per burst and reported it, and the counts still equal exactly (a missed edge and its detection
# cancel; the 16 kept edges go back and forth).
source /bench/lib.sh

bench_tau0=0.2
node=66

vcan_up vcan0
gpio_sim_up 2
step "gpio-sim chip $gpio_chip; gyrochard node $node; an overflow burst every 10 intervals"
quadrature_node "$node" 30 10  # 150 intervals: 15 bursts, fewer if gyrochard was busy too long
[ "$bursts" -ge 12 ] || fail "only $bursts overflow bursts could be played"
step "link health: $bursts lost edges reported"
gyrochar-bench link --jsonl /tmp/decoded.jsonl --node "$node" --min-reports 10 --lost-edges "$bursts" ||
  fail "link health (above)"
step "decoded estimates against gyrochar-analyze on the played counts"
check_estimates "$samples" "$node"
pass "$bursts bursts: $bursts lost edges counted and reported, the $samples samples still counted exactly"
