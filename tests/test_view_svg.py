"""gyrofilter.view.svg: the report's figures, checked on hand-made cases."""
import re

import numpy as np

from gyrofilter.view.svg import Band, Line, _Scale, figure


def polylines(svg):
    return re.findall(r"<polyline [^>]*points='([^']*)'", svg)


def test_log_ticks_are_decades_and_linear_ticks_steps_of_1_2_5():
    assert _Scale((0.01, 100.0), True, 0, 100).ticks() == [0.01, 0.1, 1.0, 10.0, 100.0]
    assert _Scale((0.1, 1.0), True, 0, 100).ticks() == [0.1, 0.2, 0.5, 1.0]
    assert _Scale((-0.5, 0.5), False, 0, 100).ticks() == [-0.4, -0.2, 0.0, 0.2, 0.4]
    scale = _Scale((1.0, 100.0), True, 10, 110)
    np.testing.assert_allclose(scale([1.0, 10.0, 100.0]), [10, 60, 110])


def test_a_point_that_cannot_be_drawn_breaks_the_line():
    x = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    y = np.array([1.0, np.nan, 3.0, -1.0, 5.0])  # nan, and -1 on a log axis
    svg = figure([Line(x, y, "red")], key="k", title="t", xlabel="x", ylabel="y", log_y=True)
    assert [len(p.split()) for p in polylines(svg)] == [1, 1, 1]
    linear = figure([Line(x, y, "red")], key="k", title="t", xlabel="x", ylabel="y")
    assert [len(p.split()) for p in polylines(linear)] == [1, 3]


def test_text_is_escaped_and_the_legend_lists_the_labelled_layers():
    x = np.arange(3.0)
    svg = figure([Band(x, x - 1, x + 1, "grey", "band <b>"), Line(x, x, "red", "a & b"), Line(x, x, "blue")],
                 key="a x", title="</svg><script>", xlabel="time (s)", ylabel="rate (deg/s)")
    assert "<script>" not in svg and "&lt;/svg&gt;&lt;script&gt;" in svg
    assert "band &lt;b&gt;" in svg and "a &amp; b" in svg
    assert "clip-a_x" in svg and svg.count("<svg") == 1


def test_a_figure_without_data_says_so():
    svg = figure([Line([], [], "red", "nothing")], key="e", title="t", xlabel="x", ylabel="y", log_x=True, log_y=True)
    assert "no data to draw" in svg
