# gyrochar.analyze() against gyrochar-analyze --format json on the same values (the oracle: the
# program, whose engine the module shares; every number must be equal to the last bit), and its
# argument checks.
import json
import subprocess

import numpy as np
import pytest

import gyrochar
from conftest import load

ROW_FIELDS = ("tau", "m", "n", "dev", "ci_low", "ci_high", "alpha", "edf", "stride")


def program_json(program, path, args):
    out = subprocess.run([program, "--format", "json", *args, str(path)], check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def assert_rows_equal(result, report, stats):
    """Every row of the program's JSON equals the module's arrays bit for bit (null: NaN or None)."""
    for stat in stats:
        rows = [r for r in report["results"] if r["stat"] == stat]
        got = result.stats[stat]
        assert len(rows) > 0 and len(got) == len(rows), stat
        for field in ROW_FIELDS:
            want = np.array([np.nan if r[field] is None else r[field] for r in rows], dtype=float)
            np.testing.assert_array_equal(np.asarray(getattr(got, field), dtype=float), want, err_msg=f"{stat} {field}")
        assert list(got.noise_id) == [r["noise_id"] for r in rows], stat
        assert got.unit == rows[0]["unit"]


CASES = [
    # (file under tests/data, program options, analyze() keywords, how the module gets the values)
    ("phasedat/PHASE.DAT", ["--type", "phase", "--tau0", "1"], dict(type="phase"), None),
    ("nbs14/nbs14_1000point_freq.txt", ["--type", "freq", "--tau0", "1"], dict(type="freq"), None),
    ("ocxo/ocxo_frequency.txt", ["--type", "freq", "--tau0", "1", "--nominal-hz", "1e7"], dict(type="freq"),
     lambda f: (f - 1e7) / 1e7),  # the program's --nominal-hz conversion, (f - F0) / F0
    ("Keysight53230A_ti_noise_floor/tic_phase.txt", ["--type", "phase", "--tau0", "1"], dict(type="phase"), None),
]
ALLAN = ["adev", "oadev", "mdev", "tdev", "hdev", "ohdev"]


@pytest.mark.parametrize("taus", ["octave", "decade"])
@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_allan_family_equals_program(analyze_program, data_dir, case, taus):
    name, args, kwargs, convert = case
    path = data_dir / name
    values = load(path)
    if convert:
        values = convert(values)
    report = program_json(analyze_program, path, args + ["--taus", taus, "--stats", ",".join(ALLAN)])
    result = gyrochar.analyze(values, 1.0, stats=ALLAN, taus=taus, **kwargs)
    assert result.n_values == report["n_samples"]
    assert_rows_equal(result, report, ALLAN)


@pytest.mark.parametrize("taus", ["octave", "all"])
def test_total_family_equals_program(analyze_program, data_dir, taus):
    stats = ["oadev", "totdev", "mtotdev", "ttotdev", "htotdev", "theo1", "theoh"]
    path = data_dir / "phasedat" / "PHASE.DAT"
    report = program_json(analyze_program, path, ["--type", "phase", "--tau0", "1", "--taus", taus, "--stats", ",".join(stats)])
    result = gyrochar.analyze(load(path), 1.0, type="phase", stats=stats, taus=taus)
    assert_rows_equal(result, report, stats)


def counts_record(tmp_path, n=20000):
    """Counts of a simulated gyro: white rate noise and a random walk of 1 arcsec pulses (seeded)."""
    rng = np.random.default_rng(21)
    rate = 40 + rng.normal(0, 3, n) + np.cumsum(rng.normal(0, 0.05, n))
    counts = np.diff(np.floor(np.concatenate([[0.0], np.cumsum(rate)]))).astype(np.int64)
    path = tmp_path / "counts.txt"
    np.savetxt(path, counts, fmt="%d")
    return counts, path


def test_counts_with_fit_equal_program(analyze_program, tmp_path):
    counts, path = counts_record(tmp_path)
    report = program_json(analyze_program, path, ["--type", "counts", "--tau0", "0.01", "--pulse-weight", "1arcsec",
                                                  "--stats", "oadev,mdev,ohdev", "--fit", "ieee952",
                                                  "--no-sinusoid-search"])
    result = gyrochar.analyze(counts, 0.01, type="counts", pulse_weight="1arcsec", stats=("oadev", "mdev", "ohdev"),
                              fit="ieee952")
    assert_rows_equal(result, report, ["oadev", "mdev", "ohdev"])
    assert result.fit == report["fit"]
    assert result.fit[0]["recommended"] and result.fit[0]["N"]["unit"] == "deg/sqrt(h)"


@pytest.mark.parametrize("args, kwargs", [
    (["--type", "freq", "--unit", "deg/s", "--rate-unit", "rad/s"], dict(type="freq", unit="deg/s", rate_unit="rad/s")),
    (["--type", "phase", "--unit", "mrad"], dict(type="phase", unit="mrad")),
    (["--type", "counts", "--pulse-weight", "0.5", "--pulse-unit", "urad", "--rate-unit", "deg/s"],
     dict(type="counts", pulse_weight=(0.5, "urad"), rate_unit="deg/s")),
])
def test_gyro_units_equal_program(analyze_program, tmp_path, args, kwargs):
    # The unit arguments resolve as the program's options (one function, input_units.cpp): same
    # units_input, same rows in the same output unit.
    counts, path = counts_record(tmp_path, 4000)
    report = program_json(analyze_program, path, args + ["--tau0", "0.01", "--stats", "oadev,tdev"])
    result = gyrochar.analyze(counts, 0.01, stats=("oadev", "tdev"), **kwargs)
    assert result.units_input == report["units"]["input"]
    assert_rows_equal(result, report, ["oadev", "tdev"])


def test_list_taus_stride_factor_and_confidence_equal_program(analyze_program, data_dir):
    path = data_dir / "phasedat" / "PHASE.DAT"
    report = program_json(analyze_program, path, ["--type", "phase", "--tau0", "2.5", "--taus", "1,3,10,64",
                                                  "--stride-factor", "8", "--confidence", "0.95", "--stats", "oadev,mdev"])
    result = gyrochar.analyze(load(path), 2.5, stats=("oadev", "mdev"), taus=[1, 3, 10, 64], stride_factor=8,
                              confidence=0.95)
    assert result.stride_factor == report["stride_factor"] == 8
    assert_rows_equal(result, report, ["oadev", "mdev"])


def test_strided_and_int64_inputs_read_in_place_give_the_same_rows(tmp_path):
    counts, _ = counts_record(tmp_path, 5000)
    wide = np.zeros((len(counts), 3))
    wide[:, 1] = counts  # a column of a 2-D array: strided, read without a copy
    base = gyrochar.analyze(counts.astype(float), 0.01, type="counts", pulse_weight=(1, "arcsec"))
    for values in (counts, wide[:, 1]):
        other = gyrochar.analyze(values, 0.01, type="counts", pulse_weight="1 arcsec")
        for field in ROW_FIELDS:
            np.testing.assert_array_equal(getattr(other.oadev, field), getattr(base.oadev, field))


@pytest.mark.parametrize("kwargs, error, words", [
    (dict(values=[1.0, np.nan, 3.0, 4.0]), ValueError, "values[1]"),
    (dict(values=np.array(["a", "b"])), TypeError, "float64 or int64"),
    (dict(values=np.zeros((4, 4))), ValueError, "one-dimensional"),
    (dict(values=[]), ValueError, "no values"),
    (dict(tau0=0), ValueError, "tau0"),
    (dict(tau0="1"), TypeError, "tau0"),
    (dict(type="rate"), ValueError, "'phase', 'freq' or 'counts'"),
    (dict(stats=("oadev", "allan")), ValueError, "unknown statistic 'allan'"),
    (dict(stats=("oadev", "oadev")), ValueError, "twice"),
    (dict(taus="octaves"), ValueError, "taus must be"),
    (dict(taus=[4, 2]), ValueError, "strictly increasing"),
    (dict(taus=[1.5]), TypeError, "integer averaging factors"),
    (dict(stride_factor=6), ValueError, "power of two"),
    (dict(confidence=1.5), ValueError, "between 0 and 1"),
    (dict(fit="ieee"), ValueError, "ieee952"),
    # The unit arguments with gyrochar-analyze's messages (input_units.cpp: test_input_units.cpp
    # has the program's side), its option named as the argument.
    (dict(unit="furlong"), ValueError, "unit: phase is in s or an angle unit (rad, mrad, urad, deg, arcsec), "
                                       "not 'furlong'"),
    (dict(type="freq", unit="furlong"), ValueError, "unit: freq is in 1 (fractional), Hz or a rate unit"),
    (dict(type="freq", unit="Hz"), ValueError, "unit: frequency in Hz needs its nominal frequency"),
    (dict(type="counts"), ValueError, "pulse_weight: counts need the angle of one pulse, e.g. 1.5arcsec"),
    (dict(type="counts", unit="deg", pulse_weight="1arcsec"), ValueError, "unit: counts take --pulse-weight instead"),
    (dict(type="counts", pulse_weight="1 parsec"), ValueError, "pulse_weight: unknown angle unit 'parsec'"),
    (dict(type="counts", pulse_weight=(0, "arcsec")), ValueError, "pulse_weight: '0.0' is not a positive angle"),
    (dict(type="counts", pulse_weight=(1, "")), ValueError, "pulse_weight: (1, '') has no unit"),
    (dict(type="counts", pulse_weight=("1", "arcsec")), TypeError, "pulse_weight must be"),
    (dict(type="counts", pulse_weight="1e-320arcsec"), ValueError, "below the smallest normal double"),
    (dict(type="counts", pulse_weight="1arcsec", rate_unit="mph"), ValueError, "rate_unit: unknown unit 'mph'"),
    (dict(rate_unit="deg/s"), ValueError, "rate_unit: only applies to gyro data"),
    (dict(type="counts", pulse_weight="1arcsec", values=[1.0, 2.5, 3.0, 4.0]), ValueError, "values[1]"),
    (dict(pulse_weight="1arcsec"), ValueError, "pulse_weight: only applies to --type counts"),
    (dict(values=[1.0, 2.0]), ValueError, "too few"),
])
def test_bad_arguments_raise_with_the_cause(kwargs, error, words):
    args = dict(values=np.arange(100.0) ** 2, tau0=1.0)
    args.update(kwargs)
    with pytest.raises(error) as e:
        gyrochar.analyze(args.pop("values"), args.pop("tau0"), **args)
    assert words in str(e.value)


def program_json_stdin(program, path, args):
    with open(path, "rb") as f:
        out = subprocess.run([program, "--format", "json", *args, "-"], stdin=f, check=True, capture_output=True)
    return json.loads(out.stdout)


@pytest.mark.parametrize("chunk", [1, 1000, 7919])
def test_characterizer_in_blocks_equals_program_on_standard_input(analyze_program, tmp_path, chunk):
    # The oracle: gyrochar-analyze reading the same counts from standard input (length unknown).
    counts, path = counts_record(tmp_path, 30000)
    stats = ["oadev", "mdev", "ohdev"]
    report = program_json_stdin(analyze_program, path, ["--type", "counts", "--tau0", "0.01", "--pulse-weight",
                                                        "1arcsec", "--stats", ",".join(stats)])
    c = gyrochar.Characterizer(0.01, type="counts", pulse_weight="1arcsec", stats=stats)
    values = counts[:5000] if chunk == 1 else counts
    for i in range(0, len(values), chunk):
        c.add(values[i:i + chunk])
    if chunk == 1:  # one at a time for the first 5000, then the rest at once
        c.add(counts[5000:])
    assert c.values == len(counts)
    assert_rows_equal(c.estimates(), report, stats)


def test_characterizer_decade_taus_equal_program_on_standard_input(analyze_program, tmp_path):
    # Decade taus without end: those the stride factor 2^16 cannot form (10^7, ...) are refused only
    # once the data reaches them, as the program does (oracle: the program on standard input).
    counts, path = counts_record(tmp_path, 30000)
    report = program_json_stdin(analyze_program, path, ["--type", "counts", "--tau0", "0.01", "--pulse-weight",
                                                        "1arcsec", "--taus", "decade", "--stats", "oadev,mdev"])
    c = gyrochar.Characterizer(0.01, type="counts", pulse_weight="1arcsec", taus="decade")
    c.add(counts)
    assert_rows_equal(c.estimates(), report, ["oadev", "mdev"])


def test_a_decade_tau_the_stride_factor_cannot_form_is_refused_as_by_the_program(analyze_program, tmp_path):
    # m = 10 with S = 4 needs a multiple of its stride 4 (plan.hpp): refused by both, with one message.
    values = np.cumsum(np.random.default_rng(8).normal(size=200))
    path = tmp_path / "phase.txt"
    np.savetxt(path, values, fmt="%.17g")
    out = subprocess.run([analyze_program, "--type", "phase", "--tau0", "1", "--taus", "decade", "--stride-factor", "4",
                          str(path)], capture_output=True, text=True)
    assert out.returncode == 2
    with pytest.raises(ValueError) as e:
        gyrochar.analyze(values, 1.0, taus="decade", stride_factor=4)
    assert str(e.value) in out.stderr and "averaging factor 10 cannot be formed with stride factor 4" in str(e.value)


def test_characterizer_estimates_at_any_time_and_refuses_bad_values():
    c = gyrochar.Characterizer(1.0, type="phase", stats=("oadev",), stride_factor=8)
    c.add(np.arange(100.0) ** 2)
    first = c.estimates().oadev
    with pytest.raises(ValueError, match=r"values\[102\]"):
        c.add([1.0, 2.0, np.inf])
    assert c.values == 102  # the two values before the refused one stay added
    assert len(first) > 0
    with pytest.raises(ValueError, match="needs the length"):
        gyrochar.Characterizer(1.0, taus="all")


def test_edf_of_gives_the_programs_exact_edf(analyze_program, data_dir):
    # Oracle: the program's rows at the same taus with a stride factor that overlaps every tau
    # fully (the smallest power of two at or above the largest m), whose EDF is the exact one.
    import gyrochar.allantools as ga
    path = data_dir / "phasedat" / "PHASE.DAT"
    values = load(path)
    taus, edf, low, high = ga.edf_of(ga.oadev, values, rate=1.0, data_type="phase", taus="octave")
    stride = 2
    while stride < taus[-1]:
        stride *= 2
    report = program_json(analyze_program, path, ["--type", "phase", "--tau0", "1", "--stats", "oadev",
                                                  "--taus", ",".join(str(int(t)) for t in taus),
                                                  "--stride-factor", str(stride)])
    rows = {r["m"]: r for r in report["results"] if r["stat"] == "oadev"}
    assert len(taus) > 5 and len(rows) == len(taus)
    for t, e, lo, hi in zip(taus, edf, low, high):
        r = rows[int(t)]
        assert e == r["edf"] and lo == r["ci_low"] and hi == r["ci_high"], t
    with pytest.raises(ValueError, match="edf_of takes a function"):
        ga.edf_of(len, values)


@pytest.mark.parametrize("case", CASES[:2], ids=[c[0] for c in CASES[:2]])
def test_allantools_functions_give_the_deviations_of_analyze_to_the_bit(data_dir, case):
    # Oracle: gyrochar.analyze with the six statistics (every sum formed, the noise identified;
    # itself equal to the program above). Each function of gyrochar.allantools forms its own
    # statistic's sums alone and identifies no noise: the same taus, ns and devs to the last bit,
    # and no EDF; the total family still identifies (its bias corrections need it).
    import gyrochar.allantools as ga
    name, _, kwargs, _ = case
    values = load(data_dir / name)
    for stat in ALLAN:
        taus, devs, errs, ns = getattr(ga, stat)(values, rate=1.0, data_type=kwargs["type"], taus="octave")
        m = np.round(taus).astype(np.int64)
        stride = 2
        while stride < m[-1]:
            stride *= 2
        want = gyrochar.analyze(values, 1.0, stats=ALLAN, taus=m, stride_factor=stride, total_stride_factor="exact",
                                **kwargs).stats[stat]
        keep = want.n > 1
        np.testing.assert_array_equal(ns, want.n[keep].astype(float), err_msg=stat)
        np.testing.assert_array_equal(devs, want.dev[keep], err_msg=stat)
        np.testing.assert_array_equal(errs, want.dev[keep] / np.sqrt(want.n[keep]), err_msg=stat)
        assert np.any(np.isfinite(want.edf[keep])), stat  # the oracle's rows have their EDF
    bare = gyrochar._deviations(values, 1.0, kwargs["type"], "oadev", "octave", "full", "exact").stats["oadev"]
    assert np.all(np.isnan(bare.edf)) and all(n is None for n in bare.noise_id)
    total = gyrochar._deviations(values, 1.0, kwargs["type"], "totdev", "octave", "full", "exact").stats["totdev"]
    assert any(n is not None for n in total.noise_id)
