#!/usr/bin/env python3
"""allantools on the cut of a record (a counts file of its first CUT samples), for the RLG job of
toolchain/total_benchmarks.sh (allantools cannot hold or finish the whole record): each statistic
at the octave taus of the cut, one tau at a time under a time limit of LIMIT seconds, and its time
extrapolated to the octave taus of the whole record (WHOLE samples) from its time per term over
the taus it finished. Once a tau runs out of time, the statistic's longer taus are not run but
extrapolated too. Prints a Markdown table and a summary line.

    allantools_cut.py PEERS_DIR CUT_FILE TAU0 CUT WHOLE LIMIT STATS   e.g. ... 0.001 1000000 432000000 60 oadev,mdev

The work of a tau (allantools' time is about proportional to it): the Allan family and TOTDEV one
vectorized pass over the n phase points; MTOTDEV 6m terms for each of n - 3m + 1 sub-sequences;
Theo1 m/2 terms for each of n - m starts.
"""
import signal
import sys
import time


def work(stat, n, m):
    if stat == "mtotdev":
        return (n - 3 * m + 1) * 6.0 * m
    if stat == "theo1":
        return (n - m) * m / 2.0
    return float(n)


def octave(stat, n):
    """The octave m of a record of n phase points, as the analyzer's rows take them."""
    last = {"oadev": (n - 1) // 2, "totdev": (n - 1) // 2, "theo1": n - 1}.get(stat, (n - 1) // 3)
    m = 2 if stat == "theo1" else 1
    out = []
    while m <= last:
        out.append(m)
        m *= 2
    return out


class OutOfTime(Exception):
    pass


def on_alarm(signum, frame):
    raise OutOfTime()


def main():
    peers, path, tau0, cut, whole, limit, stats = sys.argv[1:8]
    tau0, cut, whole, limit = float(tau0), int(cut), int(whole), int(limit)
    sys.path.insert(0, peers)
    import numpy as np
    import allantools

    counts = np.loadtxt(path, comments="#", dtype=np.float64)
    if len(counts) != cut:
        sys.exit(f"allantools_cut.py: {path} holds {len(counts)} samples, not the cut's {cut}")
    phase = np.concatenate(([0.0], np.cumsum(counts)))  # what --type counts means, in pulses
    n, n_whole = len(phase), whole + 1
    signal.signal(signal.SIGALRM, on_alarm)
    print("| stat | taus run on the cut | allantools on the cut (s) | per term (ns) | the whole record, extrapolated (s) |")
    print("|---|---:|---:|---:|---:|")
    total_cut, total_whole = 0.0, 0.0
    for stat in stats.split(","):
        f = getattr(allantools, stat)
        done, spent, worked, per_term, stopped = 0, 0.0, 0.0, None, False
        taus = octave(stat, n)
        for m in taus:
            signal.alarm(limit)
            t = time.perf_counter()
            try:
                f(phase, rate=1.0 / tau0, data_type="phase", taus=[m * tau0])
            except OutOfTime:
                stopped = True
                break
            finally:
                signal.alarm(0)
            dt = time.perf_counter() - t
            done, spent, worked = done + 1, spent + dt, worked + work(stat, n, m)
            per_term = spent / worked
        if per_term is None:
            print(f"| {stat} | 0 of {len(taus)} (the first over {limit} s) | > {limit} | - | - |")
            continue
        rest_cut = sum(work(stat, n, m) for m in taus[done:]) * per_term
        extrapolated = sum(work(stat, n_whole, m) for m in octave(stat, n_whole)) * per_term
        total_cut += spent + rest_cut
        total_whole += extrapolated
        note = f" (the next over {limit} s)" if stopped else ""
        print(f"| {stat} | {done} of {len(taus)}{note} | {spent:.2f}"
              f"{f' + {rest_cut:.0f} extrapolated' if rest_cut > 0 else ''} | {per_term * 1e9:.3g} | {extrapolated:.3g} |")
    print()
    print(f"allantools on the cut ({cut} samples), every octave tau, run and extrapolated: {total_cut:.0f} s "
          f"({total_cut / 3600:.1f} h); on the whole record ({whole} samples), extrapolated: {total_whole:.3g} s "
          f"({total_whole / 3600:.3g} h).")


if __name__ == "__main__":
    main()
