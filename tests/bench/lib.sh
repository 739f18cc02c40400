# Sourced by every bench scenario (tests/bench/scenarios/*.sh), inside the bench's guest: bash,
# busybox, iproute2's ip, can-utils and the project's programs on PATH, working directory /tmp.
# A scenario ends with `pass REASON` or `fail REASON`; /init turns that into the verdict line.
set -euo pipefail

declare -A bench_pid=()  # background programs by name; their output is in /tmp/NAME.log

uptime_s() { cut -d' ' -f1 /proc/uptime; }
step() { echo "bench: [$(uptime_s) s] $*"; }

show_logs() {
  local name
  for name in "${!bench_pid[@]}"; do
    echo "bench: --- /tmp/$name.log (last 15 lines) ---"
    tail -n 15 "/tmp/$name.log" || true
  done
}
pass() {
  printf '%s\n' "$*" > /tmp/bench-reason
  exit 0
}
fail() {
  printf '%s\n' "$*" > /tmp/bench-reason
  echo "bench: FAIL: $*"
  show_logs
  exit 1
}
trap 'fail "line $LINENO: command failed: $BASH_COMMAND"' ERR

# expect_exit CODE PATTERN COMMAND...: COMMAND must exit with CODE and say something matching
# PATTERN (grep -E) on stderr; prints what it said.
expect_exit() {
  local want=$1 pattern=$2 got=0
  shift 2
  "$@" > /tmp/expect.out 2> /tmp/expect.err || got=$?
  echo "bench: \$ $* -> exit $got: $(head -c 300 /tmp/expect.err)"
  [ "$got" -eq "$want" ] || fail "$1: exit $got instead of $want ($(head -c 200 /tmp/expect.err))"
  grep -Eq "$pattern" /tmp/expect.err || fail "$1: stderr does not match '$pattern': $(head -c 200 /tmp/expect.err)"
}

# start NAME COMMAND...: runs COMMAND in the background, output in /tmp/NAME.log.
start() {
  local name=$1
  shift
  "$@" > "/tmp/$name.log" 2>&1 &
  bench_pid[$name]=$!
}
running() { kill -0 "${bench_pid[$1]}" 2> /dev/null; }
# wait_socket NAME: waits (up to 20 s) until NAME has opened a socket (a CAN program is listening).
wait_socket() {
  local tries=0
  until ls -l "/proc/${bench_pid[$1]}/fd" 2> /dev/null | grep -q 'socket:'; do
    running "$1" || fail "$1 stopped at start"
    ((++tries <= 200)) || fail "$1 opened no socket within 20 s"
    sleep 0.1
  done
}
# finish NAME: waits for NAME to end by itself; sets `status` to its exit code.
finish() {
  status=0
  wait "${bench_pid[$1]}" || status=$?
}
# stop NAME: SIGTERM, then waits; sets `status` to its exit code.
stop() {
  kill -TERM "${bench_pid[$1]}" 2> /dev/null || true
  finish "$1"
}

vcan_up() {
  ip link add dev "$1" type vcan
  ip link set "$1" up
}
# can_up IF BITRATE: an emulated SJA1000 controller (QEMU kvaser_pci) at BITRATE bit/s.
can_up() {
  ip link set "$1" type can bitrate "$2"
  ip link set "$1" up
}

# --- Counter-input nodes: gyrochard nodes fed by simulated gyro electronics over CAN -------------
# Node A's electronics have address A + 112; tau0 0.01 s, 16 octave taus.
bench_tau0=0.01
bench_gyrochard_args=()  # more gyrochard options for start_nodes (e.g. --report-period 0.25)

# start_nodes REPORT_IF DECODE_IF NODE...: the decoder on DECODE_IF (CSV and JSON lines in /tmp,
# native units), then the gyrochard nodes on REPORT_IF; waits until they are up.
start_nodes() {
  local report_if=$1 decode_if=$2 node
  shift 2
  start decode gyrochar-decode --interface "$decode_if" --rate-unit native --csv /tmp/decoded.csv \
    --jsonl /tmp/decoded.jsonl --view none
  wait_socket decode  # listening before the first report goes out
  for node in "$@"; do
    start "gyrochard-$node" gyrochard --source can-counter --can-interface "$report_if" --node "$node" \
      --counter-node $((node + 112)) --tau0 "$bench_tau0" --octaves 16 "${bench_gyrochard_args[@]}"
  done
  sleep 2
  for node in "$@"; do running "gyrochard-$node" || fail "gyrochard node $node stopped at start"; done
}

# feed_nodes INPUT_IF DURATION_S SPEED NODE...: one gyrochar-sim per node sends DURATION_S of
# counts (seed = node, written to /tmp/counts-NODE.txt) at SPEED times real time; waits for them.
feed_nodes() {
  local input_if=$1 duration_s=$2 speed=$3 node
  shift 3
  for node in "$@"; do
    start "sim-$node" gyrochar-sim --duration "$duration_s" --tau0 "$bench_tau0" --white-angle 2 --arw 0.003 \
      --seed "$node" --can "$input_if" --can-node $((node + 112)) --speed "$speed" --out "/tmp/counts-$node.txt"
  done
  for node in "$@"; do
    finish "sim-$node"
    [ "$status" -eq 0 ] || fail "gyrochar-sim for node $node exited with $status"
    cat "/tmp/sim-$node.log"
  done
}

# stop_nodes NODE...: the decoder first (the report in flight is its last, cut short), then the
# nodes, which must stop cleanly.
stop_nodes() {
  local node
  stop decode
  [ "$status" -eq 0 ] || fail "gyrochar-decode exited with $status"
  for node in "$@"; do
    stop "gyrochard-$node"
    [ "$status" -eq 0 ] || fail "gyrochard node $node exited with $status on SIGTERM"
  done
  tail -n $(($# + 1)) /tmp/decode.log
}

# check_estimates SAMPLES NODE...: each node's last complete report with SAMPLES samples holds
# ADEV and MDEV equal to gyrochar-analyze's on /tmp/counts-NODE.txt (tau0 $bench_tau0).
check_estimates() {
  local samples=$1 node
  shift
  for node in "$@"; do
    gyrochar-analyze --type counts --tau0 "$bench_tau0" --pulse-weight 1arcsec --rate-unit deg/s --stride-factor 8 \
      --format csv "/tmp/counts-$node.txt" > "/tmp/analyzed-$node.csv"
    gyrochar-bench estimates --jsonl /tmp/decoded.jsonl --csv /tmp/decoded.csv --node "$node" --samples "$samples" \
      --analyzed "/tmp/analyzed-$node.csv" || fail "node $node: decoded estimates differ from gyrochar-analyze (above)"
  done
}

# --- GPIO quadrature: gyrochard reading two gpio-sim lines, the bench driver playing them ---------

# gpio_sim_up LINES: a gpio-sim chip with LINES lines (configfs); sets gpio_chip (gpiochipN) and
# gpio_sim_dir (its sysfs folder with sim_gpio<N>/pull).
gpio_sim_up() {
  local cfg=/sys/kernel/config/gpio-sim/bench
  mkdir "$cfg" "$cfg/bank0"
  echo "$1" > "$cfg/bank0/num_lines"
  echo 1 > "$cfg/live"
  gpio_chip=$(cat "$cfg/bank0/chip_name")
  gpio_sim_dir=/sys/devices/platform/$(cat "$cfg/dev_name")/$gpio_chip
  [ -c "/dev/$gpio_chip" ] || fail "gpio-sim made no /dev/$gpio_chip"
}

# quadrature_node NODE DURATION_S OVERFLOW_EVERY: gyrochard NODE counts quadrature edges on lines
# 0 (A) and 1 (B) of the gpio-sim chip and reports on vcan0 to the decoder; the bench driver plays
# DURATION_S of simulated counts (tau0 $bench_tau0) with an overflow burst every OVERFLOW_EVERY
# intervals (0: none). Leaves the sample stream gyrochard must have counted in /tmp/counts-NODE.txt,
# its length in `samples` and the number of overflow bursts played in `bursts`.
quadrature_node() {
  local node=$1 duration_s=$2 overflow=$3 tries=0
  gyrochar-sim --duration "$duration_s" --tau0 "$bench_tau0" --white-angle 3 --arw 0.003 --seed "$node" \
    --out "/tmp/sim-counts-$node.txt"
  start decode gyrochar-decode --interface vcan0 --rate-unit native --csv /tmp/decoded.csv \
    --jsonl /tmp/decoded.jsonl --view none
  wait_socket decode
  start player gyrochar-bench quadrature --chip "/dev/$gpio_chip" --sim "$gpio_sim_dir" --line-a 0 --line-b 1 \
    --tau0 "$bench_tau0" --counts "/tmp/sim-counts-$node.txt" --expected "/tmp/counts-$node.txt" \
    --overflow-every "$overflow"
  until grep -q watching /tmp/player.log; do
    running player || fail "the quadrature driver stopped: $(cat /tmp/player.log)"
    ((++tries <= 100)) || fail "the quadrature driver is not ready after 10 s"
    sleep 0.1
  done
  start "gyrochard-$node" gyrochard --source quadrature --gpio-chip "$gpio_chip" --line-a 0 --line-b 1 \
    --can-interface vcan0 --node "$node" --tau0 "$bench_tau0" --octaves 16
  finish player
  cat /tmp/player.log
  [ "$status" -eq 0 ] || fail "the quadrature driver failed (exit $status)"
  running "gyrochard-$node" || fail "gyrochard stopped during the playback"
  samples=$(grep -vc '^#' "/tmp/counts-$node.txt")
  bursts=$(grep -o '[0-9]* overflow bursts' /tmp/player.log | cut -d' ' -f1)
  sleep 3  # the last played interval is closed and reported
  stop_nodes "$node"
}

# --- Process and socket figures -----------------------------------------------------------------

# proc_kib PID KEY: a /proc/PID/status field in KiB (VmRSS, VmHWM, VmSize, ...).
proc_kib() { awk -v key="$2:" '$1 == key { print $2 }' "/proc/$1/status"; }
# cpu_ticks PID: user + system CPU time of PID so far, in clock ticks (1/100 s).
cpu_ticks() { awk '{ sub(/^.*\) /, ""); print $12 + $13 }' "/proc/$1/stat"; }
# minor_faults PID: pages PID has touched for the first time (or again after reclaim) so far.
minor_faults() { awk '{ sub(/^.*\) /, ""); print $8 }' "/proc/$1/stat"; }
# rx_packets IF: frames the interface has carried (vcan: every frame sent on it).
rx_packets() { cat "/sys/class/net/$1/statistics/rx_packets"; }
# socket_drops LOG: the decoder's SO_RXQ_OVFL total from the summary it printed at its end.
socket_drops() { sed -n 's/.*dropped in the socket queue \([0-9]*\).*/\1/p' "$1" | tail -n 1; }
