"""Figures as inline SVG text, drawn by the package itself: no matplotlib (a Pi may not have it),
no script (a report reads in any browser, or in a mail client that runs none).

:func:`figure` draws :class:`Line` and :class:`Band` layers on one pair of axes, linear or
logarithmic each, with ticks, a grid, axis labels (with their units: the caller's text) and a
legend below the plot. A pure function of its arguments: numbers in, text out. Coordinates
are rounded to 0.1 px, so that a figure of thousands of points stays a few tens of kB.

Scales: the data range of the layers marked ``fit`` (all, by default), widened by 4 % (linear)
or to whole decades when the range spans less than one (log); points that are not finite, or
not above 0 on a log axis, break a line (a band drops them). Everything is clipped to the plot
area, so a layer not marked ``fit`` (a model term's line) may run beyond it.
"""
from __future__ import annotations

import html
import math
from dataclasses import dataclass

import numpy as np

from ..inputs import escape_controls

#: the figure's size in px (it scales with the page: the SVG has a viewBox and width 100 %)
WIDTH, HEIGHT = 400, 270
_LEFT, _RIGHT, _TOP, _BOTTOM = 62, 12, 26, 40  # margins of the plot area (px)
_LEGEND_ROW = 15  # px per legend entry
_FONT = "font-family='sans-serif' font-size='11'"


@dataclass(frozen=True)
class Line:
    """A polyline through (x, y); ``dash``: an SVG dash array ("4 3"), ``marks``: a dot at each point."""
    x: object
    y: object
    colour: str
    label: str | None = None
    dash: str | None = None
    width: float = 1.5
    marks: bool = False
    fit: bool = True


@dataclass(frozen=True)
class Band:
    """The area between ``low`` and ``high`` over ``x``, filled with ``colour`` at ``opacity``."""
    x: object
    low: object
    high: object
    colour: str
    label: str | None = None
    opacity: float = 0.25
    fit: bool = True


def figure(layers, *, key, title, xlabel, ylabel, log_x=False, log_y=False, width=WIDTH, height=HEIGHT):
    """The SVG element (text) of ``layers`` (Line, Band; drawn in order) on one pair of axes.

    ``key``: a name unique in the page (the id of the figure's clip path); ``title``, ``xlabel``,
    ``ylabel``: plain text (escaped here), the labels with their units; ``log_x``/``log_y``:
    logarithmic axes. A figure with no drawable point says so in its plot area."""
    xs, ys = _fitted_values(layers, log_x, log_y)
    x_range = _range(xs, log_x)
    y_range = _range(ys, log_y)
    labelled = [layer for layer in layers if layer.label]
    total_height = height + _LEGEND_ROW * len(labelled)
    box = (_LEFT, _TOP, width - _RIGHT, height - _BOTTOM)
    sx = _Scale(x_range, log_x, box[0], box[2])
    sy = _Scale(y_range, log_y, box[3], box[1])
    clip = f"clip-{_id(key)}"
    out = [f"<svg viewBox='0 0 {width} {total_height}' width='100%' "
           f"role='img' aria-label='{html_text(title)}' class='figure'>",
           f"<title>{html_text(title)}</title>",
           f"<defs><clipPath id='{clip}'><rect x='{box[0]}' y='{box[1]}' width='{box[2] - box[0]}' "
           f"height='{box[3] - box[1]}'/></clipPath></defs>",
           f"<rect x='{box[0]}' y='{box[1]}' width='{box[2] - box[0]}' height='{box[3] - box[1]}' fill='white' stroke='#888'/>"]
    out += _ticks(sx, sy, box)
    out.append(f"<g clip-path='url(#{clip})'>")
    for layer in layers:
        out.append(_band(layer, sx, sy) if isinstance(layer, Band) else _line(layer, sx, sy))
    out.append("</g>")
    if not xs.size or not ys.size:
        out.append(f"<text x='{(box[0] + box[2]) / 2}' y='{(box[1] + box[3]) / 2}' text-anchor='middle' {_FONT}>"
                   "no data to draw</text>")
    out += [f"<text x='{(box[0] + box[2]) / 2}' y='16' text-anchor='middle' {_FONT} font-weight='bold'>{html_text(title)}</text>",
            f"<text x='{(box[0] + box[2]) / 2}' y='{height - 6}' text-anchor='middle' {_FONT}>{html_text(xlabel)}</text>",
            f"<text transform='translate(13 {(box[1] + box[3]) / 2}) rotate(-90)' text-anchor='middle' {_FONT}>"
            f"{html_text(ylabel)}</text>"]
    for i, layer in enumerate(labelled):
        out.append(_legend_entry(layer, box[0], height + _LEGEND_ROW * i + 4))
    out.append("</svg>")
    return "\n".join(out)


class _Scale:
    """Data -> px on one axis: ``lo..hi`` (data) onto ``start..end`` (px), in log10 when ``log``."""

    def __init__(self, data_range, log, start, end):
        self.lo, self.hi = data_range
        self.log, self.start, self.end = log, start, end

    def __call__(self, v):
        v = np.asarray(v, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.log10(np.where(v > 0, v, np.nan)) if self.log else v
            lo, hi = (math.log10(self.lo), math.log10(self.hi)) if self.log else (self.lo, self.hi)
            return self.start + (u - lo) / (hi - lo) * (self.end - self.start)

    def ticks(self):
        """The tick values inside the range: decades (and 2, 5 within less than 3 decades) on a
        log axis; steps of 1, 2 or 5 times a power of ten, about five of them, on a linear one."""
        if self.log:
            first, last = math.floor(math.log10(self.lo)), math.ceil(math.log10(self.hi))
            steps = (1, 2, 5) if last - first < 3 else (1,)
            values = [m * 10.0 ** k for k in range(first, last + 1) for m in steps]
        else:
            raw = (self.hi - self.lo) / 5
            power = 10.0 ** math.floor(math.log10(raw))
            step = next(m * power for m in (1, 2, 5, 10) if m * power >= raw)
            values = [k * step for k in range(math.ceil(self.lo / step), math.floor(self.hi / step) + 1)]
        eps = 1e-9 * (self.hi - self.lo)
        return [v for v in values if self.lo - eps <= v <= self.hi + eps]


def _fitted_values(layers, log_x, log_y):
    """The finite x and y values of the ``fit`` layers (above 0 on a log axis)."""
    xs, ys = [], []
    for layer in layers:
        if not layer.fit:
            continue
        x = np.asarray(layer.x, dtype=float)
        parts = [layer.low, layer.high] if isinstance(layer, Band) else [layer.y]
        for y in (np.asarray(p, dtype=float) for p in parts):
            ok = np.isfinite(x) & np.isfinite(y) & ((x > 0) if log_x else True) & ((y > 0) if log_y else True)
            xs.append(x[ok])
            ys.append(y[ok])
    return (np.concatenate(xs) if xs else np.empty(0)), (np.concatenate(ys) if ys else np.empty(0))


def _range(values, log):
    """(lo, hi) of ``values`` with a margin (module docstring); (1, 10) or (0, 1) for none."""
    if not values.size:
        return (1.0, 10.0) if log else (0.0, 1.0)
    lo, hi = float(values.min()), float(values.max())
    if log:
        lo_e, hi_e = math.log10(lo), math.log10(hi)
        if hi_e - lo_e < 1:  # less than a decade: the decades around it
            lo_e, hi_e = math.floor(lo_e), max(math.ceil(hi_e), math.floor(lo_e) + 1)
        else:
            lo_e, hi_e = lo_e - 0.04 * (hi_e - lo_e), hi_e + 0.04 * (hi_e - lo_e)
        return 10.0 ** lo_e, 10.0 ** hi_e
    if hi == lo:
        pad = abs(lo) * 0.1 or 1.0
        return lo - pad, hi + pad
    pad = 0.04 * (hi - lo)
    return lo - pad, hi + pad


def _tick_text(v):
    """A tick's label: 3 significant digits, without trailing zeros; 0 as 0."""
    return "0" if abs(v) < 1e-300 else f"{v:.3g}"


def _ticks(sx, sy, box):
    out = []
    for v in sx.ticks():
        px = float(sx(v))
        out.append(f"<line x1='{px:.1f}' y1='{box[1]}' x2='{px:.1f}' y2='{box[3]}' stroke='#ddd'/>"
                   f"<text x='{px:.1f}' y='{box[3] + 14}' text-anchor='middle' {_FONT}>{_tick_text(v)}</text>")
    for v in sy.ticks():
        py = float(sy(v))
        out.append(f"<line x1='{box[0]}' y1='{py:.1f}' x2='{box[2]}' y2='{py:.1f}' stroke='#ddd'/>"
                   f"<text x='{box[0] - 4}' y='{py + 4:.1f}' text-anchor='end' {_FONT}>{_tick_text(v)}</text>")
    return out


def _points(px, py):
    return " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(px.tolist(), py.tolist()))


def _line(layer, sx, sy):
    px, py = sx(layer.x), sy(layer.y)
    ok = np.isfinite(px) & np.isfinite(py)
    dash = f" stroke-dasharray='{layer.dash}'" if layer.dash else ""
    out = []
    # one polyline per run of drawable points
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(np.int8), [0]])))
    for start, stop in zip(edges[::2], edges[1::2]):
        out.append(f"<polyline fill='none' stroke='{layer.colour}' stroke-width='{layer.width}'{dash} "
                   f"points='{_points(px[start:stop], py[start:stop])}'/>")
    if layer.marks:
        out += [f"<circle cx='{a:.1f}' cy='{b:.1f}' r='2' fill='{layer.colour}'/>"
                for a, b in zip(px[ok].tolist(), py[ok].tolist())]
    return "\n".join(out)


def _band(layer, sx, sy):
    px, lo, hi = sx(layer.x), sy(layer.low), sy(layer.high)
    ok = np.isfinite(px) & np.isfinite(lo) & np.isfinite(hi)
    if not ok.any():
        return ""
    px, lo, hi = px[ok], lo[ok], hi[ok]
    return (f"<polygon fill='{layer.colour}' fill-opacity='{layer.opacity}' stroke='none' "
            f"points='{_points(np.concatenate([px, px[::-1]]), np.concatenate([lo, hi[::-1]]))}'/>")


def _legend_entry(layer, x, y):
    if isinstance(layer, Band):
        mark = (f"<rect x='{x}' y='{y}' width='22' height='9' fill='{layer.colour}' "
                f"fill-opacity='{max(layer.opacity, 0.25)}'/>")
    else:
        dash = f" stroke-dasharray='{layer.dash}'" if layer.dash else ""
        mark = (f"<line x1='{x}' y1='{y + 5}' x2='{x + 22}' y2='{y + 5}' stroke='{layer.colour}' "
                f"stroke-width='{layer.width}'{dash}/>")
    return mark + f"<text x='{x + 28}' y='{y + 9}' {_FONT}>{html_text(layer.label)}</text>"


def html_text(text):
    """``text`` as HTML text or an attribute's value: on one line (each control character written
    as its escape, :func:`~gyrofilter.inputs.escape_controls`: a raw ESC or line end of a file
    name has no place in a page), then ``& < > " '`` as entities (:func:`html.escape`). The one
    rule of every text the report and its figures hold."""
    return html.escape(escape_controls(str(text)), quote=True)


def _id(key):
    """``key`` as the characters an id may hold."""
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in str(key))
