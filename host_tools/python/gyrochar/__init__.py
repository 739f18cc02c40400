"""gyrochar for Python: the Allan-variance family of gyrochar-analyze on numpy arrays.

    import numpy as np, gyrochar
    x = np.cumsum(np.random.default_rng(1).normal(size=100_000))   # random-walk phase
    r = gyrochar.analyze(x, tau0=1.0, type="phase", stats=("oadev", "mdev"))
    print(r.oadev.tau, r.oadev.dev, r.oadev.ci_low, r.oadev.ci_high)

analyze() runs the analyzer's own C++ engine (host_tools/analyze) in process: the same taus, terms,
deviations, EDF, confidence intervals, noise identification and IEEE-952 fit as
`gyrochar-analyze --format json` on the same values. gyrochar.allantools offers allantools'
functions with allantools' arguments and return shape (docs/python.md).
"""

import json as _json
import numbers as _numbers

import numpy as _np

from . import _display
from . import _native

__all__ = ["analyze", "Characterizer", "Analysis", "StatResult", "STATS"]

#: The statistics analyze() computes, by gyrochar-analyze's names.
STATS = ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev", "mtotdev", "ttotdev", "htotdev", "theo1",
         "theoh")

_STAT_FIELDS = ("tau", "m", "n", "dev", "ci_low", "ci_high", "alpha", "edf", "noise_id", "stride")


class StatResult:
    """The rows of one statistic, as numpy arrays of equal length, one entry per tau.

    tau (s), m (averaging factor), n (terms), dev (in `unit`), ci_low and ci_high (the interval at the
    analysis' confidence; NaN where there is none), alpha (identified noise exponent; NaN where not
    identified), edf (NaN where not available), noise_id (how the noise was identified, None where
    it was not), stride (terms every `stride` phase points).
    """

    __slots__ = _STAT_FIELDS + ("stat", "unit")

    def __init__(self, stat, arrays):
        self.stat = stat
        self.unit = arrays["unit"]
        for f in _STAT_FIELDS:
            setattr(self, f, arrays[f])

    def __len__(self):
        return len(self.tau)

    def __repr__(self):
        return "<gyrochar.StatResult %s: %d taus, unit %s>" % (self.stat, len(self), self.unit)

    def to_pandas(self):
        """The rows as a pandas DataFrame, one row per tau: tau, m, n, dev, ci_low, ci_high, alpha,
        edf, noise_id, stride, unit. Needs pandas (ImportError saying so otherwise)."""
        return _display.stat_frame(self)


class Analysis:
    """What analyze() returns: one StatResult per statistic asked for (as attributes and in `stats`),
    n_values, n_phase, stride_factor, units_input (what the values were), and `fit`: the IEEE-952
    fits as gyrochar-analyze's JSON has them (a list of dicts, the recommended one first), or None.
    """

    def __init__(self, raw, tau0, type, confidence):
        self.tau0 = tau0
        self.type = type
        self.confidence = confidence
        self.n_values = raw["n_values"]
        self.n_phase = raw["n_phase"]
        self.stride_factor = raw["stride_factor"]
        self.units_input = raw["units_input"]
        self.stats = {name: StatResult(name, arrays) for name, arrays in raw["stats"].items()}
        self.fit = _json.loads(raw["fit_json"]) if "fit_json" in raw else None

    def __getattr__(self, name):
        stats = self.__dict__.get("stats", {})
        if name in stats:
            return stats[name]
        raise AttributeError("no statistic or attribute '%s' in this analysis (statistics: %s)"
                             % (name, ", ".join(stats) or "none"))

    def to_pandas(self):
        """Every statistic in one long pandas DataFrame: a column `stat`, then the columns of
        StatResult.to_pandas(); rows by statistic (in the order asked), then by tau. One statistic:
        `df[df.stat == "oadev"]`, or `r.oadev.to_pandas()`. Needs pandas."""
        return _display.analysis_frame(self)

    def plot(self, ax=None, stats=None, fit=True):
        """Log-log plot of the deviations with their confidence intervals as error bars, and the
        IEEE-952 model where a fit exists: see gyrochar._display.plot. Returns the matplotlib
        Axes (a new figure's unless `ax` is given). Needs matplotlib."""
        return _display.plot(self, ax=ax, stats=stats, fit=fit)

    def __repr__(self):
        return "<gyrochar.Analysis of %d %s values: %s>" % (self.n_values, self.type, ", ".join(self.stats))


def _power_of_two(value, what, low, high):
    if isinstance(value, bool) or not isinstance(value, _numbers.Integral):
        raise TypeError("%s must be an integer power of two or 'full', not %r" % (what, value))
    if value < low or value > high or value & (value - 1):
        raise ValueError("%s must be a power of two from %d to 2^%d, not %d" % (what, low, high.bit_length() - 1, value))
    return int(value)


def _pulse_weight(pulse_weight):
    """(text, unit) of a pulse weight for the engine, which reads it as gyrochar-analyze's
    --pulse-weight and --pulse-unit: '1.5arcsec' or '1.5 arcsec' as is, (1.5, 'arcsec') as
    ('1.5', 'arcsec'). None: not given."""
    if pulse_weight is None:
        return "", ""
    if isinstance(pulse_weight, str):
        return pulse_weight.strip(), ""
    if isinstance(pulse_weight, tuple) and len(pulse_weight) == 2 and isinstance(pulse_weight[1], str) \
            and isinstance(pulse_weight[0], _numbers.Real) and not isinstance(pulse_weight[0], bool):
        if not pulse_weight[1]:
            raise ValueError("pulse_weight: %r has no unit (rad, mrad, urad, deg, arcsec)" % (pulse_weight,))
        return repr(float(pulse_weight[0])), pulse_weight[1]
    raise TypeError("pulse_weight must be a string such as '1.5arcsec' or a tuple (1.5, 'arcsec'), not %r"
                    % (pulse_weight,))


def _taus(taus):
    """('octave'|'decade'|'all'|'list', [m...]) of the taus argument."""
    if isinstance(taus, str):
        if taus not in ("octave", "decade", "all"):
            raise ValueError("taus must be 'octave', 'decade', 'all' or a list of averaging factors, not '%s'" % taus)
        return taus, []
    m = _np.asarray(taus)
    if m.ndim != 1 or m.size == 0 or not (_np.issubdtype(m.dtype, _np.integer)):
        raise TypeError("taus must be 'octave', 'decade', 'all' or a non-empty list of integer averaging factors m "
                        "(tau = m tau0)")
    if m[0] < 1 or _np.any(_np.diff(m) <= 0):
        raise ValueError("averaging factors must be positive and strictly increasing")
    return "list", [int(v) for v in m]


def analyze(values, tau0, type="phase", unit="", pulse_weight=None, stats=("oadev", "mdev"), taus="octave",
            stride_factor="full", confidence=0.683, fit=None, rate_unit=None, alpha=None,
            total_stride_factor=16, threads=0):
    """gyrochar-analyze on an array of values (float64 or int64, one-dimensional, any strides; read in
    place). Arguments as the program's options:

    tau0        sample interval in s
    type        'phase', 'freq' or 'counts'
    unit        phase: 's' (default) or an angle unit (rad, mrad, urad, deg, arcsec); freq: '1'
                (fractional, default) or a rate unit (deg/h, deg/s, rad/s); not for counts
    pulse_weight counts only: the angle of one pulse, '1.5arcsec' or (1.5, 'arcsec')
    rate_unit   output unit of gyro data (deg/h, deg/s, rad/s; None: deg/h); not for clock data
    stats       any of STATS, in the order the results keep
    taus        'octave', 'decade', 'all' or a list of averaging factors m (tau = m tau0)
    stride_factor 'full' (every tau up to N/2 fully overlapped) or a power of two from 2 to 2^24
    confidence  of the intervals, in (0, 1)
    fit         None or 'ieee952' (the fit without the PSD's sinusoid search, as
                gyrochar-analyze --fit ieee952 --no-sinusoid-search)
    alpha       None (noise identified per tau) or the noise exponent -4..2 for the EDF
    total_stride_factor  S of the decimated total/Theo estimators, a power of two from 2 to 2^20, or 'exact'
    threads     threads summing the held record's taus (0: one per core)

    Returns an Analysis. Raises TypeError or ValueError naming the cause for bad arguments (unit,
    pulse_weight and rate_unit with gyrochar-analyze's own messages) or values (a value that is not
    finite, a count that is not an integer, too few values).
    """
    setup, rule, listed = _setup(tau0, type, unit, pulse_weight, stats, taus, stride_factor, confidence, fit, rate_unit,
                                 alpha, total_stride_factor, threads)
    return Analysis(_native.analyze(_array(values), setup, rule, listed), float(tau0), type, float(confidence))


def _array(values):
    """values as an array the engine reads in place (float64 or int64; a narrower one is widened once)."""
    data = values if isinstance(values, _np.ndarray) else _np.asarray(values, dtype=float)
    if data.dtype == _np.float32 or data.dtype == _np.int32:
        data = data.astype(float)
    return data


def _deviations(values, tau0, type, stat, taus, stride_factor, total_stride_factor):
    """analyze() of one statistic without the noise identification (so no EDF and no interval) where
    the deviations do not need it (the total family's bias corrections do): the engine sums only
    that statistic's terms. For gyrochar.allantools, whose functions return no interval."""
    setup, rule, listed = _setup(tau0, type, "", None, (stat,), taus, stride_factor, 0.683, None, None, None,
                                 total_stride_factor, 0, identify_noise=False)
    return Analysis(_native.analyze(_array(values), setup, rule, listed), float(tau0), type, 0.683)


def _setup(tau0, type, unit, pulse_weight, stats, taus, stride_factor, confidence, fit, rate_unit, alpha,
           total_stride_factor, threads, identify_noise=True):
    """The checked arguments as the engine's setup, the tau rule and the listed taus."""
    if isinstance(tau0, bool) or not isinstance(tau0, _numbers.Real):
        raise TypeError("tau0 must be a number of seconds, not %r" % (tau0,))
    tau0 = float(tau0)
    if not (tau0 > 0 and _np.isfinite(tau0)):
        raise ValueError("tau0 must be a positive number of seconds, not %r" % tau0)
    if type not in ("phase", "freq", "counts"):
        raise ValueError("type must be 'phase', 'freq' or 'counts', not %r" % (type,))
    if not isinstance(unit, str):
        raise TypeError("unit must be a string, not %r" % (unit,))
    if unit == "Hz":  # the program's --nominal-hz is not here
        raise ValueError("unit: frequency in Hz needs its nominal frequency f0, which analyze() does not take: "
                         "give the fractional frequency (f - f0) / f0 with unit='1'")
    if rate_unit is not None and not isinstance(rate_unit, str):
        raise TypeError("rate_unit must be a string such as 'deg/h', not %r" % (rate_unit,))
    pulse_text, pulse_unit = _pulse_weight(pulse_weight)
    if isinstance(stats, str):
        stats = (stats,)
    stats = list(stats)
    if not stats:
        raise ValueError("stats is empty")
    for s in stats:
        if s not in STATS:
            raise ValueError("unknown statistic %r (%s)" % (s, ", ".join(STATS)))
        if stats.count(s) > 1:
            raise ValueError("statistic %r is asked twice" % s)
    rule, listed = _taus(taus)
    sf = 0 if stride_factor == "full" else _power_of_two(stride_factor, "stride_factor", 2, 1 << 24)
    tsf = 0 if total_stride_factor == "exact" else _power_of_two(total_stride_factor, "total_stride_factor", 2,
                                                                   1 << 20)
    if isinstance(confidence, bool) or not isinstance(confidence, _numbers.Real):
        raise TypeError("confidence must be a number, not %r" % (confidence,))
    if not 0 < confidence < 1:
        raise ValueError("confidence must be between 0 and 1, not %r" % confidence)
    if fit not in (None, "ieee952"):
        raise ValueError("fit must be None or 'ieee952' (the only model), not %r" % (fit,))
    if alpha is not None and (isinstance(alpha, bool) or not isinstance(alpha, _numbers.Integral)
                              or not -4 <= alpha <= 2):
        raise ValueError("alpha must be None (identified per tau) or an integer from -4 to 2, not %r" % (alpha,))
    setup = _native.setup(tau0, type, unit, pulse_text, pulse_unit, rate_unit or "", stats, sf, tsf, float(confidence), alpha,
                          fit is not None, int(threads), identify_noise)
    return setup, rule, listed


class Characterizer:
    """The streaming characterizer: add() blocks of values of any size in order, estimates() at any
    time; what gyrochar-analyze gives for the same values on standard input (length unknown: octave
    or decade taus without end, "full" = stride factor 2^16 and taus above it strided, or a list).
    Arguments as analyze() but taus "octave", "decade" or a list; estimates() returns an Analysis.
    Memory stays fixed whatever the number of values (the history of the stride factor); a record
    is held only for the total family.
    """

    def __init__(self, tau0, type="phase", unit="", pulse_weight=None, stats=("oadev", "mdev"), taus="octave",
                 stride_factor="full", confidence=0.683, fit=None, rate_unit=None, alpha=None,
                 total_stride_factor=16, threads=0):
        if taus == "all":
            raise ValueError("taus='all' needs the length: use analyze()")
        setup, rule, listed = _setup(tau0, type, unit, pulse_weight, stats, taus, stride_factor, confidence, fit,
                                     rate_unit, alpha, total_stride_factor, threads)
        self._native = _native.Characterizer(setup, rule, listed)
        self._args = (float(tau0), type, float(confidence))

    def add(self, values):
        """Adds the next values (float64 or int64, read in place). A bad value raises ValueError
        naming its index since the first value; the values before it stay added."""
        self._native.add(_array(values))

    def estimates(self):
        """The Analysis of the values so far."""
        return Analysis(self._native.estimates(), *self._args)

    def checkpoint(self):
        """The state as bytes: the core characterizer's checkpoint, the format the board writes (format
        version, stride factor, taus and a fingerprint of type, tau0 and unit in the header, a CRC-32
        at the end; native byte order). Not with the total family, whose record it does not carry."""
        return self._native.checkpoint()

    def restore(self, checkpoint):
        """Takes up the state of checkpoint() bytes written by a Characterizer with the same arguments.
        The next value starts a new segment, as on the board after a restart: no term spans the
        restore. Bytes that are truncated, corrupted or written under other arguments raise ValueError
        with the core's reason, and the characterizer stays as it was."""
        if not isinstance(checkpoint, (bytes, bytearray, memoryview)):
            raise TypeError("a checkpoint is bytes from Characterizer.checkpoint(), not %s" % type(checkpoint).__name__)
        self._native.restore(bytes(checkpoint))

    @property
    def values(self):
        """The number of values added."""
        return self._native.values
