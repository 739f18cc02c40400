# gyrochar.allantools against allantools itself (the peer beside the checkout,
# ../shared/peers/allantools: the oracle for taus, ns and the errs convention, and for the
# deviations within 1e-10 relative where both follow SP 1065 without bias corrections). Skipped,
# saying why, when the peer or its scipy is absent (a fresh clone has no ../shared).
import os
import pathlib
import sys

import numpy as np
import pytest

from conftest import SOURCE_DIR, load

PEER = pathlib.Path(os.environ.get("GYROCHAR_ALLANTOOLS", SOURCE_DIR.parent / "shared" / "peers" / "allantools"))
if not (PEER / "allantools" / "__init__.py").is_file():
    pytest.skip(f"allantools peer not found at {PEER} (../shared/peers/allantools beside the checkout)",
                allow_module_level=True)
sys.path.insert(0, str(PEER))
try:
    import allantools as peer
except ImportError as e:  # allantools needs scipy (Debian python3-scipy)
    pytest.skip(f"allantools at {PEER} does not import: {e}", allow_module_level=True)

import gyrochar
import gyrochar.allantools as ours

# Functions compared with allantools number for number: taus, ns, devs (1e-10 relative), errs.
SAME = ["adev", "oadev", "mdev", "tdev", "hdev", "ohdev"]
SETS = [
    ("phasedat/PHASE.DAT", "phase", 1.0, None),
    ("nbs14/nbs14_1000point_freq.txt", "freq", 1.0, None),
    ("ocxo/ocxo_frequency.txt", "freq", 1.0, lambda f: (f - 1e7) / 1e7),
    ("Keysight53230A_ti_noise_floor/tic_phase.txt", "phase", 1.0, None),
]


def reference(data_dir, name, convert):
    values = load(data_dir / name)
    return convert(values) if convert else values


def assert_same(got, want, rtol=1e-10):
    taus, devs, errs, ns = got
    np.testing.assert_array_equal(taus, want[0])
    np.testing.assert_array_equal(ns, want[3])
    assert ns.dtype == want[3].dtype
    np.testing.assert_allclose(devs, want[1], rtol=rtol, atol=0)
    np.testing.assert_allclose(errs, want[2], rtol=rtol, atol=0)


@pytest.mark.parametrize("taus", [None, "octave", "decade", "list"])
@pytest.mark.parametrize("function", SAME)
@pytest.mark.parametrize("case", SETS, ids=[s[0].split("/")[0] for s in SETS])
def test_allan_family_matches_allantools(data_dir, case, function, taus):
    name, data_type, rate, convert = case
    values = reference(data_dir, name, convert)
    if taus == "list":
        taus = np.array([1.0, 3.0, 7.0, 10.0, 33.0, 100.0, 250.0])
    want = getattr(peer, function)(values, rate=rate, data_type=data_type, taus=taus)
    got = getattr(ours, function)(values, rate=rate, data_type=data_type, taus=taus)
    assert_same(got, want)


@pytest.mark.parametrize("function", SAME)
def test_all_taus_match_allantools(data_dir, function):
    values = load(data_dir / "nbs14" / "nbs14_1000point_freq.txt")[:300]
    for data_type in ("phase", "freq"):
        want = getattr(peer, function)(values, rate=2.0, data_type=data_type, taus="all")
        got = getattr(ours, function)(values, rate=2.0, data_type=data_type, taus="all")
        assert_same(got, want)


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="data_type"):
        ours.oadev(np.arange(10.0), data_type="phase_s")
    with pytest.raises(ValueError, match="rate"):
        ours.oadev(np.arange(10.0), rate=0)
    with pytest.raises(ValueError, match="taus must be"):
        ours.oadev(np.arange(10.0), taus="octaves")


# The total family: allantools' taus, ns and devs where both follow Stable32 (white noise, where
# no bias correction applies); where allantools departs from Stable32 (docs/python.md) the rows
# it computes beyond Stable32's limits are left out and the bias corrections differ.
TOTAL_SETS = [("phasedat/PHASE.DAT", "phase"), ("nbs14/nbs14_1000point_freq.txt", "freq")]
TOTAL_TAU_LIST = np.array([1.0, 6.0, 10.0, 12.0, 33.0, 100.0, 250.0])


def total_family_pair(function, values, data_type, taus):
    """allantools' and gyrochar.allantools' (taus, devs, errs, ns) of one total-family function,
    allantools' rows kept within Stable32's limits (docs/python.md): TOTDEV up to m = N/2, Theo1
    from m = 10 (allantools: to N - 1, from 2)."""
    if taus == "list":
        taus = TOTAL_TAU_LIST
    want = getattr(peer, function)(values, rate=1.0, data_type=data_type, taus=taus)
    got = getattr(ours, function)(values, rate=1.0, data_type=data_type, taus=taus)
    n_points = len(values) + (data_type == "freq")
    m = want[0]
    kept = (m <= n_points / 2) if function == "totdev" else (m >= 10) if function == "theo1" else m > 0
    return tuple(w[kept] for w in want), got


@pytest.mark.parametrize("taus", ["octave", "decade", "list"])
@pytest.mark.parametrize("function", ["totdev", "mtotdev", "ttotdev", "theo1"])
@pytest.mark.parametrize("case", TOTAL_SETS, ids=[s[0].split("/")[0] for s in TOTAL_SETS])
def test_total_family_matches_allantools_within_stable32s_limits(data_dir, case, function, taus):
    name, data_type = case
    values = load(data_dir / name)
    want, got = total_family_pair(function, values, data_type, taus)
    assert_same(got, want)


def test_htotdev_carries_stable32s_bias_correction(data_dir):
    # White FM (NBS14 and PHASE.DAT): Stable32 divides HTOTDEV by its bias factor (docs/total.md),
    # allantools does not; the ratio is the same at every tau above m = 1, where both use OHDEV.
    values = load(data_dir / "phasedat" / "PHASE.DAT")
    want = peer.htotdev(values, rate=1.0, data_type="phase", taus="octave")
    got = ours.htotdev(values, rate=1.0, data_type="phase", taus="octave")
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[3], want[3])
    np.testing.assert_allclose(got[1][0], want[1][0], rtol=1e-10)
    ratio = got[1][1:] / want[1][1:]
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-10)
    assert abs(ratio[0] - 1) > 1e-3


# The two long sets (the OCXO's frequency and the time-interval counter's floor). allantools'
# total family costs O(N m) Python steps per tau, and cuts are needed to keep the suite fast
# (measured with allantools 2024.06 on one core: totdev 0.03 s on the whole counter set; mtotdev,
# ttotdev and htotdev about 1.8 s each at octave taus on 1 024 values and 7 s at the three taus
# 1, 3, 10 s on the counter's 55 688; theo1 3.5 s at octave taus on 4 096 values). So totdev is
# compared on the whole sets, theo1 on the first 2 048 values and mtotdev, ttotdev and htotdev on
# the first 1 024 (octave and decade taus, and a tau list up to a third of the points).
LONG_SETS = [
    ("ocxo/ocxo_frequency.txt", "freq", lambda f: (f - 1e7) / 1e7),
    ("Keysight53230A_ti_noise_floor/tic_phase.txt", "phase", None),
]
LONG_CUTS = {"totdev": None, "theo1": 2048, "mtotdev": 1024, "ttotdev": 1024, "htotdev": 1024}


def stable32_bias_factor(function, m, n_points, alpha):
    """Stable32's bias correction of the deviation (docs/total.md): what gyrochar divides
    allantools' deviation by at the noise gyrochar identifies (alpha) at m."""
    if function == "totdev":  # TOTVAR / (1 - a tau / T), T the record's length
        a = {-1: 1 / (3 * np.log(2)), -2: 0.75}.get(alpha, 0.0)
        return np.sqrt(1 - a * m / (n_points - 1))
    if function == "htotdev" and m >= 2:  # HTOTVAR / (1 + a)
        return np.sqrt(1 + {0: -0.005, -1: -0.149, -2: -0.229, -3: -0.283, -4: -0.321}.get(alpha, 0.0))
    return 1.0


@pytest.mark.parametrize("taus", ["octave", "decade", "list"])
@pytest.mark.parametrize("function", list(LONG_CUTS))
@pytest.mark.parametrize("case", LONG_SETS, ids=[s[0].split("/")[0] for s in LONG_SETS])
def test_total_family_matches_allantools_on_the_long_sets(data_dir, case, function, taus):
    name, data_type, convert = case
    values = reference(data_dir, name, convert)[:LONG_CUTS[function]]
    want, got = total_family_pair(function, values, data_type, taus)
    np.testing.assert_array_equal(got[0], want[0])
    # The noise gyrochar identifies at each tau, for Stable32's bias corrections of totdev and htotdev.
    stride = ours._overlapping_stride(int(got[0][-1]))
    r = gyrochar.analyze(values, 1.0, type=data_type, stats=(function,), taus=got[0].astype(np.int64),
                         stride_factor=stride, total_stride_factor="exact").stats[function]
    alpha = r.alpha[np.isin(r.m, got[0])]
    n_points = len(values) + (data_type == "freq")
    factor = np.array([stable32_bias_factor(function, mi, n_points, a) for mi, a in zip(got[0], alpha)])
    assert_same(got, (want[0], want[1] / factor, want[2] / factor, want[3]))
