"""``cistrack export``: a run's orbit estimate, or a fit's fitted orbit, as CCSDS OEM or OPM."""
from __future__ import annotations

from cistrack.cli.fit_command import _eprint, cmd_export_fit, is_fit_export

__all__ = ["cmd_export"]


def cmd_export(args) -> int:
    from cistrack.runs.export import export_run

    if is_fit_export(args):  # a 'cistrack fit' directory (--predict DAYS): the fitted orbit
        return cmd_export_fit(args)
    params = {} if args.step is None else {"step": args.step}
    out = export_run(args.run, args.format, args.out, overwrite=args.overwrite, force=args.force, **params)
    if args.force:
        from cistrack.runs.export import export_refusal

        why = export_refusal(args.run)
        if why:
            _eprint(f"cistrack: warning: exported with --force: {why} (the file says so in a COMMENT)")
    if not args.quiet:
        print(f"wrote {out}")
    return 0
