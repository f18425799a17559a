"""Human report of a gap analysis: Markdown plus PNG figures (matplotlib imported lazily).

``write_report(report, rec, out_dir)`` writes ``out_dir/gap_report.md`` and, per axis:

* ``adev_<axis>.png`` -- measured Allan deviation, the baseline simulations' spread (mean +-
  2 sd of log ADEV) and the extended model's spread;
* ``spectrum_<axis>.png`` -- band powers of the periodogram, same three;
* ``temperature_<axis>.png`` -- block-mean rate minus bias against block-mean temperature (when
  the recording has a ``temp`` column);
* ``time_<axis>.png`` -- block means of the rate in time with the found deterministic shapes
  (step, warm-up, ramp, temperature) when the axis has one besides the temperature, or a
  finding with ``alternatives`` (their shapes dashed: how the other reading would look).

Each finding is listed with its parameters and their 95 % intervals (:func:`params_text`), its
evidence sentence and its gain; then the effects the record suggests but does not establish
(the report's ``uncertain``, :func:`uncertain_text`).
"""
from __future__ import annotations

import math
import os

import numpy as np

from ...effects import BIAS_STEP, COVARIATES, RATE_RAMP, SHAPES, TEMPERATURE, WARMUP
from ...errors import naming_file
from ...plots import pyplot, save_figure
from ...recording.header import markdown_text
from ...tempscreen import screened_temp
from ...units import AXES, utf8_text
from .confound import CONFOUNDED_SPREADS, NAMED_BECAUSE, WHY_THE_COVARIATE, effect_shown
from .features import D_FAR, d_shown

REPORT_NAME = "gap_report.md"
FIGURE_KINDS = ("adev", "spectrum", "temperature", "time")


def report_file_names():
    """Every file name :func:`write_report` may write (which figures it draws depends on the findings)."""
    return [REPORT_NAME] + [_figure(kind, a) for kind in FIGURE_KINDS for a in AXES]


def _figure(kind, axis):
    return f"{kind}_{axis}.png"


def _band_centres(edges):
    e = np.asarray(edges, dtype=float)
    return np.sqrt(np.maximum(e[:-1], 1e-12) * e[1:])


def _finish(fig, ax, path, xlabel, ylabel, title):
    """Labels, grid, legend; save as PNG and close."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def _plot_spread(x, dep, key, axis, path, *, xlabel, ylabel, title):
    """Measurement, baseline simulations' spread and extended model's spread (mean +- 2 sd
    of the log feature ``key``: 'adev' or 'band')."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    m, s = np.asarray(dep[f"{key}_sim_mean_log"]), np.asarray(dep[f"{key}_sim_sd_log"])
    ax.fill_between(x, np.exp(m - 2 * s), np.exp(m + 2 * s), color="0.8", label="baseline simulations (mean +- 2 sd)")
    ax.loglog(x, np.exp(m), color="0.5", lw=1)
    if f"extended_{key}_sim_mean_log" in dep:
        me, se = np.asarray(dep[f"extended_{key}_sim_mean_log"]), np.asarray(dep[f"extended_{key}_sim_sd_log"])
        ax.fill_between(x, np.exp(me - 2 * se), np.exp(me + 2 * se), color="tab:green", alpha=0.3,
                        label="extended model (mean +- 2 sd)")
    ax.loglog(x, np.exp(dep[f"{key}_meas_log"]), "k.-", lw=1.2, label="measurement")
    _finish(fig, ax, path, xlabel, ylabel, f"axis {axis}: {title}")


def plot_adev(dep, axis, path):
    _plot_spread(np.asarray(dep["adev_tau_s"]), dep, "adev", axis, path, xlabel="tau (s)",
                 ylabel="Allan deviation (deg/s)", title="Allan deviation")


def plot_spectrum(dep, axis, path):
    _plot_spread(_band_centres(dep["band_edges_hz"]), dep, "band", axis, path, xlabel="frequency (Hz)",
                 ylabel="mean periodogram in band ((deg/s)^2 per bin)", title="spectrum (log-spaced bands)")


def _blocks(v, n_blocks=600):
    v = np.asarray(v, dtype=float)
    length = max(1, v.size // n_blocks)
    n = v.size // length
    return v[: n * length].reshape(n, length).mean(axis=1), length


def plot_temperature(x, temp, axis, coef, path):
    plt = pyplot()
    y, _ = _blocks(x - np.mean(x))
    tb, _ = _blocks(temp)
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    ax.plot(tb, y, ".", ms=3, color="k", label="block means of the rate")
    if coef is not None:
        tt = np.linspace(tb.min(), tb.max(), 10)
        ax.plot(tt, coef * (tt - np.mean(temp)), "r-", label=f"fit: {coef:+.3g} deg/s per deg C")
    _finish(fig, ax, path, "sensor temperature (deg C)", "rate minus mean (deg/s)",
            f"axis {axis}: rate against temperature")


_SHAPES = SHAPES + COVARIATES


def _shape(findings, t, temp_blocks, ax=None):
    """The deterministic shapes of ``findings`` on the block times ``t`` (deg/s; the
    temperature's on the block-mean temperature ``temp_blocks``); a step's time marked on ``ax``."""
    shape = np.zeros_like(t)
    for f in findings:
        p = f["params"]
        if f["effect"] == BIAS_STEP:
            shape += p["size_dps"] * (t >= p["time_s"])
            if ax is not None:
                ax.axvline(p["time_s"], color="r", ls=":", lw=1)
        elif f["effect"] == WARMUP:
            shape += p["amplitude_dps"] * np.exp(-t / p["tau_s"])
        elif f["effect"] == RATE_RAMP:
            shape += p["r_dps_per_s"] * t
        elif f["effect"] == TEMPERATURE and temp_blocks is not None:
            shape += p["coefficient_dps_per_c"] * temp_blocks
    return shape


def plot_time(x, sample_rate_hz, axis, findings, path, temp=None, alternatives=()):
    """Block means of the rate in time with the found deterministic shapes (solid) and those of
    an alternative reading (``alternatives``: entries of a finding's ``alternatives``, dashed)."""
    plt = pyplot()
    y, length = _blocks(x)
    t = (np.arange(y.size) + 0.5) * length / sample_rate_hz
    tb = _blocks(temp)[0][:y.size] if temp is not None else None
    fig, ax = plt.subplots(figsize=(7.0, 4.0))
    ax.plot(t, y, "k-", lw=0.8, label=f"block means ({length / sample_rate_hz:.3g} s)")
    for group, style, words in ((findings, "r-", "found: "), (alternatives, "b--", "alternative reading: ")):
        shape = _shape(group, t, tb, ax if style == "r-" else None)
        if np.ptp(shape) > 0:
            shape += np.mean(y) - np.mean(shape)
            ax.plot(t, shape, style, lw=1.5, label=words + ", ".join(f["effect"] for f in group if f["effect"] in _SHAPES))
    _finish(fig, ax, path, "time (s)", "rate (deg/s)", f"axis {axis}: rate in time")


def covariate_preamble(findings):
    """The sentence said once before the findings where some of them cannot be told apart from a
    reading in time (their evidence ends with :data:`~gyrofilter.analysis.gap.confound.WHY_THE_COVARIATE`),
    or None; :func:`evidence_text` leaves it out of each finding."""
    if not any(WHY_THE_COVARIATE in f["evidence"] for f in findings):
        return None
    return f"Some findings below cannot be told apart in this record from a reading in time (shown under them). {WHY_THE_COVARIATE}."


def not_analysed_why(report):
    """Why the gap ``report`` analysed no axis (each axis's reason, or the analysis's first note: a
    record too short), or None where one was: ``gyrofilter gap`` exits 2 there, and a report says so."""
    d = report.get("discrepancy")
    if d and d["overall_before"] is not None:
        return None
    return ("; ".join(f"{a}: {text}" for a, text in d["not_analysed"].items()) if d
            else report["notes"][0] if report.get("notes") else "no discrepancy computed")


def no_findings_text(report):
    """What a report says where the gap ``report`` has no finding: that the baseline explains the
    axes analysed, or, where none was (:func:`not_analysed_why`), that nothing was compared with it."""
    why = not_analysed_why(report)
    if why is not None:
        return f"None: no axis was analysed ({why}); nothing was compared with the baseline."
    idle = report["discrepancy"]["not_analysed"]
    over = f" on the axes analysed ({', '.join(a for a in AXES if a not in idle)})" if idle else ""
    return f"None: the baseline explains the measurement{over} within the simulations' spread."


def evidence_text(finding):
    """A finding's evidence less the sentence :func:`covariate_preamble` says once for all."""
    return finding["evidence"].replace(f". {WHY_THE_COVARIATE}", "")


def indistinguishable_text(finding, *, figure=False):
    """The line under a finding with ``alternatives`` (console, Markdown and HTML reports): the
    reading it cannot be told apart from, and why it is the one named
    (:data:`~gyrofilter.analysis.gap.confound.NAMED_BECAUSE`: the measured covariate; of two
    wanders the one with fewer parameters); where the other reading has a shape in time and the
    caller draws it (``figure``: the Markdown report's rate in time), that the figure shows both."""
    shaped = figure and any(e["effect"] in _SHAPES for e in finding["alternatives"])
    why = NAMED_BECAUSE.get(finding["effect"])
    reading = finding["alternatives"][0].get("in_place_of", [finding["effect"]])
    instead = "instead" if reading == [finding["effect"]] else "in place of " + " + ".join(reading)
    return (f"Indistinguishable in this record from {alternatives_text(finding['alternatives'])} (D of the axis with it "
            f"{instead}, within the allowance of {CONFOUNDED_SPREADS:g} null spreads of D); {finding['effect']} is named"
            + (f": {why}" if why else "")
            + ("; the figure of the rate in time shows both readings" if shaped else ""))


def d_text(value, se):
    """D with the digits its sampling error ``se`` supports: rounded to the error's first
    significant digit (its first two where that digit is 1), ``D +- se``; three significant digits
    where the error is 0 (fewer than 3 simulations); far outside as :func:`~.features.d_shown` says it."""
    if value > D_FAR:
        return d_shown(value)
    if not se > 0:
        return f"{value:.3g}"
    digits = -int(math.floor(math.log10(se)))
    if int(se * 10 ** digits) < 2:
        digits += 1
    digits = max(digits, 0)
    return f"{value:.{digits}f} +- {se:.{digits}f}"


def alternatives_text(alternatives):
    """``effect (k = v, ...) + ...: D d`` of a finding's ``alternatives`` (one reading: the entries share D)."""
    parts = [effect_shown(e["effect"], e["params"]) for e in alternatives]
    return " + ".join(parts) + f": D {d_shown(alternatives[0]['D'])}"


def _fmt(v):
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def value_with_interval(value, interval):
    """``value [low, high]`` with as many significant digits as show the interval's width to two
    digits (at least 4, at most 10); ``value`` alone (4 digits) without an interval."""
    if not interval:
        return f"{value:.4g}"
    low, high = interval
    width = abs(high - low)
    top = max(abs(value), abs(low), abs(high))
    digits = 4
    if width > 0 and top > 0:
        digits = int(min(10, max(4, math.floor(math.log10(top)) - math.floor(math.log10(width)) + 2)))
    return f"{value:.{digits}g} [{low:.{digits}g}, {high:.{digits}g}]"


def interval_text(value, intervals, name):
    """The parameter ``name`` of value ``value`` with its interval from ``intervals`` (a
    ``params_ci95``: :func:`value_with_interval`): the value alone where the report has no
    intervals (``intervals`` None), ``value (not determined)`` where its interval is null (the
    record does not determine it, docs/formats.md section 3)."""
    if intervals is not None and intervals.get(name) is None:
        return f"{value:.4g} (not determined)"
    return value_with_interval(value, (intervals or {}).get(name))


def params_text(finding, sep="="):
    """A finding's parameters (or an ``uncertain`` entry's), each with its 95 % interval where the
    report has one: ``frequency_hz=31.4381 [31.4378, 31.4384], ...`` (``sep`` between name and
    value; :func:`interval_text`)."""
    ci = finding.get("params_ci95")
    return ", ".join(f"{k}{sep}{interval_text(v, ci, k)}" for k, v in finding["params"].items())


#: the heading of the report's ``uncertain`` entries (console, Markdown and HTML reports)
UNCERTAIN_HEADING = "Suggested but not established"


def uncertain_text(entry, sep="="):
    """An entry of the report's ``uncertain``: ``effect on axis (params): why``."""
    return f"{entry['effect']} on {entry['axis']} ({params_text(entry, sep)}): {entry['why']}"


def write_report(report, rec, out_dir):
    """Write the Markdown report and figures; returns the Markdown path."""
    os.makedirs(out_dir, exist_ok=True)
    g = rec.gyro_dps
    sample_rate_hz = rec.sample_rate_hz
    temp = None if rec.temp_c is None else screened_temp(rec.temp_c, sample_rate_hz)[0]  # as the analysis took it
    lines = [f"# Model-gap report: {markdown_text(report['recording'])}", "",
             f"{report['duration_s']:.1f} s at {report['sample_rate_hz']:g} Hz; "
             f"{report.get('n_simulations', 0)} baseline simulations; "
             f"runtime {report.get('runtime_s', float('nan')):.1f} s.", "",
             "## Baseline (constant bias + white noise + rounding to the LSB step)", "",
             "| axis | bias (deg/s) | ARW (deg/s/sqrt(Hz)) | LSB step (deg/s) | discrepancy D before | after |",
             "|---|---|---|---|---|---|"]
    disc = report.get("discrepancy", {})
    for a in AXES:
        b = report["baseline"]["axes"][a]
        bias, arw = ([interval_text(b[k], b.get("params_ci95"), k) if b.get(k) is not None else "-"
                      for k in ("bias_dps", "arw_dps_per_sqrt_hz")])
        d_before, d_after = (("not analysed",) * 2 if a in disc.get("not_analysed", {}) else
                             (_fmt(disc.get("before", {}).get(a)), _fmt(disc.get("after", {}).get(a))))
        lines.append(f"| {a} | {bias} | {arw} | {_fmt(b.get('quantization_dps'))} | {d_before} | {d_after} |")
    lines += ["", f"Discrepancy D: {disc.get('definition', '')} (lower is better; about 1 when the "
              "model explains the measurement).", "", "## Findings", ""]
    intervals = report.get("intervals") or {}
    if report["findings"] and intervals.get("bootstrap_runs"):
        lines += [f"Each parameter with its {100 * intervals['confidence']:.0f} % interval in brackets "
                  f"({intervals['bootstrap_runs']} bootstrap runs per axis with findings"
                  + "".join(f", {n} on {a}" for a, n in (intervals.get("bootstrap_runs_by_axis") or {}).items()
                            if n != intervals["bootstrap_runs"]) + "; docs/gap.md).", ""]
    if not report["findings"]:
        lines.append(no_findings_text(report))
    if covariate_preamble(report["findings"]):
        lines += [covariate_preamble(report["findings"]), ""]
    for f in report["findings"]:
        lines += [f"- **{f['effect']}** on **{f['axis']}**: {params_text(f, ' = ')}.",
                  f"  Gain: D {d_shown(f['gain']['before'])} -> {d_shown(f['gain']['after'])}."]
        if f.get("alternatives"):
            lines.append(f"  {indistinguishable_text(f, figure=True)}.")
        lines.append(f"  Evidence: {evidence_text(f)}.")
    if report.get("uncertain"):
        lines += ["", f"{UNCERTAIN_HEADING} (not in the extended model):", ""]
        lines += [f"- {uncertain_text(e, ' = ')}." for e in report["uncertain"]]
        lines.append("")
    for note in report.get("notes", []):
        lines.append(f"- note: {note}")
    lines += ["", "## Figures", ""]
    deps = report.get("departures", {})
    for i, a in enumerate(AXES):
        dep = deps.get(a)
        if not dep:
            continue
        plot_adev(dep, a, os.path.join(out_dir, _figure("adev", a)))
        plot_spectrum(dep, a, os.path.join(out_dir, _figure("spectrum", a)))
        lines += [f"### axis {a}", "", f"![Allan deviation {a}]({_figure('adev', a)}) ![spectrum {a}]({_figure('spectrum', a)})", ""]
        fa = [f for f in report["findings"] if f["axis"] == a]
        if temp is not None and np.ptp(temp) > 0:
            coef = next((f["params"]["coefficient_dps_per_c"] for f in fa if f["effect"] == TEMPERATURE), None)
            plot_temperature(g[:, i], temp, a, coef, os.path.join(out_dir, _figure("temperature", a)))
            lines += [f"![rate vs temperature {a}]({_figure('temperature', a)})", ""]
        slow = [f for f in fa if f["effect"] in _SHAPES]
        alternatives = [e for f in fa for e in f.get("alternatives", []) if e["effect"] in _SHAPES]  # a wander has no shape
        if any(f["effect"] != TEMPERATURE for f in slow) or alternatives:
            plot_time(g[:, i], sample_rate_hz, a, slow, os.path.join(out_dir, _figure("time", a)), temp=temp,
                      alternatives=alternatives)
            lines += [f"![rate in time {a}]({_figure('time', a)})", ""]
    path = os.path.join(out_dir, REPORT_NAME)
    with naming_file(path), open(path, "w", encoding="utf-8") as fh:
        fh.write(utf8_text("\n".join(lines) + "\n"))  # the recording's name may be a file name that is not UTF-8
    return path
