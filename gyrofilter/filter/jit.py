"""Optional numba compilation of the per-block kernels (numba is the ``fast`` extra).

A kernel is a plain function written in the subset of Python that numba compiles. Without
numba it runs interpreted, with the same arithmetic and so the same numbers.
"""
import types

from ..errors import SettingsError
from ..extras import install_hint

_compiled = {}


def numba_available() -> bool:
    try:
        import numba  # noqa: F401
    except ImportError:
        return False
    return True


def choose_kernel(fn, backend):
    """``fn`` compiled by numba for backend "auto" (when installed) or "numba", else ``fn``."""
    if backend == "python":
        return fn
    if not numba_available():
        if backend == "numba":
            raise SettingsError(f"backend='numba' needs numba: {install_hint('fast')}")
        return fn
    return _compile(fn)


def _compile(fn):
    """njit(cache=True) of ``fn``, with the plain functions of this package (gyrofilter.filter) that
    it calls compiled and bound."""
    if fn not in _compiled:
        import numba

        namespace = dict(fn.__globals__)
        helpers = {
            name: _compile(namespace[name])
            for name in fn.__code__.co_names
            if isinstance(namespace.get(name), types.FunctionType) and namespace[name].__module__.startswith(f"{__package__}.")
        }
        target = fn
        if helpers:
            namespace.update(helpers)
            target = types.FunctionType(fn.__code__, namespace, fn.__name__)
        _compiled[fn] = numba.njit(cache=True)(target)
    return _compiled[fn]
