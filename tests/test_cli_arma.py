"""`gyrofilter arma`: the JSON document, one-line errors naming the options, the window by t, warnings."""
import json
import os

import numpy as np
import pytest
from support import RECORDINGS

pytest.importorskip("statsmodels")
pytest.importorskip("scipy")

from gyrofilter.analysis.arma import identify as arma  # noqa: E402
from gyrofilter.analysis.arma import checks as arma_checks  # noqa: E402
from gyrofilter.analysis.arma import fit as arma_fit  # noqa: E402

PHI, THETA, SIGMA = 0.9, 0.5, 0.1  # the ARMA(1,1) of paper 003's example, as in test_arma.py


def test_cli_writes_json_and_reports_bad_input(tmp_path, capsys):
    import json

    from gyrofilter.cli import main
    from gyrofilter.recording import Recording, write_recording

    rng = np.random.default_rng(15)
    gyro = np.column_stack([rng.normal(1.0, 0.1, 5_000), rng.normal(0, 0.1, 5_000),
                            -2.0 + arma_fit.simulate_arma([PHI], [THETA], SIGMA, 5_000, seed=15)])
    path = tmp_path / "static.csv"
    write_recording(path, Recording.from_dps(gyro, 100.0))
    out = tmp_path / "arma.json"
    assert main(["arma", str(path), "--axis", "z", "--max-n", "1", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "chosen: ARMA(1, 1)" in text
    data = json.loads(out.read_text())
    z = data["axes"]["z"]
    assert z["chosen"]["phi"][0] == pytest.approx(PHI, abs=0.05)
    assert z["mean_dps"] == pytest.approx(-2.0, abs=0.05)
    assert main(["arma", str(path), "--start-s", "49.5"]) == 2
    assert "--start-s 49.5 leaves 50 of the 5000 samples (50 s at 100 Hz)" in capsys.readouterr().err


@pytest.mark.parametrize("options, expected", [
    ([], "short.csv: 150 samples (1.5 s at 100 Hz); the analysis needs at least 200"),
    (["--start-s", "0.5"], "--start-s 0.5 leaves 100 of the 150 samples"),
    (["--end-s", "1"], "--end-s 1 leaves 100 of the 150 samples"),
    (["--start-s", "0.2", "--end-s", "1.2"], "--start-s 0.2 and --end-s 1.2 leave 100 of the 150 samples"),
    (["--start-s", "1", "--end-s", "1"], "--end-s 1 must be after --start-s 1"),
    (["--max-n", "0"], "--max-n must be at least 1, got 0"),
    (["--max-samples", "50"], "--max-samples must be at least 400 (block means of a longer series are more than half "
                              "of it, and the analysis needs 200), got 50"),
    (["--max-samples", "150"], "--max-samples must be at least 400"),
])
def test_cli_errors_name_the_options_the_user_gave(tmp_path, capsys, options, expected):
    from gyrofilter.cli import main

    path = _static_recording(tmp_path, 150, "short.csv")
    assert main(["arma", path] + options) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and expected in err, err
    if not options:
        assert "--start-s" not in err and "--end-s" not in err


def test_cli_summarises_library_warnings_in_one_line(tmp_path, capsys, monkeypatch):
    import warnings

    from statsmodels.tools.sm_exceptions import ConvergenceWarning

    from gyrofilter.cli import main

    real = arma_checks.adf_test

    def warning_adf(*args, **kwargs):
        for _ in range(3):
            warnings.warn("Maximum Likelihood optimization failed to converge.", ConvergenceWarning)
        warnings.warn("divide by zero encountered", RuntimeWarning)
        return real(*args, **kwargs)

    monkeypatch.setattr(arma, "adf_test", warning_adf)
    path = _static_recording(tmp_path, 1000)
    with warnings.catch_warnings(record=True) as leaked:
        warnings.simplefilter("always")
        assert main(["arma", path, "--axis", "z", "--max-n", "1"]) == 0
    assert not leaked, [str(w.message) for w in leaked]
    err = capsys.readouterr().err
    assert err.count("gyrofilter: warning: ") == 1  # one warning (wrapped at 100 columns) summarises them
    assert ("axis z: ConvergenceWarning (3x): Maximum Likelihood optimization failed to converge.; "
            "RuntimeWarning: divide by zero encountered") in " ".join(err.split())


def test_cli_json_is_never_written_over_data(tmp_path, capsys):
    import json

    from gyrofilter.cli import main

    path = _static_recording(tmp_path, 1000)
    text = open(path).read()
    out = tmp_path / "a.json"
    out.write_text("keep")
    args = ["arma", path, "--axis", "x", "--max-n", "1"]
    assert main(args + ["--json", str(out)]) == 2
    assert "exists (use --force" in capsys.readouterr().err and out.read_text() == "keep"
    assert main(args + ["--json", path, "--force"]) == 2
    assert "is an input" in capsys.readouterr().err and open(path).read() == text
    assert main(args + ["--json", str(out), "--force"]) == 0
    doc = json.loads(out.read_text(), parse_constant=lambda token: pytest.fail(f"JSON token {token}"))
    assert doc["axes"]["x"]["warnings"] == [] and doc["n_samples"] == 1000


@pytest.mark.parametrize("option", ["--start-s", "--end-s"])
@pytest.mark.parametrize("value", ["inf", "nan"])
def test_cli_a_non_finite_window_is_one_line_naming_the_option(capsys, option, value):
    from gyrofilter.cli import main

    # since issue 22 the option's type refuses inf and nan, no plain decimal numbers, as argparse
    # errors (exit 2; SystemExit while argparse prints its usage too)
    try:
        code = main(["arma", str(RECORDINGS / "mpu6050_static_64s_set1.csv.gz"), option, value])
    except SystemExit as exc:
        code = exc.code
    assert code == 2
    assert f"argument {option}: must be a plain decimal number (like 12, -0.5 or 1e-3), got '{value}'" in capsys.readouterr().err


def test_the_gap_warning_counts_the_gaps_of_the_window_analysed(tmp_path, capsys):
    """Attack pass 17: arma warned of the file's gaps where --start-s/--end-s left them out of the
    window it fits; the count is the window's."""
    from gyrofilter.cli import main
    from gyrofilter.recording import Recording, write_recording

    steps = np.full(5999, 0.01)
    steps[100:200:10] = 0.02  # ten samples lost in the first 2 s
    t = np.concatenate(([0.0], np.cumsum(steps)))
    path = tmp_path / "gaps.csv"
    write_recording(path, Recording.from_dps(np.random.default_rng(3).normal(0.5, 0.1, (6000, 3)), 100.0, t_s=t))
    assert main(["arma", str(path), "--axis", "x", "--max-n", "1", "--start-s", "10"]) == 0
    assert "gap(s)" not in capsys.readouterr().err
    assert main(["arma", str(path), "--axis", "x", "--max-n", "1", "--end-s", "30"]) == 0
    assert "t shows 10 gap(s)" in " ".join(capsys.readouterr().err.split())


def test_cli_selects_the_window_by_t_and_warns_about_gaps(tmp_path, capsys):
    """Case 1-3: with lost samples, --start-s 20 took sample 20 * rate (t near 25 s here), the
    printed and JSON durations came from the count, and nothing said the samples were not uniform."""
    import json

    from gyrofilter.cli import main
    from gyrofilter.recording import Recording, write_recording

    rng = np.random.default_rng(17)
    steps = np.where(np.arange(5999) % 4 == 3, 0.02, 0.01)  # a sample lost after every third
    t = np.concatenate(([0.0], np.cumsum(steps)))
    path = tmp_path / "gaps.csv"
    write_recording(path, Recording.from_dps(rng.normal(0.5, 0.1, (6000, 3)), 100.0, t_s=t))
    out = tmp_path / "a.json"
    assert main(["arma", str(path), "--axis", "x", "--max-n", "1", "--start-s", "20", "--end-s", "60",
                 "--json", str(out)]) == 0
    first, last = int(np.searchsorted(t, 20.0 - 0.005)), int(np.searchsorted(t, 60.0 - 0.005))
    assert t[first] == pytest.approx(20.0) and first == 1600  # not sample 2000 (t = 25 s)
    doc = json.loads(out.read_text())
    assert doc["n_samples"] == last - first and doc["start_s"] == pytest.approx(20.0)
    assert doc["duration_s"] == pytest.approx(t[last - 1] - t[first] + 0.01)
    captured = capsys.readouterr()
    assert f"{last - first} samples at 100 Hz (40.0 s) from 20 s after the first sample" in captured.out
    warnings = " ".join(captured.err.split()).split("gyrofilter: warning: ")  # each wrapped at 100 columns
    in_window = int(np.count_nonzero(np.diff(t[first:last]) > 0.015))  # the window's gaps, not the file's 1499
    assert any(w.startswith(f"{path}: t shows {in_window} gap(s)") and "ARMA" in w and "not meaningful" in w
               for w in warnings), captured.err


def _static_recording(tmp_path, n, name="static.csv"):
    from gyrofilter.recording import Recording, write_recording

    rng = np.random.default_rng(16)
    path = tmp_path / name
    write_recording(path, Recording.from_dps(rng.normal(0.5, 0.1, (n, 3)), 100.0))
    return str(path)


def test_the_filters_output_is_analysed_saying_whose_noise_the_model_describes(tmp_path, capsys):
    """Attack pass 24's note: `arma` on `replay --out`'s output (bias-removed block means) modelled it
    as a sensor's bias noise without a word; it says so on stderr and in the JSON's warnings."""
    from gyrofilter.cli import main

    raw = _static_recording(tmp_path, 3000)
    filtered, out = str(tmp_path / "filtered.csv"), tmp_path / "arma.json"
    assert main(["replay", raw, "--out", filtered]) == 0
    for path, expected in ((raw, []), (filtered, ["filtered.csv: is the filter's output (filtered_from "])):
        capsys.readouterr()
        assert main(["arma", path, "--axis", "x", "--json", str(out), "--force"]) == 0
        err = " ".join(capsys.readouterr().err.split())  # the console folds long lines
        warnings = json.loads(out.read_text())["warnings"]
        assert [w[w.index(os.path.basename(path)):][:len(e)] for w in warnings for e in expected] == expected
        assert all(w.endswith("this one describes the filter's output") for w in warnings)
        assert err.count("this one describes the filter's output") == len(expected)


def test_cli_says_a_tau_beyond_the_record_is_not_determined(tmp_path, capsys):
    # issue 37: "Gauss-Markov tau 1.2e6 s, bias sigma 730 deg/s" from 0.025 s of a 0.0124-s bias
    import math

    from gyrofilter.cli import main
    from gyrofilter.recording import Recording, write_recording

    fs, tau, n = 8000.0, 0.0124, 200
    phi = math.exp(-1 / (fs * tau))
    rng = np.random.default_rng(35)
    from scipy.signal import lfilter

    bias = lfilter([1.0], [1.0, -phi], rng.normal(0, math.sqrt(1 - phi**2), n), zi=[phi * rng.normal()])[0]
    gyro = np.column_stack([rng.normal(0, 0.1, n), rng.normal(0, 0.1, n), bias + rng.normal(0, 0.1, n)])
    path = tmp_path / "gm.csv"
    write_recording(path, Recording.from_dps(gyro, fs))
    out = tmp_path / "gm.json"
    assert main(["arma", str(path), "--axis", "z", "--max-n", "1", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Gauss-Markov tau and bias sigma not determined (the fitted tau is longer than 0.2 x the record, 0.025 s): " \
           "within it a random walk of K = " in text, text
    b = json.loads(out.read_text())["axes"]["z"]["bias_model"]
    assert b["tau_s"] is None and b["bias_sigma_dps"] is None and b["tau_determined"] is False
    assert b["bias_walk_dps_per_sqrt_s"] == pytest.approx(math.sqrt(2 / tau), rel=0.3)


def test_a_record_that_moved_is_analysed_saying_so(tmp_path, capsys):
    """Attack pass 37j: arma judged no record's stillness (allan warns, gap refuses): a 20-degree tilt
    over 10 s (a Hann-shaped rate of peak 4 deg/s) in 120 s at 100 Hz was fitted without a word. It
    is said as allan says it (analysis.still.moved), on the screen and in the JSON."""
    from gyrofilter.cli import main
    from gyrofilter.recording import Recording, write_recording

    gyro = np.random.default_rng(4).normal(0.5, 0.1, (12_000, 3))
    gyro[5000:6000, 1] += 4.0 * np.sin(np.pi * np.arange(1000) / 1000) ** 2
    path = tmp_path / "tilt.csv"
    write_recording(path, Recording.from_dps(gyro, 100.0))
    assert main(["arma", str(path), "--max-n", "1", "--json", str(tmp_path / "a.json")]) == 0
    err = " ".join(capsys.readouterr().err.split())
    assert "axis y: the rate moves by up to" in err and "axis x:" not in err
    assert any("does not look static" in w for w in json.loads((tmp_path / "a.json").read_text())["warnings"])
