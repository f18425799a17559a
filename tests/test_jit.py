"""The numba kernels' cache (gyrofilter.filter.jit): a helper changed in another file is compiled anew."""
import os
import resource
import subprocess
import sys
import textwrap

import pytest

from gyrofilter.filter.jit import numba_available
from support import RECORDINGS

pytestmark = pytest.mark.skipif(not numba_available(), reason="needs numba (the fast extra)")

RUN = textwrap.dedent("""
    import importlib.util, sys
    from gyrofilter.filter import jit

    def load(name, path):
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    helper = load("gyrofilter.filter._test_helper", sys.argv[1] + "/helper.py")
    kernel = load("gyrofilter.filter._test_kernel", sys.argv[1] + "/kernel.py")
    kernel.step = helper.step
    print(jit.choose_kernel(kernel.run, "numba")(1.0))
""")


def _limit_files_to_one_byte():
    resource.setrlimit(resource.RLIMIT_FSIZE, (1, 1))  # Python ignores SIGXFSZ: a write past it is OSError EFBIG


def _kernel_adding_one(tmp_path):
    """A kernel and its helper in ``tmp_path`` (RUN's files): the kernel's answer to 1.0 is 2.0."""
    (tmp_path / "kernel.py").write_text("def run(x):\n    return step(x)\n")
    (tmp_path / "helper.py").write_text("def step(x):\n    return x + 1.0\n")


def _answers(tmp_path, helper_source):
    """The kernel's answer to 1.0 in a fresh process, once with each helper source (``helper_source`` formatted
    with the increments 1.0 and 2.0), the kernel's own file unchanged."""
    (tmp_path / "kernel.py").write_text("def run(x):\n    return step(x)\n")
    answers = []
    for increment in ("1.0", "2.0"):
        (tmp_path / "helper.py").write_text(helper_source.format(increment=increment))
        done = subprocess.run([sys.executable, "-c", RUN, str(tmp_path)], capture_output=True, text=True, check=True)
        answers.append(float(done.stdout))
    return answers


def test_a_kernel_is_compiled_anew_when_a_helper_in_another_file_changes(tmp_path):
    """As after an upgrade that changed gyrofilter.filter.hold but not adaptive_kalman: numba's cache is keyed on
    the kernel's own file, and served the kernel compiled with the old helper (seen: the rest model's old trend
    test after hold.trend_free changed)."""
    assert _answers(tmp_path, "def step(x):\n    return x + {increment}\n") == [2.0, 3.0]
    assert any((tmp_path / "__pycache__").glob("*.nbi"))  # the cache was used, not bypassed


def test_a_kernel_is_compiled_anew_when_a_constant_its_helper_reads_changes(tmp_path):
    """numba freezes a module constant a helper reads into the kernel; the helper's own source does not change
    (attack pass 43: kalman.guard reads kalman's GUARD_RUN)."""
    assert _answers(tmp_path, "STEP = {increment}\n\n\ndef step(x):\n    return x + STEP\n") == [2.0, 3.0]


def test_a_cache_that_cannot_be_written_costs_the_compile_not_the_run(tmp_path):
    """A file-size limit or a full disk under numba's cache: the first run's kernel still runs (attack pass 47:
    ``replay --save-calibration`` failed with a bare ``[Errno 27] File too large`` from numba's cache write)."""
    _kernel_adding_one(tmp_path)
    done = subprocess.run([sys.executable, "-c", RUN, str(tmp_path)], capture_output=True, text=True,
                          preexec_fn=_limit_files_to_one_byte)
    assert (done.returncode, done.stdout.strip(), done.stderr) == (0, "2.0", "")
    assert not [p for p in (tmp_path / "__pycache__").glob("*") if p.stat().st_size > 1]  # nothing half written kept


@pytest.mark.parametrize("pattern, size", [("*.nbi", 10), ("*.nbi", 0), ("*.nbc", 100)])
def test_a_damaged_cache_is_compiled_anew_and_saved_again(tmp_path, pattern, size):
    """Attack pass 48: a truncated index or data file of numba's cache ended the command with a traceback
    (``UnpicklingError: pickle data was truncated``, ``EOFError``). It is a miss: compiled anew, saved again."""
    _kernel_adding_one(tmp_path)
    answers = []
    for damage in (False, True, False):
        if damage:
            for path in (tmp_path / "__pycache__").glob(pattern):
                with open(path, "r+b") as cut:
                    cut.truncate(size)
        done = subprocess.run([sys.executable, "-c", RUN, str(tmp_path)], capture_output=True, text=True)
        answers.append((done.returncode, done.stdout.strip(), done.stderr))
        sizes = {p.name: p.stat().st_size for p in (tmp_path / "__pycache__").glob("*.nb[ic]")}
    assert answers == [(0, "2.0", "")] * 3
    assert sizes and min(sizes.values()) > size  # saved whole again


def test_a_cache_file_of_another_kernel_is_compiled_anew(tmp_path):
    """Attack pass 49: a data file copied over another kernel's loads without complaint (numba does not check
    whose it is) and was called with the wrong arguments (``TypeError: recent_mean expected 3 arguments, got
    25``). As a user meets it: ``replay`` with the default filter, the kernels' cache in NUMBA_CACHE_DIR."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    replay = [sys.executable, "-m", "gyrofilter", "replay", str(RECORDINGS / "mpu6050_static_100s.csv.gz")]
    outputs = []
    for swap in (False, True, False):
        if swap:
            (kernel,), (other,) = (tmp_path / "cache").rglob("adaptive_kalman.*.nbc"), (tmp_path / "cache").rglob("hold.recent_mean*.nbc")
            kernel.write_bytes(other.read_bytes())
        done = subprocess.run(replay, capture_output=True, text=True, env=env)
        outputs.append((done.returncode, done.stdout, done.stderr))
    assert outputs[0][0] == 0 and outputs == [outputs[0]] * 3
    assert kernel.read_bytes() != other.read_bytes()  # saved again, its own
