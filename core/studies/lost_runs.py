"""Runs of a study that did not finish are never passed over in silence.

:func:`refuse_in_a_starting_worker` stops a study started while a spawned worker process imports
the main script (a script that calls ``cistrack.study`` without an ``if __name__ == "__main__":``
guard), and :func:`say_lost_runs` turns a study's lost runs into an error (none finished) or a
warning (some did not), naming the first and, when the worker pool broke, the guard.
"""
from __future__ import annotations

import warnings
from pathlib import Path

from cistrack.errors import CistrackError

__all__ = ["MAIN_GUARD_HINT", "refuse_in_a_starting_worker", "say_lost_runs"]

MAIN_GUARD_HINT = ("a script that runs a study must call it under `if __name__ == \"__main__\":`: the "
                   "study's worker processes import the script again, and unguarded, each one starts the "
                   "study anew instead of its run")


def refuse_in_a_starting_worker() -> None:
    """A study started while a spawned worker process imports the main script (a script that calls
    ``cistrack.study`` without an ``if __name__ == "__main__":`` guard) is refused by name: it would
    start the study again in every worker, find the study's lock taken and end the worker."""
    import multiprocessing as mp

    if getattr(mp.current_process(), "_inheriting", False):
        raise CistrackError(f"study: started while a worker process was starting; {MAIN_GUARD_HINT}")


def say_lost_runs(name: str, directory: Path, total: int, done: int, lost) -> tuple[tuple[str, str], ...]:
    """The (run id, why) pairs of the runs of study ``name`` that did not finish (``lost``), which
    are never passed over in silence: none of the ``total`` finished raises :class:`CistrackError`,
    some warns (RuntimeWarning; the result lists them in ``problems``)."""
    problems = tuple((str(a), str(b)) for a, b in lost or ())
    if not problems:
        return problems
    first = f"{problems[0][0]}: {problems[0][1]}"
    hint = f"; {MAIN_GUARD_HINT}" if any("BrokenProcessPool" in why for _, why in problems) else ""
    if done == 0:
        raise CistrackError(f"study {name!r} ({directory}): none of its {total} runs finished; "
                            f"the first: {first}{hint}")
    warnings.warn(f"study {name!r} ({directory}): {len(problems)} of {total} runs did not finish "
                  f"(StudyResult.problems lists them); the first: {first}{hint}", RuntimeWarning, stacklevel=3)
    return problems
