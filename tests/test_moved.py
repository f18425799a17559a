"""The flat layout's import paths still work after the move into wings (gyrofilter/moved.py)."""
import importlib
import subprocess
import sys

import pytest

from gyrofilter.moved import MOVED


@pytest.mark.parametrize("old", sorted(MOVED))
def test_an_old_path_is_the_new_module_itself(old):
    assert importlib.import_module(f"gyrofilter.{old}") is importlib.import_module(f"gyrofilter.{MOVED[old]}")


def test_old_import_forms_in_a_fresh_interpreter():
    code = ("import gyrofilter.analysis.allan, gyrofilter.analysis.allan as new\n"
            "from gyrofilter import simulate, evaluate as E\n"
            "from gyrofilter.analysis.gap import analyse_gap\n"
            "import gyrofilter.sim.simulate as s2, gyrofilter.evaluation.evaluate as e2, gyrofilter.analysis.gap as g2\n"
            "assert gyrofilter.analysis.allan is new and simulate is s2 and E is e2 and analyse_gap is g2.analyse_gap\n"
            "assert new.__name__ == 'gyrofilter.analysis.allan' and new.__spec__.name == 'gyrofilter.analysis.allan'\n")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_a_name_that_never_existed_is_still_an_import_error():
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("gyrofilter.no_such_module")
