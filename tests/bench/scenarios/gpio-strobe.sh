#!/bin/bash
# Strobe plus hardware counter through the kernel's GPIO character device: gyrochard (libgpiod 1.6,
# rising edges of one gpio-sim line, kernel timestamps) reads the count latched at each strobe from
# a counter file (standing in for a sysfs counter attribute), the bench writing the accumulated
# count of 20 s of simulated gyro counts before each strobe. gyrochard reports on vcan0.
# Verdict: the counts equal exactly (the decoded ADEV and MDEV equal gyrochar-analyze's on the
# played sample stream in float32), no sample gap, every report complete.
source /bench/lib.sh

bench_tau0=0.5
node=66

vcan_up vcan0
gpio_sim_up 1
strobe=$gpio_sim_dir/sim_gpio0/pull
echo pull-down > "$strobe"
gyrochar-sim --duration 20 --tau0 "$bench_tau0" --white-angle 3 --arw 0.003 --seed "$node" \
  --out "/tmp/counts-$node.txt"
counter=4294967000  # near 2^32: the 32-bit counter wraps during the run
printf '%d\n' "$counter" > /tmp/counter
step "gpio-sim chip $gpio_chip; gyrochard node $node, strobe on line 0, counter in /tmp/counter"
start decode gyrochar-decode --interface vcan0 --rate-unit native --csv /tmp/decoded.csv \
  --jsonl /tmp/decoded.jsonl --view none
wait_socket decode
start "gyrochard-$node" gyrochard --source strobe --gpio-chip "$gpio_chip" --strobe-line 0 \
  --counter-path /tmp/counter --can-interface vcan0 --node "$node" --tau0 "$bench_tau0" --octaves 8
sleep 1
running "gyrochard-$node" || fail "gyrochard stopped at start"

step "strobes: the reference, then one per played count"
echo pull-up > "$strobe"
sleep 0.25
echo pull-down > "$strobe"
while read -r count; do
  case $count in '#'*) continue ;; esac
  sleep 0.2
  counter=$(((counter + count) % 4294967296))
  printf '%d\n' "$counter" > /tmp/counter  # latched before the strobe
  sleep 0.05
  echo pull-up > "$strobe"
  sleep 0.2
  echo pull-down > "$strobe"
done < "/tmp/counts-$node.txt"
samples=$(grep -vc '^#' "/tmp/counts-$node.txt")
sleep 3
stop_nodes "$node"

step "link health"
gyrochar-bench link --jsonl /tmp/decoded.jsonl --node "$node" --min-reports 10 || fail "link health (above)"
step "decoded estimates against gyrochar-analyze on the played counts"
check_estimates "$samples" "$node"
pass "$samples strobe samples counted exactly across a 32-bit counter wrap (ADEV/MDEV equal gyrochar-analyze), every report complete"
