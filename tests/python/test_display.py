# Analysis.to_pandas() and Analysis.plot(): the DataFrame holds the result's arrays unchanged (oracle:
# the StatResult arrays themselves), the plot's artists hold the deviations, their intervals and
# the fit's model as the analysis has them (checked on the returned axes' data, not on pixels).
import sys

import numpy as np
import pytest

import gyrochar


@pytest.fixture(scope="module")
def result():
    rng = np.random.default_rng(4)
    rate = 40 + rng.normal(0, 3, 20000) + np.cumsum(rng.normal(0, 0.05, 20000))
    counts = np.diff(np.floor(np.concatenate([[0.0], np.cumsum(rate)]))).astype(np.int64)
    return gyrochar.analyze(counts, 0.01, type="counts", pulse_weight="1arcsec", stats=("oadev", "mdev", "tdev"),
                            fit="ieee952")


def test_to_pandas_long_frame_and_per_statistic(result):
    pd = pytest.importorskip("pandas")
    df = result.to_pandas()
    assert list(df.columns) == ["stat", "tau", "m", "n", "dev", "ci_low", "ci_high", "alpha", "edf", "noise_id",
                                "stride", "unit"]
    assert list(df.stat.unique()) == ["oadev", "mdev", "tdev"]
    assert len(df) == sum(len(r) for r in result.stats.values())
    for name, r in result.stats.items():
        part = df[df.stat == name]
        for field in ("tau", "m", "n", "dev", "ci_low", "ci_high", "alpha", "edf", "stride"):
            np.testing.assert_array_equal(part[field].to_numpy(), getattr(r, field), err_msg=name + " " + field)
        assert list(part.noise_id) == list(r.noise_id)
        assert set(part.unit) == {r.unit}
        single = r.to_pandas()
        assert isinstance(single, pd.DataFrame) and "stat" not in single.columns
        pd.testing.assert_frame_equal(single, part.drop(columns="stat").reset_index(drop=True))
    assert df[df.stat == "tdev"].unit.iloc[0] == "arcsec" and df[df.stat == "oadev"].unit.iloc[0] == "deg/h"


def test_without_pandas_or_matplotlib_an_import_error_says_what_to_install(result, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas now raises ImportError
    with pytest.raises(ImportError, match="to_pandas\\(\\) needs pandas, which is not installed .*python3-pandas"):
        result.to_pandas()
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    with pytest.raises(ImportError, match="plot\\(\\) needs matplotlib.*python3-matplotlib"):
        result.plot()


@pytest.fixture()
def plt():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")  # headless
    import matplotlib.pyplot as pyplot
    yield pyplot
    pyplot.close("all")


def test_plot_draws_each_deviation_with_its_interval_and_the_fit(result, plt):
    ax = result.plot()
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    assert ax.get_ylabel() == "deviation (deg/h)"  # TDEV (arcsec) left out: one unit per axes
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert sorted(labels) == ["MDEV", "MDEV IEEE-952 model", "OADEV", "OADEV IEEE-952 model"]
    bars = ax.containers  # one ErrorbarContainer per statistic
    for container, name in zip(bars, ("oadev", "mdev")):
        r = result.stats[name]
        line, _, (vertical,) = container.lines
        np.testing.assert_array_equal(line.get_xdata(), r.tau)
        np.testing.assert_array_equal(line.get_ydata(), r.dev)
        segments = vertical.get_segments()  # each bar from ci_low to ci_high at its tau
        assert len(segments) == len(r)
        for seg, lo, hi in zip(segments, r.ci_low, r.ci_high):
            if np.isnan(lo):
                continue
            np.testing.assert_allclose(seg[:, 1], [lo, hi], rtol=1e-12)  # dev - (dev - lo) in floating point
    # The model: the recommended fit's own values (its residuals' "model") at its fitted taus.
    model = [l for l in ax.get_lines() if l.get_label() == "OADEV IEEE-952 model"][0]
    points = [p for p in result.fit[0]["residuals"] if p["stat"] == "oadev"]
    np.testing.assert_array_equal(model.get_xdata(), np.array([p["m"] for p in points]) * 0.01)
    np.testing.assert_array_equal(model.get_ydata(), [p["model"] for p in points])


def test_plot_into_given_axes_one_statistic_without_fit_and_refusals(result, plt):
    _, ax = plt.subplots()
    assert result.plot(ax=ax, stats="tdev", fit=False) is ax
    assert ax.get_ylabel() == "deviation (arcsec)" and len(ax.containers) == 1 and len(ax.get_legend().get_texts()) == 1
    with pytest.raises(ValueError, match="one axes shows one unit"):
        result.plot(stats=("oadev", "tdev"))
    with pytest.raises(ValueError, match="no statistic 'hdev'"):
        result.plot(stats="hdev")
    fig = result.plot().figure
    fig.savefig(__import__("io").BytesIO(), format="png")  # renders headless (Agg)
