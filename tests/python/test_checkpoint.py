# Characterizer.checkpoint() and restore(): the core characterizer's own checkpoint format (the
# bytes the board writes), taken up bit for bit, refused with the core's reason when truncated,
# corrupted or written under other arguments, and then nothing changes.
import re

import numpy as np
import pytest

import gyrochar

FIELDS = ("tau", "m", "n", "dev", "ci_low", "ci_high", "alpha", "edf", "stride")
STATS = ("oadev", "mdev", "ohdev")


def assert_same(a, b):
    assert a.n_values == b.n_values and list(a.stats) == list(b.stats)
    for stat in a.stats:
        for field in FIELDS:
            np.testing.assert_array_equal(getattr(a.stats[stat], field), getattr(b.stats[stat], field),
                                          err_msg="%s %s" % (stat, field))
        assert list(a.stats[stat].noise_id) == list(b.stats[stat].noise_id)


def counts(n, seed=3):
    rng = np.random.default_rng(seed)
    return np.rint(40 + rng.normal(0, 3, n) + np.cumsum(rng.normal(0, 0.05, n))).astype(np.int64)


def make(**kwargs):
    args = dict(type="counts", pulse_weight="1arcsec", stats=STATS, stride_factor=64)
    args.update(kwargs)
    return gyrochar.Characterizer(0.01, **args)


@pytest.mark.parametrize("kwargs, values", [
    (dict(), counts(20000)),
    (dict(type="phase", pulse_weight=None), np.cumsum(np.random.default_rng(5).normal(size=20000))),
    (dict(type="freq", pulse_weight=None, unit="deg/s", stride_factor="full"),
     np.random.default_rng(6).normal(size=20000)),
])
def test_round_trip_gives_the_uninterrupted_estimates_bit_for_bit(kwargs, values):
    # Oracle: the characterizer that wrote the checkpoint, read out at the same point.
    source = make(**kwargs)
    source.add(values)
    data = source.checkpoint()
    assert isinstance(data, bytes) and data[:4] == b"GYRC"  # the core's magic number, native order (little endian)
    restored = make(**kwargs)
    restored.restore(data)
    assert restored.values == source.values == len(values)
    assert_same(restored.estimates(), source.estimates())
    again = make(**kwargs)  # a restored characterizer's checkpoint (one gap more in its run state) restores too
    again.restore(restored.checkpoint())
    assert_same(again.estimates(), source.estimates())


def test_restore_is_a_gap_as_on_the_board():
    # After a restore the next value starts a new segment (characterizer.hpp): no OADEV term spans
    # it. Oracle: the overlapping term count of each segment, N_segment - 2m phase points (SP 1065).
    first, second = counts(5000, 7), counts(3000, 8)
    source = make(stats=("oadev",))
    source.add(first)
    restored = make(stats=("oadev",))
    restored.restore(source.checkpoint())
    restored.add(second)
    est = restored.estimates().oadev
    checked = 0
    for m, n, stride in zip(est.m, est.n, est.stride):
        if stride != 1:  # above S = 64 the terms are strided
            continue
        # counts: the first segment has 5001 phase points, the second the 3000 increments' ends
        # plus its start point.
        assert n == max(0, 5001 - 2 * m) + max(0, 3001 - 2 * m), m
        checked += 1
    assert checked == 7  # m = 1 .. 64
    assert restored.values == 8000


def test_continued_restores_agree():
    # Two characterizers restored from the same bytes and fed the same values stay equal.
    source = make()
    source.add(counts(4000))
    data = source.checkpoint()
    a, b = make(), make()
    a.restore(data)
    b.restore(data)
    more = counts(6000, 9)
    a.add(more)
    for i in range(0, len(more), 777):
        b.add(more[i:i + 777])
    assert_same(a.estimates(), b.estimates())


@pytest.mark.parametrize("damage, reason", [
    (lambda d: d[:len(d) // 2], "truncated"),
    (lambda d: d[:3], "truncated"),
    (lambda d: b"", "truncated"),
    (lambda d: d[:100] + bytes([d[100] ^ 0x10]) + d[101:], "CRC mismatch (corrupted)"),
    (lambda d: d[:-1] + bytes([d[-1] ^ 0x01]), "CRC mismatch (corrupted)"),
    (lambda d: b"XXXX" + d[4:], "not a gyrochar checkpoint"),
    (lambda d: d[:4] + bytes([d[4] ^ 0xFF]) + d[5:], "written by another checkpoint format version"),
])
def test_damaged_bytes_are_refused_and_change_nothing(damage, reason):
    source = make()
    source.add(counts(10000))
    data = source.checkpoint()
    target = make()
    target.add(counts(3000, 11))
    before = target.estimates()
    with pytest.raises(ValueError, match=re.escape("checkpoint refused: " + reason)):
        target.restore(damage(data))
    assert target.values == 3000
    assert_same(target.estimates(), before)
    assert target.checkpoint() != data


@pytest.mark.parametrize("other", [
    dict(stride_factor=128),                       # another stride factor: the core's header
    dict(taus=[1, 2, 4, 8]),                       # other taus
    dict(pulse_weight="2arcsec"),                  # other units: the fingerprint in the tag
    dict(type="freq", pulse_weight=None),          # another arithmetic (float, not exact counts)
])
def test_other_arguments_are_refused(other):
    source = make()
    source.add(counts(2000))
    target = make(**other)
    with pytest.raises(ValueError, match="checkpoint refused: written under another configuration"):
        target.restore(source.checkpoint())
    assert target.values == 0


def test_phase_and_freq_do_not_take_each_others_checkpoints():
    # Both float arithmetic with the same taus: the fingerprint (type, tau0, units) tells them apart.
    phase = gyrochar.Characterizer(1.0, type="phase", stride_factor=8)
    phase.add(np.arange(100.0))
    freq = gyrochar.Characterizer(1.0, type="freq", stride_factor=8)
    with pytest.raises(ValueError, match="another configuration"):
        freq.restore(phase.checkpoint())
    other_tau0 = gyrochar.Characterizer(2.0, type="phase", stride_factor=8)
    with pytest.raises(ValueError, match="another configuration"):
        other_tau0.restore(phase.checkpoint())


def test_what_a_checkpoint_cannot_carry():
    total = gyrochar.Characterizer(1.0, type="phase", stats=("oadev", "totdev"), stride_factor=8)
    total.add(np.arange(100.0))
    with pytest.raises(ValueError, match="not with the total family"):
        total.checkpoint()
    with pytest.raises(TypeError, match="a checkpoint is bytes"):
        make().restore("GYRC")
