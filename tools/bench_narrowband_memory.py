"""Peak memory (tracemalloc) of the narrow-band detector on a 24-h 100-Hz axis (8.64 M samples):

    python tools/bench_narrowband_memory.py

Prints the peak above the input array (issue 12: 346 MB, five axis sizes, with scipy.signal.welch on
the whole series; 5.4 MB with the batched welch_psd)."""
import time
import tracemalloc

import numpy as np
import gyrofilter
from gyrofilter.analysis.detectors import band_estimate, detect_narrowband
n = 24 * 3600 * 100
x = np.random.default_rng(1).normal(size=n)
band_estimate(x[:100000], 100.0)  # imports outside the measurement
tracemalloc.start()
t = time.perf_counter()
c = detect_narrowband(x, 100.0)
cur, peak = tracemalloc.get_traced_memory()
print(gyrofilter.__file__, f"N={n} ({n*8/1e6:.0f} MB input): detect_narrowband peak {peak/1e6:.1f} MB above the input ({peak/(n*8):.2f} axis sizes), {time.perf_counter()-t:.1f} s, candidate {c}")
