"""What to do about a gap report's findings: the notes that end its ``notes`` (docs/gap.md, "Start here",
3.): a named temperature comes with the filter's setting that removes it (:func:`compensation_hint`), a named
line with what it most often is and what the filter needs (:func:`mount_hint`)."""
from ...effects import BY_NAME, TEMPERATURE
from ...filter.averaging import PAPER_Q_DPS
from ...filter.presets import VIBRATION_RANGE_K
from ...filter.settings import MAX_TEMP_COEFFICIENT_DPS_PER_C
from ...units import AXES

#: a line's peak in deg/s from its size parameter: a tone's amplitude, a shock's size, about 3 rms of a band of noise
_PEAK = {"amplitude_dps": 1.0, "shock_dps": 1.0, "rms_dps": 3.0}


def compensation_hint(findings):
    """What to do with a named temperature: the filter subtracts c (T - T0) per axis (its setting
    ``temp_coefficient_dps_per_c``, :class:`gyrofilter.filter.settings.FilterSettings`), the
    coefficients the gap found (0 on an axis without one), as printed; a coefficient beyond the
    setting's +-:data:`~gyrofilter.filter.settings.MAX_TEMP_COEFFICIENT_DPS_PER_C` (which the filter
    refuses) is said instead; [] without a named temperature."""
    found = {f["axis"]: float(f"{f['params']['coefficient_dps_per_c']:.4g}") for f in findings if f["effect"] == TEMPERATURE}
    if not found:
        return []
    beyond = ", ".join(f"{a}: {c:g}" for a, c in found.items() if abs(c) > MAX_TEMP_COEFFICIENT_DPS_PER_C)
    if beyond:
        return [f"the named temperature's coefficient ({beyond}) is beyond the +-{MAX_TEMP_COEFFICIENT_DPS_PER_C:g} deg/s "
                "per deg C the filter takes (--set temp_coefficient_dps_per_c): is the temp column in deg C, and does "
                "it vary enough to measure it?"]
    values = ",".join(f"{found.get(a, 0.0):g}" for a in AXES)
    return [f"the filter removes the named temperature effect: replay or run with --set temp_coefficient_dps_per_c="
            f"{values} (deg/s per deg C, x,y,z; the recording's temp column, or the sensor's, gives T)"]


def mount_hint(findings, q_dps=PAPER_Q_DPS):
    """A note per axis with a named line (an effect of kind ``line``: a sinusoid, a narrow band, a resonance, a
    ringing, a wandering tone): a vibration or a resonance of the mount, not the sensor's noise; and where the
    line swings by more than the filter's gross-error threshold q (``q_dps``, the default filter's
    ``outlier_q_dps``) within a block, 2 x its peak (:data:`_PEAK`), paper 001's rule takes its extremes for
    gross errors and the block means of what is left are biased (a still sensor under 3 deg/s at 20 Hz read
    -0.74 deg/s through it): the default filter's q follows the swing (``outlier_range_k``,
    gyrofilter.filter.threshold), the paper preset's does not: the settings that keep it there; [] without a line."""
    notes = []
    for a in AXES:
        lines = [f for f in findings if f["axis"] == a and BY_NAME[f["effect"]].kind == "line"]
        if not lines:
            continue
        where = ", ".join(f"{f['effect']} at {f['params'].get('frequency_hz', f['params'].get('center_hz', 0.0)):.3g} Hz"
                          for f in lines)
        swing = max(2 * _PEAK[BY_NAME[f["effect"]].defining] * f["params"][BY_NAME[f["effect"]].defining] for f in lines)
        text = (f"axis {a}: the line(s) named ({where}) are most often a vibration or a resonance of the mount, not "
                "the sensor's noise: mount it firmly, away from fans and motors")
        if swing > q_dps:
            text += (f"; they swing by about {swing:.2g} deg/s, more than paper 001's gross-error threshold q = "
                     f"{q_dps:g} deg/s: the default filter's q follows the swing, but --preset paper would take their "
                     f"extremes for gross errors and bias the rows: with it add --set outlier_range_k={VIBRATION_RANGE_K:g} "
                     f"(or --set outlier_q_dps={swing * 1.5:.2g})")
        notes.append(text)
    return notes
