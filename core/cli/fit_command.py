"""``cistrack fit FILE [FILE ...] [--out DIR] [--set TABLE.KEY=VALUE ...] [--quiet]`` and the
export of a fit directory (``cistrack export FIT_DIR [--predict DAYS]``).

The work is :func:`cistrack.fitting.from_observations.fit_files`; this module parses the options and
prints, per object: the filter run's outcome, the least-squares RMS and chi-square, the assumed
and estimated noise, the rejected count, the position and velocity sigmas at the fit epoch, and
every warning. Exit status: 0 when every object's fit converged, 3 otherwise (a fit that failed
or did not converge, or observations that determine no orbit: one lone tracklet, whose summary
says so in words with the tracklet's motion and admissible region), 2 for an input error (before
anything runs).
"""
from __future__ import annotations

import argparse
import contextlib
import os
import sys

from cistrack.cli.text_width import for_stream, wrap_lines
from cistrack.errors import clipped
from cistrack.fitting.fit_summary import summary_lines
from cistrack.runs.progress import eprint as _eprint

__all__ = ["add_fit_parser", "add_predict_option", "is_fit_export", "cmd_fit", "cmd_export_fit", "summary_lines"]


@contextlib.contextmanager
def _file_size_limit(mb: float | None):
    """While open: the largest observation file read is ``mb`` MB (``--max-file-mb``; None: as it is)."""
    from cistrack.fitting.observation_input import MAX_FILE_MB_ENV

    before = os.environ.get(MAX_FILE_MB_ENV)
    if mb is not None:
        os.environ[MAX_FILE_MB_ENV] = repr(float(mb))
    try:
        yield
    finally:
        if before is None:
            os.environ.pop(MAX_FILE_MB_ENV, None)
        else:
            os.environ[MAX_FILE_MB_ENV] = before


def cmd_fit(args) -> int:
    """Fit the files of ``args`` and print the summaries; the process may then end without the
    interpreter's teardown (:mod:`cistrack.cli.process_exit`: about 1.7 s of CPU after a fit)."""
    from cistrack.cli.process_exit import allow_quick_exit
    from cistrack.fitting.from_observations import fit_files
    from cistrack.plugin.registry import default_registry
    from cistrack.runs.input_checks import check_environment

    check_environment()  # before the fit's directory is made
    quiet = bool(args.quiet)
    say = None if quiet else (lambda m: _eprint(wrap_lines(f"  {m}")))
    with _file_size_limit(getattr(args, "max_file_mb", None)):
        results = fit_files(args.files, out=args.out, settings=args.set, registry=default_registry(), log=say,
                            progress=not quiet, overwrite=args.overwrite)
    if not quiet:
        for one in results:
            for note in one.notes:
                print(wrap_lines(f"  weights: {note}"))
            for line in summary_lines(one):
                print(line)
            if one.ok:
                print(f"  next: cistrack export {one.directory} --format oem [--predict DAYS]")
    else:
        for one in results:
            if not one.ok:
                _eprint(f"cistrack: error: fit {clipped(one.designation)} failed: " + (one.failure or "; ".join(
                    one.result.messages[:1] if one.result else [])))
    allow_quick_exit()  # every results file written and closed; no recorder to flush at exit
    return 0 if all(one.ok for one in results) else 3


def _print_wrapped(line: str) -> None:
    """Print one line of the export's log, within 120 columns when stdout is a terminal."""
    print(for_stream(line, sys.stdout))


def cmd_export_fit(args) -> int:
    """``cistrack export`` on a fit directory: the fitted orbit (see :mod:`cistrack.fitting.fit_export`)."""
    from cistrack.fitting.fit_export import export_fit
    from cistrack.results.export_file import CLI_EXPORT_WORDS

    from cistrack.errors import ConfigError

    params = {} if getattr(args, "step", None) is None else {"step": args.step}
    if getattr(args, "covariance", None) is not None:  # else export_fit's default
        if args.format == "opm":
            raise ConfigError(f"--covariance {args.covariance}: --format opm writes the state and covariance at the "
                              "fit epoch, which are not propagated, and takes no --covariance; --covariance says how "
                              "--format oem carries the covariance over its grid")
        params["covariance"] = args.covariance
    quiet = getattr(args, "quiet", False)
    out = export_fit(args.run, args.format, args.out, overwrite=args.overwrite, force=getattr(args, "force", False),
                     predict_days=getattr(args, "predict", None), words=CLI_EXPORT_WORDS,
                     log=None if quiet else _print_wrapped, **params)
    if not quiet:
        print(f"wrote {out}")
    return 0


def _nonnegative_days(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of days") from None
    if not (v >= 0 and v == v and v != float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r}: give a number of days >= 0")
    return v


def _positive_mb(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of MB") from None
    if not (v > 0 and v != float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r}: give a finite number of MB > 0")
    return v


def add_fit_parser(sub, export_parser=None) -> None:
    """Add ``cistrack fit`` to the sub-command parsers ``sub``, and ``--predict`` to ``export_parser``."""
    if export_parser is not None:
        add_predict_option(export_parser)
    f = sub.add_parser("fit", help="fit an orbit to observation files (IOD, filter, then least squares)",
                       description="Observation files in (ADES PSV/XML, MPC 80-column, CCSDS TDM, cistrack CSV; "
                                   "several files and sites are merged, one fit per object), a least-squares "
                                   "orbit with covariance and post-fit residuals out. Defaults: "
                                   "cistrack/scenarios/fit-defaults.toml; docs/real-data.md.")
    from cistrack.cli.option_types import path_text

    f.add_argument("files", nargs="+", metavar="FILE", help="observation files")
    f.add_argument("--out", type=path_text("--out"), default=None, help="results directory (default runs/fit-<designation>; with several "
                   "objects, one directory per object inside it); new, empty or an earlier results directory")
    f.add_argument("--set", action="append", metavar="TABLE.KEY=VALUE",
                   help="change a default (repeatable): a scenario key (filter.n_particles=8000), a reader "
                        "parameter (measurements.reader.sigma_arcsec=0.5) or a fit setting (fit.epoch=middle, "
                        "fit.reject_sigma=4)")
    f.add_argument("--quiet", action="store_true", help="print nothing but warnings and errors (the exit status tells the outcome)")
    f.add_argument("--overwrite", action="store_true",
                   help="replace a cistrack run's results or another object's fit in --out (an earlier fit "
                        "of the same object is always redone)")
    f.add_argument("--max-file-mb", type=_positive_mb, default=None, metavar="MB",
                   help="largest observation file read, MB (default 50, or the environment variable "
                        "CISTRACK_MAX_FILE_MB); a larger file is refused before it is read")
    f.set_defaults(func=cmd_fit)


def add_predict_option(export_parser) -> None:
    """``--predict DAYS`` and ``--covariance`` on ``cistrack export`` (fit directories)."""
    export_parser.add_argument("--predict", type=_nonnegative_days, default=None, metavar="DAYS",
                               help="fit directories: also write the orbit this many days beyond the last "
                                    "observation, with its propagated covariance")
    export_parser.add_argument("--covariance", choices=("unscented", "linear"), default=None,
                               help="fit directories: how the fit covariance is carried over the grid: "
                                    "unscented (default; sigma-point orbits through the dynamics, right at a "
                                    "close perilune) or linear (state transition matrices)")


def is_fit_export(args) -> bool:
    """Whether ``cistrack export`` was given a fit directory (or --predict, which needs one)."""
    from cistrack.fitting.fit_export import is_fit_directory

    if is_fit_directory(args.run):
        return True
    if getattr(args, "predict", None) is not None:
        from cistrack.errors import ConfigError
        raise ConfigError(f"--predict: {args.run} is not a fit directory (no fit.json); --predict extends a "
                          f"fitted orbit: run 'cistrack fit FILE --out DIR' first")
    if getattr(args, "covariance", None) is not None:
        from cistrack.errors import ConfigError
        raise ConfigError(f"--covariance: {args.run} is not a fit directory (no fit.json); a run's OEM "
                          "writes the filter's own covariance at each step")
    return False

