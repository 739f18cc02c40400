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
