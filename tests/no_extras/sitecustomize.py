"""Put this folder on PYTHONPATH to run Python without some installed packages, as an install
without extras sees it: the top-level packages named in $GYROFILTER_BLOCK (comma-separated, e.g.
"matplotlib,numba") cannot be imported.

Python imports ``sitecustomize`` at start-up; this one puts a finder first on sys.meta_path
that refuses those packages with the ModuleNotFoundError a missing package raises.
tests/test_core_install.py runs the commands under it; so does .ci/run's core-install stage.
"""
import os
import sys

BLOCKED = frozenset(filter(None, os.environ.get("GYROFILTER_BLOCK", "").split(",")))


class _RefuseBlocked:
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in BLOCKED:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None


sys.meta_path.insert(0, _RefuseBlocked())
