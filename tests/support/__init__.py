"""What the tests share: paths, feeding a filter sample by sample as a live source does, and a
recording under a file name that is not UTF-8.

``plain_filter`` is the plain-way oracle of the paper's filter (``tools/bench.py`` uses it as its
baseline); ``battery`` the slow tests' ten-minute hidden-effect cases, each analysed once per session. Helpers that tools need too live in the package: the hidden-effect battery in ``gyrofilter.sim.hidden_effects`` and the
register-level MPU6050 model in ``gyrofilter.sources.mpu6050.model``. ``tool(name)`` loads a script
of ``tools/`` (``tools/docs.py`` for the tests of the documentation).
"""
from __future__ import annotations

import contextlib
import importlib.util
import os
import signal
import sys
import threading
import time
from pathlib import Path

import numpy as np

from gyrofilter.recording import Recording, write_recording

REPO = Path(__file__).resolve().parents[2]
RECORDINGS = REPO / "recordings"
SHARED_DATA = REPO.parent / "shared" / "data"  # real recordings beside the repo; tests skip without


def stream(filt, x, temps=None):
    """Feed ``x`` (N, 3) deg/s to ``filt.update`` one sample at a time (with ``temps`` deg C if
    given) and return the (M, 3) rows it emitted."""
    temps = [None] * len(x) if temps is None else np.asarray(temps).tolist()
    rows = [filt.update(tuple(s), t) for s, t in zip(np.asarray(x).tolist(), temps)]
    return np.array([r for r in rows if r is not None]).reshape(-1, 3)


def file_named_by_bytes(tmp_path, name=b"\xff.csv"):
    """A recording under a file name that is not UTF-8 (legal on Linux), and the name as Python
    gets it from argv: os.fsdecode, the byte 0xff as the lone surrogate '\\udcff'."""
    path = os.fsdecode(os.path.join(os.fsencode(tmp_path), name))
    write_recording(path, Recording.from_dps(np.random.default_rng(3).normal(0, 0.05, (6000, 3)), 100.0))
    assert os.path.exists(os.path.join(os.fsencode(tmp_path), name))
    return path


def lsb_recording(tmp_path, name="rec.csv", n=2500, gap_at=None, gap=0, notes=()):
    """An MPU6050-like recording at 100 Hz written to ``tmp_path / name``: whole LSB values (131
    LSB per deg/s, seeded), a temperature ramp, ``gap`` samples missing from row ``gap_at`` on,
    annotation ``notes``. Returns (path, the recording as read back)."""
    from gyrofilter.recording import Recording, read_recording, write_recording

    rng = np.random.default_rng(7)
    gyro = np.round(rng.normal(0, 30, size=(n, 3)))
    idx = np.arange(n)
    if gap_at is not None:
        idx[gap_at:] += gap
    rec = Recording.from_dps(gyro / 131.0, 100.0, t_s=idx / 100.0, temp_c=25 + idx / 1000.0,
                             header={"sensor": "MPU6050", "chip_id": "0x68"})
    rec.notes = list(notes)
    path = tmp_path / name
    write_recording(path, rec)
    return path, read_recording(path)


def play_serial_then_stop(primary, secondary, proc, header, lines, out, rows, timeout_s=60.0):
    """Play a serial device on the pseudo-terminal ``primary`` (its other end ``secondary``) for the
    ``record`` or ``run`` process ``proc``: answer its ``?`` with the protocol ``header`` line, send
    ``lines`` (bytes), wait until the plain-text ``out`` holds ``rows`` data rows (counted as text,
    whatever the reader says of them), then stop it with SIGINT (Ctrl-C). Both ends are closed.
    Returns the command's stderr."""
    def feed():
        with contextlib.suppress(OSError):  # the command ended and the port closed
            os.write(primary, lines)

    try:
        assert os.read(primary, 1) == b"?"
        os.write(primary, header)
        threading.Thread(target=feed, daemon=True).start()
        deadline = time.monotonic() + timeout_s
        while proc.poll() is None and time.monotonic() < deadline:
            with contextlib.suppress(OSError):
                with open(out, "rb") as f:
                    if sum(1 for ln in f if ln[:1] not in (b"#", b"t")) >= rows:
                        break
            time.sleep(0.05)
        proc.send_signal(signal.SIGINT)
        return proc.communicate(timeout=timeout_s)[1]
    finally:
        os.close(primary)
        os.close(secondary)


def wait_until_read(port, still_s=5.0):
    """Return once the reader of the pseudo-terminal ``port`` has taken every byte its device sent,
    or has taken none for ``still_s`` seconds (it stopped reading). A device that closes its side
    hangs the terminal up and Linux drops the bytes not yet read: a test that closes right after
    its last write loses lines whenever the reader is slow (CI on a loaded machine lost 598 of 600).
    The count is asked after 50 ms: the terminal queues the last bytes written a moment later."""
    import fcntl
    import struct
    import termios

    time.sleep(0.05)
    fd = os.open(port, os.O_RDONLY | os.O_NOCTTY | os.O_NONBLOCK)  # only to ask how much waits; reads nothing
    try:
        last, since = None, time.monotonic()
        while True:
            waiting = struct.unpack("i", fcntl.ioctl(fd, termios.FIONREAD, b"\0" * 4))[0]
            if waiting == 0 or time.monotonic() - since > still_s:
                return
            if waiting != last:
                last, since = waiting, time.monotonic()
            time.sleep(0.01)
    finally:
        os.close(fd)


def tool(name):
    """The module ``tools/<name>.py`` (the scripts beside the package are not installed), loaded once."""
    key = f"_tools_{name}"
    if key not in sys.modules:
        spec = importlib.util.spec_from_file_location(key, REPO / "tools" / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[key] = module
        spec.loader.exec_module(module)
    return sys.modules[key]


def play_lossy_device(primary, secondary, proc, lines, repeats, fields=b""):
    """Play a serial device on the pseudo-terminal ``primary`` (its other end ``secondary``) for the
    command ``proc`` (a ``subprocess.Popen`` reading it): answer its first byte (``?``) with the
    protocol header of a 100-Hz device in deg/s (its ``fields=`` word, if given), then send ``lines``
    (bytes) ``repeats`` times until the command ends; both ends are closed. Returns the command's stderr."""
    def feed():
        with contextlib.suppress(OSError):  # the command ended and the port closed
            for _ in range(repeats):
                os.write(primary, lines)

    try:
        assert os.read(primary, 1) == b"?"
        os.write(primary, b"# gyrofilter-serial: 1 gyro_unit=dps sample_rate_hz=100" + (b" fields=" + fields if fields else b"") + b"\n")
        threading.Thread(target=feed, daemon=True).start()
        return proc.communicate(timeout=60)[1]
    finally:
        os.close(primary)
        os.close(secondary)


#: ``python -c UNDER_A_SIZE_LIMIT BYTES ARGVS_JSON``: each command line of ARGVS_JSON through gyrofilter's main under
#: a file size limit of BYTES (a full disk alike: every write beyond it fails with EFBIG), printing "exit N" for each
UNDER_A_SIZE_LIMIT = """
import json, resource, signal, sys
from gyrofilter.cli import main
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (int(sys.argv[1]), int(sys.argv[1])))
for argv in json.loads(sys.argv[2]):
    print("exit", main(argv), flush=True)
"""
