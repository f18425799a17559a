"""The package's layers (CONTRIBUTING.md, "Layout"): each part imports only what the table there
allows, so the core never pulls in a wing and no wing reaches up into the commands."""
import ast
from pathlib import Path

import gyrofilter

#: part -> the parts it may import from (besides itself); "core" is every module at the root
ALLOWED = {"face": {"core", "filter"}, "core": set(), "filter": {"core"}, "sim": {"core"}, "analysis": {"core", "filter", "sim"},
           "evaluation": {"core", "filter", "sim"}, "sources": {"core", "sim"},
           "view": {"core", "filter", "sim", "analysis"},
           "cli": {"core", "filter", "sim", "analysis", "evaluation", "sources", "view"}}


def part_of(dotted):
    """'gyrofilter.analysis.gap.pipeline' -> 'analysis'; ``python -m gyrofilter`` (__main__) -> 'cli'; the
    package's ``__init__`` -> 'face' (the API: GyroFilter, Smoother); a module at its root -> 'core'."""
    parts = dotted.split(".")
    if parts[1:] == ["__main__"]:
        return "cli"
    if parts[1:] == ["__init__"]:
        return "face"
    return parts[1] if len(parts) >= 2 and parts[1] in ALLOWED else "core"


def imports_of(path, root):
    """The gyrofilter names (dotted) that the module at ``path`` imports, relative ones resolved
    against its place under ``root`` (the folder holding the package)."""
    here = list(path.relative_to(root).parts[:-1])
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = here[: len(here) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            out += [f"{module}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            out += [a.name for a in node.names]
    return [m for m in out if m.split(".")[0] == "gyrofilter"]


def violations(package):
    """Lines 'file (part) imports name (part)' for every import that goes up or sideways."""
    root = package.parent
    wrong = []
    for path in sorted(package.rglob("*.py")):
        source = part_of(".".join(path.relative_to(root).with_suffix("").parts))
        for target in imports_of(path, root):
            dest = part_of(target)
            if dest != source and dest not in ALLOWED[source]:
                wrong.append(f"{path.relative_to(root)} ({source}) imports {target} ({dest})")
    return wrong


def test_every_import_goes_down_the_layers():
    wrong = violations(Path(gyrofilter.__file__).parent)
    assert not wrong, "\n".join(wrong)


def test_an_upward_or_sideways_import_is_caught(tmp_path):
    package = tmp_path / "gyrofilter"
    for folder in ("analysis", "cli", "filter", "sources"):
        (package / folder).mkdir(parents=True)
    (package / "filter" / "pipeline.py").write_text("from ..analysis import gap\nfrom .. import units\n")
    (package / "analysis" / "fleet.py").write_text("from ..cli.allan import run\nfrom ..sim.simulate import simulate\n")
    (package / "sources" / "serial.py").write_text("import gyrofilter.analysis.noise.allan\nfrom ..errors import one_line\n")
    assert violations(package) == ["gyrofilter/analysis/fleet.py (analysis) imports gyrofilter.cli.allan.run (cli)",
                                   "gyrofilter/filter/pipeline.py (filter) imports gyrofilter.analysis.gap (analysis)",
                                   "gyrofilter/sources/serial.py (sources) imports gyrofilter.analysis.noise.allan (analysis)"]
