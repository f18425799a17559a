"""MPU-6050 driver through smbus2's real code; only os.open/os.close and smbus2's ioctl are fakes.

The register-level model (gyrofilter/sources/mpu6050/model.py) runs on a virtual clock shared with the driver,
so sample timing is deterministic and no test depends on the host's speed.
"""
import errno
import os
import sys

import numpy as np
import pytest


from gyrofilter.sources.mpu6050.model import FakeI2CBus, MPU6050Model, VirtualClock, samples_from_recording

from gyrofilter.errors import DeviceError, SettingsError, SourceEnded
from gyrofilter.recording import Recording
from gyrofilter.sources.mpu6050 import registers as R
from gyrofilter.sources.mpu6050.driver import open_mpu6050
from gyrofilter.sources.mpu6050.chip import auto_dlpf_cfg, decode_fifo, sample_rate_settings
from support import RECORDINGS


def indexed_gyro(n):
    """gx encodes the sample index (k mod 65536, offset to cover -32768..32767); gy, gz derived."""
    k = np.arange(n)
    gx = k % 65536 - 32768
    gy = (k // 65536) * 7 - 100
    gz = (k * 7919) % 65536 - 32768
    return np.column_stack([gx, gy, gz])


def indexed_accel(n):
    """ax, ay, az that differ from the gyro words and from each other for every sample index (so a
    frame read from the wrong offset, or a gyro word taken for an accelerometer word, shows)."""
    k = np.arange(n)
    return np.column_stack([(k * 31 + 11) % 65536 - 32768, (k * 7 + 5) % 65536 - 32768, 16384 - k % 4000])


def index_of(rows):
    """Recover model sample indices from gx, gy (see indexed_gyro)."""
    gx = rows[:, 1].astype(np.int64)
    gy = rows[:, 2].astype(np.int64)
    return (gy + 100) // 7 * 65536 + gx + 32768


@pytest.fixture
def rig(monkeypatch):
    """Factory: rig(**model kwargs) -> (clock, model, bus) installed at /dev/i2c-1, address 0x68."""

    def make(address=0x68, bus_kwargs=None, **model_kwargs):
        clock = VirtualClock()
        model = MPU6050Model(clock, **model_kwargs)
        bus = FakeI2CBus({address: model}, clock=clock, **(bus_kwargs or {})).install(monkeypatch)
        return clock, model, bus
    return make


def open_src(clock, **kwargs):
    kwargs.setdefault("sample_rate_hz", 1000)
    return open_mpu6050(clock=clock.now, sleep=clock.sleep, wall_clock=lambda: 1.7e9, **kwargs)


def read_for(src, clock, seconds):
    out, notes = [], []
    end = clock.now() + seconds
    while clock.now() < end:
        out.append(src.read())
        notes += src.pop_notes()
    return np.concatenate(out), notes


# ------------------------------------------------------------------------------------------ pure


def test_decode_big_endian_twos_complement_extremes():
    buf = bytes([0x80, 0x00, 0x7F, 0xFF, 0xFF, 0xFF, 0x00, 0x01, 0x12, 0x34, 0xED, 0xCC])
    words = decode_fifo(buf, 3)
    assert words.tolist() == [[-32768, 32767, -1], [1, 0x1234, -0x1234]]


def test_sample_rate_divider_and_refusal():
    assert sample_rate_settings(100, 3) == (9, 100.0, 1000.0)      # 1 kHz / (1 + 9)
    assert sample_rate_settings(1000, 0) == (7, 1000.0, 8000.0)    # 8 kHz / (1 + 7)
    assert sample_rate_settings(8000, 0) == (0, 8000.0, 8000.0)
    with pytest.raises(SettingsError, match="DLPF_CFG 7 is reserved"):
        sample_rate_settings(8000, 7)
    with pytest.raises(SettingsError, match="takes 0..6"):
        sample_rate_settings(100, 8)
    assert sample_rate_settings(1000 / 3, 1)[0] == 2
    with pytest.raises(SettingsError, match=r"333.333 Hz \(SMPLRT_DIV=2\) or 250 Hz \(SMPLRT_DIV=3\)"):
        sample_rate_settings(300, 1)
    with pytest.raises(SettingsError, match="SMPLRT_DIV 0..255"):
        sample_rate_settings(1, 1)                                   # needs divider 999
    # automatic DLPF: widest bandwidth below Nyquist
    assert [auto_dlpf_cfg(r) for r in (1000, 200, 100, 50, 25, 12.5)] == [0, 2, 3, 4, 5, 6]


def test_smbus2_imported_only_when_a_device_is_opened():
    import subprocess
    code = ("import sys, gyrofilter, gyrofilter.sources.mpu6050.driver as m; "
            "print('smbus2' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_register_fields_match_datasheet():
    assert R.GYRO_CONFIG.put(0, "FS_SEL", 3) == 0x18           # bits 4:3
    assert R.CONFIG.put(0, "DLPF_CFG", 6) == 0x06              # bits 2:0, not 4:3
    assert R.PWR_MGMT_1.reset == 0x40 and R.PWR_MGMT_1.mask("DEVICE_RESET") == 0x80
    assert R.INT_STATUS.mask("FIFO_OFLOW_INT") == 0x10
    assert R.FIFO_EN.mask("TEMP_FIFO_EN") == 0x80 and R.FIFO_EN.mask("ZG_FIFO_EN") == 0x10
    assert (R.FIFO_COUNT_H.address, R.FIFO_R_W.address, R.WHO_AM_I.address) == (0x72, 0x74, 0x75)


def test_bad_settings_refused_before_bus_traffic(rig):
    clock, model, bus = rig()
    with pytest.raises(SettingsError, match="range_dps=300"):
        open_src(clock, range_dps=300)
    with pytest.raises(SettingsError, match="0x68 \\(AD0 low\\) or 0x69"):
        open_src(clock, address=0x50)
    assert bus.ioctl_calls == 0


# ------------------------------------------------------------------------------------------ start-up


@pytest.mark.parametrize("range_dps,fs_bits,lsb", [(250, 0x00, "131"), (500, 0x08, "65.5"),
                                                   (1000, 0x10, "32.8"), (2000, 0x18, "16.4")])
def test_configuration_written_and_header(rig, range_dps, fs_bits, lsb):
    clock, model, bus = rig()
    src = open_src(clock, sample_rate_hz=100, range_dps=range_dps, dlpf=3)
    regs = model.regs
    assert regs[0x6B] == 0x01                     # awake, CLKSEL = 1 (PLL, X gyro)
    assert regs[0x1B] == fs_bits
    assert regs[0x1A] == 0x03 and regs[0x19] == 9  # DLPF_CFG 3, 1 kHz / (1 + 9)
    assert regs[0x23] == 0xF8                     # TEMP + XG + YG + ZG + ACCEL into the FIFO
    assert regs[0x1C] == 0x00                     # ACCEL_CONFIG.AFS_SEL 0: +-2 g
    assert regs[0x38] & 0x10 and regs[0x6A] & 0x40
    assert model.sample_rate_hz() == 100.0
    h = src.header
    assert (h["sensor"], h["chip_id"], h["gyro_unit"], h["lsb_per_dps"]) == ("MPU6050", "0x68", "lsb", lsb)
    assert (h["full_scale_dps"], h["dlpf_cfg"], h["sample_rate_hz"]) == (str(range_dps), "3", "100")
    assert (h["i2c_bus"], h["i2c_address"]) == ("/dev/i2c-1", "0x68")
    assert h["start_time_utc"] == "2023-11-14T22:13:20.000Z"
    assert (h["accel_unit"], h["lsb_per_g"], h["full_scale_g"]) == ("lsb", "16384", "2")
    assert src.columns == ["t", "gx", "gy", "gz", "temp", "ax", "ay", "az"]
    src.close()
    assert regs[0x6B] & 0x40 and not bus.fds      # asleep again, bus closed


def test_chip_starts_asleep_and_is_reset_first(rig):
    clock, model, bus = rig()
    model.regs[0x1B] = 0x18                       # leftover state from an earlier program
    model.regs[0x6B] = 0x00
    src = open_src(clock, sample_rate_hz=100, range_dps=250)
    assert model.regs[0x1B] == 0x00               # DEVICE_RESET cleared it, then 250 dps written
    assert src.header["lsb_per_dps"] == "131"
    fresh = MPU6050Model(VirtualClock())
    assert fresh.regs[0x6B] == 0x40 and not fresh.awake()


@pytest.mark.parametrize("reg,name", [(0x1B, "GYRO_CONFIG \\(0x1B\\)"), (0x1A, "CONFIG \\(0x1A\\)"),
                                      (0x19, "SMPLRT_DIV \\(0x19\\)"), (0x23, "FIFO_EN \\(0x23\\)")])
def test_readback_mismatch_refused(rig, reg, name):
    clock, model, bus = rig(stuck={reg: 0x00})
    with pytest.raises(DeviceError, match=f"register {name} reads back 0x00"):
        open_src(clock, sample_rate_hz=125, range_dps=2000, dlpf=1)   # every one of these is nonzero
    assert not bus.fds                                         # bus closed after the refusal


def test_chip_silent_during_reset_is_waited_for(rig):
    clock, model, bus = rig(reset_duration_s=0.15, reset_nack=True)
    src = open_src(clock)                                      # 100 ms sleep, then NACKs until 150 ms
    assert src.stats["retries"] == model.injected_errors > 0
    assert model.regs[0x6B] == 0x01


def test_reset_that_never_finishes_times_out(rig):
    clock, model, bus = rig(reset_stuck=True)
    t0 = clock.now()
    with pytest.raises(DeviceError, match=r"reset did not finish.*PWR_MGMT_1 \(0x6B\) still reads 0xC0"):
        open_src(clock, reset_timeout_s=0.3)
    assert 0.3 <= clock.now() - t0 < 0.5                       # bounded wait (virtual time)
    clock, model, bus = rig(reset_stuck=True, reset_nack=True)  # one that never answers again
    t0 = clock.now()
    with pytest.raises(DeviceError, match=r"PWR_MGMT_1 \(0x6B\) after repeated attempt\(s\) \(errno 121"):
        open_src(clock, reset_timeout_s=0.3)
    assert clock.now() - t0 < 0.5


# ------------------------------------------------------------------------------------------ errors


@pytest.mark.parametrize("chip,name", [(0x70, "MPU6500"), (0x71, "MPU9250"), (0x73, "MPU9255"),
                                       (0x72, "clone"), (0x98, "ICM-20689")])
def test_relatives_named_and_refused_unless_allowed(rig, chip, name):
    clock, model, bus = rig(chip_id=chip, temp_c=31.0)
    with pytest.raises(DeviceError, match=f"{name}.*WHO_AM_I 0x{chip:02X}.*allow_chip=0x{chip:02X}"):
        open_src(clock)
    src = open_src(clock, allow_chip=chip if chip % 2 else [f"0x{chip:02x}"])   # int or list of strings
    assert src.header["chip_id"] == f"0x{chip:02X}" and name in src.header["sensor"]
    assert src.fifo_size_bytes == 512
    rows, _ = read_for(src, clock, 0.05)
    np.testing.assert_allclose(rows[:, 4], 31.0, atol=0.01)  # the chip's own temperature scale, both ends
    src.close()


def test_unknown_and_incompatible_chips_refused(rig):
    clock, model, bus = rig(chip_id=0x00)
    with pytest.raises(DeviceError, match="WHO_AM_I \\(0x75\\) = 0x00.*not a known relative.*i2cdetect -y 1"):
        open_src(clock, allow_chip=True)
    model.regs[0x75] = model.chip_id = 0x47
    with pytest.raises(DeviceError, match="ICM-42688-P.*MPU6050 register map only"):
        open_src(clock, allow_chip=True)


def test_missing_bus_message(rig):
    clock, model, bus = rig(bus_kwargs={"open_errno": errno.ENOENT})
    with pytest.raises(DeviceError, match=r"^no I2C bus /dev/i2c-1: enable I2C \(sudo raspi-config"):
        open_src(clock)
    bus.open_errno = errno.EACCES
    with pytest.raises(DeviceError, match="permission denied opening /dev/i2c-1: add your user to the i2c group"):
        open_src(clock)


@pytest.mark.parametrize("code", [errno.EREMOTEIO, errno.ENXIO])
def test_missing_chip_message(rig, code):
    clock, model, bus = rig(address=0x68, bus_kwargs={"absent_errno": code})
    with pytest.raises(DeviceError) as info:
        open_src(clock, address=0x69)
    msg = str(info.value)
    assert "\n" not in msg
    assert msg.startswith(f"no chip answers at 0x69 on /dev/i2c-1 (errno {code}")
    assert "AD0" in msg and "`i2cdetect -y 1`" in msg and "SDA" in msg


def test_busy_address_message(rig):
    clock, model, bus = rig(bus_kwargs={"busy": {0x68}})
    with pytest.raises(DeviceError, match="busy.*kernel driver.*dtoverlay=mpu6050"):
        open_src(clock)


def test_transient_errors_retried_and_counted(rig):
    clock, model, bus = rig(gyro_lsb=indexed_gyro(5000))
    model.fail(errno.EREMOTEIO, times=3)          # WHO_AM_I read fails three times, then answers
    src = open_src(clock)
    assert src.stats["retries"] == 3
    model.fail(errno.EIO, times=2)                # INT_STATUS at the next poll
    rows, notes = read_for(src, clock, 0.2)
    assert src.stats["retries"] == 5 and notes == []
    assert np.all(np.diff(index_of(rows)) == 1)
    model.fail(errno.EIO, times=src.max_retries + 1)
    with pytest.raises(DeviceError, match=r"INT_STATUS \(0x3A\) after 6 attempt\(s\) \(errno 5"):
        src.read()


# ------------------------------------------------------------------------------------------ streaming


@pytest.mark.parametrize("transfer", ["smbus", "rdwr"])
def test_many_fifo_reads_nothing_lost_or_duplicated(rig, transfer):
    n = 70_000                                    # > 65536: every int16 value of gx passes through
    clock, model, bus = rig(gyro_lsb=indexed_gyro(n + 10_000), temp_c=np.linspace(20, 40, n + 10_000),
                            error_rate=0.01, error_errno=errno.EREMOTEIO, rng=np.random.default_rng(7),
                            bus_kwargs={"bus_hz": 400e3})
    src = open_src(clock, sample_rate_hz=1000, transfer=transfer)
    rows, notes = read_for(src, clock, n / 1000)
    idx = index_of(rows)
    k0 = idx[0]
    assert notes == [] and src.stats["lost_samples"] == 0
    np.testing.assert_array_equal(idx, k0 + np.arange(len(rows)))            # in order, once each
    np.testing.assert_array_equal(rows[:, 1:4], indexed_gyro(n + 10_000)[idx])
    np.testing.assert_array_equal(rows[:, 0], np.arange(len(rows)) / 1000.0)  # t from the index
    assert rows[:, 1].min() == -32768 and rows[:, 1].max() == 32767
    temp = np.linspace(20, 40, n + 10_000)[idx]
    assert np.max(np.abs(rows[:, 4] - temp)) <= 0.5 / 340 + 1e-9             # T = raw/340 + 36.53
    assert len(rows) >= n - 100 and src.stats["samples"] == len(rows)
    assert src.stats["retries"] == model.injected_errors > 100
    assert model.fifo_dropped_bytes == 0
    src.close()


def test_decoded_rates_equal_model_rates_from_a_recording(rig):
    rng = np.random.default_rng(3)
    n = 3000
    t = np.arange(n) / 200.0
    dps = np.column_stack([-3.3 + 0.2 * rng.standard_normal(n), 1.1 + 30 * np.sin(2 * np.pi * 0.5 * t),
                           np.full(n, 600.0)])           # z beyond +-500: clipped by the sensor
    rec = Recording.from_dps(dps, 200.0)
    clock, model, bus = rig(gyro_dps=rec.gyro_dps, temp_c=31.0)
    src = open_src(clock, sample_rate_hz=200, range_dps=500, temperature=False, accel=False)
    assert src.columns == ["t", "gx", "gy", "gz"]
    rows, _ = read_for(src, clock, 5.0)
    # first FIFO sample is model sample k0: find it from x, y (continuous values)
    lsb = 65.5
    expect = np.clip(np.round(rec.gyro_dps * lsb), -32768, 32767)
    k0 = next(k for k in range(n) if np.array_equal(expect[k:k + 5], rows[:5, 1:4]))
    np.testing.assert_array_equal(rows[:, 1:4], expect[k0:k0 + len(rows)])
    dec = rows[:, 1:4] / float(src.header["lsb_per_dps"])
    assert np.max(np.abs(dec[:, :2] - dps[k0:k0 + len(rows), :2])) <= 0.5 / lsb + 1e-12
    assert np.all(rows[:, 3] == 32767)
    np.testing.assert_array_equal(samples_from_recording(rec, lsb)[k0:k0 + len(rows)], rows[:, 1:4])


def test_extremes_through_the_fifo(rig):
    g = np.array([[-32768, 32767, 0], [32767, -32768, -1], [1, -1, 12345]])
    clock, model, bus = rig(gyro_lsb=np.tile(g, (400, 1)))
    src = open_src(clock, sample_rate_hz=1000, transfer="smbus")
    rows, _ = read_for(src, clock, 0.3)
    got = {tuple(r) for r in rows[:, 1:4].astype(int)}
    assert got == {tuple(r) for r in g}


@pytest.mark.parametrize("extra_s,exact", [(0.5, True), (0.5004, False)])
def test_overflow_reported_with_count_and_jump_in_t(rig, extra_s, exact):
    clock, model, bus = rig(gyro_lsb=indexed_gyro(20_000))
    src = open_src(clock, sample_rate_hz=1000, temperature=False)     # 6-byte frames: 170 fit in 1024 bytes
    before, _ = read_for(src, clock, 0.2)
    clock.advance(extra_s)                                     # the host stalls: > 170 ms of samples
    after, notes = read_for(src, clock, 0.3)
    assert model.fifo_dropped_bytes > 0 and model.regs[0x38] & 0x10
    assert len(notes) == 1 and "FIFO overflow" in notes[0]
    idx_b, idx_a = index_of(before), index_of(after)
    true_lost = idx_a[0] - idx_b[-1] - 1
    reported = src.stats["lost_samples"]
    assert notes[0].startswith(f"gap: {reported} samples lost before t=")
    if exact:   # virtual clock: the sensor's sample grid coincides with the driver's anchor
        assert reported == true_lost
    else:       # elapsed-time estimate: off by at most one sample at an unknown phase
        assert abs(reported - true_lost) <= 1
    # t jumps by the reported count, and data on both sides keep their order and alignment
    t = np.concatenate([before[:, 0], after[:, 0]]) * 1000
    steps = np.round(np.diff(t)).astype(int)
    assert sorted(set(steps)) == [1, reported + 1] and list(steps).count(reported + 1) == 1
    np.testing.assert_array_equal(np.diff(idx_a), 1)
    assert float(notes[0].split("t=")[1].split(" s")[0]) == pytest.approx(after[0, 0])
    assert src.stats["overflows"] == 1


def test_gap_estimate_does_not_accumulate_clock_drift(rig):
    """Sensor clock 1 % fast: after 60 s the lost count is still right to +-1 % of the stall."""
    clock, model, bus = rig(gyro_lsb=indexed_gyro(80_000), rate_error=0.01)
    src = open_src(clock, sample_rate_hz=1000, temperature=False)
    before, _ = read_for(src, clock, 60.0)
    clock.advance(0.5)
    after, notes = read_for(src, clock, 0.2)
    true_lost = index_of(after)[0] - index_of(before)[-1] - 1
    assert len(notes) == 1 and true_lost > 400
    assert abs(src.stats["lost_samples"] - true_lost) <= 1 + 0.01 * 500   # not 1 % of 60 s = 600


def test_overflow_seen_through_count_when_status_was_missed(rig):
    clock, model, bus = rig(gyro_lsb=indexed_gyro(20_000))
    src = open_src(clock, sample_rate_hz=1000, temperature=False)
    read_for(src, clock, 0.1)
    clock.advance(0.169)                          # 169-ish frames: FIFO nearly full, no overflow yet
    model.regs[0x38] = 0                          # no status bit from the chip
    clock.advance(0.05)
    rows, notes = read_for(src, clock, 0.1)
    assert src.stats["overflows"] == 1 and "FIFO overflow" in notes[0]
    np.testing.assert_array_equal(np.diff(index_of(rows)), 1)


def test_fifo_read_failing_part_way_resets_fifo_and_keeps_alignment(rig):
    clock, model, bus = rig(gyro_lsb=indexed_gyro(20_000))
    src = open_src(clock, sample_rate_hz=1000, temperature=False, transfer="rdwr")
    a, _ = read_for(src, clock, 0.1)
    model.fail_fifo_read(errno.EIO, consume_bytes=9)         # stopped part-way: 1.5 frames gone
    b, notes = read_for(src, clock, 0.2)
    assert len(notes) == 1 and "errno 5" in notes[0]
    rows = np.concatenate([a, b])
    idx = index_of(rows)
    assert np.all(np.diff(idx) >= 1)                         # nothing duplicated, nothing misread
    np.testing.assert_array_equal(rows[:, 1:4], indexed_gyro(20_000)[idx])
    assert abs((idx - idx[0]) - np.round(rows[:, 0] * 1000)).max() <= 1


@pytest.mark.parametrize("transfer", ["smbus", "rdwr"])
def test_gaps_on_a_busy_bus_do_not_drift_t(rig, transfer):
    """Attack pass 16 (issue 37): the samples lost at a FIFO reset (EIO part-way) are counted up to
    the moment the FIFO is enabled again; counted to the failure, those produced during the reset
    (and its retries) went uncounted, and every later t came out early: 2 to 6 samples at a gap,
    118 after 166 gaps in 20 s at 1 kHz with 2 % of transfers failing. Each gap's count may miss
    by one sample either way (the host clock), never more."""
    n = 40_000
    clock, model, bus = rig(gyro_lsb=indexed_gyro(n), error_rate=0.02, error_errno=errno.EIO,
                            rng=np.random.default_rng(8), bus_kwargs={"bus_hz": 400e3})
    src = open_src(clock, sample_rate_hz=1000, transfer=transfer)
    rows, notes = read_for(src, clock, 20.0)
    idx = index_of(rows)
    np.testing.assert_array_equal(rows[:, 1:4], indexed_gyro(n)[idx])   # whole frames, in order
    t_error = (idx - idx[0]) - np.round((rows[:, 0] - rows[0, 0]) * 1000).astype(np.int64)  # samples
    gaps = sum(note.startswith("gap:") for note in notes)
    assert gaps > 10
    assert np.abs(np.diff(t_error)).max() <= 1
    assert abs(t_error[-1]) <= gaps / 3


def test_overflow_during_a_read_drops_its_frames(rig):
    """Attack pass 16 (issue 37): where the bus is slow for the rate (1 kHz, 14-byte frames, 100 kHz
    SCL) a read after a retry outlasts the FIFO's margin, the chip drops the oldest bytes while
    they are read, and the rest of the read came out a word or more off (gx read from TEMP_OUT,
    ...), delivered as data, the overflow seen only at the next poll. INT_STATUS is read again
    after the read: its frames are dropped, a gap."""
    n = 40_000
    clock, model, bus = rig(gyro_lsb=indexed_gyro(n), error_rate=0.01, error_errno=errno.EREMOTEIO,
                            rng=np.random.default_rng(0), bus_kwargs={"bus_hz": 100e3})
    src = open_src(clock, sample_rate_hz=1000, transfer="smbus")
    rows, notes = read_for(src, clock, 5.0)
    idx = index_of(rows)
    assert idx.min() >= 0 and idx.max() < n
    np.testing.assert_array_equal(rows[:, 1:4], indexed_gyro(n)[idx])   # every row one sample's words
    assert np.all(np.diff(idx) >= 1)
    assert model.fifo_dropped_bytes > 0 and any("while it was read" in note for note in notes)


def test_misaligned_count_is_resynchronised(rig):
    clock, model, bus = rig(gyro_lsb=indexed_gyro(20_000))
    src = open_src(clock, sample_rate_hz=1000, temperature=False, accel=False, transfer="rdwr")
    a, _ = read_for(src, clock, 0.1)
    model.fail_fifo_read(errno.EREMOTEIO, consume_bytes=3)   # a NACK that still ate 3 bytes
    b, notes = read_for(src, clock, 0.2)
    assert src.stats["resyncs"] == 1 and "not a whole number of 6-byte frames" in notes[0]
    idx = index_of(np.concatenate([a, b]))
    np.testing.assert_array_equal(np.concatenate([a, b])[:, 1:4], indexed_gyro(20_000)[idx])
    assert np.all(np.diff(idx) >= 1)


def test_8khz_polls_often_enough_for_the_fifo(rig):
    clock, model, bus = rig(gyro_lsb=indexed_gyro(20_000))
    src = open_src(clock, sample_rate_hz=8000, dlpf="0", address="0x68", temperature=False, accel=False)
    assert src.smplrt_div == 0 and src.poll_interval_s == pytest.approx(170 / 8000 / 4)
    rows, notes = read_for(src, clock, 1.0)
    assert notes == [] and len(rows) >= 7900
    np.testing.assert_array_equal(np.diff(index_of(rows)), 1)


@pytest.mark.parametrize("funcs,rdwr", [(0x0EFF0009, True), (0x0EFF0008, False)])
def test_auto_transfer_follows_adapter_functionality(rig, funcs, rdwr):
    import smbus2.smbus2 as s2
    clock, model, bus = rig(gyro_lsb=indexed_gyro(5000), bus_kwargs={"funcs": funcs})
    src = open_src(clock)
    rows, _ = read_for(src, clock, 0.2)
    assert src.use_rdwr is rdwr and len(rows) > 150
    assert (bus.requests.get(s2.I2C_RDWR, 0) > 0) is rdwr


def test_read_waits_at_most_max_wait(rig):
    clock, model, bus = rig()
    src = open_src(clock, sample_rate_hz=1000)
    model.regs[0x6A] = 0                          # FIFO stopped behind the driver's back: no data
    t0 = clock.now()
    rows = src.read()
    assert rows.shape == (0, 8)
    assert clock.now() - t0 <= src.max_wait_s + src.poll_interval_s + 1e-9


# ------------------------------------------------------------------------------------------ device


@pytest.mark.device
def test_real_mpu6050_streams_at_the_configured_rate():
    """On a Raspberry Pi with an MPU6050 at 0x68 on /dev/i2c-1 (see docs/mpu6050.md)."""
    bus = int(os.environ.get("GYROFILTER_I2C_BUS", "1"))
    address = int(os.environ.get("GYROFILTER_I2C_ADDRESS", "0x68"), 0)
    import time
    with open_mpu6050(bus=bus, address=address, sample_rate_hz=1000, range_dps=250) as src:
        got = []
        t_end = time.monotonic() + 3.0
        while time.monotonic() < t_end:
            got.append(src.read())
        rows = np.concatenate(got)
        assert src.pop_notes() == [] and src.stats["lost_samples"] == 0
        assert 2700 <= len(rows) <= 3300                  # sensor clock within 10 % of 1 kHz
        np.testing.assert_allclose(np.diff(rows[:, 0]), 1e-3)
        assert np.all(np.abs(rows[:, 1:4]) < 32767)       # a resting sensor is far from full scale
        assert 0.0 < np.median(rows[:, 4]) < 60.0         # plausible temperature, deg C
        g = np.linalg.norm(rows[:, 5:8], axis=1) / float(src.header["lsb_per_g"])
        assert 0.8 < np.median(g) < 1.2                   # at rest the accelerometer reads 1 g


REAL = str(RECORDINGS / "mpu6050_multipose_102s.csv.gz")


@pytest.mark.skipif(not os.path.exists(REAL), reason="real recording not converted yet")
def test_real_recording_round_trips_through_fifo_and_smbus2(rig):
    """A real MPU6050 log (LSB, saturating at -32768/32767) replayed by the model comes back exactly."""
    from gyrofilter.recording import read_recording

    rec = read_recording(REAL)
    raw = rec.gyro.astype(np.int64)
    assert raw.min() == -32768 and raw.max() == 32767           # the file does saturate
    n = len(raw)
    ramp = np.column_stack([np.arange(n) % 65536 - 32768, np.zeros(n, int), np.zeros(n, int)])
    clock, model, bus = rig(gyro_lsb=np.concatenate([ramp[:2000], raw]))   # lead-in to find k0
    src = open_src(clock, sample_rate_hz=100, range_dps=250, transfer="smbus")
    rows, notes = read_for(src, clock, (2000 + n) / 100 + 1)
    k0 = int(rows[0, 1]) + 32768                                # lead-in encodes the index
    lead = 2000 - k0
    np.testing.assert_array_equal(rows[lead:lead + n, 1:4], raw)
    assert notes == [] and np.allclose(np.diff(rows[:, 0]), 0.01)


def test_opened_through_the_source_syntax_on_the_real_clock(monkeypatch):
    """The SOURCE text of record/run reaches open_mpu6050; the model follows the host's clock."""
    import time

    from gyrofilter.sources import open_source

    class HostClock:
        now = staticmethod(time.monotonic)

    model = MPU6050Model(HostClock(), gyro_lsb=indexed_gyro(200_000))
    FakeI2CBus({0x69: model}).install(monkeypatch)
    src = open_source("mpu6050:bus=1,addr=0x69,rate=200,range=500,dlpf=2,temp=0,accel=0")
    try:
        h = src.header
        assert (h["i2c_address"], h["sample_rate_hz"], h["lsb_per_dps"], h["dlpf_cfg"]) == \
            ("0x69", "200", "65.5", "2")
        assert src.columns == ["t", "gx", "gy", "gz"] and model.regs[0x19] == 4   # 1 kHz / (1 + 4)
        rows = np.concatenate([src.read() for _ in range(4)])
        assert len(rows) > 0
        if not src.pop_notes():              # (a host stall of > 0.85 s would overflow the FIFO)
            np.testing.assert_array_equal(np.diff(index_of(rows)), 1)
    finally:
        src.close()


def test_record_command_writes_the_mpu6050_header(monkeypatch, tmp_path):
    """`gyrofilter record --source mpu6050:...` end to end, the model standing in for the chip."""
    import time

    from gyrofilter.cli import main
    from gyrofilter.recording import read_recording

    class HostClock:
        now = staticmethod(time.monotonic)

    accel = indexed_accel(200_000)
    model = MPU6050Model(HostClock(), gyro_lsb=indexed_gyro(200_000), accel_lsb=accel, temp_c=28.0)
    FakeI2CBus({0x68: model}).install(monkeypatch)
    out = tmp_path / "rec.csv"
    assert main(["record", "--source", "mpu6050:rate=200,range=1000,accel_range=4", "--out", str(out),
                 "--duration", "0.5"]) == 0
    rec = read_recording(str(out))
    for key, value in {"sensor": "MPU6050", "chip_id": "0x68", "gyro_unit": "lsb", "lsb_per_dps": "32.8",
                       "full_scale_dps": "1000", "sample_rate_hz": "200", "i2c_bus": "/dev/i2c-1",
                       "i2c_address": "0x68", "accel_unit": "lsb", "lsb_per_g": "8192", "full_scale_g": "4"}.items():
        assert rec.header[key] == value, key
    assert model.regs[0x1C] == 0x08                                  # AFS_SEL 1: +-4 g
    got = np.column_stack([rec.columns[c] for c in ("ax", "ay", "az")])
    np.testing.assert_array_equal(got, accel[index_of(np.column_stack([rec.t_s, rec.gyro]))])
    assert "start_time_utc" in rec.header and "dlpf_cfg" in rec.header
    assert len(rec) > 0 and np.all(np.abs(rec.temp_c - 28.0) <= 0.5 / 340 + 1e-6)
    rows = np.column_stack([rec.t_s, rec.gyro])
    if not rec.notes:
        np.testing.assert_array_equal(np.diff(index_of(rows)), 1)
        np.testing.assert_allclose(np.diff(rec.t_s), 1 / 200, atol=1e-9)


def test_chip_that_stays_asleep_is_refused(rig):
    clock, model, bus = rig(stuck={0x6B: 0x40})              # PWR_MGMT_1 ignores the wake-up write
    with pytest.raises(DeviceError, match=r"chip did not wake up.*PWR_MGMT_1 \(0x6B\) still reads 0x40"):
        open_src(clock)


def test_fatal_error_part_way_through_a_fifo_read_delivers_the_frames_read_before(rig):
    """The chip vanishes during the 3rd 30-byte block of an SMBus FIFO read: the 10 frames of the
    first two blocks were read off the chip, so they are delivered; the next read raises."""
    clock, model, bus = rig(gyro_lsb=indexed_gyro(20_000))
    src = open_src(clock, sample_rate_hz=1000, temperature=False, accel=False, transfer="smbus")
    a, _ = read_for(src, clock, 0.1)
    model.fail_fifo_read(errno.ENXIO, after_reads=2)
    b = src.read()
    assert len(b) == 10
    rows = np.concatenate([a, b])
    np.testing.assert_array_equal(np.diff(index_of(rows)), 1)
    np.testing.assert_array_equal(rows[:, 0], np.arange(len(rows)) / 1000.0)
    assert src.stats["samples"] == len(rows)
    with pytest.raises(DeviceError, match=r"reading/writing FIFO_R_W \(0x74\) after 1 attempt\(s\) \(errno 6"):
        src.read()
    src.close()
    with pytest.raises(SourceEnded, match="source closed"):  # as the other sources say it
        src.read()



@pytest.mark.parametrize("fifo_errno", [errno.EIO, errno.EREMOTEIO])
def test_frames_read_before_a_failed_read_survive_a_failing_follow_up(rig, fifo_errno):
    """Attack pass 17 (issue 37): a FIFO read fails after its first two 30-byte blocks (EIO: the
    FIFO reset that follows; EREMOTEIO: the FIFO_COUNT re-read) and the chip is gone for the
    traffic after it: the 10 frames read off the chip are delivered, the next read raises (the
    follow-up's failure was raised at once and they were lost)."""
    clock, model, bus = rig(gyro_lsb=indexed_gyro(20_000))
    src = open_src(clock, sample_rate_hz=1000, temperature=False, accel=False, transfer="smbus")
    a, _ = read_for(src, clock, 0.1)
    model.fail_fifo_read(fifo_errno, after_reads=2)
    check = model.check_failure

    def chip_gone_after_the_failed_read(reg, reading):
        if model.injected_errors:
            model.failures.append(errno.ENXIO)
        return check(reg, reading)
    model.check_failure = chip_gone_after_the_failed_read
    b = src.read()
    assert len(b) == 10
    np.testing.assert_array_equal(np.diff(index_of(np.concatenate([a, b]))), 1)
    with pytest.raises(DeviceError, match=r"errno 6"):
        src.read()

# ------------------------------------------------------------------------------------------ --sample-rate-hz


def _virtual_mpu6050(monkeypatch, seconds=6.0, sample_rate_hz=200):
    """A still model at /dev/i2c-1, 0x68, on a virtual clock that the driver opened by a command shares."""
    import gyrofilter.sources.mpu6050.driver as mpu

    clock = VirtualClock()
    rng = np.random.default_rng(3)
    model = MPU6050Model(clock, gyro_dps=rng.normal(0.0, 0.05, (int(seconds * sample_rate_hz) + 2000, 3)), temp_c=30.0,
                         rng=rng)
    FakeI2CBus({0x68: model}, clock=clock).install(monkeypatch)
    monkeypatch.setattr(mpu, "open_mpu6050", lambda **kw: open_mpu6050(clock=clock.now, sleep=clock.sleep,
                                                                        wall_clock=lambda: 1.7e9, **kw))
    return model


def test_record_and_run_set_the_mpu6050_rate_from_the_option(monkeypatch, tmp_path, capsys):
    """Issue 23: the driver's keyword was rate_hz, so `--sample-rate-hz 200` was silently dropped and
    the chip sampled at its default 100 Hz. Now it sets SMPLRT_DIV (1 kHz / (1 + 4) = 200 Hz)."""
    from gyrofilter.cli import main
    from gyrofilter.recording import read_recording

    model = _virtual_mpu6050(monkeypatch)
    rec_path = tmp_path / "rec.csv"
    assert main(["record", "--source", "mpu6050", "--sample-rate-hz", "200", "--out", str(rec_path), "--duration", "3"]) == 0
    assert model.regs[0x19] == 4 and model.sample_rate_hz() == 200.0
    rec = read_recording(rec_path)
    assert rec.header["sample_rate_hz"] == "200" and len(rec) == 600
    np.testing.assert_allclose(np.diff(rec.t_s), 1 / 200)

    model = _virtual_mpu6050(monkeypatch)
    out = tmp_path / "run.csv"
    assert main(["run", "--source", "mpu6050,range=500", "--sample-rate-hz", "200", "--out", str(out), "--duration", "6",
                 "--quiet", "--preset", "paper"]) == 0
    assert model.regs[0x19] == 4
    filtered = read_recording(out)
    assert filtered.header["input_sample_rate_hz"] == "200" and filtered.sample_rate_hz == 40.0
    assert len(filtered) == (6 - 2) * 200 // 5  # after the 2-s calibration, blocks of 5
    capsys.readouterr()


def test_a_rate_the_mpu6050_cannot_reach_from_the_option_names_the_option(monkeypatch, tmp_path, capsys):
    from gyrofilter.cli import main

    _virtual_mpu6050(monkeypatch)
    assert main(["record", "--source", "mpu6050", "--sample-rate-hz", "300", "--out", str(tmp_path / "r.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--sample-rate-hz=300 is not reachable" in err
    assert "rate_hz" not in err.replace("--sample-rate-hz", "")  # the option, not the keyword
    assert not (tmp_path / "r.csv").exists()


@pytest.mark.parametrize("command", ["record", "run"])
@pytest.mark.parametrize("source, options, words", [
    ("replay:{rec}", ["--sample-rate-hz", "200"], ["--sample-rate-hz does not apply to source 'replay:",
                                                  "header gives its sample rate and units"]),
    ("{rec}", ["--sample-rate-hz", "200"], ["--sample-rate-hz does not apply to source"]),
    ("replay:{rec}", ["--gyro-unit", "dps"], ["--gyro-unit does not apply"]),
    ("mpu6050", ["--gyro-unit", "dps"], ["--gyro-unit does not apply to source 'mpu6050'", "range="]),
    ("mpu6050", ["--lsb-per-dps", "131"], ["--lsb-per-dps does not apply to source 'mpu6050'"]),
    ("sim", ["--gyro-unit", "lsb"], ["--gyro-unit does not apply to source 'sim'", "model gives the units"]),
    ("mpu6050:rate=100", ["--sample-rate-hz", "200"], ["--sample-rate-hz and the key 'rate' of source "
                                                       "'mpu6050:rate=100' give the same setting: give it once"]),
    ("sim,rate=100", ["--sample-rate-hz", "100"], ["the key 'rate'", "give it once"]),
])
def test_an_option_the_source_cannot_take_is_refused_naming_it(monkeypatch, tmp_path, capsys, command, source, options,
                                                              words):
    """record and run alike: a unit option a source does not take (a replayed file's header rules,
    an MPU6050 reads LSB) or that its SOURCE text gives too is one line naming it, not ignored."""
    from gyrofilter.cli import main
    from gyrofilter.recording import Recording, write_recording

    model = _virtual_mpu6050(monkeypatch)
    rec = tmp_path / "in.csv"
    write_recording(rec, Recording.from_dps(np.zeros((500, 3)), 100.0))
    out = tmp_path / "out.csv"
    argv = [command, "--source", source.format(rec=rec), *options, "--out", str(out), "--duration", "1"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and all(word in err for word in words), err
    assert not out.exists() and model.regs[0x6B] == 0x40  # nothing written, the chip never woken


def test_numbers_in_other_scripts_digits_are_refused(rig):
    """Issue 37 (attack): int() reads full-width digits ("\uff16\uff18" as 68): the API's address
    and allow_chip texts take ASCII only, as every number a user gives."""
    from gyrofilter.errors import SettingsError
    from gyrofilter.sources.mpu6050.chip import chip_ids

    with pytest.raises(SettingsError, match="allow_chip"):
        chip_ids(["\uff11\uff11\uff12"])
    assert chip_ids(["0x70", 113]) == {0x70, 113}
    clock, model, bus = rig()
    with pytest.raises(SettingsError, match="address=.* is not an integer"):
        open_src(clock, address="\uff11\uff10\uff14")
    open_src(clock, address="104").close()


@pytest.mark.parametrize("transfer, rate_hz, after_reads", [("smbus", 100, 0), ("rdwr", 100, 0), ("smbus", 500, 1),
                                                             ("smbus", 500, 2)])
@pytest.mark.parametrize("frames", [1, 2])
def test_a_failed_fifo_read_that_took_whole_frames_is_a_gap(rig, transfer, rate_hz, after_reads, frames):
    """Attack pass 9 (issue 37): a FIFO read refused with EREMOTEIO is retried as one that took
    nothing; one that took whole frames left FIFO_COUNT aligned, so the frames after them were
    delivered at the lost ones' times: 1 or 2 samples gone, t unbroken, lost_samples 0, no note
    (also where a later 32-byte block of an SMBus read failed, ``after_reads``, and the frames read
    before it were delivered). A count below the bytes the FIFO still held, plus those produced
    since, is now a gap, its t jumps."""
    clock, model, bus = rig(gyro_lsb=indexed_gyro(20_000))
    src = open_src(clock, sample_rate_hz=rate_hz, transfer=transfer)
    a, _ = read_for(src, clock, 0.2)
    model.fail_fifo_read(errno.EREMOTEIO, consume_bytes=frames * src.frame_bytes, after_reads=after_reads)
    b, notes = read_for(src, clock, 0.5)
    rows = np.concatenate([a, b])
    idx = index_of(rows)
    np.testing.assert_array_equal(rows[:, 1:4], indexed_gyro(20_000)[idx])
    np.testing.assert_array_equal(np.round(np.diff(rows[:, 0]) * rate_hz), np.diff(idx))  # t steps as the samples do
    assert len(notes) == 1 and notes[0].startswith(f"gap: {src.stats['lost_samples']} samples lost")
    assert src.stats["lost_samples"] >= frames


# ------------------------------------------------------------------------------------------ accelerometer


@pytest.mark.parametrize("rate_hz,temperature,transfer,stall_s", [(100, True, "smbus", 1.5), (1000, True, "rdwr", 0.2),
                                                                  (1000, False, "smbus", 0.2), (100, False, "rdwr", 1.5)])
def test_six_axes_through_smbus2_with_an_overflow_between(rig, rate_hz, temperature, transfer, stall_s):
    """The done-when of issue 39: six axes at 100 Hz and 1 kHz, a FIFO overflow between two reads;
    every row's gyro and accelerometer are the model's of one sample index (14- or 12-byte frames
    never misaligned), the gap is noted and counted as the samples truly lost."""
    n = 20_000
    gyro, accel = indexed_gyro(n), indexed_accel(n)
    clock, model, bus = rig(gyro_lsb=gyro, accel_lsb=accel, temp_c=np.linspace(20, 30, n))
    src = open_src(clock, sample_rate_hz=rate_hz, temperature=temperature, transfer=transfer)
    frame = 14 if temperature else 12
    assert src.frame_bytes == frame and model.regs[0x23] == (0xF8 if temperature else 0x78)
    assert src.columns == ["t", "gx", "gy", "gz"] + (["temp"] if temperature else []) + ["ax", "ay", "az"]
    before, notes_before = read_for(src, clock, 2.0)
    clock.advance(stall_s)                           # longer than the FIFO holds: 1024 // frame frames
    after, notes = read_for(src, clock, 2.0)
    assert notes_before == [] and model.fifo_dropped_bytes > 0
    assert len(notes) == 1 and "FIFO overflow" in notes[0] and src.stats["overflows"] == 1
    rows = np.concatenate([before, after])
    idx = index_of(rows)
    np.testing.assert_array_equal(rows[:, 1:4], gyro[idx])
    np.testing.assert_array_equal(rows[:, -3:], accel[idx])
    if temperature:
        assert np.max(np.abs(rows[:, 4] - np.linspace(20, 30, n)[idx])) <= 0.5 / 340 + 1e-9
    true_lost = index_of(after)[0] - index_of(before)[-1] - 1
    assert true_lost > 1024 // frame and src.stats["lost_samples"] == true_lost
    np.testing.assert_array_equal(np.round(rows[:, 0] * rate_hz), idx - idx[0])   # t jumps by the gap
    assert src.stats["fifo_bytes_read"] == frame * len(rows) == frame * src.stats["samples"]
    src.close()


@pytest.mark.parametrize("range_g,afs_bits,lsb", [(2, 0x00, 16384), (4, 0x08, 8192), (8, 0x10, 4096), (16, 0x18, 2048)])
def test_accelerometer_range_written_and_values_scaled(rig, range_g, afs_bits, lsb):
    """ACCEL_CONFIG.AFS_SEL (0x1C bits 4:3) and the LSB per g of product spec section 6.2."""
    g = np.array([[0.5, -0.25, 1.0], [-1.5, 1.75, 0.0], [30.0, -30.0, 0.001]])   # 30 g: beyond every range, clipped
    clock, model, bus = rig(accel_g=g)
    src = open_src(clock, sample_rate_hz=100, accel_range_g=range_g, temperature=False)
    assert model.regs[0x1C] == afs_bits
    assert (src.header["accel_unit"], src.header["lsb_per_g"], src.header["full_scale_g"]) == ("lsb", str(lsb), str(range_g))
    rows, _ = read_for(src, clock, 0.2)
    got = {tuple(r) for r in rows[:, 4:7].astype(int)}
    assert got == {tuple(r) for r in np.clip(np.round(g * lsb), -32768, 32767).astype(int)}
    src.close()


def test_accelerometer_range_that_does_not_stick_is_refused(rig):
    clock, model, bus = rig(stuck={0x1C: 0x00})
    with pytest.raises(DeviceError, match=r"register ACCEL_CONFIG \(0x1C\) reads back 0x00 after writing 0x18"):
        open_src(clock, accel_range_g=16)
    assert not bus.fds


def test_accelerometer_off_leaves_it_out_of_the_fifo_and_the_header(rig):
    clock, model, bus = rig(gyro_lsb=indexed_gyro(5000))
    src = open_src(clock, sample_rate_hz=1000, accel=False)
    assert model.regs[0x23] == 0xF0 and src.frame_bytes == 8 and src.columns == ["t", "gx", "gy", "gz", "temp"]
    assert not {"accel_unit", "lsb_per_g", "full_scale_g"} & set(src.header)
    rows, _ = read_for(src, clock, 0.2)
    np.testing.assert_array_equal(rows[:, 1:4], indexed_gyro(5000)[index_of(rows)])


def test_bad_accelerometer_range_refused_naming_the_key(rig):
    from gyrofilter.sources import open_source

    clock, model, bus = rig()
    with pytest.raises(SettingsError, match="accel_range_g=3 is not an MPU6050 accelerometer full scale.*2, 4, 8, 16"):
        open_src(clock, accel_range_g=3)
    with pytest.raises(SettingsError, match=r"^source 'mpu6050:accel_range=6': accel_range=6 is not"):
        open_source("mpu6050:accel_range=6")
    assert bus.ioctl_calls == 0


def test_accelerometer_frames_stay_aligned_after_failed_reads(rig):
    """A NACK that ate 2 bytes leaves a count that is no whole number of 14-byte frames (a resync);
    an EIO part-way resets the FIFO: both a gap, and every row still one sample's seven words."""
    n = 20_000
    gyro, accel = indexed_gyro(n), indexed_accel(n)
    clock, model, bus = rig(gyro_lsb=gyro, accel_lsb=accel)
    src = open_src(clock, sample_rate_hz=1000, transfer="rdwr")
    a, _ = read_for(src, clock, 0.1)
    model.fail_fifo_read(errno.EREMOTEIO, consume_bytes=2)     # one word: the frames would shift by a word
    b, notes_b = read_for(src, clock, 0.2)
    model.fail_fifo_read(errno.EIO, consume_bytes=20)
    c, notes_c = read_for(src, clock, 0.2)
    assert "not a whole number of 14-byte frames" in notes_b[0] and "errno 5" in notes_c[0]
    rows = np.concatenate([a, b, c])
    idx = index_of(rows)
    assert np.all(np.diff(idx) >= 1) and src.stats["resyncs"] == 2
    np.testing.assert_array_equal(rows[:, 1:4], gyro[idx])
    np.testing.assert_array_equal(rows[:, 5:8], accel[idx])


@pytest.mark.parametrize("rate_hz", [100, 1000 / 256])
def test_a_chip_that_resets_itself_mid_stream_ends_the_source(rig, rate_hz):
    """Attack 37d: a chip reset mid-stream (a power dip: it comes back asleep, its FIFO off) left
    FIFO_COUNT at 0 and read() returning nothing for ever: `record --duration 5` ran on without a
    word (5 virtual hours seen). Now a source quiet for 1 s (10 sample intervals where longer)
    ends with DeviceError naming the registers that lost the configuration; the rows before it are kept."""
    clock, model, bus = rig(gyro_lsb=indexed_gyro(5000))
    src = open_src(clock, sample_rate_hz=rate_hz)
    rows, notes = read_for(src, clock, 3.0)
    assert len(rows) >= 2 and not notes
    model.write(R.PWR_MGMT_1.address, [0x80])  # DEVICE_RESET: the register state of a power-up
    reset_at = clock.now()
    with pytest.raises(DeviceError, match=r"no sample for .* lost its configuration \(PWR_MGMT_1 \(0x6B\) 0x40"):
        read_for(src, clock, 60.0)
    assert clock.now() - reset_at < max(1.0, 10 / rate_hz) + 1.0
