"""Progress on stderr: a bar as an observer of a run's hooks, and stage lines for the commands
that have no steps to count (an export, a fit's least squares).

Both follow ``cistrack run``: the stage lines go to stderr, indented under the command's own first
line, as the ``log`` callable that :func:`cistrack.runs.pipeline.run_scenario`, ``export_run`` and
``fit_files`` take; ``--quiet`` (or ``progress=False``) passes no ``log`` and no bar is shown.
"""
from __future__ import annotations

import sys
from typing import Callable

from cistrack import units
from cistrack.plugin.hookspecs import hookimpl

__all__ = ["ProgressBar", "eprint", "stage_log", "bar_columns", "bar_class", "BAR_MAX_COLUMNS"]

BAR_MAX_COLUMNS = 120
"""The widest a progress bar is drawn (the command line's output width), narrower on a narrower
terminal."""


def bar_columns() -> int:
    """Columns for a progress bar: the width of the terminal stderr is, at most
    :data:`BAR_MAX_COLUMNS` (and that when stderr is not a terminal: a file or a CI log)."""
    import os

    try:
        if sys.stderr is not None and sys.stderr.isatty():
            return max(20, min(BAR_MAX_COLUMNS, os.get_terminal_size(sys.stderr.fileno()).columns))
    except (OSError, ValueError, AttributeError):  # no file number (a notebook), or not a terminal after all
        pass
    return BAR_MAX_COLUMNS


def bar_class() -> type:
    """tqdm's bar class: the notebook widget under IPython (``tqdm.auto``), else the text bar.

    ``tqdm.auto`` imports asyncio and tqdm's notebook module in every process (about 10 ms of a
    run's start-up); outside IPython it resolves to the text bar, which this imports directly."""
    if "IPython" in sys.modules:
        from tqdm.auto import tqdm
    else:
        from tqdm.std import tqdm
    return tqdm


def eprint(*parts: object) -> None:
    """Write ``parts`` (joined by spaces) as one line on stderr, flushed. While a progress bar is
    shown the line goes above it and the bar is drawn again below (a line written after a bar's
    last redraw would otherwise continue the bar's line). Nothing is written when stderr is
    closed (``2>&-``)."""
    stream = sys.stderr
    if stream is None:
        return
    text = " ".join(str(p) for p in parts)
    tq = sys.modules.get("tqdm")  # a bar exists only if tqdm was imported: never imported here for this
    if tq is not None and getattr(tq.tqdm, "_instances", None):
        tq.tqdm.write(text, file=stream)
        stream.flush()
        return
    print(text, file=stream, flush=True)


def stage_log(indent: str = "  ") -> Callable[[str], None]:
    """A ``log`` callable that writes each stage message on its own line of stderr after ``indent``,
    flushed at once (a person waiting sees it when the stage starts). ``sys.stderr`` is looked up
    at each message, so a redirected stderr (a test, a notebook) receives it."""
    def say(message: str) -> None:
        eprint(f"{indent}{message}")

    return say


class ProgressBar:
    """tqdm bar over a run's ``total`` filter steps, showing time, entropy and custody.

    ``custody`` is the run's :class:`~cistrack.evaluation.custody.CustodyMetric` (its verdict is shown).
    """

    def __init__(self, run_id: str, total: int, custody=None) -> None:
        tqdm = bar_class()
        self.custody = custody
        # on a terminal the bar redraws at most every 0.1 s; into a file or a CI log, where every
        # redraw is kept, at most every 10 s (and once at the end)
        interactive = getattr(sys.stderr, "isatty", lambda: False)()
        self.bar = tqdm(total=total, desc=run_id, unit="step", leave=True, mininterval=0.1 if interactive else 10.0,
                        ncols=bar_columns(),
                        disable=sys.stderr is None)  # stderr closed (2>&-): no bar, the run goes on

    def _advance(self, step) -> None:
        lost = self.custody is not None and step.truth is not None and not self.custody.verdict.kept
        # refresh=False: the step count's update below redraws, as often as mininterval allows
        self.bar.set_postfix_str(f"t={float(units.tu_to_days(step.t)):.2f} d H={step.metrics.get('entropy', float('nan')):.1f}"
                                 + (" custody LOST" if lost else ""), refresh=False)
        self.bar.update(1)

    @hookimpl
    def cistrack_step_predicted(self, run, step) -> None:
        if step.kind == "predict":
            self._advance(step)

    @hookimpl
    def cistrack_step_updated(self, run, step) -> None:
        self._advance(step)

    @hookimpl
    def cistrack_run_finished(self, run, summary) -> None:
        self.bar.close()
