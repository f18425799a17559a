"""Another tool's gyro log as a recording of format v1 (``gyrofilter convert``): :func:`read_foreign`
(:mod:`.reader`: the text, the time and gyro columns), :mod:`.stamps` (its time column's stamps and unit),
:mod:`.extras` (its temperature and accelerometer columns), :mod:`.comments` (its comment lines before the first
data row)."""
from .extras import ACCEL_UNIT_CHOICES, TEMP_UNITS
from .stamps import TIME_UNITS
from .reader import Foreign, read_foreign

__all__ = ["ACCEL_UNIT_CHOICES", "TEMP_UNITS", "TIME_UNITS", "Foreign", "read_foreign"]
