#!/usr/bin/env python3
"""gyrochar's Python package beside allantools on the same numpy array, in one process: 10^7
frequency values (white plus random-walk FM, seeded), oadev, mdev and ohdev at octave taus, by
gyrochar.analyze (one call: the three statistics with EDF, intervals and noise identification),
by gyrochar.allantools (three calls, allantools' API) and by allantools; then 10^7 integer
pulse counts by gyrochar.analyze (type="counts") and allantools on their phase. Prints the CPU time of
each (time.process_time: every thread of the process) and the ratio, and the peak RSS after each
step (ru_maxrss: the largest so far, so a step's own peak shows only when it is the largest).
With `mtotdev` instead of N: MTOTDEV of 10^5 phase points (random walk plus white, seeded) at
every octave tau by gyrochar.allantools, against allantools at the octave taus up to 32 only (its
whole octave list would take hours: its cost per tau grows with m); the ratio printed is allantools'
CPU on those six taus over gyrochar's on all of them, a lower bound of the whole job's.

    PYTHONPATH=build/host/python python3 toolchain/python_benchmark.py ../shared/peers/allantools [N|mtotdev]
"""
import resource
import sys
import time

import numpy as np


def peak_mib():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def timed(what, call):
    start = time.process_time()
    call()
    cpu = time.process_time() - start
    print(f"{what:<34} CPU {cpu:8.2f} s   peak RSS so far {peak_mib():7.0f} MiB", flush=True)
    return cpu


def mtotdev_job(allantools, gat):
    rng = np.random.default_rng(22)
    x = np.cumsum(rng.normal(0, 1, 10**5)) + rng.normal(0, 1, 10**5)
    ours = timed("gyrochar.allantools.mtotdev, octave", lambda: gat.mtotdev(x, rate=1.0, taus="octave"))
    taus = gat.mtotdev(x, rate=1.0, taus="octave")[0]
    short = taus[taus <= 32]
    theirs = timed(f"allantools.mtotdev, taus {short.min():.0f}..{short.max():.0f}",
                   lambda: allantools.mtotdev(x, rate=1.0, taus=short))
    print(f"{len(taus)} taus by gyrochar, {len(short)} by allantools; CPU-time ratio allantools (its "
          f"{len(short)} taus) / gyrochar (all {len(taus)}): {theirs / ours:.0f}", flush=True)


def main():
    sys.path.insert(0, sys.argv[1])
    import allantools
    import gyrochar
    import gyrochar.allantools as gat

    if len(sys.argv) > 2 and sys.argv[2] == "mtotdev":
        mtotdev_job(allantools, gat)
        return
    n = int(float(sys.argv[2])) if len(sys.argv) > 2 else 10**7

    rng = np.random.default_rng(21)
    y = rng.normal(0, 1e-11, n) + np.cumsum(rng.normal(0, 1e-14, n))
    print(f"{n} frequency values, {y.nbytes >> 20} MiB as float64; peak RSS {peak_mib():.0f} MiB", flush=True)
    stats = ("oadev", "mdev", "ohdev")
    ours = timed("gyrochar.analyze (one call)", lambda: gyrochar.analyze(y, 1.0, type="freq", stats=stats))
    api = timed("gyrochar.allantools (3 calls)",
                lambda: [getattr(gat, s)(y, rate=1.0, data_type="freq", taus="octave") for s in stats])
    theirs = timed("allantools (3 calls)",
                   lambda: [getattr(allantools, s)(y, rate=1.0, data_type="freq", taus="octave") for s in stats])
    print(f"CPU-time ratio allantools / gyrochar.analyze: {theirs / ours:.1f}; "
          f"allantools / gyrochar.allantools: {theirs / api:.1f}", flush=True)
    # Integer pulse counts (int64, read in place): the analyzer's batch kernel; allantools on the
    # phase they make (the cumulative sum, formed once outside the timing).
    counts = rng.poisson(40, n).astype(np.int64)
    phase = np.concatenate([[0.0], np.cumsum(counts, dtype=float)])
    ours = timed("gyrochar.analyze, counts", lambda: gyrochar.analyze(counts, 1.0, type="counts",
                                                                       pulse_weight="1arcsec", stats=stats))
    theirs = timed("allantools, their phase (3 calls)",
                   lambda: [getattr(allantools, s)(phase, rate=1.0, data_type="phase", taus="octave") for s in stats])
    print(f"CPU-time ratio allantools / gyrochar.analyze on counts: {theirs / ours:.1f}")


if __name__ == "__main__":
    main()
