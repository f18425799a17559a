"""Tests for `gyrofilter allan`: JSON per docs/formats.md section 4, Kalibr YAML, plot, bad input."""
import dataclasses
import importlib.util
import json
import math
import shutil

import numpy as np
import pytest

from gyrofilter.analysis.fleet import work
from gyrofilter.analysis.noise.fit import characterise_axis
from gyrofilter.analysis.noise.model import ACCELEROMETER_TERMS, GYROSCOPE_TERMS
from gyrofilter.cli import allan, main
from gyrofilter.effects import BIAS_INSTABILITY
from gyrofilter.sim.simulate import simulate
from gyrofilter.cli.console import MAX_LINE_CHARS
from gyrofilter.recording import Recording, read_recording, write_recording
from support import tool


def _write(path, gyro_dps, fs=100.0, lsb=True):
    rec = Recording.from_dps(gyro_dps, fs)
    if lsb:  # as an MPU6050 at +-250 deg/s writes it: integers at 131 LSB per deg/s
        from gyrofilter.recording import convert_gyro
        rec = convert_gyro(rec, "lsb", 131.0)
        for c in ("gx", "gy", "gz"):
            rec.columns[c] = np.round(rec.columns[c])
    write_recording(str(path), rec)
    return str(path)


@pytest.fixture(scope="module")
def static_recording(tmp_path_factory):
    rng = np.random.default_rng(42)
    arw = np.array([0.008, 0.010, 0.012])            # deg/sqrt(s)
    n, fs = 30000, 100.0
    g = np.array([-3.3, 1.1, -0.5]) + rng.normal(size=(n, 3)) * arw * math.sqrt(fs)
    return _write(tmp_path_factory.mktemp("rec") / "static.csv.gz", g), arw


def test_allan_json_kalibr_and_plot(static_recording, tmp_path, capsys):
    path, arw = static_recording
    out, yaml, png = tmp_path / "a.json", tmp_path / "imu.yaml", tmp_path / "a.png"
    plot = ["--plot", str(png)] if importlib.util.find_spec("matplotlib") else []  # the plot extra is optional
    assert main(["allan", path, "--json", str(out), "--kalibr", str(yaml)] + plot) == 0
    doc = json.loads(out.read_text())
    assert doc["sample_rate_hz"] == 100.0
    for name, truth in zip("xyz", arw):
        ax = doc["axes"][name]
        assert ax["tau_s"][0] == pytest.approx(0.01)
        assert ax["tau_s"][-1] <= 300 / 9 + 1e-9               # at least 9 clusters
        assert len(ax["adev_dps"]) == len(ax["tau_s"])
        # sigma(tau) in deg/s: at 0.01 s the per-sample std ~ N sqrt(fs) (quantization adds 1/131/sqrt(12))
        assert ax["adev_dps"][0] == pytest.approx(math.hypot(truth * 10, 1 / 131 / math.sqrt(12)), rel=0.03)
        c = ax["coefficients"]
        assert c["arw_dps_per_sqrt_hz"]["low"] <= c["arw_dps_per_sqrt_hz"]["value"] <= c["arw_dps_per_sqrt_hz"]["high"]
        assert c["arw_dps_per_sqrt_hz"]["value"] == pytest.approx(truth, rel=0.05)
        for key in ("bias_instability_dps", "rrw_dps_per_sqrt_s", "rate_ramp_dps_per_s"):
            assert c[key] is None  # 300 s of white noise cannot resolve them
            assert ax["details"][key]["upper_bound"] > 0
    text = yaml.read_text()
    assert "gyroscope_noise_density:" in text and "rad/s/sqrt(Hz)" in text
    assert not plot or png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    printed = capsys.readouterr().out
    assert "deg/sqrt(h)" in printed and "deg/sqrt(s)" in printed and "not resolved" in printed


def test_the_console_table_fits_100_columns(static_recording, capsys):
    """Issue 38: the table was 185 columns wide, unreadable on an 80- or 120-column terminal. Every
    line of stdout now fits 100 (the full table, every interval, is --json's); the widest
    labels: a 99.99 % interval, and unresolved terms (quantization, bias instability) with bounds."""
    path, _ = static_recording
    assert main(["allan", path, "--confidence", "0.9999"]) == 0
    printed = capsys.readouterr().out
    widest = max(printed.splitlines(), key=len)
    assert len(widest) <= 100, (len(widest), widest)
    assert "deg/sqrt(h)" in printed and "< " in printed and "--json" in printed


def test_allan_one_axis(static_recording, tmp_path):
    path, _ = static_recording
    out = tmp_path / "z.json"
    assert main(["allan", path, "--axes", "z", "--json", str(out)]) == 0
    assert list(json.loads(out.read_text())["axes"]) == ["z"]


def _assert_one_line_error(capsys, *parts):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("gyrofilter: error:"), err
    for p in parts:
        assert p in err[0]


def test_constant_axis_is_a_clear_error(tmp_path, capsys):
    g = np.column_stack([np.random.default_rng(0).normal(size=2000), np.zeros(2000),
                         np.random.default_rng(1).normal(size=2000)])
    path = _write(tmp_path / "stuck.csv", g, lsb=False)
    assert main(["allan", path]) == 2
    _assert_one_line_error(capsys, "stuck.csv: axis y", "constant", "; give --axes xz to analyse the others")
    assert main(["allan", path, "--axes", "xz", "--json", str(tmp_path / "xz.json")]) == 0
    assert sorted(json.loads((tmp_path / "xz.json").read_text())["axes"]) == ["x", "z"]
    capsys.readouterr()
    # issue 37 (attack 4): where the others are constant too, --axes names only the ones that vary
    g[:, 2] = 0.25
    path = _write(tmp_path / "stuck2.csv", g, lsb=False)
    assert main(["allan", path]) == 2
    _assert_one_line_error(capsys, "stuck2.csv: axis y", "; give --axes x to analyse the others")
    path = _write(tmp_path / "equal.csv", np.full((2000, 3), 0.5), lsb=False)
    assert main(["allan", path]) == 2
    _assert_one_line_error(capsys, "equal.csv: axis x", "; every axis asked for is constant")


def test_too_short_recording_is_a_clear_error(tmp_path, capsys):
    path = _write(tmp_path / "short.csv", np.random.default_rng(0).normal(size=(12, 3)), lsb=False)
    assert main(["allan", path]) == 2
    _assert_one_line_error(capsys, "short.csv", "too short")


def test_missing_axis_and_rate_are_clear_errors(tmp_path, capsys):
    p = tmp_path / "noz.csv"
    p.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\ngx,gy\n0.1,0.2\n")
    assert main(["allan", str(p)]) == 2
    _assert_one_line_error(capsys, "gz")
    p2 = tmp_path / "norate.csv"
    p2.write_text("# gyrofilter-recording: 1\n# gyro_unit: dps\ngx,gy,gz\n0.1,0.2,0.3\n")
    assert main(["allan", str(p2)]) == 2
    _assert_one_line_error(capsys, "sample_rate_hz")


def test_bad_options(static_recording, capsys):
    path, _ = static_recording
    assert main(["allan", path, "--axes", "xw"]) == 2
    _assert_one_line_error(capsys, "--axes")
    assert main(["allan", path, "--confidence", "1.5"]) == 2
    _assert_one_line_error(capsys, "confidence")
    assert main(["allan", str(path) + ".missing"]) == 2
    capsys.readouterr()


@pytest.mark.parametrize("confidence", ["0.5", "0.9999"])
def test_confidence_at_the_ends_of_its_range_gives_finite_intervals(static_recording, tmp_path, confidence):
    path, _ = static_recording
    out = tmp_path / "c.json"
    assert main(["allan", path, "--axes", "z", "--confidence", confidence, "--json", str(out)]) == 0
    z = json.loads(out.read_text())["axes"]["z"]
    assert all(0 < lo < hi for lo, hi in zip(z["adev_low_dps"], z["adev_high_dps"]))


@pytest.mark.parametrize("confidence, label", [("0.9999", "99.99%"), ("0.683", "68.3%")])
def test_the_confidence_is_named_as_given(static_recording, tmp_path, capsys, confidence, label):
    """Attack pass 36: --confidence 0.9999 was labelled a "100% interval" (rounded to a whole percent) on
    stdout, in the warnings and the JSON's descriptions; 0.683 a 68% one."""
    path, _ = static_recording
    out = tmp_path / "c.json"
    assert main(["allan", path, "--axes", "z", "--confidence", confidence, "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"[{label} interval]" in printed and "100%" not in printed
    assert json.loads(out.read_text())["method"]["interval"].startswith(f"{label} two-sided")


@pytest.mark.parametrize("confidence", ["0.4999", "0.99991", "0.9999999999999999", "0", "1"])
def test_confidence_outside_its_range_is_one_line_naming_the_range(static_recording, capsys, confidence):
    """0.9999999999999999 passed the check (0, 1) and failed inside the intervals with a message of
    Python's statistics module (issue 22, hostile case 3-2)."""
    path, _ = static_recording
    assert main(["allan", path, "--axes", "z", "--confidence", confidence]) == 2
    _assert_one_line_error(capsys, "--confidence must be in [0.5, 0.9999]", confidence)


def test_help_exits_zero(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["allan", "--help"])
    assert exc.value.code == 0
    assert "--kalibr" in capsys.readouterr().out


def _spiked_bundled(tmp_path, value, rows=(500, 3000, 7000)):
    """The bundled MPU6050 recording with gy replaced by ``value`` (lsb) on data rows ``rows``;
    returns (path, file line of the first spike)."""
    import gzip
    from importlib import resources

    lines = gzip.decompress((resources.files("gyrofilter") / "data" / "mpu6050_static_100s.csv.gz").read_bytes()).decode().split("\n")
    names_at = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    col = lines[names_at].split(",").index("gy")
    for r in rows:
        cells = lines[names_at + 1 + r].split(",")
        cells[col] = value
        lines[names_at + 1 + r] = ",".join(cells)
    path = tmp_path / f"spiked_{value}.csv"
    path.write_text("\n".join(lines))
    return str(path), names_at + 2 + rows[0]


@pytest.mark.parametrize("value", ["5e6", "-3e6"])  # 38 168 and -22 901 deg/s: spikes, within what a reader takes
def test_gross_errors_are_refused_by_default_naming_line_value_and_count(tmp_path, capsys, value):
    path, line = _spiked_bundled(tmp_path, value)
    outs = [tmp_path / "a.json", tmp_path / "a.yaml"]
    assert main(["allan", path, "--json", str(outs[0]), "--kalibr", str(outs[1])]) == 2
    _assert_one_line_error(capsys, path, f"line {line} (sample 500)", f"y = {float(value) / 131:.6g} deg/s",
                           "3 such sample(s)", "--keep-outliers")
    assert not any(p.exists() for p in outs)


def test_keep_outliers_analyses_them_but_writes_nothing_unless_every_result_is_finite(tmp_path, capsys):
    path, _ = _spiked_bundled(tmp_path, "5e6")
    out = tmp_path / "a.json"
    assert main(["allan", path, "--keep-outliers", "--json", str(out)]) == 0
    json.loads(out.read_text())  # strict JSON: no NaN/Infinity tokens
    assert "3 such sample(s)" in capsys.readouterr().err  # kept, but not silently
    path, line = _spiked_bundled(tmp_path, "1e308")  # 7.6e305 deg/s overflowed the deviations: the reader refuses it
    outs = [tmp_path / "b.json", tmp_path / "b.yaml", tmp_path / "b.png"]
    args = ["allan", path, "--keep-outliers", "--json", str(outs[0]), "--kalibr", str(outs[1])]
    args += ["--plot", str(outs[2])] if importlib.util.find_spec("matplotlib") else []
    assert main(args) == 2
    _assert_one_line_error(capsys, path, f"line {line}: column 'gy' is 1e+308 lsb, beyond the +-100000 deg/s")
    assert not any(p.exists() for p in outs) and list(tmp_path.glob(".partial-*")) == []


def test_allan_outputs_are_checked_before_any_work(static_recording, tmp_path, capsys):
    path, _ = static_recording
    before = open(path, "rb").read()
    assert main(["allan", path, "--json", path, "--force"]) == 2
    _assert_one_line_error(capsys, "is an input")
    assert open(path, "rb").read() == before
    out = tmp_path / "a.json"
    out.write_text("keep me")
    assert main(["allan", path, "--json", str(out)]) == 2
    _assert_one_line_error(capsys, "exists")
    assert out.read_text() == "keep me"
    assert main(["allan", path, "--json", str(out), "--force", "--axes", "x"]) == 0
    assert list(json.loads(out.read_text())["axes"]) == ["x"]


def test_arma_refuses_gross_errors_too_naming_the_file_line(tmp_path, capsys):
    """arma models still-sensor noise as allan does: a spike is refused, not modelled (a 1e30 one gave
    sigma_a = 7.6e25 deg/s, exit 0); the line counts from the file even with --start-s."""
    pytest.importorskip("statsmodels")
    path, line = _spiked_bundled(tmp_path, "5e6")
    assert main(["arma", path, "--axis", "y", "--start-s", "1"]) == 2
    _assert_one_line_error(capsys, path, f"line {line} (sample 500)", "3 such sample(s)", "--keep-outliers")


def test_a_plot_format_matplotlib_cannot_write_is_refused_before_any_work(static_recording, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    path, _ = static_recording
    out = tmp_path / "a.json"
    assert main(["allan", path, "--json", str(out), "--plot", str(tmp_path / "a.jpg2")]) == 2
    assert "matplotlib cannot write .jpg2" in capsys.readouterr().err
    assert not out.exists()


def test_a_header_only_recording_is_one_line_naming_the_file(tmp_path, capsys):
    path = tmp_path / "empty.csv"
    path.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\nt,gx,gy,gz\n")
    assert main(["allan", str(path)]) == 2
    _assert_one_line_error(capsys, str(path), "no samples (the file has a header only)")


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_moving_axis_is_analysed_with_a_warning_and_a_still_one_without(tmp_path, capsys, seed):
    """allan (like gap) says when an axis moves: a slow turn of a drawn size on a drawn axis is
    named, the still axes and the bundled static logs are not."""
    rng = np.random.default_rng(seed)
    n, fs = 6000, 100.0
    g = np.array([-3.3, 1.1, -0.5]) + rng.normal(0, 0.1, (n, 3))
    axis = int(rng.integers(3))
    amplitude = float(rng.uniform(3.0, 40.0))
    g[:, axis] += amplitude * np.sin(2 * np.pi * rng.uniform(0.05, 0.5) * np.arange(n) / fs)
    path = _write(tmp_path / "moving.csv", g)
    assert main(["allan", path]) == 0
    err = capsys.readouterr().err
    for i, a in enumerate("xyz"):
        assert (f"axis {a}: the rate moves by up to" in err) == (i == axis), err
    assert "does not look static" in err


def test_the_bundled_static_logs_look_static():
    from gyrofilter.analysis.still import not_static, read_axes
    from support import RECORDINGS

    for path in sorted(RECORDINGS.glob("mpu6050_static_*.csv.gz")):
        head, series = read_axes(str(path), "xyz")
        for a, x in series.items():
            assert not_static(x, head.sample_rate_hz, float(np.std(np.diff(x))) / math.sqrt(2)) is None, (path.name, a)
    head, series = read_axes(str(RECORDINGS / "mpu6050_rotate_z_24s.csv.gz"), "z")
    assert "does not look static" in not_static(series["z"], head.sample_rate_hz, 0.1)


def test_a_read_off_where_the_fit_resolves_nothing_is_labelled_an_upper_estimate(tmp_path, capsys):
    """Issue 23: the console printed "B not resolved (< 0.0015)" and "read-off: 0.00261" for one
    axis, as if both were B. The read-off is the slope method, another estimator: labelled so,
    and where the fit resolves no term but the read-off gives a number, said to be an upper
    estimate. The 655-s still log has such an axis (checked below, so the test is not empty)."""
    from gyrofilter.analysis.noise.export import JSON_KEY
    from gyrofilter.analysis.noise.model import TERM_SYMBOL, TERMS
    from support import RECORDINGS

    out = tmp_path / "a.json"
    assert main(["allan", str(RECORDINGS / "mpu6050_static_655s.csv.gz"), "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert "read-off:" not in printed.replace("slope read-off:", "")
    assert "another estimator" in printed and "read-off" in doc["method"]["readoff"]
    seen = 0
    for axis, ax in doc["axes"].items():
        block = " ".join(printed.split(f"  axis {axis}:\n")[1].split("  axis ")[0].split())  # wrapped lines joined
        for t in TERMS:
            key, sym = JSON_KEY[t], TERM_SYMBOL[t]
            disagree = ax["coefficients"][key] is None and ax["readoff"][key]["resolved"]
            said = f"({sym}: the fit does not resolve it" in block and f"an upper estimate, not a value of {sym})" in block
            assert said == disagree, (axis, sym, block)
            seen += disagree
    assert seen  # B on y: the fit's < 0.0015 deg/s, the read-off 0.0026 deg/s


def test_the_moving_warning_is_in_the_json_warnings_of_its_axis_only(tmp_path, capsys):
    """Issue 23: "does not look static" was printed but missing from the JSON's warnings."""
    rng = np.random.default_rng(7)
    n, fs = 6000, 100.0
    g = np.array([-3.3, 1.1, -0.5]) + rng.normal(0, 0.1, (n, 3))
    g[:, 1] += 20.0 * np.sin(2 * np.pi * 0.2 * np.arange(n) / fs)
    out = tmp_path / "a.json"
    assert main(["allan", _write(tmp_path / "moving.csv", g), "--json", str(out)]) == 0
    err = capsys.readouterr().err
    assert err.count("does not look static") == 1
    warnings = {a: ax["warnings"] for a, ax in json.loads(out.read_text())["axes"].items()}
    assert [a for a, w in warnings.items() if any("does not look static" in text for text in w)] == ["y"]
    assert any(w.startswith("axis y: the rate moves by up to") for w in warnings["y"])


@pytest.mark.parametrize("command", ["allan", "arma"])
@pytest.mark.parametrize("kind", ["tiny", "alternating"])
def test_numerically_degenerate_recordings_end_in_a_result_or_one_line_naming_the_file(tmp_path, capsys, command, kind):
    """Legal recordings that ended in "SVD did not converge" (allan) or "math domain error" (arma)
    without the file (issue 22, hostile case 3-1): noise of 1e-300 deg/s is refused naming the
    file and the floor; +-1 alternating data give an Allan result, and arma refuses them."""
    if command == "arma":
        pytest.importorskip("statsmodels")
    n = 3000
    g = (np.random.default_rng(0).normal(size=(n, 3)) * 1e-300 if kind == "tiny"
         else np.tile(((-1.0) ** np.arange(n))[:, None], 3))
    path = _write(tmp_path / f"{kind}.csv", g, lsb=False)
    code = main([command, path, "--json", str(tmp_path / "out.json")])
    if command == "allan" and kind == "alternating":
        assert code == 0
        assert "Infinity" not in (tmp_path / "out.json").read_text() and "NaN" not in (tmp_path / "out.json").read_text()
        return
    assert code == 2
    why = "below 1e-100 deg/s" if kind == "tiny" else "predicts the series exactly"
    _assert_one_line_error(capsys, f"{kind}.csv: axis x: ", why)
    assert not (tmp_path / "out.json").exists()


HOSTILE_NAME = "unit7\naccelerometer_noise_density: 1.0e-9\n#.csv.gz"


def test_a_kalibr_range_beyond_the_record_is_refused_before_any_output(static_recording, tmp_path, capsys):
    """--kalibr-tau-s: outside the record's cluster times (300 s: up to 33 s) one line and exit 2,
    no file written, nothing printed; within them the yaml covers that range; without --kalibr refused."""
    path, _ = static_recording
    doc, yaml = tmp_path / "a.json", tmp_path / "imu.yaml"
    capsys.readouterr()
    assert main(["allan", path, "--json", str(doc), "--kalibr", str(yaml), "--kalibr-tau-s", "0.1,100"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.strip().splitlines()) == 1
    assert "--kalibr-tau-s 0.1,100 s reaches beyond the record's cluster times 0.01 .. 33" in err
    assert not doc.exists() and not yaml.exists()
    assert main(["allan", path, "--kalibr", str(yaml), "--kalibr-tau-s", "0.05,20"]) == 0
    assert "bounding pair over tau 0.05 .. 20 s" in yaml.read_text()
    assert "the pair that bounds every axis's Allan deviation over tau 0.05 .. 20 s" in capsys.readouterr().out
    assert main(["allan", path, "--kalibr-tau-s", "0.05,20"]) == 2
    assert "give --kalibr OUT.yaml as well" in capsys.readouterr().err


def yaml_keys(text):
    """The keys of a flat YAML document (what is left of each line that is not a comment)."""
    return [line.split(":", 1)[0] for line in text.splitlines() if line.split("#")[0].strip()]


def test_a_file_name_cannot_add_a_key_to_the_kalibr_yaml(static_recording, tmp_path):
    """Issue 37: the recording's name goes into a comment line with its line ends escaped."""
    path = tmp_path / HOSTILE_NAME
    shutil.copyfile(static_recording[0], path)
    yaml = tmp_path / "imu.yaml"
    assert main(["allan", str(path), "--kalibr", str(yaml)]) == 0
    text = yaml.read_text()
    assert yaml_keys(text) == ["gyroscope_noise_density", "gyroscope_random_walk", "rostopic", "update_rate"]
    assert "unit7\\naccelerometer_noise_density: 1.0e-9\\n#.csv.gz" in text


@pytest.mark.parametrize("name", ["ends in a backslash\\", "two characters \\n, not a line end.csv",
                                  'a "quoted": name #.csv', "nel\x85line.csv"])
def test_the_recording_name_in_the_kalibr_yaml_reads_back_exactly(static_recording, tmp_path, name):
    """Issue 37 (leftover): the name in the comment was escaped for controls only, so the two
    characters ``\\n`` read as a line end's escape, and a name ending in a backslash would end a
    quoted string early. The comment holds the name as a JSON string: it reads back exactly."""
    path = tmp_path / name
    shutil.copyfile(static_recording[0], path)
    out = tmp_path / "imu.yaml"
    assert main(["allan", str(path), "--kalibr", str(out)]) == 0
    text = out.read_text(encoding="utf-8")
    assert yaml_keys(text) == ["gyroscope_noise_density", "gyroscope_random_walk", "rostopic", "update_rate"]
    comment, = [line for line in text.splitlines() if line.startswith("# recording: ")]
    assert json.loads(comment.removeprefix("# recording: ")) == str(path)
    try:
        import yaml
    except ImportError:
        return
    assert yaml.safe_load(comment.removeprefix("# recording: ")) == str(path)
    assert set(yaml.safe_load(text)) == {"gyroscope_noise_density", "gyroscope_random_walk", "rostopic", "update_rate"}


def test_every_label_of_the_allan_figure_stays_inside_its_panel():
    """Issue 38: a read-off's label ran out of its panel in adev.png (the B read-off near the
    right end of the curve). Every annotation's box lies within its axes' box."""
    pytest.importorskip("matplotlib")
    from gyrofilter.analysis.noise.fit import characterise
    from gyrofilter.analysis.noise.plots import allan_figure
    from gyrofilter.plots import pyplot
    from gyrofilter.recording import read_recording
    from support import RECORDINGS

    rec = read_recording(str(RECORDINGS / "mpu6050_static_655s.csv.gz"))
    plt = pyplot()
    fig = allan_figure(plt, characterise(rec.gyro_dps, rec.sample_rate_hz), title="t")
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        outside = []
        for ax in fig.axes:
            box = ax.get_window_extent(renderer)
            for text in ax.texts:
                t = text.get_window_extent(renderer)
                if t.x0 < box.x0 - 1 or t.x1 > box.x1 + 1 or t.y0 < box.y0 - 1 or t.y1 > box.y1 + 1:
                    outside.append(text.get_text())
        assert [t for ax in fig.axes for t in ax.texts], "no read-off labels drawn"
        assert outside == []
    finally:
        plt.close(fig)


def test_a_record_of_three_samples_is_too_short_not_gross_errors(tmp_path, capsys):
    """The attack pass: on 3 samples the spike screen took every sample for a gross error (the one
    residual's robust sigma is 0); the refusal now says the record is too short."""
    path = tmp_path / "three.csv"
    write_recording(path, Recording.from_dps(np.array([[0.1, 0.2, 0.3], [0.2, 0.1, 0.3], [0.1, 0.3, 0.2]]), 100.0))
    assert main(["allan", str(path)]) == 2
    err = capsys.readouterr().err
    assert "gross error" not in err and "fewer than 9 clusters" in err


def _issue36_recording(path, seed, repeats=True):
    """16 min of examples/models/repeated_samples.json (43 Hz, 1.6 LSB of noise, 2 % of the rows
    repeated), or of the same model without the repeats."""
    from support import REPO

    from gyrofilter.sim.model import load_model
    from gyrofilter.sim.simulate import simulate

    model = load_model(REPO / "examples" / "models" / "repeated_samples.json")
    if not repeats:
        del model["repeated_samples"]
    write_recording(str(path), simulate(model, 960.0, seed=seed))
    return str(path)


def test_allan_warns_of_repeated_rows_and_writes_their_count(tmp_path, capsys):
    path = _issue36_recording(tmp_path / "rep.csv", seed=1)
    assert main(["allan", path, "--json", str(tmp_path / "a.json")]) == 0
    err = capsys.readouterr().err
    assert max(len(line) for line in err.splitlines()) <= MAX_LINE_CHARS  # wrapped (was 426 columns on one line)
    words = " ".join(err.split())
    assert "repeat the previous row exactly on every axis, chance 0." in words and "half the excess), N a little high" in words
    block = json.loads((tmp_path / "a.json").read_text())["repeated_rows"]
    assert block["applicable"] and block["p_value"] < 1e-3 and block["warning"] in words
    assert 0.004 < block["chance"] < 0.007 and block["excess_fraction_ci95"][0] < 0.02 < block["excess_fraction_ci95"][1]
    assert block["fraction"] == block["repeated"] / block["rows"]


@pytest.mark.parametrize("seed", [1, pytest.param(2, marks=pytest.mark.slow), pytest.param(3, marks=pytest.mark.slow)])
def test_allan_says_nothing_of_repeats_on_a_clean_record_of_the_same_noise(tmp_path, capsys, seed):
    path = _issue36_recording(tmp_path / "clean.csv", seed=seed, repeats=False)
    assert main(["allan", path, "--json", str(tmp_path / "a.json")]) == 0
    assert "repeat the previous row" not in capsys.readouterr().err
    block = json.loads((tmp_path / "a.json").read_text())["repeated_rows"]
    assert block["applicable"] and block["warning"] is None and block["p_value"] > 1e-3


def _six_axis(path, seed=5, n=30000, accel_unit="m/s^2"):
    """A still six-axis record: the gyro of the static fixture's kind, the accelerometer white + a random walk
    with 1 g on z (m/s^2)."""
    rng = np.random.default_rng(seed)
    gyro = np.array([-3.3, 1.1, -0.5]) + rng.normal(0.0, 0.1, (n, 3))
    accel = (np.array([0.2, -0.3, 9.80665]) + rng.normal(0.0, 0.04, (n, 3))
             + np.cumsum(rng.normal(0.0, 1e-4, (n, 3)), axis=0))
    write_recording(str(path), Recording.from_dps(gyro, 100.0, accel=accel, accel_unit=accel_unit))
    return str(path), gyro


def test_a_six_axis_record_gets_the_accelerometers_table_json_block_and_kalibr_keys(tmp_path, capsys):
    """Issue 39: the accelerometer's table after the gyro's, in m/s units; --json's accelerometer block
    (the gyro's part the same as of the gyro alone); --kalibr's four keys; --axes applies to both."""
    path, gyro = _six_axis(tmp_path / "six.csv")
    gyro_only = _write(tmp_path / "gyro.csv", gyro, lsb=False)
    assert main(["allan", path, "--json", str(tmp_path / "six.json"), "--kalibr", str(tmp_path / "six.yaml")]) == 0
    out = capsys.readouterr().out
    assert out.index("accelerometer:") > out.index("  axis z:")
    table = out[out.index("accelerometer:"):]
    assert "N m/s/sqrt(s)" in table and "B m/s^2" in table and "K m/s^2/sqrt(s)" in table and "velocity random walk" in table
    assert all(len(line) <= MAX_LINE_CHARS for line in out.splitlines())
    assert main(["allan", gyro_only, "--json", str(tmp_path / "gyro.json")]) == 0
    six, alone = (json.loads((tmp_path / f"{name}.json").read_text()) for name in ("six", "gyro"))
    assert six["axes"] == alone["axes"] and six["method"] == alone["method"] and "accelerometer" not in alone
    acc = six["accelerometer"]["axes"]
    assert sorted(acc) == ["x", "y", "z"]
    for a in "xyz":  # white noise of 0.04 m/s^2 per sample at 100 Hz: N = 0.004 m/s/sqrt(s)
        n = acc[a]["coefficients"]["vrw_mps2_per_sqrt_hz"]
        assert n["low"] <= 0.004 <= n["high"]
        assert acc[a]["kalibr"]["accelerometer_noise_density"] == pytest.approx(n["value"])
    text = (tmp_path / "six.yaml").read_text()
    for key in ("gyroscope_noise_density", "gyroscope_random_walk", "accelerometer_noise_density",
                "accelerometer_random_walk"):
        assert f"\n{key}: " in text
    assert "not estimated here" not in text
    assert main(["allan", path, "--axes", "z", "--json", str(tmp_path / "z.json")]) == 0
    z = json.loads((tmp_path / "z.json").read_text())
    assert sorted(z["axes"]) == ["z"] and sorted(z["accelerometer"]["axes"]) == ["z"]


def test_a_spike_in_the_accelerometer_alone_leaves_it_out_and_keeps_the_gyros_document(tmp_path, capsys):
    """One accelerometer spike refused the whole command (exit 2, no gyro result), where the gyro's
    part of the document is the same with or without the accelerometer (attack pass 11): the
    accelerometer is left out with the refusal as a warning; --keep-outliers analyses it."""
    path, gyro = _six_axis(tmp_path / "six.csv")
    text = open(path).read().splitlines(True)
    row = len(text) - 100
    cells = text[row].rstrip("\n").split(",")
    cells[-1] = "500"  # az: 500 m/s^2 for one sample
    text[row] = ",".join(cells) + "\n"
    spiked = tmp_path / "spiked.csv"
    spiked.write_text("".join(text))
    gyro_only = _write(tmp_path / "gyro.csv", gyro, lsb=False)
    assert main(["allan", str(spiked), "--json", str(tmp_path / "s.json")]) == 0
    err = capsys.readouterr().err
    assert "az = 500 m/s^2 is a gross error" in err and "left out of the Allan analysis" in " ".join(err.split())
    assert main(["allan", gyro_only, "--json", str(tmp_path / "g.json")]) == 0
    got, alone = (json.loads((tmp_path / f"{name}.json").read_text()) for name in ("s", "g"))
    assert "accelerometer" not in got and got["axes"] == alone["axes"]
    assert main(["allan", str(spiked), "--keep-outliers", "--json", str(tmp_path / "k.json")]) == 0
    assert sorted(json.loads((tmp_path / "k.json").read_text())["accelerometer"]["axes"]) == ["x", "y", "z"]


@pytest.mark.parametrize("cause", ["gravity", "spike", "constant"])
def test_the_json_says_the_accelerometer_was_left_out_and_why(tmp_path, capsys, cause):
    """An accelerometer left out whole (it reads 9.8 g at rest under a header that says g, a spike
    of 500 m/s^2, every axis stuck) was said only on the console: the --json document had no
    accelerometer block, as a gyro-only record's (attack pass 11). Its accelerometer_left_out
    says why, the warning's words; the gyro's part is the same; a record whose accelerometer was
    analysed has no such key."""
    path, gyro = _six_axis(tmp_path / "six.csv", accel_unit="g" if cause == "gravity" else "m/s^2")
    if cause == "spike":
        text = open(path).read().splitlines(True)
        text[-100] = ",".join(text[-100].split(",")[:-1] + ["500"]) + "\n"  # az: 500 m/s^2 for one sample
        open(path, "w").write("".join(text))
    elif cause == "constant":
        write_recording(path, Recording.from_dps(gyro, 100.0, accel=np.tile([0.0, 0.0, 9.80665], (len(gyro), 1)),
                                                 accel_unit="m/s^2"))
    assert main(["allan", path, "--json", str(tmp_path / "left.json")]) == 0
    err = " ".join(capsys.readouterr().err.split())
    why = {"gravity": "the accelerometer reads 9.81 g at rest (the median |a|)", "spike": "az = 500 m/s^2 is a gross error",
           "constant": "every accelerometer axis analysed (ax, ay, az) is constant"}[cause]
    left = json.loads((tmp_path / "left.json").read_text())
    assert "accelerometer" not in left and left["accelerometer_left_out"].startswith(f"{path}: ")
    assert why in left["accelerometer_left_out"] and (cause == "constant" or left["accelerometer_left_out"] in err), err
    assert main(["allan", _write(tmp_path / "gyro.csv", gyro, lsb=False), "--json", str(tmp_path / "gyro.json")]) == 0
    alone = json.loads((tmp_path / "gyro.json").read_text())
    assert {k: v for k, v in left.items() if k not in ("recording", "accelerometer_left_out", "warnings")} == \
        {k: v for k, v in alone.items() if k not in ("recording", "warnings")}
    assert alone["warnings"] == [] and any(w.endswith("left out of the Allan analysis") for w in left["warnings"])
    assert main(["allan", _six_axis(tmp_path / "good.csv")[0], "--json", str(tmp_path / "good.json")]) == 0
    assert "accelerometer_left_out" not in json.loads((tmp_path / "good.json").read_text())


def test_accelerometer_columns_without_accel_unit_leave_the_gyro_as_it_was_and_one_warning(tmp_path, capsys):
    """Issue 39 (trial): the missing accel_unit was a note on stdout in allan and a warning in
    report; now one rule (characterise_recording warns), the same warning in allan, report and the fleet."""
    path, gyro = _six_axis(tmp_path / "six.csv")
    stripped = tmp_path / "no_unit.csv"
    stripped.write_text("".join(line for line in open(path).read().splitlines(True)
                                if not line.startswith("# accel_unit")))
    assert main(["allan", str(stripped), "--json", str(tmp_path / "a.json"), "--kalibr", str(tmp_path / "k.yaml")]) == 0
    captured = capsys.readouterr()
    assert "accelerometer:" not in captured.out and "note:" not in captured.out
    said = "the accelerometer (ax, ay, az) is not analysed: the header has no accel_unit"
    warnings = [w for w in captured.err.split("gyrofilter: warning: ") if w]
    assert sum(said in " ".join(w.split()) for w in warnings) == 1
    assert "accelerometer" not in json.loads((tmp_path / "a.json").read_text())
    assert "not estimated here" in (tmp_path / "k.yaml").read_text()
    fleet = work.analyse_recording(str(stripped), work.FleetSettings("allan"))
    assert sum(w.startswith(said) for w in fleet["warnings"]) == 1


def test_the_filters_output_is_said_to_be_the_filters_and_its_jumps_not_called_spikes(tmp_path, capsys):
    """A new user ran allan on replay --out and read N = 2.8e-5 and a resolved K as the sensor's, exit 0, not a word:
    a filter's output (``filtered_from``) is analysed with a warning that it is the filter's. Attack pass 60: on six
    example models' outputs it was refused as "a spike beyond 50 robust sigmas", unexplained: the refusal says the
    jumps may be the filter's own and names the recording to analyse, or --keep-outliers; a sensor's spike is refused
    as before."""
    rng = np.random.default_rng(60)
    x = np.cumsum(rng.normal(0.0, 1e-5, (4000, 3)), axis=0)  # smooth, as block means after the Kalman filter are
    header = {"filtered_from": "rec.csv", "input_sample_rate_hz": "100"}
    smooth = tmp_path / "smooth.csv"
    write_recording(smooth, Recording.from_dps(x, 20.0, header=header))
    assert main(["allan", str(smooth)]) == 0
    err = " ".join(capsys.readouterr().err.split())
    assert "smooth.csv: is the filter's output (filtered_from 'rec.csv'), not the sensor's samples: its Allan " \
           "deviation is the filter's" in err
    x[2000:, 1] -= 0.03  # where it follows the bias at once
    raw, filtered = tmp_path / "raw.csv", tmp_path / "filtered.csv"
    write_recording(raw, Recording.from_dps(x, 20.0))
    write_recording(filtered, Recording.from_dps(x, 20.0, header=header))
    assert main(["allan", str(filtered)]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    for part in ("filtered.csv: line", "gross error", "this is the filter's output (filtered_from 'rec.csv')",
                 "jumps may be the filter's own", "analyse the recording it was filtered from, or rerun with --keep-outliers"):
        assert part in err, err
    assert main(["allan", str(raw)]) == 2
    err = capsys.readouterr().err
    assert "gross error" in err and "filtered_from" not in err


def test_kalibr_on_the_filters_output_is_refused_and_the_fleet_writes_no_yaml_for_it(tmp_path, capsys):
    """A new user's `run --out` then `allan --kalibr` wrote gyroscope_noise_density 3.8e-7 for the
    sensor's 2.4e-4 (block means of bias-removed rates), silently: the filter's output is not the
    sensor; one line, exit 2, nothing written. The fleet analyses it but writes no imu.yaml, saying why."""
    path, _ = _six_axis(tmp_path / "six.csv")
    filtered = str(tmp_path / "filtered.csv")
    assert main(["replay", path, "--out", filtered]) == 0
    capsys.readouterr()
    out = tmp_path / "f.yaml"
    assert main(["allan", filtered, "--kalibr", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()  # the analysis' warning that it is the filter's, then the refusal
    assert err[-1].startswith("gyrofilter: error:") and not any(ln.startswith("gyrofilter: error:") for ln in err[:-1])
    assert all(part in err[-1] for part in ("--kalibr", "filtered.csv", "the filter's output", "filtered_from")), err
    assert not out.exists()
    assert main(["allan", filtered, path, "--fleet", str(tmp_path / "fleet")]) == 0
    assert not (tmp_path / "fleet" / "filtered.imu.yaml").exists() and (tmp_path / "fleet" / "six.imu.yaml").exists()
    assert "imu.yaml not written: the recording is the filter's output" in (tmp_path / "fleet" / "fleet.csv").read_text()


def test_the_kalibr_yaml_says_which_axes_and_what_warnings_its_values_carry(tmp_path, capsys):
    """A new user: a tilted accelerometer (a 0.2 g step on ax) wrote a random walk 1000x a real one
    with the console's warning nowhere in the yaml; `--axes xz` wrote values bounding x and z only,
    unsaid. The yaml now says both, one comment line each, and its values are the same."""
    path, gyro = _six_axis(tmp_path / "six.csv")
    rec_accel = np.array([0.2, -0.3, 9.80665]) + np.random.default_rng(1).normal(0.0, 0.04, (len(gyro), 3))
    rec_accel[len(gyro) // 2:, 0] += 0.2 * 9.80665  # tilted half-way
    tilted = str(tmp_path / "tilt.csv")
    write_recording(tilted, Recording.from_dps(gyro, 100.0, accel=rec_accel, accel_unit="m/s^2"))
    assert main(["allan", tilted, "--kalibr", str(tmp_path / "tilt.yaml")]) == 0
    said = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    yaml = (tmp_path / "tilt.yaml").read_text()
    assert said and any(line.startswith("# warning: ") and "acceleration" in line for line in yaml.splitlines()), yaml
    assert main(["allan", path, "--axes", "xz", "--kalibr", str(tmp_path / "xz.yaml")]) == 0
    yaml = (tmp_path / "xz.yaml").read_text()
    assert "# gyroscope: only axes x, z analysed (of x, y, z)" in yaml
    assert "# accelerometer: only axes x, z analysed (of x, y, z)" in yaml


def test_the_accelerometer_of_the_filters_output_is_left_out(tmp_path, capsys):
    """A new user's trial: `run --out` keeps one raw accelerometer sample per output row (1 in 5 at
    the default preset); allan read its density sqrt(5) times the sensor's (900 ug/sqrt(Hz) for 390)
    with no word. It is left out, said, and named in the JSON; the raw record's is analysed."""
    path, _ = _six_axis(tmp_path / "six.csv")
    out = tmp_path / "run_out.csv"
    assert main(["run", "--source", f"replay:{path}", "--out", str(out), "--quiet"]) == 0
    head = read_recording(str(out))
    assert "filtered_from" in head.header and all(c in head.columns for c in ("ax", "ay", "az"))
    capsys.readouterr()
    assert main(["allan", str(out), "--json", str(tmp_path / "out.json")]) == 0
    err = " ".join(capsys.readouterr().err.split())
    doc = json.loads((tmp_path / "out.json").read_text())
    assert "accelerometer" not in doc and "not the sensor's" in doc["accelerometer_left_out"]
    assert "1 in 5 of the sensor's samples" in doc["accelerometer_left_out"] and doc["accelerometer_left_out"] in err
    assert "the density reads sqrt(5) = 2.24 times it" in err  # a new user's second trial: k was not said
    assert main(["allan", path, "--json", str(tmp_path / "raw.json")]) == 0
    raw = json.loads((tmp_path / "raw.json").read_text())
    assert "accelerometer" in raw and "accelerometer_left_out" not in raw


def test_a_term_unresolved_once_k_is_free_is_not_blamed_on_the_misfit():
    """'B in the fitted model but not resolved: with the fit's misfit (reduced chi-square 0.45) the
    interval reaches zero' was said where chi2_nu < 1 widens nothing: B is within its uncertainty of
    zero once K (not resolved) is free. The misfit's advice to see `gyrofilter gap` is for the gyro
    only (gap analyses the gyro). Default MPU6050 model, 60 min, seed 10, x."""
    rec = simulate(tool("allan_coverage").default_model(), 3600.0, seed=10)
    r = characterise_axis(rec.gyro_dps[:, 0], 100.0)
    assert r.fit_reduced_chi2 < 1 and r.fit_values[2] > 0 and r.fitted[BIAS_INSTABILITY].value is None
    text = allan.unresolved_text(r, 9)
    assert "B in the fitted model but not resolved: within its uncertainty of zero once K (not resolved) is free" in text
    assert "misfit" not in text and "gyrofilter gap" not in text
    # the same B unresolved by the misfit: the advice to see gap for the gyro, not the accelerometer
    r.fitted[BIAS_INSTABILITY] = dataclasses.replace(r.fitted[BIAS_INSTABILITY], freed_by=())
    assert "the interval reaches zero" in allan.unresolved_text(r, 9, GYROSCOPE_TERMS)
    assert "(see `gyrofilter gap`)" in allan.unresolved_text(r, 9, GYROSCOPE_TERMS)
    assert "gyrofilter gap" not in allan.unresolved_text(r, 9, ACCELEROMETER_TERMS)


def test_the_json_document_says_the_records_lost_samples(tmp_path, capsys):
    """Attack pass 15: a record that lost samples gave an allan document with no word of it (only the
    console warned), though its N reads off by sqrt(k) where one sample in k was kept: the document
    carries the gaps' count and the console's sentence; a record without gaps has no such block."""
    rng = np.random.default_rng(23)
    steps = np.where(np.arange(5999) % 4 == 3, 0.02, 0.01)  # a sample lost after every third
    t = np.concatenate(([0.0], np.cumsum(steps)))
    gappy = tmp_path / "gaps.csv"
    write_recording(gappy, Recording.from_dps(rng.normal(0.5, 0.1, (6000, 3)), 100.0, t_s=t))
    assert main(["allan", str(gappy), "--json", str(tmp_path / "g.json")]) == 0
    said = " ".join(capsys.readouterr().err.split())  # the console wraps its lines
    doc = json.loads((tmp_path / "g.json").read_text())
    assert doc["t_gaps"]["count"] == int(np.count_nonzero(steps > 0.015)) == 1499
    assert doc["t_gaps"]["warning"].startswith(f"{gappy}: t shows 1499 gap(s)")
    assert said.count(" ".join(doc["t_gaps"]["warning"].split())) == 1
    plain = tmp_path / "plain.csv"
    write_recording(plain, Recording.from_dps(rng.normal(0.5, 0.1, (6000, 3)), 100.0))
    assert main(["allan", str(plain), "--json", str(tmp_path / "p.json")]) == 0
    assert "t_gaps" not in json.loads((tmp_path / "p.json").read_text())
