"""allantools' functions on gyrochar's engine: `import gyrochar.allantools as allantools`.

Each function takes allantools' arguments (data, rate=1.0, data_type="phase"|"freq", taus=None)
and returns its tuple (taus, devs, errs, ns) of numpy arrays: the taus allantools chooses
(None or "octave": 1, 2, 4, ...; "decade": 1, 2, 4, 10, 20, 40, ...; "all": every m; or an array
of taus in s, rounded to multiples of 1/rate), the rows with more than one term, errs = devs /
sqrt(ns) as allantools (Theo1: devs / sqrt(N - m), as allantools). The deviations are gyrochar-analyze's (gyrochar.analyze); where they depart
from allantools' (Stable32's bias corrections, the total family's terms) docs/python.md lists how.
Phase data are in s, frequency data fractional; TDEV and TTOTDEV come out in s.
"""

import numbers as _numbers

import numpy as _np

from . import analyze as _analyze
from . import _deviations

__all__ = ["adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev", "mtotdev", "ttotdev", "htotdev", "theo1",
           "edf_of"]


def _averaging_factors(n_points, rate, taus, even=False, max_m=None):
    """The averaging factors allantools analyses for `taus` over n_points points, and their taus:
    the keywords' lists (or the taus given, rounded to multiples of 1/rate), each 0 < m < n_points
    and m <= max_m, once each, increasing; only even ones when `even`."""
    if taus is None or (isinstance(taus, list) and len(taus) == 0):
        taus = "octave"
    if isinstance(taus, str):
        if taus == "all":
            m = _np.arange(1, n_points + 1, dtype=float)
        elif taus == "octave":
            m = 2.0 ** _np.arange(0, int(_np.floor(_np.log2(n_points))) + 1)
        elif taus == "decade":
            m = _np.array([f * 10.0 ** k for k in range(int(_np.floor(_np.log10(n_points))) + 1) for f in (1, 2, 4)])
        else:
            raise ValueError("taus must be None, 'octave', 'decade', 'all' or an array of taus in s, not '%s'" % taus)
    else:
        given = _np.asarray(taus, dtype=float)
        if given.ndim != 1 or not _np.all(_np.isfinite(given)):
            raise ValueError("taus must be a one-dimensional array of finite taus in s")
        m = _np.round(given * rate)
    keep = (m > 0) & (m < n_points)
    if max_m is not None:
        keep &= m <= max_m
    m = _np.unique(m[keep]).astype(_np.int64)
    if even:
        m = m[m % 2 == 0]
    return m


def _check(data, rate, data_type):
    if isinstance(rate, bool) or not isinstance(rate, _numbers.Real) or not (rate > 0 and _np.isfinite(rate)):
        raise ValueError("rate must be a positive sample rate in Hz, not %r" % (rate,))
    if data_type not in ("phase", "freq"):
        raise ValueError("data_type must be 'phase' or 'freq', not %r" % (data_type,))
    values = _np.asarray(data, dtype=float)
    if values.ndim != 1:
        raise ValueError("data must be one-dimensional")
    n_points = len(values) + (1 if data_type == "freq" else 0)
    if n_points < 3:
        raise ValueError("%d phase points are too few for any tau" % n_points)
    return values, n_points


def _overlapping_stride(m_max):
    """The stride factor that overlaps every tau up to m_max fully (Stable32's estimators)."""
    stride = 2
    while stride < m_max and stride < 1 << 24:
        stride *= 2
    return stride


def _run(stat, data, rate, data_type, taus, even=False, max_m_of=None, freq_points=False, terms_of_errs=None):
    """(taus, devs, errs, ns) of gyrochar statistic `stat` at allantools' averaging factors."""
    values, n_points = _check(data, rate, data_type)
    n_taus = n_points - 1 if freq_points else n_points  # htotdev: allantools plans on the frequency values
    m = _averaging_factors(n_taus, float(rate), taus, even, None if max_m_of is None else max_m_of(n_taus))
    if len(m) == 0:
        raise ValueError("no tau of %r fits %d phase points" % (taus, n_points))
    stride = _overlapping_stride(m[-1])
    # The deviations alone (no EDF: allantools' errs are devs / sqrt(ns)), only this statistic's sums.
    r = _deviations(values, 1.0 / rate, data_type, stat, m, stride, "exact").stats[stat]
    keep = r.n > 1
    ns = r.n[keep]
    devs = r.dev[keep]
    terms = ns if terms_of_errs is None else terms_of_errs(n_points, r.m[keep])
    return r.m[keep] / float(rate), devs, devs / _np.sqrt(terms), ns.astype(float)  # allantools' ns are floats


def _function(stat, doc, **planning):
    """The allantools function `stat`: (data, rate=1.0, data_type="phase", taus=None) -> (taus, devs,
    errs, ns)."""
    def function(data, rate=1.0, data_type="phase", taus=None):
        return _run(stat, data, rate, data_type, taus, **planning)
    function.__name__ = function.__qualname__ = stat
    function.__doc__ = doc
    return function


adev = _function("adev", "Allan deviation (non-overlapped), as allantools.adev.")
oadev = _function("oadev", "Overlapping Allan deviation, as allantools.oadev.")
mdev = _function("mdev", "Modified Allan deviation, as allantools.mdev.")
tdev = _function("tdev", "Time deviation (s), as allantools.tdev.")
hdev = _function("hdev", "Hadamard deviation (non-overlapped), as allantools.hdev.")
ohdev = _function("ohdev", "Overlapping Hadamard deviation, as allantools.ohdev.")
totdev = _function("totdev", "Total deviation, as allantools.totdev (m up to N/2 as Stable32, with its bias "
                   "corrections where the noise is identified: docs/python.md).")
mtotdev = _function("mtotdev", "Modified total deviation, as allantools.mtotdev (m up to N/3).", max_m_of=lambda n: n / 3.0)
ttotdev = _function("ttotdev", "Time total deviation (s), as allantools.ttotdev (m up to N/3).",
                    max_m_of=lambda n: n / 3.0)
htotdev = _function("htotdev", "Hadamard total deviation, as allantools.htotdev (m up to a third of the frequency "
                    "values; Stable32's bias correction where the noise is identified: docs/python.md).",
                    max_m_of=lambda n: n / 3.0, freq_points=True)
theo1 = _function("theo1", "Theo1, as allantools.theo1 (even m from 10 on: docs/python.md; errs = devs / sqrt(N - m) "
                  "as allantools).", even=True, terms_of_errs=lambda n_points, m: n_points - m)


def edf_of(function, data, rate=1.0, data_type="phase", taus=None, confidence=0.683):
    """The exact EDF and the interval of a function of this module, at the same taus: a tuple
    (taus, edf, ci_low, ci_high) from gyrochar.analyze (NaN where there is none)."""
    stat = getattr(function, "__name__", function)
    if stat not in __all__ or stat == "edf_of":
        raise ValueError("edf_of takes a function of gyrochar.allantools, not %r" % (function,))
    values, n_points = _check(data, rate, data_type)
    taus_out = function(values, rate, data_type, taus)[0]
    m = _np.round(taus_out * rate).astype(_np.int64)
    stride = _overlapping_stride(m[-1])
    r = _analyze(values, 1.0 / rate, type=data_type, stats=(stat,), taus=m, stride_factor=stride,
                 total_stride_factor="exact", confidence=confidence).stats[stat]
    keep = _np.isin(r.m, m)
    return r.m[keep] / float(rate), r.edf[keep], r.ci_low[keep], r.ci_high[keep]
