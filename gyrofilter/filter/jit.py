"""Optional numba compilation of the per-block kernels (numba is the ``fast`` extra).

A kernel is a plain function written in the subset of Python that numba compiles. Without
numba it runs interpreted, with the same arithmetic and so the same numbers.
"""
import contextlib
import hashlib
import os
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
    it calls compiled and bound.

    numba's cache is keyed on the source of ``fn``'s own file only: a helper changed in another file
    (an upgrade that changes gyrofilter.filter.hold but not adaptive_kalman) would load the kernel
    compiled with the old helper. The compiled function's name carries :func:`helpers_fingerprint`, so
    the cache file of a kernel is named by its helpers' code too.

    A cache is only a saving of time (:func:`_tolerant`): one that cannot be written (a full disk, a
    file-size limit: numba raised the OSError from deep in the first call, attack pass 47) or read (a
    truncated or damaged file: UnpicklingError, EOFError, pass 48) costs a compile, not the run."""
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
            target.__qualname__ = f"{fn.__qualname__}_{helpers_fingerprint(helpers)}"
        kernel = numba.njit(cache=True)(target)
        _tolerant(kernel._cache, kernel.py_func)
        _compiled[fn] = kernel
    return _compiled[fn]


def _tolerant(cache, py_func):
    """Make numba's ``FunctionCache`` ``cache`` of ``py_func`` take a file it cannot read, or one that holds another function
    (a data file copied over another kernel's: numba does not check, and called it with the wrong arguments,
    attack pass 49), for a miss, removing its index so that the kernel compiled anew is saved in its place; and
    skip a write that fails (ENOSPC, EFBIG, EROFS: numba removes its own partial file, ``_open_for_write``).
    Either way the kernel compiled runs the same."""
    load_overload, save_overload = cache.load_overload, cache.save_overload
    own = py_func.__module__, py_func.__qualname__

    def load(sig, target_context):
        try:
            loaded = load_overload(sig, target_context)
            if loaded is None or (loaded.fndesc.modname, loaded.fndesc.qualname) == own:
                return loaded
        except Exception:  # whatever unpickling a damaged file raises
            pass
        with contextlib.suppress(OSError):
            os.remove(cache._cache_file._index_path)
        return None

    def save(sig, data):
        with contextlib.suppress(OSError):
            save_overload(sig, data)

    cache.load_overload, cache.save_overload = load, save


def helpers_fingerprint(helpers):
    """12 hex digits of the SHA-256 of the compiled helpers' names and the source files that define them
    (the module, not the function: numba freezes the module constants a helper reads, such as kalman's guard
    indices, into the kernel; attack pass 43). A helper's own name carries its helpers' fingerprint, so the
    digest covers every level."""
    digest = hashlib.sha256()
    for name in sorted(helpers):
        py_func = helpers[name].py_func
        with open(py_func.__code__.co_filename, "rb") as source:
            digest.update(f"{name}\0{py_func.__qualname__}\0".encode() + source.read() + b"\0")
    return digest.hexdigest()[:12]
