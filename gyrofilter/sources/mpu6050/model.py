"""A register-level MPU-6050 model behind smbus2's OS boundary (no hardware needed).

Only what smbus2 hands to the kernel is replaced: ``os.open``/``os.close`` of the bus path and
``fcntl.ioctl`` as smbus2 calls it (``smbus2.smbus2.ioctl``). smbus2's own code builds the real
ctypes structures (``i2c_smbus_ioctl_data``, ``i2c_rdwr_ioctl_data``/``i2c_msg``); :class:`FakeI2CBus`
decodes them the way the Linux i2c-dev driver does and acts on :class:`MPU6050Model`.

The model (InvenSense RM-MPU-6000A-00 rev 4.2):

* registers with reset values: everything 0x00 except PWR_MGMT_1 = 0x40 (asleep) and WHO_AM_I
  (0x68, or a relative's id); read-only registers ignore writes; burst reads auto-increment the
  register pointer except at FIFO_R_W (0x74), which returns successive FIFO bytes;
* DEVICE_RESET (PWR_MGMT_1 bit 7): registers return to reset values, the FIFO empties, and bit 7
  reads 1 for ``reset_duration_s`` (forever with ``reset_stuck``);
* a sample clock running while awake at ``gyro_output_rate / (1 + SMPLRT_DIV)`` (8 kHz for
  DLPF_CFG 0/7, else 1 kHz), driven by a virtual clock; each tick updates the output registers and,
  with USER_CTRL.FIFO_EN, appends one frame to the FIFO in register order (accel, temp, gx, gy, gz
  per FIFO_EN), big-endian;
* data from ``gyro_lsb`` (N, 3 raw integers) or ``gyro_dps`` (N, 3, scaled by the configured
  FS_SEL, rounded and clipped to int16), ``accel_lsb`` (M, 3 raw integers) or ``accel_g`` (M, 3,
  scaled by the configured ACCEL_CONFIG.AFS_SEL: 16384/8192/4096/2048 LSB per g, rounded and
  clipped to int16; default 0, 0, 1 g: lying flat) and ``temp_c`` (scalar or N values); sample k
  uses row k mod N of each (the model gives every sample its own accelerometer row: the real
  part's 1-kHz accelerometer rate, which repeats samples above 1 kHz, is not modelled);
  ACCEL_XOUT_H..ACCEL_ZOUT_L (0x3B-0x40), TEMP_OUT and GYRO_XOUT_H.. hold the latest sample;
* FIFO of ``fifo_size`` bytes (1024): on overflow the oldest bytes are dropped (byte-wise, so frame
  alignment is lost) and INT_STATUS.FIFO_OFLOW_INT (bit 4) is set if INT_ENABLE.FIFO_OFLOW_EN is set
  (the model is strict: no enable, no status bit); INT_STATUS clears when read; USER_CTRL.FIFO_RESET
  empties the FIFO and clears itself;
* ``rate_error``: the sample clock runs fast (> 0) or slow by this fraction (the real part is
  within about +-1 %);
* ``reset_nack``: the chip NACKs every transfer (errno 121) while DEVICE_RESET runs;
* injected errors: ``fail(errno, times)`` makes the next transactions raise ``OSError(errno)``
  before they touch anything; ``fail_fifo_read(errno, consume_bytes)`` makes the next FIFO_R_W read
  consume some bytes and then fail (a transfer stopped part-way), optionally after some good FIFO
  reads (``after_reads``: a later 32-byte block of one SMBus FIFO read fails); ``error_rate`` with ``rng`` fails
  random transactions; ``stuck`` maps registers to values that ignore writes (read-back failures).
"""
import ctypes
import errno as _errno
import math
import os

import numpy as np

import smbus2.smbus2 as _smbus2

#: WHO_AM_I -> (TEMP_OUT LSB per deg C, deg C at TEMP_OUT 0), from the datasheets, written here
#: apart from the driver's table so that a wrong scale there is caught: MPU-6050 (RM-MPU-6000A
#: 4.18), MPU-6500 family (PS-MPU-6500A-01), ICM-206xx/MPU6886 (DS-000143 and kin)
TEMP_SCALE = {0x68: (340.0, 36.53), 0x72: (340.0, 36.53),
              0x70: (333.87, 21.0), 0x71: (333.87, 21.0), 0x73: (333.87, 21.0), 0x74: (333.87, 21.0),
              0x98: (326.8, 25.0), 0x12: (326.8, 25.0), 0x11: (326.8, 25.0), 0xAF: (326.8, 25.0), 0x19: (326.8, 25.0)}

# register addresses (kept literal here, independent of the driver's map, so a wrong address in
# the driver's table shows up as a test failure)
SMPLRT_DIV, CONFIG, GYRO_CONFIG, ACCEL_CONFIG, FIFO_EN = 0x19, 0x1A, 0x1B, 0x1C, 0x23
INT_ENABLE, INT_STATUS = 0x38, 0x3A
ACCEL_XOUT_H, TEMP_OUT_H, GYRO_XOUT_H = 0x3B, 0x41, 0x43
SIGNAL_PATH_RESET, USER_CTRL, PWR_MGMT_1 = 0x68, 0x6A, 0x6B
FIFO_COUNT_H, FIFO_COUNT_L, FIFO_R_W, WHO_AM_I = 0x72, 0x73, 0x74, 0x75
READ_ONLY = {INT_STATUS, FIFO_COUNT_H, FIFO_COUNT_L, WHO_AM_I} | set(range(0x3B, 0x61))
LSB_PER_DPS = {0: 131.0, 1: 65.5, 2: 32.8, 3: 16.4}
LSB_PER_G = {0: 16384.0, 1: 8192.0, 2: 4096.0, 3: 2048.0}    # ACCEL_CONFIG.AFS_SEL, product spec 6.2


class VirtualClock:
    """Monotonic virtual time in seconds: ``now()``, ``sleep(dt)`` advances it, ``advance(dt)``.

    ``start_s``: the initial time (s). Pass ``now`` and ``sleep`` as the driver's ``clock`` and
    ``sleep`` (and the model's ``clock``) so that tests run in no real time; ``slept_s`` totals
    the time slept (s).
    """

    def __init__(self, start_s=1000.0):
        self.t = float(start_s)
        self.slept_s = 0.0

    def now(self):
        """The virtual time (s)."""
        return self.t

    def sleep(self, dt):
        """Advance the time by ``dt`` seconds (ignored if <= 0) and add it to ``slept_s``."""
        if dt > 0:
            self.t += dt
            self.slept_s += dt

    def advance(self, dt):
        """Advance the time by ``dt`` seconds without counting it as sleep (time spent elsewhere)."""
        self.t += dt


class MPU6050Model:
    """Register-level MPU-6050 (see module docstring).

    Parameters
    ----------
    clock : VirtualClock
        The time base (anything with ``now()`` in s); the sample clock follows it.
    chip_id : int
        WHO_AM_I value (0x68 for an MPU-6050; 0x70, 0x72, ... for relatives and clones).
    gyro_lsb : array (N, 3), optional
        Raw gyro output (LSB) of samples 0..N-1, repeated; used as is whatever FS_SEL.
    gyro_dps : array (N, 3), optional
        Angular rate (deg/s), scaled by the configured FS_SEL (131/65.5/32.8/16.4 LSB per deg/s),
        rounded and clipped to int16. Neither given: zeros.
    accel_lsb : array (M, 3), optional
        Raw accelerometer output (LSB) of samples 0..M-1, repeated; used as is whatever AFS_SEL.
    accel_g : array (M, 3), optional
        Acceleration (g), scaled by the configured AFS_SEL (16384/8192/4096/2048 LSB per g),
        rounded and clipped to int16. Neither given: (0, 0, 1) g.
    temp_c : float or array (N,)
        Die temperature (deg C), written as TEMP_OUT = round((T - offset) * LSB per deg C) with the
        chip's own scale (:data:`TEMP_SCALE`; MPU6050: offset 36.53, 340 LSB per deg C).
    fifo_size : int
        FIFO capacity (bytes).
    reset_duration_s : float
        Time (s) DEVICE_RESET takes (the bit reads 1 and writes are ignored meanwhile).
    reset_stuck : bool
        DEVICE_RESET never finishes.
    reset_nack : bool
        Every transfer fails with EREMOTEIO (121) while the reset runs.
    stuck : dict, optional
        Register address -> value that reads back whatever is written (read-back failures).
    rate_error : float
        Fractional sample-clock error: the rate is nominal * (1 + ``rate_error``).
    error_rate : float
        Probability (0..1) that a transaction fails with ``error_errno``, drawn from ``rng``.
    error_errno : int
        errno of those random failures (default EREMOTEIO, 121).
    rng : numpy.random.Generator, optional
        Random generator of the failures (default ``default_rng(0)``).
    """

    def __init__(self, clock, *, chip_id=0x68, gyro_lsb=None, gyro_dps=None, accel_lsb=None, accel_g=None, temp_c=25.0,
                 fifo_size=1024, reset_duration_s=0.002, reset_stuck=False, reset_nack=False,
                 stuck=None, rate_error=0.0,
                 error_rate=0.0, error_errno=_errno.EREMOTEIO, rng=None):
        self.clock = clock
        self.chip_id = chip_id
        if gyro_lsb is None and gyro_dps is None:
            gyro_lsb = np.zeros((1, 3), dtype=np.int64)
        self.gyro_lsb = None if gyro_lsb is None else np.asarray(gyro_lsb, dtype=np.int64)
        self.gyro_dps = None if gyro_dps is None else np.asarray(gyro_dps, dtype=float)
        if accel_lsb is None and accel_g is None:
            accel_g = [[0.0, 0.0, 1.0]]
        self.accel_lsb = None if accel_lsb is None else np.asarray(accel_lsb, dtype=np.int64)
        self.accel_g = None if accel_g is None else np.asarray(accel_g, dtype=float)
        self.temp_c = np.atleast_1d(np.asarray(temp_c, dtype=float))
        self.fifo_size = fifo_size
        self.reset_duration_s = reset_duration_s
        self.reset_stuck = reset_stuck
        self.reset_nack = reset_nack
        self.rate_error = rate_error
        self.stuck = dict(stuck or {})
        self.error_rate = error_rate
        self.error_errno = error_errno
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.failures = []            # queued errnos, one per transaction
        self.fifo_failures = []       # queued (errno, consume_bytes) for FIFO_R_W reads
        self.injected_errors = 0
        self.produced = 0             # samples produced by the sample clock since power-on
        self.fifo_dropped_bytes = 0
        self.fifo_resets = 0
        self.transactions = 0
        self._power_on()

    # ------------------------------------------------------------------ state

    def _power_on(self):
        self.regs = bytearray(128)
        self.regs[PWR_MGMT_1] = 0x40
        self.regs[WHO_AM_I] = self.chip_id
        for reg, value in self.stuck.items():
            self.regs[reg] = value
        self.fifo = bytearray()
        self.reset_until = -math.inf
        self._restart_sample_clock()

    def awake(self):
        """True when no reset is running and PWR_MGMT_1.SLEEP is clear (the sample clock runs)."""
        return self.clock.now() >= self.reset_until and not self.regs[PWR_MGMT_1] & 0x40

    def sample_rate_hz(self):
        """Current sample rate (Hz): gyro output rate (8 kHz for DLPF_CFG 0/7, else 1 kHz) /
        (1 + SMPLRT_DIV), times (1 + ``rate_error``)."""
        dlpf = self.regs[CONFIG] & 0x07
        base = 8000.0 if dlpf in (0, 7) else 1000.0
        return base / (1 + self.regs[SMPLRT_DIV]) * (1.0 + self.rate_error)

    def _restart_sample_clock(self):
        self._origin = self.clock.now()
        self._ticks = 0

    def frame_words(self):
        """Names of the words one sample adds to the FIFO (register order)."""
        en = self.regs[FIFO_EN]
        words = []
        if en & 0x08:
            words += ["ax", "ay", "az"]
        if en & 0x80:
            words += ["temp"]
        words += [n for bit, n in ((0x40, "gx"), (0x20, "gy"), (0x10, "gz")) if en & bit]
        return words

    def samples(self, k):
        """Raw int16 gyro (n, 3), TEMP_OUT (n,) and accelerometer (n, 3) for sample indices ``k`` (array)."""
        if self.gyro_lsb is not None:
            g = self.gyro_lsb[k % len(self.gyro_lsb)]
        else:
            lsb = LSB_PER_DPS[(self.regs[GYRO_CONFIG] >> 3) & 3]
            g = np.round(self.gyro_dps[k % len(self.gyro_dps)] * lsb).astype(np.int64)
        g = np.clip(g, -32768, 32767)
        lsb_per_c, offset_c = TEMP_SCALE.get(self.chip_id, TEMP_SCALE[0x68])  # the chip's own TEMP_OUT scale
        t = np.round((self.temp_c[k % len(self.temp_c)] - offset_c) * lsb_per_c).astype(np.int64)
        if self.accel_lsb is not None:
            a = self.accel_lsb[k % len(self.accel_lsb)]
        else:
            lsb = LSB_PER_G[(self.regs[ACCEL_CONFIG] >> 3) & 3]
            a = np.round(self.accel_g[k % len(self.accel_g)] * lsb).astype(np.int64)
        return g, np.clip(t, -32768, 32767), np.clip(a, -32768, 32767)

    def sync(self):
        """Run the sample clock up to the virtual ``now``."""
        now = self.clock.now()
        if now >= self.reset_until and self.regs[PWR_MGMT_1] & 0x80:
            self.regs[PWR_MGMT_1] = 0x40           # reset finished: asleep, like power-on
            self._restart_sample_clock()
        if not self.awake():
            self._restart_sample_clock()
            return
        period = 1.0 / self.sample_rate_hz()
        due = int(math.floor((now - self._origin) / period + 1e-9))
        new = due - self._ticks
        if new <= 0:
            return
        self._ticks = due
        k = self.produced + np.arange(new)
        self.produced += new
        g, t, a = self.samples(k)
        regs = self.regs
        regs[ACCEL_XOUT_H:ACCEL_XOUT_H + 6] = np.asarray(a[-1], dtype=">i2").tobytes()
        regs[TEMP_OUT_H:TEMP_OUT_H + 2] = int(t[-1]).to_bytes(2, "big", signed=True)
        regs[GYRO_XOUT_H:GYRO_XOUT_H + 6] = np.asarray(g[-1], dtype=">i2").tobytes()
        if not regs[USER_CTRL] & 0x40:
            return
        words = self.frame_words()
        if not words:
            return
        frame_bytes = 2 * len(words)
        keep = min(new, self.fifo_size // frame_bytes + 2)   # older frames would be dropped anyway
        cols = {"ax": a[-keep:, 0], "ay": a[-keep:, 1], "az": a[-keep:, 2], "temp": t[-keep:],
                "gx": g[-keep:, 0], "gy": g[-keep:, 1], "gz": g[-keep:, 2]}
        block = np.column_stack([cols[w] for w in words]).astype(">i2").tobytes()
        dropped_before = (new - keep) * frame_bytes
        self.fifo += block
        excess = len(self.fifo) - self.fifo_size
        if excess > 0 or dropped_before:
            if excess > 0:
                del self.fifo[:excess]
            self.fifo_dropped_bytes += max(excess, 0) + dropped_before
            if regs[INT_ENABLE] & 0x10:
                regs[INT_STATUS] |= 0x10

    # ------------------------------------------------------------------ register access

    def fail(self, errno_value, times=1):
        """The next ``times`` transactions raise OSError(errno_value) without touching the model."""
        self.failures += [errno_value] * times

    def fail_fifo_read(self, errno_value, consume_bytes=0, after_reads=0):
        """The FIFO_R_W read after the next ``after_reads`` ones pops ``consume_bytes`` and then raises
        OSError(errno_value)."""
        self.fifo_failures.append([errno_value, consume_bytes, after_reads])

    def check_failure(self, reg, reading):
        """Called by the bus at the start of each transaction touching register ``reg``.

        ``reg``: register address (None for a quick command); ``reading``: True for a read.
        Raises OSError for a queued, NACKed (during reset) or random failure; returns None.
        """
        self.transactions += 1
        if self.failures:
            code = self.failures.pop(0)
            self.injected_errors += 1
            raise OSError(code, os.strerror(code))
        if reading and reg == FIFO_R_W and self.fifo_failures and self.fifo_failures[0][2] > 0:
            self.fifo_failures[0][2] -= 1
        elif reading and reg == FIFO_R_W and self.fifo_failures:
            self.sync()
            code, consume, _ = self.fifo_failures.pop(0)
            del self.fifo[:consume]
            self.injected_errors += 1
            raise OSError(code, os.strerror(code))
        if self.reset_nack and self.clock.now() < self.reset_until:
            self.injected_errors += 1
            raise OSError(_errno.EREMOTEIO, os.strerror(_errno.EREMOTEIO))   # busy resetting: NACK
        if self.error_rate and self.rng.random() < self.error_rate:
            self.injected_errors += 1
            raise OSError(self.error_errno, os.strerror(self.error_errno))

    def read(self, reg, length):
        """Burst read of ``length`` bytes starting at register address ``reg``; returns bytes.

        The pointer auto-increments except at FIFO_R_W, which pops FIFO bytes (0xFF when empty).
        """
        self.sync()
        out = bytearray()
        for _ in range(length):
            out.append(self._read_one(reg))
            if reg != FIFO_R_W:
                reg = (reg + 1) & 0x7F
        return bytes(out)

    def _read_one(self, reg):
        if reg in self.stuck:
            return self.stuck[reg]
        if reg == FIFO_R_W:
            if not self.fifo:
                return 0xFF
            value = self.fifo[0]
            del self.fifo[0]
            return value
        if reg == FIFO_COUNT_H:
            return (len(self.fifo) >> 8) & 0xFF
        if reg == FIFO_COUNT_L:
            return len(self.fifo) & 0xFF
        if reg == INT_STATUS:
            value = self.regs[INT_STATUS]
            self.regs[INT_STATUS] = 0
            return value
        if reg == PWR_MGMT_1 and self.clock.now() < self.reset_until:
            return 0xC0
        return self.regs[reg]

    def write(self, reg, data):
        """Burst write of ``data`` (byte values) starting at register address ``reg``; read-only
        and stuck registers ignore it, as does everything while a reset runs."""
        self.sync()
        for value in data:
            self._write_one(reg, value & 0xFF)
            if reg != FIFO_R_W:
                reg = (reg + 1) & 0x7F

    def _write_one(self, reg, value):
        if reg in self.stuck or reg in READ_ONLY:
            return
        if self.clock.now() < self.reset_until:
            return                                   # busy resetting
        if reg == PWR_MGMT_1 and value & 0x80:
            self._power_on()
            self.regs[PWR_MGMT_1] = 0xC0
            self.reset_until = math.inf if self.reset_stuck else self.clock.now() + self.reset_duration_s
            return
        if reg == USER_CTRL:
            if value & 0x04:
                self.fifo.clear()
                self.fifo_resets += 1
            value &= ~0x07                           # FIFO_RESET, I2C_MST_RESET, SIG_COND_RESET self-clear
        if reg == SIGNAL_PATH_RESET:
            value = 0
        if reg == FIFO_R_W:
            return
        self.regs[reg] = value
        if reg in (SMPLRT_DIV, CONFIG, PWR_MGMT_1):
            self._restart_sample_clock()


class FakeI2CBus:
    """Stands in for the kernel's i2c-dev: ``os.open`` of ``path`` and smbus2's ``ioctl``.

    devices: {address: MPU6050Model}. open_errno: errno for opening the path (2 = no bus, 13 = no
    permission). absent_errno: errno for a transaction to an address nobody answers (121 on a
    Raspberry Pi, 6 on some adapters). busy: addresses a kernel driver owns (I2C_SLAVE -> EBUSY).
    funcs: the adapter functionality mask (default: plain I2C + SMBus emulation, like i2c-bcm2835).
    bus_hz: if given, each transaction advances ``clock`` by its bit time at that SCL frequency
    (Hz). path: the bus device path it answers for. clock: the :class:`VirtualClock` to advance.

    Use as ``with FakeI2CBus({0x68: model}): MPU6050Source(1, ...)`` or with pytest's
    ``monkeypatch`` (:meth:`install`); then smbus2 really runs, down to its ioctl calls.
    """

    def __init__(self, devices, *, path="/dev/i2c-1", open_errno=None, absent_errno=_errno.EREMOTEIO,
                 busy=(), funcs=int(_smbus2.I2cFunc.I2C | _smbus2.I2cFunc.SMBUS_EMUL), clock=None,
                 bus_hz=None):
        self.devices = dict(devices)
        self.path = path
        self.open_errno = open_errno
        self.absent_errno = absent_errno
        self.busy = set(busy)
        self.funcs = funcs
        self.clock = clock
        self.bus_hz = bus_hz
        self.fds = {}
        self.next_fd = 100000
        self.ioctl_calls = 0
        self.requests = {}            # ioctl request -> count
        self.bus_bits = 0
        self._undo = []

    # ------------------------------------------------------------------ OS boundary

    def install(self, monkeypatch=None):
        """Replace os.open/os.close (for this bus path only) and smbus2's ioctl; return self.

        ``monkeypatch``: a pytest ``monkeypatch`` fixture, which then undoes the patches itself;
        without it the originals are kept for :meth:`uninstall`.
        """
        real_open, real_close = os.open, os.close

        def fake_open(path, flags, *args, **kwargs):
            if path == self.path:
                if self.open_errno is not None:
                    raise OSError(self.open_errno, os.strerror(self.open_errno), path)
                fd = self.next_fd
                self.next_fd += 1
                self.fds[fd] = None
                return fd
            return real_open(path, flags, *args, **kwargs)

        def fake_close(fd):
            if fd in self.fds:
                del self.fds[fd]
                return None
            return real_close(fd)

        patches = [(os, "open", fake_open), (os, "close", fake_close), (_smbus2, "ioctl", self.ioctl)]
        for obj, name, value in patches:
            if monkeypatch is not None:
                monkeypatch.setattr(obj, name, value)
            else:
                self._undo.append((obj, name, getattr(obj, name)))
                setattr(obj, name, value)
        return self

    def uninstall(self):
        """Restore what :meth:`install` replaced (without ``monkeypatch``); safe to call twice."""
        while self._undo:
            obj, name, value = self._undo.pop()
            setattr(obj, name, value)

    def __enter__(self):
        return self.install()

    def __exit__(self, *exc):
        self.uninstall()

    def _device(self, fd, addr=None):
        if fd not in self.fds:
            raise OSError(_errno.EBADF, os.strerror(_errno.EBADF))
        addr = self.fds[fd] if addr is None else addr
        dev = self.devices.get(addr)
        if dev is None:
            raise OSError(self.absent_errno, os.strerror(self.absent_errno))
        return dev

    def _spend(self, n_bytes, n_messages=1):
        # start + address + ack per message, 9 bits per byte, stop
        bits = 10 * n_messages + 9 * n_bytes + 1
        self.bus_bits += bits
        if self.bus_hz and self.clock is not None:
            self.clock.advance(bits / self.bus_hz)

    def ioctl(self, fd, request, arg=0, *rest):
        """smbus2's ``ioctl`` as i2c-dev answers it: I2C_FUNCS (``funcs``), I2C_SLAVE(_FORCE)
        (selects the address; EBUSY for ``busy`` ones), I2C_SMBUS and I2C_RDWR (act on the
        model). ``fd``: a descriptor from the patched ``os.open``; ``request``: the ioctl number;
        ``arg``: smbus2's ctypes structure or the address. Returns 0; raises OSError as the
        kernel would (EBADF, EINVAL, ENOTTY, the absent-device errno, injected errors).
        """
        self.ioctl_calls += 1
        self.requests[request] = self.requests.get(request, 0) + 1
        if request == _smbus2.I2C_FUNCS:
            if fd not in self.fds:
                raise OSError(_errno.EBADF, os.strerror(_errno.EBADF))
            arg.value = self.funcs
            return 0
        if request in (_smbus2.I2C_SLAVE, _smbus2.I2C_SLAVE_FORCE):
            if fd not in self.fds:
                raise OSError(_errno.EBADF, os.strerror(_errno.EBADF))
            if arg in self.busy and request == _smbus2.I2C_SLAVE:
                raise OSError(_errno.EBUSY, os.strerror(_errno.EBUSY))
            self.fds[fd] = arg
            return 0
        if request == _smbus2.I2C_SMBUS:
            return self._smbus(fd, arg)
        if request == _smbus2.I2C_RDWR:
            return self._rdwr(fd, arg)
        raise OSError(_errno.ENOTTY, os.strerror(_errno.ENOTTY))

    def _smbus(self, fd, msg):
        dev = self._device(fd)
        rw, cmd, size = msg.read_write, msg.command, msg.size
        reading = rw == _smbus2.I2C_SMBUS_READ
        if size == _smbus2.I2C_SMBUS_QUICK:
            dev.check_failure(None, False)
            self._spend(0)
            return 0
        dev.check_failure(cmd, reading)
        data = msg.data.contents
        if size == _smbus2.I2C_SMBUS_BYTE_DATA:
            if reading:
                data.byte = dev.read(cmd, 1)[0]
                self._spend(3, 2)
            else:
                dev.write(cmd, [data.byte])
                self._spend(2)
        elif size == _smbus2.I2C_SMBUS_WORD_DATA:
            if reading:
                lo, hi = dev.read(cmd, 2)       # SMBus words are little-endian on the wire
                data.word = lo | (hi << 8)
                self._spend(4, 2)
            else:
                dev.write(cmd, [data.word & 0xFF, data.word >> 8])
                self._spend(3)
        elif size == _smbus2.I2C_SMBUS_I2C_BLOCK_DATA:
            n = data.block[0]
            if not 1 <= n <= _smbus2.I2C_SMBUS_BLOCK_MAX:
                raise OSError(_errno.EINVAL, os.strerror(_errno.EINVAL))
            if reading:
                data.block[1:n + 1] = list(dev.read(cmd, n))
                self._spend(n + 2, 2)
            else:
                dev.write(cmd, list(data.block[1:n + 1]))
                self._spend(n + 2)
        else:
            raise OSError(_errno.EOPNOTSUPP, os.strerror(_errno.EOPNOTSUPP))
        return 0

    def _rdwr(self, fd, ioctl_data):
        if fd not in self.fds:
            raise OSError(_errno.EBADF, os.strerror(_errno.EBADF))
        n = ioctl_data.nmsgs
        if not 1 <= n <= 42:                       # I2C_RDRW_IOCTL_MAX_MSGS
            raise OSError(_errno.EINVAL, os.strerror(_errno.EINVAL))
        msgs = [ioctl_data.msgs[i] for i in range(n)]
        pointer = {}
        total = 0
        for i, m in enumerate(msgs):
            if m.len > 8192:
                raise OSError(_errno.EINVAL, os.strerror(_errno.EINVAL))
            dev = self._device(fd, addr=m.addr)
            if m.flags & _smbus2.I2C_M_RD:
                reg = pointer.get(m.addr, 0)
                if i == 0 or not msgs[i - 1].flags & _smbus2.I2C_M_RD:
                    dev.check_failure(reg, True)
                data = dev.read(reg, m.len)
                ctypes.memmove(m.buf, data, m.len)
            else:
                raw = ctypes.string_at(m.buf, m.len)
                if raw:
                    pointer[m.addr] = raw[0]
                    if i + 1 == n or msgs[i + 1].flags & _smbus2.I2C_M_RD == 0 or len(raw) > 1:
                        dev.check_failure(raw[0], False)
                    if len(raw) > 1:
                        dev.write(raw[0], list(raw[1:]))
            total += m.len
        self._spend(total, n)
        return 0


def samples_from_recording(rec, lsb_per_dps):
    """Raw gyro LSB (N, 3) for the model from a :class:`gyrofilter.recording.Recording`.

    ``rec``: the recording (its ``gyro_dps``, deg/s); ``lsb_per_dps``: the scale of the range
    the driver will set (131 for +-250 deg/s). Returns int64 LSB, rounded and clipped to int16,
    to pass as ``MPU6050Model(gyro_lsb=...)``.
    """
    return np.clip(np.round(rec.gyro_dps * lsb_per_dps), -32768, 32767).astype(np.int64)
