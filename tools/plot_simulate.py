"""Figure: the Allan deviation of each example model's affected axis against the plain baseline.

    python tools/plot_simulate.py [--duration 3600] [--out docs/figures/simulate_effects_allan.png]

Each panel simulates examples/models/<effect>.json (MPU6050 baseline + one effect, seed 1) and
its baseline (the same model without the effect, same seed: common random numbers), and draws
the overlapping Allan deviation of the affected axis, with the theoretical line of the effect
where one exists (0.664 B, K sqrt(tau/3), R tau/sqrt(2), N/sqrt(tau)).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
EFFECTS = ["bias_instability", "rate_random_walk", "rate_ramp", "gauss_markov", "sinusoid",
           "temperature", "bias_step", "warmup", "outliers", "colored_noise"]


def affected_axis(model):
    """The axis carrying the example's one effect, and that effect."""
    for axis, spec in model["axes"].items():
        if spec.get("effects"):
            return axis, spec["effects"][-1]
    raise ValueError("no effect in model")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=3600.0)
    parser.add_argument("--out", default=str(ROOT / "docs" / "figures" / "simulate_effects_allan.png"))
    args = parser.parse_args(argv)

    from gyrofilter.plots import pyplot

    plt = pyplot()

    from gyrofilter.analysis.noise.allan import overlapping_adev
    from gyrofilter.sim.simulate import simulate

    fig, axes = plt.subplots(2, 5, figsize=(18, 7.5), sharex=True)
    for ax, name in zip(axes.ravel(), EFFECTS):
        model = json.loads((ROOT / "examples" / "models" / f"{name}.json").read_text())
        axis, eff = affected_axis(model)
        i = "xyz".index(axis)
        base = json.loads(json.dumps(model))
        base["axes"][axis]["effects"] = []
        fs = model["sample_rate_hz"]
        for label, m, style in (("baseline", base, "k-"), (name, model, "C3-")):
            g = simulate(m, args.duration, seed=1).gyro_dps[:, i]
            tau, ad = overlapping_adev(g, fs)
            ax.loglog(tau, ad, style, lw=1.3, label=label)
        n_arw = model["axes"][axis]["arw_dps_per_sqrt_hz"]
        ax.loglog(tau, n_arw / np.sqrt(tau), "k:", lw=0.8, label="N/sqrt(tau)")
        theory = {
            "bias_instability": lambda t: np.full_like(t, 0.664 * eff.get("b_dps", 0)),
            "rate_random_walk": lambda t: eff.get("k_dps_per_sqrt_s", 0) * np.sqrt(t / 3),
            "rate_ramp": lambda t: abs(eff.get("r_dps_per_s", 0)) * t / math.sqrt(2),
        }.get(name)
        if theory is not None:
            ax.loglog(tau, theory(tau), "C0--", lw=1.0, label="theory")
        params = ", ".join(f"{k}={v:g}" for k, v in eff.items() if k != "effect" and isinstance(v, (int, float)))
        ax.set_title(f"{name} ({axis})\n{params}", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="lower left")
    for ax in axes[1]:
        ax.set_xlabel("tau (s)")
    for ax in axes[:, 0]:
        ax.set_ylabel("Allan deviation (deg/s)")
    fig.suptitle(f"gyrofilter simulate: MPU6050 baseline + one effect, {args.duration:g} s at 100 Hz, seed 1", fontsize=11)
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=90)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
