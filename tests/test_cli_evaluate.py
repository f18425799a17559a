"""`gyrofilter evaluate`: the table, and one-line errors."""
import json
import math
import os

import numpy as np
import pytest

from gyrofilter.evaluation import evaluate as E
from gyrofilter.recording import Recording, write_recording


@pytest.mark.slow
def test_evaluate_command_writes_table_json_and_figure(tmp_path, capsys):
    pytest.importorskip("matplotlib")  # the command always draws the Pareto figure
    from gyrofilter.cli import main

    rng = np.random.default_rng(6)
    rec_dir = tmp_path / "recordings"
    rec_dir.mkdir()
    static = Recording.from_dps(rng.normal(scale=0.1, size=(9100, 3)) + [1.0, 0.5, -0.2], 100.0,
                                header={"sensor": "MPU6050", "description": "static: synthetic"})
    write_recording(rec_dir / "mpu6050_static_91s.csv.gz", static)
    out = tmp_path / "out"
    code = main(["evaluate", "--recordings", str(rec_dir), "--out", str(out), "--no-lag"])
    assert code == 0
    text = (out / "evaluate_table.md").read_text()
    assert "| paper001 |" in text and "recommended preset" in text
    console = capsys.readouterr().out  # a row per filter that fits 100 columns; every number in the file
    assert max(len(line) for line in console.splitlines()) <= 100
    assert sum(line.startswith(("paper001 ", "recommended preset ")) for line in console.splitlines()) == 2
    data = json.loads((out / "evaluate.json").read_text())
    # the block mean reduces white noise by sqrt(5)
    assert np.allclose(data["static_std_reduction"]["block mean 5"]["mpu6050_static_91s"], math.sqrt(5), rtol=0.1)
    assert os.path.getsize(out / "evaluate_pareto.png") > 10_000
    assert main(["evaluate", "--recordings", str(tmp_path / "nope")]) == 2


@pytest.mark.slow
def test_evaluate_command_refuses_existing_outputs_and_a_failure_leaves_none(tmp_path, capsys, monkeypatch):
    pytest.importorskip("matplotlib")
    from gyrofilter.cli import main
    from gyrofilter.errors import SettingsError

    out = tmp_path / "out"
    out.mkdir()
    (out / "evaluate.json").write_text("a user's results")
    argv = ["evaluate", "--recordings", str(tmp_path / "none"), "--out", str(out)]
    assert main(argv) == 2  # refused before the recordings are even looked for
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "evaluate.json: exists (use --force" in err
    assert os.listdir(out) == ["evaluate.json"] and (out / "evaluate.json").read_text() == "a user's results"

    def failing(ev, path, reference="paper001"):
        raise SettingsError("simulated failure while drawing")

    rng = np.random.default_rng(7)
    rec_dir = tmp_path / "recordings"
    rec_dir.mkdir()
    short = rec_dir / "mpu6050_static_30s.csv.gz"
    header = {"sensor": "MPU6050", "description": "static: synthetic"}
    write_recording(short, Recording.from_dps(rng.normal(scale=0.1, size=(3000, 3)), 100.0, header=header))
    fresh = tmp_path / "fresh"
    assert main(["evaluate", "--recordings", str(rec_dir), "--out", str(fresh), "--no-lag"]) == 2
    assert "no static recording lasts the 90 s" in capsys.readouterr().err  # was a ZeroDivisionError
    short.unlink()
    write_recording(rec_dir / "mpu6050_static_91s.csv.gz",
                    Recording.from_dps(rng.normal(scale=0.1, size=(9100, 3)), 100.0, header=header))
    monkeypatch.setattr(E, "plot_pareto", failing)
    assert main(["evaluate", "--recordings", str(rec_dir), "--out", str(fresh), "--no-lag"]) == 2
    assert "simulated failure" in capsys.readouterr().err
    assert not fresh.exists()  # no table or JSON without the figure, and no empty folder


@pytest.mark.slow
def test_a_file_size_limit_names_the_file_that_failed(tmp_path):
    """Attack pass 59: under a file size limit of 3000 bytes, evaluate said "ev3: File too large; not written",
    naming the folder, not its table (written with open(), whose close failed without a file name)."""
    pytest.importorskip("matplotlib")
    import resource
    import subprocess
    import sys

    rng = np.random.default_rng(8)
    rec_dir = tmp_path / "recordings"
    rec_dir.mkdir()
    write_recording(rec_dir / "mpu6050_static_91s.csv.gz",
                    Recording.from_dps(rng.normal(scale=0.1, size=(9100, 3)), 100.0,
                                       header={"sensor": "MPU6050", "description": "static: synthetic"}))
    out = tmp_path / "ev"

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (3000, 3000))

    run = subprocess.run([sys.executable, "-m", "gyrofilter", "evaluate", "--recordings", str(rec_dir), "--out", str(out),
                          "--no-lag"], preexec_fn=limit, capture_output=True, text=True, timeout=900)
    assert run.returncode == 2
    assert run.stderr.splitlines()[-1] == f"gyrofilter: error: {out / 'evaluate_table.md'}: File too large; not written"
    assert not out.exists() or os.listdir(out) == []
