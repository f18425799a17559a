"""Host cost per frame of the MPU6050 driver, beside naive baselines (no hardware needed).

Run: python tools/bench_mpu6050.py [--frames N]

What is timed (wall clock on this machine, per gyro frame = one three-axis sample):

* decode: bytes of whole FIFO frames -> rows [t, gx, gy, gz, temp] (numpy ``>i2`` view), against
  a per-frame ``struct.unpack`` loop building the same rows;
* read: ``source.read()`` end to end through smbus2's real code (INT_STATUS + FIFO_COUNT + FIFO
  data per poll, 20 frames per poll at 1 kHz) with the register-level model of
  gyrofilter/sources/mpu6050/model.py behind smbus2's ``ioctl``; the time spent inside the fake ioctl (the
  model, standing in for the kernel) is measured and subtracted, so "host" is driver + smbus2;
* baselines through the same smbus2 + model: one ``read_byte_data`` per gyro register (6 per
  sample, the naive loop), and one 6-byte ``read_i2c_block_data`` of GYRO_XOUT_H per sample.

Bus time per frame is computed from the bits each approach puts on the wire at 400 kHz
(start + address + ack per message, 9 bits per byte): the budget that the host cost must stay
far below for 1 kHz reading. On a Raspberry Pi the per-call ioctl also costs kernel time,
which this machine cannot measure; the bus-time column bounds it from below.
"""
import argparse
import struct
import sys
import time

import numpy as np


from gyrofilter.sources.mpu6050.model import FakeI2CBus, MPU6050Model, VirtualClock

from gyrofilter.sources.mpu6050.driver import open_mpu6050

SCL_HZ = 400e3


class _TimedBus(FakeI2CBus):
    """FakeI2CBus that adds up the time spent inside the fake ioctl (the model = the 'kernel')."""

    def __init__(self, *a, **k):
        super().__init__(*a, **k)
        self.inside_s = 0.0

    def ioctl(self, *args):
        t0 = time.perf_counter()
        try:
            return super().ioctl(*args)
        finally:
            self.inside_s += time.perf_counter() - t0


def _rig(n_frames, sample_rate_hz=1000):
    clock = VirtualClock()
    k = np.arange(n_frames + 20_000)
    gyro = np.column_stack([k % 65536 - 32768, (k * 3) % 65536 - 32768, (k * 7) % 65536 - 32768])
    model = MPU6050Model(clock, gyro_lsb=gyro, temp_c=30.0)
    bus = _TimedBus({0x68: model}, clock=clock)
    return clock, model, bus


def bench_decode(n_frames=20, repeat=2000):
    """Per-frame cost of decoding ``n_frames`` 8-byte frames (temp + gyro), numpy vs struct loop."""
    clock, model, bus = _rig(100)
    with bus:
        src = open_mpu6050(sample_rate_hz=1000, accel=False, clock=clock.now, sleep=clock.sleep)
    rng = np.random.default_rng(0)
    buf = rng.integers(0, 256, 8 * n_frames, dtype=np.uint8).tobytes()
    t0 = time.perf_counter()
    for _ in range(repeat):
        src._rows(buf)
    driver_s = (time.perf_counter() - t0) / (repeat * n_frames)

    unpack = struct.Struct(">4h").unpack_from

    def naive(buf, start_index, sample_rate_hz=1000.0):
        rows = []
        for i in range(len(buf) // 8):
            temp, gx, gy, gz = unpack(buf, 8 * i)
            rows.append([(start_index + i) / sample_rate_hz, gx, gy, gz, temp / 340.0 + 36.53])
        return np.array(rows)

    t0 = time.perf_counter()
    for _ in range(repeat):
        naive(buf, 0)
    naive_s = (time.perf_counter() - t0) / (repeat * n_frames)
    return driver_s, naive_s


def bench_read(n_frames, transfer, sample_rate_hz=1000):
    """Per-frame host cost of source.read() through smbus2 + model; returns a dict."""
    clock, model, bus = _rig(n_frames)
    with bus:
        src = open_mpu6050(sample_rate_hz=sample_rate_hz, temperature=True, accel=False, transfer=transfer, clock=clock.now,
                           sleep=clock.sleep)
        bus.inside_s, bus.bus_bits, bus.ioctl_calls = 0.0, 0, 0
        got = 0
        t0 = time.perf_counter()
        while got < n_frames:
            got += len(src.read())
        total_s = time.perf_counter() - t0
        src.close()
    return {"total_us": 1e6 * total_s / got, "host_us": 1e6 * (total_s - bus.inside_s) / got,
            "ioctls": bus.ioctl_calls / got, "bus_us": 1e6 * bus.bus_bits / SCL_HZ / got,
            "lost": src.stats["lost_samples"]}


def bench_naive(n_frames, per_register):
    """Per-sample register reads (no FIFO): 6 x read_byte_data, or one 6-byte block read."""
    import smbus2

    clock, model, bus = _rig(n_frames)
    with bus:
        src = open_mpu6050(sample_rate_hz=1000, accel=False, clock=clock.now, sleep=clock.sleep)
        dev = smbus2.SMBus(1)
        bus.inside_s, bus.bus_bits, bus.ioctl_calls = 0.0, 0, 0
        out = np.empty((n_frames, 3))
        t0 = time.perf_counter()
        for i in range(n_frames):
            clock.advance(0.001)
            if per_register:
                b = [dev.read_byte_data(0x68, r) for r in range(0x43, 0x49)]
            else:
                b = dev.read_i2c_block_data(0x68, 0x43, 6)
            out[i] = struct.unpack(">3h", bytes(b))
        total_s = time.perf_counter() - t0
        dev.close()
        src.close()
    return {"total_us": 1e6 * total_s / n_frames, "host_us": 1e6 * (total_s - bus.inside_s) / n_frames,
            "ioctls": bus.ioctl_calls / n_frames, "bus_us": 1e6 * bus.bus_bits / SCL_HZ / n_frames,
            "lost": None}


def measure(n_frames=20_000):
    """All figures as rows (name, host us/frame, ioctls/frame, bus us/frame at 400 kHz, note)."""
    dec, naive_dec = bench_decode()
    rows = [("decode 20 frames: driver (numpy >i2)", 1e6 * dec, None, None, ""),
            ("decode 20 frames: struct.unpack loop", 1e6 * naive_dec, None, None, "baseline")]
    for transfer in ("rdwr", "smbus"):
        r = bench_read(n_frames, transfer)
        rows.append((f"driver read(), FIFO via {'I2C_RDWR' if transfer == 'rdwr' else '<=32-byte SMBus blocks'}",
                     r["host_us"], r["ioctls"], r["bus_us"], f"lost {r['lost']}"))
    r = bench_read(min(n_frames, 5000), "rdwr", sample_rate_hz=100)
    rows.append(("driver read() at 100 Hz (2 frames per poll), I2C_RDWR", r["host_us"], r["ioctls"],
                 r["bus_us"], f"lost {r['lost']}"))
    for per_register, name in ((True, "6 x read_byte_data per sample"),
                               (False, "read_i2c_block_data(0x43, 6) per sample")):
        r = bench_naive(min(n_frames, 5000), per_register)
        rows.append((name, r["host_us"], r["ioctls"], r["bus_us"], "baseline, no FIFO"))
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20_000, help="frames per read benchmark")
    args = parser.parse_args(argv)
    rows = measure(args.frames)
    print("MPU6050 host cost per frame (1 kHz unless stated, gyro + temp; "
          "model behind smbus2's ioctl, its time removed)")
    print(f"{'approach':<56} {'host us/frame':>13} {'ioctl/frame':>11} {'bus us/frame @400k':>18}  note")
    for name, host, ioctls, bus, note in rows:
        io = "" if ioctls is None else f"{ioctls:.2f}"
        bt = "" if bus is None else f"{bus:.0f}"
        print(f"{name:<56} {host:13.2f} {io:>11} {bt:>18}  {note}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
