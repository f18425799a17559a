"""How often the fit's intervals and upper bounds of Q, N, B and K hold the simulated coefficient,
where the rate random walk K and a slow temperature drift are not resolved by the record.

    python tools/allan_coverage.py [--seeds 1-10] [--minutes 10,30,60] [--cases NAME,...]
                                   [--jobs 2] [--rows OUT.json] [--before ROWS.json]

A coefficient is *covered* on an axis when the fit resolves it and its interval holds the
simulated value, or when the fit does not resolve it and its upper bound is at or above that value
(:func:`gyrofilter.analysis.noise.intervals.fitted_intervals` states both rules). Each count is
given with its two-sided 95 % Clopper-Pearson interval. The cases (100 Hz):

* ``default-gyro`` / ``default-accel``: the default MPU6050 model (``gyrofilter/data/mpu6050_model.json``)
  with its temperature profile: the gyro's N and B (its K is 0, its drift is the temperature's),
  the accelerometer's N, B and K (4e-5 m/s^2/sqrt(s)) with its temperature drift;
* ``white-rw``: white noise and a rate random walk only, K = 5e-5, 1e-4, 2e-4 deg/s/sqrt(s) on
  x, y, z (the default model's ARW), so that K goes from unresolved to resolved over 10-60 min;
* ``white-flicker``: the default gyro model without its temperature (white noise, bias instability,
  quantization; K = 0): where a rule for an unresolved K must not widen B much;
* ``white-flicker-rw``: white noise, flicker and a random walk together, N = 0.01 deg/s/sqrt(Hz),
  B = 0.005 deg/s, K = 0.003 deg/s/sqrt(s) on every axis: where B, not resolved on short records,
  leaves its share of the long taus to K unless it is freed too (issue 37);
* ``white-quant``: white noise N = 0.01 deg/s/sqrt(Hz) and angle quantization: the rate is the
  first difference of an angle whose quantization error is uniform and independent from sample to
  sample, of step q, so Q = q / sqrt(12) (IEEE Std 952-1997 C.1; El-Sheimy et al. 2008, eq. 8:
  sigma^2 = 3 Q^2 / tau^2), Q = 1e-4, 2e-4, 5e-4 deg on x, y, z (x's resolved on 7, 30 and
  39 of seeds 41-80 at 10, 30 and 60 min) (the simulator's own
  ``lsb_per_dps`` rounds the rate, white noise in rate: N, not Q).

``--rows`` writes every axis's numbers (JSON); ``--before`` reads such a file written by the
code before a change and prints, per case and term, the median ratio of the interval widths
(high / low, the same seeds, both resolved) after / before.
"""
from __future__ import annotations

import argparse
import copy
import json
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from gyrofilter.analysis.noise.fit import characterise
from gyrofilter.analysis.noise.model import ANGLE_RANDOM_WALK, QUANTIZATION, TERM_SYMBOL
from gyrofilter.effects import BIAS_INSTABILITY, RATE_RANDOM_WALK, TEMPERATURE
from gyrofilter.sim.model import load_model
from gyrofilter.sim.simulate import simulate
from gyrofilter.sources.simulated import DEFAULT_MODEL_PATH

SAMPLE_RATE_HZ = 100.0
TERMS = (QUANTIZATION, ANGLE_RANDOM_WALK, BIAS_INSTABILITY, RATE_RANDOM_WALK)
#: the white + random walk case's K per axis (deg/s/sqrt(s))
WHITE_RW_K = {"x": 5e-5, "y": 1e-4, "z": 2e-4}
#: the white + flicker + random walk case's N (deg/s/sqrt(Hz)), B (deg/s) and K (deg/s/sqrt(s)), every axis
WHITE_FLICKER_RW = {"arw_dps_per_sqrt_hz": 0.01, "b_dps": 0.005, "k_dps_per_sqrt_s": 0.003}
#: the white + quantization case's N (deg/s/sqrt(Hz), every axis) and Q per axis (deg)
WHITE_QUANT_N = 0.01
WHITE_QUANT_Q = {"x": 1e-4, "y": 2e-4, "z": 5e-4}


def default_model():
    return load_model(str(DEFAULT_MODEL_PATH))


def white_rw_model():
    model = default_model()
    model.pop("temperature")
    model.pop("accelerometer")
    for axis, spec in model["axes"].items():
        spec["effects"] = [{"effect": RATE_RANDOM_WALK, "k_dps_per_sqrt_s": WHITE_RW_K[axis]}]
    return model


def white_flicker_model():
    model = default_model()
    model.pop("temperature")
    model.pop("accelerometer")
    for spec in model["axes"].values():
        spec["effects"] = [e for e in spec["effects"] if e["effect"] != TEMPERATURE]
    return model


def white_flicker_rw_model():
    """No quantization (no ``lsb_per_dps``), as attack pass 34a measured it."""
    effects = [{"effect": BIAS_INSTABILITY, "b_dps": WHITE_FLICKER_RW["b_dps"]},
               {"effect": RATE_RANDOM_WALK, "k_dps_per_sqrt_s": WHITE_FLICKER_RW["k_dps_per_sqrt_s"]}]
    return {"sample_rate_hz": SAMPLE_RATE_HZ, "gyro_unit": "dps",
            "axes": {axis: {"bias_dps": 0.5, "arw_dps_per_sqrt_hz": WHITE_FLICKER_RW["arw_dps_per_sqrt_hz"],
                            "effects": copy.deepcopy(effects)} for axis in "xyz"}}


def white_quant_model():
    return {"sample_rate_hz": SAMPLE_RATE_HZ, "gyro_unit": "dps",
            "axes": {axis: {"bias_dps": 0.5, "arw_dps_per_sqrt_hz": WHITE_QUANT_N, "effects": []} for axis in "xyz"}}


def quantize_angle(rate_dps, seed):
    """The rate plus the first difference of an angle quantization error (deg), uniform on
    [-q/2, q/2] with q = sqrt(12) Q, independent per sample: rate + (e[n] - e[n-1]) f_s."""
    rng = np.random.default_rng([seed, 952])
    out = np.array(rate_dps, dtype=float)
    for i, axis in enumerate("xyz"):
        step = np.sqrt(12.0) * WHITE_QUANT_Q[axis]
        e = rng.uniform(-step / 2, step / 2, len(out) + 1)
        out[:, i] += np.diff(e) * SAMPLE_RATE_HZ
    return out


def quant_truth(model):
    return {axis: {QUANTIZATION: WHITE_QUANT_Q[axis], ANGLE_RANDOM_WALK: WHITE_QUANT_N,
                   BIAS_INSTABILITY: 0.0, RATE_RANDOM_WALK: 0.0} for axis in model["axes"]}


def gyro_truth(model):
    """{axis: {term: simulated value}} of a gyro model (deg/s units)."""
    out = {}
    for axis, spec in model["axes"].items():
        effects = {e["effect"]: e for e in spec["effects"]}
        out[axis] = {ANGLE_RANDOM_WALK: spec["arw_dps_per_sqrt_hz"],
                     BIAS_INSTABILITY: effects.get(BIAS_INSTABILITY, {}).get("b_dps", 0.0),
                     RATE_RANDOM_WALK: effects.get(RATE_RANDOM_WALK, {}).get("k_dps_per_sqrt_s", 0.0)}
    return out


def accel_truth(model):
    return {axis: {ANGLE_RANDOM_WALK: s["vrw_mps_per_sqrt_s"], BIAS_INSTABILITY: s["b_mps2"],
                   RATE_RANDOM_WALK: s["k_mps2_per_sqrt_s"]}
            for axis, s in model["accelerometer"]["axes"].items()}


#: name -> (model, sensor, truth)
CASES = {"default-gyro": (default_model, "gyro", gyro_truth),
         "default-accel": (default_model, "accel", accel_truth),
         "white-rw": (white_rw_model, "gyro", gyro_truth),
         "white-flicker": (white_flicker_model, "gyro", gyro_truth),
         "white-flicker-rw": (white_flicker_rw_model, "gyro", gyro_truth),
         "white-quant": (white_quant_model, "quant", quant_truth)}


def run(job):
    """One record: a row per axis and term."""
    case, minutes, seed = job
    make, sensor, truth_of = CASES[case]
    model = make()
    rec = simulate(copy.deepcopy(model), 60.0 * minutes, seed=seed, accelerometer=sensor == "accel")
    data = rec.accel_mps2 if sensor == "accel" else rec.gyro_dps
    if sensor == "quant":
        data = quantize_angle(data, seed)
    truth = truth_of(model)
    rows = []
    for axis, r in characterise(data, SAMPLE_RATE_HZ).items():
        for term in (t for t in TERMS if t in truth[axis]):
            c = r.fitted[term]
            rows.append({"case": case, "minutes": minutes, "seed": seed, "axis": axis, "term": term,
                         "true": truth[axis][term], "value": c.value, "low": c.low, "high": c.high, "upper": c.upper})
    return rows


def covered(row):
    if row["value"] is not None:
        return row["low"] <= row["true"] <= row["high"]
    return row["upper"] is not None and row["true"] <= row["upper"]


def clopper_pearson(k, n, level=0.95):
    """Two-sided Clopper-Pearson interval (%) of a rate with ``k`` events in ``n`` trials."""
    from scipy.stats import beta
    a = (1 - level) / 2
    lo = 0.0 if k == 0 else beta.ppf(a, k, n - k + 1)
    hi = 1.0 if k == n else beta.ppf(1 - a, k + 1, n - k)
    return 100 * lo, 100 * hi


def cell(rows):
    if not rows:
        return "-"
    k = sum(covered(r) for r in rows)
    lo, hi = clopper_pearson(k, len(rows))
    return f"{k}/{len(rows)} [{lo:.0f}, {hi:.0f}]"


def table(rows):
    """Coverage per case, minutes and term: resolved (interval) and not resolved (upper bound)."""
    lines = [f"{'case':>16s} {'min':>4s} {'term':>4s}  {'resolved: inside interval':>26s}  "
             f"{'not resolved: true <= upper':>28s}  {'all':>22s}"]
    keys = sorted({(r["case"], r["minutes"], r["term"]) for r in rows},
                  key=lambda k: (list(CASES).index(k[0]), k[1], TERMS.index(k[2])))
    for case, minutes, term in keys:
        sel = [r for r in rows if (r["case"], r["minutes"], r["term"]) == (case, minutes, term)]
        if all(r["true"] == 0 for r in sel) and term == RATE_RANDOM_WALK:
            continue  # K = 0: an upper bound always holds it, a resolved K is the drift's
        res = [r for r in sel if r["value"] is not None]
        unres = [r for r in sel if r["value"] is None]
        lines.append(f"{case:>16s} {minutes:4d} {TERM_SYMBOL[term]:>4s}  {cell(res):>26s}  {cell(unres):>28s}  "
                     f"{cell(sel):>22s}")
    return lines


def width_ratios(rows, before):
    """Per case and term: the median over the axes resolved in both of (high/low after) / (high/low before)."""
    old = {(r["case"], r["minutes"], r["seed"], r["axis"], r["term"]): r for r in before}
    out = {}
    for r in rows:
        b = old.get((r["case"], r["minutes"], r["seed"], r["axis"], r["term"]))
        if b is None or r["value"] is None or b["value"] is None or not (r["low"] > 0 and b["low"] > 0):
            continue
        out.setdefault((r["case"], TERM_SYMBOL[r["term"]]), []).append(
            np.log(r["high"] / r["low"]) / np.log(b["high"] / b["low"]))
    return [f"{case:>16s} {sym}: median width ratio (log high/low) after/before {np.median(v):.2f} "
            f"(quartiles {np.quantile(v, 0.25):.2f}-{np.quantile(v, 0.75):.2f}, {len(v)} axes)"
            for (case, sym), v in sorted(out.items())]


def seeds(text):
    lo, _, hi = text.partition("-")
    return range(int(lo), int(hi or lo) + 1)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="1-10", help="seed range, e.g. 1-10 (default)")
    parser.add_argument("--minutes", default="10,30,60", help="record lengths (default 10,30,60)")
    parser.add_argument("--cases", default=",".join(CASES), help=f"of {', '.join(CASES)}")
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--rows", help="write every axis's numbers here (JSON)")
    parser.add_argument("--before", help="rows of the code before a change: print the width ratios")
    args = parser.parse_args(argv)
    jobs = [(c, int(m), s) for c in args.cases.split(",") for m in args.minutes.split(",") for s in seeds(args.seeds)]
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = [row for rec in pool.map(run, jobs) for row in rec]
    print(f"Coverage of the 95 % intervals and upper bounds, seeds {args.seeds} x 3 axes "
          "(two-sided 95 % Clopper-Pearson intervals, %)")
    print("\n".join(table(rows)))
    if args.rows:
        with open(args.rows, "w") as f:
            json.dump(rows, f)
    if args.before:
        with open(args.before) as f:
            print("\n".join(width_ratios(rows, json.load(f))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
