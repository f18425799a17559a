"""A new user's unit mistakes: deg/s written as rad/s is refused by every still analysis
(allan, arma, gap, report) as replay's calibration refuses it, not analysed 57 times too large."""
import math

import numpy as np
import pytest

from gyrofilter.cli import main
from gyrofilter.recording import Recording, convert_gyro, write_recording


@pytest.fixture(scope="module")
def dps_as_rad(tmp_path_factory):
    """20 s at 50 Hz of a still gyro (bias 4.5, 0.1, 1.2 deg/s) whose deg/s numbers are labelled rad/s."""
    rng = np.random.default_rng(7)
    g = np.array([4.5, 0.1, 1.2]) + rng.normal(size=(1000, 3)) * 0.05
    rec = convert_gyro(Recording.from_dps(g, 50.0), "rad/s")
    for c in ("gx", "gy", "gz"):
        rec.columns[c] = g[:, "xyz".index(c[1])]  # the deg/s numbers, read as rad/s
    path = tmp_path_factory.mktemp("u") / "dps_as_rad.csv.gz"
    write_recording(str(path), rec)
    return str(path)


@pytest.mark.parametrize("command", [["allan"], ["arma"], ["gap", "--sims", "20", "--bootstrap", "0"]])
def test_a_mean_beyond_any_bias_is_refused(dps_as_rad, command, capsys):
    assert main(command + [dps_as_rad]) == 2
    err = capsys.readouterr().err
    assert dps_as_rad in err and "axis x reads 258 deg/s on average" in err
    assert "deg/s written as rad/s" in err and "--allow-large-mean" in err


def test_allow_large_mean_analyses_it_with_a_warning(dps_as_rad, capsys):
    assert main(["allan", dps_as_rad, "--allow-large-mean"]) == 0
    err = " ".join(capsys.readouterr().err.split())  # warnings are wrapped
    assert "axis x reads 258 deg/s on average" in err and "4.5 deg/s if the numbers are deg/s" in err


def test_report_says_it_among_its_warnings(dps_as_rad, tmp_path, capsys):
    """A report is made of a moving record too (its page lists the warnings): the mean is said, not refused."""
    assert main(["report", dps_as_rad, "--out", str(tmp_path / "r.html"), "--sims", "10"]) == 0
    err = " ".join(capsys.readouterr().err.split())
    assert "axis x reads 258 deg/s on average" in err and "deg/s written as rad/s" in err


def test_a_fleet_refuses_allow_large_mean(dps_as_rad, tmp_path, capsys):
    assert main(["allan", dps_as_rad, dps_as_rad, "--fleet", str(tmp_path / "f"), "--allow-large-mean"]) == 2
    assert "--allow-large-mean is for one recording" in capsys.readouterr().err


def test_a_fleets_failure_names_a_way_out_that_is_taken(dps_as_rad, tmp_path, capsys):
    """Attack pass 32b: a fleet's failure line said "rerun with --allow-large-mean", which a fleet refuses:
    it says to analyse the file alone with it, which is taken."""
    assert main(["allan", dps_as_rad, "--fleet", str(tmp_path / "f"), "--jobs", "1"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert "analyse the file alone with --allow-large-mean" in err, err
    assert main(["allan", dps_as_rad, "--allow-large-mean"]) == 0


def test_the_refusal_names_a_way_out_that_is_taken(dps_as_rad, tmp_path, capsys):
    """Attack pass 31a: the refusal said "Fix the unit (gyrofilter convert --unit)", and convert refuses a
    recording ("already a gyrofilter recording"): the way out is the header's gyro_unit (or the log converted
    again), and the recording with its header fixed is analysed."""
    import gzip
    assert main(["allan", dps_as_rad]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert "header's gyro_unit" in err, err
    with gzip.open(dps_as_rad, "rt") as f:
        text = f.read()
    fixed = tmp_path / "fixed.csv"
    fixed.write_text(text.replace("# gyro_unit: rad/s", "# gyro_unit: dps"))
    assert main(["allan", str(fixed)]) == 0


@pytest.mark.parametrize("command", [["allan", "--axes", "y"], ["allan", "--axes", "zy"], ["arma", "--axis", "y"]])
def test_the_axes_not_analysed_count_too(dps_as_rad, command, capsys):
    """Attack pass 31a's note: ``allan --axes y`` checked the mean of y alone (0.1 "rad/s" reads 5.7 deg/s,
    a plausible bias) and printed y's Allan deviation 57 times too large, exit 0; a unit mistake is the
    whole file's: x's 258 deg/s refuses it, whichever axes are analysed."""
    assert main(command[:1] + [dps_as_rad] + command[1:]) == 2
    assert "axis x reads 258 deg/s on average" in capsys.readouterr().err


def test_an_axis_not_analysed_leaves_the_results_of_the_others_as_they_were(tmp_path, capsys):
    """Reading every axis for the mean changes nothing of the axes analysed (their order included)."""
    import json
    rng = np.random.default_rng(3)
    path = str(tmp_path / "still.csv")
    write_recording(path, Recording.from_dps(np.array([1.0, -2.0, 0.5]) + 0.05 * rng.normal(size=(3000, 3)), 100.0))
    out = {}
    for axes in ("xyz", "zx"):
        assert main(["allan", path, "--axes", axes, "--json", str(tmp_path / f"{axes}.json")]) == 0
        out[axes] = json.loads((tmp_path / f"{axes}.json").read_text())["axes"]
    assert list(out["zx"]) == ["z", "x"] and all(out["zx"][a] == out["xyz"][a] for a in "zx")


def test_replays_refusal_of_a_large_bias_names_its_way_through(tmp_path, capsys):
    """Attack pass 32b: a real bias beyond 20 deg/s (20.5, a gyro beyond its datasheet) was refused by
    replay's start-up calibration with "Keep it still while calibrating" alone, as allan names its
    --allow-large-mean: the setting that takes it is named (replay's --set takes it)."""
    g = np.array([20.5, 0.1, 1.2]) + np.random.default_rng(3).normal(size=(500, 3)) * 0.05
    path = str(tmp_path / "big_bias.csv")
    write_recording(path, Recording.from_dps(g, 50.0))
    assert main(["replay", path]) == 2
    assert "raise the filter's setting max_bias_dps (to 21)" in capsys.readouterr().err
    assert main(["replay", path, "--set", "max_bias_dps=21"]) == 0


def test_the_max_bias_named_takes_every_axis(tmp_path, capsys):
    """Attack pass 33a: the refusal named the value that takes the first axis beyond max_bias_dps
    (x 20.5: "to 21"), and followed, the calibration was refused again for y (-25.3: "to 26"):
    the value named takes every axis."""
    g = np.array([20.5, -25.3, 1.2]) + np.random.default_rng(3).normal(size=(500, 3)) * 0.05
    path = str(tmp_path / "big_biases.csv")
    write_recording(path, Recording.from_dps(g, 50.0))
    assert main(["replay", path]) == 2
    assert "axis x reads 20.5" in (err := capsys.readouterr().err) and "max_bias_dps (to 26)" in err
    assert main(["replay", path, "--set", "max_bias_dps=26"]) == 0


def test_a_saved_calibration_with_a_large_bias_names_its_way_through(tmp_path, capsys):
    """Attack pass 33c: --calibration FILE whose saved bias is beyond 20 deg/s (x 20.5, y -25.3) was
    refused with "bias_dps x must be in [-20, 20]" alone, where the start-up calibration's refusal
    names the setting that takes it: the same words, the value taking every axis (26), which --set takes."""
    g = np.array([20.5, -25.3, 1.2]) + np.random.default_rng(3).normal(size=(500, 3)) * 0.05
    path, cal = str(tmp_path / "big_biases.csv"), str(tmp_path / "cal.json")
    write_recording(path, Recording.from_dps(g, 50.0))
    assert main(["replay", path, "--set", "max_bias_dps=26", "--save-calibration", cal]) == 0
    capsys.readouterr()
    assert main(["replay", path, "--calibration", cal]) == 2
    err = capsys.readouterr().err
    assert f"{cal}: bias_dps x must be in [-20, 20]" in err and "raise the filter's setting max_bias_dps (to 26)" in err
    assert main(["replay", path, "--calibration", cal, "--set", "max_bias_dps=26"]) == 0


def test_a_large_bias_in_report_and_evaluate_names_the_commands_that_take_it(tmp_path, capsys):
    """Attack pass 35: report (its filter part, a warning) and evaluate (a refusal) said "raise the filter's
    setting max_bias_dps (to 26)" for a real bias beyond 20 deg/s, and neither takes a filter setting
    (``report --set`` is refused as unrecognised): they name the commands whose --set takes it (taken: tested)."""
    from gyrofilter.errors import CalibrationError
    from gyrofilter.evaluation import evaluate as E
    from gyrofilter.evaluation.filters import default_filters

    g = np.array([20.5, -25.3, 1.2]) + np.random.default_rng(3).normal(size=(500, 3)) * 0.05
    path = str(tmp_path / "big_biases.csv")
    write_recording(path, Recording.from_dps(g, 50.0))
    assert main(["report", path, "--out", str(tmp_path / "r.html"), "--sims", "10"]) == 0
    err = " ".join(capsys.readouterr().err.split())
    assert "raise the filter's setting" not in err and "replay and run take --set max_bias_dps=26" in err
    assert main(["replay", path, "--set", "max_bias_dps=26"]) == 0
    folder = tmp_path / "recordings"
    folder.mkdir()
    write_recording(str(folder / "mpu6050_static_10s.csv"),
                    Recording.from_dps(g, 50.0, header={"sensor": "MPU6050", "description": "static: big bias"}))
    paper = [spec for spec in default_filters() if spec.name == "paper001"]
    with pytest.raises(CalibrationError) as refused:
        E.evaluate(paper, str(folder), profiles=[], with_lag=False)
    text = str(refused.value)
    assert "raise the filter's setting" not in text and "move it out of the recordings folder" in text
    assert "replay and run take --set max_bias_dps=26" in text


@pytest.mark.parametrize("command", ["allan", "arma"])
def test_allow_large_mean_warning_is_in_the_json_document(dps_as_rad, tmp_path, command):
    """Attack pass 37k: the warning of --allow-large-mean (and every other of the file's) was said on stderr
    but missing from allan's and arma's --json document, which a reader of the file alone sees."""
    import json
    out = tmp_path / "out.json"
    assert main([command, dps_as_rad, "--allow-large-mean", "--json", str(out)]) == 0
    warnings = json.loads(out.read_text())["warnings"]
    assert any("axis x reads 258 deg/s on average" in w and "Analysed as it is" in w for w in warnings), warnings
