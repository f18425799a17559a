"""docs/formats.md is the one statement of the formats: its examples must run through the code."""
import json
import re

import numpy as np
import pytest

from gyrofilter.cli import main
from gyrofilter.effects import BY_NAME
from gyrofilter.filter.calibration import Calibration
from gyrofilter.analysis.noise.export import JSON_KEY
from gyrofilter.recording import read_recording
from gyrofilter.sim.model import EFFECTS, validate_model
from gyrofilter.sim.simulate import simulate
from gyrofilter.sources import KINDS
from support import REPO, tool
from support.report_page import parse

ROOT = REPO
DOC = (ROOT / "docs" / "formats.md").read_text(encoding="utf-8")


def section(number):
    """The text of section ``number`` ("## 3. ...") of docs/formats.md."""
    match = re.search(rf"^## {number}\. .*?(?=^## |\Z)", DOC, re.M | re.S)
    assert match, f"docs/formats.md has no section {number}"
    return match.group(0)


def example(number, language):
    blocks = re.findall(rf"^```{language}\n(.*?)^```", section(number), re.M | re.S)
    assert blocks, f"section {number} has no ```{language} example"
    return blocks[0]


def table_rows(text):
    """First cell -> the whole row, for the Markdown table rows of ``text``."""
    rows = {}
    for line in text.splitlines():
        if line.startswith("| ") and not line.startswith("|---"):
            rows[line.split("|")[1].strip()] = line
    return rows


def test_recording_example_parses(tmp_path):
    path = tmp_path / "formats.csv"
    path.write_text(example(1, "text"), encoding="utf-8")
    rec = read_recording(path)
    assert rec.warnings == []
    assert rec.sample_rate_hz == 100.0 and rec.gyro_unit == "lsb" and rec.lsb_per_dps == 131.0
    assert rec.header["any_other_key"] == "free text"
    assert list(rec.columns) == ["t", "gx", "gy", "gz", "temp"]
    assert np.allclose(rec.t_s, [0.0, 0.01, 0.04]) and np.allclose(rec.gyro_dps[0], np.array([12, -3, 40]) / 131)
    assert [text for _, text in rec.notes] == ["gap: 2 samples lost before t=0.04 s"]


def test_six_axis_recording_example_parses(tmp_path):
    blocks = re.findall(r"^```text\n(.*?)^```", section(1), re.M | re.S)
    six = next(block for block in blocks if "accel_unit" in block)
    path = tmp_path / "six.csv"
    path.write_text(six, encoding="utf-8")
    rec = read_recording(path)
    assert rec.accel_unit == "lsb" and rec.lsb_per_g == 16384.0 and list(rec.columns)[-3:] == ["ax", "ay", "az"]
    np.testing.assert_allclose(rec.accel_mps2[0], np.array([-120, 88, 16390]) * 9.80665 / 16384)
    assert "9.80665" in section(1) and "`accel_unit`" in section(1) and "`lsb_per_g`" in section(1)


def test_model_example_validates_and_runs():
    model = json.loads(example(2, "json"))
    spec, warnings = validate_model(model)
    assert warnings == []
    assert [e["effect"] for a in "xyz" for e in spec["axes"][a]["effects"]] == ["temperature", "sinusoid", "gauss_markov"]
    rec = simulate(model, 2.0, seed=1)
    assert len(rec) == 200 and rec.temp_c is not None


def test_effect_table_lists_every_effect_with_its_parameters():
    effects = {name.strip("`"): row for name, row in table_rows(section(2)).items()
               if name.startswith("`") and row.count("|") == 5}  # the effect table has 4 columns
    assert set(effects) == set(EFFECTS)
    for name, (required, optional) in EFFECTS.items():
        cells = effects[name].split("|")
        for param in required:
            assert f"`{param}`" in cells[3], (name, param)
        for param in optional:
            assert f"`{param}`" in cells[4], (name, param)


def test_gap_example_findings_use_the_effect_table():
    report = json.loads(example(3, "json"))
    for key in ("recording", "sample_rate_hz", "duration_s", "baseline", "findings", "extended_model"):
        assert key in report
    for finding in report["findings"]:
        required, optional = EFFECTS[finding["effect"]]
        assert set(required) <= set(finding["params"]) <= set(required) | set(optional)
        assert finding["axis"] in "xyz" and {"metric", "before", "after"} <= set(finding["gain"])


def test_gap_alternatives_example_uses_the_effect_table():
    blocks = re.findall(r"^```json\n(.*?)^```", section(3), re.M | re.S)
    finding = json.loads(next(b for b in blocks if '"alternatives": [{' in b))
    assert finding["alternatives"]
    for entry in [finding] + finding["alternatives"]:
        required, optional = EFFECTS[entry["effect"]]
        assert set(required) <= set(entry["params"]) <= set(required) | set(optional)
    assert {"effect", "params", "D", "in_place_of"} == set(finding["alternatives"][0])
    assert "`alternatives`" in section(3)


def test_gap_example_intervals_follow_the_parameters():
    """Every parameter of a finding and of the baseline has its [low, high]; the intervals block
    is in the example and in the key table."""
    report = json.loads(example(3, "json"))
    for finding in report["findings"]:
        assert set(finding["params_ci95"]) == set(finding["params"])
        assert all(low < high for low, high in finding["params_ci95"].values())
    for axis in report["baseline"]["axes"].values():
        for name, (low, high) in axis.get("params_ci95", {}).items():
            assert name in axis and low < high
    assert {"confidence", "bootstrap_runs", "method"} <= set(report["intervals"])
    assert "`intervals`" in table_rows(section(3))


def test_gap_uncertain_example_has_the_entry_shape_of_the_code():
    """The example of an ``uncertain`` entry: the keys the pipeline writes, the parameters of the
    effect table, the defining parameter not determined (null); ``uncertain`` in the example
    report and in the key table."""
    blocks = re.findall(r"^```json\n(.*?)^```", section(3), re.M | re.S)
    entry = json.loads(next(b for b in blocks if '"why"' in b))
    assert set(entry) == {"effect", "axis", "params", "params_ci95", "why"}
    required, optional = EFFECTS[entry["effect"]]
    assert set(required) <= set(entry["params"]) <= set(required) | set(optional)
    assert set(entry["params_ci95"]) == set(entry["params"])
    assert entry["params_ci95"][BY_NAME[entry["effect"]].defining] is None
    assert json.loads(example(3, "json"))["uncertain"] == [] and "`uncertain`" in table_rows(section(3))


def test_allan_example_uses_the_coefficient_keys_of_the_code():
    doc = json.loads(example(4, "json"))
    for axis in doc["axes"].values():
        assert set(axis["coefficients"]) == set(JSON_KEY.values())
        assert len(axis["tau_s"]) == len(axis["adev_dps"])
    for key in JSON_KEY.values():
        assert f"`{key}`" in section(4)


def test_report_example_has_the_keys_of_the_report(tmp_path, capsys):
    doc = json.loads(example(10, "json"))
    out = tmp_path / "r.html"
    assert main(["report", str(ROOT / "recordings" / "mpu6050_static_100s.csv.gz"), "--out", str(out), "--sims", "10"]) == 0
    capsys.readouterr()
    data = json.loads(parse(out).data)
    assert set(doc) == set(data) and doc["format"] == data["format"]
    for key in ("recording", "options", "filter"):
        assert set(doc[key]) == set(data[key]), key


def test_calibration_example_loads(tmp_path):
    path = tmp_path / "cal.json"
    path.write_text(example(5, "json"))
    cal = Calibration.load(path)
    assert cal.bias_dps == (-3.2732, 1.1220, -0.5022) and cal.samples == 200 and cal.temp_c == 25.3


def test_source_table_names_every_key():
    rows = list(table_rows(section(6)).values())[1:]  # after the header row
    for kind, (_, keys) in KINDS.items():
        row = next((r for r in rows if f"`{kind}" in r), None)
        assert row is not None, kind
        for key in keys:
            assert f"`{key}`" in row, (kind, key)


def test_embedding_example_runs(capsys):
    exec(compile(example(7, "python"), "formats.md section 7", "exec"), {})
    bias = eval(capsys.readouterr().out)
    assert np.allclose(bias, [-3.3, 1.1, -0.5], atol=0.05)


@pytest.mark.parametrize("folder", ["gyrofilter", "docs", "examples"])
def test_no_reference_to_the_outside_contract(folder):
    outside = re.compile(r"interfaces\.md|shared" + "/")
    for path in (ROOT / folder).rglob("*"):
        if path.suffix in (".py", ".md", ".json", ".txt") and path.is_file():
            text = path.read_text(encoding="utf-8", errors="replace")
            assert not outside.search(text), f"{path.relative_to(ROOT)} refers to the outside contract"


def test_links_to_formats_md_point_at_its_sections():
    def slug(heading):  # GitHub's anchor of a heading
        return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")

    anchors = {slug(h) for h in re.findall(r"^#+ (.*)$", DOC, re.M)}
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    links = [(page.name, anchor) for page in pages
             for anchor in re.findall(r"formats\.md#([\w\-]+)", page.read_text(encoding="utf-8"))]
    assert len(links) >= 8
    for page, anchor in links:
        assert anchor in anchors, f"{page}: formats.md#{anchor} is not a heading of docs/formats.md"


def test_fleet_table_example_has_the_columns_of_the_code():
    import csv

    from gyrofilter.analysis.fleet.table import COLUMNS

    rows = list(csv.reader(example(9, "text").splitlines()))
    assert rows[0] == list(COLUMNS)
    assert all(len(r) == len(COLUMNS) for r in rows[1:]) and len(rows) == 3
    documented = " ".join(table_rows(section(9)))
    assert all(c in documented or c.rsplit("_", 1)[0] in documented for c in COLUMNS)


def test_section_8_states_every_settings_range_as_the_code_holds_it():
    """The table of the filter settings' ranges, from settings.SETTING_RANGES (written by tools/docs.py)."""
    table = tool("docs").setting_ranges_table()
    assert table.startswith("| setting | range |") and "| `block_len` | [1, 100] whole |" in table
    assert table in section(8)


@pytest.mark.parametrize("row, value", [
    ("any sample rate", lambda u: f"[{u.MIN_SAMPLE_RATE_HZ:g}, {u.MAX_SAMPLE_RATE_HZ:g}] Hz"),
    ("a gyro sample", lambda u: f"±{u.MAX_RATE_DPS:g}"),
    ("a temperature", lambda u: f"[{u.TEMP_RANGE_C[0]:g}, {u.TEMP_RANGE_C[1]:g}] °C"),
    ("a header's rate", lambda u: f"{u.RATE_TOLERANCE * 100:g} %"),
    ("a duration", lambda u: "(0, 10⁹] s" if u.MAX_DURATION_S == 1e9 else "changed"),
])
def test_section_8_states_the_bounds_the_code_holds(row, value):
    from gyrofilter import units

    line = next(ln for ln in section(8).splitlines() if ln.startswith(f"| {row}"))
    assert value(units).replace("-", "−") in line, (value(units), line)


def test_section_8_states_the_sizes_the_code_holds():
    from gyrofilter import inputs, recording
    from gyrofilter.analysis.fleet import runner
    from gyrofilter.sim import model
    from gyrofilter.sources.serial import protocol as serial_protocol

    text = section(8)
    assert recording.MAX_LINE_BYTES == 2 ** 20 and "| a recording's line (data or header) | 1 MiB |" in text
    assert recording.MAX_HEADER_LINES == 1000 and "| 1000 lines, 1 MiB |" in text
    assert f"| a serial line | {serial_protocol.MAX_LINE_BYTES} bytes |" in text
    assert inputs.MAX_JSON_BYTES == 16 * 2 ** 20 and f"| 16 MiB, {inputs.MAX_JSON_DEPTH} levels |" in text
    assert (f"| {model.MAX_EFFECTS_PER_AXIS}; {model.MAX_ARMA_COEFFICIENTS}; {model.MAX_TABLE_POINTS} |"
            in text)
    assert f"| {runner.SCHEDULER_TIMEOUT_S:g} s |" in text


def test_the_glossary_names_each_term_as_the_code_does():
    """Section 12: one row per Allan term, in the model's order, with the code's name, symbol,
    Allan document key and (for an effect) its parameter."""
    from gyrofilter.analysis.noise.model import TERM_SYMBOL, TERMS
    from gyrofilter.effects import BY_NAME
    rows = [line.split("|")[1:-1] for line in section(12).splitlines() if line.startswith("| ") and "---" not in line][1:]
    assert [r[2].strip().strip("`") for r in rows] == list(TERMS)
    for (_, symbol, name, key, param, _), term in zip(rows, TERMS):
        assert symbol.strip() == TERM_SYMBOL[term] and key.strip().strip("`") == JSON_KEY[term]
        if term in BY_NAME:
            assert param.strip().strip("`") == next(iter(BY_NAME[term].required))
