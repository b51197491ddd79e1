"""The ``cistrack study`` command: ``study run`` and ``study report`` (see :mod:`cistrack.studies.study`
and :mod:`cistrack.studies.report`)."""
from __future__ import annotations

__all__ = ["add_study_parser", "cmd_study"]


def cmd_study(args) -> int:
    """``cistrack study run`` and ``cistrack study report``; the exit status: 0, or 3 when a run
    of the study is not done (failed, missing or left running), 2 for a refused input."""
    from cistrack.studies import study

    if args.study_cmd == "run":
        from cistrack.runs.input_checks import check_environment

        check_environment()  # before the study's directory: its workers would each fail on it
        res = study.run_study(args.study, out_dir=args.out, workers=args.workers, dask=args.dask,
                              progress=not args.quiet, rerun_dir=args.rerun, settings=args.set,
                              first_seed=args.first_seed, n_seeds=args.n_seeds, overwrite=args.overwrite)
        if not args.quiet:
            print(study.done_line(res))
        _report_problems(res)
        return 0 if res["failed"] == 0 else 3
    if args.study_cmd == "report":
        from cistrack.studies.report import report_study

        rep = report_study(args.study, out_dir=args.out, settings=args.set, first_seed=args.first_seed,
                           n_seeds=args.n_seeds)
        print(rep["text"])
        files = rep["files"]
        where = sorted({str(p.parent) for p in files})
        print(f"written: {len(files)} files in {', '.join(where)} (summary.md, summary.csv, runs.csv, figures)")
        return 0
    return 2


def _report_problems(res: dict) -> None:
    """On stderr (also with --quiet): every run of the study that is not done on disk, and why."""
    problems = res.get("problems") or []
    if not problems:
        return
    import sys

    for run_id, why in problems:
        print(f"cistrack: run {run_id} did not finish: {why}", file=sys.stderr)
    print(f"cistrack: error: study '{res['name']}': {len(problems)} of {res['total']} runs did not finish "
          f"(listed above; their results in {res['out_dir']} are incomplete); 'cistrack study run' on the "
          f"same study and --out runs them again", file=sys.stderr)


def _seed_arguments(parser) -> None:
    parser.add_argument("--first-seed", type=int, default=None, metavar="N",
                        help="run (or report) consecutive seeds from N instead of the study's own")
    parser.add_argument("--n-seeds", type=int, default=None, metavar="N",
                        help="how many seeds (default: the study's own number)")


def add_study_parser(subparsers) -> None:
    """Add ``study run`` and ``study report`` to the ``cistrack`` command's subparsers."""
    from cistrack.cli.option_types import path_text

    st = subparsers.add_parser("study", help="run or report a comparative study")
    stsub = st.add_subparsers(dest="study_cmd", required=True)
    sr = stsub.add_parser("run", help="run every missing run of a study")
    sr.add_argument("study", help="study TOML file, built-in study name or study results directory")
    sr.add_argument("--out", type=path_text("--out"), default=None, help="study directory (default studies_out/<name>)")
    sr.add_argument("--workers", type=int, default=None, help="local worker processes (default: cores)")
    sr.add_argument("--dask", default=None, metavar="ADDRESS", type=path_text("--dask"),
                    help="run on a Dask cluster ('local' for a local one)")
    sr.add_argument("--rerun", metavar="DIR", default=None, type=path_text("--rerun"),
                    help="write one rerun recording per run into DIR")
    sr.add_argument("--set", action="append", metavar="TABLE.KEY=VALUE",
                    help="override a value in every run (after the study's own overrides and variants), "
                         "validated like a scenario file; the default study directory names the settings")
    sr.add_argument("--quiet", action="store_true", help="print nothing but warnings and errors")
    sr.add_argument("--overwrite", action="store_true",
                    help="run again finished runs the study now plans otherwise (another scenario, settings, seed "
                         "or input file), replacing their results; refused without it")
    _seed_arguments(sr)
    sr.set_defaults(func=cmd_study)
    srep = stsub.add_parser("report", help="summarise a study (terminal, CSV, Markdown, PNG)")
    srep.add_argument("study", help="study TOML file, built-in study name or study results directory (its own seeds and --set values)")
    srep.add_argument("--out", type=path_text("--out"), default=None,
                      help="the study directory 'study run --out' wrote (default studies_out/<name>); the report "
                           "goes into its report/ folder")
    srep.add_argument("--set", action="append", metavar="TABLE.KEY=VALUE",
                      help="report the study run with these --set values")
    _seed_arguments(srep)
    srep.set_defaults(func=cmd_study)
