"""The house rules that the code itself can be held to (CONTRIBUTING.md, "Rules the code is held
to"): modules of one concern (at most 600 lines), functions that fit on a screen or two (at
most 120 lines, unless a numba kernel needs the length and a comment above it says so), one name
for a sample rate, no import circle, imports at the top of the module, no private name imported
from another module, and a family of three or more modules in a folder of its own."""
import ast
from pathlib import Path

import gyrofilter
from gyrofilter.effects import REGISTRY

PACKAGE = Path(gyrofilter.__file__).parent
MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 120
KERNEL_MARK = "numba kernel"  # in a comment right above a def: its length is the kernel's
#: third-party packages a function may import where it needs them (optional extras, and the heavy
#: libraries that ``import gyrofilter`` must not load); everything else is imported at the top
LAZY_OK = {"scipy", "statsmodels", "matplotlib", "numba", "dask", "distributed", "serial", "smbus2", "filterpy"}
#: names a sample rate must not have (it is ``sample_rate_hz`` everywhere)
RATE_ALIASES = {"fs", "rate_hz"}
#: an effect's name is spelled through gyrofilter.effects' constants; as a literal in at most this
#: many modules (the registry itself, and where the same word names another thing: the model's
#: temperature profile, a figure, a source option, the `arma` command)
MAX_EFFECT_LITERAL_MODULES = 5
#: former names of the rate random walk, the bias instability and the rate ramp (docs/formats.md,
#: section 12: one name per term)
TERM_ALIASES = {"rrw", "flicker", "ramp"}
#: modules whose names share a prefix up to '_' (``gap_baseline``, ``gap_features``, ...) in one
#: folder: this many make a family that belongs in a folder of its own
FAMILY_SIZE = 3


def modules(package=PACKAGE):
    """(path, source text, syntax tree) of every module of ``package``."""
    for path in sorted(package.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        yield path, text, ast.parse(text)


def _name(path, package):
    return ".".join(("gyrofilter",) + path.relative_to(package).with_suffix("").parts).removesuffix(".__init__")


def long_modules(package=PACKAGE):
    return [f"{p.relative_to(package)}: {len(t.splitlines())} lines" for p, t, _ in modules(package)
            if len(t.splitlines()) > MAX_MODULE_LINES]


def long_functions(package=PACKAGE):
    out = []
    for path, text, tree in modules(package):
        lines = text.splitlines()
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                first = min([node.lineno] + [d.lineno for d in node.decorator_list])
                length = node.end_lineno - first + 1
                above = lines[first - 2] if first >= 2 else ""
                if length > MAX_FUNCTION_LINES and not (above.lstrip().startswith("#") and KERNEL_MARK in above):
                    out.append(f"{path.relative_to(package)}:{node.lineno} {node.name}: {length} lines")
    return out


def rate_aliases(package=PACKAGE):
    """Parameters, dataclass fields and attributes named ``fs`` or ``rate_hz``."""
    out = []
    for path, _, tree in modules(package):
        for node in ast.walk(tree):
            names = []
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                a = node.args
                names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                names = [node.target.id]
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                names = [node.attr]
            out += [f"{path.relative_to(package)}:{node.lineno} {n}" for n in names if n in RATE_ALIASES]
    return out


def _resolve(path, package, node):
    """The gyrofilter modules an import node names (``from . import x``: x when it is a module)."""
    here = _name(path, package).split(".")
    if path.name != "__init__.py":
        here = here[:-1]
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name.split(".")[0] == "gyrofilter"]
    base = here[: len(here) - node.level + 1] if node.level else []
    module = ".".join(base + ([node.module] if node.module else []))
    if module.split(".")[0] != "gyrofilter":
        return []
    out = []
    for a in node.names:
        sub = package.parent.joinpath(*f"{module}.{a.name}".split("."))
        out.append(f"{module}.{a.name}" if sub.with_suffix(".py").exists() or sub.is_dir() else module)
    return out


def import_graph(package=PACKAGE):
    graph = {}
    for path, _, tree in modules(package):
        me = _name(path, package)
        graph[me] = {t for node in ast.walk(tree) if isinstance(node, (ast.Import, ast.ImportFrom))
                     for t in _resolve(path, package, node) if t != me}
    return graph


def import_circles(package=PACKAGE):
    """Every cycle of the module import graph, as 'a -> b -> a' (each reported once)."""
    graph = import_graph(package)
    cycles, seen = [], set()

    def visit(node, trail):
        for nxt in sorted(graph.get(node, ())):
            if nxt in trail:
                cycle = trail[trail.index(nxt):]
                key = frozenset(cycle)
                if key not in seen:
                    seen.add(key)
                    cycles.append(" -> ".join(cycle + [nxt]))
            elif len(trail) < 12:
                visit(nxt, trail + [nxt])

    for start in sorted(graph):
        visit(start, [start])
    return cycles


def imports_in_functions(package=PACKAGE):
    """Imports inside a function of anything but the heavy third-party packages of LAZY_OK."""
    out = []
    for path, _, tree in modules(package):
        for fn in ast.walk(tree):
            if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(fn):
                if isinstance(node, ast.Import):
                    roots = [a.name.split(".")[0] for a in node.names]
                elif isinstance(node, ast.ImportFrom):
                    roots = ["gyrofilter" if node.level else node.module.split(".")[0]]
                else:
                    continue
                out += [f"{path.relative_to(package)}:{node.lineno} {fn.name} imports {r}" for r in roots if r not in LAZY_OK]
    return sorted(set(out))


def private_imports(package=PACKAGE):
    """``from module import _name`` of a gyrofilter module's private name in another module."""
    out = []
    for path, _, tree in modules(package):
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").split(".")[0] == "gyrofilter"):
                out += [f"{path.relative_to(package)}:{node.lineno} imports {a.name}" for a in node.names
                        if a.name.startswith("_") and not a.name.startswith("__")]
    return out


def flat_families(package=PACKAGE):
    """Folders holding FAMILY_SIZE or more modules named ``<prefix>_...`` or ``<prefix>``: a family
    whose prefix stands in for a folder."""
    out = []
    for folder in sorted({p.parent for p, _, _ in modules(package)}):
        stems = [p.stem for p in folder.glob("*.py") if p.stem != "__init__"]
        for prefix in sorted({s.split("_")[0] for s in stems if "_" in s}):
            members = sorted(s for s in stems if s == prefix or s.startswith(prefix + "_"))
            if len(members) >= FAMILY_SIZE:
                out.append(f"{folder.relative_to(package.parent)}: {', '.join(members)}")
    return out


def effect_literals(package=PACKAGE, names=None):
    """Per effect name of the registry, the modules holding it as a string literal (docstrings aside)."""
    names = {e.name for e in REGISTRY} if names is None else set(names)
    where = {n: set() for n in names}
    for path, _, tree in modules(package):
        docs = {id(node.body[0].value) for node in ast.walk(tree)
                if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
                and ast.get_docstring(node, clean=False) is not None}
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and node.value in names and id(node) not in docs:
                where[node.value].add(str(path.relative_to(package)))
    return where


def term_aliases(package=PACKAGE):
    """String literals (docstrings aside) that spell a term by a former alias of :data:`TERM_ALIASES`."""
    return sorted(f"{module}: {name!r}" for name, where in effect_literals(package, TERM_ALIASES).items() for module in where)


def test_no_module_is_over_600_lines():
    assert not long_modules(), "\n".join(long_modules())


def test_no_function_is_over_120_lines_outside_numba_kernels():
    assert not long_functions(), "\n".join(long_functions())


def test_a_sample_rate_is_called_sample_rate_hz():
    assert not rate_aliases(), "\n".join(rate_aliases())


def test_no_import_circle():
    assert not import_circles(), "\n".join(import_circles())


def test_imports_are_at_the_top_but_for_heavy_optional_packages():
    assert not imports_in_functions(), "\n".join(imports_in_functions())


def test_no_private_name_is_imported_from_another_module():
    assert not private_imports(), "\n".join(private_imports())


def test_a_family_of_modules_lives_in_its_own_folder():
    assert not flat_families(), "\n".join(flat_families())


def test_an_effect_name_is_a_literal_in_few_modules():
    wide = {n: sorted(m) for n, m in effect_literals().items() if len(m) > MAX_EFFECT_LITERAL_MODULES}
    assert not wide, wide


def test_a_term_has_one_name():
    assert not term_aliases(), "\n".join(term_aliases())


def test_the_checks_catch_what_they_look_for(tmp_path):
    package = tmp_path / "gyrofilter"
    (package / "cli").mkdir(parents=True)
    (package / "cli" / "a.py").write_text("from . import b\n")
    (package / "cli" / "b.py").write_text("def f(fs, *, rate_hz=1):\n    from .a import x\n    import scipy\n    import json\n")
    body = "\n".join(["    y = 1"] * 121)
    (package / "long.py").write_text(f"def g():\n{body}\n\n# numba kernel: one loop\ndef k():\n{body}\n" + "\n" * 359)
    assert long_modules(package) == ["long.py: 605 lines"]
    assert long_functions(package) == ["long.py:1 g: 122 lines"]
    assert rate_aliases(package) == ["cli/b.py:1 fs", "cli/b.py:1 rate_hz"]
    assert import_circles(package) == ["gyrofilter.cli.a -> gyrofilter.cli.b -> gyrofilter.cli.a"]
    assert imports_in_functions(package) == ["cli/b.py:2 f imports gyrofilter", "cli/b.py:4 f imports json"]
    (package / "cli" / "c.py").write_text("from .a import _hidden, public, __version__\nfrom numpy import _core\n")
    assert private_imports(package) == ["cli/c.py:1 imports _hidden"]
    for name in ("gap.py", "gap_one.py", "gap_two.py", "noise_a.py", "noise_b.py"):
        (package / "cli" / name).write_text("")
    assert flat_families(package) == ["gyrofilter/cli: gap, gap_one, gap_two"]
    (package / "cli" / "d.py").write_text('"""warmup"""\nX = ("warmup", "sinusoid")\n\n\ndef f():\n    """warmup"""\n    return "warmup"\n')
    assert effect_literals(package, ["warmup", "sinusoid", "outliers"]) == {"warmup": {"cli/d.py"}, "sinusoid": {"cli/d.py"},
                                                                            "outliers": set()}
    (package / "cli" / "e.py").write_text('TERMS = ("rrw", "arw")\n')
    assert term_aliases(package) == ["cli/e.py: 'rrw'"]
