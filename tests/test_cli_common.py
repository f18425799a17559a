"""cli.common: output safety (check_outputs, replacing, replacing_in) and strict JSON."""
import json
import os

import numpy as np
import pytest

from gyrofilter.cli import common
from gyrofilter.errors import SettingsError


def _strict(text):
    def refuse(token):
        raise AssertionError(f"non-standard JSON token {token}")

    return json.loads(text, parse_constant=refuse)


def test_write_json_makes_numpy_plain_and_non_finite_null(tmp_path):
    path = tmp_path / "a.json"
    common.write_json(path, {"a": np.float64(np.nan), "b": [np.inf, -np.inf, np.float32(0.5)], "c": np.arange(2),
                             "d": (np.int64(3), True, None, "s")})
    assert _strict(path.read_text()) == {"a": None, "b": [None, None, 0.5], "c": [0, 1], "d": [3, True, None, "s"]}


def test_replacing_in_moves_files_on_success_and_leaves_nothing_on_failure(tmp_path):
    folder = tmp_path / "out"
    with common.replacing_in(str(folder)) as tmp:
        (open(os.path.join(tmp, "a.png"), "w")).write("new")
        assert not (folder / "a.png").exists()
    assert sorted(os.listdir(folder)) == ["a.png"] and (folder / "a.png").read_text() == "new"
    with pytest.raises(RuntimeError), common.replacing_in(str(folder)) as tmp:
        (open(os.path.join(tmp, "a.png"), "w")).write("half")
        raise RuntimeError("failed")
    assert sorted(os.listdir(folder)) == ["a.png"] and (folder / "a.png").read_text() == "new"
    with pytest.raises(RuntimeError), common.replacing_in(str(tmp_path / "made")) as tmp:
        raise RuntimeError("failed")
    assert not (tmp_path / "made").exists()


def test_check_outputs(tmp_path):
    existing, new, inp = tmp_path / "e.json", tmp_path / "n.json", tmp_path / "in.csv"
    existing.write_text("x")
    inp.write_text("x")
    common.check_outputs([str(new), None], [str(inp)])
    common.check_outputs([str(existing)], [str(inp)], force=True)
    with pytest.raises(FileExistsError):
        common.check_outputs([str(existing)], [str(inp)])
    with pytest.raises(SettingsError, match="is an input"):
        common.check_outputs([str(tmp_path / "." / "in.csv")], [str(inp)], force=True)
    with pytest.raises(SettingsError, match="two outputs"):
        common.check_outputs([str(new), str(new)], [])


def test_replacing_makes_missing_folders_and_removes_them_on_failure(tmp_path):
    target = tmp_path / "a" / "b" / "out.json"
    with pytest.raises(RuntimeError), common.replacing(str(target)) as tmp:
        assert os.path.basename(tmp).endswith("-out.json") and os.path.isdir(tmp_path / "a" / "b")
        open(tmp, "w").write("half")
        raise RuntimeError("failed")
    assert os.listdir(tmp_path) == []
    with common.replacing(str(target)) as tmp:
        open(tmp, "w").write("whole")
    assert target.read_text() == "whole" and os.listdir(target.parent) == ["out.json"]


@pytest.mark.parametrize("command, old", [("record", "--sample-rate"), ("run", "--sample-rate"), ("simulate", "--rate")])
def test_sample_rate_option_has_one_spelling_and_keeps_the_old_one(command, old):
    from gyrofilter.cli import build_parser

    for spelling in ("--sample-rate-hz", old):
        extra = ["--model", "m.json", "--duration", "1", "--out", "o.csv"] if command == "simulate" else ["--source", "sim", "--out", "o.csv"]
        args = build_parser(command).parse_args([command, *extra, spelling, "250"])
        assert args.sample_rate_hz == 250.0 and args.sample_rate_hz_option == spelling


def test_an_error_writing_the_temporary_file_names_the_users_path(tmp_path):
    """The user gave ``out.csv``; an OSError on the hidden temporary file must name ``out.csv``."""
    path = str(tmp_path / "out.csv")
    with pytest.raises(OSError) as err:
        with common.replacing(path) as tmp:
            open(os.path.join(tmp, "cannot", "exist"), "w")  # tmp is a file path: ENOTDIR / ENOENT
    assert err.value.filename == os.path.join(path, "cannot", "exist")
    assert ".partial-" not in str(err.value)
    folder = str(tmp_path / "rep")
    with pytest.raises(OSError) as err:
        with common.replacing_in(folder) as tmp:
            open(os.path.join(tmp, "no", "fig.png"), "w")
    assert err.value.filename == os.path.join(folder, "no", "fig.png")
