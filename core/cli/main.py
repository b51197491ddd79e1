"""The ``cistrack`` command.

    cistrack run [SCENARIO] [--seed N] [--out DIR] [--set K=V ...] [--overwrite] [--rerun FILE.rrd] [--rerun-serve [--rerun-port N]]
    cistrack plugins [NAME] [--check NAME] [--kind KIND]
    cistrack view FILE.rrd [--port 9090]
    cistrack scenarios
    cistrack init [NAME]
    cistrack study run STUDY [--workers N] [--dask ADDRESS|local] [--out DIR] [--first-seed N] [--n-seeds N]
    cistrack study report STUDY [--out DIR] [--first-seed N] [--n-seeds N]
    cistrack export RUN_DIR [--format oem|opm] [--out FILE [--overwrite]] [--step N]
    cistrack fit FILE [FILE ...] [--out DIR] [--set TABLE.KEY=VALUE ...] [--quiet]
    cistrack predict DIR --site CODE [--start UTC] [--stop UTC] [--step MINUTES] [--out PREFIX]
"""
from __future__ import annotations

import argparse
import os
import signal
import sys
import warnings
from pathlib import Path

from cistrack.errors import CistrackError, ConfigError
from cistrack.cli.study import add_study_parser
from cistrack.cli.init_scenario import add_init_parser
from cistrack.cli.output_streams import NamedOutput
from cistrack.cli.fit_command import add_fit_parser, cmd_export_fit, is_fit_export
from cistrack.cli.predict_command import add_predict_parser
from cistrack.scenario.limits import check_seed
from cistrack.results.output_paths import check_output_dir
from cistrack.cli.process_exit import allow_quick_exit, exit_process
from cistrack.cli.signals import install_signal_handlers, interrupts_prevail
from cistrack.interrupts import clear as clear_interrupts
from cistrack.cli.plot_config import set_plot_config_dir
from cistrack.cli.suggesting_parser import SuggestingParser, closest_choice
from cistrack.cli.text_width import cap_help_width, fit_row, wrap_labelled, wrap_lines, wrap_row
from cistrack.cli.text_width import for_stream as _for_stream
from cistrack.runs.progress import eprint as _eprint

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

DEFAULT_SCENARIO = "example-1"


def _fmt(v, nd=3) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.{nd}g}" if abs(v) < 1e4 else f"{v:.4g}"
    return str(v)


def cmd_run(args) -> int:
    from cistrack.plugin.registry import default_registry
    from cistrack.results.dir_lock import run_lock
    from cistrack.results.earlier_run import check_recording_path, check_replacing, clear_replaced_fit
    from cistrack.runs.run_id import scenario_run_id
    from cistrack.runs.input_checks import check_run_inputs
    from cistrack.scenario.loading import load_scenario
    from cistrack.scenario.settings import apply_settings, settings_suffix

    if args.rerun_port is not None and not args.rerun_serve:
        raise ConfigError("--rerun-port: the port of --rerun-serve only; give --rerun-serve too")
    reg = default_registry()
    scen = apply_settings(load_scenario(args.scenario or DEFAULT_SCENARIO, reg), args.set, reg)
    seed = scen.seed if args.seed is None else check_seed(args.seed, "--seed")
    # the default directory of a run with --set items names them, so it never replaces the plain run's
    out = Path(args.out) if args.out else Path("runs") / (scenario_run_id(scen, seed) + settings_suffix(args.set))
    where = "--out" if args.out else "the results directory"
    check_run_inputs(scen, args.rows_per_part)  # before the results directory is made
    if args.rerun:
        check_recording_path(args.rerun, out)
    made = not os.path.lexists(out)  # (False, not an error, where the parent may not be searched)
    check_output_dir(out, where)
    try:
        with run_lock(out, where):  # one run at a time in a results directory
            replaced = check_replacing(out, scen, seed, where, overwrite=args.overwrite)
            if replaced:
                clear_replaced_fit(out)
            res, recorder = _run_into(args, reg, scen, seed, out, replaced)
    except CistrackError:  # refused before the run (e.g. its --rerun file): leave no directory it made
        if made:
            _remove_if_only_lock(out)
        raise
    out_ = (lambda *a, **k: None) if args.quiet else print
    if recorder is not None and (args.rerun_serve or args.rerun_spawn):
        _serve_until_interrupted(recorder, out_)
    if recorder is None:
        allow_quick_exit()  # results written and closed; no recorder to flush at exit
    return 0 if res.summary.status == "finished" else 3


def _remove_if_only_lock(out: Path) -> None:
    """Remove the directory ``out`` when it holds nothing but the run's lock file."""
    from cistrack.results.output_paths import RUN_LOCK

    try:
        if [p.name for p in out.iterdir()] == [RUN_LOCK]:
            (out / RUN_LOCK).unlink()
            out.rmdir()
    except OSError:
        pass


def _run_into(args, reg, scen, seed: int, out: Path, replaced: str):
    """Run ``scen`` with ``seed`` into ``out`` (its lock held) and print the outcome; returns the
    run's result and its rerun recorder (None without one)."""
    from cistrack.runs.pipeline import run_scenario

    say = (lambda *a, **k: None) if args.quiet else _eprint
    out_ = (lambda *a, **k: None) if args.quiet else print
    recorder = _rerun_recorder(args, reg, scen)
    observers = [recorder] if recorder is not None else []
    say(f"cistrack: scenario '{scen.name}' ({scen.source}), seed {seed}")
    say(f"  filter {scen.components['filter'].name}, IOD {scen.components['iod'].name}, "
        f"{scen.duration_days:g} days; results -> {out}")
    if replaced:
        say(f"  --overwrite: replacing the results in {out} ({replaced})")
    res = run_scenario(scen, seed=seed, registry=reg, observers=observers, output_dir=out, progress=not args.quiet,
                       log=(None if args.quiet else lambda m: _eprint(f"  {m}")), rows_per_part=args.rows_per_part,
                       residual_figure=True)
    _print_outcome(res.summary, out, args.quiet, out_)
    if args.rerun and res.summary.status == "finished":
        out_(f"  rerun recording: {args.rerun}  (open with: cistrack view {args.rerun})")
    elif args.rerun and os.path.exists(args.rerun):
        out_(f"  rerun recording: {args.rerun} is incomplete (the run {res.summary.status}); a run with "
             "--overwrite replaces it")
    return res, recorder


def _rerun_recorder(args, reg, scen):
    """The rerun recorder the options ask for (a file, a server, a viewer), or None."""
    if not (args.rerun or args.rerun_serve or args.rerun_spawn):
        return None
    port_ = {} if args.rerun_port is None else {"serve_port": args.rerun_port}
    return reg.create("recorder", "rerun", path=args.rerun, serve=args.rerun_serve,
                      spawn=args.rerun_spawn, max_points=args.max_points,
                      frame=scen.recording_frame, overwrite=args.overwrite, **port_)


def _print_outcome(s, out: Path, quiet: bool, out_) -> None:
    """The run's status, verdict, counts, final sigmas and errors, and its result files."""
    from cistrack.evaluation.run_summary import count_lines, final_lines, maneuver_lines
    from cistrack.evaluation.verdicts import verdict_lines
    from cistrack.results.store import results_line

    def say(line: str) -> None:  # within 120 columns, continuations under the text after a label
        for part in wrap_labelled(line):
            out_(part)

    say(f"run {s.run_id}: {s.status}" + (f" ({s.failure})" if s.failure else ""))
    if quiet and s.status != "finished":
        _eprint(f"cistrack: error: run {s.run_id}: {s.status}" + (f" ({s.failure})" if s.failure else ""))
    ended = s.status in ("finished", "filter-failed")  # a failed run was not judged at its end
    for line in (verdict_lines(s, out, _fmt) if ended else _unfinished_verdict_lines(s, out)):
        say(line)
    for line in count_lines(s) + maneuver_lines(s):
        say(line)
    for line in final_lines(s.final, _fmt):  # velocities in m/s throughout
        say(line)
    say(results_line(out))  # only files that exist (a full disk may have kept some from being written)


def _unfinished_verdict_lines(s, out: Path) -> list[str]:
    """The stored verdict of a run that did not finish (docs/running.md): ``none``, or ``lost`` (with
    custody) when custody was lost before it stopped."""
    from cistrack.evaluation.verdicts import verdict_lines

    if s.verdict.kind != "lost":  # judged only at the end: what it held before it stopped is no verdict
        return ["  verdict: none (the run did not finish; see its status above)"]
    head, *rest = verdict_lines(s, out, _fmt)
    return [f"{head} (before the run stopped; see its status above)", *rest]


def _serve_until_interrupted(recorder, out_) -> None:
    """Keep the rerun server or viewer up until Ctrl-C, then close the recorder."""
    uri = getattr(recorder, "server_uri", None)
    if uri:
        out_(f"  rerun server (127.0.0.1 only): connect a viewer with: rerun {uri}")
    out_("  the viewer stays available until you press Ctrl-C", flush=True)
    _wait_for_ctrl_c(recorder.close)


def _wait_for_ctrl_c(close) -> None:
    """Sleep until Ctrl-C, then call ``close()`` (also when anything else ends the wait)."""
    import time

    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        clear_interrupts()  # handled: the command ends as asked, not as interrupted
    finally:
        close()


def cmd_plugins(args) -> int:
    from cistrack.interfaces import KINDS
    from cistrack.plugin.registry import default_registry

    reg = default_registry()
    if args.param and not args.check:
        raise ConfigError("--param: sets a parameter for --check NAME only (to see the parameters: cistrack plugins NAME)")
    if args.check:
        return _check_plugin(reg, args)
    kinds = [args.kind] if args.kind else list(KINDS)
    if args.name:
        return _describe(reg, args.name, kinds)
    for kind in kinds:
        entries = reg.entries(kind)
        print(f"{kind} ({len(entries)})")
        for e in entries:  # one line per component: a long summary is cut ('cistrack plugins NAME' has it whole)
            print(fit_row(f"  {e.name:<30} {e.distribution} {e.version:<8} ", e.summary))
    if reg.failures:
        print("plugins that failed to load:")
        for f in reg.failures:
            print("\n".join(wrap_row("  ", str(f))))
    return 0


SLOW_CHECK_S = 60.0
"""A conformance check that takes longer than this many seconds is warned about: docs/plugins.md
says the whole suite runs in seconds, and a plugin's tests run it."""
SHOWN_CHECK_S = 1.0
"""A check that takes longer than this shows its time."""


def _check_plugin(reg, args) -> int:
    """``cistrack plugins --check NAME [--param KEY=VALUE ...]``: each check's line as soon as it ends."""
    from cistrack.testing import check_registered

    import tempfile

    params = _check_params(args.param or [])
    _check_param_names(reg, args.check, args.kind, params)
    advice = (f"if it needs settings, give them with --param KEY=VALUE, VALUE in TOML syntax, e.g. cistrack plugins "
              f"--check {args.check} --param path=\"out.rrd\"; cistrack plugins {args.check} lists its parameters")
    with tempfile.TemporaryDirectory(prefix="cistrack-check-") as scratch:
        params = params or _recorder_sink(reg, args.check, args.kind, scratch)
        results = check_registered(args.check, kind=args.kind, registry=reg, params=params or None,
                                   on_result=_print_check, advice=advice)
    failed = sum(not r.passed for r in results)
    print(f"{len(results) - failed} passed, {failed} failed")
    return 1 if failed else 0


def _recorder_sink(reg, name: str, kind: str | None, scratch: str) -> dict:
    """For a recorder that takes a ``path`` (checked without ``--param``): ``{"path": a file in the
    temporary folder scratch}``, said on the terminal (a recorder has nothing to record to without
    one, as a test gives pytest's tmp_path); {} otherwise."""
    from cistrack.interfaces.component import param_specs

    if kind not in (None, "recorder") or ("recorder", name) not in reg:
        return {}
    factory = reg.get("recorder", name).factory
    if not isinstance(factory, type) or "path" not in param_specs(factory):
        return {}
    path = os.path.join(scratch, f"check-{name}.rrd")
    print(wrap_lines(f"checking recorder {name!r} with path = {path!r}, a temporary file removed afterwards "
                     "(--param path=... to choose another)"))
    return {"path": path}


def _check_params(items: list[str]) -> dict:
    """``--param KEY=VALUE`` items as a dict (VALUE in TOML syntax; a bare word is a string)."""
    params = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ConfigError(f"--param {item!r}: expected KEY=VALUE (VALUE in TOML syntax, e.g. path=\"out.rrd\")")
        try:
            params[key.strip()] = tomllib.loads(f"v = {value}")["v"]
        except tomllib.TOMLDecodeError:
            params[key.strip()] = value  # a bare word: take it as a string
    return params


def _print_check(result) -> None:
    """One check's line (wrapped within the width; its time when it took over a second), flushed at
    once so that a slow suite shows its progress, and a warning on stderr for a check that took
    longer than :data:`SLOW_CHECK_S`."""
    took = f" ({result.seconds:.1f} s)" if result.seconds > SHOWN_CHECK_S else ""
    text = result.name + took + (f": {result.message}" if result.message and not result.passed else "")
    print("\n".join(wrap_row(f"  {'PASS' if result.passed else 'FAIL'}  ", text)), flush=True)
    if result.seconds > SLOW_CHECK_S:
        _eprint("\n".join(wrap_row("cistrack: warning: ", f"check '{result.name}' took {result.seconds:.0f} s; the "
                                    f"whole conformance suite is meant to run in seconds (docs/plugins.md), and a "
                                    f"plugin's tests run it: make the component faster on the checks' small "
                                    f"inputs")))


def _check_param_names(reg, name: str, kind: str | None, params: dict) -> None:
    """ConfigError naming a ``--param`` key that the component ``name`` does not take, with the ones it takes."""
    from cistrack.interfaces import KINDS
    from cistrack.interfaces.component import param_specs

    found = [reg.get(k, name) for k in ([kind] if kind else KINDS) if (k, name) in reg]
    takes = set().union(*(param_specs(e.factory) for e in found if isinstance(e.factory, type))) if found else set()
    unknown = sorted(set(params) - takes)
    if found and unknown:
        raise ConfigError(f"--param {unknown[0]}: {name!r} takes no parameter {unknown[0]!r}; it takes "
                          f"{', '.join(sorted(takes)) or 'none'}")


def _describe(reg, name: str, kinds: list[str]) -> int:
    """``cistrack plugins NAME``: every parameter of each component called NAME."""
    from cistrack.interfaces import KINDS
    from cistrack.plugin.param_docs import describe_component

    found = [reg.get(kind, name) for kind in kinds if (kind, name) in reg]
    if not found and name in KINDS:
        raise ConfigError(f"{name!r} is a kind of component, not a component: cistrack plugins --kind {name} lists them")
    if not found:
        every = sorted({n for kind in kinds for n in reg.names(kind)})
        msg = f"no component named {name!r}"
        close = closest_choice(name, every)
        msg += f"; did you mean {close!r}?" if close else f"; components: {', '.join(every)}"
        raise ConfigError(msg + " (cistrack plugins lists them all)")
    print(wrap_lines("\n\n".join(describe_component(e.kind, e.name, e.factory, e.source) for e in found)))
    return 0


def _check_step_option(format: str, step: int | None) -> None:
    """Refuse a ``--step`` below -1 (-1: the last step), and any ``--step`` for an exporter that writes
    every step (it has no ``step`` parameter)."""
    from cistrack.interfaces.component import param_specs
    from cistrack.plugin.registry import default_registry

    if step is not None and step < -1:
        raise ConfigError(f"--step {step}: give a step number of the run, 0 or more, or -1 for the last step "
                          "(the default)")
    reg = default_registry()
    if step is None or format not in reg.names("exporter"):
        return  # an unknown --format is refused by name where the exporter is made
    factory = reg.get("exporter", format).factory
    if not isinstance(factory, type) or "step" not in param_specs(factory):
        raise ConfigError(f"--step {step}: --format {format} writes every step and takes no --step; "
                          "--step selects the one step of a single-state format such as --format opm")


def _exporter_name(format: str) -> str:
    """The registered exporter ``--format`` names in any case (OEM: oem); as given when several
    match. An unknown one is refused here, naming it (before ``--out`` is judged by the format)."""
    from cistrack.plugin.registry import default_registry

    reg = default_registry()
    names = reg.names("exporter")
    same = [n for n in names if n.lower() == format.lower()]
    name = same[0] if format not in names and len(same) == 1 else format
    reg.get("exporter", name)  # UnknownComponentError: "unknown exporter ''; ... Did you mean 'oem'?"
    return name


def cmd_export(args) -> int:
    """``cistrack export``: a run's orbit estimate, or a fit's fitted orbit, as CCSDS OEM or OPM."""
    from cistrack.runs.export import export_refusal, export_run
    from cistrack.results.export_file import CLI_EXPORT_WORDS

    from cistrack.results.earlier_run import check_export_path

    args.format = _exporter_name(args.format)
    _check_step_option(args.format, args.step)
    if args.out:
        check_export_path(args.out, args.run, overwrite=args.overwrite)
    _check_out_suffix(args.format, args.out)
    if is_fit_export(args):  # a 'cistrack fit' directory (--predict DAYS): the fitted orbit
        return cmd_export_fit(args)
    from cistrack.runs.progress import stage_log

    params = {} if args.step is None else {"step": args.step}
    out = export_run(args.run, args.format, args.out, overwrite=args.overwrite, force=args.force,
                     log=None if args.quiet else stage_log("cistrack: "), words=CLI_EXPORT_WORDS, **params)
    if args.force:
        why = export_refusal(args.run)
        if why:
            _eprint(f"cistrack: warning: exported with --force: {why} (the file says so in a COMMENT)")
    if not args.quiet:
        print(f"wrote {out}")
    return 0


_FORMAT_SUFFIXES = {"oem": ".oem", "opm": ".opm"}
"""The file name endings of the CCSDS message formats cistrack writes."""

_OTHER_SUFFIXES = {".psv": "ADES observations", ".csv": "a table", ".parquet": "a results table",
                   ".json": "a manifest or fit result", ".toml": "a scenario", ".rrd": "a rerun recording",
                   ".svg": "a figure", ".png": "a figure", ".tdm": "a CCSDS tracking data message"}
"""Endings of files of other kinds, refused as an export's ``--out`` (an orbit message under such a
name would be taken for what the name says)."""


def _check_out_suffix(format: str, out: str | None) -> None:
    """Refuse an ``--out`` named for the other CCSDS message than ``--format`` writes (x.oem for OPM),
    or for another kind of file (:data:`_OTHER_SUFFIXES`)."""
    if out is None:
        return
    ending = Path(out).suffix.lower()
    if ending in _OTHER_SUFFIXES:
        raise ConfigError(f"--out {out}: a {ending} name is for {_OTHER_SUFFIXES[ending]}, not a CCSDS "
                          f"{format.upper()}; name it {Path(out).with_suffix(_FORMAT_SUFFIXES.get(format, '.txt'))}")
    named = next((f for f, suffix in _FORMAT_SUFFIXES.items() if suffix == ending), None)
    if named is not None and named != format:
        raise ConfigError(f"--out {out}: named for {named.upper()}, but --format {format} writes "
                          f"{format.upper()}; name it {Path(out).with_suffix(_FORMAT_SUFFIXES.get(format, '.txt'))} or "
                          f"give --format {named}")


RRD_MAGIC = b"RRF"
"""How a rerun recording file starts (then the format's version digit)."""


def _check_recording(path: str) -> None:
    """Refuse a file that is not a rerun recording (empty, or another file renamed .rrd) before a
    viewer is started for it; what is not a regular file is left to the recorder's own message."""
    if not os.path.isfile(path):
        return
    try:
        with open(path, "rb") as fh:
            head = fh.read(len(RRD_MAGIC))
    except OSError as exc:
        raise CistrackError(f"{path}: cannot read it ({exc.strerror or exc})") from None
    if head != RRD_MAGIC:
        raise CistrackError(f"{path}: not a rerun recording (" + ("an empty file" if not head else
                            "it does not start as a .rrd file does") + "); give a file written by "
                            "'cistrack run --rerun FILE.rrd'")


def cmd_view(args) -> int:
    """``cistrack view FILE.rrd``: host the web viewer with the recording loaded, print the URL."""
    from cistrack.plugin.registry import default_registry

    _check_recording(args.recording)
    # the recorder that wrote the file serves it (core never imports a plugin)
    recorder = default_registry().get("recorder", "rerun").factory
    served = recorder.serve_file(args.recording, web_port=args.port, option="--port")
    print(f"open in a browser (127.0.0.1 only): {served.page_url or served.url}", flush=True)
    if getattr(served, "software_url", None):
        print("  (a browser without a GPU, rendering in software, gets a faster playback speed: the run still "
              "plays in about a minute)", flush=True)
    print("serving until you press Ctrl-C", flush=True)
    _wait_for_ctrl_c(served.close)
    return 0


def cmd_scenarios(args) -> int:
    from cistrack.scenario.loading import builtin_scenarios
    from cistrack.studies.study import builtin_studies

    print("scenarios (cistrack run NAME):")
    for name, desc in builtin_scenarios().items():
        print("\n".join(wrap_row(f"  {name:<28} ", desc)))
    print("studies (cistrack study run NAME):")
    for name, desc in builtin_studies().items():
        print("\n".join(wrap_row(f"  {name:<28} ", desc)))
    return 0


def build_parser() -> argparse.ArgumentParser:
    from cistrack import __version__
    from cistrack.cli.option_types import count, path_text, port

    p = SuggestingParser(prog="cistrack", description="Probabilistic IOD and OD in cislunar space.")
    p.add_argument("--version", action="version", version=f"cistrack {__version__}")
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="run a scenario (default: the built-in 'example-1')")
    r.add_argument("scenario", nargs="?", help="scenario TOML file or built-in scenario name")
    r.add_argument("--seed", type=int, default=None, help="override the scenario's seed")
    r.add_argument("--out", type=path_text("--out"), default=None, help="results directory (default runs/<scenario>__<filter>__<iod>__seed<N>, with __set-<hash> "
                   "after it for --set items; must be new, empty or an earlier results directory; one "
                   "holding another scenario's, settings' or seed's results is refused without --overwrite)")
    r.add_argument("--rerun", metavar="FILE.rrd", default=None, type=path_text("--rerun"), help="write a rerun recording")
    r.add_argument("--overwrite", action="store_true", help="replace an existing --rerun file, and the results of another scenario, "
                   "other settings or another seed in --out (both refused otherwise)")
    r.add_argument("--rerun-serve", action="store_true", help="serve the recording to a viewer on 127.0.0.1")
    r.add_argument("--rerun-port", type=port(9876), default=None, metavar="PORT",
                   help="the 127.0.0.1 port --rerun-serve serves on (default 9876)")
    r.add_argument("--rerun-spawn", action="store_true", help="start the native rerun viewer")
    r.add_argument("--max-points", type=count(1), default=2000, help="particles logged per step in rerun (each mixture component kept)")
    r.add_argument("--rows-per-part", type=int, default=None, metavar="N", help="steps per results part file (default 1000, or 10 s)")
    r.add_argument("--set", action="append", metavar="TABLE.KEY=VALUE",
                   help="override a scenario value, validated like the file (repeatable), "
                        "e.g. --set filter.n_particles=20000 --set duration_days=2")
    r.add_argument("--quiet", action="store_true", help="print nothing but warnings and errors (the exit status tells the outcome)")
    r.set_defaults(func=cmd_run)
    pl = sub.add_parser("plugins", help="list registered components, describe one, or check one")
    pl.add_argument("name", nargs="?", default=None,
                    help="describe this component: every parameter with type, default, unit and meaning")
    pl.add_argument("--check", metavar="NAME", default=None, help="run the conformance suite on a component")
    pl.add_argument("--kind", default=None, help="restrict to one kind")
    pl.add_argument("--param", action="append", metavar="KEY=VALUE",
                    help="with --check: build the component with this parameter (repeatable)")
    pl.set_defaults(func=cmd_plugins)
    ex = sub.add_parser("export", help="write a run's orbit estimate as CCSDS OEM or OPM")
    ex.add_argument("run", help="a run directory (written by 'cistrack run --out DIR')")
    ex.add_argument("--format", default="oem", help="a registered exporter: oem (default) or opm (either case)")
    ex.add_argument("--out", type=path_text("--out"), default=None, help="file to write (default RUN/estimate.<format>)")
    ex.add_argument("--step", type=int, default=None, help="opm: the step number to write, from 0; -1 or none: the "
                    "last step")
    ex.add_argument("--overwrite", action="store_true", help="replace an existing --out file, or a different export "
                    "(other --step, --predict) in the default RUN/estimate.<format>, or write into the folder of another "
                    "run, fit or study (refused otherwise)")
    ex.add_argument("--quiet", action="store_true", help="print nothing but warnings and errors")
    ex.add_argument("--force", action="store_true", help="export a run that did not finish, was killed or diverged "
                    "(refused otherwise); the file then says so in a COMMENT")
    ex.set_defaults(func=cmd_export)
    v = sub.add_parser("view", help="open a rerun recording in the web viewer (prints a URL that loads it)")
    v.add_argument("recording", help="a .rrd file written by cistrack run --rerun")
    v.add_argument("--port", type=port(9090), default=9090,
                   help="web viewer port on 127.0.0.1, 1 to 65535, not in use (default 9090)")
    v.set_defaults(func=cmd_view)
    sc = sub.add_parser("scenarios", help="list the built-in scenarios and studies")
    sc.set_defaults(func=cmd_scenarios)
    add_study_parser(sub)
    add_init_parser(sub)
    add_fit_parser(sub, export_parser=ex)
    add_predict_parser(sub)
    return cap_help_width(p)  # every help within MAX_WIDTH columns, whatever the terminal's width


def _configure_logging(quiet: bool) -> None:
    """Library progress notes (logger ``cistrack``, e.g. one-time kernel compilation) go to stderr;
    ``--quiet`` keeps only warnings and errors."""
    import logging

    class _Stderr(logging.Handler):  # looks sys.stderr up at each message (tests swap it)
        def emit(self, record: logging.LogRecord) -> None:  # within 120 columns on a terminal, like errors
            _eprint(_for_stream(f"cistrack: {record.getMessage()}", sys.stderr))

    logger = logging.getLogger("cistrack")
    if not any(type(h).__name__ == "_Stderr" for h in logger.handlers):
        logger.addHandler(_Stderr())
    logger.setLevel(logging.WARNING if quiet else logging.INFO)


def main(argv: list[str] | None = None) -> int:
    set_plot_config_dir()  # before any plot is drawn: matplotlib reads it on import
    try:  # building the parser imports the commands' modules: a Ctrl-C may come while it does
        args = build_parser().parse_args(argv)
        _configure_logging(bool(getattr(args, "quiet", False)))
    except KeyboardInterrupt:
        _eprint("cistrack: interrupted (SIGINT) while starting; nothing was done")
        return 130
    previous = install_signal_handlers()
    try:
        with interrupts_prevail():  # an ImportError a Ctrl-C caused, or a Ctrl-C lost, ends as the Ctrl-C
            return int(args.func(args) or 0)
    except CistrackError as exc:
        _eprint(error_text(exc, sys.stderr))
        return 2
    except KeyboardInterrupt as exc:
        why = str(exc) or "SIGINT"
        _eprint(f"cistrack: interrupted ({why}){_interrupted_advice(args)}")
        sig = getattr(signal, why, None) if why.startswith("SIG") else None
        return 128 + int(sig) if sig is not None else 130
    except BrokenPipeError:  # the reader closed our stdout (e.g. `cistrack scenarios | head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:  # a path the system refuses where no check caught it first: said, not a traceback
        _eprint(os_error_text(exc))
        return 2
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def os_error_text(exc: OSError) -> str:
    """``cistrack: error: PATH: WHY`` for an OSError no check caught first; when the current folder
    was deleted (a path without a name, or a relative one, fails there), that, with the folder's path:
    ``cistrack fit`` there had said only "No such file or directory" (probe J7)."""
    name = str(exc.filename) if exc.filename else ""
    gone = _deleted_current_folder() if not os.path.isabs(name) else None
    if gone is not None:
        tried = f" ({name})" if name else ""
        return (f"cistrack: error: the current folder {gone} no longer exists (it was deleted), so the relative "
                f"paths{tried} there cannot be used (the default --out among them): cd to an existing folder, or "
                f"give absolute paths ({exc.strerror or exc})")
    return f"cistrack: error: {name + ': ' if name else ''}{exc.strerror or exc}"


def _deleted_current_folder() -> str | None:
    """The path of the current folder when it no longer exists ("?" when it cannot be told), else None."""
    try:
        os.getcwd()
        return None
    except FileNotFoundError:
        pass
    try:
        return os.readlink("/proc/self/cwd").removesuffix(" (deleted)")
    except OSError:
        return os.environ.get("PWD") or "?"


def error_text(exc: BaseException, stream: object) -> str:
    """``cistrack: error: MESSAGE`` as :func:`cistrack.cli.text_width.for_stream` shows it on ``stream``."""
    return _for_stream(f"cistrack: error: {exc}", stream)


def __getattr__(name: str):
    """``for_stream``, moved to :mod:`cistrack.cli.text_width`, still imports from here, with a
    DeprecationWarning."""
    if name == "for_stream":
        import warnings

        warnings.warn("cistrack.cli.main.for_stream moved to cistrack.cli.text_width.for_stream; import it from "
                      "there", DeprecationWarning, stacklevel=2)
        return _for_stream
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


_INTERRUPTED = {
    "run": ("; completed steps are kept, and the manifest says 'interrupted' unless the run had not started or had "
            "already finished"),
    "fit": ("; a fit is complete only once its fit.json is written (its filter run may have finished): "
            "run 'cistrack fit' into the same directory again"),
    "study": "; finished runs are kept: 'cistrack study run' with the same options runs the rest",
    "study report": "; study report interrupted: no report was written (the runs are untouched)",
}
"""What an interrupted command leaves, by command (``study report`` by its subcommand; nothing
said for the others)."""


def _interrupted_advice(args: argparse.Namespace) -> str:
    """What the interrupted command ``args`` leaves, in words (:data:`_INTERRUPTED`)."""
    cmd = getattr(args, "cmd", "")
    sub = f"{cmd} {getattr(args, 'study_cmd', '')}"
    return _INTERRUPTED.get(sub, _INTERRUPTED.get(cmd, ""))


def console_main() -> None:
    """The ``cistrack`` command: :func:`main`, then the end of the process (without interpreter
    teardown after a run: :mod:`cistrack.cli.process_exit`). Text the terminal's encoding cannot
    show (a scenario named in Unicode under ``PYTHONIOENCODING=ascii`` or a C locale) is printed
    as backslash escapes (``\\xef``), never an encoding error."""
    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)  # absent on a stream that is not a text file
        if reconfigure is not None:
            reconfigure(errors="backslashreplace")
    if sys.stdout is not None:
        sys.stdout = NamedOutput(sys.stdout, "standard output")
    if sys.stderr is not None:  # its reader gone (`2>&1 | head`): the messages stop, the work goes on
        sys.stderr = NamedOutput(sys.stderr, "standard error", drop_all_errors=True)
    warnings.showwarning = show_warning
    exit_process(main())


def show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """How the command shows a Python warning: ``cistrack: warning: <message>`` on stderr (above a
    progress bar), without the source file and line that Python's default adds (they mean nothing
    to a person running the command); within 120 columns when stderr is a terminal."""
    text = str(message)
    _eprint(_for_stream(f"cistrack: warning: {text.removeprefix('cistrack: ')}", sys.stderr))


if __name__ == "__main__":
    console_main()
