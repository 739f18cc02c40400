#!/bin/bash
# gyrochard refuses to start, with the documented exit code and a message naming the problem, when
# a configuration value is bad (2, even when the hardware is missing too: the configuration is
# checked first), the CAN interface does not exist (3) or the GPIO chip of the quadrature source
# does not exist (3). Real kernel: SocketCAN (vcan) and the GPIO character
# device layer, with no GPIO chip registered.
source /bench/lib.sh

vcan_up vcan0

step "bad configuration values: exit 2, the message names the key"
expect_exit 2 '^gyrochard: stride-factor: ' gyrochard --source can-counter --can-interface vcan0 --stride-factor 3
printf '%s\n' 'source = can-counter' 'can-interface = vcan0' 'tau0 = -0.01' > /tmp/bad.conf
expect_exit 2 '^gyrochard: /tmp/bad.conf:3: tau0: ' gyrochard --config /tmp/bad.conf
expect_exit 2 '^gyrochard: node: ' gyrochard --source can-counter --can-interface vcan0 --node 254
expect_exit 2 '^gyrochard: report-period: ' gyrochard --source can-counter --can-interface can7 --report-period 100

step "missing CAN interface: exit 3, the message names the interface"
expect_exit 3 '^gyrochard: can7: No such device' gyrochard --source can-counter --can-interface can7

step "missing GPIO chip for the quadrature source"
[ -z "$(ls /dev/gpiochip* 2> /dev/null)" ] || fail "a GPIO chip exists before the scenario made one"
status=0
gyrochard --source quadrature --gpio-chip gpiochip5 --can-interface vcan0 2> /tmp/quadrature.err || status=$?
echo "bench: quadrature on gpiochip5 -> exit $status: $(cat /tmp/quadrature.err)"
if [ "$status" -eq 2 ] && grep -q 'only can-counter input is in this build' /tmp/quadrature.err; then
  pass "bad values exit 2 naming the key, missing can7 exits 3; this gyrochard has no quadrature source (exit 2)"
fi
[ "$status" -eq 3 ] || fail "quadrature without its GPIO chip: exit $status instead of 3"
grep -q 'gpiochip5' /tmp/quadrature.err || fail "quadrature without its GPIO chip: the message does not name gpiochip5"
pass "bad values exit 2 naming the key, missing can7 exits 3, missing gpiochip5 exits 3"
