"""gyrofilter: real-time filtering and error analysis for low-cost MEMS gyroscopes.

Conventions: angular rate in deg/s (names end in ``_dps``), time in s (``_s``), rates in Hz
(``_hz``); three-axis arrays have shape (N, 3) with columns x, y, z. See ``CONTRIBUTING.md``.

    >>> from gyrofilter import GyroFilter
    >>> f = GyroFilter(sample_rate_hz=100.0, calibration_s=2.0)
"""
from .errors import GyroFilterError
from .filter.pipeline import GyroFilter
from .filter.smoother import Smoother, smooth

__version__ = "0.2.0"
__all__ = ["GyroFilter", "GyroFilterError", "Smoother", "__version__", "smooth"]
