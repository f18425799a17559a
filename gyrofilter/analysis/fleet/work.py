"""The per-file work of a fleet run (:mod:`gyrofilter.analysis.fleet`): what ``allan`` or ``gap``
computes of one recording, as plain data that a worker process or a Dask worker returns."""
from __future__ import annotations

import dataclasses
import time

from ...errors import NotStillError, SettingsError, one_line
from ...recording import filtered_words
from ...units import AXES
from ..gap.pipeline import analyse_file
from ..noise.allan import MIN_CLUSTERS
from ..noise.export import kalibr_yaml, to_json
from ..still import characterise_recording


#: how a unit's warning that its imu.yaml was not written (and why) starts (the fleet's summary lists them)
NO_IMU_YAML = "imu.yaml not written: "

#: exceptions that make a file's row "failed": the same as the command line's one-line errors,
#: and running out of memory (a worker with too large a file)
FILE_ERRORS = (OSError, ValueError, MemoryError)


@dataclasses.dataclass(frozen=True)
class FleetSettings:
    """What :func:`analyse_recording` does with each file (picklable, the same for all files).

    ``command``: ``"allan"`` (the Allan part only) or ``"gap"`` (the gap analysis and the Allan
    part). The Allan part uses ``axes``, ``confidence``, ``min_clusters``, ``keep_outliers`` and
    ``kalibr_tau_s`` as ``gyrofilter allan`` does; the gap part ``sims`` as ``gyrofilter gap``.
    A record whose gyro moved is not analysed (skipped, :func:`analyse_recording`) unless
    ``allow_motion``, which also allows its mean rate (a turning gyro's mean is real), as
    ``gyrofilter gap --allow-motion`` does.
    """

    command: str
    axes: tuple | str = AXES  # axis letters, in order: all three, or e.g. "xz" from the command line
    confidence: float = 0.95
    min_clusters: int = MIN_CLUSTERS
    keep_outliers: bool = False
    sims: int | None = None
    kalibr_tau_s: tuple | None = None  # the imu.yaml's range (s), as allan's --kalibr-tau-s; None: the default
    allow_motion: bool = False  # --allow-motion: analyse records whose gyro moved (kept out of the comparison)


def analyse_recording(path, settings):
    """The per-file work of a fleet run: a dict of plain data.

    Keys: ``recording`` (``path``), ``error`` (None, or the one-line reason the file could not be
    analysed), ``skipped`` (True when that reason is that the gyro moved, NotStillError: a record
    the still-sensor analysis refuses, not a failed file), ``warnings`` (sentences),
    ``sample_rate_hz``, ``duration_s``, ``allan`` (the Allan
    document of docs/formats.md section 4, or None), ``kalibr`` (Kalibr's imu.yaml text, or
    None), ``gap`` (the gap report of section 3, or None) and ``runtime_s`` (wall time).

    A unit whose record the imu.yaml's range (``kalibr_tau_s``) does not fit keeps its Allan
    document; ``kalibr`` is None and a warning starting :data:`NO_IMU_YAML` says why.
    With ``settings.command == "gap"`` a failure of the Allan part (gross errors, a record too
    short for two cluster times) leaves ``allan`` None with the reason in ``warnings``, and the
    gap report stands.
    """
    t0 = time.perf_counter()
    result = {"recording": path, "error": None, "skipped": False, "warnings": [], "sample_rate_hz": None,
              "duration_s": None, "allan": None, "kalibr": None, "gap": None}
    try:
        if settings.command == "gap":
            result["gap"] = _gap_report(path, settings, result["warnings"])
            result["sample_rate_hz"] = result["gap"]["sample_rate_hz"]
            result["duration_s"] = result["gap"]["duration_s"]
        try:
            _allan_part(path, settings, result)
        except FILE_ERRORS as exc:
            if settings.command == "allan":
                raise
            result["warnings"].append(f"Allan coefficients not fitted: {one_line(exc)}")
    except FILE_ERRORS as exc:
        reason = "out of memory" if isinstance(exc, MemoryError) else one_line(exc)
        result["error"] = reason if reason.startswith(path) else f"{path}: {reason}"
        result["skipped"] = isinstance(exc, NotStillError)
    result["runtime_s"] = time.perf_counter() - t0
    return result


def _gap_report(path, settings, warnings):
    return analyse_file(path, n_sims=settings.sims, warn=warnings.append, refuse_motion=not settings.allow_motion)[1]


def _allan_part(path, settings, result):
    told = []  # the Allan document's own, as allan --json writes them

    def warn(text):
        told.append(text)
        if text not in result["warnings"]:  # the gap part read the same file and said it already
            result["warnings"].append(text)

    head, results, repeats, accel, accel_left_out = characterise_recording(
        path, axes=settings.axes, confidence=settings.confidence, min_clusters=settings.min_clusters,
        keep_outliers=settings.keep_outliers, warn=warn, skip_constant=True,
        # gap's part judged the motion already
        refuse_motion=settings.command == "allan" and not settings.allow_motion, allow_large_mean=settings.allow_motion)
    sample_rate_hz = head.sample_rate_hz
    kalibr = None
    filtered = filtered_words(head.header)
    if filtered:  # the filter's output is analysed, but its noise is not the sensor's
        result["warnings"].append(f"{NO_IMU_YAML}the recording is {filtered}")
    else:
        try:
            kalibr = kalibr_yaml(results, sample_rate_hz, recording=path, tau_range_s=settings.kalibr_tau_s,
                                 accelerometer=accel, header=head.header, warnings=result["warnings"])
        except SettingsError as exc:  # --kalibr-tau-s beyond this unit's record: its Allan results stand
            result["warnings"].append(NO_IMU_YAML + one_line(exc))
    for prefix, sensor in (("", results), ("a", accel or {})):
        for axis, r in sensor.items():
            result["warnings"].extend(text if text.startswith("axis ") else f"axis {prefix}{axis}: {text}"
                                      for text in r.warnings)
    result["allan"] = to_json(results, sample_rate_hz, recording=path, duration_s=head.rows / sample_rate_hz,
                              repeated_rows=repeats, accelerometer=accel, accelerometer_left_out=accel_left_out,
                              warnings=told)
    result["kalibr"] = kalibr
    result["sample_rate_hz"], result["duration_s"] = sample_rate_hz, head.rows / sample_rate_hz


def failed(path, reason):
    """The result of a file whose work never ran or never returned (a glob that matched nothing,
    a worker that died): its ``error`` names the file ``path`` and ``reason``."""
    return {"recording": path, "error": f"{path}: {reason}", "skipped": False, "warnings": [], "sample_rate_hz": None,
            "duration_s": None,
            "allan": None, "kalibr": None, "gap": None, "runtime_s": None}
