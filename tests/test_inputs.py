"""gyrofilter.inputs: the one reader of numbers in text and JSON values, the one JSON loader, quote()."""
import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gyrofilter import inputs
from gyrofilter.errors import CalibrationError, SettingsError
from gyrofilter.inputs import (MAX_JSON_DEPTH, MAX_NUMBER_CHARS, MAX_QUOTE_CHARS, check_number, is_plain_number,
                               load_json, parse_json, parse_number, quote)


# ------------------------------------------------------------------------------ numbers in text


@pytest.mark.parametrize("text, value", [
    ("12", 12.0), ("-0.5", -0.5), ("+3", 3.0), ("1e-3", 1e-3), ("1E+2", 100.0), (".5", 0.5), ("5.", 5.0),
    (" 7 ", 7.0), ("\t-2.5e1\n", -25.0), ("0", 0.0), ("-0", 0.0), ("1e-400", 0.0), ("9" * MAX_NUMBER_CHARS, 1e64),
])
def test_plain_decimal_numbers_are_read(text, value):
    assert parse_number(text, "x") == pytest.approx(value, rel=1e-15) and is_plain_number(text)


@pytest.mark.parametrize("text", [
    "0.0_1", "1_000", "nan", "NaN", "inf", "-inf", "Infinity", "infinity", "0x10", "0b1", "0o7", "1e", "e3", ".", "",
    " ", "+", "-", "1.2.3", "--1", "+-1", "1,5", "1 2", "1e2.5", "1j", "\u0661\u0662", "\uff11\uff12", "12\u0661",
    "9" * (MAX_NUMBER_CHARS + 1), "True",
])
def test_anything_else_is_refused_as_not_plain_decimal(text):
    assert not is_plain_number(text)
    with pytest.raises(SettingsError, match=r"^--gain must be a plain decimal number \(like 12, -0.5 or 1e-3\), got "):
        parse_number(text, "--gain")


def test_a_number_beyond_a_float_is_refused_as_not_finite():
    with pytest.raises(SettingsError, match=r"^x must be a finite number, got '1e400'$"):
        parse_number("1e400", "x")
    with pytest.raises(SettingsError, match="must be a finite number"):
        parse_number("-1e309", "x")


def test_parse_number_raises_the_callers_error_class():
    with pytest.raises(CalibrationError):
        parse_number("abc", "x", error=CalibrationError)
    with pytest.raises(CalibrationError):
        parse_number("5", "x", high=1, error=CalibrationError)


@pytest.mark.parametrize("bounds, accepted, refused, shown", [
    (dict(low=0), [0, 1e300], [-1e-300, -1], ">= 0"),
    (dict(low=0, low_open=True), [1e-300, 5], [0, -1], "> 0"),
    (dict(high=10), [10, -1e300], [10.000001], "<= 10"),
    (dict(high=10, high_open=True), [9.999999], [10, 11], "< 10"),
    (dict(low=-1, high=1), [-1, 0, 1], [-1.5, 1.5], "in [-1, 1]"),
    (dict(low=-1, high=1, low_open=True, high_open=True), [-0.999, 0.999], [-1, 1], "in (-1, 1)"),
    (dict(low=0, high=1, high_open=True), [0, 0.5], [1], "in [0, 1)"),
])
def test_bounds_are_closed_unless_said_open(bounds, accepted, refused, shown):
    for value in accepted:
        assert check_number(value, "x", **bounds) == value
        assert parse_number(repr(float(value)), "x", **bounds) == value
    for value in refused:
        with pytest.raises(SettingsError) as info:
            check_number(value, "x", **bounds)
        assert str(info.value).startswith(f"x must be {shown}, got "), str(info.value)
        with pytest.raises(SettingsError, match="^x must be "):
            parse_number(repr(float(value)), "x", **bounds)


def test_integer_asks_for_a_whole_number_and_returns_an_int():
    assert parse_number("12", "n", integer=True) == 12 and isinstance(parse_number("12", "n", integer=True), int)
    assert check_number(3.0, "n", integer=True) == 3 and isinstance(check_number(3.0, "n", integer=True), int)
    assert check_number(np.int64(7), "n", integer=True) == 7
    for value in (2.5, 1e-9, -0.5):
        with pytest.raises(SettingsError, match=r"^n must be a whole number, got "):
            check_number(value, "n", integer=True)
    with pytest.raises(SettingsError, match=r"^n must be a whole number, got '2.5'$|^n must be a whole number, got 2.5$"):
        parse_number("2.5", "n", integer=True)


# ------------------------------------------------------------------------------ numbers from JSON or Python


@pytest.mark.parametrize("value", [1, -2.5, 0, np.float32(1.5), np.float64(-3.0), np.int64(4), np.uint8(200), 2**1023, 1e308])
def test_ints_and_floats_are_numbers(value):
    result = check_number(value, "x")
    assert isinstance(result, float) and result == float(value)


@pytest.mark.parametrize("value, shown", [
    (True, "True"), (False, "False"), (np.bool_(True), "True"), (None, "None"), ("3", "'3'"), ([1], "[1]"),
    ({"a": 1}, "{'a': 1}"), (math.nan, "nan"), (math.inf, "inf"), (-math.inf, "-inf"), (np.float64("nan"), "nan"),
    (10**400, "1" + "0" * (MAX_QUOTE_CHARS - 1)), (-(10**400), "-1"), (2**1024, "1797693"), (1j, "1j"),
])
def test_anything_but_a_finite_int_or_float_is_refused_without_overflow(value, shown):
    with pytest.raises(SettingsError) as info:
        check_number(value, "key")
    text = str(info.value)
    assert text.startswith(f"key must be a finite number, got {shown}") and "\n" not in text, text
    assert len(text) <= 200  # a 400-digit int is cut, its length given
    if isinstance(value, int) and abs(value) > 10**300:
        assert "characters)" in text


def test_a_long_string_value_is_quoted_cut():
    with pytest.raises(SettingsError) as info:
        check_number("x" * 10_000, "key")
    assert str(info.value) == f"key must be a finite number, got {'x' * MAX_QUOTE_CHARS!r}... (10000 characters)"


# ------------------------------------------------------------------------------ JSON text


@pytest.mark.parametrize("token", ["NaN", "Infinity", "-Infinity"])
def test_nan_and_infinity_tokens_are_refused(token):
    assert json.loads(f'{{"a": [1, {token}]}}')  # Python's json takes them
    with pytest.raises(SettingsError, match=rf"^doc: not valid JSON: {token} is not a JSON number$"):
        parse_json(f'{{"a": [1, {token}]}}', "doc")


def _nested(depth, opener="[", closer="]"):
    return opener * depth + closer * depth


def test_nesting_of_32_levels_is_read_and_33_is_refused():
    assert parse_json(_nested(MAX_JSON_DEPTH), "doc") == json.loads(_nested(MAX_JSON_DEPTH))
    with pytest.raises(SettingsError, match=f"^doc: JSON nested more than {MAX_JSON_DEPTH} levels deep$"):
        parse_json(_nested(MAX_JSON_DEPTH + 1), "doc")
    mixed = '{"a": ' * 16 + "[" * 16 + "1" + "]" * 16 + "}" * 16  # objects and lists count alike
    assert inputs._depth(parse_json(mixed, "doc")) == 32
    with pytest.raises(SettingsError, match="nested more than 32"):
        parse_json('{"a": ' * 17 + "[" * 16 + "1" + "]" * 16 + "}" * 17, "doc")
    assert inputs._depth(parse_json("[[], [[[]]], 1]", "doc")) == 4 and inputs._depth(parse_json("5", "doc")) == 0


def test_nesting_beyond_the_recursion_limit_is_refused_not_a_recursion_error():
    with pytest.raises(SettingsError, match="nested more than 32 levels deep"):
        parse_json(_nested(200_000), "doc")
    with pytest.raises(SettingsError, match="nested more than 32 levels deep"):
        parse_json('{"a": ' * 200_000 + "1" + "}" * 200_000, "doc")


def test_invalid_json_and_an_integer_of_too_many_digits_are_one_line():
    with pytest.raises(SettingsError, match=r"^doc: not valid JSON: line 2 column 1: Expecting value$"):
        parse_json("[1,\n]", "doc")
    with pytest.raises(SettingsError) as info:
        parse_json("1" + "0" * 5000, "doc")  # beyond Python's 4300-digit int conversion limit
    assert str(info.value).startswith("doc: not valid JSON: ") and len(str(info.value)) <= 120
    assert parse_json("1" + "0" * 400, "doc") == 10**400  # valid JSON: check_number refuses it where a number is read


# ------------------------------------------------------------------------------ JSON files


def test_load_json_reads_a_file_and_names_it_in_every_error(tmp_path):
    path = tmp_path / "m.json"
    path.write_text('{"a": [1, 2.5, "x", null, true]}', encoding="utf-8")
    assert load_json(path, "model") == {"a": [1, 2.5, "x", None, True]}
    path.write_bytes(b'{"a": "\xff"}')
    with pytest.raises(SettingsError, match=rf"^{path}: not a model file: not UTF-8 text$"):
        load_json(path, "model")
    path.write_text("{", encoding="utf-8")
    with pytest.raises(CalibrationError, match=rf"^{path}: not valid JSON: line 1 column 2"):
        load_json(path, "calibration", CalibrationError)
    with pytest.raises(SettingsError, match=rf"^{tmp_path / 'none.json'}: cannot read the model file: No such file"):
        load_json(tmp_path / "none.json", "model")
    with pytest.raises(SettingsError, match=rf"^{tmp_path}: cannot read the model file: Is a directory"):
        load_json(tmp_path, "model")


def test_the_size_cap_counts_bytes_and_is_inclusive(tmp_path, monkeypatch):
    monkeypatch.setattr(inputs, "MAX_JSON_BYTES", 2 * 1024 * 1024)
    path = tmp_path / "big.json"
    text = '["' + "x" * (inputs.MAX_JSON_BYTES - 4) + '"]'
    path.write_text(text)
    assert len(path.read_bytes()) == inputs.MAX_JSON_BYTES and load_json(path, "model") == ["x" * (inputs.MAX_JSON_BYTES - 4)]
    path.write_text(text + " ")
    with pytest.raises(SettingsError, match=rf"^{path}: not a model file: larger than 2 MiB$"):
        load_json(path, "model")


def test_an_endless_file_ends_at_the_cap():
    with pytest.raises(SettingsError, match="^/dev/zero: not a model file: larger than 16 MiB$"):
        load_json("/dev/zero", "model")


# ------------------------------------------------------------------------------ quote


def test_quote_cuts_at_the_limit_and_gives_the_length():
    assert quote("a" * MAX_QUOTE_CHARS) == repr("a" * MAX_QUOTE_CHARS)
    assert quote("a" * (MAX_QUOTE_CHARS + 1)) == f"{'a' * MAX_QUOTE_CHARS!r}... ({MAX_QUOTE_CHARS + 1} characters)"
    assert quote("two\nlines") == "'two\\nlines'"  # one line, whatever the text
    assert quote(12) == "'12'" and quote("abc", limit=2) == "'ab'... (3 characters)"


def test_a_whole_number_in_text_is_read_exactly():
    """parse_number(integer=True) went through float: seed=9007199254740993 became ...992."""
    assert parse_number("9007199254740993", "seed", integer=True, low=0) == 9007199254740993
    assert parse_number("-3", "n", integer=True) == -3 and isinstance(parse_number("-3", "n", integer=True), int)
    assert parse_number("1e3", "n", integer=True) == 1000
    assert check_number(2 ** 63 - 1, "seed", integer=True, high=2 ** 63 - 1) == 2 ** 63 - 1
    with pytest.raises(SettingsError, match=r"seed must be <= 9.22337e\+18, got 9223372036854775808"):
        check_number(2 ** 63, "seed", integer=True, high=2 ** 63 - 1)


def test_a_key_given_twice_in_a_json_object_is_refused():
    """json.loads keeps the last of two equal keys: a second bias_dps was used unseen."""
    with pytest.raises(SettingsError, match="doc: not valid JSON: key 'bias_dps' given twice"):
        parse_json('{"bias_dps": [0, 0, 0], "x": {"a": 1}, "bias_dps": [10, 10, 10]}', "doc")
    with pytest.raises(SettingsError, match="key 'a' given twice"):
        parse_json('[{"a": 1, "a": 1}]', "doc")
    assert parse_json('[{"a": 1}, {"a": 2}]', "doc") == [{"a": 1}, {"a": 2}]


def test_a_json_key_with_an_invisible_character_is_refused(tmp_path):
    """Attack pass 21: a calibration holding "bias_dps\u200b" beside "bias_dps" shows a key
    given twice, which is refused; it was read as another key and ignored (the bias taken from
    the other one without a word)."""
    with pytest.raises(SettingsError, match=r"doc: not valid JSON: key 'bias_dps\\u200b' holds the invisible "
                                            r"character U\+200B \(ZERO WIDTH SPACE\)"):
        parse_json('{"bias_dps": [0, 0, 0], "bias_dps\u200b": [10, 10, 10]}', "doc")
    from gyrofilter.filter.calibration import Calibration, CalibrationError

    path = tmp_path / "cal.json"
    path.write_text('{"bias_dps\ufeff": [9, 9, 9], "bias_dps": [0.1, 0.2, 0.3], "noise_std_dps": [0.1, 0.1, 0.1], '
                    '"samples": 200, "sample_rate_hz": 100}', encoding="utf-8")
    with pytest.raises(CalibrationError, match=r"cal.json: .*key 'bias_dps\\ufeff' holds the invisible character U\+FEFF"):
        Calibration.load(path)
    # pass 22's notes: letter-like blanks show as nothing too (attack pass 23's lead fix)
    for key, shown in (("bias_dps\u3164", "U\\+3164 \\(HANGUL FILLER\\)"), ("bias_dps\u2800", "U\\+2800 \\(BRAILLE"),
                       ("bias\u034f_dps", "U\\+034F \\(COMBINING GRAPHEME JOINER\\)"), ("bias_dps\u3000", "U\\+3000")):
        with pytest.raises(SettingsError, match="holds the invisible character " + shown):
            parse_json('{"bias_dps": [0, 0, 0], "%s": [10, 10, 10]}' % key, "doc")
    assert parse_json('{"bias dps": 1, "b\u00e4r": 2}', "doc") == {"bias dps": 1, "b\u00e4r": 2}  # a space, a letter
    assert parse_json('{"note": "a\u200bb"}', "doc") == {"note": "a\u200bb"}  # a value is text as it is


@pytest.mark.parametrize("path", [2, 0, True, {"bias_dps": [0, 0, 0]}, None, 1.5])
def test_load_json_takes_only_a_file_name(path):
    """An int was taken by open() as a file descriptor and closed (calibration=2 closed stderr)."""
    import os

    before = os.fstat(2)
    with pytest.raises(SettingsError, match="the model must be a file name, got"):
        load_json(path, "model")
    assert os.fstat(2) == before


@pytest.mark.parametrize("text", ["9007199254740993.0", "9.007199254740993e15", "1e18"])
def test_a_whole_number_of_2_53_or_more_must_be_written_in_digits(text):
    """9007199254740993.0 went through float to ...992 and was taken as a seed."""
    with pytest.raises(SettingsError, match="must be written in digits when it is 2\\^53 or more"):
        parse_number(text, "seed", integer=True)
    assert parse_number(text.split(".")[0].split("e")[0] if text[0] == "9" and "e" not in text else "1" + "0" * 18,
                        "seed", integer=True) > 2 ** 53


#: names that read differently once escaped the old way: a backslash at the end, the two characters
#: backslash and n, a line end, a quote, DEL/C1 controls and separators, a lone surrogate
ODD_NAMES = ["unit\\", "a\\nb.csv", "a\nb.csv", 'say "hi".csv', "x\x7f\x85\u2028\u2029.csv", "\udcff.csv",
             "tab\there", "\\u0041", "é ü.csv", " both ends ", ""]


@pytest.mark.parametrize("name", ODD_NAMES)
def test_a_json_string_is_one_line_and_reads_back_exactly(name):
    """Issue 37 (leftover): a name written by the one-line rule (escape_controls) read the same for
    a line end and for the two characters ``\\n``, and a name ending in a backslash could end a
    quoted string early. json_string is one line, has no control character and reads back
    exactly with the format's own reader."""
    text = inputs.json_string(name)
    assert json.loads(text) == name
    assert not inputs.CONTROL_CHARACTER.search(text) and text.encode("utf-8")
    assert text.startswith('"') and text.endswith('"')


@given(st.text(st.characters(blacklist_categories=())))
def test_every_string_reads_back_from_its_json_string(name):
    text = inputs.json_string(name)
    assert json.loads(text) == name and not inputs.CONTROL_CHARACTER.search(text)


@pytest.mark.parametrize("name", ODD_NAMES)
def test_a_json_string_reads_back_as_a_yaml_double_quoted_scalar(name):
    yaml = pytest.importorskip("yaml")
    assert yaml.safe_load(f"key: {inputs.json_string(name)}  # comment\nother: 1\n") == {"key": name, "other": 1}


def test_a_json_file_saved_with_a_byte_order_mark_is_read(tmp_path):
    """Attack pass (issue 37): a model saved by a Windows editor (UTF-8 with BOM) was refused with
    Python's "Unexpected UTF-8 BOM (decode using utf-8-sig)"; a recording's BOM is skipped, and
    RFC 8259 (section 8.1) lets a parser ignore it: so does load_json, only at the start."""
    path = tmp_path / "model.json"
    path.write_text('{"a": [1, 2.5]}', encoding="utf-8-sig")
    assert inputs.load_json(str(path), "model") == {"a": [1, 2.5]}
    path.write_text('{"a": "\ufeff"}', encoding="utf-8-sig")
    assert inputs.load_json(str(path), "model") == {"a": "\ufeff"}
    path.write_bytes(b' \xef\xbb\xbf{"a": 1}')
    with pytest.raises(SettingsError, match="not valid JSON"):
        inputs.load_json(str(path), "model")


def test_a_json_fifo_nobody_writes_to_is_refused_and_one_written_is_read(tmp_path, monkeypatch, capsys):
    """Attack pass 12 (issue 37): ``--calibration``, ``--model``, ``--temp-model`` and
    ``GyroFilter(calibration=...)`` given a FIFO nobody writes to (``mkfifo cal.json``) waited
    forever in open(), as recordings did before attack pass 6. JSON files are opened as every input
    is (``inputs.open_input``): refused after PIPE_WAIT_S in one line; a writer that comes within
    the wait, or a pipe (``<(cat cal.json)``), is read."""
    import os
    import re
    import threading

    from gyrofilter import GyroFilter
    from gyrofilter.cli import main
    monkeypatch.setattr(inputs, "PIPE_WAIT_S", 0.3)
    fifo = tmp_path / "cal.json"
    os.mkfifo(fifo)
    said = f"{fifo}: not a regular file (a pipe or FIFO) and nothing was written to it in 0.3 s; give the file itself"
    with pytest.raises(SettingsError, match=f"^{re.escape(said)}$"):
        load_json(fifo, "model")
    with pytest.raises(CalibrationError, match=f"^{re.escape(said)}$"):
        GyroFilter(100.0, calibration=str(fifo))
    assert main(["simulate", "--model", str(fifo), "--duration", "1", "--out", str(tmp_path / "o.csv")]) == 2
    assert capsys.readouterr().err == f"gyrofilter: error: {said}\n"
    monkeypatch.setattr(inputs, "PIPE_WAIT_S", 30.0)

    def write_late():
        with open(fifo, "w") as fh:
            fh.write('{"a": [1, 2.5]}')
    writer = threading.Timer(0.1, write_late)
    writer.start()
    assert load_json(fifo, "model") == {"a": [1, 2.5]}
    writer.join()


def test_api_refusals_of_passes_23_and_24_now_take_what_is_right_and_name_what_is_not(tmp_path):
    """Passes 23 and 24's notes: `iter_recording(chunk_rows=np.int64(7))` was refused as "not a whole
    number >= 1" (and True taken as 1); `update(temp_c=np.array(25.0))` as "not a finite number";
    `parse_source(b"sim")` as an "empty source"; `read_foreign(columns=[1, 2, 3])` a TypeError."""
    from gyrofilter import GyroFilter
    from gyrofilter.errors import RecordingError
    from gyrofilter.recording import Recording, iter_recording, write_recording
    from gyrofilter.recording.foreign import read_foreign
    from gyrofilter.sources import parse_source

    path = tmp_path / "r.csv"
    write_recording(path, Recording.from_dps(np.zeros((20, 3)), 100.0))
    sizes = [len(chunk) for chunk in list(iter_recording(path, chunk_rows=np.int64(7)))[1:]]
    assert sum(sizes) == 20 and max(sizes) == 7
    with pytest.raises(SettingsError, match="chunk_rows must be a finite number \\(a whole number\\), got True"):
        next(iter_recording(path, chunk_rows=True))
    zero_d, plain = GyroFilter(sample_rate_hz=100.0), GyroFilter(sample_rate_hz=100.0)
    rates = np.random.default_rng(1).normal(0.5, 0.1, (800, 3))
    out = [(zero_d.update(r, temp_c=np.array(25.0 + i / 100)), plain.update(r, temp_c=25.0 + i / 100)) for i, r in enumerate(rates)]
    assert sum(a is not None for a, _ in out) > 100 and all(np.array_equal(a, b) for a, b in out if a is not None)
    with pytest.raises(SettingsError, match="a source is text .*, got bytes$"):
        parse_source(b"sim")
    foreign = tmp_path / "log.csv"
    foreign.write_text("time_ms,wx,wy,wz\n" + "".join(f"{10 * i},{i},2,3\n" for i in range(50)))
    assert read_foreign(foreign, columns=[1, 2, 3, 4], unit="dps").columns == read_foreign(
        foreign, columns=["1", "2", "3", "4"], unit="dps").columns
    with pytest.raises(RecordingError, match="got the text 'wx'"):
        read_foreign(foreign, columns="wx", unit="dps")


def test_read_foreign_refuses_columns_in_a_set(tmp_path):
    """Attack pass 26: read_foreign(columns={"time_ms", "wx", "wy", "wz"}) took them in the set's
    order, the hash seed's: the time read as a rate, axes swapped, without a word."""
    from gyrofilter.errors import RecordingError
    from gyrofilter.recording.foreign import read_foreign

    foreign = tmp_path / "log.csv"
    foreign.write_text("time_ms,wx,wy,wz\n" + "".join(f"{10 * i},{i},2,3\n" for i in range(50)))
    for columns in ({"time_ms", "wx", "wy", "wz"}, frozenset({2, 3, 4})):
        with pytest.raises(RecordingError, match=r"--columns takes a list .* in order \(time, x, y, z\), got a set"):
            read_foreign(foreign, columns=columns, unit="dps")
