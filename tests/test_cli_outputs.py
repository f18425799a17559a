"""cli.outputs: output safety (check_outputs, replacing, replacing_in, commit, stale partials) and
the report writers (strict JSON)."""
import json
import os
import stat
import subprocess
import sys
import time

import numpy as np
import pytest

from gyrofilter import files
from gyrofilter.cli import outputs
from gyrofilter.errors import SettingsError
from gyrofilter.recording import Recording, read_recording, write_recording
from support import REPO, RECORDINGS, UNDER_A_SIZE_LIMIT, file_named_by_bytes
from gyrofilter.sources.simulated import DEFAULT_MODEL_PATH


def _strict(text):
    def refuse(token):
        raise AssertionError(f"non-standard JSON token {token}")

    return json.loads(text, parse_constant=refuse)


def test_write_json_makes_numpy_plain_and_non_finite_null(tmp_path):
    path = tmp_path / "a.json"
    outputs.write_json(path, {"a": np.float64(np.nan), "b": [np.inf, -np.inf, np.float32(0.5)], "c": np.arange(2),
                             "d": (np.int64(3), True, None, "s")})
    assert _strict(path.read_text()) == {"a": None, "b": [None, None, 0.5], "c": [0, 1], "d": [3, True, None, "s"]}


def test_replacing_in_moves_files_on_success_and_leaves_nothing_on_failure(tmp_path):
    folder = tmp_path / "out"
    with outputs.replacing_in(str(folder)) as tmp:
        (open(os.path.join(tmp, "a.png"), "w")).write("new")
        assert not (folder / "a.png").exists()
    assert sorted(os.listdir(folder)) == ["a.png"] and (folder / "a.png").read_text() == "new"
    with pytest.raises(RuntimeError), outputs.replacing_in(str(folder)) as tmp:
        (open(os.path.join(tmp, "a.png"), "w")).write("half")
        raise RuntimeError("failed")
    assert sorted(os.listdir(folder)) == ["a.png"] and (folder / "a.png").read_text() == "new"
    with pytest.raises(RuntimeError), outputs.replacing_in(str(tmp_path / "made")) as tmp:
        raise RuntimeError("failed")
    assert not (tmp_path / "made").exists()


def test_check_outputs(tmp_path):
    existing, new, inp = tmp_path / "e.json", tmp_path / "n.json", tmp_path / "in.csv"
    existing.write_text("x")
    inp.write_text("x")
    outputs.check_outputs([str(new), None], [str(inp)])
    outputs.check_outputs([str(existing)], [str(inp)], force=True)
    with pytest.raises(FileExistsError):
        outputs.check_outputs([str(existing)], [str(inp)])
    with pytest.raises(SettingsError, match="is an input"):
        outputs.check_outputs([str(tmp_path / "." / "in.csv")], [str(inp)], force=True)
    with pytest.raises(SettingsError, match="two outputs"):
        outputs.check_outputs([str(new), str(new)], [])
    with pytest.raises(SettingsError, match=r"newdir/: ends in /, so it names a folder"):  # hostile 5-13
        outputs.check_outputs([str(tmp_path / "newdir") + "/"], [])


def test_an_output_named_as_a_folder_that_does_not_exist_is_refused_before_any_work(tmp_path, capsys):
    """``--out newdir/`` failed only after the work, with "Not a directory" (issue 22, hostile 5-13)."""
    from gyrofilter.cli import main
    from gyrofilter.recording import Recording, read_recording, write_recording

    src = str(tmp_path / "in.csv")
    write_recording(src, Recording.from_dps(np.random.default_rng(0).normal(size=(600, 3)) * 0.05, 100.0))
    assert main(["replay", src, "--out", str(tmp_path / "newdir") + "/"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "newdir/: ends in /, so it names a folder" in err[0], err
    assert sorted(os.listdir(tmp_path)) == ["in.csv"]


def test_an_output_named_dot_in_a_folder_that_does_not_exist_is_refused_before_any_work(tmp_path, capsys):
    """Attack pass 30b: ``--out newdir/.`` (no ``newdir``) was refused only after the work, as a
    file that "appeared or changed while this command ran (rerun with --force ...)", --force given
    or not (the folder made for it, the file then not linked there): a name ending in ``/.`` names a
    folder as one ending in ``/`` does (``newdir/..`` was refused before the work already)."""
    from gyrofilter.cli import main

    src = str(tmp_path / "in.csv")
    write_recording(src, Recording.from_dps(np.random.default_rng(0).normal(size=(600, 3)) * 0.05, 100.0))
    assert main(["replay", src, "--out", os.path.join(tmp_path, "newdir", "."), "--force"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "newdir/.: ends in /., so it names a folder" in err[0], err
    assert sorted(os.listdir(tmp_path)) == ["in.csv"]


def test_an_output_past_a_missing_folder_and_dotdot_is_refused_before_any_work(tmp_path, monkeypatch, capsys):
    """``--json rel/../rel2/x.json`` with no ``rel``: the check read the path as written without
    ``rel/..`` (it passed), the system does not (the analysis ran, then "No such file or directory")."""
    from gyrofilter.cli import main
    from gyrofilter.recording import Recording, read_recording, write_recording

    monkeypatch.chdir(tmp_path)
    write_recording("in.csv", Recording.from_dps(np.random.default_rng(0).normal(size=(600, 3)) * 0.05, 100.0))
    out = os.path.join("rel", "..", "rel2", "x.json")
    assert main(["gap", "in.csv", "--json", out, "--sims", "10"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"gyrofilter: error: {out}: the folder rel does not exist, so rel/.. does not name a folder"], err
    assert sorted(os.listdir(tmp_path)) == ["in.csv"]
    os.mkdir("rel")
    outputs.check_outputs([out], [])  # with rel there, rel/.. is the folder


@pytest.mark.parametrize("command", ["allan", "record"])
def test_an_output_past_a_link_and_dotdot_lands_where_the_system_puts_it(tmp_path, monkeypatch, capsys, command):
    """``--json link/../x.json`` with ``link`` a symbolic link to a folder on another file system:
    the system reads it as the link target's parent; the temporary file was made in the folder
    the path names without ``link/..`` (``abspath``), so the rename crossed file systems and failed
    after the work ("Invalid cross-device link"). It now lands in the target's parent, whole, and
    no temporary file stays anywhere. (/dev/shm is another file system than the test's folder on
    most Linux machines; skipped where it is not.)"""
    from gyrofilter.cli import main

    if not os.path.isdir("/dev/shm") or os.stat("/dev/shm").st_dev == os.stat(tmp_path).st_dev:
        pytest.skip("needs /dev/shm on a file system of its own")
    import tempfile
    with tempfile.TemporaryDirectory(dir="/dev/shm") as other:
        os.mkdir(os.path.join(other, "target"))
        os.symlink(os.path.join(other, "target"), tmp_path / "link")
        monkeypatch.chdir(tmp_path)
        out = os.path.join("link", "..", "x.json" if command == "allan" else "x.csv")
        args = (["allan", str(RECORDINGS / "mpu6050_static_100s.csv.gz"), "--json", out] if command == "allan" else
                ["record", "--source", "sim:seed=1,realtime=0,duration=1", "--out", out])
        assert main(args) == 0, capsys.readouterr().err
        landed = os.path.join(other, os.path.basename(out))
        if command == "allan":
            assert _strict(open(landed).read())["axes"]
        else:
            from gyrofilter.recording import read_recording
            assert len(read_recording(landed)) == 100
        assert sorted(os.listdir(other)) == sorted(["target", os.path.basename(out)]) and os.listdir(tmp_path) == ["link"]


def _read_only_folder(tmp_path, monkeypatch):
    """A folder this process cannot write: mode 0o555, and for root (whom the mode does not stop)
    ``os.access`` answering as the kernel would for any other user."""
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    if os.geteuid() == 0:
        real = os.access
        monkeypatch.setattr(os, "access", lambda p, mode, **kw: False if os.path.abspath(p) == str(folder)
                            and mode & os.W_OK else real(p, mode, **kw))
    return folder


@pytest.mark.parametrize("command", ["gap", "report", "simulate"])
def test_an_output_in_a_folder_that_cannot_be_written_is_refused_before_any_work(tmp_path, monkeypatch, capsys, command):
    """``gap`` ran its whole analysis before finding that --json could not be written (the
    hostile pass of issue 24); every command now refuses such an output first, naming it."""
    from gyrofilter.cli import main
    from gyrofilter.recording import Recording, read_recording, write_recording

    folder = _read_only_folder(tmp_path, monkeypatch)
    src = str(tmp_path / "in.csv")
    write_recording(src, Recording.from_dps(np.random.default_rng(0).normal(size=(600, 3)) * 0.05, 100.0))
    out = str(folder / "sub" / "out.json")
    argv = {"gap": ["gap", src, "--json", out],
            "report": ["report", src, "--out", out],
            "simulate": ["simulate", "--model", str(DEFAULT_MODEL_PATH), "--duration", "1", "--out", out]}[command]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0] == f"gyrofilter: error: {out}: the folder {folder} is not writable", err
    assert os.listdir(folder) == []
    folder.chmod(0o755)


def test_replacing_makes_missing_folders_and_removes_them_on_failure(tmp_path):
    target = tmp_path / "a" / "b" / "out.json"
    with pytest.raises(RuntimeError), outputs.replacing(str(target)) as tmp:
        assert os.path.basename(tmp).endswith("-out.json") and os.path.isdir(tmp_path / "a" / "b")
        open(tmp, "w").write("half")
        raise RuntimeError("failed")
    assert os.listdir(tmp_path) == []
    with outputs.replacing(str(target)) as tmp:
        open(tmp, "w").write("whole")
    assert target.read_text() == "whole" and os.listdir(target.parent) == ["out.json"]


def test_an_error_writing_the_temporary_file_names_the_users_path(tmp_path):
    """The user gave ``out.csv``; an OSError on the hidden temporary file must name ``out.csv``."""
    path = str(tmp_path / "out.csv")
    with pytest.raises(OSError) as err:
        with outputs.replacing(path) as tmp:
            open(os.path.join(tmp, "cannot", "exist"), "w")  # tmp is a file path: ENOTDIR / ENOENT
    assert err.value.filename == os.path.join(path, "cannot", "exist")
    assert ".partial-" not in str(err.value)
    folder = str(tmp_path / "rep")
    with pytest.raises(OSError) as err:
        with outputs.replacing_in(folder) as tmp:
            open(os.path.join(tmp, "no", "fig.png"), "w")
    assert err.value.filename == os.path.join(folder, "no", "fig.png")


def test_a_writers_refusal_inside_replacing_names_the_users_path_in_the_same_class(tmp_path):
    """A recording writer refusing a value named ``.partial-PID-out.csv`` (issue 22, hostile 5-1)."""
    from gyrofilter.errors import RecordingError
    from gyrofilter.recording import Recording, read_recording, write_recording

    for path, opened in ((str(tmp_path / "out.csv"), outputs.replacing), (str(tmp_path / "rep"), outputs.replacing_in)):
        rec = Recording.from_dps(np.array([[0.0, 0.0, 0.0], [2e5, 0.0, 0.0]]), 100.0)
        with pytest.raises(RecordingError) as err:
            with opened(path) as tmp:
                write_recording(tmp if opened is outputs.replacing else os.path.join(tmp, "a.csv"), rec)
        assert ".partial-" not in str(err.value)
        assert str(err.value).startswith(path if opened is outputs.replacing else os.path.join(path, "a.csv"))
        assert not os.path.exists(path)


# ------------------------------------------------------------------------------ only regular files are replaced


def _special_file(tmp_path, kind):
    """A path in ``tmp_path`` that exists as ``kind``, something other than a regular file."""
    path = tmp_path / f"{kind}.csv"
    if kind == "symlink":
        (tmp_path / "target.csv").write_text("the link's target")
        path.symlink_to(tmp_path / "target.csv")
    elif kind == "dangling symlink":
        path.symlink_to(tmp_path / "nowhere.csv")
    elif kind == "FIFO":
        os.mkfifo(path)
    else:  # a copy of /dev/null, char device 1, 3
        if os.geteuid() != 0:
            pytest.skip("making a device node needs root")
        try:
            os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 3))
        except PermissionError:
            pytest.skip("making a device node needs CAP_MKNOD")
    return path


SPECIAL = ["symlink", "dangling symlink", "FIFO", "device"]


@pytest.mark.parametrize("force", [False, True])
@pytest.mark.parametrize("kind", SPECIAL)
def test_check_outputs_replaces_only_regular_files(tmp_path, kind, force):
    """Issue 22 (23): --force replaced symlinks and device nodes (as root, --out /dev/null --force
    made /dev/null a regular file)."""
    path = _special_file(tmp_path, kind)
    expected = "is a symbolic link" if "symlink" in kind else "is not a regular file (a device, FIFO or socket)"
    with pytest.raises(SettingsError) as info:
        outputs.check_outputs([str(path)], force=force)
    assert str(info.value).startswith(f"{path}: {expected}; outputs replace only regular files")


@pytest.mark.parametrize("kind", SPECIAL)
def test_no_command_replaces_a_symlink_a_fifo_or_a_device(tmp_path, capsys, kind):
    from gyrofilter.cli import main

    path = _special_file(tmp_path, kind)
    model = str(DEFAULT_MODEL_PATH)
    for argv in (["simulate", "--model", model, "--duration", "1", "--out", str(path), "--force"],
                 ["record", "--source", "sim:realtime=0,duration=1", "--out", str(path), "--force"],
                 ["run", "--source", "sim:realtime=0,duration=3", "--out", str(path), "--force", "--quiet"]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith(f"gyrofilter: error: {path}: is "), err
    assert not stat.S_ISREG(os.lstat(path).st_mode)
    if kind == "symlink":
        assert (tmp_path / "target.csv").read_text() == "the link's target"


# ------------------------------------------------------------------------------ stale partial files


def _dead_pid():
    """The pid of a process that has ended (and been reaped)."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _stale(path, age_s=outputs.STALE_AFTER_S + 60):
    """Make ``path`` look untouched for ``age_s`` seconds."""
    old = time.time() - age_s
    os.utime(path, (old, old))
    return path


def test_stale_partials_of_dead_processes_go_at_the_next_write_to_their_folder(tmp_path):
    """Issue 22 (26): a SIGKILL left .partial-PID-* files that nothing removed. Only this host's,
    of a dead process, untouched for STALE_AFTER_S, go: a shared folder holds other machines'."""
    dead, host = _dead_pid(), files.HOST
    stale_file = tmp_path / f".partial-{dead}.{host}-old.csv"
    stale_file.write_text("half")
    stale_folder = tmp_path / f".partial-{dead}.{host}-k3j4h5g6"  # what replacing_in makes
    stale_folder.mkdir()
    (stale_folder / "fig.png").write_text("half")
    _stale(stale_file), _stale(stale_folder)
    kept = [tmp_path / f".partial-{os.getpid()}.{host}-mine.csv",  # this process: alive
            tmp_path / f".partial-1.{host}-init.csv",  # pid 1 runs
            tmp_path / f".partial-0.{host}-group.csv",  # 0 is no process of its own
            tmp_path / f".partial-{dead}.another_host-theirs.csv",  # another machine's (NFS): its pid means nothing here
            tmp_path / f".partial-{dead}-old_style.csv",  # no host: not the pattern
            tmp_path / f".partial-{dead}x.{host}-other.csv", tmp_path / f"partial-{dead}.{host}-other.csv",
            tmp_path / f".partial-{dead}.{host}-"]
    for path in kept:
        path.write_text("not mine to remove")
        _stale(path)
    recent = tmp_path / f".partial-{dead}.{host}-recent.csv"  # a pid namespace's live writer looks dead: too fresh
    recent.write_text("not mine to remove")
    kept.append(recent)
    with outputs.replacing(str(tmp_path / "new.json")) as tmp:
        open(tmp, "w").write("{}")
    assert not stale_file.exists() and not stale_folder.exists()
    assert all(path.read_text() == "not mine to remove" for path in kept)
    assert (tmp_path / "new.json").read_text() == "{}"


@pytest.mark.parametrize("command", ["record", "simulate"])
def test_a_command_writing_to_a_folder_removes_its_stale_partials(tmp_path, command):
    from gyrofilter.cli import main

    stale = tmp_path / f".partial-{_dead_pid()}.{files.HOST}-killed.csv"
    stale.write_text("# gyrofilter-recording: 1\n")
    _stale(stale)
    model = str(DEFAULT_MODEL_PATH)
    argv = {"record": ["record", "--source", "sim:realtime=0,duration=1", "--out", str(tmp_path / "out.csv")],
            "simulate": ["simulate", "--model", model, "--duration", "1", "--out", str(tmp_path / "out.csv")]}[command]
    assert main(argv) == 0
    assert sorted(os.listdir(tmp_path)) == ["out.csv"]


def test_an_output_that_appears_while_the_command_runs_is_not_replaced(tmp_path):
    """The no-overwrite check ran only before the work: a file made at the output's name meanwhile
    (two record runs, the user) was silently replaced when the output landed."""
    out = tmp_path / "out.json"
    outputs.check_outputs([str(out)])
    with pytest.raises(FileExistsError, match="appeared or changed while this command ran"):
        with outputs.replacing(str(out)) as tmp:
            open(tmp, "w").write("mine")
            out.write_text("theirs")  # appears meanwhile
    assert out.read_text() == "theirs" and os.listdir(tmp_path) == ["out.json"]
    outputs.check_outputs([str(out)], force=True)  # --force replaces the file it was shown, not another
    with outputs.replacing(str(out)) as tmp:
        open(tmp, "w").write("mine")
    assert out.read_text() == "mine"
    outputs.check_outputs([str(out)], force=True)
    with pytest.raises(FileExistsError, match="appeared or changed while this command ran"):
        with outputs.replacing(str(out)) as tmp:
            open(tmp, "w").write("third")
            os.unlink(out)
            out.write_text("theirs again")  # another file at the name: not the one --force was given for
    assert out.read_text() == "theirs again"


def test_force_keeps_the_permissions_of_the_file_it_replaces(tmp_path, capsys):
    """Attack pass 20: `replay --out private.csv --force` over a file kept private (mode 0600)
    left one every user could read (0644: the temporary file's mode under the umask took its
    place); the output now keeps the replaced file's permission bits, as `sed -i` does."""
    from gyrofilter.cli import main

    out, cal = tmp_path / "private.csv", tmp_path / "private.json"
    for path in (out, cal):
        path.write_text("old")
        path.chmod(0o600)
    rec = str(RECORDINGS / "mpu6050_static_100s.csv.gz")
    assert main(["replay", rec, "--out", str(out), "--save-calibration", str(cal), "--force"]) == 0
    for path in (out, cal):
        assert stat.S_IMODE(path.stat().st_mode) == 0o600 and path.read_text() != "old"
    new = tmp_path / "new.csv"
    assert main(["replay", rec, "--out", str(new)]) == 0  # a new file: the umask's mode, as before
    assert stat.S_IMODE(new.stat().st_mode) == 0o666 & ~_umask()


def test_the_successor_of_a_private_file_is_private_while_it_is_written(tmp_path, monkeypatch):
    """Attack pass 20's notes: the temporary file (``.partial-*``) that replaces a file of mode
    0600 was made with the umask's mode (0644): readable by every user for as long as the command
    wrote it (minutes of `record`); commit gave it the mode only at the end. It is now made with
    the replaced file's mode before a byte is written: by `replacing` and by the live writers."""
    from gyrofilter.cli import live, main

    out = tmp_path / "private.csv"
    out.write_text("old")
    out.chmod(0o600)
    outputs.check_outputs([str(out)], force=True)
    with outputs.replacing(str(out)) as tmp:
        assert stat.S_IMODE(os.stat(tmp).st_mode) == 0o600
        with open(tmp, "w") as fh:
            fh.write("new")
    assert out.read_text() == "new" and stat.S_IMODE(out.stat().st_mode) == 0o600
    seen = []
    real = live.RecordingWriter

    def spying(path, *args, **kwargs):
        writer = real(path, *args, **kwargs)
        seen.append(stat.S_IMODE(os.stat(path).st_mode))
        return writer

    monkeypatch.setattr(live, "RecordingWriter", spying)
    rec = str(RECORDINGS / "mpu6050_static_100s.csv.gz")
    assert main(["record", "--source", f"replay:{rec}", "--duration", "1", "--out", str(out), "--force"]) == 0
    assert seen == [0o600] and stat.S_IMODE(out.stat().st_mode) == 0o600


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_a_file_name_that_is_not_utf8_is_written_escaped_in_every_output(tmp_path, monkeypatch):
    """The name in a header value, a JSON document, a Kalibr file and the fleet table crashed
    after all the work ("'utf-8' codec can't encode character '\\udcff'"): it is written escaped,
    \\udcff, as the control characters are, and reads back as written. (The summaries on stdout
    print the name too: stdout here escapes what it cannot encode, as stderr always does.)"""
    import io

    from gyrofilter.cli import main
    from gyrofilter.recording import read_recording

    monkeypatch.setattr(sys, "stdout", io.TextIOWrapper(io.BytesIO(), encoding="utf-8", errors="backslashreplace"))
    src = file_named_by_bytes(tmp_path)
    escaped = src.replace("\udcff", "\\udcff")
    out = tmp_path / "out.csv"
    assert main(["replay", src, "--out", str(out)]) == 0
    assert read_recording(out).header["filtered_from"] == escaped
    assert main(["allan", src, "--json", str(tmp_path / "a.json")]) == 0
    assert json.loads((tmp_path / "a.json").read_text(encoding="utf-8"))["recording"] == escaped
    other = file_named_by_bytes(tmp_path, b"plain.csv")
    assert main(["allan", src, other, "--fleet", str(tmp_path / "fleet"), "--jobs", "1"]) == 0
    table = (tmp_path / "fleet" / "fleet.csv").read_text(encoding="utf-8").splitlines()
    assert len(table) == 7 and table[1].startswith("\\udcff,") and f",{escaped}," in table[1]
    assert f'# recording: "{escaped}"' in (tmp_path / "fleet" / "\udcff.imu.yaml").read_text(encoding="utf-8")
    assert "| \\\\udcff | x |" in (tmp_path / "fleet" / "fleet.md").read_text(encoding="utf-8")  # shown: \\udcff


def test_utf8_text_escapes_lone_surrogates_only():
    from gyrofilter.units import json_ready, utf8_text

    assert utf8_text("b\udcffc\ud800.csv") == "b\\udcffc\\ud800.csv"
    assert utf8_text("ü ✓ \\udcff") == "ü ✓ \\udcff"  # any other text unchanged
    assert json_ready({"\udcff": ["\udcfe", 1.0]}) == {"\\udcff": ["\\udcfe", 1.0]}


def test_outputs_land_together_or_none_when_one_name_was_taken_meanwhile(tmp_path):
    """gap --json --report and replay --out --plot --save-calibration landed the outputs committed
    before the one whose name another file had taken meanwhile, then exited 2."""
    import contextlib

    a, b = tmp_path / "a.json", tmp_path / "b.json"
    outputs.check_outputs([str(a), str(b)])
    with pytest.raises(FileExistsError, match="appeared or changed while this command ran"):
        with contextlib.ExitStack() as files:
            for path in (a, b):  # b lands first (an ExitStack exits in reverse)
                open(files.enter_context(outputs.replacing(str(path))), "w").write("mine")
            a.write_text("theirs")  # the name of the one that would land last is taken
    assert a.read_text() == "theirs" and not b.exists()
    assert sorted(os.listdir(tmp_path)) == ["a.json"]


def test_a_write_that_fails_names_the_file_and_says_it_was_not_written(tmp_path):
    """Issue 37 (9): under a file size limit (a full disk alike) every command that writes a whole
    file says "FILE: File too large; not written" (docs/formats.md section 8), leaves nothing behind
    (it said "[Errno 27] File too large", no file named)."""
    rec = tmp_path / "in.csv"
    write_recording(rec, Recording.from_dps(np.random.default_rng(37).normal(0, 0.05, (3000, 3)), 100.0))
    out = tmp_path / "out"
    commands = {"sim.csv": ["simulate", "--model", str(DEFAULT_MODEL_PATH), "--duration", "30", "--seed", "1"],
                "replay.csv": ["replay", str(rec)],
                "allan.json": ["allan", str(rec), "--json"],
                "kalibr.yaml": ["allan", str(rec), "--kalibr"],
                "report.html": ["report", str(rec), "--sims", "10"]}
    argvs = [argv + ([] if argv[-1].startswith("--") else ["--out"]) + [str(out / name)] for name, argv in commands.items()]
    proc = subprocess.run([sys.executable, "-c", UNDER_A_SIZE_LIMIT, "200", json.dumps(argvs)],
                          capture_output=True, text=True, timeout=120, cwd=REPO)
    assert [line for line in proc.stdout.splitlines() if line.startswith("exit")] == ["exit 2"] * len(commands)
    lines = [line for line in proc.stderr.splitlines() if not line.startswith(("gyrofilter: warning", "  "))]  # a warning's lines
    assert lines == [f"gyrofilter: error: {out / name}: File too large; not written" for name in commands], proc.stderr
    assert not out.exists()


def test_convert_and_arma_under_a_size_limit_say_what_was_not_written(tmp_path):
    """Attack pass (issue 37, fresh case of 9): the commands the first test leaves out, convert
    (a gzip recording: the limit is met inside the compressor) and arma --json."""
    log = tmp_path / "log.csv"
    log.write_text("t,gx_dps,gy_dps,gz_dps\n" + "".join(f"{i * 0.01:.2f},{(i * 7919) % 13 * 0.01:.2f},0.2,0.3\n"
                                                          for i in range(40000)))
    rec = tmp_path / "in.csv"
    write_recording(rec, Recording.from_dps(np.random.default_rng(38).normal(0, 0.05, (3000, 3)), 100.0))
    out = tmp_path / "out"
    argvs = [["convert", str(log), "--out", str(out / "c.csv.gz")], ["convert", str(log), "--out", str(out / "c.csv")],
             ["arma", str(rec), "--axis", "x", "--max-n", "1", "--json", str(out / "a.json")]]
    proc = subprocess.run([sys.executable, "-c", UNDER_A_SIZE_LIMIT, "100", json.dumps(argvs)],
                          capture_output=True, text=True, timeout=120, cwd=REPO)
    assert [line for line in proc.stdout.splitlines() if line.startswith("exit")] == ["exit 2"] * 3, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.startswith("gyrofilter: error")]
    assert lines == [f"gyrofilter: error: {out / name}: File too large; not written" for name in ("c.csv.gz", "c.csv", "a.json")]
    assert not out.exists()


def test_a_figure_that_fails_names_the_figure_not_its_folder(tmp_path):
    """Issue 37 (attack): ``gap --report DIR`` under a file size limit said "DIR: File too large;
    not written": the image writer raises without a file name (and removes what it wrote), so the
    folder was named. Now the figure is, as ``allan --plot`` names its file; nothing is left behind."""
    rec = tmp_path / "in.csv"
    write_recording(rec, Recording.from_dps(np.random.default_rng(37).normal(0, 0.05, (3000, 3)), 100.0))
    out = tmp_path / "out"
    argvs = [["gap", str(rec), "--sims", "10", "--bootstrap", "0", "--report", str(out / "rep")],
             ["gap", str(rec), "--sims", "10", "--bootstrap", "0", "--report", str(out / "rep") + os.sep],  # pass 48: rep//adev_x.png
             ["allan", str(rec), "--plot", str(out / "allan.png")]]
    proc = subprocess.run([sys.executable, "-c", UNDER_A_SIZE_LIMIT, "2000", json.dumps(argvs)],
                          capture_output=True, text=True, timeout=120, cwd=REPO)
    assert [line for line in proc.stdout.splitlines() if line.startswith("exit")] == ["exit 2"] * 3
    lines = [line for line in proc.stderr.splitlines() if not line.startswith(("gyrofilter: warning", "  "))]  # a warning's lines
    assert lines == [f"gyrofilter: error: {out / 'rep' / 'adev_x.png'}: File too large; not written"] * 2 + [
                     f"gyrofilter: error: {out / 'allan.png'}: File too large; not written"], proc.stderr
    assert not out.exists()


@pytest.mark.parametrize("out", [os.path.join("d", "x.csv"), os.path.join("d", "sub", "x.csv")])
def test_an_output_below_a_symbolic_link_to_a_missing_place_is_refused_not_made(tmp_path, monkeypatch, capsys, out):
    """Issue 37 (attack 3): with ``d -> nowhere``, ``simulate --out d/x.csv`` made ``./nowhere/``
    (the folder was resolved, then made) and wrote there. One line names the link; nothing is made."""
    from gyrofilter.cli import main

    os.symlink("nowhere", tmp_path / "d")
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "--model", str(DEFAULT_MODEL_PATH), "--duration", "1", "--out", out]) == 2
    assert capsys.readouterr().err == (f"gyrofilter: error: {out}: d is a symbolic link that leads to no folder "
                                       "(No such file or directory)\n")
    assert os.listdir(tmp_path) == ["d"]


def test_two_long_names_that_differ_where_the_partial_cuts_have_two_partials(tmp_path, monkeypatch, capsys):
    """Attack pass 24: two outputs of one command whose long names (240 bytes) differ only in the
    middle that a partial's name leaves out shared one partial: `replay --out A --save-calibration B`
    wrote both into it, B took it and A failed ("No such file or directory; not written"), exit 2
    with B landed alone (had A been renamed first, it would have held B's text)."""
    from gyrofilter.cli import main

    names = [("a" * 222 + digit + "a" * 17 + ".csv") for digit in "12"]
    assert outputs.partial_path(str(tmp_path / names[0])) != outputs.partial_path(str(tmp_path / names[1]))
    monkeypatch.chdir(tmp_path)
    write_recording("in.csv", Recording.from_dps(np.random.default_rng(1).normal(0, 0.05, (300, 3)), 100.0))
    assert main(["replay", "in.csv", "--out", names[0], "--save-calibration", names[1]]) == 0
    assert read_recording(tmp_path / names[0]).header["filtered_from"] == "in.csv"
    assert json.loads((tmp_path / names[1]).read_text())["gyrofilter-calibration"] == 1


@pytest.mark.parametrize("name", ["y" * 236 + ".csv.gz", "é" * 118 + ".json"])  # 243 and 241 bytes: legal names
def test_a_long_legal_name_is_written_and_one_too_long_is_refused_before_any_work(tmp_path, capsys, name):
    """Issue 37 (attack 6): a legal output name of 240 bytes failed every command after its work
    (``gap --json``: "/dir/.partial-PID.HOST-yyy...: File name too long", the hidden partial
    named): the partial's prefix took it past the 255 bytes a name may have, and the cleanup's
    own error hid the translated one. The partial's name now keeps the end (the extension) and
    fits; a name past 255 bytes is refused by the option, before any work."""
    from gyrofilter.cli import main
    out = tmp_path / name
    assert len(outputs.partial_path(str(out)).rsplit("/", 1)[1].encode()) <= outputs.NAME_MAX_BYTES
    assert outputs.partial_path(str(out)).endswith(name[-16:])
    if name.endswith(".json"):
        with outputs.replacing(str(out)) as tmp:
            outputs.write_json(tmp, {"a": 1})
        assert json.loads(out.read_text()) == {"a": 1}
    else:
        assert main(["simulate", "--model", str(DEFAULT_MODEL_PATH), "--duration", "1", "--seed", "1",
                     "--out", str(out)]) == 0
        assert len(read_recording(out)) == 100
    too_long = str(tmp_path / ("x" * 300 + ".json"))
    with pytest.raises(SystemExit) as exit_info:
        main(["gap", str(out), "--json", too_long])
    assert exit_info.value.code == 2
    assert "argument --json: a name longer than 255 bytes" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


@pytest.mark.parametrize("argv", [["replay", "{src}", "--out", "-"], ["allan", "{src}", "--json", "-"],
                                  ["simulate", "--model", str(DEFAULT_MODEL_PATH), "--duration", "1", "--out", "-"],
                                  ["gap", "{src}", "--report", "-"]])
def test_dash_as_an_output_is_refused_not_written_as_a_file_named_dash(tmp_path, monkeypatch, capsys, argv):
    """``--out -`` is the standard output in ``run`` and ``-`` the standard input of ``convert``; every
    other command wrote a file named ``-`` and said "wrote -" (attack pass 10)."""
    from gyrofilter.cli import main

    src = str(tmp_path / "in.csv")
    write_recording(src, Recording.from_dps(np.random.default_rng(0).normal(size=(600, 3)) * 0.05, 100.0))
    monkeypatch.chdir(tmp_path)
    assert main([a.format(src=src) for a in argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "outputs are files, not the standard output" in err[0], err
    assert sorted(os.listdir(tmp_path)) == ["in.csv"]


def test_a_failed_command_leaves_the_files_another_wrote_meanwhile_in_the_folder_it_made(tmp_path):
    """Two ``gap --report rep`` at once: the one that failed (the other's files had appeared) removed
    the folder it had made with the other's whole report, which had said "wrote rep/gap_report.md"
    (attack pass 10). A failure removes its own files and then the folders it made only while empty."""
    folder = tmp_path / "made" / "rep"
    with pytest.raises(RuntimeError), outputs.replacing_in(str(folder)) as tmp:
        (folder / "gap_report.md").write_text("the other command's report")  # lands while this one runs
        (open(os.path.join(tmp, "adev_x.png"), "w")).write("mine")
        raise RuntimeError("failed")
    assert sorted(os.listdir(folder)) == ["gap_report.md"]
    with pytest.raises(RuntimeError), outputs.replacing(str(tmp_path / "new" / "a.json")) as tmp:
        (tmp_path / "new" / "b.json").write_text("another command's")
        open(tmp, "w").write("mine")
        raise RuntimeError("failed")
    assert sorted(os.listdir(tmp_path / "new")) == ["b.json"]
    with pytest.raises(RuntimeError), outputs.replacing(str(tmp_path / "gone" / "deeper" / "a.json")) as tmp:
        open(tmp, "w").write("mine")
        raise RuntimeError("failed")
    assert not (tmp_path / "gone").exists()  # what it made, empty again, goes


def test_files_of_a_folder_output_land_all_or_none_when_a_commit_fails_midway(tmp_path, monkeypatch):
    """A file that appears between the check of all and the landing of the third: the two that
    landed go again (none of them, as the contract says), the other command's file stays."""
    folder = tmp_path / "rep"
    real_commit = outputs.commit

    def commit(tmp, path):
        if path.endswith("c.png"):
            (folder / "c.png").write_text("another command's")
        return real_commit(tmp, path)

    monkeypatch.setattr(outputs, "commit", commit)
    with pytest.raises(FileExistsError), outputs.replacing_in(str(folder)) as tmp:
        for name in "abc":
            open(os.path.join(tmp, f"{name}.png"), "w").write("mine")
    assert sorted(os.listdir(folder)) == ["c.png"] and (folder / "c.png").read_text() == "another command's"


def test_a_gzip_output_stores_no_name_of_its_partial(tmp_path, capsys):
    """gzip's header held the partial's name (``.partial-PID.HOST-a.csv``): ``gunzip -N`` made a
    hidden file of another name, the host and process were written into the data, and two runs
    of one seed differed by bytes (mtime is 0 for that). No name is stored (as ``gzip -n``)."""
    from gyrofilter.cli import main
    out = tmp_path / "a.csv.gz"
    assert main(["simulate", "--model", str(DEFAULT_MODEL_PATH), "--duration", "0.5", "--seed", "1",
                 "--out", str(out)]) == 0
    head = out.read_bytes()[:10]
    assert head[:2] == b"\x1f\x8b" and head[3] & 0x08 == 0  # FLG.FNAME unset


def test_gap_report_force_removes_the_figures_of_an_earlier_run_it_does_not_draw(tmp_path, capsys):
    """Attack pass 37i (issue 37): ``gap A --report rep`` (A with a temperature column: three
    temperature_*.png), then ``gap B --report rep --force`` (B without one) left A's temperature
    figures beside B's report, as if they were B's (the fleet removes an earlier run's reports it
    does not write; a single report folder kept them). Now the folder holds this run's files only;
    a file of no name the report writes stays."""
    from gyrofilter.cli import main
    from gyrofilter.analysis.gap import report as gap_report

    rec = tmp_path / "b.csv"
    write_recording(rec, Recording.from_dps(np.random.default_rng(37).normal(0, 0.05, (3000, 3)), 100.0))
    rep = tmp_path / "rep"
    rep.mkdir()
    for name in gap_report.report_file_names() + ["mine.txt"]:  # an earlier run's files, and the user's
        (rep / name).write_text("earlier")
    assert main(["gap", str(rec), "--sims", "10", "--bootstrap", "0", "--report", str(rep), "--force"]) == 0
    capsys.readouterr()
    left = sorted(os.listdir(rep))
    assert "mine.txt" in left and not any(name.startswith("temperature_") for name in left)
    assert all((rep / name).read_text(errors="replace") != "earlier" for name in left if name != "mine.txt")
