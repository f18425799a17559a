"""Named settings for :class:`gyrofilter.GyroFilter` (``preset=``).

``paper`` is the faithful paper-001 pipeline and the default. Explicit keyword arguments
override a preset.
"""

PRESETS = {
    "paper": {},
}
