#!/usr/bin/env python3
"""The analyzer's job done with allantools, for toolchain/benchmarks.sh: load a counts file (one
integer per line, '#' comments), then the deviations at the given taus. Prints, step by step on
one line, 'allantools: load S s, STAT S s (K taus), ..., total S s' (wall times of each step), so
that a run stopped by a time limit shows how far it got; a step that runs out of memory ends the
line with the error.

    allantools_job.py PEERS_DIR FILE TAU0 STATS TAUS     e.g. ... run.txt 0.01 oadev,mdev,ohdev octave
"""
import sys
import time


def say(text):
    print(text, end="", flush=True)


def main():
    peers, path, tau0, stats, taus = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4], sys.argv[5]
    sys.path.insert(0, peers)
    import numpy as np
    import allantools

    start = time.perf_counter()
    say("allantools:")
    try:
        t = time.perf_counter()
        counts = np.loadtxt(path, comments="#", dtype=np.float64)
        # Phase in pulses: x0 = 0, x_k = sum of the first k counts (what --type counts means). It is
        # formed once here, so allantools does not convert the frequency data again for each stat.
        phase = np.concatenate(([0.0], np.cumsum(counts)))
        del counts
        say(f" load {time.perf_counter() - t:.2f} s")
        for stat in stats.split(","):
            t = time.perf_counter()
            result = getattr(allantools, stat)(phase, rate=1.0 / tau0, data_type="phase", taus=taus)
            say(f", {stat} {time.perf_counter() - t:.2f} s ({len(result[0])} taus)")
        say(f", total {time.perf_counter() - start:.2f} s\n")
    except MemoryError:
        say(f", out of memory after {time.perf_counter() - start:.1f} s\n")


if __name__ == "__main__":
    main()
