#!/usr/bin/env python3
"""The DBC must not drift from the codec: docs/gyrochar.dbc, loaded with canmatrix, decodes every
frame the C++ codec produced (gyrochar_dbc_frames) to exactly the values the codec decodes.

Checks, for every frame: the candump line parses with python-can (so canplayer and can-utils read the
log), the DBC message is found by PGN whatever the node address, its length equals the frame's, the
set of decoded signals equals the codec's, every value matches (integers exactly, floats to 1e-12
relative), every VAL_ name equals the codec's name, every value lies in the signal's [min|max].
Then, over all frames: every DBC message, signal and VAL_ entry was exercised at least once.

With --demo, the frames are instead those captured from a run of the live system: gyrochar-demo
(the board program's loop on the in-process bus) writes the bus as a candump log, and every frame of
it must decode the same through the DBC and the codec (the coverage check is the synthetic set's).

Usage: test_dbc.py --dbc docs/gyrochar.dbc --frames build/.../gyrochar_dbc_frames [--demo build/.../gyrochar-demo]
Exit status: 0 pass, 1 mismatch (or the program failed), 2 usage.
"""
import argparse
import json
import math
import re
import subprocess
import sys
import tempfile

import can
import canmatrix
import canmatrix.formats

CANDUMP_LINE = re.compile(r"^\(\d+\.\d{6}\) [a-z0-9]+ [0-9A-F]{8}#(?:[0-9A-F]{2}){0,8}$")


def run(program, *args):
    return subprocess.run([program, *args], check=True, capture_output=True, text=True).stdout


def parse_candump(text):
    """Frames of a candump log as python-can reads it (the reader takes a file name)."""
    with tempfile.NamedTemporaryFile("w", suffix=".log") as log:
        log.write(text)
        log.flush()
        return list(can.io.CanutilsLogReader(log.name))


def same_value(actual, expected):
    if isinstance(expected, int):
        return actual == expected
    return math.isclose(float(actual), expected, rel_tol=1e-12, abs_tol=0.0)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dbc", required=True)
    parser.add_argument("--frames", required=True, help="the gyrochar_dbc_frames program")
    parser.add_argument("--demo", help="the gyrochar-demo program: check the frames of a captured run")
    args = parser.parse_args()

    db = canmatrix.formats.loadp_flat(args.dbc)
    if args.demo:
        with tempfile.TemporaryDirectory() as scratch:
            log = f"{scratch}/run.log"
            subprocess.run([args.demo, "--hours", "0.05", "--nodes", "2", "--octaves", "24", "--loss", "0.001",
                            "--view-every", "0", "--csv", f"{scratch}/run.csv", "--plot", "", "--candump", log],
                           check=True, capture_output=True)
            candump = open(log).read()
            expected = json.loads(run(args.frames, "--log", log, "--expected"))
    else:
        candump = run(args.frames)
        expected = json.loads(run(args.frames, "--expected"))
    messages = parse_candump(candump)
    lines = candump.splitlines()

    failures = []
    fail = failures.append
    if not (len(lines) == len(messages) == len(expected)):
        fail(f"counts differ: {len(lines)} candump lines, {len(messages)} parsed, {len(expected)} expected")
    seen_signals = set()  # (message, signal)
    seen_names = set()    # (message, signal, raw value)
    for line, msg, exp in zip(lines, messages, expected):
        where = line
        if line != exp["candump"] or not CANDUMP_LINE.match(line):
            fail(f"{where}: not the expected candump line {exp['candump']}")
            continue
        if not msg.is_extended_id or msg.is_fd:
            fail(f"{where}: python-can reads it as standard or FD")
        frame = db.frame_by_pgn(canmatrix.ArbitrationId(msg.arbitration_id, extended=True).pgn)
        if frame is None:
            fail(f"{where}: no DBC message with this PGN")
            continue
        if frame.size != len(msg.data):
            fail(f"{where}: DBC {frame.name} has {frame.size} bytes, frame has {len(msg.data)}")
            continue
        decoded = db.decode(canmatrix.ArbitrationId(msg.arbitration_id, extended=True), bytes(msg.data))
        want = exp["signals"]
        if set(decoded) != set(want):
            fail(f"{where}: DBC {frame.name} gives signals {sorted(decoded)}, codec {sorted(want)}")
            continue
        for name, value in decoded.items():
            signal = value.signal
            seen_signals.add((frame.name, name))
            phys = value.phys_value
            if not same_value(phys, want[name]):
                fail(f"{where}: {frame.name}.{name} = {phys} by the DBC, {want[name]} by the codec")
            if not (signal.min <= phys <= signal.max):
                fail(f"{where}: {frame.name}.{name} = {phys} outside the DBC range [{signal.min}, {signal.max}]")
            if signal.values:
                seen_names.add((frame.name, name, value.raw_value))
                if name in exp["names"] and value.named_value != exp["names"][name]:
                    fail(f"{where}: {frame.name}.{name} VAL_ name {value.named_value!r}, codec {exp['names'][name]!r}")
        for name in exp["names"]:
            if not decoded[name].signal.values:
                fail(f"{where}: {frame.name}.{name} has no VAL_ table")

    for frame in [] if args.demo else db.frames:
        for signal in frame.signals:
            if (frame.name, signal.name) not in seen_signals:
                fail(f"{frame.name}.{signal.name}: never exercised")
            for raw in signal.values:
                if (frame.name, signal.name, raw) not in seen_names:
                    fail(f"{frame.name}.{signal.name}: VAL_ {raw} {signal.values[raw]!r} never exercised")

    for f in failures:
        print(f"test_dbc: {f}", file=sys.stderr)
    print(f"test_dbc: {len(expected)} frames, {len(seen_signals)} signals, {len(seen_names)} VAL_ entries, "
          f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
