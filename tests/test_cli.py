"""cli (the ``gyrofilter`` command): one-line refusals of unknown options with the closest
option, and output that survives a file name that is not UTF-8."""
import json
import os
import re
import subprocess
import sys

import pytest

from gyrofilter.recording import read_recording
from support import REPO, file_named_by_bytes, lsb_recording


@pytest.mark.parametrize("argv, prog, said", [
    (["replay", "REC", "--ot", "x.csv"], "gyrofilter replay", "unrecognized arguments: --ot x.csv; did you mean --out?"),
    (["allan", "REC", "--jsno=a.json"], "gyrofilter allan", "unrecognized arguments: --jsno=a.json; did you mean --json?"),
    (["replay", "REC", "--sample-rat", "3", "--outt", "x"], "gyrofilter replay", "; did you mean --out?"),
    (["replay", "REC", "-q"], "gyrofilter replay", "unrecognized arguments: -q"),
    (["--bogus"], "gyrofilter", "unrecognized arguments: --bogus"),
    (["replya"], "gyrofilter", "unknown command 'replya'; did you mean replay?; the commands: replay, record,"),
    (["--version", "convret", "x"], "gyrofilter", "unknown command 'convret'; did you mean convert?"),
    (["frobnicate"], "gyrofilter", "unknown command 'frobnicate'; the commands: replay,"),
    (["simulate", "--duration", "x"], "gyrofilter simulate", "argument --duration: must be a plain decimal number"),
])
def test_an_unknown_option_gets_its_commands_usage_and_the_closest_option(argv, prog, said, capsys):
    """Issue 23: a mistyped option of a command printed the top-level usage with no hint; issue
    22: every refusal is one line (argparse printed its usage text first), pointing at --help."""
    from gyrofilter.cli import main

    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("gyrofilter: error: ") and said in err  # one prefix (attack pass 8)
    assert err.rstrip().endswith(f"(see {prog} --help)")
    assert ("did you mean" in err) == ("did you mean" in said)


@pytest.mark.parametrize("argv", [
    ["simulate", "--model", "m.json", "--duration", "1", "--out", "o.csv", "--rate", "250"],
    ["simulate", "--model", "m.json", "--duration", "1", "--out", "o.csv", "--rate=250"],
    ["record", "--source", "sim", "--out", "o.csv", "--sample-rate", "250"],
    ["run", "--source", "sim", "--sample-rate=250"],
    ["run", "--source", "sim", "--sample-rate-h", "250"],  # an option is never taken by a prefix of it
])
def test_a_removed_spelling_of_the_sample_rate_is_refused_naming_the_one_spelling(argv, capsys):
    """Issue 23: --rate and --sample-rate, aliases of --sample-rate-hz until 0.2.0, are refused in
    one line that names the one spelling (--sample-rate would have passed as its abbreviation)."""
    from gyrofilter.cli import main

    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    typed = " ".join(argv[argv.index(next(a for a in argv if "rate" in a)):])
    assert err == (f"gyrofilter: error: unrecognized arguments: {typed}; did you mean --sample-rate-hz? "
                   f"(see gyrofilter {argv[0]} --help)\n")


def test_did_you_mean_takes_the_closest_option_or_one_whose_words_hold_the_typed_ones():
    from gyrofilter.cli import build_parser, did_you_mean

    simulate = build_parser("simulate").commands["simulate"]
    assert did_you_mean(simulate, ["--rate", "5"]) == "; did you mean --sample-rate-hz?"
    assert did_you_mean(simulate, ["--sed", "5"]) == "; did you mean --seed?"
    assert did_you_mean(simulate, ["--hz"]) == "; did you mean --sample-rate-hz?"
    assert did_you_mean(simulate, ["--bogus", "-q", "5", "--"]) == ""
    gap = build_parser("gap").commands["gap"]
    assert did_you_mean(gap, ["--rate"]) == ""  # no option of gap has the word


def test_a_summary_naming_a_file_that_is_not_utf8_prints_under_a_utf8_locale(tmp_path):
    """Under a UTF-8 locale (a Pi's en_GB.UTF-8) stdout is strict: the summary's file name, with
    the lone surrogate os.fsdecode makes of byte 0xff, crashed after the work was done."""
    path = file_named_by_bytes(tmp_path)
    env = {**os.environ, "LC_ALL": "C.UTF-8", "PYTHONIOENCODING": ""}
    proc = subprocess.run([sys.executable, "-m", "gyrofilter", "replay", os.fsencode(path)], capture_output=True, env=env)
    assert proc.returncode == 0, proc.stderr
    assert b"\\udcff.csv" in proc.stdout + proc.stderr and b"Traceback" not in proc.stderr


def test_help_does_not_import_device_libraries():
    code = (
        "import sys\n"
        "from gyrofilter.cli import main\n"
        "for argv in (['--help'], ['record', '--help'], ['run', '--help']):\n"
        "    try:\n"
        "        main(argv)\n"
        "    except SystemExit:\n"
        "        pass\n"
        "bad = [m for m in ('serial', 'smbus2') if m in sys.modules]\n"
        "print('IMPORTED', bad)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert "IMPORTED []" in out.stdout, out.stdout + out.stderr
    assert "serial:/dev/ttyUSB0" in out.stdout  # the SOURCE syntax is in --help


def test_version_prints_the_package_version(capsys):
    """`gyrofilter --version` (a new user's first question about a bug report): the version of
    gyrofilter.__version__, the one home the package metadata also takes it from."""
    import gyrofilter
    from gyrofilter.cli import main

    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out == f"gyrofilter {gyrofilter.__version__}\n"


def test_a_mistyped_choice_gets_the_closest_one(capsys):
    """The new user's `--preset papr` listed the presets but suggested none."""
    from gyrofilter.cli import main

    with pytest.raises(SystemExit) as stop:
        main(["replay", "--preset", "papr"])
    err = capsys.readouterr().err.strip()
    assert stop.value.code == 2 and len(err.splitlines()) == 1 and "did you mean paper?" in err


#: a file name that would fake an output line and colour the terminal, were it printed as it is
_FAKING = "a\nb\x1b[31m"


def test_file_names_with_control_characters_print_escaped_on_their_own_line(tmp_path, capsys):
    """Issue 37 (attack): `gyrofilter allan "$(printf 'a\\nb.csv')" --json "$(printf 'x\\ny.json')"`
    printed the names as they are: the "recording:" and "wrote" lines broke in two (a faked output
    line) and an ESC sequence coloured the terminal. Every line the commands print goes through one
    rule (gyrofilter.inputs.escape_controls): the names show as repr writes them inside quotes."""
    from gyrofilter.cli import main

    rec = tmp_path / f"{_FAKING}.csv"
    lsb_recording(tmp_path, name=rec.name)
    out_json, out_rec = tmp_path / f"x{_FAKING}.json", tmp_path / f"c{_FAKING}.csv"
    log = tmp_path / f"log{_FAKING}.csv"  # another tool's log (convert refuses a recording)
    log.write_text("time_s,gx,gy,gz\n" + "".join(f"{i / 100:.2f},{i % 5},-3,40\n" for i in range(300)))
    assert main(["allan", str(rec), "--json", str(out_json)]) == 0
    assert main(["convert", str(log), "--out", str(out_rec), "--unit", "lsb", "--lsb-per-dps", "131"]) == 0
    assert main(["convert", str(log), "--out", str(out_rec), "--unit", "lsb", "--lsb-per-dps", "131"]) == 2  # exists
    said = capsys.readouterr()
    text = said.out + said.err
    assert "\x1b" not in text and "b\\x1b[31m" in text
    shown = str(tmp_path) + "/a\\nb\\x1b[31m"
    lines = text.splitlines()
    assert f"recording: {shown}.csv" in lines
    assert f"wrote {tmp_path}/xa\\nb\\x1b[31m.json" in lines
    assert any(line.startswith(f"wrote {tmp_path}/ca\\nb\\x1b[31m.csv: ") for line in lines)
    # a refusal's whitespace is collapsed to one line (errors.one_line), its other controls escaped
    assert f"gyrofilter: error: {tmp_path}/ca b\\x1b[31m.csv: exists (use --force to overwrite)" in lines
    assert not any(line.startswith(("b\x1b", "b\\x1b")) for line in lines)  # no line begins inside a name


def test_a_file_name_that_reverses_the_text_after_it_prints_escaped(tmp_path, capsys):
    """Attack pass 20: a right-to-left override (U+202E) in a file name or a header value went to the
    console and the report as it is, so that ``x\u202egpj.csv`` showed as ``xvsc.jpg`` (Trojan
    Source, CVE-2021-42574); the bidirectional formatting characters are escaped as the other
    controls are (gyrofilter.inputs.BIDI_FORMATTING), in printed lines and in JSON strings."""
    from gyrofilter.cli import main
    from gyrofilter.inputs import BIDI_FORMATTING, escape_controls, json_string

    rec = tmp_path / "x\u202egpj.csv"
    lsb_recording(tmp_path, name=rec.name)
    assert main(["allan", str(rec)]) == 0
    text = capsys.readouterr().out
    assert "\u202e" not in text and f"recording: {tmp_path}/x\\u202egpj.csv" in text.splitlines()
    every = "".join(chr(c) for c in range(0x2000, 0x2100)) + "\u061c"
    for shown in (json_string(every), escape_controls(every)):
        assert not re.search(f"[{BIDI_FORMATTING}]", shown) and json.loads(json_string(every)) == every


def test_a_wrapped_console_line_keeps_a_value_with_its_label(capsys):
    """A new user read "D" at a line's end and its value on the next, and "95" apart from "%"."""
    from gyrofilter.cli import console

    text = ("x" * 88 + " stay below it in 95 % of runs; " + "y" * 90 + " (D of the axis with it instead): D 0.607 and "
            + "z" * 89 + " tau_s = 5.565")
    console.paragraph(text)
    lines = capsys.readouterr().out.splitlines()
    assert not any(line.rstrip().endswith(("95", " D", "=")) for line in lines), lines
    assert " ".join(line.strip() for line in lines) == text


def test_a_warning_is_wrapped_at_the_console_width_and_keeps_a_number_with_its_unit(capsys):
    """A new user read the repeated rows' warning as one line of 426 columns, and "66.7" at a
    line's end with its "s" on the next."""
    from gyrofilter.cli import console

    text = "axis x: B, K, R not resolved: the longest cluster time with 9 clusters is 66.7 s; " + "w " * 120
    console.say_warning(text)
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert captured.out == "" and len(lines) > 1 and max(map(len, lines)) <= console.MAX_LINE_CHARS
    assert lines[0].startswith("gyrofilter: warning: axis x: ") and all(line.startswith("  ") for line in lines[1:])
    assert not any(line.rstrip().endswith("66.7") for line in lines), lines
    assert " ".join(captured.err.split()) == f"gyrofilter: warning: {text}".strip()


@pytest.mark.parametrize("argv, said", [
    (["run", "--source", "sim", "--preset", "paper", "--preset", "hold"], "argument --preset: given twice ('paper', then 'hold')"),
    (["convert", "in.csv", "--out", "a.csv", "--out=b.csv"], "argument --out: given twice ('a.csv', then 'b.csv')"),
    (["gap", "r.csv", "--fleet", "a", "--out-dir", "b"], "argument --out-dir: given twice ('a', then 'b')"),
])
def test_an_option_of_one_value_given_twice_is_refused(argv, said, capsys, tmp_path, monkeypatch):
    """Attack pass 8 (issue 37): argparse kept the last of an option given twice, silently
    (``--out a.csv --out b.csv`` wrote b.csv only, ``--preset paper --preset hold`` ran hold);
    refused as ``--set`` refuses a setting given twice, before any work. An option that may
    repeat (``--set``) and a flag given twice are taken."""
    from gyrofilter.cli import main

    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    assert capsys.readouterr().err == f"gyrofilter: error: {said}; give it once (see gyrofilter {argv[0]} --help)\n"
    assert not list(tmp_path.iterdir())
    assert main(["simulate", "--model", str(REPO / "examples" / "models" / "sinusoid.json"), "--duration", "1",
                 "--out", "s.csv", "--force", "--force"]) == 0


@pytest.mark.parametrize("argv, option, hint", [
    (["allan", "r.csv", "--kalibr", "k.yaml", "--kalibr-tau-s", "-1,10"], "--kalibr-tau-s",
     "; a value that starts with '-' goes after '=': --kalibr-tau-s=-1,10"),
    (["gap", "r.csv", "--out-dir", "-reports"], "--fleet/--out-dir",
     "; a value that starts with '-' goes after '=': --out-dir=-reports"),
    (["allan", "r.csv", "--kalibr", "--force"], "--kalibr", ""),  # the next option: a value forgotten, no hint
])
def test_a_value_that_starts_with_a_dash_is_said_how_to_give(argv, option, hint, capsys):
    """Issue 39 (trial): ``--kalibr-tau-s -1,10`` said only argparse's "expected one argument"
    (``=-1,10`` works): the line says how to give such a value."""
    from gyrofilter.cli import main

    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    assert capsys.readouterr().err == (f"gyrofilter: error: argument {option}: expected one argument{hint} "
                                       f"(see gyrofilter {argv[0]} --help)\n")


def test_running_out_of_memory_is_one_line_not_a_traceback(monkeypatch, capsys):
    """A MemoryError anywhere in a command (an input too large to analyse) ended in a traceback,
    exit 1 (attack pass 10); the recording reader names its file itself (tests/test_recording.py)."""
    from gyrofilter.cli import main, simulate

    def out_of_memory(args):
        raise MemoryError("Unable to allocate 7.45 GiB")

    monkeypatch.setattr(simulate, "run", out_of_memory)
    assert main(["simulate", "--model", "m.json", "--duration", "1", "--out", "x.csv"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["gyrofilter: error: out of memory running simulate; give it a shorter input"], err


def test_a_deleted_current_folder_is_said_not_a_nameless_errno(tmp_path, monkeypatch, capsys):
    """Run from a folder deleted meanwhile, every command ended in "[Errno 2] No such file or
    directory", naming nothing (attack pass 10)."""
    from gyrofilter.cli import main

    gone = tmp_path / "gone"
    gone.mkdir()
    monkeypatch.chdir(gone)
    gone.rmdir()
    assert main(["replay", str(REPO / "gyrofilter" / "data" / "mpu6050_static_100s.csv.gz"), "--out", "x.csv"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        "gyrofilter: error: the current folder no longer exists (deleted?); cd to one that does"]


@pytest.mark.parametrize("unbuffered", ["1", ""])
@pytest.mark.parametrize("command, out_option, out_name", [
    ("allan", "--json", "allan.json"), ("arma", "--json", "arma.json")])
def test_a_closed_stdout_leaves_the_output_files_written(tmp_path, command, out_option, out_name, unbuffered):
    """Attack pass 17 (issue 37): `allan --json F | head` (stdout's reader gone before the
    console table was printed): F is written and the exit is clean. Unbuffered (PYTHONUNBUFFERED,
    `python -u`) the first print's BrokenPipeError ended the command with exit 0 and no word, F not
    written; buffered, F was written and the exit was 120 with 'Exception ignored ... BrokenPipeError'."""
    rec, _ = lsb_recording(tmp_path, n=3000)
    out = tmp_path / out_name
    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader gone before the first line
    env = {**os.environ, "PYTHONUNBUFFERED": unbuffered}
    try:
        proc = subprocess.run([sys.executable, "-m", "gyrofilter", command, str(rec), out_option, str(out)],
                              stdout=write_end, stderr=subprocess.PIPE, env=env, timeout=300)
    finally:
        os.close(write_end)
    err = proc.stderr.decode()
    assert proc.returncode == 0, err
    assert "Traceback" not in err and "BrokenPipe" not in err and f"wrote {out}" in err
    assert json.loads(out.read_text())


def test_record_whose_stderr_reader_goes_away_records_to_the_end(tmp_path):
    """Attack pass 17 (issue 37): `record --progress ... 2>&1 | head`: the status line's reader
    goes away; the recording goes on to --duration (it stopped at the first status line after,
    1.2 s of 3, exit 0, no word)."""
    out = tmp_path / "rec.csv"
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        proc = subprocess.run([sys.executable, "-m", "gyrofilter", "record", "--source", "sim:seed=1", "--duration", "3",
                               "--out", str(out), "--progress"], stdout=subprocess.DEVNULL, stderr=write_end, timeout=120)
    finally:
        os.close(write_end)
    assert proc.returncode == 0
    assert len(read_recording(out)) == 300


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (a device every write to fails, ENOSPC)")
def test_a_console_that_cannot_be_written_does_not_stop_a_command(tmp_path):
    """Attack pass 18 (issue 37): stderr that takes no write (`2>>LOG` on a full disk, ENOSPC; a
    terminal gone, EIO) is a console no one reads: `record --progress 2>/dev/full` records to
    --duration (it stopped at its first status line, 51 samples of 300, exit 1), and `allan --json
    F --kalibr Y 2>/dev/full` writes F and Y (it stopped at "wrote F", no Y, exit 1)."""
    rec_out = tmp_path / "rec.csv"
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "gyrofilter", "record", "--source", "sim:seed=1,realtime=1",
                               "--duration", "3", "--out", str(rec_out), "--progress"],
                              stdout=subprocess.DEVNULL, stderr=full, timeout=120)
        assert proc.returncode == 0
        assert len(read_recording(rec_out)) == 300
        rec, _ = lsb_recording(tmp_path, n=3000)
        out, yaml = tmp_path / "allan.json", tmp_path / "allan.yaml"
        proc = subprocess.run([sys.executable, "-m", "gyrofilter", "allan", str(rec), "--json", str(out), "--kalibr", str(yaml)],
                              stdout=subprocess.DEVNULL, stderr=full, timeout=300)
    assert proc.returncode == 0
    assert json.loads(out.read_text()) and "gyroscope_noise_density" in yaml.read_text()


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (a device every write to fails, ENOSPC)")
@pytest.mark.parametrize("unbuffered", ["1", ""])
def test_a_full_stdout_is_an_error_naming_it(tmp_path, unbuffered):
    """Attack pass 18: `arma F > FULL` (the table its result, on a full disk): exit 2 naming
    stdout (buffered, it ended with exit 0 and no word, the table lost; `allan F` the same); `simulate --out F > FULL`: F is
    written whole, the console's line is not, and the error names stdout (it read "[Errno 28] No
    space left on device" alone, as if F's disk had filled; buffered, exit 120 and "Exception
    ignored")."""
    rec, _ = lsb_recording(tmp_path, n=3000)
    out = tmp_path / "sim.csv"
    env = {**os.environ, "PYTHONUNBUFFERED": unbuffered}
    with open("/dev/full", "w") as full:
        for args in (["arma", str(rec)], ["simulate", "--model", str(REPO / "examples" / "models" / "bias_step.json"),
                                           "--duration", "2", "--out", str(out)]):
            proc = subprocess.run([sys.executable, "-m", "gyrofilter", *args], stdout=full, stderr=subprocess.PIPE, env=env,
                                  timeout=300)
            assert proc.returncode == 2
            assert proc.stderr.decode().splitlines()[-1] == "gyrofilter: error: stdout: No space left on device"
    assert len(read_recording(out)) > 0



@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (a device every write to fails, ENOSPC)")
def test_a_program_running_the_commands_keeps_its_stdout(tmp_path):
    """Attack pass 19 (issue 37): a program that runs `gyrofilter.cli.main` twice on a full stdout
    gets exit 2 from each, and its descriptor 1 is its own file again after them (the first
    failure left it on the null device for good: the second `arma` ended with exit 0, its table
    lost, and the program's own writes after it went nowhere)."""
    rec, _ = lsb_recording(tmp_path, n=3000)
    script = ("import os, sys\n"
              "from gyrofilter.cli import main\n"
              "codes = [main(['arma', sys.argv[1]]) for _ in range(2)]\n"
              "try:\n    os.write(1, b'x'); after = 'written'\n"
              "except OSError as exc:\n    after = exc.strerror\n"
              "print(codes, after, file=sys.stderr)\n")
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-c", script, str(rec)], stdout=full, stderr=subprocess.PIPE, timeout=300)
    assert proc.stderr.decode().splitlines()[-1] == "[2, 2] No space left on device"

def test_a_console_closed_at_the_start_is_the_null_device(tmp_path):
    """Attack pass 18 (issue 37): `gyrofilter allan F --json J >&- 2>&-` (a descriptor closed, as a
    daemon or a cron line may start a command; Python's stdout and stderr None) and `record
    --progress ... 2>&-`: the output files are written and the exit is clean (each ended with
    exit 120 or 1 on an AttributeError, nothing written)."""
    rec, _ = lsb_recording(tmp_path, n=3000)
    out, rec_out = tmp_path / "allan.json", tmp_path / "recorded.csv"
    allan = subprocess.run(["sh", "-c", f'"$0" -m gyrofilter allan "$1" --json "$2" >&- 2>&-', sys.executable, rec, out],
                           timeout=300)
    record = subprocess.run(["sh", "-c", f'"$0" -m gyrofilter record --source sim:seed=1 --duration 1 --progress --out "$1" 2>&-',
                             sys.executable, rec_out], timeout=120)
    assert (allan.returncode, record.returncode) == (0, 0)
    assert json.loads(out.read_text()) and len(read_recording(rec_out)) == 100


def test_progress_in_a_log_is_a_line_a_while_and_every_line_said_always(capsys):
    """A new user's trial: `allan --fleet` under nohup printed nothing for 8 minutes (progress only
    on a terminal). In a log (stderr not a terminal, no --progress) the rule of every command is
    one line per LOG_PROGRESS_EVERY_S (none in a short run: a refusal stays one line) and every line
    said with always=True (a fleet's recording); with --progress, every line, as on a terminal."""
    from gyrofilter.cli.console import LOG_PROGRESS_EVERY_S, ProgressLines
    now = [0.0]
    logged = ProgressLines(False, "gap", clock=lambda: now[0])
    for t in (0.0, 1.0, LOG_PROGRESS_EVERY_S - 1, LOG_PROGRESS_EVERY_S + 0.5, LOG_PROGRESS_EVERY_S + 2,
              2 * LOG_PROGRESS_EVERY_S + 1):
        now[0] = t
        logged(f"at {t:g}")
    logged("a unit done", always=True)
    err = capsys.readouterr().err.splitlines()
    assert err == [f"gap [{LOG_PROGRESS_EVERY_S + 0.5:5.1f} s] at {LOG_PROGRESS_EVERY_S + 0.5:g}",
                   f"gap [{2 * LOG_PROGRESS_EVERY_S + 1:5.1f} s] at {2 * LOG_PROGRESS_EVERY_S + 1:g}",
                   f"gap [{2 * LOG_PROGRESS_EVERY_S + 1:5.1f} s] a unit done"]
    forced = ProgressLines(True, clock=lambda: now[0])
    for k in range(5):
        forced(f"line {k}")
    assert capsys.readouterr().err.splitlines() == [f"line {k}" for k in range(5)]


def test_no_command_decides_alone_whether_progress_shows():
    """One rule (console.ProgressLines): no command of gyrofilter/cli asks stderr whether it is a
    terminal for its progress (each did, and each showed nothing in a log)."""
    cli = os.path.join(REPO, "gyrofilter", "cli")
    asking = [name for name in sorted(os.listdir(cli)) if name.endswith(".py") and name != "console.py"
              and "stderr.isatty" in open(os.path.join(cli, name), encoding="utf-8").read()]
    assert asking == ["record.py"]  # record's status line every second is a live display (live.Status), not progress
