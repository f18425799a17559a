"""``gyrofilter simulate``: writes what :func:`simulate` returns; bad input is one line, exit 2."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gyrofilter.cli import main
from gyrofilter.recording import read_recording
from gyrofilter.sim.simulate import simulate
from gyrofilter.sources.simulated import DEFAULT_MODEL_PATH
from support import REPO

EXAMPLES = REPO / "examples" / "models"


def write_json(path, obj):
    path.write_text(json.dumps(obj))
    return str(path)


MODEL = {
    "sample_rate_hz": 50.0, "gyro_unit": "lsb", "lsb_per_dps": 131.0, "full_scale_dps": 250.0,
    "temperature": {"start_c": 25.0, "end_c": 30.0, "tau_s": 20.0, "noise_c": 0.02, "resolution_c": 1 / 340},
    "axes": {"x": {"bias_dps": -3.3, "arw_dps_per_sqrt_hz": 0.009,
                   "effects": [{"effect": "gauss_markov", "sigma_dps": 0.05, "tau_s": 3.0},
                               {"effect": "temperature", "coefficient_dps_per_c": 0.02}]},
             "y": {"bias_dps": 1.0, "arw_dps_per_sqrt_hz": 0.01,
                   "effects": [{"effect": "bias_instability", "b_dps": 0.01}]},
             "z": {"bias_dps": 0.2, "arw_dps_per_sqrt_hz": 0.008,
                   "effects": [{"effect": "outliers", "rate": 0.01, "magnitude_dps": 2.0}]}},
}


def test_cli_writes_the_same_numbers_as_simulate_in_small_chunks(tmp_path, capsys):
    model_path = write_json(tmp_path / "m.json", MODEL)
    out = tmp_path / "sim.csv.gz"
    rc = main(["simulate", "--model", model_path, "--duration", "30", "--seed", "8", "--out", str(out), "--chunk", "333"])
    assert rc == 0
    assert "1500 samples" in capsys.readouterr().out
    rec = read_recording(out)
    ref = simulate(MODEL, 30.0, seed=8)
    assert np.array_equal(rec.gyro, ref.gyro)
    assert np.allclose(rec.temp_c, ref.temp_c, atol=1e-5)
    assert np.allclose(rec.t_s, ref.t_s)
    assert rec.header["sensor"] == "simulated" and rec.header["simulated_seed"] == "8"
    assert json.loads(rec.header["simulated_model"])["axes"]["x"]["effects"][0]["tau_s"] == 3.0


def test_the_file_is_the_same_text_whatever_the_chunk(tmp_path):
    """Attack pass 22's notes: with --chunk 1 the first row's t (0) was written "0", as an
    integer column (the writer chooses a column's format per block), and "0.0" otherwise."""
    for model_path in (write_json(tmp_path / "m.json", MODEL), str(DEFAULT_MODEL_PATH)):  # the default: six axes
        texts = []
        for chunk in ("1", "7", "65536"):
            out = tmp_path / f"sim{chunk}.csv"
            assert main(["simulate", "--model", model_path, "--duration", "0.5", "--seed", "3", "--out", str(out),
                         "--chunk", chunk, "--force"]) == 0
            texts.append(out.read_text())
        assert texts[0] == texts[1] == texts[2] and "\n0.0," in texts[0]


def test_cli_without_a_seed_draws_one_and_writes_it_so_the_run_can_be_repeated(tmp_path):
    model_path = write_json(tmp_path / "m.json", MODEL)
    a, b, again = tmp_path / "a.csv", tmp_path / "b.csv", tmp_path / "again.csv"
    for out in (a, b):
        assert main(["simulate", "--model", model_path, "--duration", "5", "--out", str(out)]) == 0
    ra, rb = read_recording(a), read_recording(b)
    assert ra.header["simulated_seed"] != rb.header["simulated_seed"]
    assert not np.array_equal(ra.gyro, rb.gyro)
    seed = ra.header["simulated_seed"]
    assert main(["simulate", "--model", model_path, "--duration", "5", "--seed", seed, "--out", str(again)]) == 0
    assert np.array_equal(read_recording(again).gyro, ra.gyro)


def test_cli_rate_override_and_plain_csv(tmp_path):
    model_path = write_json(tmp_path / "m.json", MODEL)
    out = tmp_path / "sim.csv"
    assert main(["simulate", "--model", model_path, "--duration", "2", "--sample-rate-hz", "200", "--seed", "1", "--out", str(out)]) == 0
    rec = read_recording(out)
    assert rec.sample_rate_hz == 200.0 and len(rec) == 400
    assert out.read_text().startswith("# gyrofilter-recording: 1\n")


def test_cli_sample_rate_spelling_and_the_removed_alias(tmp_path, capsys):
    model_path = write_json(tmp_path / "m.json", MODEL)
    out = tmp_path / "sim.csv"
    assert main(["simulate", "--model", model_path, "--duration", "1", "--sample-rate-hz", "50", "--out", str(out)]) == 0
    assert read_recording(out).sample_rate_hz == 50.0
    assert main(["simulate", "--model", model_path, "--duration", "1", "--sample-rate-hz", "1e-9", "--out", str(tmp_path / "o.csv")]) == 2
    assert "--sample-rate-hz must be a number of Hz in [0.001, 100000], got 1e-09" in capsys.readouterr().err
    # inf is no plain decimal number: the option's type refuses it (issue 22), naming the option
    try:  # SystemExit while argparse prints its usage too
        code = main(["simulate", "--model", model_path, "--duration", "1", "--sample-rate-hz", "inf", "--out", str(tmp_path / "o.csv")])
    except SystemExit as exc:
        code = exc.code
    assert code == 2
    assert "argument --sample-rate-hz: must be a plain decimal number" in capsys.readouterr().err
    # --rate, the alias until 0.2.0, is refused before any work, naming the one spelling
    with pytest.raises(SystemExit) as stop:
        main(["simulate", "--model", model_path, "--duration", "1", "--rate", "50", "--out", str(tmp_path / "o.csv")])
    assert stop.value.code == 2
    assert "unrecognized arguments: --rate 50; did you mean --sample-rate-hz?" in capsys.readouterr().err
    assert not (tmp_path / "o.csv").exists()


def test_cli_accepts_a_gap_report_with_extended_model(tmp_path):
    report = {"recording": "r.csv", "findings": [], "extended_model": MODEL}
    model_path = write_json(tmp_path / "gap.json", report)
    out = tmp_path / "sim.csv"
    assert main(["simulate", "--model", model_path, "--duration", "1", "--seed", "1", "--out", str(out)]) == 0
    assert np.array_equal(read_recording(out).gyro, simulate(MODEL, 1.0, seed=1).gyro)


@pytest.mark.parametrize("model_text, expected", [
    ('{"sample_rate_hz": 100, "axes": {"x": {"effects": [{"effect": "gauss_markov", "sigma_dps": 1}]}}}',
     "axes.x.effects[0] (gauss_markov): missing parameter 'tau_s' (expected a number > 0)"),
    ('{"sample_rate_hz": 100, "axes": {"q": {}}}', "axes.q: unknown axis (expected x, y or z)"),
    ('{"sample_rate_hz": 100, "axes": {"x": {"effects": [{"effect": "wobble"}]}}}', 'unknown effect "wobble"'),
    ('{"sample_rate_hz": 100, "axes": {"x": {"bias_dps": -1, "effects": [{"effect": "warmup", "amplitude_dps": 1, "tau_s": -5}]}}}',
     "tau_s: expected a number > 0, got -5.0"),
    ('{"sample_rate_hz": 100, "axes": {', "not valid JSON: line 1 column"),
    ('[1, 2]', "top level: expected a JSON object"),
])
def test_cli_bad_model_is_one_line_naming_the_key(tmp_path, capsys, model_text, expected):
    path = tmp_path / "bad.json"
    path.write_text(model_text)
    rc = main(["simulate", "--model", str(path), "--duration", "1", "--out", str(tmp_path / "o.csv")])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1 and err.startswith("gyrofilter: error: ")
    assert str(path) in err and expected in err


def test_cli_missing_model_file_and_bad_duration(tmp_path, capsys):
    assert main(["simulate", "--model", str(tmp_path / "none.json"), "--duration", "1", "--out", str(tmp_path / "o.csv")]) == 2
    assert "none.json" in capsys.readouterr().err
    model_path = write_json(tmp_path / "m.json", MODEL)
    assert main(["simulate", "--model", model_path, "--duration", "-3", "--out", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err
    assert "--duration must be in (0, 1e+09], got -3.0" in err and err.count("\n") == 1 and model_path not in err


@pytest.mark.parametrize("option, expected", [
    (["--sample-rate-hz", "-5"], "--sample-rate-hz must be a number of Hz in [0.001, 100000], got -5.0"),
    (["--sample-rate-hz", "1e-320"], "--sample-rate-hz must be a number of Hz in [0.001, 100000], got 1e-320"),
    (["--seed", "-1"], "--seed must be an integer in [0, 2^63 - 1], got -1"),
    (["--seed", str(10**30)], "--seed must be an integer in [0, 2^63 - 1], got an integer of 31 digits"),
    (["--chunk", "0"], "--chunk must be at least 1 sample, got 0"),
    (["--chunk", "2000000"], "--chunk must be at most 1048576 samples, got 2000000"),
    # issue 22: a duration that overflowed the sample count, and one of more samples than a file can hold
    (["--duration", "1e308"], "--duration must be in (0, 1e+09], got 1e+308"),
    (["--duration", "1e8"], "--duration: 1e+08 s at 50 Hz is 5e+09 samples; a simulated recording holds at most 1e+09"),
])
def test_cli_bad_options_are_named_not_blamed_on_the_model(tmp_path, capsys, option, expected):
    model_path = write_json(tmp_path / "m.json", MODEL)
    duration = [] if option[0] == "--duration" else ["--duration", "1"]  # an option is given once
    assert main(["simulate", "--model", model_path, *duration, "--out", str(tmp_path / "o.csv")] + option) == 2
    err = capsys.readouterr().err
    assert expected in err and model_path not in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json"]


def test_cli_warns_about_unknown_effect_parameters(tmp_path, capsys):
    m = json.loads(json.dumps(MODEL))
    m["axes"]["z"]["effects"].append({"effect": "sinusoid", "frequency_hz": 1.0, "amplitude_dps": 0.1, "evidence": "x"})
    model_path = write_json(tmp_path / "m.json", m)
    assert main(["simulate", "--model", model_path, "--duration", "1", "--out", str(tmp_path / "o.csv")]) == 0
    err = capsys.readouterr().err
    assert "warning" in err and "unknown parameter 'evidence' ignored" in err


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.json")) + [Path(str(DEFAULT_MODEL_PATH))], ids=lambda p: p.stem)
def test_example_models_run(tmp_path, path):
    out = tmp_path / "o.csv.gz"
    assert main(["simulate", "--model", str(path), "--duration", "5", "--seed", "1", "--out", str(out)]) == 0
    rec = read_recording(out)
    assert len(rec) == round(5 * rec.sample_rate_hz)
    assert np.all(np.isfinite(rec.gyro))


def test_help_and_entry_point():
    res = subprocess.run([sys.executable, "-m", "gyrofilter", "simulate", "--help"], capture_output=True, text=True)
    assert res.returncode == 0 and "--model" in res.stdout and "--seed" in res.stdout


def test_cli_refuses_to_overwrite_and_never_writes_onto_the_model(tmp_path, capsys):
    model_path = write_json(tmp_path / "m.json", MODEL)
    model_text = (tmp_path / "m.json").read_text()
    out = tmp_path / "sim.csv"
    out.write_text("a user's data\n")
    assert main(["simulate", "--model", model_path, "--duration", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "exists (use --force to overwrite)" in err and str(out) in err
    assert out.read_text() == "a user's data\n"
    for force in ([], ["--force"]):
        assert main(["simulate", "--model", model_path, "--duration", "1", "--out", model_path] + force) == 2
        assert "is an input of this command" in capsys.readouterr().err
        assert (tmp_path / "m.json").read_text() == model_text
    assert main(["simulate", "--model", model_path, "--duration", "1", "--seed", "2", "--out", str(out), "--force"]) == 0
    assert len(read_recording(out)) == 50


def test_cli_failure_leaves_no_file_and_a_rerun_works(tmp_path, capsys, monkeypatch):
    import gyrofilter.cli.simulate as command
    from gyrofilter.errors import SettingsError

    real = command.simulate_chunks

    def failing(*args, **kwargs):
        chunks = real(*args, **kwargs)
        yield next(chunks)
        raise SettingsError("simulated failure after the first block")

    model_path = write_json(tmp_path / "m.json", MODEL)
    out = tmp_path / "sim.csv.gz"
    argv = ["simulate", "--model", model_path, "--duration", "10", "--chunk", "100", "--seed", "3", "--out", str(out)]
    monkeypatch.setattr(command, "simulate_chunks", failing)
    assert main(argv) == 2
    assert "simulated failure" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json"]  # no header-only file, no temporary
    monkeypatch.setattr(command, "simulate_chunks", real)
    assert main(argv) == 0
    assert np.array_equal(read_recording(out).gyro, simulate(MODEL, 10.0, seed=3).gyro)


@pytest.mark.parametrize("signame", ["SIGTERM", "SIGHUP"])
def test_a_killed_simulation_leaves_no_partial_file(tmp_path, capsys, monkeypatch, signame):
    """kill or a closed terminal stops the command as Ctrl-C does: clean-up runs, nothing is left."""
    import os
    import signal

    import gyrofilter.cli.simulate as command

    before = signal.getsignal(getattr(signal, signame))
    real = command.simulate_chunks

    def chunks_then_killed(*args, **kwargs):
        for i, chunk in enumerate(real(*args, **kwargs)):
            if i == 2:
                os.kill(os.getpid(), getattr(signal, signame))
            yield chunk

    monkeypatch.setattr(command, "simulate_chunks", chunks_then_killed)
    model = DEFAULT_MODEL_PATH
    out = tmp_path / "long.csv.gz"
    assert main(["simulate", "--model", str(model), "--duration", "3600", "--out", str(out), "--chunk", "1000"]) == 130
    # attack pass (issue 37): the line said "interrupted" only; it names the output that was not written
    assert capsys.readouterr().err == f"gyrofilter: interrupted; not written: {out}\n"
    assert list(tmp_path.iterdir()) == []
    assert signal.getsignal(getattr(signal, signame)) is before  # main() leaves the process's handlers as they were


def test_one_model_file_works_for_simulate_the_sim_source_and_temp_model(tmp_path, capsys):
    """The same file (a gap report here) through the one loader: simulate --model, sim:FILE and
    sim:model=FILE give the same samples; --temp-model takes it too."""
    gap_report = REPO / "docs" / "gap" / "mpu6050_static_100s.json"
    mine = write_json(tmp_path / "gap.json", {"recording": "r.csv", "findings": [], "extended_model": MODEL})
    for path in (str(gap_report), mine):
        sim = tmp_path / "sim.csv"
        assert main(["simulate", "--model", path, "--duration", "2", "--seed", "3", "--out", str(sim), "--force"]) == 0
        expected = read_recording(sim).gyro
        for spec in (f"sim:{path}", f"sim:model={path}"):
            out = tmp_path / "rec.csv"
            assert main(["record", "--source", spec + ",seed=3,duration=2,realtime=0", "--out", str(out), "--force"]) == 0
            np.testing.assert_array_equal(read_recording(out).gyro, expected)
    assert main(["replay", str(sim), "--temp-model", mine, "--calibration-s", "1"]) == 0  # 2 s: a row after the window
    assert "unknown key" not in capsys.readouterr().err
