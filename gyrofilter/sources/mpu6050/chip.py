"""What an MPU-6050 is and how it is set, without any bus traffic: the WHO_AM_I table of the chip
and its relatives (:data:`CHIPS`), the full scales (GYRO_CONFIG.FS_SEL, ACCEL_CONFIG.AFS_SEL), the digital low-pass
filter (CONFIG.DLPF_CFG) and the sample-rate divider (SMPLRT_DIV) for a requested rate, and the
FIFO's frames: their layout, their decoding into a source's columns and the temperature formula.

Datasheet sections: InvenSense RM-MPU-6000A-00 rev 4.2 (register map, :mod:`.registers`)
and PS-MPU-6000A-00 rev 3.4 (product specification).
"""
import functools

import numpy as np

from ...errors import SettingsError
from ...recording import ACCEL_COLUMNS, GYRO_COLUMNS
from . import registers as R
from ...units import check_sample_rate_hz

# WHO_AM_I value -> (name, FIFO bytes, temperature LSB per degC, temperature offset degC, usable)
# "usable" = shares the MPU-6050 gyro/FIFO registers, so allow_chip may let it through.
# MPU-6500 family: PS-MPU-6500A-01 (FIFO 512 bytes, T = TEMP_OUT/333.87 + 21);
# MPU-9250: PS-MPU-9250A-01; MPU-9255 reads 0x73; ICM-20689: DS-000143 (WHO_AM_I 0x98).
CHIPS = {
    0x68: ("MPU6050", R.FIFO_SIZE_BYTES, R.TEMP_LSB_PER_C, R.TEMP_OFFSET_C, True),
    0x70: ("MPU6500 (also found on boards sold as MPU6050 or MPU9250)", 512, 333.87, 21.0, True),
    0x71: ("MPU9250", 512, 333.87, 21.0, True),
    0x73: ("MPU9255", 512, 333.87, 21.0, True),
    0x74: ("MPU6515", 512, 333.87, 21.0, True),
    # clones: FIFO size unknown, assume the smaller 512 bytes so that an overflow is never missed
    0x72: ("MPU6050 clone (WHO_AM_I 0x72, sold as MPU6050/GY-521)", 512, 340.0, 36.53, True),
    0x98: ("ICM-20689 or a clone sold as MPU6050/MPU6500", 512, 326.8, 25.0, True),
    0x12: ("ICM-20602", 512, 326.8, 25.0, True),
    0x11: ("ICM-20600", 512, 326.8, 25.0, True),
    0xAF: ("ICM-20608", 512, 326.8, 25.0, True),
    0x19: ("MPU6886", 512, 326.8, 25.0, True),
    0x47: ("ICM-42688-P (different register map)", 0, 1.0, 0.0, False),
    0x42: ("ICM-42605 (different register map)", 0, 1.0, 0.0, False),
}
MPU6050_ID = 0x68


def chip_ids(allow_chip):
    """allow_chip as a set of ids: None -> {}, 0x70 / "0x70" -> {0x70}, a collection -> its ids."""
    if allow_chip is None or allow_chip is False:
        return set()
    if isinstance(allow_chip, (int, str)):
        allow_chip = [allow_chip]
    try:
        if any(isinstance(c, str) and not c.isascii() for c in allow_chip):  # int() takes other scripts' digits
            raise ValueError(allow_chip)
        return {int(c, 0) if isinstance(c, str) else int(c) for c in allow_chip}
    except (TypeError, ValueError):
        raise SettingsError(f"allow_chip={allow_chip!r}: expected a WHO_AM_I value such as 0x70, a list "
                            f"of them, or True") from None


def lsb_per_dps_for(range_dps):
    """Return (FS_SEL, LSB per deg/s) for a full scale of ``range_dps`` (250, 500, 1000 or 2000)."""
    for fs_sel, (full_scale, lsb) in R.GYRO_FULL_SCALE.items():
        if float(range_dps) == full_scale:
            return fs_sel, lsb
    raise SettingsError(f"range_dps={range_dps!r} is not an MPU6050 full scale; expected one of "
                        f"{', '.join(str(v[0]) for v in R.GYRO_FULL_SCALE.values())} (deg/s)")


def lsb_per_g_for(range_g):
    """Return (AFS_SEL, LSB per g) for an accelerometer full scale of ``range_g`` (2, 4, 8 or 16 g):
    16384, 8192, 4096 or 2048 LSB per g (product spec PS-MPU-6000A-00 section 6.2; register map
    ACCEL_CONFIG 0x1C, AFS_SEL bits 4:3)."""
    for afs_sel, (full_scale, lsb) in R.ACCEL_FULL_SCALE.items():
        if float(range_g) == full_scale:
            return afs_sel, lsb
    raise SettingsError(f"accel_range_g={range_g!r} is not an MPU6050 accelerometer full scale; expected one of "
                        f"{', '.join(str(v[0]) for v in R.ACCEL_FULL_SCALE.values())} (g)")


def auto_dlpf_cfg(sample_rate_hz):
    """Widest DLPF bandwidth below the Nyquist frequency ``sample_rate_hz / 2`` (DLPF_CFG 0..6).

    Table from register map section 4.3 (gyro bandwidth 256, 188, 98, 42, 20, 10, 5 Hz).
    Falls back to DLPF_CFG 6 (5 Hz) for rates below 10 Hz.
    """
    for cfg in range(0, 7):
        if R.DLPF[cfg][0] < sample_rate_hz / 2.0:
            return cfg
    return 6


def sample_rate_settings(sample_rate_hz, dlpf_cfg):
    """Return (SMPLRT_DIV, actual rate Hz, gyro output rate Hz) for a requested rate.

    ``sample_rate_hz``: the requested sample rate (Hz, finite and > 0); ``dlpf_cfg``: CONFIG.DLPF_CFG
    0..6, which sets the gyro output rate (7 is reserved in the register map, section 4.3, and refused).

    rate = gyro_output_rate / (1 + SMPLRT_DIV), gyro_output_rate = 8 kHz when DLPF_CFG is 0,
    else 1 kHz (register map section 4.2). A rate that no divider 0..255 reaches exactly is refused
    (SettingsError) with the nearest reachable rates in the message.
    """
    if dlpf_cfg == 7:
        raise SettingsError("dlpf=7: CONFIG.DLPF_CFG 7 is reserved in the MPU-6050 register map (section 4.3); "
                            "use 0 for the 8-kHz gyro output rate (256-Hz bandwidth)")
    if dlpf_cfg not in R.DLPF:
        raise SettingsError(f"dlpf={dlpf_cfg!r}: CONFIG.DLPF_CFG (bits 2:0) takes 0..6 (or none for automatic)")
    base_hz = R.DLPF[dlpf_cfg][2]
    sample_rate_hz = check_sample_rate_hz(sample_rate_hz, "sample_rate_hz")
    div_f = base_hz / sample_rate_hz - 1.0
    div = int(round(div_f))
    if 0 <= div <= 255 and abs(base_hz / (1 + div) - sample_rate_hz) <= 1e-6 * sample_rate_hz:
        return div, base_hz / (1 + div), base_hz
    lo = min(255, max(0, int(np.floor(div_f))))
    hi = min(255, max(0, lo + 1))
    near = sorted({base_hz / (1 + d) for d in (lo, hi)}, reverse=True)
    near_txt = " or ".join(f"{r:g} Hz (SMPLRT_DIV={int(round(base_hz / r - 1))})" for r in near)
    raise SettingsError(
        f"sample_rate_hz={sample_rate_hz:g} is not reachable with DLPF_CFG={dlpf_cfg}: the MPU6050 samples at "
        f"{base_hz:g} Hz / (1 + SMPLRT_DIV), SMPLRT_DIV 0..255; nearest: {near_txt}")


def frame_layout(temperature, accel=False):
    """Names of the 16-bit words in one FIFO frame, in FIFO order: register order (section 4.6),
    ACCEL_XOUT_H 0x3B .. ACCEL_ZOUT_L 0x40, TEMP_OUT 0x41, GYRO_XOUT_H 0x43 .. GYRO_ZOUT_L 0x48.

    ``temperature``: True when TEMP_OUT is in the FIFO; ``accel``: True when the accelerometer is.
    Returns a tuple of names, e.g. ``("ax", "ay", "az", "temp", "gx", "gy", "gz")`` (14 bytes a
    frame) or ``("gx", "gy", "gz")`` (6 bytes).
    """
    return (ACCEL_COLUMNS if accel else ()) + (("temp",) if temperature else ()) + GYRO_COLUMNS


def decode_fifo(buf, n_words):
    """Decode whole FIFO frames: big-endian 16-bit two's complement -> int16 array (frames, n_words).

    ``buf``: the bytes read from FIFO_R_W, a whole number of frames of ``2 * n_words`` bytes;
    ``n_words``: 16-bit words per frame (``len(frame_layout(...))``). Returns raw values in LSB
    (gyro, accelerometer) or TEMP_OUT counts, one row per frame, columns in :func:`frame_layout` order.
    """
    return np.frombuffer(bytes(buf), dtype=">i2").reshape(-1, n_words)


def frame_values(words, layout, columns, lsb_per_c=R.TEMP_LSB_PER_C, offset_c=R.TEMP_OFFSET_C):
    """Decoded frames (:func:`decode_fifo`, words in ``layout`` order) as a source's value columns.

    ``layout`` and ``columns``: tuples of names; ``columns`` the names wanted, in the source's
    order (``gx, gy, gz[, temp][, ax, ay, az]``, each in ``layout``). Gyro and accelerometer stay
    in LSB, ``temp`` becomes deg C by :func:`temperature_c` with the chip's ``lsb_per_c`` and
    ``offset_c``. Returns floats, shape (frames, len(columns)).
    """
    order, temp_at = _column_order(layout, columns)
    out = words[:, order].astype(float)
    if temp_at is not None:
        out[:, temp_at] = temperature_c(out[:, temp_at], lsb_per_c, offset_c)
    return out


@functools.lru_cache(maxsize=None)
def _column_order(layout, columns):
    """(the index in ``layout`` of each of ``columns``, the place of ``temp`` in ``columns`` or None)."""
    return np.array([layout.index(name) for name in columns]), (columns.index("temp") if "temp" in columns else None)


def temperature_c(raw, lsb_per_c=R.TEMP_LSB_PER_C, offset_c=R.TEMP_OFFSET_C):
    """T / degC = TEMP_OUT / 340 + 36.53 (register map section 4.18).

    ``raw``: TEMP_OUT (LSB, scalar or array); ``lsb_per_c``: LSB per deg C (340 for an MPU-6050);
    ``offset_c``: temperature at TEMP_OUT = 0 (deg C; 36.53). Relatives use their own pair
    (:data:`CHIPS`). Returns the temperature in deg C as floats, the shape of ``raw``.
    """
    return np.asarray(raw, dtype=float) / lsb_per_c + offset_c


#: a source with no frame for this long (s), or for 10 sample intervals where that is longer, has
#: stopped: a chip reset by a power dip comes back asleep with its FIFO off, FIFO_COUNT 0 for ever
STALL_S = 1.0


def stall_s(sample_rate_hz):
    """How long (s) a source at ``sample_rate_hz`` (Hz) may go without a frame: max(:data:`STALL_S`, 10 / f_s)."""
    return max(STALL_S, 10.0 / sample_rate_hz)


def stall_text(where, quiet_s, last_t_s, registers):
    """The DeviceError text of a source quiet for ``quiet_s`` (s) after its sample at ``last_t_s``
    (s): ``registers`` holds (register, value read now, value written) of each the driver configured;
    those that differ say the chip lost its configuration (a reset, e.g. by a power dip, after
    which the bias is another power-up's: the record cannot go on as one)."""
    lost = [f"{reg} 0x{got:02X} (0x{put:02X} written)" for reg, got, put in registers if got != put]
    why = (f"the chip lost its configuration ({', '.join(lost)}): it was reset, e.g. by a power dip, and its bias "
           "after a new power-up differs; record again" if lost else
           "its registers hold the configuration; check its power, wiring and clock")
    return f"{where}: no sample for {quiet_s:.3g} s after t={last_t_s:.6g} s; {why}"
