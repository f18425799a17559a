"""gyrofilter report end to end: its numbers are those of allan --json, gap --json and replay on the
same file with the same options; the file is self-contained; every shipped recording yields one;
--source records first (the real sim source); every bad input is one line and exit 2."""
import contextlib
import gzip
import html
import json
import os
import signal
import subprocess
import sys
import threading
import time
from dataclasses import replace

import numpy as np
import pytest

from gyrofilter.analysis.agreement import compare
from gyrofilter.analysis.gap.report import params_text
from gyrofilter.analysis.clipping import clipped
from gyrofilter.cli import main
from gyrofilter.recording import Recording, read_recording, write_recording
from gyrofilter.units import AXES
from gyrofilter.view.report import FORMAT
from support import REPO, RECORDINGS
from support.report_page import check_shipped_report, parse

STATIC = str(RECORDINGS / "mpu6050_static_100s.csv.gz")
MULTIPOSE = str(RECORDINGS / "mpu6050_multipose_102s.csv.gz")  # saturates: x 12 samples, z 6 (its header says)
#: the one shipped recording whose report the default run makes here besides the 100 s still one and the
#: multipose one (a moving record: no filter); the browser test reports on every shipped recording
FAST = {"mpu6050_rotate_z_24s"}


def without_wall_times(gap_doc):
    """The gap document less the run's own numbers, its wall times (each must be there)."""
    assert gap_doc.pop("runtime_s") > 0 and gap_doc["intervals"].pop("runtime_s", 1.0) > 0


def report(tmp_path, capsys, *args, name="report.html"):
    out = tmp_path / name
    assert main(["report", *args, "--out", str(out)]) == 0
    capsys.readouterr()
    return out, json.loads(parse(out).data)


@pytest.fixture(scope="module")
def static_report(tmp_path_factory):
    """The 100 s still record's report with --sims 10 (its page and its data), made once for the
    tests that read it."""
    out = tmp_path_factory.mktemp("static") / "report.html"
    assert main(["report", STATIC, "--sims", "10", "--out", str(out)]) == 0
    return out, json.loads(parse(out).data)


def test_the_numbers_are_those_of_allan_gap_and_replay(tmp_path, capsys):
    out, data = report(tmp_path, capsys, STATIC, "--seed", "3", "--sims", "10")
    assert data["format"] == FORMAT
    assert main(["allan", STATIC, "--json", str(tmp_path / "adev.json")]) == 0
    assert main(["gap", STATIC, "--json", str(tmp_path / "gap.json"), "--seed", "3", "--sims", "10"]) == 0
    assert main(["replay", STATIC]) == 0
    table = capsys.readouterr().out
    assert data["allan"] == json.loads((tmp_path / "adev.json").read_text())
    want = json.loads((tmp_path / "gap.json").read_text())
    for doc in (data["gap"], want):
        without_wall_times(doc)
    assert data["gap"] == want
    assert data["gap"]["n_simulations"] == 10 and data["options"]["sims"] == 10
    # replay's summary table prints these with 4 decimals
    f = data["filter"]
    for i, axis in enumerate("xyz"):
        row = next(line.split() for line in table.splitlines() if line.startswith(f"  {axis}  "))
        printed = [float(v) for v in row[1:5]] + [float(row[5].rstrip("x")), int(row[6])]
        got = [f["raw_mean_dps"][i], f["raw_std_dps"][i], f["filtered_mean_dps"][i], f["filtered_std_dps"][i]]
        np.testing.assert_allclose(printed[:4], got, atol=5e-5, rtol=0)
        assert printed[4] == pytest.approx(f["std_ratio"][i], abs=5e-3)
        assert printed[5] == f["rejected"][i]
    assert f["preset"] == "recommended" and f"{f['rows_out']} output rows" in table
    # what the page shows is that data: a coefficient of the table, a finding of the gap analysis
    text = out.read_text(encoding="utf-8")
    n = data["allan"]["axes"]["x"]["details"]["arw_dps_per_sqrt_hz"]
    assert f"{n['value']:.4g} [{n['low']:.4g}, {n['high']:.4g}]" in text
    for finding in data["gap"]["findings"]:
        assert f"<b>{finding['effect']}</b> on <b>{finding['axis']}</b>" in text
        # every parameter with the console's digits: enough that an interval's ends differ
        assert html.escape(params_text(finding, sep=" = ")) in text, finding
    # issue 38: two white-noise levels side by side (Allan N, gap ARW) said why; one meaning per word:
    # "quantization" is the Allan Q (deg), the gap's step of the recorded unit is the "LSB step" (deg/s)
    from gyrofilter.view.report import WHITE_LEVELS

    allan_at, gap_at = text.index("<h2>Allan deviation and noise coefficients"), text.index("<h2>What the baseline")
    assert allan_at < gap_at  # "the Allan N above"
    gap_part = text[gap_at:text.index("<script", gap_at)]  # the page's text, not its data block's keys
    assert html.escape(WHITE_LEVELS) in gap_part and "<th>LSB step (deg/s)</th>" in gap_part
    assert "quantization" not in gap_part.replace(html.escape(WHITE_LEVELS), "")
    # issue 35: allan and gap tell one story here; the page says nothing of their agreement
    assert data["allan_and_gap"] == compare(data["allan"], data["gap"]) == []
    assert "<h2>allan and gap</h2>" not in text


def test_where_allan_and_gap_disagree_the_page_says_why(tmp_path, capsys):
    """The 64-s record's z axis: gap's baseline white level holds a 31.6-Hz line that allan's N
    (the tau^-1/2 slope) averages out; the page says so under "allan and gap" (issue 35)."""
    out, data = report(tmp_path, capsys, str(RECORDINGS / "mpu6050_static_64s_set1.csv.gz"), "--sims", "10")
    said = data["allan_and_gap"]
    assert said == compare(data["allan"], data["gap"])
    assert ("z", "N") in [(s["axis"], s["term"]) for s in said]
    text = out.read_text(encoding="utf-8")
    part = text[text.index("<h2>allan and gap</h2>"):text.index("<script", text.index("<h2>allan and gap</h2>"))]
    for s in said:
        assert html.escape(s["text"]) in part
    assert "sinusoid" in next(s["text"] for s in said if s["axis"] == "z")


def test_the_file_is_self_contained(static_report, capsys):
    out, data = static_report
    check_shipped_report(STATIC, data, capsys)
    page = parse(out)
    assert page.scripts == ["application/json"]  # the data block only: nothing runs
    linked = [(tag, k, v) for tag, attrs in page.tags for k, v in attrs.items()
              if k in ("src", "href", "xlink:href", "srcset", "action", "data", "poster")]
    assert linked == []
    assert not [tag for tag, _ in page.tags if tag in ("link", "img", "iframe", "object", "embed", "base")]
    text = out.read_text(encoding="utf-8")
    for word in ("http://", "https://", "@import", "url(http", "url(//"):
        assert word not in text
    # per axis: the filter's trace, the gyro's and the accelerometer's Allan deviation (the shipped record has six axes)
    assert [tag for tag, _ in page.tags].count("svg") == 9
    assert text.count("Allan deviation</title>") == 6 and text.count("accelerometer axis") >= 3
    assert text.count("rate in time</title>") == 3
    assert data["warnings"] == [w for w in data["warnings"] if isinstance(w, str)]


def test_text_from_the_file_cannot_end_the_data_block(tmp_path, capsys):
    """A header value with </script> and markup is shown as text and read back whole."""
    lines = gzip.decompress(open(STATIC, "rb").read()).decode().splitlines(keepends=True)
    lines.insert(1, "# description: </script><script>alert(1)</script> <b>&amp;\n")
    rec = tmp_path / "odd.csv"
    rec.write_text("".join(line for line in lines if not line.startswith("# description: static")))
    out, data = report(tmp_path, capsys, str(rec), "--sims", "10")
    assert data["recording"]["header"]["description"] == "</script><script>alert(1)</script> <b>&amp;"
    assert parse(out).scripts == ["application/json"]


def test_control_characters_of_a_file_name_are_not_written_raw(tmp_path, capsys):
    """Attack pass 12: a file name holding ESC and a line end reached the page raw (escaped for
    HTML, but not for the controls the console and fleet.md escape): written as their escapes."""
    rec = tmp_path / "odd\x1b[31m\nname.csv.gz"
    rec.write_bytes(open(STATIC, "rb").read())
    out, data = report(tmp_path, capsys, str(rec), "--sims", "10")
    text = out.read_text(encoding="utf-8")
    title = text[text.index("<title>"):text.index("</title>")]
    assert "\x1b" not in text and "\n" not in title and "odd\\x1b[31m\\nname" in title
    assert data["recording"]["name"] == str(rec)  # the data block keeps the name as it is (JSON escapes it)


def test_the_shipped_moving_recording_yields_a_report(tmp_path, capsys):
    """Every shipped recording's report, made with the defaults a user gets, is held to
    :func:`~support.report_page.check_shipped_report` in the browser test that opens it
    (``tests/test_cli_report_browser.py``, CI's browser stage); here the one of the moving record
    (no filter), with --sims 10, so that the default run holds a refusal's page too."""
    (name,) = FAST
    path = RECORDINGS / f"{name}.csv.gz"
    _, data = report(tmp_path, capsys, str(path), "--sims", "10")
    assert data["filter"] is None
    check_shipped_report(path, data, capsys)


@pytest.mark.slow  # about a minute (a gap of the moving record); test_the_shipped_moving_recording_yields_a_report
# reports it in the fast run
def test_warnings_clipping_and_a_moving_record(tmp_path, capsys, static_report):
    out, data = report(tmp_path, capsys, MULTIPOSE, "--sims", "10")
    check_shipped_report(MULTIPOSE, data, capsys)
    rec = read_recording(MULTIPOSE)
    clip = clipped(rec.gyro_dps, 250.0, 131.0)
    assert "18 sample(s) at the full scale of +-250 deg/s (x: 12, z: 6)" in clip
    assert clip in data["warnings"]
    assert data["allan"] is None and "--keep-outliers" in data["allan_error"]
    # issue 35: the report says first that the record is not still (the gap analysis models a still gyro)
    assert "does not look static; the gap analysis models a still gyro" in data["warnings"][0]
    # --keep-outliers reaches the report's Allan part: on 15 s of the record around its clipped x samples
    # (the whole record's second report cost the default run half a minute in its bootstrap)
    part = tmp_path / "part.csv"
    write_recording(part, replace(rec, columns={c: v[6000:7500] for c, v in rec.columns.items()}))
    assert main(["allan", str(part)]) == 2 and "--keep-outliers" in capsys.readouterr().err  # it holds the gross errors
    _, kept = report(tmp_path, capsys, str(part), "--sims", "10", "--keep-outliers", name="kept.html")
    assert kept["allan"] is not None and any("does not look static" in w for w in kept["warnings"])
    assert main(["allan", str(part), "--keep-outliers", "--json", str(tmp_path / "a.json")]) == 0
    assert kept["allan"] == json.loads((tmp_path / "a.json").read_text())
    _, still = static_report
    assert not any("full scale" in w or "static" in w for w in still["warnings"])


def test_clipped_counts_samples_at_the_full_scale():
    x = np.zeros((10, 3))
    x[2, 0], x[3, 2], x[4, 1] = 32767 / 131, -32768 / 131, 249.9  # two saturated registers, one sample below
    assert clipped(x, 250.0, 131.0) == ("2 sample(s) at the full scale of +-250 deg/s (x: 1, z: 1): the rate was "
                                        "clipped there (the motion was faster than the sensor's range)")
    assert clipped(x, 250.0) is not None and clipped(np.clip(x, -249.0, 249.0), 250.0, 131.0) is None
    assert clipped(x, None) is None


def test_the_gap_section_says_why_the_covariate_is_named_once():
    """The trial's "wall of text": three temperature findings each ended their evidence with the
    same paragraph on why the covariate is named. The page says it once, above the findings; each
    finding shows its alternative before its evidence, and promises no figure of the readings (the
    page draws none; the shared line said "the figure of the rate in time shows both readings");
    the notes are a list."""
    from gyrofilter.analysis.gap.confound import WHY_THE_COVARIATE
    from gyrofilter.view.report import _gap

    axis = {"bias_dps": 0.1, "arw_dps_per_sqrt_hz": 0.01, "quantization_dps": None}
    findings = [{"effect": "temperature", "axis": a, "params": {"coefficient_dps_per_c": 0.02},
                 "gain": {"before": 15.0, "after": 3.0},
                 "evidence": f"the bias follows the temperature on {a}; so this record cannot tell them apart. "
                             f"{WHY_THE_COVARIATE}; axis {a} as a whole departs most from the baseline simulations in the spike count",
                 "alternatives": [{"effect": "warmup", "params": {"amplitude_dps": 0.06, "tau_s": 840.0}, "D": 0.84}]}
                for a in AXES]
    page = _gap({"options": {}, "warnings": [], "gap": {"n_simulations": 24, "baseline": {"axes": {a: axis for a in AXES}},
                                                 "findings": findings, "notes": ["first note", "second note"],
                                                 "extended_model": None}})
    assert page.count(html.escape(WHY_THE_COVARIATE)) == 1
    assert page.index(html.escape(WHY_THE_COVARIATE)) < page.index("<b>temperature</b>")
    for a in AXES:
        item = page[page.index(f"<b>temperature</b> on <b>{a}</b>"):]
        item = item[:item.index("</li>")]
        assert item.index("Indistinguishable") < item.index("Evidence:")
        assert "figure" not in item  # the page's rate in time is the filter's trace: it shows no reading
        assert f"cannot tell them apart; axis {a} as a whole departs most from the baseline simulations in the spike count." in item
    assert "<h3>Notes</h3><ul><li>first note</li><li>second note</li></ul>" in page


def test_source_records_first_then_reports(tmp_path, capsys):
    out = tmp_path / "unit1.html"
    assert main(["report", "--source", "sim:seed=5", "--duration", "5", "--out", str(out), "--sims", "10"]) == 0
    err = capsys.readouterr().err
    assert "keep the sensor still" in err and "duration reached" in err
    kept = tmp_path / "unit1.csv"  # beside the report
    rec = read_recording(kept)
    assert len(rec) == 500 and rec.header["live_source"] == "sim:seed=5"
    data = json.loads(parse(out).data)
    assert data["recording"]["name"] == str(kept) and data["recording"]["samples"] == 500
    # the recording is the report's: the same report of the kept file
    again = tmp_path / "again.html"
    assert main(["report", str(kept), "--out", str(again), "--sims", "10"]) == 0
    data_again = json.loads(parse(again).data)
    for d in (data, data_again):
        without_wall_times(d["gap"])
    assert data == data_again
    # never overwritten without --force, before anything is recorded
    capsys.readouterr()
    assert main(["report", "--source", "sim", "--duration", "5", "--out", str(tmp_path / "other.html"),
                 "--recording-out", str(kept)]) == 2
    assert "exists (use --force" in capsys.readouterr().err and not (tmp_path / "other.html").exists()


def test_a_recording_without_a_sample_is_refused_and_not_left_behind(tmp_path, capsys):
    """``--duration`` shorter than one sample recorded a header alone, kept it, and failed with the
    gap analysis's complaint about that file (issue 24's hostile pass): now one line naming the
    source and the duration, and no file, nor the folder made for it (it stayed behind, empty)."""
    out = tmp_path / "new" / "unit1.html"
    assert main(["report", "--source", "sim", "--duration", "0.001", "--out", str(out)]) == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last == f"gyrofilter: error: sim: no sample was recorded in --duration 0.001 s; the empty {out.parent / 'unit1.csv'} is not kept"
    assert os.listdir(tmp_path) == []


def test_a_recording_without_a_sample_leaves_the_file_it_would_replace_as_it_was(tmp_path, capsys):
    """``--recording-out OLD --force`` and a ``--duration`` shorter than a sample: nothing was
    recorded, so the user's OLD is kept as it was (it was replaced by the header, then removed)."""
    old = tmp_path / "old.csv"
    old.write_text("precious\n")
    out = tmp_path / "unit1.html"
    assert main(["report", "--source", "sim", "--duration", "0.001", "--out", str(out),
                 "--recording-out", str(old), "--force"]) == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last == f"gyrofilter: error: sim: no sample was recorded in --duration 0.001 s; {old} is left as it was"
    assert old.read_text() == "precious\n" and sorted(os.listdir(tmp_path)) == ["old.csv"]


def test_a_paced_replay_source_records_its_first_seconds(tmp_path, capsys):
    """The real replay:FILE,realtime source: the recording kept is the file's first 20 s, sample for sample."""
    out, kept = tmp_path / "r.html", tmp_path / "first20.csv.gz"
    assert main(["report", "--source", f"replay:{STATIC},realtime,speed=20", "--duration", "20", "--out", str(out),
                 "--recording-out", str(kept), "--sims", "10"]) == 0
    capsys.readouterr()
    got, whole = read_recording(kept), read_recording(STATIC)
    assert len(got) == 2000
    np.testing.assert_array_equal(got.gyro, whole.gyro[:2000])
    assert json.loads(parse(out).data)["recording"]["samples"] == 2000


def test_an_interrupted_recording_is_kept_and_reported(tmp_path):
    """Ctrl-C ends the recording early: the recording reads, the report covers it (exit 0)."""
    out, kept = tmp_path / "r.html", tmp_path / "r.csv"
    proc = subprocess.Popen([sys.executable, "-m", "gyrofilter", "report", "--source", "sim:seed=2", "--out", str(out),
                             "--sims", "10"], cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(REPO)},
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not (kept.exists() and len(read_recording(kept)) >= 400):  # some 4 s of samples
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.2)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 0, err
    assert "stopped by SIGINT" in err
    data = json.loads(parse(out).data)
    assert data["recording"]["samples"] == len(read_recording(kept)) >= 400


@pytest.mark.parametrize("args, words", [
    (["{tmp}/bad.csv"], "bad.csv"),
    (["{tmp}/missing.csv"], "missing.csv"),
    (["{static}", "--out", "{static}", "--force"], "is an input of this command"),
    (["{static}", "--out", "{tmp}/exists.html"], "exists (use --force"),
    (["{static}", "--out", "{tmp}/bad.csv/r.html"], "is a file, not a folder"),
    (["{static}", "--out", "{tmp}/"], "folder"),
    (["{static}", "--source", "sim"], "one of them"),
    ([], "one of them"),
    (["{static}", "--duration", "5"], "--duration records a source first"),
    (["{static}", "--recording-out", "{tmp}/x.csv"], "--recording-out records a source first"),
    (["{static}", "--sims", "9"], "--sims must be in [10, 1000]"),
    (["{static}", "--seed", "-1"], "--seed"),
    (["--source", "sim", "--duration", "0"], "--duration"),
    (["--source", "nosuchkind"], "nosuchkind"),
    (["--source", "sim", "--duration", "5", "--out", "{tmp}/r.csv"], "named for two outputs"),
])
def test_errors_are_one_line_and_exit_2(tmp_path, capsys, args, words):
    (tmp_path / "bad.csv").write_text("this is not a recording\n1,2,3\n")
    (tmp_path / "exists.html").write_text("mine\n")
    argv = [a.format(tmp=tmp_path, static=STATIC) for a in args]
    if "--out" not in argv:
        argv += ["--out", str(tmp_path / "r.html")]
    before = sorted(os.listdir(tmp_path))
    assert main(["report", *argv]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and words in err, err
    assert sorted(os.listdir(tmp_path)) == before  # nothing written, nothing recorded
    assert (tmp_path / "exists.html").read_text() == "mine\n"


def test_missing_out_is_one_line(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["report", STATIC])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "--out" in err


def test_a_stuck_axis_leaves_the_others_allan_results(tmp_path, capsys):
    """Issue 37: one constant axis made the whole Allan part fail ("no Allan deviation")."""
    g = np.random.default_rng(12).normal(0, 0.05, (6000, 3))
    g[:, 0] = -3.3
    path = tmp_path / "stuckx.csv"
    write_recording(path, Recording.from_dps(g, 100.0))
    _, data = report(tmp_path, capsys, str(path), "--sims", "10")
    assert data["allan_error"] is None and sorted(data["allan"]["axes"]) == ["y", "z"]
    assert any(w.startswith("axis x: all 6000 samples equal -3.3 deg/s") and w.endswith("left out of the Allan analysis")
               for w in data["warnings"]), data["warnings"]


def test_a_recording_from_a_pipe_is_refused(tmp_path, capsys):
    """`report <(zcat rec.csv.gz)`: the report reads its recording three times, and a pipe gives its
    text once: the report came out with exit 0, its Allan and filter sections lost to 'empty file'."""
    text = gzip.decompress(open(STATIC, "rb").read())
    read_end, write_end = os.pipe()  # as the shell makes <(...): /dev/fd/N, the pipe's read end

    def feed():
        with contextlib.suppress(BrokenPipeError), open(write_end, "wb") as fh:
            fh.write(text)

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    out = tmp_path / "r.html"
    try:
        rc = main(["report", f"/dev/fd/{read_end}", "--sims", "10", "--out", str(out)])
    finally:
        os.close(read_end)
    writer.join(timeout=10)
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "not a regular file (a pipe?)" in err and len(err.splitlines()) == 1, err
    assert not out.exists()


def test_repeated_rows_are_warned_and_named(tmp_path, capsys):
    """Issue 36: a record with 2 % of its rows repeated (examples/models/repeated_samples.json):
    the report warns with the fraction and the chance level, and its gap section names the effect."""
    from gyrofilter.effects import REPEATED_SAMPLES
    from gyrofilter.sim.model import load_model
    from gyrofilter.sim.simulate import simulate

    path = tmp_path / "rep.csv"
    write_recording(str(path), simulate(load_model(REPO / "examples" / "models" / "repeated_samples.json"), 600.0, seed=4))
    out, data = report(tmp_path, capsys, str(path), "--sims", "10")
    (warning,) = [w for w in data["warnings"] if "repeat the previous row exactly on every axis" in w]
    assert "chance 0." in warning and warning.endswith("N a little high")
    assert data["allan"]["repeated_rows"]["warning"] in warning
    assert [f["axis"] for f in data["gap"]["findings"] if f["effect"] == REPEATED_SAMPLES] == ["xyz"]
    # the extended model's whole-row effect (its top-level key) is in the page's table, not "none" alone
    fraction = data["gap"]["extended_model"][REPEATED_SAMPLES]["fraction"]
    page = out.read_text()
    table = page[page.index("<h3>Extended model</h3>"):]
    assert f"{REPEATED_SAMPLES}: fraction = {fraction:.4g}" in table[:table.index("</p>")]


@pytest.mark.parametrize("sims, samples, ran, said", [
    (None, 10_000, 24, "--sims 24 (gap's default for 10000 samples per axis: 24 up to 200000, fewer above"),
    (None, 400_000, 12, "--sims 12 (gap's default for 400000 samples per axis: 24 up to 200000, fewer above"),
    (10, 10_000, 10, "--sims 10"),
])
def test_the_summary_says_the_number_of_simulations_gap_ran(sims, samples, ran, said):
    """A new user's trial: the options row said "--sims as gap chooses", which a reader of the page
    cannot know. It says the number the analysis ran and, where gap chose it, why."""
    from gyrofilter.view.report import _summary

    data = {"recording": {"name": "r.csv", "samples": samples, "duration_s": samples / 100, "header": {}},
            "options": {"sims": sims, "keep_outliers": False},
            "gap": {"n_simulations": ran, "discrepancy": {"overall_before": 1.0, "not_analysed": {}}}}  # analysed
    page = _summary(data)
    assert "as gap chooses" not in page and html.escape(said) in page, page


def test_a_report_on_a_record_of_no_axis_analysed_does_not_say_the_baseline_explains_it(tmp_path):
    """Attack pass 26: on a record whose every axis is constant (gap exits 2: "no axis analysed") the
    report's gap section said "None: the baseline explains the record within the simulations'
    spread", the reading gap's exit 2 is there to prevent; it says that no axis was analysed, and why;
    and on a record too short for any, its options said "--sims 24" of a gap that ran none."""
    src, out = tmp_path / "const.csv", tmp_path / "r.html"
    write_recording(src, Recording.from_dps(np.full((3000, 3), 0.5), 100.0))
    assert main(["report", str(src), "--out", str(out)]) == 0
    text = " ".join(html.unescape(out.read_text()).split())
    assert "explains" not in text.split("<h3>Findings</h3>")[1].split("</p>")[0]
    assert "None: no axis was analysed (x: constant signal; y: constant signal; z: constant signal)" in text
    write_recording(src, Recording.from_dps(np.array([[1.0, 2, 3], [1.1, 2, 3]]), 100.0))  # too short: no gap run
    assert main(["report", str(src), "--out", str(out), "--force"]) == 0
    text = " ".join(html.unescape(out.read_text()).split())
    assert "None: no axis was analysed (only 2 samples" in text and "--sims 24" not in text
    assert "no gap simulation ran (no axis analysed)" in text


def test_a_record_shorter_than_the_calibration_window_names_the_command_that_takes_the_way_through(tmp_path, capsys):
    """Attack pass 37a: report's warning for a record that ends inside the start-up calibration window
    (1.5 s of a 2-s window) said "give a shorter --calibration-s or a saved calibration (--calibration
    FILE)", replay's way through, which report refuses as unrecognised arguments."""
    g = np.random.default_rng(13).normal(0, 0.05, (150, 3))
    path = str(tmp_path / "short.csv")
    write_recording(path, Recording.from_dps(g, 100.0))
    _, data = report(tmp_path, capsys, path, "--sims", "10")
    said = " ".join(data["filter_error"].split())
    assert "end inside the start-up calibration window" in said, said
    assert said.endswith("report filters with the default settings; replay takes a shorter --calibration-s or a saved "
                         "calibration (--calibration FILE)"), said
    assert main(["replay", path, "--calibration-s", "1"]) == 0


def test_a_record_that_moves_in_the_calibration_window_names_the_commands_that_take_a_saved_calibration(tmp_path, capsys):
    """Attack pass 37a: report's warning for a record that turns in its start-up calibration window
    advised "use a saved calibration of this sensor (GyroFilter(calibration=...), --calibration FILE
    from --save-calibration ...)", and report takes no --calibration (an unrecognised argument)."""
    g = np.random.default_rng(14).normal(0, 0.1, (400, 3)) + np.where(np.arange(400) >= 100, 5.0, 0.0)[:, None]
    path = str(tmp_path / "turned.csv")
    write_recording(path, Recording.from_dps(g, 100.0))
    _, data = report(tmp_path, capsys, path, "--sims", "10")
    said = " ".join(data["filter_error"].split())
    assert said.startswith("calibration: the sensor moved (axis x"), said
    assert said.endswith("keep it still for the first 2.0 s; report filters with the default settings; replay and run "
                         "take a saved calibration (--calibration FILE from --save-calibration on a still recording)"), said


def test_a_record_with_gaps_in_t_says_the_gap_caveat_once_on_the_page(tmp_path, capsys):
    """Attack pass 37d made the caveat of gaps in t the gap report's first note; the page showed it twice,
    under Warnings and under the gap analysis's notes: said once, under Warnings."""
    t = np.concatenate(([0.0], np.cumsum(np.where(np.arange(2999) % 50 == 49, 0.02, 0.01))))
    path = tmp_path / "gaps.csv"
    write_recording(str(path), Recording.from_dps(np.random.default_rng(0).normal(0, 0.1, (3000, 3)), 100.0, t_s=t))
    out, data = report(tmp_path, capsys, str(path), "--sims", "10")
    caveat = "the gap analysis models uniform samples"
    assert any(caveat in note for note in data["gap"]["notes"])  # the document keeps it, as gap --json does
    page = out.read_text().split("<script")[0]
    assert page.count(html.escape(caveat, quote=True)) == 1
