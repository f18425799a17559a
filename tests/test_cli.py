"""cli (the ``gyrofilter`` command): one-line refusals of unknown options with the closest
option, and output that survives a file name that is not UTF-8."""
import os
import subprocess
import sys

import pytest

from support import file_named_by_bytes


@pytest.mark.parametrize("argv, prog, said", [
    (["replay", "REC", "--ot", "x.csv"], "gyrofilter replay", "unrecognized arguments: --ot x.csv; did you mean --out?"),
    (["allan", "REC", "--jsno=a.json"], "gyrofilter allan", "unrecognized arguments: --jsno=a.json; did you mean --json?"),
    (["replay", "REC", "--sample-rat", "3", "--outt", "x"], "gyrofilter replay", "; did you mean --out?"),
    (["replay", "REC", "-q"], "gyrofilter replay", "unrecognized arguments: -q"),
    (["--bogus"], "gyrofilter", "unrecognized arguments: --bogus"),
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
    assert err.count("\n") == 1 and err.startswith(f"{prog}: error: ") and said in err
    assert err.rstrip().endswith(f"(see {prog} --help)")
    assert ("did you mean" in err) == ("did you mean" in said)


def test_a_summary_naming_a_file_that_is_not_utf8_prints_under_a_utf8_locale(tmp_path):
    """Under a UTF-8 locale (a Pi's en_GB.UTF-8) stdout is strict: the summary's file name, with
    the lone surrogate os.fsdecode makes of byte 0xff, crashed after the work was done."""
    path = file_named_by_bytes(tmp_path)
    env = {**os.environ, "LC_ALL": "C.UTF-8", "PYTHONIOENCODING": ""}
    proc = subprocess.run([sys.executable, "-m", "gyrofilter", "replay", os.fsencode(path)], capture_output=True, env=env)
    assert proc.returncode == 0, proc.stderr
    assert b"\\udcff.csv" in proc.stdout + proc.stderr and b"Traceback" not in proc.stderr
