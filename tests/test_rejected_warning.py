"""replay and run warn when the filter rejects more than occasional gross errors: a vibration that swings by more
than q within a block loses its extremes to paper 001's rule and biases the block means (a new user's trial: a still
sensor on a 20-Hz, 3-deg/s vibration read -0.74 deg/s with 80 % of the samples rejected, and no word)."""
import numpy as np
import pytest

from gyrofilter.cli import main
from gyrofilter.recording import Recording, write_recording

FS = 100.0


def _vibrating(path, amplitude_dps, seed=0):
    """A still 300-s record at 100 Hz: bias, white noise of 0.05 deg/s and a 20-Hz vibration after a still 2 s."""
    rng = np.random.default_rng(seed)
    n = 30_000
    t = np.arange(n) / FS
    x = np.array([0.8, -1.2, 0.3]) + rng.normal(0, 0.05, (n, 3))
    x[200:] += amplitude_dps * np.sin(2 * np.pi * 20.0 * t[200:, None] + np.array([0.0, 1.0, 2.0]))
    write_recording(path, Recording.from_dps(x, FS))
    return str(path)


def test_a_vibration_beyond_q_is_warned_of_and_raising_q_takes_it(tmp_path, capsys):
    path = _vibrating(tmp_path / "vib.csv", 3.0)
    assert main(["replay", path, "--out", str(tmp_path / "a.csv")]) == 0
    err = " ".join(capsys.readouterr().err.split())
    assert "the filter rejected many samples as gross errors (x" in err and "--set outlier_q_dps=VALUE" in err, err
    assert main(["replay", path, "--set", "outlier_q_dps=7", "--out", str(tmp_path / "b.csv")]) == 0
    assert "rejected many samples" not in capsys.readouterr().err
    from gyrofilter.recording import read_recording
    rows = read_recording(str(tmp_path / "b.csv"))
    means = [float(np.mean(rows.columns[c][100:])) for c in ("gx", "gy", "gz")]
    assert np.abs(means).max() < 0.01


@pytest.mark.parametrize("amplitude_dps", [0.0, 0.3])
def test_a_still_or_gently_vibrating_record_gets_no_warning(tmp_path, capsys, amplitude_dps):
    assert main(["replay", _vibrating(tmp_path / "still.csv", amplitude_dps)]) == 0
    assert "rejected many samples" not in capsys.readouterr().err


def test_run_says_it_too(tmp_path, capsys):
    path = _vibrating(tmp_path / "vib.csv", 3.0)
    assert main(["run", "--source", f"replay:{path}", "--out", str(tmp_path / "r.csv")]) == 0
    assert "the filter rejected many samples as gross errors" in " ".join(capsys.readouterr().err.split())
