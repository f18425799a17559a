"""The sensor report of ``gyrofilter report``: one self-contained HTML page (docs/report.md).

:func:`report_page` turns the report's data (:func:`report_data`: the ``allan --json`` and
``gap --json`` documents as those commands write them, replay's filter summary, the warnings)
and the filter's min/max envelopes into the page. Everything shown is read from that data,
which the page also carries whole in ``<script type="application/json" id="report-data">``
(docs/formats.md, section 10), so that the numbers a reader sees are the numbers a program
reads. The figures are inline SVG (:mod:`gyrofilter.view.svg`); the page loads nothing (no
URL, no script to run), so it reads offline, attached to a bug report or a mail.

A pure function of its arguments: numbers in, text out; nothing here reads a file or prints.
"""
from __future__ import annotations

import json

import numpy as np

from ..effects import ROWS
from ..analysis.gap.report import (UNCERTAIN_HEADING, covariate_preamble, evidence_text, indistinguishable_text,
                                   no_findings_text, not_analysed_why, params_text, uncertain_text)
from ..analysis.gap.baseline import default_n_sims, default_n_sims_why
from ..analysis.noise.export import ACCEL_JSON, GYRO_JSON
from ..analysis.noise.model import TERMS, TERM_SLOPE, TERM_SYMBOL, basis, model_adev
from ..units import AXES
from .svg import Band, Line, figure, html_text

#: the format of the embedded data block (docs/formats.md, section 10)
FORMAT = "gyrofilter-report 1"
#: the id of the embedded data block
DATA_ID = "report-data"
AXIS_COLOURS = {"x": "#c0392b", "y": "#27864a", "z": "#2e5fa8"}
#: the header keys the summary shows, in this order (the data block has the whole header)
SUMMARY_KEYS = ("sensor", "chip_id", "full_scale_dps", "dlpf_cfg", "start_time_utc", "live_source", "recorded_by",
                "description")
_LONG_TEXT = 400  # characters of a header value the summary shows

#: why the gap baseline's white level (ARW) and the Allan fit's N differ for one axis, said where both stand
WHITE_LEVELS = ("Two white-noise levels, two meanings: the ARW here is the per-sample scatter of the noise faster "
                "than about 0.5 s, over sqrt(sample rate): all that a white-noise-only model must reproduce, spectral "
                "lines and colored noise included (the findings below name them); the Allan N above is the density "
                "of the tau^-1/2 slope the Allan fit reads at cluster times where such fast noise has averaged out. "
                "They agree for pure white noise. Likewise the LSB step here (deg/s) is the rounding of the recorded "
                "unit, and the Allan Q above (deg) the quantization noise the Allan curve shows.")

_STYLE = """
body { font-family: sans-serif; margin: 0 auto; padding: 0 16px 32px; max-width: 1180px; color: #222; line-height: 1.4; }
h1 { font-size: 1.5em; margin-top: 18px; } h2 { border-bottom: 1px solid #ccc; margin-top: 28px; } h3 { margin-bottom: 4px; }
table { border-collapse: collapse; margin: 8px 0; } td, th { border: 1px solid #ccc; padding: 3px 8px; vertical-align: top; }
th { background: #f2f2f2; text-align: left; } td.num { text-align: right; font-family: monospace; white-space: nowrap; }
.figures { display: grid; grid-template-columns: repeat(auto-fit, minmax(320px, 1fr)); gap: 12px; }
.warnings li { margin: 4px 0; } .warnings { background: #fff6e0; border: 1px solid #e0b050; padding: 8px 8px 8px 28px; }
.ok { background: #eaf6ea; border: 1px solid #8c8; padding: 8px; } .small { font-size: 0.9em; color: #555; }
.scroll { overflow-x: auto; } code { white-space: nowrap; }
"""


def report_data(*, recording, allan, gap, filter_summary, warnings, options, version, allan_error=None,
                filter_error=None, allan_and_gap=()):
    """The report's data block (docs/formats.md, section 10): ``allan`` (the ``allan --json``
    document, None when allan refused the record: ``allan_error`` says why), ``gap`` (the ``gap
    --json`` document), ``filter_summary`` (:meth:`~gyrofilter.cli.replay.Replay.summary`, None
    with ``filter_error``), ``recording`` (name, header, samples, duration), the ``warnings``
    (lines of text), the ``options`` that change numbers, the gyrofilter ``version``, and
    ``allan_and_gap``: where the two analyses disagree (:func:`gyrofilter.analysis.agreement.compare`)."""
    return {"format": FORMAT, "gyrofilter_version": version, "recording": recording, "options": options,
            "warnings": list(warnings), "filter": filter_summary, "filter_error": filter_error,
            "allan": allan, "allan_error": allan_error, "gap": gap, "allan_and_gap": list(allan_and_gap)}


def report_page(data, raw_envelope=None, filtered_envelope=None):
    """The HTML page (text) of the report ``data`` (:func:`report_data`), with the filter's
    trace drawn from the :class:`~gyrofilter.streamstats.Envelope` of the raw samples minus the
    start-up bias and of the filtered rows (none without them)."""
    rec = data["recording"]
    title = f"gyrofilter sensor report: {rec['name']}"
    parts = ["<!DOCTYPE html>", "<html lang='en'><head><meta charset='utf-8'>",
             "<meta name='viewport' content='width=device-width, initial-scale=1'>",
             f"<title>{html_text(title)}</title><style>{_STYLE}</style></head><body>",
             f"<h1>{html_text(title)}</h1>",
             _summary(data), _warnings(data["warnings"]), _filter(data, raw_envelope, filtered_envelope),
             _allan(data), _gap(data), _allan_and_gap(data.get("allan_and_gap")),
             "<p class='small'>Made by gyrofilter " + html_text(data["gyrofilter_version"]) + " (<code>gyrofilter report</code>). "
             f"Every number above is in the JSON block <code>#{DATA_ID}</code> of this file (docs/formats.md, "
             "section 10): the documents of <code>allan --json</code> and <code>gap --json</code> as those commands "
             "write them, and replay's filter summary.</p>",
             f"<script type='application/json' id='{DATA_ID}'>{embedded_json(data)}</script>",
             "</body></html>"]
    return "\n".join(parts) + "\n"


def embedded_json(data):
    """``data`` as JSON that can sit inside a script element: every ``<`` written as ``\\u003c``
    (the same JSON value), so that no text in it ends the element."""
    return json.dumps(data, allow_nan=False, separators=(",", ":")).replace("<", "\\u003c")


def _summary(data):
    rec, opts = data["recording"], data["options"]
    header = rec["header"]
    rows = [("file", rec["name"]), ("samples", f"{rec['samples']} at {_num(header.get('sample_rate_hz'))} Hz "
                                                f"({rec['duration_s']:.1f} s)"),
            ("unit in the file", header.get("gyro_unit", "") + (f", {header['lsb_per_dps']} LSB per deg/s"
                                                                  if header.get("lsb_per_dps") else ""))]
    if header.get("accel_unit"):
        rows.append(("accelerometer unit in the file", header["accel_unit"] + (f", {header['lsb_per_g']} LSB per g"
                                                                               if header.get("lsb_per_g") else "")))
    for key in SUMMARY_KEYS:
        if key in header:
            text = str(header[key])
            rows.append((key, text if len(text) <= _LONG_TEXT else text[:_LONG_TEXT] + " ..."))
    if rec.get("t_gaps"):
        rows.append(("gaps in t", f"{rec['t_gaps']} step(s) longer than 1.5 sample intervals"))
    gap = data.get("gap")
    ran = (gap or {}).get("n_simulations") or opts["sims"] or default_n_sims(rec["samples"])
    sims = ("no gap simulation ran (no axis analysed)" if gap and not_analysed_why(gap) is not None else
            "--sims " + (f"{ran}" if opts["sims"] else f"{ran} ({default_n_sims_why(rec['samples'])})"))
    rows.append(("options", sims + (", --keep-outliers" if opts["keep_outliers"] else "")))
    return "<h2>Recording</h2>" + _table(["", ""], rows, header_row=False)


def _warnings(warnings):
    if not warnings:
        return "<h2>Warnings</h2><p class='ok'>None: the record looks still, whole and unclipped.</p>"
    return "<h2>Warnings</h2><ul class='warnings'>" + "".join(f"<li>{html_text(w)}</li>" for w in warnings) + "</ul>"


def _filter(data, raw_envelope, filtered_envelope):
    out = ["<h2>The default filter's effect</h2>"]
    s = data["filter"]
    if s is None:
        return out[0] + f"<p>Not filtered: {html_text(data['filter_error'])}</p>"
    bias = ("start-up bias " + ", ".join(f"{b:+.4f}" for b in s["bias_dps"]) + f" deg/s ({s['calibration_samples']} "
            "samples)") if s["bias_dps"] is not None else "no start-up calibration"
    out.append(f"<p>Preset <b>{html_text(s['preset'])}</b>, as <code>gyrofilter replay</code> runs it: {s['samples_in']} "
               f"samples in at {html_text(_num(s['sample_rate_hz']))} Hz, {s['rows_out']} rows out at {html_text(_num(s['output_rate_hz']))} Hz; "
               f"{bias}. Raw: the samples after the calibration window that made a row, bias included; filtered: "
               "the rows, bias removed (deg/s).</p>")
    rows = [(a, _num(s["raw_mean_dps"][i]), _num(s["raw_std_dps"][i]), _num(s["filtered_mean_dps"][i]),
             _num(s["filtered_std_dps"][i]), _num(s["std_ratio"][i], ".3g") + "x" if s["std_ratio"][i] is not None else "-",
             str(s["rejected"][i])) for i, a in enumerate(AXES)]
    out.append(_table(["axis", "raw mean (deg/s)", "raw std (deg/s)", "filtered mean (deg/s)", "filtered std (deg/s)",
                       "std ratio", "rejected samples"], rows, numeric_from=1))
    if raw_envelope is not None and len(raw_envelope.t_s):
        out.append("<div class='figures'>" + "".join(_trace(i, a, raw_envelope, filtered_envelope)
                                                     for i, a in enumerate(AXES)) + "</div>")
        out.append(f"<p class='small'>Min/max of every bucket of {raw_envelope.bucket} raw samples (grey) and of "
                   f"{filtered_envelope.bucket} filtered rows (colour) over the whole record.</p>")
    return "".join(out)


def _trace(i, axis, raw, filtered):
    layers = [Band(raw.t_s, raw.low[:, i], raw.high[:, i], "#777", "raw minus start-up bias (min/max)", 0.35),
              Band(filtered.t_s, filtered.low[:, i], filtered.high[:, i], AXIS_COLOURS[axis], "filtered (min/max)", 0.9),
              Line(filtered.t_s, (filtered.low[:, i] + filtered.high[:, i]) / 2, AXIS_COLOURS[axis], width=1.0)]
    return figure(layers, key=f"trace-{axis}", title=f"axis {axis}: rate in time", xlabel="time (s)",
                  ylabel="rate (deg/s)")


def _allan(data):
    doc = data["allan"]
    out = ["<h2>Allan deviation and noise coefficients</h2>"]
    if doc is None:
        return out[0] + f"<p>Not computed: {html_text(data['allan_error'])}</p>"
    out.append("<p>Overlapping Allan deviation with its chi-square interval, the fitted five-term model "
               "(sigma<sup>2</sup> = 3Q<sup>2</sup>/tau<sup>2</sup> + N<sup>2</sup>/tau + (2 ln2/pi) B<sup>2</sup> + "
               "K<sup>2</sup> tau/3 + R<sup>2</sup> tau<sup>2</sup>/2) and each resolved term's line with its slope; "
               f"as <code>gyrofilter allan</code> computes them. {html_text(doc['method']['interval'])}. The slope "
               "read-off takes each term from where its slope meets the curve (IEEE Std 952 practice); the other terms "
               "add to the curve there, so it overstates the term: where the fit leaves a term not resolved, the "
               "fit's bound (&lt; value) is the tighter statement, even below the read-off.</p>")
    accel = doc.get("accelerometer")
    sensors = [("", doc["axes"], GYRO_JSON)] + ([("accelerometer ", accel["axes"], ACCEL_JSON)] if accel else [])
    out.append("<div class='figures'>" + "".join(_allan_figure(a, ax, sensor, prefix)
                                                 for prefix, axes, sensor in sensors for a, ax in axes.items()) + "</div>")
    if accel:
        out.append("<p>The accelerometer's (beside the gyro's): the same analysis of the acceleration in m/s<sup>2</sup>, "
                   "velocity in the place of the angle (N the velocity random walk, K the acceleration random walk); "
                   "gravity, a constant on the axis that points up, does not enter the Allan deviation.</p>")
    for prefix, axes, sensor in sensors:
        for a, ax in axes.items():
            out.append(f"<h3>{html_text(prefix)}axis {html_text(a)}</h3>")
            rows = []
            for t in TERMS:
                d, ro = ax["details"][sensor.keys[t]], ax["readoff"][sensor.keys[t]]
                rows.append((f"{TERM_SYMBOL[t]} {sensor.terms.term_name[t]}", _interval(d), d["unit"],
                             _interval(d["customary"]), d["customary"]["unit"], _interval(ro)))
            out.append("<div class='scroll'>" + _table(["term", "fit: value [interval]", "unit", "customary", "unit",
                                                         "slope read-off (upper estimate)"], rows, numeric_from=1) + "</div>")
    return "".join(out)


def _allan_figure(axis, ax, sensor=GYRO_JSON, prefix=""):
    """The log-log figure of one axis of the allan document (``sensor``: a
    :class:`~gyrofilter.analysis.noise.export.JsonSensor`, its keys; ``prefix`` names the sensor in the
    title): the deviation, its interval, the
    fitted model (:func:`~gyrofilter.analysis.noise.model.model_adev` of every term's
    ``model_value``: a term the model holds counts even where its interval, widened by the misfit,
    leaves it not resolved) and each resolved term's line."""
    tau = np.asarray(ax["tau_s"], dtype=float)
    colour = AXIS_COLOURS.get(axis, "#333")
    suffix, keys = sensor.suffix, sensor.keys
    layers = [Band(tau, _floats(ax[f"adev_low_{suffix}"]), _floats(ax[f"adev_high_{suffix}"]), colour,
                   "interval of each point"),
              Line(tau, _floats(ax[f"adev_{suffix}"]), colour, "measured", marks=True)]
    if tau.size:
        t = np.logspace(np.log10(tau[0]), np.log10(tau[-1]), 120)
        values = [(ax["coefficients"][keys[term]] or {}).get("value") for term in TERMS]
        layers.append(Line(t, model_adev([ax["details"][keys[term]]["model_value"] for term in TERMS], t), "#000",
                           "fitted model", width=1.2, fit=False))
        b = basis(t)
        for j, term in enumerate(TERMS):
            if values[j] is not None:
                layers.append(Line(t, np.sqrt(b[:, j]) * values[j], "#666", dash="5 3", width=1.0, fit=False,
                                   label=f"{TERM_SYMBOL[term]} = {values[j]:.3g} {sensor.units[term]} "
                                         f"(slope {_slope(TERM_SLOPE[term])})"))
    name = "allan" if not prefix else "allan-" + prefix.strip()
    return figure(layers, key=f"{name}-{axis}", title=f"{prefix}axis {axis}: Allan deviation", xlabel="tau (s)",
                  ylabel=f"Allan deviation ({sensor.terms.unit})", log_x=True, log_y=True)


def _gap(data):
    g = data["gap"]
    out = ["<h2>What the baseline model misses (gap analysis)</h2>",
           f"<p>As <code>gyrofilter gap</code> finds it: the baseline (constant bias + white noise + rounding to "
           f"the LSB step) against {g.get('n_simulations', 0)} simulations of it (fixed streams); D is the mean squared z-score of the record's features against "
           f"the model's simulations, about 1 where the model explains the record. {WHITE_LEVELS}</p>"]
    disc = g.get("discrepancy") or {}
    rows = []
    for a in AXES:
        b = g["baseline"]["axes"][a]
        d_cells = (("not analysed",) * 2 if a in disc.get("not_analysed", {}) else
                   (_num(disc.get("before", {}).get(a)), _num(disc.get("after", {}).get(a))))
        rows.append((a, _num(b.get("bias_dps")), _num(b.get("arw_dps_per_sqrt_hz")), _num(b.get("quantization_dps")),
                     *d_cells))
    out.append(_table(["axis", "bias (deg/s)", "ARW (deg/s/sqrt(Hz))", "LSB step (deg/s)", "D baseline",
                       "D extended"], rows, numeric_from=1))
    out.append("<h3>Findings</h3>")
    if not g["findings"]:
        out.append(f"<p>{html_text(no_findings_text(g))}</p>")
    if covariate_preamble(g["findings"]):
        out.append(f"<p>{html_text(covariate_preamble(g['findings']))}</p>")
    out.append("<ul>" + "".join(_finding(f) for f in g["findings"]) + "</ul>")
    if g.get("uncertain"):
        out.append(f"<h3>{html_text(UNCERTAIN_HEADING)}</h3><p>Not in the extended model.</p><ul>"
                   + "".join(f"<li>{html_text(uncertain_text(e, sep=' = '))}.</li>" for e in g["uncertain"]) + "</ul>")
    notes = [note for note in g.get("notes") or () if note not in data["warnings"]]  # (said once, under Warnings)
    if notes:
        out.append("<h3>Notes</h3><ul>" + "".join(f"<li>{html_text(note)}</li>" for note in notes) + "</ul>")
    out.append("<h3>Extended model</h3>" + _extended(g.get("extended_model")))
    return "".join(out)


def _allan_and_gap(sentences):
    """Where allan and gap disagree on a noise term, a sentence each with the reasons known
    (:func:`gyrofilter.analysis.agreement.compare`); nothing where they tell one story."""
    if not sentences:
        return ""
    return ("<h2>allan and gap</h2><p>The two analyses estimate N, B, K and R on their own: allan from the Allan "
            "curve's five-term fit, gap from its baseline and findings. Where they do not tell one story:</p><ul>"
            + "".join(f"<li>{html_text(s['text'])}</li>" for s in sentences) + "</ul>")


def _finding(f):
    ci = f.get("params_ci95") or {}
    params = html_text(params_text(f, sep=" = "))  # the console's digits: enough to tell an interval's ends apart
    text = (f"<li><b>{html_text(f['effect'])}</b> on <b>{html_text(f['axis'])}</b>: {params}"
            + (" (95 % intervals in brackets)" if ci else "") + f". Gain: D {html_text(_num(f['gain']['before']))} -&gt; "
            f"{html_text(_num(f['gain']['after']))}.")
    if f.get("alternatives"):
        text += f"<br>{html_text(indistinguishable_text(f))}."
    return text + f"<br><span class='small'>Evidence: {html_text(evidence_text(f))}.</span></li>"


def _extended(model):
    """The extended model: a row per axis (bias, white level, its effects), and a line under the
    table with the model's whole-row effects, its top-level keys (:data:`~gyrofilter.effects.ROWS`:
    ``repeated_samples``), which no axis holds."""
    if not model:
        return "<p>None.</p>"
    rows = []
    for a, spec in model["axes"].items():
        effects = "; ".join(_term(e["effect"], e) for e in spec.get("effects", [])) or "none"
        rows.append((a, _num(spec.get("bias_dps")), _num(spec.get("arw_dps_per_sqrt_hz")), effects))
    table = _table(["axis", "bias (deg/s)", "ARW (deg/s/sqrt(Hz))", "effects"], rows, numeric_from=1, numeric_to=3)
    whole = [_term(name, model[name]) for name in ROWS if name in model]
    if whole:
        table += f"<p>Effects of whole rows (every axis at once; top-level keys of the model): {html_text('; '.join(whole))}.</p>"
    return table


def _term(name, params):
    """An effect of the extended model as text: "name: key = value, ..." (its parameters but ``effect``)."""
    return f"{name}: " + ", ".join(f"{k} = {_num(v)}" for k, v in params.items() if k != "effect")


def _interval(d):
    """A coefficient of the allan document: value [low, high], or "not resolved (< bound)"."""
    if d.get("value") is None:
        return "not resolved" + (f" (< {_num(d['upper_bound'])})" if d.get("upper_bound") is not None else "")
    return f"{_num(d['value'])} [{_num(d.get('low'))}, {_num(d.get('high'))}]"


def _table(headers, rows, *, numeric_from=None, numeric_to=None, header_row=True):
    """An HTML table of plain-text cells (escaped here); those of the columns numeric_from ..
    numeric_to - 1 right-aligned."""
    out = ["<table>"]
    if header_row:
        out.append("<tr>" + "".join(f"<th>{html_text(h)}</th>" for h in headers) + "</tr>")
    for row in rows:
        cells = []
        for j, cell in enumerate(row):
            numeric = numeric_from is not None and j >= numeric_from and (numeric_to is None or j < numeric_to)
            cells.append(f"<td class='num'>{html_text(cell)}</td>" if numeric else f"<td>{html_text(cell)}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    return "".join(out) + "</table>"


def _num(v, spec=".4g"):
    """A number of the data as plain text (4 significant digits), "-" for None (not finite)."""
    if v is None:
        return "-"
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return format(v, spec)
    return str(v)


def _floats(values):
    return np.array([np.nan if v is None else v for v in values], dtype=float)


def _slope(s):
    return {-1.0: "-1", -0.5: "-1/2", 0.0: "0", 0.5: "+1/2", 1.0: "+1"}[s]



