"""gyrofilter allan: overlapping Allan deviation and noise coefficients of a recording.

Prints, per axis, the fitted coefficients Q, N, B, K, R with their intervals in deg/s-based and
customary units, the slope read-offs of papers 000/002 beside them (another estimator: an upper
estimate of each term, said so where the fit resolves none), and what the record is too short
to resolve. ``--json`` writes the Allan document of docs/formats.md, ``--plot`` the
log-log figure, ``--kalibr`` Kalibr's imu.yaml gyroscope entries (the pair that bounds the
measured deviation over ``--kalibr-tau-s``, :mod:`gyrofilter.analysis.noise.kalibr`).

The recording is read in chunks into one float64 array per axis. Gross errors (isolated spikes
far beyond the noise, or rates beyond any MEMS full scale: :func:`gyrofilter.analysis.noise.screen.gross_errors`)
are refused before any computation unless ``--keep-outliers`` is given; they are never dropped.
Output files are written only once every result is finite, each whole or not at all.
"""

from ..effects import BIAS_INSTABILITY, RATE_RAMP, RATE_RANDOM_WALK
from ..analysis.noise.allan import MAX_CONFIDENCE, MIN_CLUSTERS, AllanInputError, ConstantAxisError, confidence_text
from ..analysis.fleet.work import FleetSettings
from ..analysis.noise.export import kalibr_yaml, to_json
from ..analysis.noise.kalibr import DEFAULT_TAU_RANGE_S, check_tau_range_s, kalibr_sensor
from ..analysis.noise.model import ACCELEROMETER_TERMS, GYROSCOPE_TERMS, TERMS, TERM_SYMBOL, convert
from ..analysis.noise.readoff import NOT_DETERMINED
from ..analysis.noise.plots import plot_allan
from ..analysis.still import GAPS_CONSEQUENCE, characterise_recording
from ..errors import SettingsError
from ..plots import check_figure_path
from ..recording import warn_about_gaps
from ..units import AXES, check_axes
from . import batch, console, options, outputs, still

MAX_MIN_CLUSTERS = 1000  # clusters asked for at the longest tau (paper 002: 9)
ALL_AXES = "".join(AXES)  # --axes as one word: xyz



def add_arguments(parser):
    parser.add_argument("recordings", nargs="+", metavar="RECORDING",
                        help="recording file (format v1, .csv or .csv.gz), sensor still; several files or globs "
                             "with --fleet")
    parser.add_argument("--json", metavar="OUT", type=options.file_name, help="write the deviation curves and coefficients as JSON")
    parser.add_argument("--plot", metavar="OUT.png", type=options.file_name, help="draw the Allan deviation per axis (needs matplotlib)")
    parser.add_argument("--kalibr", metavar="OUT.yaml", type=options.file_name, help="write Kalibr imu.yaml noise entries (the gyroscope's, and the accelerometer's where the record "
                             "has one): the white + random-walk pair that bounds the measured Allan deviation over "
                             "--kalibr-tau-s, the plain values in comments")
    parser.add_argument("--kalibr-tau-s", metavar="LOW,HIGH", type=options.number_pair, default=None,
                        help="integration times (s) over which the imu.yaml's values bound the measured Allan "
                             f"deviation of every axis (default {DEFAULT_TAU_RANGE_S[0]:g},{DEFAULT_TAU_RANGE_S[1]:g}, "
                             "cut to the record; docs/allan.md)")
    parser.add_argument("--axes", default=ALL_AXES, help=f"axes to analyse, a subset of {ALL_AXES} (default {ALL_AXES}), "
                                                          "of the gyro and of the accelerometer")
    parser.add_argument("--confidence", type=options.decimal, default=0.95, help="two-sided confidence of the intervals (default 0.95)")
    parser.add_argument("--min-clusters", type=options.whole_number, default=MIN_CLUSTERS,
                        help=f"fit only taus with at least this many clusters (default {MIN_CLUSTERS}, paper 002; lower values are flagged)")
    still.add_keep_outliers_argument(parser)
    parser.add_argument("--allow-motion", action="store_true",
                        help="with --fleet: analyse the recordings whose gyro does not look still (skipped by default: "
                             "their Allan deviation describes the motion), kept out of the fleet's comparison")
    still.add_allow_large_mean_argument(parser)
    console.add_progress_argument(parser)
    batch.add_arguments(parser)
    options.add_force_argument(parser)


#: widest line of the console table (characters): it reads on a 100-column terminal; the full table is --json's


def _fmt(c, unit, interval=True):
    """A coefficient ``c`` in ``unit``: "value [low, high]" (the value alone without ``interval``),
    "< bound" when not resolved, "-" when not resolved and unbounded, "not determined" for a
    read-off the curve cannot give (:data:`~gyrofilter.analysis.noise.readoff.NOT_DETERMINED`)."""
    if c.value is None and c.note.startswith(NOT_DETERMINED):
        return NOT_DETERMINED
    if c.value is None:
        up = convert(c.upper, c.term, unit)
        return f"< {up:.3g}" if up is not None else "-"
    v, lo, hi = (convert(x, c.term, unit) for x in (c.value, c.low, c.high))
    return f"{v:.4g} [{lo:.3g}, {hi:.3g}]" if interval else f"{v:.4g}"


def readoff_only(r, terms=GYROSCOPE_TERMS):
    """One sentence per term of the axis result ``r`` (an AxisNoise) that the fit does not
    resolve but the slope read-off gives a number for: the two are different estimators, and
    the read-off (the curve at one tau, every term included) bounds the term from above.
    ``terms``: the sensor's :class:`~gyrofilter.analysis.noise.model.SensorTerms` (its units)."""
    out = []
    for t in TERMS:
        c, ro = r.fitted[t], r.readoff[t]
        if c.value is None and ro.value is not None:
            unit, sym = terms.term_unit[t], TERM_SYMBOL[t]
            bound = f" (< {c.upper:.3g} {unit})" if c.upper is not None else ""
            out.append(f"{sym}: the fit does not resolve it{bound}; the slope read-off {ro.value:.3g} {unit} is the "
                       f"curve at tau = {ro.tau_s:.3g} s, where the other terms add to {sym}: an upper estimate, "
                       f"not a value of {sym}")
    return out


def analyse(path, *, axes=ALL_AXES, confidence=0.95, min_clusters=MIN_CLUSTERS, keep_outliers=False, warn, progress=None,
            skip_constant=False, allow_large_mean=False):
    """What ``allan`` computes of one recording ``path``: (head, {axis: AxisNoise}, the ``--json``
    document of docs/formats.md section 4, the accelerometer's {axis: AxisNoise} or None), through :func:`~gyrofilter.analysis.still.characterise_recording`
    (its arguments, ``warn(text)``, ``progress(text)``, ``skip_constant`` and ``allow_large_mean`` included) and
    :func:`~gyrofilter.analysis.noise.export.to_json` (with the count of repeated rows and the t column's gaps); the
    duration is rows / sample rate (s).
    A result that is not finite raises AllanInputError naming the file; a stuck axis (not
    skipped) says which ``--axes`` analyse the others."""
    told = []

    def tell(text):
        told.append(text)
        warn(text)

    try:
        head, results, repeats, accel, accel_left_out = characterise_recording(
            path, axes=axes, confidence=confidence, min_clusters=min_clusters, keep_outliers=keep_outliers, warn=tell,
            progress=progress, skip_constant=skip_constant, allow_large_mean=allow_large_mean)
    except ConstantAxisError as exc:  # which --axes would run: the others that vary (all of them were "yz" of a file of equal rows)
        others = exc.varying
        advice = (f"; give --axes {others} to analyse the others" if others else
                  "; every axis asked for is constant" if len(axes) > 1 else "")
        raise AllanInputError(f"{path}: {exc}{advice}") from None
    except AllanInputError as exc:  # the data of this file: name it
        raise AllanInputError(f"{path}: {exc}") from None
    duration_s = head.rows / head.sample_rate_hz
    gaps = []
    warn_about_gaps(head, GAPS_CONSEQUENCE, gaps.append)
    return head, results, to_json(results, head.sample_rate_hz, recording=path, duration_s=duration_s,
                                  repeated_rows=repeats, accelerometer=accel,
                                  accelerometer_left_out=accel_left_out,
                                  t_gaps=(head.t_gaps, gaps[0]) if gaps else None, warnings=told), accel


def misfit_text(r):
    """The fit's reduced chi-square of the axis result ``r`` (an AxisNoise; one with a fit that has
    degrees of freedom left) and what it did to the intervals, one line."""
    text = f"fit's reduced chi-square {r.fit_reduced_chi2:.3g} ({r.fit_dof:.3g} effective dof)"
    return text + (f": intervals and bounds widened x{r.interval_widening:.3g}" if r.fit_reduced_chi2 > 1 else "")


def unresolved_text(r, min_clusters, terms=GYROSCOPE_TERMS):
    """What the record ``r`` (an AxisNoise) does not resolve of the slow terms (B, K, R): those the
    fit left out, with the longest cluster time with ``min_clusters`` clusters (the record is too
    short); those the model holds that are within their uncertainty of zero once a B, K or R the
    record does not resolve is free (``Coefficient.freed_by``); and those the model holds whose interval,
    widened by the fit's misfit, reaches zero (the curve holds what the five terms do not fit; the
    advice to see ``gyrofilter gap`` where it analyses the sensor, ``terms.gap``); "" when it
    resolves them all. ``terms``: the sensor's :class:`~gyrofilter.analysis.noise.model.SensorTerms`."""
    slow = [t for t in (BIAS_INSTABILITY, RATE_RANDOM_WALK, RATE_RAMP) if r.fitted[t].value is None]
    held = [t for t in slow if r.fit_values[TERMS.index(t)] > 0]
    missing = [TERM_SYMBOL[t] for t in slow if r.fit_values[TERMS.index(t)] == 0]
    misfit = [TERM_SYMBOL[t] for t in held if not r.fitted[t].freed_by]
    out = []
    if missing:
        longest = r.tau_s[r.fit_used][-1]
        out.append(f"{', '.join(missing)} not resolved: the longest cluster time with {min_clusters} clusters is "
                   f"{longest:.3g} s; slower effects need a longer still recording")
    for t in (t for t in held if r.fitted[t].freed_by):
        freed = r.fitted[t].freed_by
        out.append(f"{TERM_SYMBOL[t]} in the fitted model but not resolved: within its uncertainty of zero once "
                   f"{' and '.join(TERM_SYMBOL[f] for f in freed)} (not resolved) {'are' if len(freed) > 1 else 'is'} "
                   "free")
    if misfit:
        out.append(f"{', '.join(misfit)} in the fitted model but not resolved: with the fit's misfit (reduced "
                   f"chi-square {r.fit_reduced_chi2:.3g}) the interval reaches zero; the curve holds what the "
                   "five terms do not fit" + (" (see `gyrofilter gap`)" if terms.gap else ""))
    return "; ".join(out)


def kalibr_text_line(k):
    """One paragraph on the bounding pair of ``k`` (a :class:`~gyrofilter.analysis.noise.kalibr.KalibrValues`):
    the values written, their factors over the plain values and how far the model lies above the data."""
    f_nd, f_rw = (held if held is not None else f"{f:.3g}x the plain value" if f is not None else "no plain value"
                  for f, held in zip(k.factors(), k.held_texts()))
    low, high = k.tau_range_s
    cut = (f" (the default {DEFAULT_TAU_RANGE_S[0]:g} .. {DEFAULT_TAU_RANGE_S[1]:g} s cut to the record)"
           if k.cut else "")
    return (f"kalibr, {k.sensor.name}: the pair that bounds every axis's Allan deviation over tau {low:g} .. {high:g} s{cut}: "
            f"{k.sensor.name}_noise_density {k.noise_density:.3e} {k.sensor.density_unit} ({f_nd}), "
            f"{k.sensor.name}_random_walk {k.random_walk:.3e} {k.sensor.walk_unit} ({f_rw}); its model lies at "
            f"{k.bound.least:.3g} .. {k.bound.excess:.3g}x the largest axis's deviation there")


def print_coefficients(results, terms, confidence, min_clusters):
    """The console table of one sensor's ``results`` ({axis: AxisNoise}) in the units of ``terms`` (its
    :class:`~gyrofilter.analysis.noise.model.SensorTerms`): per axis the misfit, each term's fit with its
    interval, its customary unit and the slope read-off, and what the record does not resolve."""
    console.paragraph(", ".join(f"{TERM_SYMBOL[t]} {terms.term_name[t]}" for t in TERMS), "  ")
    for a, r in results.items():
        print(f"  axis {a}:")
        if r.fit_reduced_chi2 is not None:
            print(f"    {misfit_text(r)}")
        print(f"    {'':<16}{'fit [' + confidence_text(confidence) + ' interval]':<32}{'= customary unit':<25}slope read-off")
        for t in TERMS:
            c, ro = r.fitted[t], r.readoff[t]
            base, cust = terms.term_unit[t], terms.customary_unit[t]
            print(f"    {TERM_SYMBOL[t]} {base:<14}{_fmt(c, base):<32}{_fmt(c, cust, interval=False) + ' ' + cust:<25}"
                  f"{_fmt(ro, base, interval=False)}".rstrip())
        for line in readoff_only(r, terms):
            console.paragraph(f"({line})", "    ")
        missing = unresolved_text(r, min_clusters, terms)
        if missing:
            console.paragraph(f"({missing}; the bounds above hold)", "    ")
        console.print_warnings(r.warnings)


def run(args):
    axes = "".join(check_axes(args.axes, "--axes"))
    if not 2 <= args.min_clusters <= MAX_MIN_CLUSTERS:
        raise SettingsError(f"--min-clusters must be in [2, {MAX_MIN_CLUSTERS}], got {args.min_clusters}")
    if not 0.5 <= args.confidence <= MAX_CONFIDENCE:  # the library's highest (analysis.noise.allan.check_confidence)
        raise SettingsError(f"--confidence must be in [0.5, {MAX_CONFIDENCE:g}] (e.g. 0.95), got {args.confidence!r}")
    if args.kalibr_tau_s is not None:
        check_tau_range_s(args.kalibr_tau_s)
        if not args.kalibr and args.fleet is None:
            raise SettingsError("--kalibr-tau-s sets the range of --kalibr's values: give --kalibr OUT.yaml as well")
    paths = batch.expand(args.recordings)
    if args.fleet is not None:
        batch.refuse_single_file_outputs(args, ["--json", "--plot", "--kalibr"])
        still.refuse_allow_large_mean_in_fleet(args)
        settings = FleetSettings("allan", axes=axes, confidence=args.confidence, min_clusters=args.min_clusters,
                                 keep_outliers=args.keep_outliers, kalibr_tau_s=args.kalibr_tau_s,
                                 allow_motion=args.allow_motion)
        return batch.run(args, settings, paths)
    if args.allow_motion:
        raise SettingsError("--allow-motion works on a fleet (--fleet DIR); a single recording that moved is "
                            "analysed, with a warning that its Allan deviation describes the motion")
    args.recording = batch.single(args, paths)
    outputs.check_outputs([args.json, args.plot, args.kalibr], [args.recording], args.force)
    if args.plot:
        check_figure_path(args.plot)
    progress = console.ProgressLines(args.progress)
    said = []  # the analysis' warnings, also written into the yaml

    def warn(text):
        said.append(text)
        console.say_warning(text)

    head, results, document, accel = analyse(args.recording, axes=axes, confidence=args.confidence,
                                             min_clusters=args.min_clusters, keep_outliers=args.keep_outliers,
                                             warn=warn, progress=progress, allow_large_mean=args.allow_large_mean)
    sample_rate_hz = head.sample_rate_hz
    duration_s = head.rows / sample_rate_hz
    # before anything is printed or written: a --kalibr-tau-s beyond the record is refused in one line
    kalibr_text = (kalibr_yaml(results, sample_rate_hz, recording=args.recording, tau_range_s=args.kalibr_tau_s,
                               accelerometer=accel, header=head.header, warnings=said) if args.kalibr else None)
    console.tell(f"recording: {args.recording}")
    print(f"  {head.rows} samples at {sample_rate_hz:g} Hz ({duration_s:.1f} s); unit {head.gyro_unit}; "
          f"taus {results[axes[0]].tau_s[0]:g} .. {results[axes[0]].tau_s[-1]:g} s")
    console.paragraph(f"coefficients: weighted NNLS fit of the five-term Allan model, value [{confidence_text(args.confidence)} interval], and "
         "its customary unit; slope read-off: the slope method of papers 000/002, another estimator, for "
         "comparison: the curve at one tau, which every term adds to, so an upper estimate of its term "
         "(<: not resolved, at most; -: not resolved; every interval: --json)", "  ")
    print_coefficients(results, GYROSCOPE_TERMS, args.confidence, args.min_clusters)
    if accel is not None:
        console.tell("accelerometer:")
        console.paragraph("the same analysis of the acceleration (m/s^2; gravity, a constant on the axis that points "
                          "up, does not enter the Allan deviation): Q velocity (m/s), N in m/s/sqrt(s) = "
                          "m/s^2/sqrt(Hz), B in m/s^2, K in m/s^2/sqrt(s), R in m/s^3", "  ")
        print_coefficients(accel, ACCELEROMETER_TERMS, args.confidence, args.min_clusters)
    if args.kalibr:
        for sensor, unit in ((results, "deg/s"), (accel, "m/s^2")):
            if sensor is not None:
                console.paragraph(kalibr_text_line(kalibr_sensor(sensor, unit, args.kalibr_tau_s)), "  ")
    # every result is finite here; each file appears only when it is complete
    if args.json:
        with outputs.replacing(args.json) as tmp:
            outputs.write_json_document(tmp, document)
        console.say(f"wrote {args.json}")
    if args.kalibr:
        with outputs.replacing(args.kalibr) as tmp:
            outputs.write_text(tmp, kalibr_text)
        console.say(f"wrote {args.kalibr}")
    if args.plot:
        with outputs.replacing(args.plot) as tmp:
            plot_allan(tmp, results, title=f"{args.recording} ({duration_s:.0f} s at {sample_rate_hz:g} Hz)")
        console.say(f"drew {args.plot}")
    return 0
