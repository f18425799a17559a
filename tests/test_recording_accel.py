"""The six axes of recording format v1 (docs/formats.md section 1, "Six axes"): the columns
``ax, ay, az`` with ``accel_unit`` (and ``lsb_per_g``), checked where the header is checked, their
conversion to m/s^2, the writer's exact round trip, the gyro-only commands that ignore them and
``run``/``record``, which carry them along."""
import json
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gyrofilter.cli import main
from gyrofilter.errors import RecordingError, SettingsError
from gyrofilter.recording import (ACCEL_COLUMNS, Recording, RecordingWriter, format_number, iter_recording,
                                  read_recording, write_recording)
from gyrofilter.units import STANDARD_GRAVITY_MPS2, check_lsb_per_g, to_mps2
from support import REPO

REAL = REPO / "recordings" / "mpu6050_static_100s.csv.gz"  # a real MPU6050, gx, gy, gz, ax, ay, az (accel_unit: g)

SIX = """# gyrofilter-recording: 1
# sample_rate_hz: 100
# gyro_unit: lsb
# lsb_per_dps: 131
# accel_unit: lsb
# lsb_per_g: 16384
t,gx,gy,gz,temp,ax,ay,az
0.00,12,-3,40,25.31,-120,88,16390
0.01,15,-1,37,25.31,-118,90,16388
"""


def test_to_mps2_uses_standard_gravity_in_each_unit():
    values = np.array([[-120.0, 88.0, 16384.0]])
    np.testing.assert_array_equal(to_mps2(values, "m/s^2"), values)
    np.testing.assert_array_equal(to_mps2(values, "g"), values * 9.80665)
    np.testing.assert_allclose(to_mps2(values, "lsb", 16384.0)[0, 2], 9.80665, rtol=0, atol=1e-15)  # 1 g
    np.testing.assert_allclose(to_mps2([[2048.0]], "lsb", 2048.0), [[9.80665]], rtol=1e-15)
    assert STANDARD_GRAVITY_MPS2 == 9.80665
    with pytest.raises(SettingsError, match="lsb_per_g"):
        to_mps2(values, "lsb")
    with pytest.raises(SettingsError, match="'G'"):
        to_mps2(values, "G")


@pytest.mark.parametrize("value", [0, -1.0, float("nan"), float("inf"), 1e-308, 1e308, True, "16384"])
def test_check_lsb_per_g_refuses_what_no_accelerometer_has(value):
    with pytest.raises(SettingsError, match="lsb_per_g must be a number of LSB per g"):
        check_lsb_per_g(value)


def test_check_lsb_per_g_takes_the_mpu6050_scales():
    assert [check_lsb_per_g(v) for v in (2048, 4096, 8192, 16384)] == [2048.0, 4096.0, 8192.0, 16384.0]


def test_a_six_axis_file_reads_with_its_accelerometer_in_mps2(tmp_path):
    path = tmp_path / "six.csv"
    path.write_text(SIX)
    rec = read_recording(path)
    assert rec.accel_unit == "lsb" and rec.lsb_per_g == 16384.0
    np.testing.assert_allclose(rec.accel_mps2, np.array([[-120, 88, 16390], [-118, 90, 16388]]) * 9.80665 / 16384)
    head = next(chunks := iter_recording(path, chunk_rows=1))
    np.testing.assert_array_equal(np.concatenate([head.accel_mps2(c) for c in chunks]), rec.accel_mps2)
    np.testing.assert_array_equal(rec.gyro_dps, np.array([[12, -3, 40], [15, -1, 37]]) / 131)


@pytest.mark.parametrize("edit, where, key", [
    (("accel_unit: lsb", "accel_unit: G"), "line 5", "accel_unit 'G' is not one of m/s^2, g, lsb"),
    (("# lsb_per_g: 16384\n", ""), "line 5", "'lsb_per_g' is missing"),
    (("lsb_per_g: 16384", "lsb_per_g: 0"), "line 6", "lsb_per_g must be"),
    (("lsb_per_g: 16384", "lsb_per_g: -16384"), "line 6", "lsb_per_g must be"),
    (("lsb_per_g: 16384", "lsb_per_g: lots"), "line 6", "lsb_per_g must be a plain decimal number"),
    ((",ax,ay,az\n", ",ax,ay,q\n"), "line 7", "accelerometer column(s) az missing"),
    ((",ax,ay,az\n", ",p,q,r\n"), "line 5", "'accel_unit' is given but the column row (line 7) has no accelerometer"),
], ids=["unit", "no-lsb_per_g", "zero", "negative", "not-a-number", "some-columns", "no-columns"])
def test_a_bad_accelerometer_header_is_one_line_naming_file_line_and_key(tmp_path, capsys, edit, where, key):
    path = tmp_path / "bad.csv"
    path.write_text(SIX.replace(*edit))
    with pytest.raises(RecordingError) as info:
        read_recording(path)
    assert str(info.value).startswith(f"{path}: {where}: ") and key in str(info.value)
    assert main(["allan", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"gyrofilter: error: {info.value}"]
    # the writers refuse the same header before creating the file, naming the line it would have
    rec = Recording.from_dps(np.zeros((2, 3)), 100.0)
    lines = SIX.replace(*edit).splitlines()
    rec.header = dict(ln[2:].split(": ", 1) for ln in lines if ln.startswith("#"))
    rec.columns = {name: np.zeros(2) for name in next(ln for ln in lines if not ln.startswith("#")).split(",")}
    out = tmp_path / "out.csv"
    with pytest.raises(RecordingError, match=f"^{out}: {where}: "):
        write_recording(out, rec)
    assert not out.exists()


@pytest.mark.parametrize("unit, cell, lsb_per_g", [("g", "1.1e6", None), ("m/s^2", "-2e7", None),
                                                  ("lsb", "-1e308", "16384")])
def test_an_acceleration_no_accelerometer_reads_is_refused_naming_line_and_column(tmp_path, unit, cell, lsb_per_g):
    text = SIX.replace("accel_unit: lsb", f"accel_unit: {unit}").replace("16388\n", f"{cell}\n")
    if lsb_per_g is None:
        text = text.replace("# lsb_per_g: 16384\n", "")
    path = tmp_path / "far.csv"
    path.write_text(text)
    line = 9 if lsb_per_g else 8  # the last row
    with pytest.raises(RecordingError, match=f"^{path}: line {line}: column 'az' is {re.escape(format_number(float(cell)))} "
                                             f"{re.escape(unit)}, beyond the "
                                             r"\+-1e\+07 m/s\^2 any accelerometer reads$"):
        read_recording(path)
    # without accel_unit the value is carried along as any other column
    path.write_text(text.replace(f"# accel_unit: {unit}\n", ""))
    assert read_recording(path).columns["az"][-1] == float(cell)
    # a writer refuses it before writing
    good = Recording.from_dps(np.zeros((2, 3)), 100.0, accel=np.array([[0, 0, 1.0], [0, 0, float(cell)]]),
                              accel_unit=unit, lsb_per_g=lsb_per_g and float(lsb_per_g))
    with pytest.raises(RecordingError, match="row 2 of the rows to write: column 'az'"):
        write_recording(tmp_path / "w.csv", good)
    assert not (tmp_path / "w.csv").exists()


def test_without_accel_unit_the_columns_are_carried_and_only_their_analysis_refused(tmp_path):
    path = tmp_path / "old.csv"
    path.write_text(SIX.replace("# accel_unit: lsb\n# lsb_per_g: 16384\n", ""))
    rec = read_recording(path)
    np.testing.assert_array_equal(rec.columns["az"], [16390, 16388])
    with pytest.raises(RecordingError, match=f"^{path}: header key 'accel_unit' is missing"):
        rec.accel_mps2
    gyro_only = Recording.from_dps(np.zeros((2, 3)), 100.0)
    with pytest.raises(RecordingError, match="no accelerometer columns ax, ay, az"):
        gyro_only.accel_mps2
    # some of ax, ay, az without accel_unit: any other columns, as before
    path.write_text(SIX.replace("# accel_unit: lsb\n# lsb_per_g: 16384\n", "").replace(",ax,ay,az", ",ax,ay,q"))
    assert list(read_recording(path).columns)[-3:] == ["ax", "ay", "q"]


@st.composite
def six_axis_records(draw):
    """A recording at 100 Hz with ax, ay, az in a drawn unit: whole LSB (to 2^31, at most about
    1e5 g) or any float to 1e5 (in g: 1e6 m/s^2, within MAX_ACCEL_MPS2)."""
    unit = draw(st.sampled_from(["m/s^2", "g", "lsb"]))
    n = draw(st.integers(1, 40))
    lsb_per_g = draw(st.sampled_from([16384.0, 2048.0, 256.0, 0.5, 3e9, 1.0 / 3.0 + 1])) if unit == "lsb" else None
    values = (st.integers(-min(2**31, int(1e5 * lsb_per_g)), min(2**31, int(1e5 * lsb_per_g))).map(float)
              if unit == "lsb" else st.floats(-1e5, 1e5, width=64))
    accel = np.array(draw(st.lists(values, min_size=3 * n, max_size=3 * n))).reshape(n, 3)
    gyro_dps = np.array(draw(st.lists(st.floats(-2000, 2000), min_size=3 * n, max_size=3 * n))).reshape(n, 3)
    return Recording.from_dps(gyro_dps, 100.0, t_s=np.arange(n) / 100.0, accel=accel, accel_unit=unit,
                              lsb_per_g=lsb_per_g)


@settings(max_examples=40, deadline=None)
@given(rec=six_axis_records(), write_rows=st.integers(1, 50), read_rows=st.integers(1, 50),
       gz=st.booleans())
def test_a_six_axis_record_reads_back_exactly_whatever_the_chunking(tmp_path_factory, rec, write_rows, read_rows, gz):
    path = tmp_path_factory.mktemp("six") / ("six.csv.gz" if gz else "six.csv")
    names = list(rec.columns)
    data = np.column_stack([rec.columns[c] for c in names])
    with RecordingWriter(path, rec.header, names, flush_interval_s=None) as writer:
        for i in range(0, len(data), write_rows):
            writer.write(data[i:i + write_rows])
    chunks = iter_recording(path, chunk_rows=read_rows)
    head = next(chunks)
    back = np.concatenate(list(chunks))
    assert head.names == names and head.accel_unit == rec.header["accel_unit"]
    assert head.header.get("lsb_per_g") == rec.header.get("lsb_per_g")
    np.testing.assert_array_equal(back, data)  # every number, exactly
    whole = read_recording(path)
    np.testing.assert_array_equal(whole.accel_mps2, rec.accel_mps2)
    write_recording(path, whole)
    np.testing.assert_array_equal(np.column_stack(list(read_recording(path).columns.values())), data)


TWIN_ROWS = 4000  # the first 40 s of the real record: enough for every command, quick


def _first_rows(path):
    """The recording at ``path``, its first TWIN_ROWS rows."""
    rec = read_recording(path)
    rec.columns = {name: values[:TWIN_ROWS] for name, values in rec.columns.items()}
    return rec


def _without_accelerometer(path, out):
    """``path`` (a six-axis recording) written to ``out`` without ax, ay, az and their keys."""
    rec = _first_rows(path)
    for name in ACCEL_COLUMNS:
        del rec.columns[name]
    for key in ("accel_unit", "accel_full_scale_g"):
        rec.header.pop(key)
    write_recording(out, rec)
    return out


def _accelerometer_first(path, out):
    """``path`` written to ``out`` with ax, ay, az before the gyro columns: a reader that took
    columns by their place would read the accelerometer as the gyro."""
    rec = _first_rows(path)
    rec.columns = {**{c: rec.columns[c] for c in ACCEL_COLUMNS}, **rec.columns}
    write_recording(out, rec)
    return out


@pytest.fixture(scope="module")
def twins(tmp_path_factory):
    """The real six-axis MPU6050 record (ax, ay, az first) and the same without the accelerometer."""
    folder = tmp_path_factory.mktemp("twins")
    return _accelerometer_first(REAL, folder / "six.csv"), _without_accelerometer(REAL, folder / "three.csv")


def _without_paths_and_times(value):
    """A JSON document without its ``recording`` (the file's path) and ``runtime_s`` (wall time) keys."""
    if isinstance(value, dict):
        return {k: _without_paths_and_times(v) for k, v in value.items() if k not in ("recording", "runtime_s")}
    if isinstance(value, list):
        return [_without_paths_and_times(v) for v in value]
    return value


@pytest.mark.parametrize("command", [["allan"], ["gap", "--sims", "10"], ["arma", "--axis", "z", "--max-n", "1"]],
                         ids=["allan", "gap", "arma"])
def test_gyro_only_commands_give_the_same_results_with_and_without_the_accelerometer(twins, tmp_path, capsys, command):
    reports = []
    for rec in twins:
        out = tmp_path / f"{rec.stem}.json"
        assert main([command[0], str(rec), "--json", str(out), *command[1:]]) == 0
        reports.append(_without_paths_and_times(json.loads(out.read_text())))
    capsys.readouterr()
    if command[0] == "allan":  # allan characterises the accelerometer too (issue 39): its block beside the gyro's
        assert "accelerometer" in reports[0] and "accelerometer" not in reports[1]
        reports[0].pop("accelerometer")
    assert reports[0] == reports[1]


def test_replay_and_run_filter_the_gyro_alone(twins, tmp_path, capsys):
    six, three = twins
    outputs = {}
    for rec in twins:
        replayed, ran = tmp_path / f"replay-{rec.name}", tmp_path / f"run-{rec.name}"
        assert main(["replay", str(rec), "--out", str(replayed)]) == 0
        assert main(["run", "--source", f"replay:{rec}", "--out", str(ran), "--quiet"]) == 0
        outputs[rec] = read_recording(replayed), read_recording(ran)
    capsys.readouterr()
    for with_accel, without in zip(outputs[six], outputs[three]):
        for name in ("t", "gx", "gy", "gz"):
            np.testing.assert_array_equal(with_accel.columns[name], without.columns[name])
    assert list(outputs[three][1].columns) == ["t", "gx", "gy", "gz"]


def test_run_out_keeps_the_accelerometer_of_each_blocks_last_sample_raw(twins, tmp_path, capsys):
    six = read_recording(twins[0])
    out = tmp_path / "run.csv"
    assert main(["run", "--source", f"replay:{twins[0]}", "--out", str(out), "--quiet", "--set", "block_len=4"]) == 0
    capsys.readouterr()
    ran = read_recording(out)
    assert list(ran.columns) == ["t", "gx", "gy", "gz", *ACCEL_COLUMNS]
    assert ran.accel_unit == "g" and "lsb_per_g" not in ran.header
    # the row's t is its block's last sample's (uniform times: t = row / rate); its ax, ay, az that sample's, exactly
    rows = np.rint(ran.t_s * six.sample_rate_hz).astype(int)
    assert len(rows) > 900 and np.all(np.diff(rows) == 4)
    for name in ACCEL_COLUMNS:
        np.testing.assert_array_equal(ran.columns[name], six.columns[name][rows])
    np.testing.assert_array_equal(ran.accel_mps2, six.accel_mps2[rows])


def test_run_stdout_keeps_the_accelerometer_as_its_out_file_does(twins, tmp_path, capsys):
    out = tmp_path / "run.csv"
    assert main(["run", "--source", f"replay:{twins[0]}", "--out", str(out), "--quiet", "--duration", "5"]) == 0
    capsys.readouterr()
    assert main(["run", "--source", f"replay:{twins[0]}", "--quiet", "--duration", "5"]) == 0
    printed = tmp_path / "stdout.csv"
    printed.write_text(capsys.readouterr().out)
    from_file, from_stdout = read_recording(out), read_recording(printed)
    assert list(from_stdout.columns) == list(from_file.columns) == ["t", "gx", "gy", "gz", *ACCEL_COLUMNS]
    for name in ("t", *ACCEL_COLUMNS):
        np.testing.assert_array_equal(from_stdout.columns[name], from_file.columns[name])


def test_record_keeps_the_sources_accelerometer_and_its_unit(tmp_path, capsys):
    source = tmp_path / "six.csv"
    rng = np.random.default_rng(3)
    n = 500
    accel = np.round(rng.normal([0, 0, 16384], 30, (n, 3)))
    rec = Recording.from_dps(rng.normal(0, 0.1, (n, 3)), 100.0, t_s=np.arange(n) / 100.0,
                             temp_c=np.full(n, 25.5), accel=accel, accel_unit="lsb", lsb_per_g=16384)
    write_recording(source, rec)
    out = tmp_path / "recorded.csv"
    assert main(["record", "--source", f"replay:{source}", "--out", str(out), "--quiet"]) == 0
    capsys.readouterr()
    recorded = read_recording(out)
    assert recorded.accel_unit == "lsb" and recorded.lsb_per_g == 16384.0
    assert list(recorded.header)[1:5] == ["sample_rate_hz", "gyro_unit", "accel_unit", "lsb_per_g"]  # the units together
    for name in ("t", "gx", "gy", "gz", "temp", *ACCEL_COLUMNS):
        np.testing.assert_array_equal(recorded.columns[name], rec.columns[name])
    np.testing.assert_array_equal(recorded.accel_mps2, accel * (9.80665 / 16384))


@pytest.mark.parametrize("kwargs, said", [
    ({"accel": np.zeros((5, 3)), "accel_unit": "lsb"}, "lsb_per_g must be a number of LSB per g"),
    ({"accel_unit": "g"}, "accel_unit and lsb_per_g go with accel"),
    ({"lsb_per_g": 16384}, "accel_unit and lsb_per_g go with accel"),
    ({"accel": np.zeros((5, 3)), "accel_unit": "furlong"}, "accel_unit 'furlong' is not one of")])
def test_from_dps_checks_the_accelerometer_s_arguments_together(kwargs, said):
    """Attack pass 26: from_dps(accel=..., accel_unit="lsb") without lsb_per_g ended in Python's
    TypeError; accel_unit without accel built a recording the writer refused, lsb_per_g alone was
    dropped without a word."""
    with pytest.raises(RecordingError, match=f"from_dps: {said}"):
        Recording.from_dps(np.zeros((5, 3)), 100.0, **kwargs)
