"""gyrofilter arma: paper 003's time-series model of a static recording's bias noise, per axis.

Gross errors (spikes far beyond the noise) are refused before any fit, as ``allan`` refuses them
(``--keep-outliers`` analyses them anyway). Warnings of scipy/statsmodels (hard fits) are
summarised in one line on stderr, not printed one by one. ``--json`` is refused when it exists (unless ``--force``) or is the recording, before
any work, and written under a temporary name that takes its place when complete.
"""
import dataclasses
import math

import numpy as np

from ..analysis.arma import identify as arma
from ..analysis.still import moved, not_analysed, read_axes, refuse_gross_errors, refuse_large_mean
from ..errors import SettingsError
from ..recording import filtered_words, warn_about_gaps
from ..recording.checks import gap_step_s
from ..units import AXES, MAX_DURATION_S
from . import console, options, outputs, still

MAX_MAX_N = 10  # ARMA(20, 19): the longest model the simulator takes (20 coefficients each side)
PAPER_003 = "paper 003 (ADIS16405 z gyro): ADF -110.18; KS and JB reject normality; ARMA(1, 1): x_t - 1.0000 x_{t-1} = a_t - 0.9994 a_{t-1}"


def add_arguments(parser):
    parser.add_argument("recording", help="a static recording (format v1); the sensor must not move")
    parser.add_argument("--axis", choices=(*AXES, "all"), default="all", help="axis to analyse (default: all three)")
    parser.add_argument("--json", metavar="OUT", type=options.file_name, help="write every number of the analysis to this JSON file")
    parser.add_argument("--start-s", type=options.decimal, default=None, help="skip the first seconds (e.g. a warm-up or a move; default 0)")
    parser.add_argument("--end-s", type=options.decimal, default=None, help="stop at this time in seconds (default: the end)")
    parser.add_argument("--max-n", type=options.whole_number, default=4, help="highest Pandit-Wu order ARMA(2n, 2n-1) tried (default 4: ARMA(8, 7))")
    parser.add_argument("--max-samples", type=options.whole_number, default=200_000,
                        help="longer series are block-averaged to at most this many samples (default 200000)")
    parser.add_argument("--alpha", type=options.decimal, default=0.05, help="significance level of every test (default 0.05)")
    parser.add_argument("--criterion", choices=("f", "aic", "bic"), default="bic",
                        help="what decides each order step: BIC (default; the F test and AIC over-select on simulated ARMA(1,1)), "
                             "the F test (paper 003's rule) or AIC; all three are printed")
    console.add_progress_argument(parser)
    still.add_keep_outliers_argument(parser)
    still.add_allow_large_mean_argument(parser)
    options.add_force_argument(parser)


def run(args):
    outputs.check_outputs([args.json], [args.recording], args.force)
    arma.require_stats()
    if not 0 < args.alpha < 0.5:
        raise SettingsError(f"--alpha must be in (0, 0.5), got {args.alpha:g}")
    if args.max_n < 1:
        raise SettingsError(f"--max-n must be at least 1, got {args.max_n}")
    if args.max_n > MAX_MAX_N:
        raise SettingsError(f"--max-n must be at most {MAX_MAX_N} (ARMA({2 * MAX_MAX_N}, {2 * MAX_MAX_N - 1})), got {args.max_n}")
    arma.check_max_samples(args.max_samples, "--max-samples")
    axes = AXES if args.axis == "all" else (args.axis,)
    head, series, t_s = read_axes(args.recording, axes + not_analysed(axes), with_t=True)  # the others' means too
    warnings = list(head.warnings)
    filtered = filtered_words(head.header)
    if filtered:  # analysed, as allan analyses it, but said: the model is the output's, not the sensor's bias
        warnings.append(f"{args.recording}: is {filtered}: paper 003's model describes a sensor's bias noise; this "
                        "one describes the filter's output")
    console.print_warnings(warnings)

    def warn(text):  # said, and in the --json document
        warnings.append(text)
        console.say_warning(text)

    fs = head.sample_rate_hz
    i0, i1 = _window(args, head.rows, fs, t_s)
    if t_s is not None and (i0, i1) != (0, head.rows):  # the gaps of the window analysed, not of the file
        head = dataclasses.replace(head, t_gaps=int(np.count_nonzero(np.diff(t_s[i0:i1]) > gap_step_s(head))))
    warn_about_gaps(head, "an ARMA model assumes uniform samples: its fit across the gaps is not meaningful", warn)
    series = {a: x[i0:i1] for a, x in series.items()}
    refuse_large_mean(head.path, head.gyro_unit, series, args.allow_large_mean, warn=warn)
    series = {a: series[a] for a in axes}
    refuse_gross_errors(head, series, args.keep_outliers, warn=warn, first_row=i0)
    for name in axes:  # as allan says it: the model of a moving gyro's record is the motion's
        motion = moved(series[name], head.sample_rate_hz)
        if motion:
            warn(f"{args.recording}: axis {name}: {motion}; paper 003's model of a moving gyro describes the "
                 "motion, not the bias")
    progress = console.ProgressLines(args.progress)
    quantum = 1.0 / head.lsb_per_dps if head.lsb_per_dps else None
    n = i1 - i0
    start_s, span_s = _start_s(i0, fs, t_s), _span_s(i0, i1, fs, t_s)
    reports = {}
    console.tell(f"recording: {args.recording}")
    print(f"  {n} samples at {fs:g} Hz ({span_s:.1f} s) from {start_s:g} s after the first sample, unit {head.gyro_unit}; "
          "each axis minus its mean")
    for name in axes:
        progress(f"arma: axis {name}: tests and Pandit-Wu order search ...")
        try:
            rep = arma.analyze_axis(series[name], fs, axis=name, max_samples=args.max_samples,
                                    max_n=args.max_n, alpha=args.alpha, quantum_dps=quantum, criterion=args.criterion)
        except SettingsError as exc:  # what the data of this file cannot give: name it (the options are checked above)
            raise SettingsError(f"{args.recording}: {exc}") from None
        reports[name] = rep
        _print_axis(rep, args.alpha)
    print(f"\n{PAPER_003}")
    warned = [f"axis {k}: " + "; ".join(v.warnings) for k, v in reports.items() if v.warnings]
    if warned:
        console.print_warnings(["scipy/statsmodels warned during the fits (check the results above): " + "; ".join(warned)])
    if args.json:
        out = {"recording": args.recording, "sample_rate_hz": fs, "start_s": start_s, "duration_s": span_s, "n_samples": n,
               "alpha": args.alpha, "axes": {k: v.to_dict() for k, v in reports.items()},
               "warnings": warnings}
        with outputs.replacing(args.json) as tmp:
            outputs.write_json(tmp, out)
        console.say(f"wrote {args.json}")
    return 0


def _window(args, n, sample_rate_hz, t_s=None):
    """Sample indices [i0, i1) of --start-s/--end-s, in seconds after the first sample: by the
    ``t`` column when the file has one (``t_s``: the samples from the first at or after the time
    minus half an interval, so that a uniform ``t`` selects as the count does), else by the count
    (sample i at i / ``sample_rate_hz``); errors name the options the user gave."""
    for option, value in (("--start-s", args.start_s), ("--end-s", args.end_s)):
        if value is not None and not abs(value) <= MAX_DURATION_S:
            raise SettingsError(f"{option} must be a finite number of seconds, at most {MAX_DURATION_S:g}, got {value:g}")
    if args.start_s is not None and args.start_s < 0:
        raise SettingsError(f"--start-s must be >= 0 s, got {args.start_s:g}")
    start_s = args.start_s or 0.0
    if args.end_s is not None and args.end_s <= start_s:
        raise SettingsError(f"--end-s {args.end_s:g} must be after " +
                            (f"--start-s {start_s:g}" if args.start_s is not None else "the start (0 s)"))
    if t_s is None:
        i0 = int(round(start_s * sample_rate_hz))
        i1 = n if args.end_s is None else min(n, int(round(args.end_s * sample_rate_hz)))
    else:
        after_s = t_s - t_s[0]
        i0 = int(np.searchsorted(after_s, start_s - 0.5 / sample_rate_hz))
        i1 = n if args.end_s is None else int(np.searchsorted(after_s, args.end_s - 0.5 / sample_rate_hz))
    if i1 - i0 >= arma.MIN_SAMPLES:
        return i0, i1
    length = f"{n} samples ({_span_s(0, n, sample_rate_hz, t_s):g} s at {sample_rate_hz:g} Hz)"
    given = " and ".join(f"--{name.replace('_', '-')} {value:g}" for name, value in
                         (("start_s", args.start_s), ("end_s", args.end_s)) if value is not None)
    if not given:
        raise SettingsError(f"{args.recording}: {length}; the analysis needs at least {arma.MIN_SAMPLES}")
    verb = "leave" if " and " in given else "leaves"
    raise SettingsError(f"{given} {verb} {max(0, i1 - i0)} of the {length} of {args.recording}; "
                        f"the analysis needs at least {arma.MIN_SAMPLES}")


def _start_s(i0, sample_rate_hz, t_s):
    """When sample ``i0`` was taken, in seconds after the first (by ``t_s`` when the file has it)."""
    return i0 / sample_rate_hz if t_s is None else float(t_s[i0] - t_s[0])


def _span_s(i0, i1, sample_rate_hz, t_s):
    """The time samples [i0, i1) span (s), one interval per sample: by ``t_s`` when the file has it
    (lost samples lengthen it), else the count over ``sample_rate_hz``."""
    return (i1 - i0) / sample_rate_hz if t_s is None else float(t_s[i1 - 1] - t_s[i0]) + 1.0 / sample_rate_hz


def _print_axis(rep, alpha):
    pct = f"{alpha * 100:g} %"
    print(f"\naxis {rep.axis}: mean {rep.mean_dps:+.4g} deg/s, std {rep.std_dps:.4g} deg/s")
    for note in rep.notes:
        print(f"  note: {note}")
    s = rep.stationarity
    print(f"  stationarity (ADF, constant, {s.lags_used} lags): statistic {s.adf_statistic:.2f} "
          f"(1 % {s.critical_values['1%']:.2f}, 5 % {s.critical_values['5%']:.2f}) -> {'stationary' if s.stationary else 'unit root not rejected'}")
    n = rep.normality
    print(f"  normality: KS D = {n.ks_statistic:.4f} (5 % critical {n.ks_critical_5pct:.4f}, p = {n.ks_p_value:.3g}) -> "
          f"{'normal' if n.normal_ks else 'rejected'}; JB = {n.jb_statistic:.1f} (5 % critical {n.jb_critical_5pct:.2f}, "
          f"p = {n.jb_p_value:.3g}) -> {'normal' if n.normal_jb else 'rejected'}; skew {n.skewness:+.3f}, excess kurtosis {n.excess_kurtosis:+.3f}")
    if n.ks_dithered_statistic is not None:
        print(f"  KS with one LSB of uniform dither (removes the quantisation steps): D = {n.ks_dithered_statistic:.4f}, "
              f"p = {n.ks_dithered_p_value:.3g} -> {'normal' if n.normal_ks_dithered else 'rejected'}")
    print(f"  Pandit-Wu order search, decided by {rep.criterion.upper()} (AIC = ln(sigma_a^2) + 2 r / N, BIC = ln(sigma_a^2) + r ln N / N, sigma_a in deg/s):")
    print("    model        AIC         BIC         sigma_a     RSS")
    for f in rep.fits:
        mark = " <- chosen" if f is rep.chosen else (" <- adequate ARMA(2n, 2n-1)" if f.order == rep.adequate_order else "")
        bic = arma.information_criterion(f, "bic")
        print(f"    ARMA({f.p},{f.q})  {f.aic:10.5f}  {bic:10.5f}  {f.sigma_a:<8.4g}  {f.rss:.6g}{mark}")
    print(f"  F tests at {pct} (larger model significantly better?):")
    for st in rep.steps:
        print(f"    ARMA{st.smaller} vs ARMA{st.larger}: F = {st.f_statistic:.3f}, critical {st.f_critical:.3f} -> {'yes' if st.significant else 'no'}")
    print(f"  chosen: ARMA{rep.chosen.order}: {rep.chosen.equation()}   (sigma_a = {rep.chosen.sigma_a:.4g} deg/s)")
    if rep.chosen.order != (1, 1):
        print(f"  ARMA(1,1) for comparison with paper 003: {rep.arma11.equation()}")
    w = rep.whiteness
    print(f"  residuals: {w.outside_band} of {len(w.lags)} ACF lags outside +-{w.band:.4f}; Ljung-Box Q({w.ljung_box_lag}) = "
          f"{w.ljung_box_q:.1f}, p = {w.ljung_box_p_value:.3g} -> {'white' if w.white else 'not white'}")
    b = rep.bias_model
    if b.valid and not b.tau_determined:
        print(f"  bias model from ARMA(1,1) (phi {rep.arma11.phi[0]:.6f}): {b.note}; "
              f"white noise {b.white_noise_dps_per_sqrt_hz:.4g} deg/s/sqrt(Hz)")
    elif b.valid:
        tau = "inf (random walk)" if math.isinf(b.tau_s) else f"{b.tau_s:.4g} s"
        sigma = "-" if math.isinf(b.bias_sigma_dps) else f"{b.bias_sigma_dps:.4g} deg/s"
        print(f"  bias model from ARMA(1,1): Gauss-Markov tau {tau}, bias sigma {sigma}, drive {b.bias_walk_dps_per_sqrt_s:.4g} deg/s/sqrt(s); "
              f"white noise {b.white_noise_dps_per_sqrt_hz:.4g} deg/s/sqrt(Hz)")
    else:
        print(f"  bias model: {b.note}")
