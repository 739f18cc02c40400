#!/bin/bash
# GPIO quadrature input through the kernel's GPIO character device: gyrochard (libgpiod 1.6, both
# edges of lines A and B, kernel timestamps) reads a gpio-sim chip whose lines the bench driver
# moves by writing pull-up / pull-down, playing 30 s of simulated gyro counts as 4x quadrature
# edges, each interval's edges inside that interval of gyrochard's grid. gyrochard reports on vcan0.
# Verdict: the counts equal exactly (the decoded ADEV and MDEV equal gyrochar-analyze's on the
# played sample stream in float32), no lost edge, no sample gap, every report complete.
source /bench/lib.sh

bench_tau0=0.2
node=65

vcan_up vcan0
gpio_sim_up 2
step "gpio-sim chip $gpio_chip ($gpio_sim_dir); gyrochard node $node on lines 0 and 1"
quadrature_node "$node" 30 0
step "link health"
gyrochar-bench link --jsonl /tmp/decoded.jsonl --node "$node" --min-reports 10 || fail "link health (above)"
step "decoded estimates against gyrochar-analyze on the played counts"
check_estimates "$samples" "$node"
pass "$samples quadrature samples counted exactly (ADEV/MDEV equal gyrochar-analyze), no lost edge, every report complete"
