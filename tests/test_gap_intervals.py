"""The 95 % intervals of the gap's parameters (gyrofilter.analysis.gap.intervals): the interval
formula against a hand computation, the analytic baseline intervals' coverage on white noise,
one hidden-effect case per family of effects whose true parameters must lie inside their
intervals (the effect drawn at random within the family from the seed), ``--bootstrap 0``, the
console, and (slow) the coverage over many seeds per effect kind.

The coverage figures per kind, on more cases, are in docs/gap.md (``tools/gap_coverage.py``).
"""
import html
import json
import math
from statistics import NormalDist

import numpy as np
import pytest
from scipy.stats import t as student_t

import gyrofilter.sim.hidden_effects as he
from gyrofilter.analysis.gap import intervals as gi
from gyrofilter.analysis.gap.pipeline import analyse_gap
from gyrofilter.analysis.gap.baseline import baseline_model
from gyrofilter.analysis.gap.report import interval_text, params_text, uncertain_text, value_with_interval
from gyrofilter.cli import main
from gyrofilter.effects import BY_NAME
from gyrofilter.recording import write_recording
from gyrofilter.sim.simulate import simulate
from gyrofilter.units import AXES
from support import REPO, battery

SIMS = 8
#: the families of effects, each drawn at random from the seed
FAMILIES = {"spikes": ("outliers", "heavy_tails"), "line": ("sinusoid",), "colored": ("colored_noise",),
            "slow shape": ("rate_ramp", "bias_step", "warmup", "temperature"),
            "slow spectrum": ("bias_instability", "rate_random_walk", "gauss_markov")}


def _inside(true, interval, name):
    low, high = interval
    if name == "phase_rad":
        true += 2 * math.pi * math.ceil((low - true) / (2 * math.pi))
    return low <= true <= high


def _check_finite_and_ordered(report):
    """Every finding and baseline axis has an interval per parameter, finite, low < high, holding
    the estimate, or null and a note saying so."""
    for f in report["findings"]:
        assert set(f["params_ci95"]) == set(f["params"]), f
        for name, interval in f["params_ci95"].items():
            if interval is None:
                assert any(n.startswith(f"{f['effect']} on {f['axis']}: {name} not determined") for n in report["notes"])
                continue
            low, high = interval
            assert math.isfinite(low) and math.isfinite(high) and low < high, (f["effect"], name, low, high)
            assert low <= f["params"][name] <= high, (f["effect"], name, f["params"][name], low, high)
    for a in AXES:
        for name, (low, high) in report["baseline"]["axes"][a]["params_ci95"].items():
            assert math.isfinite(low) and math.isfinite(high) and low < high, (a, name, low, high)
    assert report["intervals"]["bootstrap_runs"] == gi.DEFAULT_BOOTSTRAP and report["intervals"]["confidence"] == 0.95


def _family_case(family, seed, duration_s=600.0):
    rng = np.random.default_rng(seed)
    effects = FAMILIES[family]
    return he.draw_case(seed, effect=effects[rng.integers(len(effects))], duration_s=duration_s)


def _hit(case, report):
    hit = [f for f in report["findings"] if f["effect"] == case["effect"] and f["axis"] == case["axis"]]
    assert hit, (case["effect"], case["axis"], case["params"], report["findings"])
    return hit[0]


def _true(case, name):
    return case["params"].get(name, case["params"].get("lag1", 0.0) ** 2)


def test_interval_is_the_bias_corrected_student_interval_on_the_log_scale():
    """By hand: u = log(replicates), bias = mean(u) - log(estimate), half-width
    t_{0.975, B-1} sqrt(1 + 1/B) sd(u)."""
    reps = [1.1, 1.3, 0.9, 1.2, 1.25, 1.05, 1.15, 1.4]
    u = np.log(reps)
    b = len(reps)
    centre = math.log(1.0) - (u.mean() - math.log(1.0))
    half = student_t.ppf(0.975, b - 1) * math.sqrt(1 + 1 / b) * u.std(ddof=1)
    low, high = gi._interval(1.0, reps, "log").ends
    assert low == pytest.approx(math.exp(centre - half)) and high == pytest.approx(math.exp(centre + half))
    # replicates 10 % high on average: the interval is moved down by that bias
    assert high < 1.0 * math.exp(half)
    # a signed parameter on the linear scale; too few replicates: no interval
    low, high = gi._interval(-2.0, [-2.1, -1.9, -2.05, -1.95, -2.0, None], "linear").ends
    assert low < -2.0 < high and gi._interval(1.0, [1.0, 1.1, None, None], "log").ends is None


def test_a_step_of_test_inversion_mends_an_estimator_whose_spread_grows_with_the_parameter():
    """A scale estimate log(theta-hat) = log(theta) + 0.5 sqrt(theta) z (its spread grows with theta,
    as a Gauss-Markov estimate's with tau): the plain interval, from replicates at theta-hat,
    misses a true theta above more often than below; one step of test inversion
    (gi.inversion_step, replicates at the ends) brings the coverage closer to 95 % and balances
    the two sides. 4000 seeded records, 20 replicates each; the coverage of the intervals given
    (an estimate far above theta has a spread of over a factor 100: not determined, a few %)."""
    rng = np.random.default_rng(5)
    draw = lambda theta, size=None: theta * np.exp(0.5 * math.sqrt(theta) * rng.standard_normal(size))
    theta = 1.0
    miss = {"plain": [0, 0], "inverted": [0, 0]}
    given = {"plain": 0, "inverted": 0}
    for _ in range(4000):
        est = float(draw(theta))
        reps = draw(est, 20)
        plain = gi._interval(est, reps, "log").ends
        inverted = gi.inversion_step({"p": est}, [{"p": v} for v in reps],
                                     lambda at: [{"p": v} for v in draw(at["p"], 20)], {"p": "log"})["p"].ends
        for name, interval in (("plain", plain), ("inverted", inverted)):
            if interval is None:
                continue
            given[name] += 1
            miss[name][0] += theta < interval[0]
            miss[name][1] += theta > interval[1]
    assert min(given.values()) > 0.95 * 4000, given
    cover = {name: 1 - sum(m) / given[name] for name, m in miss.items()}
    assert cover["plain"] < 0.93 and abs(cover["inverted"] - 0.95) < abs(cover["plain"] - 0.95), (cover, miss)
    assert miss["plain"][1] > 2 * miss["plain"][0]  # the plain interval misses above
    assert miss["inverted"][1] < miss["plain"][1]


def test_phase_interval_wraps_the_replicates_and_lags_stay_inside_minus_one_one():
    low, high = gi._interval(3.1, [3.05, -3.12, 3.13, -3.1, 3.08, 3.11], "phase").ends  # replicates across +-pi
    assert high - low < 0.5 and _inside(3.1, (low, high), "phase_rad")
    low, high = gi._interval(0.97, [0.95, 0.985, 0.99, 0.96, 0.975], "atanh").ends
    assert -1 < low < high < 1


def test_baseline_intervals_of_white_noise_cover_the_truth():
    """Analytic intervals of bias and white noise on clean 10-minute records (quantized like the
    MPU6050), 200 seeds: each covers its true value in 90-99 % of the records (at a true 95 %
    the count leaves that range with binomial probability 0.3 %)."""
    inside = {"bias_dps": 0, "arw_dps_per_sqrt_hz": 0}
    n = 200
    rng = np.random.default_rng(7)
    for seed in range(n):
        arw, bias = float(rng.uniform(0.005, 0.015)), float(rng.uniform(-5, 5))
        model = {"sample_rate_hz": 100.0, "gyro_unit": "lsb", "lsb_per_dps": 131.0,
                 "axes": {"x": {"bias_dps": bias, "arw_dps_per_sqrt_hz": arw, "effects": []}}}
        rec = simulate(model, 600.0, seed=seed)
        run = _BaselineRun(rec)
        ci = gi._baseline_analytic(run, 0)
        inside["bias_dps"] += _inside(bias, ci["bias_dps"], "bias_dps")
        inside["arw_dps_per_sqrt_hz"] += _inside(arw, ci["arw_dps_per_sqrt_hz"], "arw")
    for name, k in inside.items():
        assert 0.90 * n <= k <= 0.99 * n, (name, k)


class _BaselineRun:
    """What _baseline_analytic reads of a gap run."""

    def __init__(self, rec):
        self.base = baseline_model(rec)
        self.n, self.sample_rate_hz = len(rec), rec.sample_rate_hz
        self.q = 1.0 / rec.lsb_per_dps


@pytest.mark.parametrize("family", FAMILIES)
def test_a_hidden_effect_lies_inside_its_intervals(family):
    """One 30-minute case per family (the standard battery's shortest record; the effect drawn
    from the family by the seed): every true parameter inside its interval widened to 99.9 %,
    every interval finite and ordered. The 95 % rates are the slow test's and
    tools/gap_coverage.py's."""
    case = _family_case(family, 500 + list(FAMILIES).index(family), duration_s=1800.0)
    report = analyse_gap(he.simulate_case(case), seed=case["seed"], n_sims=SIMS)
    _check_finite_and_ordered(report)
    f = _hit(case, report)
    for name in f["params"]:
        interval = _widened(f["params_ci95"][name], gi.SCALES.get(case["effect"], {}).get(name, "linear"))
        assert _inside(_true(case, name), interval, name), (case["effect"], name, case["params"], f)


def _widened(interval, scale, confidence=0.999):
    """The 95 % interval stretched about its centre, on its scale, to ``confidence`` (normal
    quantiles): a single case then misses 0.1 % of the time, not 5 %, and the test stays
    able to fail when an interval is off by more than its own width."""
    z = NormalDist().inv_cdf(0.5 + confidence / 2) / NormalDist().inv_cdf(0.975)
    scale = scale if scale in ("log", "atanh") and (scale != "log" or interval[0] > 0) else "linear"
    lo, hi = gi._forward(interval, scale)
    mid, half = (lo + hi) / 2, z * (hi - lo) / 2
    return [gi._back(mid - half, scale), gi._back(mid + half, scale)]


def test_a_hidden_narrowband_lies_inside_its_intervals():
    case = he.draw_case(61, effect="none", duration_s=600.0)
    rng = np.random.default_rng(61)
    axis = AXES[rng.integers(3)]
    sigma = case["model"]["axes"][axis]["arw_dps_per_sqrt_hz"] * 10.0
    true = {"center_hz": float(rng.uniform(12, 38)), "bandwidth_hz": float(rng.uniform(0.6, 3.0)),
            "rms_dps": float(rng.uniform(0.5, 1.5) * sigma)}
    case["model"]["axes"][axis]["effects"].append(dict(effect="narrowband", **true))
    report = analyse_gap(he.simulate_case(case), seed=61, n_sims=SIMS)
    _check_finite_and_ordered(report)
    f = _hit({"effect": "narrowband", "axis": axis, "params": true}, report)
    for name, value in true.items():
        assert _inside(value, f["params_ci95"][name], name), (name, true, f)


def test_bootstrap_zero_gives_no_intervals_and_says_so():
    case = he.draw_case(3, effect="sinusoid", duration_s=300.0)
    report = analyse_gap(he.simulate_case(case), seed=0, n_sims=4, bootstrap=0)
    assert report["findings"] and not any("params_ci95" in f for f in report["findings"])
    assert not any("params_ci95" in report["baseline"]["axes"][a] for a in AXES)
    assert report["intervals"]["bootstrap_runs"] == 0 and "no intervals" in report["intervals"]["method"]


def test_intervals_are_seeded():
    case = he.draw_case(4, effect="warmup", duration_s=300.0)
    rec = he.simulate_case(case)
    a, b = (analyse_gap(rec, seed=5, n_sims=4, bootstrap=6) for _ in range(2))
    assert [f["params_ci95"] for f in a["findings"]] == [f["params_ci95"] for f in b["findings"]]
    c = analyse_gap(rec, seed=6, n_sims=4, bootstrap=6)
    assert [f["params_ci95"] for f in a["findings"]] != [f["params_ci95"] for f in c["findings"]]


def test_cli_prints_every_parameter_with_its_interval_and_checks_the_option(tmp_path, capsys):
    case = he.draw_case(3, effect="sinusoid", duration_s=300.0)
    path = tmp_path / "rec.csv.gz"
    write_recording(str(path), he.simulate_case(case))
    out = tmp_path / "gap.json"
    assert main(["gap", str(path), "--sims", "10", "--bootstrap", "6", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    rep = json.loads(out.read_text())
    assert rep["intervals"]["bootstrap_runs"] == 6
    f = _hit(case, rep)
    for name, value in f["params"].items():
        assert f"{name}={interval_text(value, f['params_ci95'], name)}" in printed, printed
    for bad in ("-1", "1", str(gi.MIN_REPLICATES - 1), str(gi.MAX_BOOTSTRAP + 1)):  # 1-4 runs: no interval at all
        assert main(["gap", str(path), "--bootstrap", bad, "--json", str(tmp_path / "o.json")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "--bootstrap must be 0 (no intervals) or in [5, 1000]" in err, err


def test_value_with_interval_shows_the_width():
    assert value_with_interval(31.43812, [31.43781, 31.43843]) == "31.43812 [31.43781, 31.43843]"
    assert value_with_interval(0.01215, [0.0113, 0.0131]) == "0.01215 [0.0113, 0.0131]"
    assert value_with_interval(0.01215, None) == "0.01215"


#: the slow battery's bound per kind: at a true coverage of 95 % a kind's count of 8 trials
#: falls below it with probability 0.6 % (3 misses or more), of 7 (a case not named) 4 %, of 16
#: or more trials far less
LOW_SLOW = 0.75


@pytest.mark.slow
def test_coverage_per_effect_kind():
    """8 ten-minute cases per effect kind (tests/support/battery.py: seeds 7000...; random axis
    and parameters; test_gap.py's heavy-tails battery and repeated-rows seeds score the same
    runs): the coverage per kind at least 75 % (a kind at 95 % falls below with probability
    < 1 % on 8-32 trials) and over all kinds in 90-98 % (about 240 trials: +-3 % is two binomial
    standard errors). 8 cases per kind, not 12 (the test took over a quarter of the slow run):
    the fewest that keep a one-parameter kind's bound below 1 %, and the trials over all kinds
    above the 200 of the two standard errors (measured: 226 of 239 inside, every kind at 7 of 8
    or better)."""
    per_kind = {}
    for effect in he.EFFECTS:
        for case, report in battery.cases(effect, battery.PER_KIND):
            hit = [f for f in report["findings"] if f["effect"] == effect and f["axis"] == case["axis"]]
            if not hit:
                continue
            ok, n = per_kind.get(effect, (0, 0))
            for name, interval in hit[0]["params_ci95"].items():
                if interval is not None and (name in case["params"] or name == "lag2"):  # null: not determined, no trial
                    ok, n = ok + _inside(_true(case, name), interval, name), n + 1
            per_kind[effect] = (ok, n)
    for effect, (ok, n) in per_kind.items():
        assert ok >= LOW_SLOW * n, (effect, ok, n, per_kind)
    ok, n = (sum(v[i] for v in per_kind.values()) for i in (0, 1))
    assert 0.90 * n <= ok <= 0.98 * n, per_kind


def test_intervals_stay_inside_the_parameters_domain():
    """A heavy-tailed noise at the largest fraction (half the samples at 3 times the others' sd):
    the log-scale interval of ``fraction`` reached 0.518, beyond the 0.5 a model takes (and a scale
    ratio's beyond 1000, hostile 24a). Every end of every interval is a value the model takes."""
    from gyrofilter.sim.model import validate_model

    model = json.loads((REPO / "examples" / "models" / "heavy_tails.json").read_text())
    model["axes"]["z"]["effects"] = [{"effect": "heavy_tails", "fraction": 0.5, "scale_ratio": 3.0}]
    report = analyse_gap(simulate(model, 300.0, seed=101), seed=1, n_sims=12)
    hit = [f for f in report["findings"] if f["effect"] == "heavy_tails"]
    assert hit and hit[0]["params_ci95"]["fraction"] is not None
    # cut to the domain; none where the bias correction put it wholly outside
    assert gi._interval(0.45, [0.42, 0.44, 0.46, 0.48, 0.5], "log", (0.0, 0.5)).ends[1] == 0.5
    # where the bias correction alone would put it wholly outside, the hull with the estimate is cut
    assert gi._interval(0.45, [0.3, 0.301, 0.302, 0.299, 0.3], "log", (0.0, 0.5)).ends == [0.45, 0.5]
    for f in report["findings"]:
        for end in (0, 1):
            entry = dict({k: v[end] for k, v in f["params_ci95"].items() if v is not None}, effect=f["effect"])
            validate_model({"sample_rate_hz": 100.0, "axes": {f["axis"]: {"bias_dps": 0.0, "effects": [entry]}}})


def test_the_coverage_tool_scores_the_gaps_intervals_and_the_alternatives_on_the_same_runs(capsys):
    """tools/gap_coverage.py wraps gap_intervals._interval to score other intervals on the same
    bootstrap runs; when _interval took the parameter's domain, the wrapper's old signature made
    the tool (and the docs block it writes) fail. One sinusoid case, scored by all four methods:
    the gap's own interval counted for each of its parameters, the alternatives beside it."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("gap_coverage", REPO / "tools" / "gap_coverage.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    tool.main(["--cases", "1", "--duration", "300", "--effects", "sinusoid", "--sims", "4", "--bootstrap", "6",
               "--compare"])
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("sinusoid "))
    cases, named, trials = (int(v) for v in row.split()[1:4])
    assert (cases, named, trials) == (1, 1, 3), row  # frequency, amplitude and phase of the one case
    compare = out[out.index("coverage of other intervals"):]
    assert all(m in compare for m in tool.METHODS)
    assert gi._interval.__name__ == "_interval"  # the wrapper is undone


def test_an_interval_holds_its_estimate_where_the_bias_exceeds_the_spread():
    """Replicates 20 % above the estimate with a spread of 1 %: the bias-corrected interval alone
    lies wholly below the estimate (scale_ratio=10.42 [8.5, 8.8] before); the interval given is
    its hull with the estimate, its far end the bias-corrected one. So on every scale, and after
    a step of test inversion."""
    rng = np.random.default_rng(11)
    reps = 12.5 * np.exp(0.01 * rng.standard_normal(20))
    bias_corrected = math.exp(2 * math.log(10.42) - np.log(reps).mean())  # the centre, moved down by the bias
    low, high = gi._interval(10.42, list(reps), "log").ends
    assert low < bias_corrected < 10.42 == pytest.approx(high), (low, high)
    for estimate, replicates, scale in ((0.6445, 0.5621 + 0.004 * rng.standard_normal(20), "atanh"),
                                        (-2.0, -1.0 + 0.01 * rng.standard_normal(20), "linear"),
                                        (3.0, -2.9 + 0.01 * rng.standard_normal(20), "phase")):  # bias across +-pi
        low, high = gi._interval(estimate, list(replicates), scale).ends
        assert low <= estimate <= high and estimate in (pytest.approx(low), pytest.approx(high)), (scale, low, high)
    inverted = gi.inversion_step({"p": 10.42}, [{"p": v} for v in reps],
                                 lambda at: [{"p": v} for v in at["p"] * 1.2 * np.exp(0.01 * rng.standard_normal(20))],
                                 {"p": "log"})["p"].ends
    assert inverted[0] <= 10.42 <= inverted[1], inverted


def test_a_positive_parameter_spanning_over_a_factor_100_is_not_determined():
    """A log-scale interval over two decades (b_dps 0.0033 in [3.4e-7, 1412] on a real record):
    null, and the reason names the ends; a signed parameter is never cut by the span."""
    rng = np.random.default_rng(12)
    reps = 0.0033 * np.exp(2.0 * rng.standard_normal(20))  # a spread of a factor e^2 per sd
    got = gi._interval(0.0033, list(reps), "log")
    assert got.ends is None and f"over a factor {gi.MAX_SPAN_RATIO}" in got.why, got
    narrower = gi._interval(0.0033, list(0.0033 * np.exp(0.5 * rng.standard_normal(20))), "log")
    assert narrower.ends is not None and narrower.ends[1] < gi.MAX_SPAN_RATIO * narrower.ends[0]
    assert gi._interval(0.0033, list(reps - 0.0033), "linear").ends is not None


def test_a_parameter_whose_estimator_ran_on_fewer_than_half_the_runs_is_not_determined():
    """9 of 20 runs gave an estimate (an interval from 5 before): null, the reason says how many;
    10 of 20 give an interval."""
    values = [1.0, 1.1, 0.9, 1.05, 0.95, 1.02, 0.98, 1.08, 0.93]
    got = gi._interval(1.0, values + [None] * 11, "log")
    assert got.ends is None and "9 of 20 bootstrap runs, fewer than half" in got.why, got
    assert gi._interval(1.0, values + [1.01] + [None] * 10, "log").ends is not None


def _uncertain_case():
    """Hidden spikes on y, a 2-minute record at a third of the battery's size: the tail detector
    reads them as outliers (rate 0.00125, magnitude 0.39 deg/s after its threshold correction),
    but spikes of that size in records simulated from the extended model stay below the spike
    detector's threshold on every bootstrap run, so their size is not determined. (A random walk
    read as a bias instability with an interval of 0.00015 to 0.29 deg/s served here until a
    wander no better than white was estimated as 0: one bootstrap run's stray 1e-6 had made that
    span.)"""
    return he.draw_case(103, effect="outliers", duration_s=120.0, scale=0.3)


def test_a_finding_whose_defining_parameter_is_not_determined_is_uncertain_not_named():
    """Not in findings, not in the extended model, D after of its axis without it; listed in
    uncertain with its (null) interval and why, and a note."""
    case = _uncertain_case()
    report = analyse_gap(he.simulate_case(case), seed=103, n_sims=10)
    entry = next(e for e in report["uncertain"] if e["axis"] == case["axis"])
    effect, defining = entry["effect"], BY_NAME[entry["effect"]].defining
    assert set(entry) == {"effect", "axis", "params", "params_ci95", "why"}
    assert entry["params_ci95"][defining] is None and f"its defining parameter {defining} is not determined" in entry["why"]
    assert not any(f["effect"] == effect and f["axis"] == case["axis"] for f in report["findings"])
    assert all(e["effect"] != effect for e in report["extended_model"]["axes"][case["axis"]]["effects"])
    assert f"{effect} on {case['axis']}: {defining} not determined by this record (" in " ".join(
        report["notes"])
    if not any(f["axis"] == case["axis"] for f in report["findings"]):
        d = report["discrepancy"]
        assert d["after"][case["axis"]] == d["before"][case["axis"]]
    _check_finite_and_ordered(report)


def test_the_console_and_the_reports_say_not_determined_and_list_the_uncertain(tmp_path, capsys):
    case = _uncertain_case()
    path = tmp_path / "rec.csv.gz"
    write_recording(str(path), he.simulate_case(case))
    assert main(["gap", str(path), "--sims", "10", "--json", str(tmp_path / "gap.json"),
                 "--report", str(tmp_path / "md")]) == 0
    printed = capsys.readouterr().out
    rep = json.loads((tmp_path / "gap.json").read_text())
    entry = rep["uncertain"][0]
    assert "(not determined)" in params_text(entry)
    markdown = (tmp_path / "md" / "gap_report.md").read_text()
    for text in (" ".join(printed.split()), markdown):
        assert "Suggested but not established" in text and uncertain_text(entry) in text.replace(" = ", "=")
    assert main(["report", str(path), "--sims", "10", "--out", str(tmp_path / "r.html")]) == 0
    page = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert "<h3>Suggested but not established</h3>" in page and html.escape(uncertain_text(entry, sep=" = ")) in page


def test_interval_text_says_not_determined_for_a_null_interval():
    assert interval_text(0.0033, {"b_dps": None}, "b_dps") == "0.0033 (not determined)"
    assert interval_text(0.0033, None, "b_dps") == "0.0033"  # no intervals at all (--bootstrap 0)
    assert interval_text(0.0033, {"b_dps": [0.003, 0.004]}, "b_dps") == "0.0033 [0.003, 0.004]"


def test_a_wandering_tone_read_short_takes_the_step_of_test_inversion_and_its_centre_the_plain_interval(monkeypatch):
    """Case 16001 of the coverage tool's tones (10 min): a tone whose frequency wanders with a
    correlation time of 142 s, a quarter of the record, so its spread reads 0.14 Hz for 0.38. The
    plain interval of the spread ([0.091, 0.256]) missed it; one step of test inversion (the
    track is a Gauss-Markov process, module docstring of gap.intervals) holds it. The centre, a
    location parameter, keeps its plain interval: the same as without the step."""
    case = he.draw_case(16001, effect="wandering_tone", duration_s=600.0)
    rec = he.simulate_case(case)
    report = analyse_gap(rec, seed=16001, n_sims=SIMS)
    f = _hit(case, report)
    assert _inside(case["params"]["spread_hz"], f["params_ci95"]["spread_hz"], "spread_hz"), (case["params"], f)
    monkeypatch.setattr(gi, "INVERTED", tuple(e for e in gi.INVERTED if e != "wandering_tone"))
    plain = _hit(case, analyse_gap(rec, seed=16001, n_sims=SIMS))
    assert not _inside(case["params"]["spread_hz"], plain["params_ci95"]["spread_hz"], "spread_hz")
    assert plain["params_ci95"]["center_hz"] == f["params_ci95"]["center_hz"]


def test_the_inversion_runs_only_the_estimators_its_finding_reads(monkeypatch):
    """The test inversion reads one finding's replicates (gap.intervals): ``reestimate_axis`` with
    ``wanted`` gives those findings the estimates of the full run, without the estimators they do not
    read (the resonance's fit beside a wandering tone), and still with the ones they do (the colored
    noise's lags read the bands')."""
    import scipy.signal

    from gyrofilter.analysis.gap import detectors as det
    from gyrofilter.analysis.gap.reestimate import reestimate_axis

    rng = np.random.default_rng(3)
    t = np.arange(8192) / 100.0
    tone = 0.3 * np.sin(2 * np.pi * (20.0 * t + 0.5 * np.sin(2 * np.pi * t / 30.0)))
    x = scipy.signal.lfilter([1.0], [1.0, -0.5], 0.3 * rng.standard_normal(t.size)) + tone + 0.2 * np.sin(2 * np.pi * 3.1 * t)
    cands = [det.Candidate(effect, params, 0.0, 0.0, "") for effect, params in
             [("sinusoid", {"frequency_hz": 3.1}), ("wandering_tone", {}), ("resonance", {}), ("colored_noise", {"lag1": 0.2})]]
    full = reestimate_axis(x, 100.0, None, cands)
    assert all(e is not None for e in full), full
    assert reestimate_axis(x, 100.0, None, cands, wanted=[3]) == full  # the lags read every band
    fits = []
    monkeypatch.setattr(det, "resonance_fit", lambda *args, **kwargs: fits.append(args))
    assert reestimate_axis(x, 100.0, None, cands, wanted=[1]) == [full[0], full[1], None, None]
    assert fits == []


#: the package's model (gyrofilter/data/mpu6050_model.json): a bias instability and a temperature
#: coefficient on every axis
PACKAGE_MODEL = REPO / "gyrofilter" / "data" / "mpu6050_model.json"


def _true_effect(model, axis, effect, name):
    return next(e[name] for e in model["axes"][axis]["effects"] if e["effect"] == effect)


def _package_temperature(duration_s):
    """The package model's record of ``duration_s`` (seed 4) and its x temperature finding at the true coefficient."""
    from gyrofilter.analysis.gap.detectors.common import Candidate

    model = json.loads(PACKAGE_MODEL.read_text())
    rec = simulate(model, duration_s, seed=4, accelerometer=False)
    temp = np.asarray(rec.temp_c, dtype=float)
    coefficient = _true_effect(model, "x", "temperature", "coefficient_dps_per_c")
    return model, rec, Candidate("temperature", {"coefficient_dps_per_c": coefficient}, 0.0, 0.0, "",
                                 component=coefficient * (temp - temp.mean()))


def test_a_temperature_findings_replicates_carry_the_wander_its_axis_holds_but_does_not_name():
    """Issue 37: the bootstrap of a temperature finding on an axis that names no wander simulated
    white noise about the coefficient, and the axis's bias instability (real, unnamed) was missing
    from its spread. The replicates now carry the wander at the upper end of its confidence set: on x
    of the package model's 10-minute record, seed 4 (b_dps 0.0015), that B is within a factor 3 of
    the truth and not below the maximum likelihood estimate; none where the axis names a wander or
    has no temperature finding."""
    from types import SimpleNamespace

    from gyrofilter.analysis.gap.baseline import axis_dps
    from gyrofilter.analysis.gap.detectors.common import Candidate
    from gyrofilter.analysis.gap.detectors.slow import stochastic_fits
    from gyrofilter.analysis.stats import block_means

    model, rec, temperature = _package_temperature(600.0)
    inp = SimpleNamespace(rec=rec, sample_rate_hz=rec.sample_rate_hz)
    (wander,) = gi.unnamed_wander(inp, 0, [temperature])
    b_dps = _true_effect(model, "x", "bias_instability", "b_dps")
    assert wander["effect"] == "bias_instability" and b_dps / 3 < wander["b_dps"] < 3 * b_dps, wander
    y, length = block_means(axis_dps(rec, 0).astype(float) - temperature.component)
    mle = stochastic_fits(y, length / rec.sample_rate_hz, ("bias_instability",))[0]["bias_instability"][1][0]
    assert wander["b_dps"] >= math.sqrt(mle), (wander, math.sqrt(mle))
    named = Candidate("bias_instability", {"b_dps": b_dps}, 0.0, 0.0, "")
    assert gi.unnamed_wander(inp, 0, [temperature, named]) == []
    assert gi.unnamed_wander(inp, 0, [Candidate("rate_ramp", {"r_dps_per_s": 1e-5}, 0.0, 0.0, "")]) == []


def test_the_unnamed_wander_is_judged_without_the_spikes_its_axis_names():
    """Attack pass 37j: one 150 deg/s spike (named outliers) stayed in the block means the unnamed
    wander's upper bound is read from: B 0.0011 -> 0.017 deg/s on a 300-s record, and the temperature
    finding's replicates, simulated with that wander, moved it to uncertain (coefficient 0.029 [0.023,
    0.034] -> [-0.042, 0.093]). The spikes are cleaned as the replicates' estimators clean them."""
    from types import SimpleNamespace

    from gyrofilter.analysis.gap import detectors as det

    _, rec, temperature = _package_temperature(300.0)
    inp = SimpleNamespace(rec=rec, sample_rate_hz=rec.sample_rate_hz, q=1.0 / rec.lsb_per_dps)
    (clean,) = gi.unnamed_wander(inp, 0, [temperature])
    rec.columns["gx"][15_000] += 150.0 * rec.lsb_per_dps
    spikes, _ = det.detect_outliers(np.asarray(rec.columns["gx"], dtype=float) / rec.lsb_per_dps, inp.q)
    (spiked,) = gi.unnamed_wander(inp, 0, [spikes, temperature])
    assert spiked["b_dps"] == pytest.approx(clean["b_dps"], rel=0.05), (spiked, clean)


@pytest.mark.slow
def test_temperature_coefficients_of_the_package_model_lie_inside_their_intervals():
    """Issue 37: the package model's 10-minute records, seeds 0-7: the temperature coefficient named
    on an axis lies inside its interval on at least 90 % of the findings. Before the replicates
    carried the unnamed wander, 16 of 19 (seed 2's y, seed 4's x and y missed: x 0.02 outside
    [0.0161, 0.0188]); measured after, on seeds 0-19: 44 of 45 (98 %; before, 35 of 45)."""
    model = json.loads(PACKAGE_MODEL.read_text())
    ok = n = 0
    for seed in range(8):
        report = analyse_gap(simulate(model, 600.0, seed=seed, accelerometer=False))  # as the commands run it
        for f in report["findings"]:
            if f["effect"] == "temperature":
                low, high = f["params_ci95"]["coefficient_dps_per_c"]
                ok, n = ok + (low <= _true_effect(model, f["axis"], "temperature", "coefficient_dps_per_c") <= high), n + 1
    assert n >= 12 and ok >= 0.9 * n, (ok, n)


def _named_temperatures(model, duration_s, seeds):
    """``[(seed, axis, truth, [low, high])]`` of the temperature findings named on the package
    model's records of ``duration_s``, as the commands run them."""
    out = []
    for seed in seeds:
        report = analyse_gap(simulate(model, duration_s, seed=seed, accelerometer=False))
        out.extend((seed, f["axis"], _true_effect(model, f["axis"], "temperature", "coefficient_dps_per_c"),
                    f["params_ci95"]["coefficient_dps_per_c"]) for f in report["findings"] if f["effect"] == "temperature")
    return out


def test_a_temperature_named_on_a_short_record_holds_its_truth_in_its_interval():
    """Issue 37: on the package model's 2-minute records the unnamed wander's estimate is mostly 0
    (the coefficient's fit takes its drift), so the replicates were white noise about the selected
    large coefficient: seed 41's x named 0.040 deg/s per deg C with [0.0278, 0.0505], the truth 0.02
    outside. The replicates now carry the wander at the upper end of its confidence set."""
    model = json.loads(PACKAGE_MODEL.read_text())
    (found,) = _named_temperatures(model, 120.0, [41])
    _, axis, truth, (low, high) = found
    assert axis == "x" and low <= truth <= high, found


#: the seeds of 0-199 whose 2-minute record of the package model named a temperature before the unnamed
#: wander was taken at its upper bound (the others name none, before or after: 200 records take 15 minutes)
SHORT_TEMPERATURE_SEEDS = (3, 5, 7, 32, 33, 35, 41, 53, 57, 58, 62, 69, 70, 71, 73, 80, 86, 89, 114, 122, 130, 147,
                           148, 149, 153, 157, 173, 176, 178, 190, 199)


@pytest.mark.slow
def test_temperatures_named_on_short_records_hold_their_truth_at_about_the_nominal_rate():
    """Issue 37: the package model's 2-minute records: a named temperature coefficient lies inside its
    interval on at least 80 % of the findings. Seeds 0-199: before the unnamed wander was taken at its
    upper bound, 16 of 31 (52 %); after, 16 of 18 (89 %), 13 moved to uncertain. Run on the seeds that
    named one before (:data:`SHORT_TEMPERATURE_SEEDS`)."""
    model = json.loads(PACKAGE_MODEL.read_text())
    found = _named_temperatures(model, 120.0, SHORT_TEMPERATURE_SEEDS)
    inside = [low <= truth <= high for _, _, truth, (low, high) in found]
    assert len(found) >= 12 and sum(inside) >= 0.8 * len(found), found
