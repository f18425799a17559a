"""A fleet that mixes still and moving records, and paths that are no recordings (a new user's
``gyrofilter gap recordings/* --fleet DIR``): the moving records are not analysed unless
--allow-motion, and never enter the comparison that decides who stands out."""
import numpy as np

from gyrofilter.cli import main

RATE_HZ = 100.0


def _write(path, rng, white_dps, moving=False, seconds=60.0):
    """A recording in deg/s: white noise of ``white_dps`` per sample on each axis, and with ``moving``
    a slow turn about x (50 deg/s, a 20-s period)."""
    t = np.arange(int(seconds * RATE_HZ)) / RATE_HZ
    g = rng.standard_normal((t.size, 3)) * white_dps
    if moving:
        g[:, 0] += 50.0 * np.sin(2 * np.pi * t / 20.0)
    rows = "".join(f"{a:.6f},{b:.6f},{c:.6f}\n" for a, b, c in g)
    path.write_text(f"# gyrofilter-recording: 1\n# sample_rate_hz: {RATE_HZ:g}\n# gyro_unit: dps\ngx,gy,gz\n{rows}")


def _fleet(folder):
    """Six still units (unit0's white noise 1.6x the others': N high on every axis) and three moving
    ones of very different noise, a README and a folder beside them."""
    rng = np.random.default_rng(7)
    for u in range(6):
        _write(folder / f"unit{u}.csv", rng, 0.1 * (1.6 if u == 0 else np.exp(0.02 * rng.standard_normal())))
    for u, white in enumerate((0.02, 0.4, 0.8)):
        _write(folder / f"moving{u}.csv", rng, white, moving=True)
    (folder / "README.md").write_text("# Recordings\n")
    (folder / "LICENSES").mkdir()
    return sorted(str(p) for p in folder.iterdir())


def test_moving_records_are_skipped_and_do_not_hide_a_still_units_flag(tmp_path, capsys):
    (tmp_path / "in").mkdir()
    paths = _fleet(tmp_path / "in")
    assert main(["allan", *paths, "--fleet", str(tmp_path / "out"), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "fleet: 9 recording(s), 6 analysed, 3 not still (not analysed), 0 failed, 1 stand(s) out" in out
    assert out.count("  not still: ") == 3 and "moving1.csv: axis x is not still" in out
    assert out.count("  skipped, not a recording: ") == 2  # README.md and LICENSES: not counted, not failed
    assert "stands out: unit0 x: N high" in out
    md = (tmp_path / "out" / "fleet.md").read_text()
    assert "## Not still" in md and "## Not recordings" in md and "## Failed" not in md


def test_with_allow_motion_the_moving_records_are_analysed_but_kept_out_of_the_comparison(tmp_path, capsys):
    (tmp_path / "in").mkdir()
    paths = [p for p in _fleet(tmp_path / "in") if p.endswith(".csv")]
    assert main(["allan", *paths, "--fleet", str(tmp_path / "out"), "--jobs", "1", "--allow-motion"]) == 0
    out = capsys.readouterr().out
    assert "fleet: 9 recording(s), 9 analysed (3 of them moving: kept out of the comparison), 0 failed, " \
           "1 stand(s) out" in out
    assert "kept out of the comparison: moving0, moving1, moving2" in out
    assert "stands out: unit0 x: N high" in out and "stands out: moving" not in out
    md = (tmp_path / "out" / "fleet.md").read_text()
    assert "| x | N | 6 |" in md  # the statistics over the six still units only


def test_a_damaged_gzip_file_beside_the_recordings_fails_alone(tmp_path, capsys):
    """Attack pass 37j: a damaged gzip file named neither .csv nor .csv.gz (its deflate data broken) ended
    the fleet run in a traceback (zlib.error while its first line was read to tell whether it is a
    recording); it fails alone, with the reader's reason."""
    import gzip

    rng = np.random.default_rng(1)
    for u in range(2):
        _write(tmp_path / f"unit{u}.csv", rng, 0.1, seconds=20.0)
    data = gzip.compress(b"# gyrofilter-recording: 1\n" * 100)
    (tmp_path / "notes.gz").write_bytes(data[:10] + b"\xff" * 30 + data[40:])
    paths = sorted(str(p) for p in tmp_path.iterdir())
    assert main(["allan", *paths, "--fleet", str(tmp_path / "out"), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "3 recording(s), 2 analysed" in out and "1 failed" in out and "damaged gzip data" in out


def test_a_recording_with_a_byte_order_mark_named_txt_is_analysed(tmp_path, capsys):
    """Attack pass 37j: a recording saved by a Windows editor (a UTF-8 byte-order mark first) as .txt, which
    every command reads, was skipped as "not a recording (... the first line is not '# gyrofilter-recording:
    1')" and lost from the fleet."""
    rng = np.random.default_rng(1)
    for u in range(2):
        _write(tmp_path / f"unit{u}.csv", rng, 0.1, seconds=20.0)
    (tmp_path / "unit2.txt").write_bytes(b"\xef\xbb\xbf" + (tmp_path / "unit1.csv").read_bytes())
    paths = sorted(str(p) for p in tmp_path.iterdir())
    assert main(["allan", *paths, "--fleet", str(tmp_path / "out"), "--jobs", "1"]) == 0
    assert "3 recording(s), 3 analysed" in capsys.readouterr().out


def test_a_sharp_turn_is_skipped_with_advice_that_analyses_it(tmp_path, capsys):
    """Attack pass 37k: allan's fleet said a record with a sharp turn "--allow-motion analyses it anyway",
    and with --allow-motion refused the turn's edges as gross errors; the skip names --keep-outliers too,
    and the advice as given analyses it."""
    rng = np.random.default_rng(3)
    for u in range(2):
        _write(tmp_path / f"unit{u}.csv", rng, 0.1, seconds=20.0)
    t = np.arange(2000) / RATE_HZ
    g = rng.standard_normal((t.size, 3)) * 0.1
    g[800:900, 2] += 200.0  # a 1-s turn at 200 deg/s, its edges one sample each
    rows = "".join(f"{a:.6f},{b:.6f},{c:.6f}\n" for a, b, c in g)
    (tmp_path / "turn.csv").write_text(f"# gyrofilter-recording: 1\n# sample_rate_hz: {RATE_HZ:g}\n# gyro_unit: dps\n"
                                       f"gx,gy,gz\n{rows}")
    paths = sorted(str(p) for p in tmp_path.iterdir())
    assert main(["allan", *paths, "--fleet", str(tmp_path / "out"), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    advice = "--allow-motion --keep-outliers analyses it anyway (its motion reads as gross errors)"
    assert "turn.csv: axis z is not still" in out and advice in out
    assert main(["allan", *paths, "--fleet", str(tmp_path / "out2"), "--jobs", "1", "--allow-motion",
                 "--keep-outliers"]) == 0
    assert "3 analysed (1 of them moving: kept out of the comparison), 0 failed" in capsys.readouterr().out
