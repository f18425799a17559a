"""The documentation cannot go stale: every table and number in README.md and docs/*.md that a
command or tool produces is a block that ``tools/docs.py`` writes, and these tests hold the
committed text to what the code gives now.

* fast blocks (command outputs on shipped recordings, the settings and presets, tables rendered
  from the committed artefacts) are regenerated and compared in full;
* slow blocks (benchmarks, batteries, long analyses) must be there and name their tool; where a
  block has a check, a cheap deterministic part is recomputed (timings are never checked);
* the artefacts the slow commands wrote (``docs/figures/evaluate.json``, ``docs/gap/*.json``) are
  recomputed on one recording and compared;
* every relative link of the pages reaches an existing file and, with ``#anchor``, a heading.

After a change that moves a number: ``python tools/docs.py --fast`` (or ``--only NAME``, or the
full run for the slow blocks), then commit the pages.
"""
import os
import re
import shutil
import subprocess
import sys

import pytest

from support import REPO, tool

docs = tool("docs")
FAST = [name for name, b in docs.BLOCKS.items() if not b.slow]
CHECKED_SLOW = [name for name, b in docs.BLOCKS.items() if b.slow and b.check is not None]
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]


def test_every_block_sits_once_in_its_page_under_its_header():
    assert docs.structure_problems() == []


def test_every_block_names_the_command_that_regenerates_it():
    found = docs.committed()
    for name, b in docs.BLOCKS.items():
        (_, _, header), = found[name]
        assert f"`python tools/docs.py --only {name}`" in header
        assert "tools/" in b.source or "gyrofilter" in b.source or "docs/" in b.source, (name, b.source)


@pytest.mark.parametrize("name", FAST)
def test_fast_block_is_what_the_code_writes(name):
    (_, body, _), = docs.committed()[name]
    assert docs.generate(name).strip() == body.strip(), f"run: python tools/docs.py --only {name}"


@pytest.mark.parametrize("name", CHECKED_SLOW)
def test_slow_block_keeps_the_numbers_the_code_gives(name):
    (_, body, _), = docs.committed()[name]
    assert docs.BLOCKS[name].check(body) == []


@pytest.mark.parametrize("name", list(docs.ARTEFACTS))
def test_artefact_is_what_the_code_computes(name):
    assert docs.ARTEFACTS[name].check() == []


def test_check_lists_what_differs(tmp_path, monkeypatch):
    """``--check`` names a block whose committed text was edited by hand."""
    page = tmp_path / "settings.md"
    text = (REPO / "docs" / "settings.md").read_text(encoding="utf-8").replace("| `block_len` | 5 |", "| `block_len` | 6 |")
    page.write_text(text, encoding="utf-8")
    monkeypatch.setattr(docs, "ROOT", tmp_path)
    monkeypatch.setattr(docs, "PAGES", [page])
    monkeypatch.setitem(docs.BLOCKS, "settings", docs.dataclasses.replace(docs.BLOCKS["settings"], page="settings.md"))
    monkeypatch.setitem(docs.BLOCKS, "presets", docs.dataclasses.replace(docs.BLOCKS["presets"], page="settings.md"))
    problems = docs.check(["settings", "presets"])
    assert any(p.startswith("settings (settings.md): differs") for p in problems)
    assert not any(p.startswith("presets") for p in problems)


# ---------------------------------------------------------------------------------------------
# links between the pages


def slug(heading):
    """GitHub's anchor of a Markdown heading."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading.strip())  # a link in a heading: its text
    return re.sub(r"[^\w\- ]", "", text.lower()).replace(" ", "-")


def anchors(path):
    """The anchors of the headings of ``path`` (a repeated heading gets -1, -2, ... as on GitHub)."""
    seen, out = {}, set()
    for heading in re.findall(r"^#+ (.*)$", _without_code(path.read_text(encoding="utf-8")), re.M):
        base = slug(heading)
        n = seen.get(base, 0)
        out.add(base if n == 0 else f"{base}-{n}")
        seen[base] = n + 1
    return out


def _without_code(text):
    return re.sub(r"^```.*?^```", "", text, flags=re.M | re.S)


def links(path):
    """The relative links and images of a page, outside code blocks and inline code."""
    text = re.sub(r"`[^`\n]*`", "", _without_code(path.read_text(encoding="utf-8")))
    return [t for t in re.findall(r"\]\(([^)\s]+)\)", text) if not re.match(r"[a-z]+:", t)]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_relative_link_reaches_a_file_and_a_heading(page):
    bad = []
    for target in links(page):
        file, _, anchor = target.partition("#")
        dest = (page.parent / file).resolve() if file else page
        if not dest.exists():
            bad.append(f"{target}: no file {dest}")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            bad.append(f"{target}: no heading #{anchor} in {dest.relative_to(REPO)}")
    assert bad == []


def test_the_readme_set_up_section_runs_the_main_job_and_the_tests_word_for_word():
    """.ci/run runs the second sh block of "## Set up and run" as the test command, word for word;
    the first filters a recording that ships in recordings/."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    section = re.search(r"^## Set up and run\n(.*?)(?=^## )", readme, re.M | re.S).group(1)
    blocks = re.findall(r"^```sh\n(.*?)^```", section, re.M | re.S)
    assert len(blocks) == 2
    assert blocks[1].strip() == ('python3 -m venv .venv && . .venv/bin/activate && pip install -e ".[test,fast,stats]" '
                                 "&& python -m pytest")
    recording = re.search(r"gyrofilter replay (recordings/\S+\.csv\.gz)$", blocks[0].strip())
    assert recording and (REPO / recording.group(1)).is_file()
    assert "python3 -m venv .venv && . .venv/bin/activate && pip install" in blocks[0]
    assert '"## Set up and run"' in (REPO / ".ci" / "run").read_text(encoding="utf-8")


def test_the_readme_embedding_example_runs_in_a_folder_of_its_own(tmp_path):
    """The Python block of "### 2. Embed the filter in your code", run as a user runs it: in a
    fresh folder holding the recording it reads, so the calibration file it saves lands there and
    not in the clone (a tracked cal.json was once rewritten by it). Its calibration reads back."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    section = re.search(r"^### 2\. Embed the filter in your code\n(.*?)(?=^### )", readme, re.M | re.S).group(1)
    code = re.search(r"^```python\n(.*?)^```", section, re.M | re.S).group(1)
    paths = re.findall(r'read_recording\("([^"]+)"\)', code)
    assert paths
    for rel in paths:
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(REPO / rel, tmp_path / rel)
    checks = "\nassert g.bias_dps == f.bias_dps and rates.ndim == 2 and rates.shape[1] == 3 and len(rates) > 0\n"
    env = dict(os.environ, PYTHONPATH=str(REPO))
    done = subprocess.run([sys.executable, "-c", code + checks], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert (tmp_path / "cal.json").is_file()
    assert not (REPO / "cal.json").exists()


def test_where_a_page_shows_record_from_the_sim_source_it_says_the_pacing():
    """Issue 39 (trial): ``record --source sim`` records in real time (a 10-minute record takes 10
    minutes) unless the source says ``realtime=0``; a user who met it in docs/simulate.md waited.
    Every mention of it in README.md and docs/ says so within its paragraph."""
    mentions = 0
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for found in re.finditer(r"record\s+--source\s+`?sim\b", text):
            paragraph = text[text.rfind("\n\n", 0, found.start()) + 2:text.find("\n\n", found.end())]
            assert "realtime" in paragraph, f"{page.name}: {text[found.start():found.end() + 40]!r}"
            mentions += 1
    assert mentions >= 3
