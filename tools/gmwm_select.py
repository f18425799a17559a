"""Model selection of the composite (GMWM) fit: how often WVIC and Q + 2p choose the true model.

    python tools/gmwm_select.py [--seeds 10] [--duration 3600]

Simulated composite processes at 100 Hz (``--seeds`` records each; white noise N = 0.01
deg/s/sqrt(Hz) in every one): white noise alone, with a Gauss-Markov term (0.005 deg/s, 20 s), with
a rate random walk (2e-4 deg/s/sqrt(s)), with both, with two Gauss-Markov terms (0.01 deg/s, 3 s and
0.004 deg/s, 300 s), and the last two again with a heavy-tailed white noise (5 % of the samples at
20 times the others' sd; the classical wavelet variance, as ``gap`` uses it there, with the
WVIC's bootstrap simulating the heavy tails). The composite fit of the gap analysis (white noise,
optional random walk, 0-3 Gauss-Markov terms, tau >= 1 s; :func:`gyrofilter.analysis.noise.gmwm.select_model`)
chooses by ``criterion="wvic"`` and by ``"q2p"``; printed: how often each names the true model,
and how often it chooses one with more terms, fewer, or as many but others.
"""
from __future__ import annotations

import argparse
import time

from gyrofilter.analysis.noise import gmwm
from gyrofilter.effects import RATE_RANDOM_WALK
from gyrofilter.sim.simulate import simulate

FS = 100.0
GM_A = {"effect": "gauss_markov", "sigma_dps": 0.005, "tau_s": 20.0}
RW = {"effect": "rate_random_walk", "k_dps_per_sqrt_s": 2e-4}
GM_FAST = {"effect": "gauss_markov", "sigma_dps": 0.01, "tau_s": 3.0}
GM_SLOW = {"effect": "gauss_markov", "sigma_dps": 0.004, "tau_s": 300.0}
TAILS = {"effect": "heavy_tails", "fraction": 0.05, "scale_ratio": 20.0}
CASES = [("WN", []), ("WN+1GM", [GM_A]), ("WN+RW", [RW]), ("WN+RW+1GM", [GM_A, RW]), ("WN+2GM", [GM_FAST, GM_SLOW]),
         ("WN+RW+1GM", [GM_A, RW, TAILS]), ("WN+2GM", [GM_FAST, GM_SLOW, TAILS])]


def size(name):
    """Number of terms of a model name such as WN+RW+2GM."""
    return sum(int(p[:-2]) if p.endswith("GM") else 1 for p in name.split("+"))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--duration", type=float, default=3600.0)
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    print(f"{'true model':24s} {'criterion':9s} {'true':>6s} {'more terms':>10s} {'fewer terms':>11s} {'other':>6s}")
    totals = {"wvic": 0, "q2p": 0}
    for name, effects in CASES:
        tails = next(((e["fraction"], e["scale_ratio"]) for e in effects if e["effect"] == "heavy_tails"), None)
        counts = {"wvic": [0, 0, 0, 0], "q2p": [0, 0, 0, 0]}
        for seed in range(args.seeds):
            model = {"sample_rate_hz": FS, "axes": {"x": {"arw_dps_per_sqrt_hz": 0.01, "effects": effects}}}
            x = simulate(model, args.duration, seed=500 + seed).gyro_dps[:, 0]
            wv = gmwm.haar_wv(x, FS, min_m=int(FS), tails=tails)
            for criterion in counts:
                fit, _ = gmwm.select_model(wv, terms_allowed=(RATE_RANDOM_WALK,), starts=3, seed=seed, criterion=criterion)
                k = 0 if fit.name == name else 1 if size(fit.name) > size(name) else 2 if size(fit.name) < size(name) else 3
                counts[criterion][k] += 1
        label = name + (" (heavy tails)" if tails else "")
        for criterion, (ok, more, fewer, other) in counts.items():
            totals[criterion] += ok
            print(f"{label:24s} {criterion:9s} {ok:6d} {more:10d} {fewer:11d} {other:6d}")
    n = args.seeds * len(CASES)
    print(f"all: WVIC {totals['wvic']} of {n}, Q + 2p {totals['q2p']} of {n} true "
          f"({args.seeds} records of {args.duration:.0f} s per model; {time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
