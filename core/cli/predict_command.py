"""``cistrack predict DIR --site CODE [--start UTC] [--stop UTC] [--step MINUTES] [--out PREFIX]``:
where to point a telescope at MPC site CODE, with the uncertainty ellipse on the sky.

The work is :func:`cistrack.fitting.sky_ephemeris.sky_ephemeris_of` on the orbit of a fit or run
directory (:func:`cistrack.fitting.sky_ephemeris.orbit_of_directory`); this module checks the
options, prints the table (at most 120 columns), and writes ``PREFIX.csv`` and ``PREFIX.png``
(default ``DIR/sky-<CODE>``). docs/sky-predictions.md.
"""
from __future__ import annotations

import argparse
import math
import sys
import os
from datetime import timedelta
from pathlib import Path

import numpy as np

from cistrack.runs.progress import eprint as _eprint

__all__ = ["add_predict_parser", "cmd_predict", "table_lines", "MAX_TIMES"]

MAX_TIMES = 20_000
"""Most prediction times one command computes."""
_HEADER = (f"{'UTC':<20}{'RA deg':>11}{'Dec deg':>10}{'RA rate':>9}{'Dec rate':>9}{'range km':>10}{'elev':>7}"
           f"{'Sun':>7}{'Moon':>7}{'3sig a':>9}{'3sig b':>9}{'PA':>6}")
_UNITS = ("".ljust(20) + "".rjust(11) + "".rjust(10) + '"/min'.rjust(9) + '"/min'.rjust(9) + "".rjust(10)
          + "deg".rjust(7) * 3 + "arcsec".rjust(9) * 2 + "deg".rjust(6))


MIN_STEP_MINUTES = 1.0 / 60.0
"""The shortest --step, minutes: one second, the resolution of the UTC times predict writes (a shorter
step had written rows with repeated time stamps)."""
MAX_STEP_MINUTES = 1e7
"""The longest --step, minutes (a larger one overflowed the UTC grid's arithmetic)."""


def _minutes(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of minutes") from None
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"{text!r}: give a number of minutes > 0")
    if v < MIN_STEP_MINUTES:
        raise argparse.ArgumentTypeError(f"{text!r}: give at least {MIN_STEP_MINUTES:.4g} minutes (1 second: "
                                         "the predictions' UTC times are written to the second)")
    if v > MAX_STEP_MINUTES:
        raise argparse.ArgumentTypeError(f"{text!r}: give at most {MAX_STEP_MINUTES:,.0f} minutes (about 19 years; "
                                         "DE421 spans 1900-2050)")
    return v


def _utc(text: str):
    from cistrack import units
    from cistrack.errors import quoted
    from cistrack.fitting.sky_ephemeris import FIRST_YEAR, LAST_YEAR

    try:
        t = units.parse_utc(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{quoted(text)} {units.utc_problem(text, '2026-03-08T00:00:00Z')}") from None
    if not FIRST_YEAR <= t.year <= LAST_YEAR:
        raise argparse.ArgumentTypeError(f"{text!r}: sky predictions need the DE421 ephemeris, which covers the "
                                         f"years {FIRST_YEAR} to {LAST_YEAR}; give a time within them")
    return t


def add_predict_parser(sub) -> None:
    """Add ``cistrack predict`` to the sub-command parsers ``sub``."""
    from cistrack.cli.option_types import OnceOnly, path_text

    p = sub.add_parser("predict", help="where to point: RA/Dec, rates and the 1/3-sigma sky ellipse from an MPC site",
                       description="Sky predictions of the orbit of a 'cistrack fit' directory (the least-squares "
                                   "fit) or a 'cistrack run' directory (the filter's last estimate), seen from an "
                                   "MPC observatory: docs/sky-predictions.md.")
    p.add_argument("run", metavar="DIR", help="a fit or run results directory")
    p.add_argument("--site", required=True, metavar="CODE", action=OnceOnly,
                   once_hint="one site a prediction: run 'cistrack predict' once per site",
                   help="MPC observatory code, e.g. 568, 711, J04; or LAT,LON,HEIGHT_M (WGS84 degrees, metres; "
                        "--site=-29.26,289.27,2345 for a southern latitude)")
    p.add_argument("--start", type=_utc, default=None, metavar="UTC", help="first time (default: the orbit's epoch)")
    p.add_argument("--stop", type=_utc, default=None, metavar="UTC", help="last time (default: one day after --start)")
    p.add_argument("--step", type=_minutes, default=60.0, metavar="MINUTES", help="spacing, minutes (default 60)")
    p.add_argument("--out", type=path_text("--out"), default=None, metavar="PREFIX", help="write PREFIX.csv and PREFIX.png "
                   "(default DIR/sky-<CODE>; a folder: FOLDER/sky-<CODE>)")
    p.add_argument("--quiet", action="store_true", help="print no table (the files are still written); notes and "
                   "warnings still go to stderr")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing --out PREFIX.csv/.png, or a different earlier prediction in DIR/sky-<CODE>, "
                        "or write into the folder of another run, fit or study")
    p.set_defaults(func=cmd_predict)


def _times(args, orbit) -> np.ndarray:
    """Prediction times (K,) TU since the orbit's epoch from --start, --stop and --step."""
    from cistrack import units
    from cistrack.errors import ConfigError

    start = args.start or units.tu_to_utc(orbit.epoch, orbit.t0)
    if args.start is None:  # the orbit's own epoch: the directory is at fault, not an option
        _check_year(f"{args.run}: the orbit's epoch ({_epoch_field(args.run)}, the default --start)", start,
                    "the directory does not hold an orbit cistrack can predict: fit the observations again")
    _check_year("--start", start)
    stop = args.stop or start + timedelta(days=1)
    if args.stop is None:  # not given: say which time it is, and how to move it
        _check_year("the default --stop (one day after --start)", stop, "give an earlier --start or an explicit --stop",
                    shown=units.format_utc(stop)[:16] + "Z")
    _check_year("--stop", stop)
    if stop < start:
        raise ConfigError(f"--stop {units.format_utc(stop)[:19]}Z is before --start {units.format_utc(start)[:19]}Z")
    n = int(math.floor((stop - start).total_seconds() / (60.0 * args.step) + 1e-9)) + 1
    if n > MAX_TIMES:
        raise ConfigError(f"--step {args.step:g}: {n} times between --start and --stop; at most {MAX_TIMES} "
                          "(give a longer --step or a shorter span)")
    first = (start - orbit.epoch).total_seconds()
    times = units.seconds_to_tu(first + 60.0 * args.step * np.arange(n))
    leaps = units.grid_leap_seconds(orbit.epoch, start, timedelta(minutes=args.step), n)  # a grid of UTC labels
    return times if leaps is None else times + units.seconds_to_tu(leaps)


def _until_impact(times: np.ndarray, orbit) -> tuple[np.ndarray, str]:
    """The prediction ``times`` before the orbit hits a body, and a note saying how many later
    ones it leaves out (""); ConfigError naming --start when the orbit has hit it before them all."""
    from cistrack import units
    from cistrack.errors import ConfigError
    from cistrack.least_squares.events import times_until_impact

    times, back_note = _after_backward_impact(times, orbit)
    kept, hit = times_until_impact(orbit.dynamics, orbit.state, orbit.t0, times)
    if hit is None:
        return times, back_note
    when = units.format_utc(units.tu_to_utc(orbit.epoch, hit[0]))[:19] + "Z"
    before = times[times < hit[0]]
    if before.size == 0:
        raise ConfigError(f"--start: the orbit hits the {hit[1]} at {when} (see the fit's events), before the first "
                          "prediction time; give a --start before it")
    return before, "\n".join(filter(None, (back_note, f"note: the orbit hits the {hit[1]} at {when}; the "
                                              f"{times.size - before.size} prediction times after it are left out")))


def _after_burns(times: np.ndarray, run_dir, orbit) -> tuple[np.ndarray, str]:
    """The prediction ``times`` from 3 sigma after a fit's last burn on
    (:func:`cistrack.fitting.fit_export.after_burns_tu`: before it the object flew another orbit than
    the fitted one), and a note on those left out ("" when none); ConfigError naming --start when
    none is left. Unchanged for a run or a fit without burns."""
    from pathlib import Path

    from cistrack import units
    from cistrack.errors import ConfigError
    from cistrack.fitting.fit_export import after_burns_tu
    from cistrack.fitting.fit_record import read_fit_record

    if times.size == 0 or not (Path(run_dir) / "fit.json").is_file():
        return times, ""
    start = after_burns_tu(read_fit_record(run_dir))
    if start is None or times[0] >= start - 1e-12:
        return times, ""
    when = units.format_utc(units.tu_to_utc(orbit.epoch, start))[:19] + "Z"
    after = times[times >= start - 1e-12]
    if after.size == 0:
        raise ConfigError(f"--start/--stop: every prediction time is before {when}, 3 sigma after the fit's last burn "
                          "(fit.json maneuvers): before it the object flew another orbit than the fitted one; give "
                          "a --start after it")
    return after, (f"note: the fitted orbit is the one flown after the fit's last burn; the {times.size - after.size} "
                   f"prediction times before {when} (3 sigma after the burn) are left out")


def _after_backward_impact(times: np.ndarray, orbit) -> tuple[np.ndarray, str]:
    """The prediction ``times`` after the body the orbit, carried back from its epoch, meets first
    (a body it came from), and a note on those left out ("" when none); ConfigError naming --start
    when that leaves no time."""
    from cistrack import units
    from cistrack.errors import ConfigError
    from cistrack.least_squares.events import IMPACT_MARGIN_S, first_impact

    if times.size == 0 or times[0] >= orbit.t0:
        return times, ""
    hit = first_impact(orbit.dynamics, orbit.state, orbit.t0, float(times[0]))
    if hit is None:
        return times, ""
    when = units.format_utc(units.tu_to_utc(orbit.epoch, hit[0]))[:19] + "Z"
    after = times[times > hit[0] + units.seconds_to_tu(IMPACT_MARGIN_S)]
    if after.size == 0:
        raise ConfigError(f"--start: carried back from its epoch, the orbit meets the {hit[1]} at {when}, after every "
                          "prediction time: the fitted orbit cannot be carried back past it; give a --start after it")
    return after, (f"note: carried back from its epoch, the orbit meets the {hit[1]} at {when}; the "
                   f"{times.size - after.size} prediction times before it are left out")


LOST_DEG = 10.0
"""A 3-sigma ellipse longer than this (degrees) says the orbit no longer gives the sky position."""


WHOLE_SKY_DEG = 180.0
"""A 3-sigma semi-axis longer than this (degrees) covers the whole sky: the table says so in words."""


def _lost_note(sky) -> str:
    """A note on the times whose 3-sigma ellipse is longer than :data:`LOST_DEG` ("" if none), its
    largest semi-major axis in degrees, or "the whole sky" beyond :data:`WHOLE_SKY_DEG`."""
    major = 3.0 * sky.ellipse()[0] / 3600.0
    lost = np.flatnonzero(~(major <= LOST_DEG))
    if lost.size == 0:
        return ""
    most = np.nanmax(major)
    upto = (f"up to {most:.3g} degrees" if most <= WHOLE_SKY_DEG else
            f"up to the whole sky: semi-major axes beyond {WHOLE_SKY_DEG:g} degrees, the sky position unbounded")
    return (f"note: at {lost.size} of {major.size} times the 3-sigma ellipse is longer than {LOST_DEG:g} degrees "
            f"({upto}): the orbit does not give the sky position there")


def _axis_cell(arcsec: float) -> str:
    """A 3-sigma semi-axis (arcsec) for the 9-character table column; "all sky" beyond :data:`WHOLE_SKY_DEG`."""
    return f"{'all sky':>9}" if not arcsec <= WHOLE_SKY_DEG * 3600.0 else f"{arcsec:>9.3g}"


def _epoch_field(run_dir) -> str:
    """Where a results directory states its orbit's epoch: fit.json's epoch_utc, or a run's last estimate."""
    from cistrack.fitting.fit_export import is_fit_directory

    return "fit.json epoch_utc" if is_fit_directory(run_dir) else "the run's last estimate"


def _check_year(option: str, t, advice: str = "give a time within them", shown: str | None = None) -> None:
    """Refuse a prediction time ``t`` (UTC datetime) outside the years of the DE421 ephemeris the sky
    positions need, naming ``option`` (what gave the time), showing ``shown`` (default its date) and
    ending with ``advice``."""
    from cistrack.errors import ConfigError
    from cistrack.fitting.sky_ephemeris import FIRST_YEAR, LAST_YEAR

    if not FIRST_YEAR <= t.year <= LAST_YEAR:
        shown = shown or f"{t.year:04d}-{t.month:02d}-{t.day:02d}"
        raise ConfigError(f"{option} {shown}: sky predictions need the DE421 "
                          f"ephemeris, which covers the years {FIRST_YEAR} to {LAST_YEAR}; {advice}")


def _prefix(args) -> Path:
    """The --out PREFIX (default DIR/sky-CODE; a folder given as PREFIX gets FOLDER/sky-CODE; a
    PREFIX ending .csv or .png, one of the two files' names, is taken without it);
    ConfigError when its folder does not exist, when
    PREFIX.csv or PREFIX.png would replace one of the directory's own results (fit.json, ...), or
    when a given PREFIX's files exist without --overwrite."""
    from cistrack.errors import ConfigError
    from cistrack.results.earlier_run import check_export_path
    from cistrack.results.output_paths import check_printable_path

    if args.out:
        check_printable_path(args.out, "--out")
        _not_special(args.out)
    default = Path(args.run) / f"sky-{args.site}"
    prefix = Path(args.out) if args.out else default
    if args.out and (args.out.endswith(("/", os.sep)) or prefix.is_dir()):  # a folder: the files go inside it
        prefix = prefix / default.name
    elif args.out and prefix.suffix.lower() in (".csv", ".png"):  # the table's or the plot's name: its PREFIX
        prefix = prefix.with_suffix("")
    if args.out and not prefix.parent.is_dir():
        raise ConfigError(f"--out {args.out}: the folder {prefix.parent} does not exist; give a PREFIX in an "
                          "existing folder")
    for suffix in (".csv", ".png"):
        path = prefix.with_name(prefix.name + suffix)
        check_export_path(path, args.run, f"--out {args.out}:", by="the prediction",
                          instead=f"give another PREFIX (default {default})", overwrite=args.overwrite)
        if args.out and not args.overwrite and os.path.lexists(path):
            raise ConfigError(f"--out {args.out}: {path} already exists; give another PREFIX, or add --overwrite to "
                              "replace it")
    return prefix


def _not_special(out: str) -> None:
    """ConfigError when ``--out`` names something that is neither a file nor a folder (a device
    such as /dev/null, a pipe): PREFIX.csv and PREFIX.png would have been written beside it (into
    /dev), as export refuses such a path."""
    from cistrack.errors import ConfigError

    path = Path(out)
    if os.path.exists(path) and not (path.is_file() or path.is_dir()):
        raise ConfigError(f"--out {out}: names a device or pipe, not a file or folder; give a PREFIX for the two "
                          "files PREFIX.csv and PREFIX.png (or a folder for them)")


def table_lines(sky) -> list[str]:
    """The printed table of a :class:`~cistrack.fitting.sky_ephemeris.SkyEphemeris` (<= 120 columns)."""
    a, b, pa = sky.ellipse()
    lines = [_HEADER, _UNITS]
    for k, utc in enumerate(sky.utc):
        lines.append(f"{utc[:19]:<20}{sky.ra_deg[k]:>11.5f}{sky.dec_deg[k]:>10.5f}{sky.ra_rate_arcsec_min[k]:>9.2f}"
                     f"{sky.dec_rate_arcsec_min[k]:>9.2f}{sky.range_km[k]:>10.0f}{sky.elevation_deg[k]:>7.1f}"
                     f"{sky.solar_elongation_deg[k]:>7.1f}{sky.lunar_distance_deg[k]:>7.1f}{_axis_cell(3 * a[k])}"
                     f"{_axis_cell(3 * b[k])}{pa[k]:>6.0f}")
    return lines


def _site(code: str):
    """The site of ``--site``: an MPC observatory code, or LAT,LON,HEIGHT_M (WGS84: degrees North,
    degrees East, metres) for a site outside the list (one a fit's file declared, say)."""
    from cistrack.astro.sites import observatory
    from cistrack.errors import ConfigError, MeasurementError, shown

    if "," in code:  # coordinates (an MPC code has no comma): three of them, or told so
        if len(code.split(",")) != 3:
            raise ConfigError(f"--site {shown(code)}: LAT,LON,HEIGHT_M must be three numbers (degrees, degrees, "
                              f"metres), got {len(code.split(','))}")
        return _given_site(code)
    try:
        return observatory(code)
    except MeasurementError as exc:
        raise ConfigError(f"--site {shown(code)}: {str(exc).split('; give its coordinates')[0]}; give the site as "
                          "LAT,LON,HEIGHT_M instead (WGS84 degrees North, degrees East, metres)") from None


def _given_site(text: str):
    """The site LAT,LON,HEIGHT_M of ``--site``; ConfigError naming the option otherwise."""
    from cistrack.astro.sites import Site
    from cistrack.errors import ConfigError, MeasurementError, shown

    try:
        lat, lon, height = (float(p) for p in text.split(","))
    except ValueError:
        raise ConfigError(f"--site {shown(text)}: LAT,LON,HEIGHT_M must be three numbers (degrees, degrees, metres)") from None
    if not all(math.isfinite(v) for v in (lat, lon, height)):
        raise ConfigError(f"--site {shown(text)}: LAT,LON,HEIGHT_M must be finite numbers")
    try:
        return Site(lat, lon, height, name="given site")
    except MeasurementError as exc:
        raise ConfigError(f"--site {shown(text)}: {str(exc).split(': ', 1)[-1]}") from None


def _write(sky, prefix: Path, title: str, keep_other: bool = False) -> tuple[Path, Path]:
    """PREFIX.csv and PREFIX.png of ``sky``, both or neither: each is written to a temporary file
    beside it and the two are renamed into place once both are whole (a full disk leaves neither,
    and an earlier pair as it was); ConfigError naming the file that cannot be written, or, with
    ``keep_other``, naming the PREFIX.csv that holds a different prediction (nothing changed)."""
    import errno
    from contextlib import ExitStack

    from cistrack.errors import ConfigError
    from cistrack.fitting.sky_plot import sky_figure
    from cistrack.results.atomic_files import atomic_target

    csv_path, png = prefix.with_name(prefix.name + ".csv"), prefix.with_name(prefix.name + ".png")
    path = next((p for p in (csv_path, png) if p.is_dir()), csv_path)
    try:
        if path.is_dir():  # found before either is written: its rename would fail after the other's
            raise IsADirectoryError(errno.EISDIR, "a folder is there")
        with ExitStack() as both:  # both temporaries renamed on leaving, once both are written
            tmp_csv, tmp_png = (both.enter_context(atomic_target(p)) for p in (csv_path, png))
            sky.write_csv(tmp_csv)
            if keep_other and csv_path.is_file() and csv_path.read_bytes() != tmp_csv.read_bytes():
                raise ConfigError(f"{csv_path}: already holds a different prediction (another window, step or orbit); "
                                  "give --out PREFIX to write this one beside it, or add --overwrite to replace it")
            path = png
            sky_figure(sky, title).savefig(tmp_png, dpi=110, format="png")
    except OSError as exc:
        raise ConfigError(f"--out {prefix}: cannot write {path} ({exc.strerror or exc}); neither {csv_path.name} nor "
                          f"{png.name} was written; {_write_advice(exc.errno)}") from None
    return csv_path, png


def _write_advice(errno_: int | None) -> str:
    """What to do when PREFIX.csv or PREFIX.png cannot be written for the reason ``errno_``: a name
    too long is not a folder's room or permissions (probe J8 had been told "with room")."""
    import errno

    if errno_ == errno.ENAMETOOLONG:
        return "the name is too long for the file system: give a shorter PREFIX"
    if errno_ in (errno.ENOSPC, errno.EDQUOT):
        return "the disk or quota is full: give a PREFIX in a folder with room, or free some"
    return "give a PREFIX in a folder you can write to"


def _horizon_note(run_dir, times: np.ndarray, orbit) -> str:
    """Notes when the prediction ``times`` (TU) run past a fit's horizon or its covariance horizon,
    as an export of the same orbit says (:func:`cistrack.fitting.fit_export.prediction_warnings`);
    "" for a run, or within them."""
    from cistrack.errors import CistrackError
    from cistrack.fitting.fit_export import is_fit_directory, prediction_warnings
    from cistrack.fitting.fit_record import read_fit_record

    if times.size == 0 or not is_fit_directory(run_dir):
        return ""
    try:
        warned = prediction_warnings(read_fit_record(Path(run_dir)), times, 0, None, orbit.epoch)
    except (OSError, ValueError, CistrackError):  # the orbit was read from it already: no note is no harm
        return ""
    return "\n".join(f"note: {w}" for w in warned)


def _bent_line_note(run_dir, sky) -> str:
    """A note when the fit's line of variations bends away from its covariance: the ellipses were
    widened to hold it (``sky.line_reach_arcsec``), or, when the line could not be followed or read,
    a warning that the ellipses drawn from the covariance understate where to look."""
    from cistrack.errors import CistrackError
    from cistrack.fitting.fit_export import covariance_doubt, is_fit_directory, line_drawn_short
    from cistrack.fitting.fit_record import read_fit_record

    if not is_fit_directory(run_dir):
        return ""
    try:
        rec = read_fit_record(Path(run_dir))
        doubt = covariance_doubt(rec)
    except (OSError, ValueError, CistrackError):  # the orbit was read from it already: no note is no harm
        return ""
    if doubt is None:
        return ""
    if doubt == "bends" and sky.line_reach_arcsec is not None:
        return ("note: the fit's line of variations bends away from its covariance: the 3-sigma ellipses are widened "
                "to hold the orbits along it within 3 sigma (up to "
                f"{float(np.max(sky.line_reach_arcsec)):,.0f} arcsec from the predicted position; line_reach_arcsec)"
                + line_drawn_short(rec))
    return ("warning: the fit's line of variations " + ("bends away from" if doubt == "bends" else
            "could not check") + " its covariance: the 3-sigma ellipses understate where to look")


def cmd_predict(args) -> int:
    """``cistrack predict``: see the module docstring."""
    from cistrack.cli.text_width import for_stream
    from cistrack.fitting.sky_ephemeris import orbit_of_directory, sky_ephemeris_of
    from cistrack.errors import ConfigError
    from cistrack.interrupts import raise_pending
    from cistrack.results.dir_lock import check_still_as_read, results_stamp
    from cistrack.plugin.registry import default_registry

    site = _site(args.site)
    prefix = _prefix(args)
    reg = default_registry()
    stamp = results_stamp(args.run)
    orbit = orbit_of_directory(args.run, reg)
    times, burn_note = _after_burns(_times(args, orbit), args.run, orbit)
    times, impact_note = _until_impact(times, orbit)
    impact_note = "\n".join(filter(None, (burn_note, impact_note)))
    if not args.quiet:
        _eprint(f"predicting {orbit.name} ({orbit.source}) at {times.size} times from {args.site} "
                f"({site.name or 'site'}) ...")
    sky = _flagged(sky_ephemeris_of(orbit, times, site, reg), args.run)
    check_still_as_read(args.run, stamp, "prediction")  # a fit or run may have started (and ended) meanwhile
    raise_pending()  # a Ctrl-C lost while numba loaded: no files (probe J1)
    try:
        csv_path, png = _write(sky, prefix, f"{orbit.name} from {args.site} {site.name}: {orbit.source}",
                               keep_other=not (args.out or args.overwrite))
    except ConfigError:  # a fit or run starting in the folder sweeps away temporary files: say that, if so
        check_still_as_read(args.run, stamp, "prediction")
        raise
    if not args.quiet:
        print("\n".join(table_lines(sky)))
    linear = f"note: {int(np.sum(sky.linear))} times carry the linear covariance (a sigma-point orbit hit a body)" \
        if np.any(sky.linear) else ""
    notes = (linear, impact_note, _horizon_note(args.run, times, orbit), _lost_note(sky), _bent_line_note(args.run, sky),
             _hidden_burn_note(args.run))
    out = sys.stderr if args.quiet else sys.stdout  # --quiet drops the table, not what qualifies the files
    for note in filter(None, notes):
        for line in note.splitlines():
            print(for_stream(line, out), file=out)  # within 120 columns on a terminal
    if not args.quiet:
        print(f"wrote {csv_path}\nwrote {png}")
    return 0


def _hidden_burn_note(run_dir) -> str:
    """A note when a gap between the fit's observing sessions could hide a burn of any size
    (``burn_sensitivity``: more than :data:`~cistrack.fitting.fit_summary.HIDDEN_ANY_SIZE_MS`, or
    not determined): the predictions, like the fit, assume none there, and their ellipses hold no
    such burn ("" for a run, or when every gap would show a large one)."""
    from cistrack.errors import CistrackError
    from cistrack.fitting.fit_export import is_fit_directory
    from cistrack.fitting.fit_record import read_fit_record
    from cistrack.fitting.fit_summary import HIDDEN_ANY_SIZE_MS

    if not is_fit_directory(run_dir):
        return ""
    try:
        gaps = ((read_fit_record(Path(run_dir)).get("burn_sensitivity") or {}).get("gaps")) or []
    except (OSError, ValueError, CistrackError):  # the orbit was read from it already: no note is no harm
        return ""
    blind = [g for g in gaps if isinstance(g, dict) and not (isinstance(g.get("largest_hidden_ms"), (int, float))
                                                              and g["largest_hidden_ms"] <= HIDDEN_ANY_SIZE_MS)]
    if not blind:
        return ""
    last = blind[-1]
    more = f" (and {len(blind) - 1} earlier gaps)" if len(blind) > 1 else ""
    return (f"note: a burn of any size between {str(last.get('start_utc'))[:16]} and {str(last.get('end_utc'))[:16]}"
            f"{more} would not show in the fit's observations: these predictions assume none, and their ellipses "
            "do not allow for one (fit.json burn_sensitivity)")


def _flagged(sky, run_dir):
    """``sky`` with ``beyond_checked_horizon`` per time when ``run_dir`` is a fit's folder (its
    record's horizons: :func:`cistrack.fitting.fit_export.beyond_checked_horizon`), else as it is."""
    from dataclasses import replace

    from cistrack.errors import CistrackError
    from cistrack.fitting.fit_export import beyond_checked_horizon, is_fit_directory
    from cistrack.fitting.fit_record import read_fit_record

    if not is_fit_directory(run_dir):
        return sky
    try:
        record = read_fit_record(Path(run_dir))
    except (OSError, ValueError, CistrackError):  # the orbit was read from it already: no flag is no harm
        return sky
    return replace(sky, beyond_checked_horizon=beyond_checked_horizon(record, sky.t_tu))
