"""What an Analysis offers a notebook: its rows as pandas DataFrames and its curves drawn with
matplotlib. Both libraries are optional: imported on first use, a clear ImportError when absent."""

import numpy as _np

# The columns of a statistic's DataFrame, in this order (StatResult's arrays, then its unit).
COLUMNS = ("tau", "m", "n", "dev", "ci_low", "ci_high", "alpha", "edf", "noise_id", "stride", "unit")


def _need(module, what):
    try:
        return __import__(module, fromlist=["_"])
    except ImportError as e:
        package = {"pandas": "python3-pandas", "matplotlib.pyplot": "python3-matplotlib"}[module]
        raise ImportError("%s needs %s, which is not installed (Debian: apt-get install %s; pip: pip install %s)"
                          % (what, module.split(".")[0], package, module.split(".")[0])) from e


def stat_frame(result):
    """One StatResult as a DataFrame: one row per tau, COLUMNS as columns."""
    pd = _need("pandas", "StatResult.to_pandas()")
    columns = {c: getattr(result, c) for c in COLUMNS if c != "unit"}
    columns["unit"] = [result.unit] * len(result)
    return pd.DataFrame(columns, columns=list(COLUMNS))


def analysis_frame(analysis):
    """Every statistic of an Analysis in one long DataFrame: a column `stat` first, then COLUMNS;
    the rows by statistic (in the order asked) then by tau, numbered from 0."""
    pd = _need("pandas", "Analysis.to_pandas()")
    frames = []
    for name, result in analysis.stats.items():
        frame = stat_frame(result)
        frame.insert(0, "stat", name)
        frames.append(frame)
    return pd.concat(frames, ignore_index=True)


def _plotted(analysis, stats):
    """The statistics to draw on one axes, all in one unit (TDEV and TTOTDEV, in a time or an angle
    unit, are left out by default when there are others)."""
    if stats is None:
        stats = [s for s, r in analysis.stats.items() if len(r)]
        devs = [s for s in stats if analysis.stats[s].unit == _dev_unit(analysis)]
        stats = devs or stats
    else:
        stats = [stats] if isinstance(stats, str) else list(stats)
        for s in stats:
            if s not in analysis.stats:
                raise ValueError("plot: no statistic '%s' in this analysis (statistics: %s)"
                                 % (s, ", ".join(analysis.stats)))
    units = {analysis.stats[s].unit for s in stats}
    if len(units) > 1:
        raise ValueError("plot: one axes shows one unit, and %s are in %s: plot them on separate axes"
                         % (", ".join(stats), ", ".join(sorted(units))))
    if not stats:
        raise ValueError("plot: no statistic has a row to draw")
    return stats


def _dev_unit(analysis):
    units = [r.unit for s, r in analysis.stats.items() if s not in ("tdev", "ttotdev")]
    return units[0] if units else None


def plot(analysis, ax=None, stats=None, fit=True):
    """Draws the deviations of `stats` (default: every statistic in the deviation unit) on log-log
    axes, each with its confidence interval as error bars (none where the interval is not
    available), and where the analysis has an IEEE-952 fit and `fit` is true, the recommended
    fit's model through its fitted taus of OADEV and MDEV (the `model` of its residuals, computed
    by the engine). Draws into `ax` or a new figure's axes; returns the axes."""
    plt = _need("matplotlib.pyplot", "Analysis.plot()")
    stats = _plotted(analysis, stats)
    if ax is None:
        _, ax = plt.subplots()
    unit = analysis.stats[stats[0]].unit
    for name in stats:
        r = analysis.stats[name]
        below = _np.where(_np.isnan(r.ci_low), 0.0, r.dev - r.ci_low)
        above = _np.where(_np.isnan(r.ci_high), 0.0, r.ci_high - r.dev)
        ax.errorbar(r.tau, r.dev, yerr=_np.vstack([below, above]), fmt="o-", markersize=3, capsize=2,
                    label=name.upper())
    if fit and analysis.fit:
        best = analysis.fit[0]
        for name in stats:
            points = [p for p in best.get("residuals", []) if p["stat"] == name]
            if points:
                tau = _np.array([p["m"] for p in points], dtype=float) * analysis.tau0
                ax.plot(tau, [p["model"] for p in points], "--", label="%s IEEE-952 model" % name.upper())
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("tau (s)")
    ax.set_ylabel("deviation (%s)" % unit)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    return ax
