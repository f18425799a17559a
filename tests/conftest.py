"""What pytest sets up for every test: ``tests/`` on ``sys.path``, so that ``from support import ...``
(the shared helpers of ``tests/support/``) works under any ``--import-mode``, not only pytest's
default one that happens to put each test file's folder first."""
import sys
from pathlib import Path

TESTS = str(Path(__file__).resolve().parent)
if TESTS not in sys.path:
    sys.path.insert(0, TESTS)
