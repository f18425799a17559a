"""A core install (``pip install gyrofilter``, no extras) runs replay, allan, gap, simulate and report; a
command that needs an extra stops with one line naming it, not a traceback.

The commands run in a subprocess with the optional packages made unimportable
(tests/no_extras/sitecustomize.py), so every configuration checks this without a separate venv.
scipy is a core dependency (gap's fits and every simulation need it) but replay and allan run
without it.
"""
import os
import re
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import pytest

import gyrofilter
from gyrofilter.extras import EXTRA

BLOCKER = Path(__file__).parent / "no_extras"
RECORDING = Path(gyrofilter.__file__).parent / "data" / "mpu6050_static_100s.csv.gz"
MODEL = Path(gyrofilter.__file__).parent / "data" / "mpu6050_model.json"
OPTIONAL = ("matplotlib", "statsmodels", "numba", "allantools", "dask", "distributed")


def _run(args, blocked, cwd):
    """``python -m gyrofilter ARGS`` with the packages in ``blocked`` unimportable."""
    gyrofilter_home = str(Path(gyrofilter.__file__).parent.parent)  # the gyrofilter under test
    env = dict(os.environ, GYROFILTER_BLOCK=",".join(blocked),
               PYTHONPATH=os.pathsep.join([str(BLOCKER), gyrofilter_home]))
    return subprocess.run([sys.executable, "-m", "gyrofilter", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)


def test_the_blocker_makes_a_package_unimportable(tmp_path):
    env = dict(os.environ, GYROFILTER_BLOCK="numpy", PYTHONPATH=str(BLOCKER))
    code = "try:\n    import numpy.linalg\nexcept ModuleNotFoundError as e:\n    print(e.name)"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, cwd=tmp_path)
    assert out.stdout.strip() == "numpy"


@pytest.mark.parametrize("args,blocked", [
    (["replay"], ("scipy",) + OPTIONAL),
    (["replay", "--preset", "recommended"], ("scipy",) + OPTIONAL),
    (["allan", str(RECORDING), "--json", "adev.json"], ("scipy",) + OPTIONAL),
    (["gap", str(RECORDING), "--json", "gap.json", "--sims", "10"], OPTIONAL),
    (["simulate", "--model", str(MODEL), "--duration", "20", "--seed", "1", "--out", "sim.csv.gz"], OPTIONAL),
    (["gap", str(RECORDING), "--fleet", "fleet", "--sims", "10", "--jobs", "2"], OPTIONAL),
], ids=["replay", "replay-recommended", "allan", "gap", "simulate", "fleet"])
def test_core_commands_run_without_the_extras(tmp_path, args, blocked):
    out = _run(args, blocked, tmp_path)
    assert out.returncode == 0, out.stderr
    assert "Traceback" not in out.stderr
    assert "No module named" not in out.stdout + out.stderr  # no analysis silently skipped
    assert out.stdout.strip()


def test_the_report_runs_without_the_extras(tmp_path):
    """Its figures are the package's own SVG: no matplotlib."""
    out = _run(["report", str(RECORDING), "--out", "r.html", "--sims", "10"], OPTIONAL, tmp_path)
    assert out.returncode == 0, out.stderr
    assert "Traceback" not in out.stderr and "No module named" not in out.stderr
    # per axis the filter's trace and the gyro's and the accelerometer's Allan figures (the record has six axes)
    assert (tmp_path / "r.html").read_text(encoding="utf-8").count("<svg ") == 9


@pytest.mark.parametrize("args,package", [
    (["replay", "--plot", "out.png"], "matplotlib"),
    (["allan", str(RECORDING), "--plot", "out.png"], "matplotlib"),
    (["arma", str(RECORDING), "--axis", "z"], "statsmodels"),
    (["replay", "--set", "backend=numba"], "numba"),
    (["allan", str(RECORDING), "--fleet", "fleet", "--scheduler", "tcp://127.0.0.1:9"], "dask"),
], ids=["replay-plot", "allan-plot", "arma", "numba-backend", "fleet-scheduler"])
def test_a_command_that_needs_an_extra_names_it_in_one_line(tmp_path, args, package):
    out = _run(args, OPTIONAL, tmp_path)
    assert out.returncode == 2
    assert out.stderr.strip().splitlines()[-1].endswith(f'needs {package}: pip install "gyrofilter[{EXTRA[package]}]"')
    assert "Traceback" not in out.stderr
    assert not (tmp_path / "out.png").exists()


def test_each_extra_named_in_messages_installs_its_package():
    try:
        requirements = metadata.requires("gyrofilter") or []
    except metadata.PackageNotFoundError:
        pytest.skip("gyrofilter is not installed (no metadata to compare with)")
    declared = set()
    for r in requirements:  # e.g. 'matplotlib; extra == "plot"'
        m = re.match(r'\s*([A-Za-z0-9_.-]+)[^;]*;\s*extra\s*==\s*"(\w+)"', r)
        if m:
            declared.add((m[1].lower(), m[2]))
    for package, extra in EXTRA.items():
        assert (package, extra) in declared, f"pyproject.toml: the [{extra}] extra does not install {package}"
