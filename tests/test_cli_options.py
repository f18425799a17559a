"""cli.options: the numeric types of the options (plain decimal numbers, whole numbers) and the
one spelling of a sample rate."""
import os

import pytest

from gyrofilter.cli import options
from gyrofilter.errors import SettingsError
from gyrofilter.sources.simulated import DEFAULT_MODEL_PATH


@pytest.mark.parametrize("command", ["record", "run", "simulate"])
def test_sample_rate_option_has_one_spelling(command):
    """Issue 23: --sample-rate-hz is the one spelling; --rate (simulate) and --sample-rate (record,
    run) are gone (test_cli: typing them is refused, naming --sample-rate-hz)."""
    from gyrofilter.cli import build_parser

    parser = build_parser(command)
    extra = ["--model", "m.json", "--duration", "1", "--out", "o.csv"] if command == "simulate" else ["--source", "sim", "--out", "o.csv"]
    args = parser.parse_args([command, *extra, options.SAMPLE_RATE_OPTION, "250"])
    assert args.sample_rate_hz == 250.0 and options.sample_rate_hz(args) == 250.0
    spellings = [s for a in parser.commands[command]._actions for s in a.option_strings if "rate" in s]
    assert spellings == ["--sample-rate-hz"] == [options.SAMPLE_RATE_OPTION]
    assert options.sample_rate_hz(parser.parse_args([command, *extra])) is None


def test_a_bad_sample_rate_is_refused_naming_the_option_for_a_live_source_too(tmp_path, capsys):
    """record and run named the source's keyword (sample_rate_hz) for --sample-rate-hz 0; the
    option is checked where it is read, with the one check of a sample rate."""
    from gyrofilter.cli import main

    with pytest.raises(SettingsError, match=r"^--sample-rate-hz must be a number of Hz in \[0.001, 100000\], got 0.0$"):
        options.sample_rate_hz(type("Args", (), {"sample_rate_hz": 0.0}))
    for command in ("record", "run"):
        argv = [command, "--source", "sim:realtime=0,duration=1", "--sample-rate-hz", "0", "--out", str(tmp_path / "o.csv")]
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err == "gyrofilter: error: --sample-rate-hz must be a number of Hz in [0.001, 100000], got 0.0\n", err
    assert os.listdir(tmp_path) == []



@pytest.mark.parametrize("text", ["١_٠", "1_0", "٣", "0x10", "nan", "inf", "-inf", "1e400", "1d5", ".", "", "1j"])
def test_numeric_option_types_take_plain_decimal_numbers_only(text):
    """argparse's float/int took Python's extras (``--duration ١_٠`` was 10 s) that every other
    reader of numbers refuses (issue 22, hostile 5-6)."""
    import argparse

    for kind in (options.decimal, options.whole_number):
        with pytest.raises(argparse.ArgumentTypeError, match=r"^must be a (plain decimal|finite) number"):
            kind(text)


def test_numeric_option_types_read_plain_numbers_exactly():
    import argparse

    assert options.decimal(" 5") == 5.0 and options.decimal("-1e-3") == -0.001 and options.decimal(".5") == 0.5
    assert options.whole_number("9007199254740993") == 9007199254740993  # beyond 2^53: every digit kept
    assert options.whole_number("1e3") == 1000 and options.whole_number("-1") == -1 and options.whole_number("+7") == 7
    assert options.whole_number(str(10**30)) == 10**30  # --seed's own check names it
    with pytest.raises(argparse.ArgumentTypeError, match="must be a whole number, got 1.5"):
        options.whole_number("1.5")
    with pytest.raises(argparse.ArgumentTypeError, match=r"^must be written in digits when it is 2\^53 or more, got '1e308'$"):
        options.whole_number("1e308")  # not a 309-digit count in a message
    with pytest.raises(argparse.ArgumentTypeError, match="written in digits"):
        options.whole_number("9007199254740993.0")  # rounded to ...992 before any check could see it
    with pytest.raises(argparse.ArgumentTypeError, match="plain decimal"):
        options.whole_number("+-5")


def test_every_numeric_option_of_every_command_uses_the_plain_number_types():
    from gyrofilter.cli import COMMANDS, build_parser

    checked = 0
    for name in COMMANDS:
        sub = next(a for a in build_parser(name)._actions if a.dest == "command").choices[name]
        for action in sub._actions:
            assert action.type not in (float, int), (name, action.option_strings)
            checked += action.type in (options.decimal, options.whole_number, options.lsb_per_dps, options.number_pair)
    assert checked >= 19  # the options of 2026-12: --duration, --seed, --jobs, --confidence, ...


def test_a_number_in_another_script_is_refused_before_any_work(tmp_path, capsys):
    from gyrofilter.cli import main

    out = tmp_path / "o.csv"
    try:  # SystemExit while argparse prints its usage too
        code = main(["simulate", "--model", str(DEFAULT_MODEL_PATH), "--duration", "١_٠", "--out", str(out)])
    except SystemExit as exc:
        code = exc.code
    assert code == 2
    assert "argument --duration: must be a plain decimal number (like 12, -0.5 or 1e-3), got '١_٠'" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize("value", ["1e308", "1e-308", "0.05", "2e8"])
@pytest.mark.parametrize("command", ["convert", "record", "run"])
def test_lsb_per_dps_is_bounded_to_what_a_gyro_can_be(tmp_path, capsys, command, value):
    """Issue 37 (attack): --lsb-per-dps took any positive number (1e308 read every sample as 0
    deg/s, 1e-308 as inf); it is refused outside units.LSB_PER_DPS_RANGE in one line naming it."""
    from gyrofilter.cli import main

    log = tmp_path / "log.csv"
    log.write_text("t,gx,gy,gz\n" + "".join(f"{i / 100},1,2,3\n" for i in range(100)))
    argv = {"convert": ["convert", str(log), "--unit", "lsb"],
            "record": ["record", "--source", "serial:loop://", "--gyro-unit", "lsb"],
            "run": ["run", "--source", "serial:loop://", "--gyro-unit", "lsb"]}[command]
    with pytest.raises(SystemExit) as info:
        main(argv + ["--lsb-per-dps", value, "--out", str(tmp_path / "o.csv")])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "argument --lsb-per-dps: must be a number of LSB per deg/s in [0.1, 1e+08]" in err
    assert sorted(os.listdir(tmp_path)) == ["log.csv"]


def test_lsb_per_dps_in_the_range_is_taken():
    assert options.lsb_per_dps("131") == 131.0 and options.lsb_per_dps("0.1") == 0.1 and options.lsb_per_dps("1e8") == 1e8
