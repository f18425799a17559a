"""The import paths of modules that moved into the wings (issue 13) keep working.

``import gyrofilter.analysis.allan`` gives the module ``gyrofilter.analysis.allan`` itself (the same
object, not a copy), so code written against 0.1's flat layout runs unchanged. A finder on
``sys.meta_path`` answers only for the names in :data:`MOVED`; the module is imported under its
new name and put into ``sys.modules`` under the old one as well.
"""
import importlib
import importlib.abc
import importlib.util
import sys

#: old name under gyrofilter -> new dotted path under gyrofilter
MOVED = {name: f"{wing}.{name}" for wing, names in {
    "analysis": ["allan", "noise_model", "arma", "bias_kf", "gmwm", "gap", "detectors", "gap_report",
                 "plots_allan", "fleet"],
    "sim": ["simulate", "noise_terms", "profiles", "hidden_effects"],
    "evaluation": ["evaluate", "reference"]}.items() for name in names}


class MovedModuleFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``gyrofilter.<old>`` for each old name of :data:`MOVED` and loads the new module."""

    def find_spec(self, fullname, path=None, target=None):
        """A spec loaded by this finder for ``gyrofilter.<old name>`` of :data:`MOVED`, else None."""
        package, _, name = fullname.rpartition(".")
        if package == __package__ and name in MOVED:
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        """None: the import system makes a plain placeholder module for ``spec``."""
        return None  # a placeholder; exec_module puts the real module in its place

    def exec_module(self, module):
        """Import the module's new name and put it into ``sys.modules`` under the old name."""
        real = importlib.import_module(f"{__package__}.{MOVED[module.__name__.rpartition('.')[2]]}")
        sys.modules[module.__name__] = real  # the import system returns what sys.modules holds


def install():
    """Put the finder on ``sys.meta_path`` once (``import gyrofilter`` does)."""
    if not any(isinstance(f, MovedModuleFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, MovedModuleFinder())  # before path finders: a stale copy cannot shadow it
