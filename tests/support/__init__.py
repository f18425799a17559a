"""What the tests share: paths, and feeding a filter sample by sample as a live source does.

``plain_filter`` is the plain-way oracle of the paper's filter (``tools/bench.py`` uses it as its
baseline). Helpers that tools need too live in the package: the hidden-effect battery in ``gyrofilter.sim.hidden_effects`` and the
register-level MPU6050 model in ``gyrofilter.sources.mpu6050_model``. ``tool(name)`` loads a script
of ``tools/`` (``tools/docs.py`` for the tests of the documentation).
"""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
RECORDINGS = REPO / "recordings"
SHARED_DATA = REPO.parent / "shared" / "data"  # real recordings beside the repo; tests skip without


def stream(filt, x, temps=None):
    """Feed ``x`` (N, 3) deg/s to ``filt.update`` one sample at a time (with ``temps`` deg C if
    given) and return the (M, 3) rows it emitted."""
    temps = [None] * len(x) if temps is None else np.asarray(temps).tolist()
    rows = [filt.update(tuple(s), t) for s, t in zip(np.asarray(x).tolist(), temps)]
    return np.array([r for r in rows if r is not None]).reshape(-1, 3)


def tool(name):
    """The module ``tools/<name>.py`` (the scripts beside the package are not installed), loaded once."""
    key = f"_tools_{name}"
    if key not in sys.modules:
        spec = importlib.util.spec_from_file_location(key, REPO / "tools" / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[key] = module
        spec.loader.exec_module(module)
    return sys.modules[key]
