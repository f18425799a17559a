"""Allan deviation plots (matplotlib imported lazily, Agg backend).

* :func:`plot_allan`: log-log overlapping Allan deviation per axis with its chi-square band,
  the fitted five-term model, each resolved term's line, and the read-off points marked.
* :func:`plot_before_after`: raw and filtered deviation of the same axes on one plot
  (paper 001 Fig. 4).
"""
from __future__ import annotations

import math

import numpy as np

from ...effects import BIAS_INSTABILITY, RATE_RAMP, RATE_RANDOM_WALK
from .allan import confidence_text
from .model import ANGLE_RANDOM_WALK, QUANTIZATION, TERMS, TERM_SLOPE, TERM_SYMBOL, basis
from ...plots import plain_text, pyplot, save_figure

AXIS_COLOURS = {"x": "tab:red", "y": "tab:green", "z": "tab:blue"}
TERM_STYLE = {QUANTIZATION: ":", ANGLE_RANDOM_WALK: "--", BIAS_INSTABILITY: "-.", RATE_RANDOM_WALK: (0, (5, 2, 1, 2)),
              RATE_RAMP: (0, (1, 1))}


def plot_allan(path, results, title=""):
    """Write the figure file ``path`` (PNG) with one panel per axis, headed ``title``.
    ``results``: {axis: AxisNoise}."""
    plt = pyplot()
    return _save(allan_figure(plt, results, title), path)


def allan_figure(plt, results, title=""):
    """The figure of :func:`plot_allan` (laid out, not saved). A read-off's label stands on the
    side of its point that faces the panel's middle, so that it stays inside the panel."""
    n = len(results)
    fig, axes = plt.subplots(1, n, figsize=(5.2 * n, 4.6), squeeze=False)
    for ax, (name, r) in zip(axes[0], results.items()):
        colour = AXIS_COLOURS.get(name, "k")
        ok = r.n_clusters >= 9
        ax.fill_between(r.tau_s, r.ci_low, r.ci_high, color=colour, alpha=0.2, lw=0,
                        label=f"{confidence_text(r.confidence)} chi-square interval")
        ax.loglog(r.tau_s[ok], r.adev[ok], "o-", ms=3, color=colour, label=f"{name}: overlapping ADEV")
        if np.any(~ok):
            ax.loglog(r.tau_s[~ok], r.adev[~ok], "o", ms=3, mfc="none", color=colour,
                      label="< 9 clusters (not fitted)")
        t = np.logspace(math.log10(r.tau_s[0]), math.log10(r.tau_s[-1]), 200)
        ax.loglog(t, r.model_adev(t), "k-", lw=1.2, label="fitted model")
        b = basis(t)
        for j, term in enumerate(TERMS):
            c = r.fitted[term]
            if c.value is None:
                continue
            ax.loglog(t, np.sqrt(b[:, j]) * c.value, color="0.35", ls=TERM_STYLE[term], lw=1,
                      label=f"{TERM_SYMBOL[term]} = {c.value:.3g} {c.unit}")
        for term in TERMS:
            c = r.readoff[term]
            if c.value is None or c.tau_s is None:
                continue
            i = int(np.argmin(np.abs(r.tau_s - c.tau_s)))
            ax.loglog([r.tau_s[i]], [r.adev[i]], "s", ms=8, mfc="none", mec="k")
            text = (f"B read-off: min/0.664 = {c.value:.3g}" if term == BIAS_INSTABILITY
                    else f"{TERM_SYMBOL[term]} (slope {TERM_SLOPE[term]:+g})")
            right_half = math.log(r.tau_s[i] / r.tau_s[0]) > 0.5 * math.log(r.tau_s[-1] / r.tau_s[0])
            ax.annotate(text, (r.tau_s[i], r.adev[i]), textcoords="offset points", fontsize=7,
                        xytext=(-6 if right_half else 6, 12 if term == BIAS_INSTABILITY else 6),
                        ha="right" if right_half else "left")
        _label(ax, None, legend_size=6.5)
        low = np.min(np.where(r.ci_low > 0, r.ci_low, np.min(r.adev[r.adev > 0])))
        ax.set_ylim(low / 2.0, np.max(r.ci_high) * 1.5)
        ax.set_title(f"axis {name}", fontsize=10)
    axes[0][0].set_ylabel("Allan deviation (deg/s)")
    if title:
        fig.suptitle(plain_text(title), fontsize=10)
    fig.tight_layout()
    return fig


def plot_before_after(path, curves, title=""):
    """Write the figure file ``path`` (PNG), headed ``title``: one log-log axes of ``curves``, a
    list of (label, tau_s, adev_dps, colour, linestyle)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for label, tau, dev, colour, style in curves:
        ax.loglog(tau, dev, style, color=colour, ms=3, label=label)
    _label(ax, "Allan deviation (deg/s)", legend_size=7)
    if title:
        ax.set_title(plain_text(title), fontsize=9)
    return _save(fig, path)


def _label(ax, ylabel, legend_size):
    ax.set_xlabel("cluster time tau (s)")
    if ylabel:
        ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=legend_size, loc="best")


def _save(fig, path):
    fig.tight_layout()
    save_figure(fig, path)
    return path
