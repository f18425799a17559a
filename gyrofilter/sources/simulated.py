"""A simulation as a live source (``sim[:MODEL.json][,seed=1][,realtime=0][,duration=60][,rate=1000]``).

Samples come from :func:`gyrofilter.sim.simulate.simulate_chunks` (the shared simulator model
schema; without a model, :data:`DEFAULT_MODEL`, an MPU6050 at rest, read from
``gyrofilter/data/mpu6050_model.json``). By default they are paced in real time, so ``record``
and ``run`` behave as with a device; ``realtime=0`` hands them out as fast as they are read. The simulator's output does not depend on how it is chunked, so the
samples equal ``gyrofilter simulate --model MODEL --duration D --seed S`` for the same model,
seed and duration, whatever the pacing. Without ``seed`` a random one is drawn and written in
the header (``simulated_seed``), so every run can be repeated. Without ``duration`` (``record``
and ``run`` give their ``--duration``) the source runs for :data:`UNLIMITED_S` (a week).
"""
from __future__ import annotations

import json
import math
import time
from importlib import resources

import numpy as np

from ..errors import SettingsError, SourceEnded
from ..recording import VERSION_KEY
from ..sim.model import load_model, validate_model
from ..sim.simulate import block_rows, check_seed, draw_seed, recording_columns, recording_header, simulate_chunks
from ..units import check_duration_s
from .base import WARNING_PREFIX, Source

MAX_WAIT_S = 0.1
POLL_S = 0.02  # paced reads return at most this often (batches, like a device's FIFO poll)
CHUNK_S = 0.1  # seconds of samples per simulator block
FAST_CHUNK_SAMPLES = 1000  # rows per read() when not paced
UNLIMITED_S = 7 * 24 * 3600.0

#: the model of a source given none: an MPU6050 at rest, +-250 deg/s (131 LSB per deg/s), 100 Hz,
#: DLPF-free, levels as measured in recordings/mpu6050_static_449s.csv.gz, and its accelerometer at
#: +-2 g (16384 LSB per g) from the datasheet (gyrofilter/data/README.md); the package's one copy
DEFAULT_MODEL_PATH = resources.files("gyrofilter") / "data" / "mpu6050_model.json"
DEFAULT_MODEL = load_model(str(DEFAULT_MODEL_PATH))


class SimulatedSource(Source):
    """Live source backed by the simulator; see the module docstring.

    Parameters
    ----------
    model : dict or str, optional
        The simulator model (:func:`gyrofilter.sim.model.validate_model` schema) or the path
        of its JSON file (a gap report's ``extended_model`` is used); None or ``""``:
        :data:`DEFAULT_MODEL`.
    seed : int, optional
        Random seed; None draws one and writes it in the header (``simulated_seed``).
    realtime : bool
        Pace the samples: the sample with time ``t`` (s) is delivered ``t`` seconds after the
        first ``read()``; False hands them out as fast as they are read.
    duration_s : float, optional
        Seconds of samples before the source ends (> 0); None runs for :data:`UNLIMITED_S`.
    sample_rate_hz : float, optional
        Sample rate (Hz), overriding the model's.
    clock, sleep : callable
        Monotonic clock (s) and sleep(s) for the pacing (test seams).

    SettingsError names the model for an invalid model or duration.
    """

    def __init__(self, model=None, seed=None, realtime=True, duration_s=None, sample_rate_hz=None, *,
                 clock=time.monotonic, sleep=time.sleep):
        if model is None or model == "":
            model, self.model_name = json.loads(json.dumps(DEFAULT_MODEL)), "default MPU6050-like model"
        elif isinstance(model, dict):
            self.model_name = "model given in code"
        else:
            model, self.model_name = load_model(model), str(model)
        try:
            spec, self.warnings = validate_model(model, sample_rate_hz=sample_rate_hz)
        except SettingsError as exc:
            raise SettingsError(f"sim: {self.model_name}: {exc}") from None
        if duration_s is not None:  # the one check of a run's length: a text ended in Python's TypeError, True was 1 s
            duration_s = check_duration_s(duration_s, "sim: duration_s")
        self.seed = draw_seed() if seed is None else check_seed(seed)
        self.sample_rate_hz, self.gyro_unit = spec["sample_rate_hz"], spec["gyro_unit"]
        self.lsb_per_dps = spec["lsb_per_dps"] if self.gyro_unit == "lsb" else None
        self.duration_s = UNLIMITED_S if duration_s is None else float(duration_s)
        self.realtime = bool(realtime)
        header = recording_header(model, self.duration_s, seed=self.seed, validated=spec)
        header.pop(VERSION_KEY, None)
        header["sensor"] = "simulated"
        header["simulated_model_name"] = self.model_name
        header["start_time_utc"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        self.header = header
        self.columns = recording_columns(spec)
        chunk = max(1, int(round(CHUNK_S * self.sample_rate_hz)))
        self._chunks = simulate_chunks(model, self.duration_s, chunk_samples=chunk, seed=self.seed, validated=spec)
        self._buf = np.empty((0, len(self.columns)))
        self._clock = clock
        self._sleep = sleep
        self._start = None
        self._last = -math.inf
        self._exhausted = False
        # a simulation has no events; the model's warnings (a parameter ignored, a frequency that aliases) are its
        # first notes, warnings as a replayed file's are (said on stderr and written to the file)
        self._notes = [f"{WARNING_PREFIX}sim: {self.model_name}: {text}" for text in self.warnings]
        self.stats = {"samples": 0, "lost_samples": 0}

    def _more(self):
        """Append the next simulator block to the buffer; False at the end."""
        try:
            rows = block_rows(next(self._chunks))
        except StopIteration:
            self._exhausted = True
            return False
        self._buf = np.concatenate([self._buf, rows]) if len(self._buf) else rows
        return True

    def read(self):
        """Next simulated rows, shape (n, len(columns)): t (s), gyro in the model's ``gyro_unit``
        (deg/s, rad/s or LSB), then ``temp`` (deg C) when the model has a temperature, then ``ax, ay,
        az`` in its ``accel_unit`` (m/s^2 or LSB) when it has an accelerometer.

        Up to :data:`FAST_CHUNK_SAMPLES` rows when not paced; with ``realtime`` the rows due by
        now, waiting at most :data:`MAX_WAIT_S` (0.1 s). Raises
        :class:`gyrofilter.errors.SourceEnded` after ``duration_s`` of samples or once closed.
        """
        if self._closed:
            raise SourceEnded("simulation closed")
        if not self.realtime:
            while len(self._buf) < FAST_CHUNK_SAMPLES and self._more():
                pass
            n = min(len(self._buf), FAST_CHUNK_SAMPLES)
        else:
            if not len(self._buf):
                self._more()
            now = self._clock()
            if self._start is None:  # paced from the first sample on, not from before its block was made
                self._start = now
            if len(self._buf):
                # sleep until the next sample is due, and at least POLL_S since the last read
                wait = max(self._buf[0, 0] - (now - self._start), POLL_S - (now - self._last))
                if wait > 0:
                    self._sleep(min(wait, MAX_WAIT_S))
                    now = self._clock()
            due_t = now - self._start
            while len(self._buf) and self._buf[-1, 0] <= due_t and self._more():
                pass
            n = int(np.searchsorted(self._buf[:, 0], due_t, side="right")) if len(self._buf) else 0
            self._last = now
        if n == 0 and not len(self._buf) and self._exhausted:
            raise SourceEnded(f"end of the simulation ({self.stats['samples']} samples, {self.duration_s:g} s)")
        rows, self._buf = self._buf[:n], self._buf[n:]
        self.stats["samples"] += n
        return rows

    def _close(self):
        self._chunks.close()
