"""Measured filter comparison: static noise, synthetic motion on real noise, real motion vs optics.

Every filter of :mod:`gyrofilter.evaluation.filters` runs on every data set of
:mod:`gyrofilter.evaluation.datasets` (:func:`evaluate`) and is scored by the metrics of
:mod:`gyrofilter.evaluation.metrics`; this module holds the whole run, the dominance test against
paper 001's filter, the table and the Pareto figure.

Held-out split used to tune the hold and adaptive_kalman presets (:data:`TUNE_SPLIT`): tuned on the
sensor-fusion static recordings (655 s, 123 s, 64 s), the profiles ``paper001`` and ``steps``
and the BROAD trials 02 and 07; held out: the ImuCalibration static recordings (449 s, 100 s),
the profiles ``sine_1hz`` and ``chirp``, BROAD 05 and 09 (the trials with rest breaks).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .datasets import NOISE_SEGMENT_S, find_broad_recordings, find_static_recordings, noise_segments, stem
from .filters import default_filters
from .metrics import broad_metrics, dynamic_metrics, static_reduction
from ..errors import CalibrationError, SettingsError
from ..filter.calibration import without_settings
from ..plots import pyplot, save_figure
from ..sim.profiles import PROFILES

PAPER_CLAIM_REDUCTION = 12.6
TUNE_SPLIT = {
    "static": ("mpu6050_static_655s", "mpu6050_static_123s", "mpu6050_static_64s_set1"),
    "profiles": ("paper001", "steps"),
    "broad": ("broad_02_slow", "broad_07_fast"),
}
HOLDOUT_SPLIT = {
    "static": ("mpu6050_static_449s", "mpu6050_static_100s"),
    "profiles": ("sine_1hz", "chirp"),
    "broad": ("broad_05_slow_breaks", "broad_09_fast_breaks"),
}


# ---------------------------------------------------------------------------------------------
# the whole evaluation


@dataclass
class Evaluation:
    """What :func:`evaluate` measured, per filter name: static reductions, dynamic RMSE and lags
    (per profile), BROAD RMSE (per trial)."""

    filters: list
    static_names: list
    static: dict  # filter -> {recording: (3,) reductions}
    profiles: list
    dynamic: dict  # filter -> {profile: {"rmse_dps", "worst_lag_s", "lags_s"}}
    broad_names: list
    broad: dict  # filter -> {trial: {"rmse_motion_dps", ...}}
    families: dict = field(default_factory=dict)  # filter -> family

    def static_min(self, name, only=None):
        """The smallest static std reduction of filter ``name`` over axes and recordings (those in
        ``only``, when given); NaN when there is none."""
        vals = [v for rec, v in self.static[name].items() if only is None or rec in only]
        return float(np.min(vals)) if vals else float("nan")

    def static_geomean(self, name, only=None):
        """Geometric mean of the static std reductions of filter ``name`` (recordings in ``only``)."""
        vals = np.concatenate([v for rec, v in self.static[name].items() if only is None or rec in only])
        return float(np.exp(np.mean(np.log(vals))))

    def dynamic_geomean(self, name, only=None):
        """Geometric mean of the dynamic RMSE (deg/s) of filter ``name`` over profiles (those in ``only``)."""
        vals = [d["rmse_dps"] for p, d in self.dynamic[name].items() if only is None or p in only]
        return float(np.exp(np.mean(np.log(vals))))


def evaluate(filters=None, recordings_dir="recordings", profiles=None, with_lag=True, progress=None,
             static_names=None, broad_names=None):
    """Run every filter on every data set; returns an :class:`Evaluation`.

    ``filters``: FilterSpecs (default :func:`default_filters`); ``recordings_dir``: the folder
    of recordings; ``profiles``: names of :mod:`gyrofilter.sim.profiles` (default all);
    ``with_lag``: estimate lags; ``static_names``, ``broad_names``: only these recordings (file
    stems; default all); ``progress``: optional callable(str) told what runs (the CLI prints it
    on stderr).
    """
    filters = default_filters() if filters is None else filters
    profiles = list(PROFILES) if profiles is None else list(profiles)
    static_recs = find_static_recordings(recordings_dir)
    if static_names is not None:
        static_recs = [r for r in static_recs if stem(r.path) in static_names]
    if not static_recs:
        raise SettingsError(f"{recordings_dir}: no static MPU6050 recordings found")
    broad_recs = find_broad_recordings(recordings_dir)
    if broad_names is not None:
        broad_recs = [r for r in broad_recs if stem(r.path) in broad_names]
    segments = noise_segments(static_recs)
    if profiles and not segments:
        raise SettingsError(f"{recordings_dir}: no static recording lasts the {NOISE_SEGMENT_S:g} s of noise "
                            "the synthetic-motion profiles need")
    ev = Evaluation([f.name for f in filters], [stem(r.path) for r in static_recs], {}, profiles, {},
                    [stem(r.path) for r in broad_recs], {}, {f.name: f.family for f in filters})
    for spec in filters:
        if progress:
            progress(f"evaluating {spec.name}")
        ev.static[spec.name] = {stem(r.path): _naming(r, static_reduction, spec, r.gyro_dps, r.sample_rate_hz)
                                for r in static_recs}
        ev.dynamic[spec.name] = {}
        for p in profiles:
            d = dynamic_metrics(spec, p, segments, with_lag=with_lag)
            d.pop("runs")
            ev.dynamic[spec.name][p] = d
        ev.broad[spec.name] = {stem(r.path): _naming(r, broad_metrics, spec, r) for r in broad_recs}
    return ev


def _naming(rec, metric, *args):
    """``metric(*args)`` of the recording ``rec`` (a static recording or a BROAD trial); its
    CalibrationError (the sensor moved in the start-up window) or SettingsError (a recording
    shorter than the window) names the file."""
    try:
        return metric(*args)
    except CalibrationError as exc:  # a large bias's way through is a setting, which evaluate does not take
        raise CalibrationError(f"{rec.path}: " + without_settings(
            exc, "evaluate runs each filter at its own settings: move it out of the recordings folder")) from None
    except SettingsError as exc:
        raise SettingsError(f"{rec.path}: {exc}") from None


def dominates(ev, candidate, reference="paper001", claim=PAPER_CLAIM_REDUCTION, static_only=None,
              profiles=None, broad_only=None):
    """Does ``candidate`` Pareto-dominate ``reference`` in the :class:`Evaluation` ``ev``? Returns
    (bool, list of reasons it fails). ``static_only``, ``profiles``, ``broad_only``: consider only
    these static recordings, profiles and BROAD trials (default all).

    Criteria (issue 5): static std reduction >= ``claim`` on every axis of every static
    recording considered, and dynamic RMSE <= the reference's on every profile and every BROAD
    trial (all valid blocks).
    """
    fails = []
    for rec, red in ev.static[candidate].items():
        if static_only is not None and rec not in static_only:
            continue
        if np.min(red) < claim:
            fails.append(f"static {rec}: reduction {np.min(red):.2f} < {claim}")
    for label, table, key, only in (("profile", ev.dynamic, "rmse_dps", profiles), ("BROAD", ev.broad, "rmse_all_dps", broad_only)):
        for name, d in table[candidate].items():
            ref = table[reference][name][key]
            if (only is None or name in only) and d[key] > ref:
                fails.append(f"{label} {name}: RMSE {d[key]:.4f} > {ref:.4f}")
    return (not fails), fails


# ---------------------------------------------------------------------------------------------
# outputs


def pareto_front(points):
    """Indices of the points (error, reduction) not dominated: lower error and higher reduction."""
    idx = []
    for i, (e, r) in enumerate(points):
        if not any((e2 <= e and r2 >= r) and (e2 < e or r2 > r) for j, (e2, r2) in enumerate(points) if j != i):
            idx.append(i)
    return idx


def format_table(ev):
    """One Markdown table of the :class:`Evaluation` ``ev``: a row per filter."""
    head = ["filter", "static reduction min / geo-mean"]
    head += [f"{p} RMSE / worst lag" for p in ev.profiles]
    head += [f"{b} RMSE motion / rest / lag" for b in ev.broad_names]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name in ev.filters:
        row = [name, f"{ev.static_min(name):.2f} / {ev.static_geomean(name):.2f}x"]
        for p in ev.profiles:
            d = ev.dynamic[name][p]
            lag = d["worst_lag_s"]
            row.append(f"{d['rmse_dps']:.3f} / {lag * 1e3:.0f} ms" if math.isfinite(lag) else f"{d['rmse_dps']:.3f}")
        for b in ev.broad_names:
            d = ev.broad[name][b]
            row.append(f"{d['rmse_motion_dps']:.2f} / {d['rmse_rest_dps']:.2f} / {d['lag_s'] * 1e3:.0f} ms")
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def console_table(ev):
    """A row per filter of the :class:`Evaluation` ``ev`` that fits a 100-column terminal: the
    static std reduction (min / geometric mean), the profiles' RMSE (geometric mean, deg/s) and
    their worst lag, the BROAD trials' RMSE in motion and at rest (geometric means, deg/s; "-" without
    trials). Every
    number per profile and trial is in :func:`format_table`."""
    width = max([len("filter")] + [len(name) for name in ev.filters])
    lines = [f"{'filter':<{width}}  {'static min / geo':>16}  {'profiles RMSE':>13}  {'worst lag':>9}  "
             f"{'BROAD motion / rest':>19}"]
    for name in ev.filters:
        lags = [d["worst_lag_s"] for d in ev.dynamic[name].values() if math.isfinite(d["worst_lag_s"])]
        broad = [ev.broad[name][b] for b in ev.broad_names]
        motion = float(np.exp(np.mean(np.log([d["rmse_motion_dps"] for d in broad])))) if broad else None
        rest = float(np.exp(np.mean(np.log([d["rmse_rest_dps"] for d in broad])))) if broad else None
        lag = f"{max(lags) * 1e3:.0f} ms" if lags else "-"
        trials = f"{motion:.2f} / {rest:.2f}" if broad else "- (no trials)"
        lines.append(f"{name:<{width}}  {f'{ev.static_min(name):.2f} / {ev.static_geomean(name):.2f}x':>16}  "
                     f"{ev.dynamic_geomean(name):>13.3f}  {lag:>9}  {trials:>19}")
    return "\n".join(lines)


def plot_pareto(ev, path, reference="paper001"):
    """Static std reduction (geometric mean) against dynamic RMSE (geometric mean over profiles)
    of the :class:`Evaluation` ``ev``, drawn to the figure file ``path``; ``reference``: the
    filter the others are compared with.

    The Pareto front is drawn through the real-time filters; offline ones (the smoother) are
    stars beside it. Labels that would overlap are moved down, one line at a time."""
    plt = pyplot()
    pts = [(ev.dynamic_geomean(n), ev.static_geomean(n)) for n in ev.filters]
    fam = ev.families
    realtime = [i for i, n in enumerate(ev.filters) if fam.get(n) != "offline"]
    front = {realtime[j] for j in pareto_front([pts[i] for i in realtime])}
    fig, ax = plt.subplots(figsize=(9, 6))
    ax.set_xscale("log")
    ax.set_yscale("log")
    colors = {"baseline": "tab:gray", "paper": "tab:red", "candidate": "tab:blue", "offline": "tab:green"}
    for i, (e, r) in enumerate(pts):
        family = fam.get(ev.filters[i], "candidate")
        ax.scatter([e], [r], color=colors.get(family, "tab:blue"), marker="*" if family == "offline" else "o",
                   s=120 if family == "offline" else (60 if i in front else 30),
                   edgecolor="k" if i in front else "none", zorder=3)
    fig.canvas.draw()
    placed = []  # label boxes in display pixels
    for i in sorted(range(len(pts)), key=lambda i: (-pts[i][1], pts[i][0])):
        x_px, y_px = ax.transData.transform(pts[i])
        width, height = 5.5 * len(ev.filters[i]), 11.0
        dy = 3.0
        while any(abs(x_px + 5 - bx) < max(width, bw) and abs(y_px + dy - by) < height for bx, by, bw in placed):
            dy -= height
        placed.append((x_px + 5, y_px + dy, width))
        ax.annotate(ev.filters[i], pts[i], textcoords="offset points", xytext=(5, dy * 72 / fig.dpi), fontsize=8)
    fr = sorted(pts[i] for i in front)
    ax.plot([p[0] for p in fr], [p[1] for p in fr], "k--", lw=0.8, zorder=2, label="Pareto front (real-time filters)")
    ax.axhline(PAPER_CLAIM_REDUCTION, color="tab:red", lw=0.8, ls=":", label="paper 001 claim 12.6x")
    if reference in ev.filters:
        e0, _ = pts[ev.filters.index(reference)]
        ax.axvline(e0, color="tab:red", lw=0.8, ls="-.", label="paper001 dynamic RMSE")
    ax.set_xlabel("dynamic RMSE, geometric mean over profiles (deg/s)  - lower is better")
    ax.set_ylabel("static std reduction, geometric mean (x)  - higher is better")
    ax.set_title("Noise reduction vs tracking error (real MPU6050 noise)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
    return path
