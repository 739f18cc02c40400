# A KeyboardInterrupt stops a long gyrochar.analyze(): the module checks for pending signals
# between blocks of values while it adds them, and between blocks of taus while it sums a held
# record (taus="all": every m up to N/2, minutes at 10^6 values). No timing is asserted: the test
# fails when analyze() returns (the interrupt then arrives after it) instead of raising.
import os
import signal
import threading

import numpy as np
import pytest

import gyrochar


def interrupted(call, after_s):
    """Runs call() with a SIGINT sent to this process after_s seconds in; returns what it returned
    (a list holding it) or [] when it raised KeyboardInterrupt."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals reach Python's main thread only")
    got = []
    timer = threading.Timer(after_s, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            got.append(call())
            threading.Event().wait(30)  # had call() returned, the interrupt lands here
    finally:
        timer.cancel()
    return got


def test_interrupt_during_the_sums_of_every_tau():
    # 10^6 phase points are added in well under a second; summing their 5 * 10^5 taus takes
    # minutes (docs/python.md): the interrupt comes during the sums, or at the check after adding.
    x = np.cumsum(np.random.default_rng(2).normal(size=1_000_000))
    assert interrupted(lambda: gyrochar.analyze(x, 1.0, stats=("oadev",), taus="all"), 0.5) == []


def test_interrupt_while_adding_values():
    # 2^26 frequency values into a characterizer with decade taus: adding takes seconds, checked
    # every 2^20 values.
    y = np.broadcast_to(np.float64(0.0), (1 << 26,))  # stride 0: no memory, converted block by block
    c = gyrochar.Characterizer(1.0, type="freq", stats=("oadev", "mdev", "ohdev"), taus="decade")
    assert interrupted(lambda: c.add(y), 0.3) == []
    assert 0 < c.values < len(y) and c.values % (1 << 20) == 0  # stopped at a block's end, values kept
