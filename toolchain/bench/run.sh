#!/usr/bin/env bash
# Boots the bench (toolchain/bench/build.sh assembles it) under QEMU and runs one scenario:
#   toolchain/bench/run.sh SCENARIO [--can] [--timeout S]
# SCENARIO is tests/bench/scenarios/SCENARIO.sh. --can adds two emulated SJA1000 controllers
# (kvaser_pci, can0 and can1) on one emulated CAN bus; a scenario whose file has the line
# `# bench: can-controllers` gets them without the option; one with `# bench: timeout S` gets S
# seconds instead of the default 180. The serial console goes to
# build/bench/logs/SCENARIO.log and is printed when the scenario fails.
# Exit code: 0 PASS, 1 FAIL (or no verdict: crash, time limit), 2 usage, 77 bench not assembled.
set -euo pipefail
cd "$(dirname "$0")/../.."

out=build/bench
usage() { echo "usage: toolchain/bench/run.sh SCENARIO [--can] [--timeout S]" >&2; exit 2; }
say() { echo "bench/run.sh: $*" >&2; }

scenario=""
can=no
limit_s=180
limit_given=no
while (($#)); do
  case "$1" in
    --can) can=yes ;;
    --timeout) [ $# -ge 2 ] || usage; limit_s=$2; limit_given=yes; shift ;;
    -*) usage ;;
    *) [ -z "$scenario" ] || usage; scenario=$1 ;;
  esac
  shift
done
[ -n "$scenario" ] || usage
script=tests/bench/scenarios/$scenario.sh
if [ ! -f "$script" ]; then
  say "no scenario '$scenario'; there are: $(cd tests/bench/scenarios && ls -- *.sh | sed 's/\.sh$//' | tr '\n' ' ')"
  exit 2
fi
grep -qx '# bench: can-controllers' "$script" && can=yes
# A scenario longer than the default limit says so: `# bench: timeout S` (--timeout overrides it).
if [ "$limit_given" = no ]; then
  own_limit=$(sed -n 's/^# bench: timeout \([0-9][0-9]*\)$/\1/p' "$script" | head -n 1)
  [ -z "$own_limit" ] || limit_s=$own_limit
fi

kernel=$out/kernel/vmlinuz
initramfs=$out/initramfs.cpio.gz
for f in "$kernel" "$initramfs"; do
  [ -s "$f" ] || { say "$f is missing: assemble the bench with toolchain/bench/build.sh"; exit 77; }
done
command -v qemu-system-x86_64 > /dev/null || { say "qemu-system-x86_64 is missing: toolchain/bench/build.sh installs it"; exit 77; }
if [ -n "$(find tests/bench/scenarios tests/bench/lib.sh toolchain/bench/init -newer "$initramfs" -print -quit)" ]; then
  say "warning: scenarios or init changed since $initramfs was assembled: run toolchain/bench/build.sh"
fi

mkdir -p "$out/logs"
log=$out/logs/$scenario.log
devices=()
if [ "$can" = yes ]; then
  # Two controllers on one emulated bus: what can0 sends arrives at can1 and the other way round.
  devices=(-object can-bus,id=canbus0 -device kvaser_pci,canbus=canbus0 -device kvaser_pci,canbus=canbus0)
fi
# The guest stops the scenario itself 20 s before QEMU is stopped, so a slow scenario still gets a
# verdict line and its logs.
guest_limit_s=$((limit_s > 40 ? limit_s - 20 : limit_s))
say "$scenario: booting (QEMU, software emulation${devices:+, two SJA1000 controllers}; limit $limit_s s)"
start_s=$(date +%s.%N)
status=0
timeout --kill-after=5 "$limit_s" qemu-system-x86_64 \
  -m 512 -smp 1 -nic none -nographic -no-reboot \
  -kernel "$kernel" -initrd "$initramfs" \
  -append "console=ttyS0 quiet panic=-1 scenario=$scenario bench_timeout=$guest_limit_s" \
  "${devices[@]}" < /dev/null > "$log" 2>&1 || status=$?
elapsed_s=$(echo "$start_s $(date +%s.%N)" | awk '{printf "%.1f", $2 - $1}')

# The firmware's terminal escapes may precede a line: match anywhere in it.
verdict=$(tr -d '\r' < "$log" | grep -ao "BENCH-VERDICT $scenario .*" | tail -n 1 || true)
boot_s=$(tr -d '\r' < "$log" | sed -n 's/.*bench: init started at uptime \([0-9.]*\) s.*/\1/p' | head -n 1)
case "$verdict" in
  "BENCH-VERDICT $scenario PASS"*)
    say "$scenario: PASS in $elapsed_s s (init at ${boot_s:-?} s guest uptime): ${verdict#BENCH-VERDICT "$scenario" PASS }"
    say "serial log: $log"
    exit 0
    ;;
esac
tr -d '\r' < "$log" >&2 || true
if [ -n "$verdict" ]; then
  say "$scenario: FAIL in $elapsed_s s: ${verdict#BENCH-VERDICT "$scenario" FAIL }"
elif [ "$status" -eq 124 ] || [ "$status" -eq 137 ]; then
  say "$scenario: FAIL: no verdict within $limit_s s (QEMU stopped)"
else
  say "$scenario: FAIL: no verdict line (QEMU exit status $status)"
fi
say "serial log: $log"
exit 1
