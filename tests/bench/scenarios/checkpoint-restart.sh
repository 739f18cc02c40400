#!/bin/bash
# Checkpoints on the real kernel: gyrochard --checkpoint in a tmpfs folder (every 2 s), fed by its
# simulated gyro electronics in real time, is killed with SIGKILL mid-run and started again; later
# stopped with SIGTERM; then one byte of its checkpoint is flipped and it is started once more.
# Verdict: the second run says it resumed from the checkpoint and its first reports carry at least
# the samples it resumed with; SIGTERM stops it with exit 0 and a checkpoint written; the decoder
# saw each start as a restart (session 0 -> 1 -> 2), with no report lost or rejected; the
# corrupted checkpoint gives the warning (CRC mismatch) and is kept aside as .bad; every run's
# reports arrive.
source /bench/lib.sh

node=54
dir=/run/gyrochar
ckpt=$dir/node.ckpt

vcan_up vcan0
mkdir -p "$dir"
mount -t tmpfs -o size=4m gyrochar "$dir"
start decode gyrochar-decode --interface vcan0 --rate-unit native --jsonl /tmp/decoded.jsonl --view none
wait_socket decode
( feed_nodes vcan0 40 1 "$node" ) > /tmp/feed.log 2>&1 &
feeder=$!
board() {  # NAME: gyrochard with the checkpoint, output in /tmp/NAME.log
  start "$1" gyrochard --source can-counter --can-interface vcan0 --node "$node" --counter-node $((node + 112)) \
    --tau0 "$bench_tau0" --octaves 16 --checkpoint "$ckpt" --checkpoint-period 2
}
reports() { grep -c '"type":"report"' /tmp/decoded.jsonl || true; }

step "run 1: gyrochard with --checkpoint $ckpt (tmpfs), SIGKILL after 10 s"
board run1
sleep 10
[ -s "$ckpt" ] || fail "no checkpoint written within 10 s: $(ls -l "$dir")"
kill -KILL "${bench_pid[run1]}"
finish run1
[ "$status" -eq 137 ] || fail "run 1 ended with $status, not by SIGKILL"
cat /tmp/run1.log

step "run 2: started again on the same checkpoint"
board run2
sleep 8
running run2 || fail "run 2 stopped: $(cat /tmp/run2.log)"
resumed=$(sed -n 's/.*resumed from .*: \([0-9]*\) samples.*/\1/p' /tmp/run2.log)
[ -n "$resumed" ] && [ "$resumed" -gt 0 ] || fail "run 2 did not say it resumed from the checkpoint: $(cat /tmp/run2.log)"
stop run2
cat /tmp/run2.log
[ "$status" -eq 0 ] || fail "run 2 exited with $status on SIGTERM"
grep -q 'checkpoint written' /tmp/run2.log || fail "run 2 wrote no checkpoint when stopped"

step "run 3: one byte of the checkpoint flipped"
size=$(stat -c %s "$ckpt")
offset=$((size / 2))
byte=$(od -An -tu1 -j "$offset" -N1 "$ckpt" | tr -d ' ')
printf "$(printf '\\%03o' $((byte ^ 0x20)))" | dd of="$ckpt" bs=1 seek="$offset" conv=notrunc 2> /dev/null
[ "$(od -An -tu1 -j "$offset" -N1 "$ckpt" | tr -d ' ')" -ne "$byte" ] || fail "the byte at $offset was not flipped"
board run3
sleep 6
running run3 || fail "run 3 stopped: $(cat /tmp/run3.log)"
cat /tmp/run3.log
grep -q "checkpoint $ckpt not used: .*; starting fresh, the file is kept as $ckpt.bad" /tmp/run3.log ||
  fail "run 3 gave no warning about the corrupted checkpoint: $(cat /tmp/run3.log)"
[ -s "$ckpt.bad" ] || fail "the corrupted checkpoint was not kept as $ckpt.bad: $(ls -l "$dir")"
why=$(sed -n 's/.* not used: \(.*\); starting fresh.*/\1/p' /tmp/run3.log)
wait "$feeder" || fail "the gyro electronics failed: $(cat /tmp/feed.log)"
stop run3
[ "$status" -eq 0 ] || fail "run 3 exited with $status on SIGTERM"
stop decode
[ "$status" -eq 0 ] || fail "gyrochar-decode exited with $status"
tail -n 2 /tmp/decode.log

step "the decoder: two restarts, sessions 0, 1, 2"
grep '"event":"restart"' /tmp/decoded.jsonl || true
restarts=$(grep -c '"event":"restart"' /tmp/decoded.jsonl || true)
[ "$restarts" -eq 2 ] || fail "the decoder saw $restarts restarts, not 2"
last=$(grep '"type":"report"' /tmp/decoded.jsonl | tail -n 1)
for key in reports_lost duplicates; do
  [ "$(grep -o "\"$key\":[0-9]*" <<< "$last" | cut -d: -f2)" -eq 0 ] || fail "$key in the last report: $last"
done
for session in 0 1 2; do
  n=$(grep '"type":"report"' /tmp/decoded.jsonl | grep -c "\"session\":$session," || true)
  [ "$n" -ge 3 ] || fail "session $session has $n reports"
done
first1=$(awk '/"type":"report"/ && /"session":1,/ { print; exit }' /tmp/decoded.jsonl | grep -o '"sample_count":[0-9]*' | cut -d: -f2)
[ "$first1" -ge "$resumed" ] || fail "run 2's first report has $first1 samples, fewer than the $resumed it resumed with"
pass "SIGKILL, then resumed with $resumed samples (first report $first1); SIGTERM wrote the checkpoint; a flipped byte: '$why', kept as .bad; decoder: 2 restarts, sessions 0-2, no report lost"
