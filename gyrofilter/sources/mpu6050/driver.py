"""MPU-6050 gyroscope and accelerometer over I2C (Linux i2c-dev through smbus2), read through the chip's FIFO.

Entry point: :func:`open_mpu6050` returns a live source (see the source protocol in
``gyrofilter/sources``): ``header``, ``columns``, ``read()``, ``pop_notes()``, ``stats``, ``close()``.

What the driver does, with the datasheet sections it follows (InvenSense RM-MPU-6000A-00 rev 4.2,
register map; PS-MPU-6000A-00 rev 3.4, product specification):

* identifies the chip by WHO_AM_I (0x75, section 4.32): 0x68 is an MPU-6050; relatives and clones
  are named and refused unless ``allow_chip`` lets them through;
* resets it (PWR_MGMT_1.DEVICE_RESET), wakes it with the clock from the PLL (CLKSEL = 1, section 4.30),
  with a timeout on every wait;
* sets full scale (GYRO_CONFIG.FS_SEL bits 4:3: 250/500/1000/2000 deg/s = 131/65.5/32.8/16.4 LSB per
  deg/s), the accelerometer's full scale (ACCEL_CONFIG.AFS_SEL bits 4:3: 2/4/8/16 g = 16384/8192/4096/2048
  LSB per g, product spec section 6.2), digital low-pass filter (CONFIG.DLPF_CFG bits 2:0) and sample rate
  ``rate = gyro output rate / (1 + SMPLRT_DIV)`` with a gyro output rate of 8 kHz for DLPF_CFG 0
  and 1 kHz otherwise (section 4.2); every written register is read back before data are trusted;
* reads the FIFO (section 4.6: accelerometer X, Y, Z, TEMP and gyro X, Y, Z as enabled, written in
  register order: accel, temp, gyro; 14 bytes a frame with all, 12 without TEMP): FIFO_COUNT
  (0x72/0x73) then whole frames, big-endian 16-bit two's complement;
* time stamps samples from the sensor's clock: ``t = sample_index / sample_rate_hz``; a FIFO overflow
  (INT_STATUS.FIFO_OFLOW_INT, bit 4) resets the FIFO, keeps frame alignment, and records the gap
  (samples lost, estimated from the host clock at the configured rate) as a note and as a jump in t;
* retries transient I2C errors (EIO 5, EREMOTEIO 121) with a bounded exponential back-off and
  counts them in ``stats["retries"]``.

Temperature: T / degC = TEMP_OUT / 340 + 36.53 (section 4.18).

This module holds the source (the bus traffic); the chip without the bus is :mod:`.chip`, the
register map :mod:`.registers`. smbus2 is imported only when a bus is opened by number or path; a
bus object can be injected instead (smbus2's ``read_byte_data``, ``write_byte_data``,
``read_i2c_block_data`` and, optionally, ``i2c_rdwr``).
"""
import errno as _errno
import time
from datetime import datetime, timezone

import numpy as np

from ...errors import DeviceError, SettingsError, SourceEnded
from ...recording import ACCEL_COLUMNS, COLUMNS, format_number, units_header
from . import registers as R
from ..base import Source
from .bus import as_int, bus_name, bus_number, open_bus
from .chip import (CHIPS, MPU6050_ID, auto_dlpf_cfg, chip_ids, decode_fifo, frame_layout, frame_values,
                   lsb_per_dps_for, lsb_per_g_for, sample_rate_settings, stall_s, stall_text)

__all__ = ["open_mpu6050", "MPU6050Source"]

TRANSIENT_ERRNOS = (_errno.EIO, _errno.EREMOTEIO)  # 5, 121
I2C_BLOCK_MAX = 32          # SMBus I2C-block transfers carry at most 32 bytes
I2C_FUNC_I2C = 0x00000001   # adapter supports plain I2C messages (I2C_RDWR)


class MPU6050Source(Source):
    """A configured MPU-6050 streaming gyro (and temperature and accelerometer) samples from its FIFO.

    Use :func:`open_mpu6050`; the constructor does all the bus traffic of start-up.
    ``read()`` returns rows ``[t, gx, gy, gz(, temp)(, ax, ay, az)]``: t in seconds from the sensor's
    sample index, gyro in LSB (``lsb_per_dps`` LSB per deg/s), temp in deg C, accelerometer in LSB
    (``lsb_per_g`` LSB per g).

    Parameters
    ----------
    bus : int, str or bus object
        I2C bus number N (``/dev/i2c-N``) or device path, opened with smbus2 and closed with the
        source; or an smbus2-like bus object, used as is and not closed.
    address : int or str
        I2C address, 0x68 (AD0 low) or 0x69 (AD0 high); ``"0x69"`` is accepted.
    sample_rate_hz : float
        Requested sample rate (Hz); must be exactly ``gyro_output_rate / (1 + SMPLRT_DIV)``
        (:func:`sample_rate_settings`), else SettingsError names the nearest reachable rates.
    range_dps : float
        Full scale (deg/s): 250, 500, 1000 or 2000 (131, 65.5, 32.8, 16.4 LSB per deg/s).
    dlpf : int, optional
        CONFIG.DLPF_CFG 0..6 (7 is reserved and refused); None picks the widest bandwidth below ``sample_rate_hz / 2``
        (:func:`auto_dlpf_cfg`).
    temperature : bool
        Put TEMP_OUT in the FIFO and a ``temp`` column (deg C) in the rows.
    allow_chip : int, str, collection or True, optional
        WHO_AM_I values accepted besides 0x68 (known relatives and clones of :data:`CHIPS`
        only); True accepts any usable one; None accepts only an MPU-6050.
    accel : bool
        Put the accelerometer in the FIFO (6 more bytes a frame) and ``ax, ay, az`` columns (LSB)
        in the rows. The accelerometer's output rate is 1 kHz: above it a sample repeats.
    accel_range_g : float
        Accelerometer full scale (g): 2, 4, 8 or 16 (16384, 8192, 4096, 2048 LSB per g).
    transfer : str
        How the FIFO is read: ``"smbus"`` (I2C-block reads of at most 32 bytes), ``"rdwr"`` (one
        combined I2C_RDWR transfer; needs a bus with ``i2c_rdwr``) or ``"auto"`` (rdwr when the
        adapter supports plain I2C messages).
    clock, sleep, wall_clock : callable, optional
        Injected time functions (test seams): monotonic clock (s), sleep(s) and wall clock
        (s since the epoch, for ``start_time_utc``); default ``time.monotonic``, ``time.sleep``
        and ``time.time``.
    poll_interval_s : float
        Longest time between FIFO polls (s); lowered to a quarter of the time the FIFO takes to
        fill at ``sample_rate_hz``.
    max_wait_s : float
        Longest time one ``read()`` waits for the first row (s).
    max_retries : int
        Retries of a bus transaction failing with EIO or EREMOTEIO before DeviceError.
    retry_backoff_s : float
        First back-off (s) between retries; doubles on each retry (1, 2, 4, ... ms by default).
    reset_timeout_s : float
        Longest wait (s) for the device reset, wake-up and each FIFO reset to finish.
    fifo_bytes : int, optional
        FIFO size (bytes) overriding the chip's from :data:`CHIPS` (1024 for an MPU-6050).

    Raises SettingsError for a bad setting (before any bus traffic) and
    :class:`gyrofilter.errors.DeviceError` when the chip cannot be identified or configured.
    """

    gyro_unit = "lsb"

    def __init__(self, bus=1, address=0x68, sample_rate_hz=100, range_dps=250, dlpf=None, temperature=True,
                 allow_chip=None, accel=True, accel_range_g=2, *, transfer="auto", clock=None, sleep=None, wall_clock=None,
                 poll_interval_s=0.02, max_wait_s=0.1, max_retries=5, retry_backoff_s=0.001,
                 reset_timeout_s=0.5, fifo_bytes=None):
        # settings are checked before any bus traffic (strings such as "0x69" or "3" are accepted)
        address = as_int(address, "address")
        dlpf = None if dlpf is None else as_int(dlpf, "dlpf")
        if address not in (0x68, 0x69):
            raise SettingsError(f"address=0x{int(address):02X}: an MPU6050 answers at 0x68 (AD0 low) "
                                f"or 0x69 (AD0 high)")
        self.fs_sel, self.lsb_per_dps = lsb_per_dps_for(range_dps)
        self.full_scale_dps = R.GYRO_FULL_SCALE[self.fs_sel][0]
        self.afs_sel, self.lsb_per_g = lsb_per_g_for(accel_range_g)
        self.dlpf_cfg = auto_dlpf_cfg(float(sample_rate_hz)) if dlpf is None else dlpf
        self.smplrt_div, self.sample_rate_hz, self.gyro_output_rate_hz = sample_rate_settings(
            sample_rate_hz, self.dlpf_cfg)
        if transfer not in ("auto", "smbus", "rdwr"):
            raise SettingsError(f"transfer={transfer!r}: expected 'auto', 'smbus' or 'rdwr'")
        self.temperature, self.accel, self.address = bool(temperature), bool(accel), int(address)
        self.bus_name = bus_name(bus)
        self._clock, self._sleep, self._wall_clock = clock or time.monotonic, sleep or time.sleep, \
            wall_clock or time.time
        self.poll_interval_s, self.max_wait_s, self.reset_timeout_s = float(poll_interval_s), float(max_wait_s), \
            float(reset_timeout_s)
        self.max_retries, self.retry_backoff_s = int(max_retries), float(retry_backoff_s)
        self.stats = {"samples": 0, "lost_samples": 0, "retries": 0, "overflows": 0, "resyncs": 0,
                      "polls": 0, "fifo_bytes_read": 0}
        self._notes = []
        self._failure = None  # a DeviceError that ended a FIFO read part-way, raised by the next read()
        self._layout = frame_layout(self.temperature, self.accel)
        self.frame_bytes = 2 * len(self._layout)
        self.columns = [*COLUMNS] + (["temp"] if self.temperature else []) + ([*ACCEL_COLUMNS] if self.accel else [])
        self._owns_bus = isinstance(bus, (int, str))
        self._bus = open_bus(bus) if self._owns_bus else bus
        try:
            self.chip_id = self._identify(allow_chip)
            self.chip_name, chip_fifo, self._temp_lsb_per_c, self._temp_offset_c, _ = CHIPS[self.chip_id]
            self.fifo_size_bytes = int(fifo_bytes or chip_fifo)
            capacity = self.fifo_size_bytes // self.frame_bytes          # frames the FIFO holds
            # poll often enough to read the FIFO at a quarter full; keep a margin of 10 ms of
            # samples (at most a quarter of the FIFO) for frames that arrive during one read
            self.poll_interval_s = min(self.poll_interval_s, capacity / self.sample_rate_hz / 4)
            self._margin_frames = max(1, min(int(np.ceil(self.sample_rate_hz * 0.01)), capacity // 4))
            self.use_rdwr = self._choose_transfer(transfer)
            self._start()
        except BaseException:
            self._close_bus()
            raise
        self.header = self._make_header()

    # ---------------------------------------------------------------- bus access with retries

    def _where(self):
        return f"0x{self.address:02X} on {self.bus_name}"

    def _xfer(self, what, fn, *args):
        """Call one bus transaction; retry EIO/EREMOTEIO with back-off 1, 2, 4, ... ms (bounded)."""
        for attempt in range(self.max_retries + 1):
            try:
                return fn(*args)
            except OSError as exc:
                code = exc.errno
                if code in TRANSIENT_ERRNOS and attempt < self.max_retries:
                    self.stats["retries"] += 1
                    self._sleep(self.retry_backoff_s * (2 ** attempt))
                    continue
                raise self._io_error(what, exc, attempt + 1) from None

    def _io_error(self, what, exc, attempts):
        code = exc.errno
        desc = f"errno {code}: {exc.strerror or _errno.errorcode.get(code, '?')}"
        if code in (_errno.ENXIO, _errno.EREMOTEIO) and not getattr(self, "_identified", False):
            return DeviceError(
                f"no chip answers at {self._where()} ({desc}): check the wiring (VCC 3.3 V, GND, "
                f"SDA to GPIO2/pin 3, SCL to GPIO3/pin 5) and the address (0x68 with AD0 low, 0x69 with "
                f"AD0 high); `i2cdetect -y {bus_number(self.bus_name)}` should list it")
        if code == _errno.EBUSY:
            return DeviceError(
                f"address {self._where()} is busy ({desc}): a kernel driver owns it (remove "
                f"dtoverlay=mpu6050 from /boot/firmware/config.txt and reboot)")
        return DeviceError(f"I2C transfer failed at {self._where()} reading/writing {what} after "
                           f"{attempts} attempt(s) ({desc}): check wiring, cable length and pull-ups")

    def _read_byte(self, reg):
        return self._xfer(str(reg), self._bus.read_byte_data, self.address, reg.address)

    def _write_byte(self, reg, value):
        self._xfer(str(reg), self._bus.write_byte_data, self.address, reg.address, value)

    def _read_block(self, reg, length):
        return self._xfer(str(reg), self._bus.read_i2c_block_data, self.address, reg.address, length)

    # ---------------------------------------------------------------- start-up

    def _identify(self, allow_chip):
        self._identified = False
        who = self._read_byte(R.WHO_AM_I)
        self._identified = True
        if who == MPU6050_ID:
            return who
        known = CHIPS.get(who)
        allowed = allow_chip is True or who in chip_ids(allow_chip)
        if known is None:
            raise DeviceError(
                f"chip at {self._where()} answers WHO_AM_I (0x75) = 0x{who:02X}, not 0x68 (MPU6050), "
                f"and is not a known relative: wrong device at this address? (`i2cdetect -y "
                f"{bus_number(self.bus_name)}` lists what answers)")
        if not known[4]:
            raise DeviceError(f"chip at {self._where()} is a {known[0]} (WHO_AM_I 0x{who:02X}); this driver "
                              f"speaks the MPU6050 register map only")
        if not allowed:
            raise DeviceError(
                f"chip at {self._where()} is a {known[0]} (WHO_AM_I 0x{who:02X}), not an MPU6050 (0x68): "
                f"its gyro registers are similar but FIFO size, filters and temperature scale differ; "
                f"pass allow_chip=0x{who:02X} to use it anyway")
        return who

    def _choose_transfer(self, transfer):
        has_rdwr = hasattr(self._bus, "i2c_rdwr")
        if transfer == "smbus":
            return False
        if transfer == "rdwr":
            if not has_rdwr:
                raise SettingsError("transfer='rdwr' needs a bus with i2c_rdwr (smbus2.SMBus)")
        else:
            funcs = getattr(self._bus, "funcs", 0)
            if not (has_rdwr and int(funcs) & I2C_FUNC_I2C):
                return False
        from smbus2 import i2c_msg  # the message type smbus2's i2c_rdwr expects

        self._i2c_msg = i2c_msg
        return True

    def _wait_for(self, reg, done, what, timeout_s):
        """Poll ``reg`` until ``done(value)``; DeviceError after ``timeout_s`` (every wait is bounded).

        Transient errors (the chip may not answer while it resets) count as retries and are
        tolerated until the deadline.
        """
        deadline = self._clock() + timeout_s
        value, last_exc = None, None
        while True:
            try:
                value = self._bus.read_byte_data(self.address, reg.address)
                if done(value):
                    return value
            except OSError as exc:
                if exc.errno not in TRANSIENT_ERRNOS:
                    raise self._io_error(str(reg), exc, 1) from None
                self.stats["retries"] += 1
                last_exc = exc
            if self._clock() >= deadline:
                if value is None:
                    raise self._io_error(str(reg), last_exc, "repeated") from None
                raise DeviceError(f"{what} at {self._where()}: {reg} still reads 0x{value:02X} after "
                                  f"{timeout_s:g} s; power-cycle the sensor")
            self._sleep(0.005)

    def _start(self):
        pm1 = R.PWR_MGMT_1
        # reset (section 4.30), then wait for DEVICE_RESET to clear
        self._write_byte(pm1, pm1.put(0, "DEVICE_RESET", 1))
        self._sleep(0.1)   # InvenSense reset sequence: wait 100 ms after DEVICE_RESET
        self._wait_for(pm1, lambda v: not v & pm1.mask("DEVICE_RESET"), "reset did not finish",
                       self.reset_timeout_s)
        self._write_byte(R.SIGNAL_PATH_RESET, 0x07)
        self._sleep(0.01)
        # wake with the clock from the PLL (X gyro reference)
        self._write_byte(pm1, pm1.put(0, "CLKSEL", R.CLKSEL_PLL_XGYRO))
        self._wait_for(pm1, lambda v: not v & pm1.mask("SLEEP"), "chip did not wake up",
                       self.reset_timeout_s)
        self._sleep(0.05)  # gyro start-up time, product spec table 6.1: 30 ms typical
        # configuration (FIFO stopped while configuring)
        fifo_en = (R.FIFO_EN.mask("XG_FIFO_EN") | R.FIFO_EN.mask("YG_FIFO_EN") | R.FIFO_EN.mask("ZG_FIFO_EN")
                   | (R.FIFO_EN.mask("TEMP_FIFO_EN") if self.temperature else 0)
                   | (R.FIFO_EN.mask("ACCEL_FIFO_EN") if self.accel else 0))
        writes = [
            (R.USER_CTRL, 0x00),
            (R.FIFO_EN, 0x00),
            (R.SMPLRT_DIV, self.smplrt_div),
            (R.CONFIG, R.CONFIG.put(0, "DLPF_CFG", self.dlpf_cfg)),
            (R.GYRO_CONFIG, R.GYRO_CONFIG.put(0, "FS_SEL", self.fs_sel)),
            (R.ACCEL_CONFIG, R.ACCEL_CONFIG.put(0, "AFS_SEL", self.afs_sel)),
            (R.INT_PIN_CFG, 0x00),
            (R.INT_ENABLE, R.INT_ENABLE.mask("FIFO_OFLOW_EN")),
            (R.PWR_MGMT_2, 0x00),
            (R.FIFO_EN, fifo_en),
        ]
        for reg, value in writes:
            self._write_byte(reg, value)
        # read every written register back (its last value); refuse to start on a mismatch
        final = {reg.address: (reg, value) for reg, value in writes}
        final[pm1.address] = (pm1, pm1.put(0, "CLKSEL", R.CLKSEL_PLL_XGYRO))
        # what a chip reset undoes, read where the frames stop (:meth:`_poll`)
        self._watched = [(pm1, final[pm1.address][1]), (R.FIFO_EN, fifo_en), (R.USER_CTRL, R.USER_CTRL.mask("FIFO_EN"))]
        for reg, value in final.values():
            got = self._read_byte(reg)
            if got != value:
                raise DeviceError(
                    f"{self.chip_name} at {self._where()}: register {reg} reads back 0x{got:02X} after "
                    f"writing 0x{value:02X}; refusing to start (bad connection or not an MPU6050)")
        self._fifo_restart()
        self.start_time_utc = datetime.fromtimestamp(self._wall_clock(), tz=timezone.utc).isoformat(
            timespec="milliseconds").replace("+00:00", "Z")

    def _fifo_restart(self):
        """Stop, reset and re-enable the FIFO; clear INT_STATUS; anchor the host clock to the next
        sample: the anchor is the moment the FIFO_EN write returned, the first sample the FIFO
        keeps being the first produced after it (the read-back after it, and the reset and its
        retries before it, take time in which samples are produced: kept after it, lost before)."""
        uc = R.USER_CTRL
        self._write_byte(uc, uc.put(0, "FIFO_RESET", 1))           # FIFO_RESET while FIFO_EN = 0
        self._wait_for(uc, lambda v: not v & uc.mask("FIFO_RESET"), "FIFO reset did not finish",
                       self.reset_timeout_s)
        self._read_byte(R.INT_STATUS)                               # clears FIFO_OFLOW_INT
        self._write_byte(uc, uc.put(0, "FIFO_EN", 1))
        enabled_at = self._clock()
        if not (got := self._read_byte(uc)) & uc.mask("FIFO_EN"):
            raise DeviceError(f"{self.chip_name} at {self._where()}: register {uc} reads back 0x{got:02X} "
                              f"after writing 0x{uc.put(0, 'FIFO_EN', 1):02X}: the FIFO could not be (re)started")
        self._anchor_time = enabled_at
        self._anchor_index = getattr(self, "_next_index", 0)
        self._next_index = self._anchor_index
        self._last_poll = self._anchor_time
        self._fifo_floor = None  # (bytes left, time) after a failed read: the FIFO grows by the rate, shrinks as read

    def _make_header(self):
        bw = R.DLPF[self.dlpf_cfg][0]
        head = {
            "sensor": "MPU6050" if self.chip_id == MPU6050_ID else self.chip_name.split(" (")[0],
            "chip_name": self.chip_name,
            "chip_id": f"0x{self.chip_id:02X}",
            **units_header(self.sample_rate_hz, self.gyro_unit, self.lsb_per_dps),
            "full_scale_dps": f"{self.full_scale_dps:g}",
            "dlpf_cfg": str(self.dlpf_cfg),
            "dlpf_bandwidth_hz": f"{bw:g}",
            "smplrt_div": str(self.smplrt_div),
            "gyro_output_rate_hz": f"{self.gyro_output_rate_hz:g}",
            "clock_source": "PLL, X gyro reference (CLKSEL=1)",
            "start_time_utc": self.start_time_utc,
            "i2c_bus": self.bus_name,
            "i2c_address": f"0x{self.address:02X}",
            "time_base": "t = sample_index / sample_rate_hz (sensor clock); lost samples show as jumps in t",
            "source": "gyrofilter.sources.mpu6050 (FIFO)",
        }
        if self.temperature:
            head["temp_formula"] = f"temp_c = TEMP_OUT / {self._temp_lsb_per_c:g} + {self._temp_offset_c:g}"
        if self.accel:
            head.update({"accel_unit": "lsb", "lsb_per_g": format_number(self.lsb_per_g),
                         "full_scale_g": format_number(R.ACCEL_FULL_SCALE[self.afs_sel][0]),
                         "accel_output_rate_hz": format_number(R.ACCEL_OUTPUT_RATE_HZ)})
        return head

    # ---------------------------------------------------------------- streaming

    def _fifo_count(self):
        hi, lo = self._read_block(R.FIFO_COUNT_H, 2)
        return (hi << 8) | lo

    def _read_fifo(self, n_bytes):
        """Read ``n_bytes`` (whole frames) from FIFO_R_W without retrying: returns (bytes, error or None).

        With I2C_RDWR one combined transfer (register pointer write + read) takes all bytes; otherwise
        SMBus I2C-block reads of at most 32 bytes, each a whole number of frames, so the bytes read
        before a failing block are whole frames and are kept. A failed read is not repeated here:
        the caller re-reads FIFO_COUNT first, since a failure part-way may have consumed FIFO bytes.
        """
        if self.use_rdwr:
            i2c_msg = self._i2c_msg
            w = i2c_msg.write(self.address, [R.FIFO_R_W.address])
            r = i2c_msg.read(self.address, n_bytes)
            try:
                self._bus.i2c_rdwr(w, r)
            except OSError as exc:
                return b"", exc
            return bytes(r), None
        per_block = (I2C_BLOCK_MAX // self.frame_bytes) * self.frame_bytes
        out = bytearray()
        read_block = self._bus.read_i2c_block_data
        while len(out) < n_bytes:
            k = min(per_block, n_bytes - len(out))
            try:
                out += bytes(read_block(self.address, R.FIFO_R_W.address, k))
            except OSError as exc:
                return bytes(out), exc
        return bytes(out), None

    def _gap(self, reason):
        """Reset the FIFO after an overflow or lost alignment and record the gap.

        Samples lost = round((restart - anchor) * rate) - (samples delivered since the anchor), where the
        anchor is the last moment the FIFO was known to be drained (the FIFO_COUNT read of the last
        complete poll, or the last FIFO restart) and ``restart`` the moment the FIFO is enabled
        again (:meth:`_fifo_restart`: the samples produced while it is reset, and its retries, are
        lost too: counted to the failure, each gap's count came out 1 to 6 samples low, every
        later ``t`` as much early). An estimate from the host clock at the configured rate,
        uncertain by +-1 sample plus the sensor clock's tolerance (about +-1 % of nominal,
        product spec table 6.1) over the stall only, since the anchor is at most one poll old.
        """
        since_s, delivered = self._anchor_time, self._next_index - self._anchor_index
        at_t = self._next_index / self.sample_rate_hz
        self._fifo_restart()  # samples produced until the FIFO is enabled again are lost too
        produced = int(round((self._anchor_time - since_s) * self.sample_rate_hz))
        lost = max(0, produced - delivered)
        self._next_index, self.stats["lost_samples"] = self._next_index + lost, self.stats["lost_samples"] + lost
        self._anchor_index = self._next_index
        self._notes.append(f"gap: {lost} samples lost before t={self._next_index / self.sample_rate_hz:.6g} s "
                           f"(last good sample at t={at_t - 1 / self.sample_rate_hz:.6g} s; {reason}; "
                           f"count estimated from the host clock)")

    def _poll(self):
        """One look at the FIFO: overflow check, count, whole frames -> rows.

        A FIFO data read that fails with EREMOTEIO (121: NACK, nothing transferred) is retried after
        re-reading INT_STATUS and FIFO_COUNT (a count below the bytes left: it took some, a gap); one
        that fails with EIO (5: may stop part-way, consuming bytes) resets the FIFO, a gap, so frames
        never lose alignment. A FIFO_COUNT that is not a whole number of frames also resets it (a gap),
        and an overflow while the FIFO was read drops that read's frames, misaligned (a gap).
        Any other failure ends the source; frames read before it in the same poll are delivered
        first (the next read() raises), so no good frame read off the chip is dropped.
        """
        self.stats["polls"] += 1
        self._last_poll = self._clock()
        empty = self._empty()
        for attempt in range(self.max_retries + 1):
            status = self._read_byte(R.INT_STATUS)
            if status & R.INT_STATUS.mask("FIFO_OFLOW_INT"):
                self.stats["overflows"] += 1
                self._gap("FIFO overflow")
                return empty
            count = self._fifo_count()
            t_count = self._clock()
            if self._fifo_shrank(count, t_count):
                return empty
            if count > self.fifo_size_bytes - self.frame_bytes * self._margin_frames:
                # (nearly) full: samples arriving while we read would overwrite the oldest bytes
                # before we get them, and frame alignment would be lost
                self.stats["overflows"] += 1
                self._gap("FIFO overflow")
                return empty
            if count % self.frame_bytes:
                self.stats["resyncs"] += 1
                self._gap(f"FIFO count {count} is not a whole number of {self.frame_bytes}-byte frames; "
                          f"FIFO reset")
                return empty
            if count == 0:
                if (quiet_s := t_count - self._anchor_time) > stall_s(self.sample_rate_hz):  # stopped for good
                    raise DeviceError(stall_text(f"{self.chip_name} at {self._where()}", quiet_s, (self._next_index - 1) /
                                      self.sample_rate_hz, [(r, self._read_byte(r), v) for r, v in self._watched]))
                return empty
            buf, exc = self._read_fifo(count)
            if buf and self._overflowed_while_read():
                return empty
            rows = self._rows(buf) if buf else empty
            if exc is None:
                self._fifo_floor = None
                # every sample produced up to the FIFO_COUNT read is now delivered: re-anchor
                self._anchor_time, self._anchor_index = t_count, self._next_index
                return rows
            code = exc.errno
            if code in TRANSIENT_ERRNOS and attempt < self.max_retries:  # (a NACK may have taken bytes too)
                self.stats["retries"] += 1
                self._fifo_floor = (count - len(buf), t_count)
                if code == _errno.EIO:
                    self.stats["resyncs"] += 1
                    self._keeping(rows, lambda: self._gap(f"FIFO read failed part-way (errno {code}); "
                                                          f"FIFO reset to keep frame alignment"))
                    return rows
                self._sleep(self.retry_backoff_s * (2 ** attempt))
                if len(rows):  # the frames read before it, once the count says whether it took bytes
                    self._keeping(rows, lambda: self._fifo_shrank(self._fifo_count(), self._clock()))
                    return rows
                continue
            failure = self._io_error(str(R.FIFO_R_W), exc, attempt + 1)
            if len(rows):  # frames read off the chip before the failure: deliver them, fail on the next read
                self._failure = failure
                return rows
            raise failure
        return empty

    def _keeping(self, rows, step):
        """Run ``step`` (bus traffic after a failed FIFO read) with ``rows`` read off the chip before
        it: where it fails too, the rows are delivered and the next read() raises (they were lost)."""
        try:
            step()
        except DeviceError as failure:
            if not len(rows):
                raise
            self._failure = self._failure or failure

    def _overflowed_while_read(self):
        """Whether the FIFO overflowed while it was read (INT_STATUS read again after the read):
        the chip dropped the oldest bytes, the ones being read, and the frames read after that
        start mid-frame (a read outlasts the margin's 10 ms of samples where the bus is slow for
        the rate: 1 kHz of 14-byte frames is 126 kbit/s). Its frames are dropped, a gap. Where
        INT_STATUS cannot be read the frames are delivered and the next read() raises."""
        try:
            status = self._read_byte(R.INT_STATUS)
        except DeviceError as failure:
            self._failure = self._failure or failure
            return False
        if not status & R.INT_STATUS.mask("FIFO_OFLOW_INT"):
            return False
        self.stats["overflows"] += 1
        self._gap("FIFO overflow while it was read (the I2C bus too slow for the rate and frame?); "
                  "the frames of that read dropped")
        return True

    def _fifo_shrank(self, count, t_count):
        """A FIFO read that failed took bytes after all (a gap: whole frames keep the count aligned,
        and the frames after them would take their ``t``): FIFO_COUNT ``count``, read at ``t_count``,
        is below the bytes left after it plus the frames produced since (less one, and 2 % for the
        sensor clock). So the count is re-read at once after a failure that leaves frames read."""
        left, since = self._fifo_floor or (0, t_count)
        if count >= left + self.frame_bytes * max(0, int((t_count - since) * self.sample_rate_hz * 0.98) - 1):
            return False
        self.stats["resyncs"] += 1
        self._gap("a failed FIFO read took bytes; FIFO reset")
        return True

    def _rows(self, buf):
        """Decode whole frames into rows ``[t, gx, gy, gz(, temp)(, ax, ay, az)]`` and advance the sample index."""
        self.stats["fifo_bytes_read"] += len(buf)
        words = decode_fifo(buf, len(self._layout))
        n = len(words)
        rows = np.empty((n, len(self.columns)))
        rows[:, 0] = (self._next_index + np.arange(n)) / self.sample_rate_hz
        rows[:, 1:] = frame_values(words, self._layout, tuple(self.columns[1:]), self._temp_lsb_per_c,
                                   self._temp_offset_c)
        self._next_index += n
        self.stats["samples"] += n
        return rows

    def _empty(self):
        return np.empty((0, len(self.columns)))

    def read(self):
        """Rows available now (shape (n, len(columns))); waits at most ``max_wait_s`` for the first.

        Rows are ``[t, gx, gy, gz(, temp)(, ax, ay, az)]``: t (s) = sample index / ``sample_rate_hz``,
        gyro and accelerometer in LSB, temp in deg C; shape (0, len(columns)) when nothing arrived. Raises DeviceError when
        the bus failed (after delivering the rows read before the failure) and
        :class:`gyrofilter.errors.SourceEnded` once closed, as every source does.
        """
        if self._closed:
            raise SourceEnded(f"{self.chip_name} at {self._where()}: source closed")
        if self._failure is not None:
            raise self._failure
        start = self._clock()
        wait = self._last_poll + self.poll_interval_s - start
        if wait > 0:
            self._sleep(min(wait, self.max_wait_s))
        while True:
            rows = self._poll()
            if len(rows) or self._notes:
                return rows
            left = start + self.max_wait_s - self._clock()
            if left <= 0:
                return rows
            self._sleep(min(self.poll_interval_s, left))

    def _close_bus(self):
        if self._owns_bus and self._bus is not None:
            try:
                self._bus.close()
            except OSError:
                pass

    def _close(self):
        """Stop the FIFO, put the chip to sleep (best effort) and close the bus if we opened it."""
        try:
            self._bus.write_byte_data(self.address, R.USER_CTRL.address, 0x00)
            self._bus.write_byte_data(self.address, R.PWR_MGMT_1.address,
                                      R.PWR_MGMT_1.put(R.CLKSEL_PLL_XGYRO, "SLEEP", 1))
        except OSError:
            pass
        self._close_bus()


def open_mpu6050(bus=1, address=0x68, sample_rate_hz=100, range_dps=250, dlpf=None, temperature=True,
                 allow_chip=None, accel=True, accel_range_g=2, **options):
    """Open, identify, reset and configure an MPU-6050; return the started :class:`MPU6050Source`
    reading its FIFO (the parameters and the keyword-only options are its own, described there)."""
    return MPU6050Source(bus, address, sample_rate_hz, range_dps, dlpf, temperature, allow_chip, accel, accel_range_g,
                         **options)
