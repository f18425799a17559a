import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from gyrofilter import GyroFilter
from gyrofilter.cli import main
from gyrofilter.cli.filtering import ROW_FORMATS
from gyrofilter.recording import Recording, RecordingWriter, dps_header, read_recording, write_recording
from support import REPO


def test_replay_without_argument_filters_the_bundled_recording(capsys):
    assert main(["replay"]) == 0
    out = capsys.readouterr().out
    assert "mpu6050_static_100s.csv.gz" in out
    rows = [ln.split() for ln in out.splitlines() if ln.strip()[:2] in ("x ", "y ", "z ")]
    assert [r[0] for r in rows] == ["x", "y", "z"]
    for r in rows:
        raw_std, filt_std, ratio = float(r[2]), float(r[4]), float(r[5].rstrip("x"))
        half = 0.5e-4  # the stds are printed with 4 decimals: the ratio lies within their rounding
        assert (raw_std - half) / (filt_std + half) <= ratio <= (raw_std + half) / (filt_std - half) and ratio > 2


def test_the_bundled_recordings_figure_is_titled_by_its_name_not_the_package_path(tmp_path, monkeypatch, capsys):
    """Issue 38: ``replay --plot`` titled the figure with the absolute path of the installed package."""
    import gyrofilter.plots

    titles = []

    def plot_filtered(path, raw, filtered, title):
        titles.append(title)
        open(path, "wb").close()

    monkeypatch.setattr(gyrofilter.plots, "plot_filtered", plot_filtered)
    monkeypatch.setattr(gyrofilter.plots, "check_figure_path", lambda path: None)
    assert main(["replay", "--plot", str(tmp_path / "r.png")]) == 0
    assert titles == ["mpu6050_static_100s.csv.gz (bundled) (raw minus start-up bias)"]


def test_a_replay_without_a_start_up_calibration_says_so_in_its_figure_and_table(tmp_path, monkeypatch, capsys):
    """A new user's trial: with --calibration FILE (the moving mpu6050_rotate_z_24s needs one) the figure's title
    still said "raw minus start-up bias" and the table's note "the samples after the calibration window", though
    no window was taken; with --calibration-s 0 nothing is removed at all."""
    import gyrofilter.plots

    titles = []
    monkeypatch.setattr(gyrofilter.plots, "plot_filtered", lambda path, raw, filtered, title: titles.append(title)
                        or open(path, "wb").close())
    monkeypatch.setattr(gyrofilter.plots, "check_figure_path", lambda path: None)
    cal = tmp_path / "cal.json"
    assert main(["replay", "--save-calibration", str(cal)]) == 0
    notes = []
    for extra in (["--calibration", str(cal)], ["--calibration-s", "0", "--preset", "paper"], []):
        capsys.readouterr()
        assert main(["replay", "--plot", str(tmp_path / f"r{len(notes)}.png"), *extra]) == 0
        notes.append(capsys.readouterr().out.split("(deg/s; ")[1])
    assert titles == [f"mpu6050_static_100s.csv.gz (bundled) (raw minus the bias loaded from {cal})",
                      "mpu6050_static_100s.csv.gz (bundled) (raw)",
                      "mpu6050_static_100s.csv.gz (bundled) (raw minus start-up bias)"]
    assert [("after the calibration window" in n, "no bias removed" in n) for n in notes] == [
        (False, False), (False, True), (True, False)]
    assert all("rejected = samples left out of their block's mean as gross errors" in n for n in notes)


def test_a_missing_csv_whose_gz_exists_names_it(tmp_path, capsys):
    """Issue 38: a .csv/.csv.gz mix-up said only "No such file"."""
    write_recording(tmp_path / "rec.csv.gz", Recording.from_dps(np.zeros((10, 3)), 100.0))
    assert main(["replay", str(tmp_path / "rec.csv")]) == 2
    assert capsys.readouterr().err.rstrip().endswith(f"No such file or directory; there is {tmp_path / 'rec.csv.gz'}")
    assert main(["convert", str(tmp_path / "rec.csv"), "--out", str(tmp_path / "o.csv")]) == 2
    assert f"; there is {tmp_path / 'rec.csv.gz'}" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["replay", "allan"])
def test_a_dash_for_the_standard_input_says_how_to_give_it(tmp_path, command):
    """Attack pass 59: ``cat f | gyrofilter replay -`` said only "-: cannot read: No such file or directory"."""
    with open(REPO / "recordings" / "mpu6050_static_100s.csv.gz", "rb") as stdin:
        run = subprocess.run([sys.executable, "-m", "gyrofilter", command, "-"], stdin=stdin, cwd=tmp_path,
                             capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and run.stderr == ("gyrofilter: error: -: cannot read: No such file or directory; to read "
                                                  "the standard input give /dev/stdin (convert alone reads it as -)\n")


def test_replay_out_writes_the_filtered_series(tmp_path, capsys):
    rng = np.random.default_rng(0)
    src = tmp_path / "in.csv"
    write_recording(src, Recording.from_dps(rng.normal([1, 2, 3], 0.1, (1003, 3)), 100.0))
    out = tmp_path / "out.csv.gz"
    assert main(["replay", str(src), "--out", str(out), "--save-calibration", str(tmp_path / "cal.json")]) == 0
    rec = read_recording(out)
    assert len(rec) == (1003 - 200) // 5 and rec.sample_rate_hz == 20.0
    np.testing.assert_allclose(rec.t_s[:2], [2.04, 2.09])  # end of the first blocks after calibration
    assert "3 trailing sample(s)" in capsys.readouterr().out
    assert main(["replay", str(src), "--calibration", str(tmp_path / "cal.json")]) == 0


@pytest.mark.parametrize(
    "args,message",
    [
        (["replay", "/no/such/file.csv"], "cannot read"),
        (["replay", "BAD"], "line 5: 2 values, expected 3"),
        (["replay", "MOVING"], "moved"),
        (["replay", "--preset", "nope"], "invalid choice"),
    ],
)
def test_bad_input_is_one_line_on_stderr_and_exit_2(tmp_path, args, message):
    bad = tmp_path / "bad.csv"
    bad.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\ngx,gy,gz\n1,2\n")
    rng = np.random.default_rng(1)
    moving = rng.normal(0, 0.1, (1000, 3))
    moving[50:150, 1] += np.linspace(0, 30, 100)
    write_recording(tmp_path / "moving.csv", Recording.from_dps(moving, 100.0))
    args = [{"BAD": str(bad), "MOVING": str(tmp_path / "moving.csv")}.get(a, a) for a in args]
    proc = subprocess.run([sys.executable, "-m", "gyrofilter", *args], capture_output=True, text=True)
    assert proc.returncode == 2
    assert message in proc.stderr and "Traceback" not in proc.stderr
    assert len(proc.stderr.splitlines()) == 1


def test_help_everywhere_exits_0():
    for args in (["--help"], ["replay", "--help"]):
        proc = subprocess.run([sys.executable, "-m", "gyrofilter", *args], capture_output=True, text=True)
        assert proc.returncode == 0 and "usage" in proc.stdout


def test_set_overrides_a_setting_and_is_recorded_in_the_output(tmp_path):
    rng = np.random.default_rng(2)
    src = tmp_path / "in.csv"
    write_recording(src, Recording.from_dps(rng.normal([1, 2, 3], 0.1, (2000, 3)), 100.0))
    out = tmp_path / "out.csv"
    assert main(["replay", str(src), "--out", str(out), "--set", "outlier_rule=median_slope", "--set", "block_len=4"]) == 0
    rec = read_recording(out)
    assert rec.sample_rate_hz == 25.0 and '"outlier_rule":"median_slope"' in rec.header["filter_settings"]
    assert main(["replay", str(src), "--set", "outlier_rule=nope"]) == 2
    with pytest.raises(SystemExit, match="2"):  # argparse's own refusal: argument --set: expected NAME=VALUE
        main(["replay", str(src), "--set", "no_equals"])


def test_temp_model_compensates_a_drift_from_a_gap_report(tmp_path, capsys):
    import json

    n = 60000
    rng = np.random.default_rng(3)
    temp = 30.0 + 12.0 * (1 - np.exp(-np.arange(n) / 15000))
    coef = [0.0, 0.04, 0.0]
    gyro = np.array([0.5, -1.0, 2.0]) + np.outer(temp - 30.0, coef) + rng.normal(0, 0.1, (n, 3))
    src = tmp_path / "warm.csv.gz"
    write_recording(src, Recording.from_dps(gyro, 100.0, temp_c=temp))
    report = tmp_path / "gap.json"
    report.write_text(json.dumps({"findings": [], "extended_model": {"axes": {
        "y": {"effects": [{"effect": "temperature", "coefficient_dps_per_c": 0.04}]}}}}))
    late_means = []
    for extra in ([], ["--temp-model", str(report)]):
        out = tmp_path / f"out{len(extra)}.csv"
        assert main(["replay", str(src), "--preset", "recommended", "--out", str(out)] + extra) == 0
        late_means.append(read_recording(out).gyro_dps[-2000:, 1].mean())
    # drift left: c (T - T0) ~ 0.45 deg/s; after: the calibration's own error, 0.1 / sqrt(200) = 0.007
    assert abs(late_means[0]) > 0.4 and abs(late_means[1]) < 0.03
    # no temp column, or a model without a temperature effect: one clear line
    write_recording(tmp_path / "cold.csv", Recording.from_dps(gyro[:1000], 100.0))
    assert main(["replay", str(tmp_path / "cold.csv"), "--temp-model", str(report)]) == 2
    assert "no temperature" in capsys.readouterr().err
    report.write_text(json.dumps({"axes": {"x": {"effects": []}}}))
    assert main(["replay", str(src), "--temp-model", str(report)]) == 2
    assert "no temperature effect" in capsys.readouterr().err


def test_a_calibration_saved_without_temp_model_serves_a_later_temp_model_run(tmp_path, capsys):
    import json

    rng = np.random.default_rng(4)
    temp = 30.0 + 0.001 * np.arange(3000)
    src = tmp_path / "warm.csv"
    write_recording(src, Recording.from_dps(rng.normal([0.5, -1.0, 2.0], 0.1, (3000, 3)), 100.0, temp_c=temp))
    cal = tmp_path / "cal.json"
    assert main(["replay", str(src), "--save-calibration", str(cal)]) == 0
    assert json.loads(cal.read_text())["temp_c"] == pytest.approx(temp[:200].mean())
    model = tmp_path / "model.json"
    model.write_text(json.dumps({"axes": {"y": {"effects": [{"effect": "temperature", "coefficient_dps_per_c": 0.04}]}}}))
    out = tmp_path / "comp.csv"
    assert main(["replay", str(src), "--calibration", str(cal), "--temp-model", str(model), "--out", str(out)]) == 0
    assert "temperature compensated (0, 0.04, 0 deg/s/degC)" in capsys.readouterr().out
    assert read_recording(out).header["calibration_from"] == str(cal)
    # from a recording without temperatures the saved calibration has none, and the later run says why
    write_recording(tmp_path / "cold.csv", Recording.from_dps(rng.normal(0, 0.1, (1000, 3)), 100.0))
    assert main(["replay", str(tmp_path / "cold.csv"), "--save-calibration", str(tmp_path / "cold.json")]) == 0
    assert main(["replay", str(src), "--calibration", str(tmp_path / "cold.json"), "--temp-model", str(model)]) == 2
    assert "came without temperatures" in capsys.readouterr().err


def test_set_takes_calibration_s_and_lists_and_refuses_what_has_its_own_option(tmp_path, capsys):
    rng = np.random.default_rng(12)
    src = tmp_path / "in.csv"
    write_recording(src, Recording.from_dps(rng.normal([1, 2, 3], 0.1, (1000, 3)), 100.0, temp_c=np.full(1000, 30.0)))
    outs = []
    for extra in (["--set", "calibration_s=1"], ["--calibration-s", "1"]):
        outs.append(tmp_path / f"o{len(outs)}.csv")
        assert main(["replay", str(src), "--out", str(outs[-1]), *extra]) == 0
    assert _data_lines(outs[0]) == _data_lines(outs[1]) and len(read_recording(outs[0])) == (1000 - 100) // 5
    out = tmp_path / "t.csv"
    assert main(["replay", str(src), "--out", str(out), "--set", "temp_coefficient_dps_per_c=0.01,0.02,0"]) == 0
    assert '"temp_coefficient_dps_per_c":[0.01,0.02,0]' in read_recording(out).header["filter_settings"]
    assert main(["replay", str(src), "--preset", "paper", "--calibration-s", "0"]) == 0
    assert "no calibration, so no bias removed" in capsys.readouterr().out
    for spelling in ("True", "true"):  # Python's spelling, as the settings' errors print it, and JSON's
        assert main(["replay", str(src), "--out", str(out), "--force", "--set", f"hold={spelling}"]) == 0
        assert '"hold":true' in read_recording(out).header["filter_settings"]
    capsys.readouterr()
    cal = tmp_path / "cal.json"
    assert main(["replay", str(src), "--save-calibration", str(cal)]) == 0
    for extra, message in ((["--set", "calibration_s=1", "--calibration-s", "2"], "both given"),
                           (["--set", "sample_rate_hz=50"], "comes from the recording"),
                           (["--set", "calibration=x.json"], "use --calibration JSON"),
                           (["--set", "calibration_s=abc"], "setting calibration_s must be a finite number, got 'abc'"),
                           (["--calibration", str(cal), "--calibration-s", "1"], "give one of them"),
                           # GyroFilter's own check now (issue 22): it names the value, not the option
                           (["--calibration", str(cal), "--set", "calibration_s=1"], "(calibration_s=1) has nothing to do"),
                           (["--set", "temp_coefficient_dps_per_c=0.01", "--temp-model", str(cal)], "both give the temperature"),
                           (["--preset", "paper", "--calibration-s", "0", "--save-calibration", str(tmp_path / "c0.json")],
                            "no calibration to save")):
        capsys.readouterr()
        assert main(["replay", str(src), *extra]) == 2, extra
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err, (extra, err)


def test_a_calibration_from_another_sample_rate_is_refused(tmp_path, capsys):
    rng = np.random.default_rng(13)
    fast, slow = tmp_path / "fast.csv", tmp_path / "slow.csv"
    write_recording(fast, Recording.from_dps(rng.normal(0, 0.1, (3000, 3)), 1000.0))
    write_recording(slow, Recording.from_dps(rng.normal(0, 0.1, (1000, 3)), 100.0))
    cal = tmp_path / "cal.json"
    assert main(["replay", str(fast), "--save-calibration", str(cal)]) == 0
    capsys.readouterr()
    assert main(["replay", str(slow), "--calibration", str(cal)]) == 2
    assert f"calibration {cal} was made at 1000 Hz and this filter runs at 100 Hz" in capsys.readouterr().err
    write_recording(tmp_path / "near.csv", Recording.from_dps(rng.normal(0, 0.1, (3000, 3)), 1030.0))
    assert main(["replay", str(tmp_path / "near.csv"), "--calibration", str(cal)]) == 0  # within 5 %


def test_all_outputs_land_together_or_none_does(tmp_path, capsys, monkeypatch):
    """--out, --plot and --save-calibration go through one commit: missing folders are made for
    each, and a failure in the last of them leaves none behind."""
    pytest.importorskip("matplotlib")
    import gyrofilter.plots

    rng = np.random.default_rng(14)
    src = tmp_path / "in.csv"
    write_recording(src, Recording.from_dps(rng.normal(0, 0.1, (1000, 3)), 100.0))
    out, plot, cal = tmp_path / "a" / "o.csv", tmp_path / "b" / "p.png", tmp_path / "c" / "d" / "cal.json"
    assert main(["replay", str(src), "--out", str(out), "--plot", str(plot), "--save-calibration", str(cal)]) == 0
    assert len(read_recording(out)) == 160 and plot.stat().st_size > 0 and "bias_dps" in cal.read_text()

    def broken(path, *args, **kwargs):
        raise OSError(28, "No space left on device", path)

    monkeypatch.setattr(gyrofilter.plots, "plot_filtered", broken)
    out2, plot2 = tmp_path / "e" / "o.csv", tmp_path / "f" / "p.png"
    assert main(["replay", str(src), "--out", str(out2), "--plot", str(plot2)]) == 2
    err = capsys.readouterr().err
    assert f"{plot2}: No space left on device" in err, err
    assert not (tmp_path / "e").exists() and not (tmp_path / "f").exists()
    for option in ("--out", "--plot", "--save-calibration"):  # argparse names the option
        with pytest.raises(SystemExit) as info:
            main(["replay", str(src), option, ""])
        assert info.value.code == 2 and f"argument {option}: an empty name" in capsys.readouterr().err
    assert main(["replay", str(src), "--out", str(tmp_path / "a")]) == 2 and "is a folder" in capsys.readouterr().err


def _data_lines(path):
    import gzip

    opener = gzip.open if str(path).endswith(".gz") else open
    with opener(path, "rt") as fh:
        return [ln for ln in fh if not ln.startswith("#")]


@pytest.mark.parametrize("chunk_rows", [7, 1000])
def test_replay_in_chunks_writes_the_rows_of_the_one_shot_filter(tmp_path, monkeypatch, chunk_rows):
    """The old replay filtered everything at once: GyroFilter.filter(all samples), rows stamped
    with the t of each block's last sample; the chunked one must write exactly those rows."""
    from gyrofilter import GyroFilter
    from gyrofilter.cli import replay

    rng = np.random.default_rng(7)
    n = 3003
    t = np.cumsum(rng.uniform(0.009, 0.011, n))  # irregular t: the stamps must come from the column
    gyro = np.array([0.5, -1.0, 2.0]) + rng.normal(0, 0.1, (n, 3))
    gyro[1500:1505, 2] += 30.0  # some spikes for the outlier rejection
    src = tmp_path / "in.csv"
    write_recording(src, Recording.from_dps(gyro, 100.0, t_s=t))
    rec = read_recording(src)
    filt = GyroFilter(100.0)
    rows = filt.filter(rec.gyro_dps)
    expected = tmp_path / "expected.csv"
    with RecordingWriter(expected, dps_header({}, 20.0), ["t", "gx", "gy", "gz"], formats=ROW_FORMATS) as writer:
        writer.write(np.column_stack([rec.t_s[filt.block_end_indices(len(rows))], rows]))
    monkeypatch.setattr(replay, "CHUNK_ROWS", chunk_rows)
    out = tmp_path / "out.csv"
    assert main(["replay", str(src), "--out", str(out)]) == 0
    assert _data_lines(out) == _data_lines(expected) and len(_data_lines(out)) == len(rows) + 1


def test_realtime_rows_carry_the_same_time_stamps_as_out(tmp_path, capsys):
    rng = np.random.default_rng(8)
    n = 700
    src = tmp_path / "fast.csv"
    write_recording(src, Recording.from_dps(rng.normal(0, 0.1, (n, 3)), 5000.0))  # paced: 0.14 s
    out = tmp_path / "out.csv"
    assert main(["replay", str(src), "--realtime", "--calibration-s", "0.02", "--out", str(out)]) == 0
    printed = [ln for ln in capsys.readouterr().out.splitlines() if ln[:1].isdigit()]
    stamps = [float(ln.split(",")[0]) for ln in printed]
    filtered = read_recording(out)
    assert len(stamps) == len(filtered) == (n - 100) // 5
    np.testing.assert_allclose(stamps, filtered.t_s, rtol=0, atol=1e-9)
    assert stamps[0] == pytest.approx(104 / 5000.0)  # samples 100..104 make the first block


def test_a_loaded_calibration_is_named_as_such(tmp_path, capsys):
    rng = np.random.default_rng(9)
    src = tmp_path / "in.csv"
    write_recording(src, Recording.from_dps(rng.normal([1, 2, 3], 0.1, (1000, 3)), 100.0))
    cal = tmp_path / "cal.json"
    assert main(["replay", str(src), "--save-calibration", str(cal)]) == 0
    assert "start-up calibration, 200 samples" in capsys.readouterr().out
    assert main(["replay", str(src), "--calibration", str(cal)]) == 0
    out = capsys.readouterr().out
    assert f"bias (loaded from {cal})" in out and "start-up calibration" not in out


def test_summary_is_readable_for_constant_and_huge_values(tmp_path, capsys):
    from types import SimpleNamespace

    from gyrofilter.cli.console import print_summary
    from gyrofilter.streamstats import RunningMoments

    gyro = np.column_stack([np.full(1200, 2.0), np.random.default_rng(10).normal(0, 0.1, 1200), np.full(1200, 3.0)])
    src = tmp_path / "stuck.csv"
    write_recording(src, Recording.from_dps(gyro, 100.0))
    assert main(["replay", str(src)]) == 0  # x and z: 0 deg/s after the bias, raw and filtered std 0
    rows = {ln.split()[0]: ln for ln in capsys.readouterr().out.splitlines() if ln.strip()[:2] in ("x ", "y ", "z ")}
    assert "inf" not in "".join(rows.values()) and "n/a" in rows["x"] and "n/a" not in rows["y"]
    raw, filtered = RunningMoments(3), RunningMoments(3)
    raw.add(np.array([[1e150, 1e-3, -4e100], [-1e150, 2e-3, 4e100]]))
    filtered.add(np.array([[1e300, 1e-3, 1.0], [1e300, 1e-3, 1.0]]))
    head = SimpleNamespace(rows=2, sample_rate_hz=100.0, gyro_unit="dps")
    filt = SimpleNamespace(calibration=None, preset="paper", output_rate_hz=20.0, pending_samples=0, rejected=np.zeros(3),
                           compensates_temperature=False)
    print_summary("huge.csv", head, filt, raw, filtered)
    table = capsys.readouterr().out
    assert max(len(ln) for ln in table.splitlines()) < 100 and "1.41e+150" in table and "+1e+300" in table and "n/a" in table


@pytest.mark.parametrize("value_dps", [-3.3, 3 / 131.0])
def test_a_stuck_sensor_has_no_std_ratio(tmp_path, capsys, value_dps):
    """Issue 37: every sample -3.3 deg/s (or 3 LSB) gave a ratio of 46x (100x) from the rounding
    of the running sums; a constant raw series has no noise to reduce: n/a, null in the JSON."""
    src = tmp_path / "stuck.csv"
    write_recording(src, Recording.from_dps(np.full((1500, 3), value_dps), 100.0))
    assert main(["replay", str(src)]) == 0
    rows = [ln for ln in capsys.readouterr().out.splitlines() if ln.strip()[:2] in ("x ", "y ", "z ")]
    assert len(rows) == 3 and all(ln.split()[5] == "n/a" for ln in rows), rows


@pytest.mark.parametrize("seed", range(4))
def test_a_stuck_sensor_whose_samples_differ_by_rounding_is_stuck_everywhere(tmp_path, capsys, seed):
    """Attack pass 59: every sample 19.99 deg/s or the float after it (rounding in a logger's unit conversion) gave
    std ratios of 10000x in replay, N = 1.8e-16 in allan, six gap findings per axis, exit 0: the constant-axis test
    wanted exactly equal samples. Samples a few float64 spacings apart are one value (``units.one_value``): replay
    says n/a, allan, gap and arma refuse the axis as constant. Value, sign, spread and stuck axis drawn per seed;
    noise a million spacings wide is noise."""
    pytest.importorskip("statsmodels")
    from gyrofilter.analysis.arma.identify import analyze_axis
    from gyrofilter.analysis.gap.pipeline import nothing_to_analyse
    from gyrofilter.analysis.noise.fit import characterise_axis
    from gyrofilter.units import ROUNDING_ULPS

    rng = np.random.default_rng(seed)
    value = float(rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-6, 1.2))  # within the plausible bias (20 deg/s)
    stuck = int(rng.integers(3))
    gyro = rng.normal(0.0, 0.05, (3000, 3))
    steps = rng.integers(0, ROUNDING_ULPS // 2 + 1, 3000)  # floats above the value, a few spacings at most
    gyro[:, stuck] = value + steps * np.spacing(abs(value))
    assert np.ptp(gyro[:, stuck]) > 0
    src = tmp_path / "stuck.csv"
    write_recording(src, Recording.from_dps(gyro, 100.0))
    assert main(["replay", str(src)]) == 0
    rows = [ln.split() for ln in capsys.readouterr().out.splitlines() if ln.strip()[:2] in ("x ", "y ", "z ")]
    assert [row[5] == "n/a" for row in rows] == [axis == stuck for axis in range(3)], rows
    with pytest.raises(ValueError, match="constant"):
        characterise_axis(gyro[:, stuck], 100.0)
    with pytest.raises(ValueError, match="constant"):
        analyze_axis(gyro[:, stuck], 100.0)
    assert nothing_to_analyse(gyro[:, stuck]) == "constant signal"
    noisy = value + rng.normal(0.0, 1e6 * np.spacing(abs(value)), 3000)
    assert nothing_to_analyse(noisy) is None


@pytest.mark.parametrize("seed", range(4))
def test_a_stuck_axis_is_filtered_to_zero_not_to_rounding(tmp_path, capsys, seed):
    """Attack pass 60: replay --out of a stuck axis (19.99 deg/s and the float after it) wrote 0 and +-7e-16 deg/s,
    the bias's rounding, which gap analysed (three findings) and allan called a gross error, or fitted (N = 1.8e-16).
    A block mean within the bias's float64 rounding of it is 0: the output of a stuck axis is 0 exactly, and allan
    refuses it as constant, suggesting the others; the noisy axes are filtered as before, to the last bit. Value,
    stuck axis and chunk sizes drawn per seed."""
    from gyrofilter import GyroFilter
    from gyrofilter.units import ROUNDING_ULPS

    rng = np.random.default_rng(600 + seed)
    value = float(rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-3, 1.2))
    stuck = int(rng.integers(3))
    gyro = rng.normal(0.0, 0.05, (6000, 3))
    gyro[:, stuck] = value + rng.integers(0, ROUNDING_ULPS // 2 + 1, 6000) * np.spacing(abs(value))
    whole = GyroFilter(100.0).filter(gyro)
    assert len(whole) > 1000 and not np.any(whole[:, stuck]) and np.all(np.std(np.delete(whole, stuck, 1), axis=0) > 1e-4)
    chunked, filt, at = [], GyroFilter(100.0), 0
    while at < len(gyro):
        step = int(rng.integers(1, 400))
        chunked += [filt.filter(gyro[at:at + step])] if step > 1 else [np.array([r]) for r in [filt.update(gyro[at])] if r]
        at += step
    np.testing.assert_array_equal(np.vstack(chunked), whole)
    src, out = tmp_path / "stuck.csv", tmp_path / "out.csv"
    write_recording(src, Recording.from_dps(gyro, 100.0))
    assert main(["replay", str(src), "--out", str(out)]) == 0
    assert not np.any(read_recording(out).gyro_dps[:, stuck])
    capsys.readouterr()
    assert main(["allan", str(out)]) == 2
    err = capsys.readouterr().err
    assert "constant" in err and "--axes " + "".join(a for i, a in enumerate("xyz") if i != stuck) in err, err


def test_outputs_are_checked_before_any_work(tmp_path, capsys):
    rng = np.random.default_rng(11)
    src = tmp_path / "in.csv"
    write_recording(src, Recording.from_dps(rng.normal(0, 0.1, (1000, 3)), 100.0))
    before = src.read_bytes()
    for extra in (["--out", str(src)], ["--out", str(src), "--force"], ["--plot", str(src), "--force"]):
        assert main(["replay", str(src), *extra]) == 2
        assert "is an input" in capsys.readouterr().err
    assert src.read_bytes() == before
    cal = tmp_path / "cal.json"
    assert main(["replay", str(src), "--save-calibration", str(cal)]) == 0
    assert main(["replay", str(src), "--calibration", str(cal), "--save-calibration", str(cal), "--force"]) == 2
    out = tmp_path / "out.csv"
    out.write_text("keep me")
    assert main(["replay", str(src), "--out", str(out)]) == 2
    assert "exists" in capsys.readouterr().err and out.read_text() == "keep me"
    assert main(["replay", str(src), "--out", str(out), "--force"]) == 0
    assert len(read_recording(out)) == (1000 - 200) // 5


def test_a_figure_format_matplotlib_cannot_write_is_refused_before_any_work(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    out = tmp_path / "late.csv"
    assert main(["replay", "--plot", str(tmp_path / "o.jpg2"), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "matplotlib cannot write .jpg2" in err and ".png" in err
    assert not out.exists()


def test_out_takes_any_name_as_its_help_says(tmp_path, capsys):
    """--out o.txt writes plain CSV text (gzip only for .gz), and the help of every command that
    writes a recording says so instead of promising .csv/.csv.gz."""
    out = tmp_path / "o.txt"
    assert main(["replay", "--out", str(out)]) == 0
    assert out.read_bytes().startswith(b"# gyrofilter-recording: 1") and len(read_recording(out)) > 0
    capsys.readouterr()
    for command in ("replay", "record", "run", "simulate"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "compressed with gzip when the name ends in .gz" in text, command


def _paced_source(tmp_path, n, rate_hz):
    rng = np.random.default_rng(8)
    src = tmp_path / "paced.csv"
    write_recording(src, Recording.from_dps(rng.normal(0, 0.1, (n, 3)), rate_hz))
    return src


def test_realtime_stdout_is_a_recording(tmp_path, capsys):
    src = _paced_source(tmp_path, 700, 5000.0)
    out = tmp_path / "out.csv"
    assert main(["replay", str(src), "--realtime", "--calibration-s", "0.02", "--out", str(out)]) == 0
    printed = tmp_path / "stdout.csv"
    printed.write_text(capsys.readouterr().out)
    got, filtered = read_recording(printed), read_recording(out)
    assert got.gyro_unit == "dps" and got.sample_rate_hz == filtered.sample_rate_hz == 1000.0
    np.testing.assert_allclose(got.t_s, filtered.t_s, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(got.gyro, filtered.gyro)  # the same 9 significant digits as --out
    bias = json.loads(filtered.header["bias_dps"])
    assert f"# calibrated: bias {bias[0]:+.4f}, {bias[1]:+.4f}, {bias[2]:+.4f} deg/s" in printed.read_text()


def test_realtime_into_head_still_writes_the_whole_out_file(tmp_path):
    """`replay --realtime --out F | head`: the reader goes away; F is complete, the exit clean, and
    stderr says that the rest of the rows were not printed (the summary counts every row filtered:
    a new user read it as every row delivered)."""
    src = _paced_source(tmp_path, 4000, 1000.0)  # 4 s paced
    out = tmp_path / "out.csv"
    proc = subprocess.Popen([sys.executable, "-m", "gyrofilter", "replay", str(src), "--realtime", "--calibration-s", "0.2", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    for _ in range(20):  # the header and a few rows, then the pipe is closed like `head` does
        proc.stdout.readline()
    proc.stdout.close()
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 0, err
    assert "Traceback" not in err and "BrokenPipe" not in err
    assert len(read_recording(out)) == (4000 - 200) // 5
    closed = re.search(r"gyrofilter: warning: stdout was closed by its reader; (\d+) lines were written to it \((\d+) of "
                       r"them filtered rows\): the rest of the rows", " ".join(err.split()))
    # lines, the header's and the calibration note's too (a new user's `| head -20` was told "after 11 lines"):
    # the 20 read, and those written before the reader closed the pipe
    assert closed and 20 <= int(closed.group(1)) < (4000 - 200) // 5, err
    assert int(closed.group(2)) == int(closed.group(1)) - 11, err  # 10 header lines, the calibration note


@pytest.mark.parametrize("name", ["x$\\foo$.csv", "y$^{{{$.csv", "z$x$.csv"])
def test_a_figure_titled_by_a_file_name_with_dollars_shows_the_name(tmp_path, monkeypatch, capsys, name):
    """Attack pass 20: matplotlib read a file name's $...$ as mathtext: `replay 'x$\\foo$.csv' --plot
    p.png` (and `allan --plot`) exited 2 with "\\foo ^ ParseFatalException: Unknown symbol", naming
    nothing, and 'z$x$.csv' was titled "zx.csv" with an italic x. The title is the name as it is."""
    matplotlib = pytest.importorskip("matplotlib")
    from matplotlib.axes import Axes
    from matplotlib.cbook import is_math_text
    from support import RECORDINGS

    titles, draw = [], Axes.set_title
    monkeypatch.setattr(Axes, "set_title", lambda ax, text, *a, **k: titles.append(text) or draw(ax, text, *a, **k))
    path = tmp_path / name
    path.write_bytes((RECORDINGS / "mpu6050_static_100s.csv.gz").read_bytes())
    assert main(["replay", str(path), "--plot", str(tmp_path / "p.png")]) == 0, capsys.readouterr().err
    assert not is_math_text(titles[0]) and titles[0].replace("\\$", "$") == f"{path} (raw minus start-up bias)"
    assert main(["allan", str(path), "--plot", str(tmp_path / "a.png")]) == 0, capsys.readouterr().err


@pytest.mark.parametrize("rows, args, message", [
    ("", [], "no samples (the file has a header only)"),
    ("".join(f"{i / 100:.2f},0.1,0.2,0.3\n" for i in range(150)), [], "end inside the start-up calibration window (2 s)"),
    # attack pass 20: the window filled, then 4 samples, fewer than a block: a header-only file, exit 0
    ("".join(f"{i / 100:.2f},0.1,0.2,0.3\n" for i in range(204)), [],
     "end 4 sample(s) after the start-up calibration window (2 s), fewer than a block of 5"),
])
def test_nothing_to_filter_is_an_error_and_writes_nothing(tmp_path, capsys, rows, args, message):
    path = tmp_path / "short.csv"
    path.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\nt,gx,gy,gz\n" + rows)
    out = tmp_path / "out.csv"
    assert main(["replay", str(path), "--out", str(out), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and str(path) in err[0], err
    assert not out.exists()


def test_an_output_below_a_file_is_refused_naming_the_file(tmp_path, capsys):
    (tmp_path / "cal.json").write_text("{}")
    out = tmp_path / "cal.json" / "sub" / "x.csv"
    assert main(["replay", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"gyrofilter: error: {out}: {tmp_path / 'cal.json'} is a file, not a folder"]


def test_an_output_below_a_loop_of_links_is_refused_naming_the_loop(tmp_path, capsys):
    """Attack pass (issue 37): a folder that is a loop of symbolic links was called "a file"."""
    os.symlink(tmp_path / "b", tmp_path / "a")
    os.symlink(tmp_path / "a", tmp_path / "b")
    out = tmp_path / "a" / "x.csv"
    assert main(["replay", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"gyrofilter: error: {out}: {tmp_path / 'a'} is a symbolic link that leads to no folder "
                   "(Too many levels of symbolic links)"]


@pytest.mark.parametrize("realtime", [[], ["--realtime"]])
@pytest.mark.parametrize("column, value, reason", [
    ("gy", 1e300, "column 'gy' is 1e+300 dps, beyond the +-100000 deg/s any gyro reads"),  # the reader's refusal
    ("temp", 1e6, "temp_c (deg C) must be in [-100, 200], got 1000000.0"),  # the filter's, mapped to the line
])
def test_a_sample_beyond_the_filters_range_is_refused_naming_the_line(tmp_path, capsys, realtime, column, value, reason):
    """A finite but absurd sample (1e300 deg/s) made every later row inf and replay exited 0."""
    rng = np.random.default_rng(22)
    x = rng.normal(0, 0.1, (1000, 3))
    temp = np.full(1000, 25.0)
    (x[:, 1] if column == "gy" else temp)[700] = value
    src, out = tmp_path / "in.csv", tmp_path / "out.csv"
    x[700, 1] = min(x[700, 1], 1.0)  # the writer refuses what the reader would: written by hand below
    write_recording(src, Recording.from_dps(x, 100.0, temp_c=temp))
    if column == "gy":
        lines = src.read_text().splitlines()
        cells = lines[-300].split(",")
        cells[1] = "1e+300"  # gx,gy,gz,temp
        lines[-300] = ",".join(cells)
        src.write_text("\n".join(lines) + "\n")
    names_at = next(i for i, text in enumerate(src.read_text().splitlines(), 1) if not text.startswith("#"))
    line = names_at + 1 + 700
    assert main(["replay", str(src), "--out", str(out), *realtime]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"gyrofilter: error: {src}: line {line}: {reason}"
    assert not out.exists()


def test_set_refuses_a_repeated_key_bools_for_numbers_and_huge_numbers(tmp_path, capsys):
    src = tmp_path / "in.csv"
    write_recording(src, Recording.from_dps(np.random.default_rng(3).normal(0, 0.1, (500, 3)), 100.0))
    for extra, message in (
            (["--set", "block_len=4", "--set", "block_len=5"], "--set block_len: given twice"),
            (["--set", "stillness_z=true"], "setting stillness_z must be a finite number, got True"),
            (["--set", "block_len=" + "9" * 400], "setting block_len must be a finite number (a whole number), got 999"),
            (["--set", "fifo_depth=1e12"], "setting fifo_depth must be in [1, 100], got 1000000000000.0"),
            (["--set", "stillness_z=NaN"], "setting stillness_z must be a finite number, got 'NaN'"),
            (["--set", "calibration_s=null"], "--set calibration_s=null: every setting needs a value"),
            (["--set", "blok_len=5"], "not a filter setting; did you mean block_len?")):
        assert main(["replay", str(src), *extra]) == 2, extra
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err, (extra, err)


# --- issue 22: what the commands write reads back ----------------------------------------------

def _clock_recording(tmp_path, n=1500, rate_hz=100.0):
    """A recording stamped with a clock (t = 1.7e9 s + k / rate): 10 digits made every stamp one value."""
    rng = np.random.default_rng(22)
    src = tmp_path / "clock.csv"
    t = 1.7e9 + np.arange(n) / rate_hz
    write_recording(src, Recording.from_dps(rng.normal(0, 0.1, (n, 3)), rate_hz, t_s=t))
    return src, t


@pytest.mark.parametrize("command", ["replay", "run", "record"])
def test_clock_time_stamps_survive_every_command_that_writes_a_recording(tmp_path, command):
    src, t = _clock_recording(tmp_path)
    out = tmp_path / "out.csv.gz"
    args = {"replay": ["replay", str(src)], "run": ["run", "--source", f"replay:{src}", "--quiet"],
            "record": ["record", "--source", f"replay:{src}", "--quiet"]}[command]
    assert main([*args, "--out", str(out)]) == 0
    back = read_recording(out).t_s
    if command == "record":
        np.testing.assert_array_equal(back, t)
    else:  # one row per block of 5: the t of its last sample
        assert len(back) > 250
        np.testing.assert_array_equal(back, t[4::5][len(t[4::5]) - len(back):])


def test_a_newline_in_the_input_path_leaves_the_output_readable(tmp_path):
    src, _ = _clock_recording(tmp_path)
    odd = tmp_path / "in\nput.csv"
    odd.write_bytes(src.read_bytes())
    out = tmp_path / "out.csv"
    assert main(["replay", str(odd), "--out", str(out)]) == 0
    assert read_recording(out).header["filtered_from"] == str(odd).replace("\n", "\\n")
    recorded = tmp_path / "rec.csv"
    assert main(["record", "--source", f"replay:{odd}", "--out", str(recorded), "--quiet"]) == 0
    assert read_recording(recorded).header["source"] == f"replay of {odd}".replace("\n", "\\n")


def test_replaying_dev_zero_ends_at_once_with_one_line(tmp_path):
    out = tmp_path / "out.csv"
    proc = subprocess.run([sys.executable, "-m", "gyrofilter", "replay", "/dev/zero", "--out", str(out)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "/dev/zero: line 1: longer than" in proc.stderr
    assert len(proc.stderr) < 300 and not out.exists()


def test_set_with_a_space_instead_of_an_equals_sign_is_told_so(capsys):
    """--set block_len 5 read 5 as the recording's name: '5: cannot read: No such file or directory'."""
    with pytest.raises(SystemExit) as info:
        main(["replay", "--set", "block_len", "5"])
    err = capsys.readouterr().err
    assert info.value.code == 2 and "argument --set: expected NAME=VALUE (e.g. block_len=5), got 'block_len'" in err


@pytest.mark.parametrize("options", [[], ["--smooth"], ["--calibration-s", "0.5"]])
def test_replaying_a_filtered_output_is_refused_naming_where_it_came_from(tmp_path, capsys, options):
    """Issue 23: replay of a file replay --out wrote (header filtered_from) failed as "the sensor
    moved" (its rows are bias-removed block means): refused by name, before any output; allan on
    it stays legitimate (the noise of the output)."""
    rng = np.random.default_rng(3)
    src = tmp_path / "in.csv"
    write_recording(src, Recording.from_dps(rng.normal([1, 2, 3], 0.1, (3000, 3)), 100.0))
    filtered = tmp_path / "filtered.csv"
    assert main(["replay", str(src), "--out", str(filtered)]) == 0
    capsys.readouterr()
    out = tmp_path / "twice.csv"
    assert main(["replay", str(filtered), "--out", str(out), *options]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == (
        f"gyrofilter: error: {filtered} is the filter's output (filtered_from '{src}'), not the sensor's "
        "samples; filter the raw recording it came from (from a live source: `record` it, then replay)\n")
    assert not out.exists()
    assert main(["allan", str(filtered)]) == 0


def test_an_input_that_lost_samples_in_most_blocks_gives_rows_at_their_own_t_that_read_back(tmp_path, capsys):
    """Case 1-1, then issue 37 (attack 4): a legal input with samples lost in 40 % of its steps (the
    median step is the rate's) gives rows whose t steps by more than 1 / output rate in most
    blocks; replay refused the --out (exit 2, nothing written). Every block of delivered samples
    has its row at the t of its last sample, and the output reads: a header with
    input_sample_rate_hz, whose blocks that span lost samples are its gaps."""
    rng = np.random.default_rng(5)
    steps = np.where(rng.random(19999) < 0.4, 0.02, 0.01)
    t = np.concatenate(([0.0], np.cumsum(steps)))
    x = rng.normal(0, 0.05, (20000, 3))
    src = tmp_path / "gaps.csv"
    write_recording(src, Recording.from_dps(x, 100.0, t_s=t))
    assert len(read_recording(src)) == 20000  # the input reads: its gaps are legal
    out = tmp_path / "out.csv"
    assert main(["replay", str(src), "--out", str(out)]) == 0
    capsys.readouterr()
    got = read_recording(out)
    t_want, want = GyroFilter(100.0).filter_timed(x, t)
    assert len(got) == len(want) == (20000 - 200) // 5 and got.header["input_sample_rate_hz"] == "100"
    np.testing.assert_allclose(got.gyro_dps, want, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(got.t_s, t_want, atol=1e-9)
    assert got.t_gaps == np.count_nonzero(np.diff(t_want) > 0.055) > len(got) / 2


def test_a_device_counter_recording_that_lost_every_other_sample_replays_to_rows_that_read(tmp_path, capsys):
    """Attack pass 14: a recording of a serial device's counter (t_from: device counter) that lost
    every other sample throughout reads, its gaps counted; replay --out of it refused its rows at
    the close (every block spans 10 sample intervals, 2 row intervals: a t at half the rate), exit 2.
    The output carries the recording's t_from: its rows read, every step a gap."""
    rng = np.random.default_rng(6)
    t = 0.02 * np.arange(3000)
    src = tmp_path / "counted.csv"
    write_recording(src, Recording.from_dps(rng.normal(0, 0.05, (3000, 3)), 100.0, t_s=t,
                                            header={"t_from": "device counter"}))
    out = tmp_path / "out.csv"
    assert main(["replay", str(src), "--out", str(out)]) == 0, capsys.readouterr().err
    capsys.readouterr()
    got = read_recording(out)
    assert got.header["t_from"] == "device counter" and len(got) == (3000 - 200) // 5  # 2 s of calibration: 200 samples
    assert got.t_gaps == len(got) - 1


def test_realtime_rows_on_a_full_stdout_name_stdout(tmp_path, monkeypatch, capsys):
    """``replay --realtime > out.csv`` on a full disk: "[Errno 28] No space left on device", naming
    nothing (run named stdout; attack pass 10)."""
    import errno

    from gyrofilter.recording import Recording, write_recording

    src = str(tmp_path / "in.csv")
    write_recording(src, Recording.from_dps(np.random.default_rng(0).normal(size=(600, 3)) * 0.05, 100.0))

    class Full:
        def write(self, text):
            raise OSError(errno.ENOSPC, "No space left on device")

        def flush(self):
            pass

    monkeypatch.setattr(sys, "stdout", Full())
    assert main(["replay", src, "--realtime"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["gyrofilter: error: stdout: No space left on device; 0 lines printed before it"], err
