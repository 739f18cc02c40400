#!/usr/bin/env python3
"""The analyzer's job done with allantools, for toolchain/benchmarks.sh: load a counts file (one
integer per line, '#' comments), then the deviations at the given taus. Prints one line
'allantools: load S s, STAT S s, ..., total S s, taus K' (wall times of this process's steps),
or, when a step fails (memory), the steps done and the error.

    allantools_job.py PEERS_DIR FILE TAU0 STATS TAUS     e.g. ... run.txt 0.01 oadev,mdev,ohdev octave
"""
import sys
import time


def main():
    peers, path, tau0, stats, taus = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4], sys.argv[5]
    sys.path.insert(0, peers)
    import numpy as np
    import allantools

    steps = []
    start = time.perf_counter()
    try:
        t = time.perf_counter()
        counts = np.loadtxt(path, comments="#", dtype=np.float64)
        # Phase in pulses: x0 = 0, x_k = sum of the first k counts (what --type counts means). It is
        # formed once here, so allantools does not convert the frequency data again for each stat.
        phase = np.concatenate(([0.0], np.cumsum(counts)))
        del counts
        steps.append(f"load {time.perf_counter() - t:.3f} s")
        n_taus = 0
        for stat in stats.split(","):
            t = time.perf_counter()
            result = getattr(allantools, stat)(phase, rate=1.0 / tau0, data_type="phase", taus=taus)
            n_taus = max(n_taus, len(result[0]))
            steps.append(f"{stat} {time.perf_counter() - t:.3f} s")
        steps.append(f"total {time.perf_counter() - start:.3f} s")
        steps.append(f"taus {n_taus}")
    except MemoryError as e:
        steps.append(f"failed after {time.perf_counter() - start:.1f} s: MemoryError {e}")
    print("allantools: " + ", ".join(steps))


if __name__ == "__main__":
    main()
