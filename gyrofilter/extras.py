"""Optional packages (the extras in pyproject.toml): import one, or raise naming the extra.

A core install (``pip install gyrofilter``) runs ``replay``, ``record``, ``run``, ``allan``,
``simulate`` and ``gap`` (with ``--fleet``, on local worker processes too); figures, the numba
kernels, ``arma`` and a Dask cluster (``--scheduler``) need an extra. Library code
imports an optional package through :func:`require`, inside the function that uses it.
"""
import importlib

from .errors import MissingExtraError

#: top-level module -> the extra that installs it (tests check this against the package metadata)
EXTRA = {"matplotlib": "plot", "numba": "fast", "statsmodels": "stats", "dask": "cluster"}


def install_hint(extra):
    """The command that installs ``extra``, quoted for every shell."""
    return f'pip install "gyrofilter[{extra}]"'


def require(module, purpose):
    """``importlib.import_module(module)``, or :class:`MissingExtraError` when the optional package
    behind it is not installed: "<purpose> needs <package>: pip install "gyrofilter[<extra>]"".
    """
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as exc:
        package = (exc.name or module).partition(".")[0]
        if package not in EXTRA:
            raise
        raise MissingExtraError(f"{purpose} needs {package}: {install_hint(EXTRA[package])}") from None
