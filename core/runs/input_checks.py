"""What a run reads or is told, checked before its results directory is made.

``cistrack run`` creates its results directory before the run starts; an input that only fails
inside the run (an observation file that is not there, a part size of 0) would leave that
directory behind, empty. :func:`check_run_inputs` refuses those first, naming the file or flag.
"""
from __future__ import annotations

from typing import Any

from cistrack.errors import ConfigError
from cistrack.interfaces.reader import not_a_file
from cistrack.scenario.limits import check_count

__all__ = ["check_run_inputs", "check_environment"]


def check_run_inputs(scenario: Any, rows_per_part: int | None = None) -> None:
    """Raise :class:`ConfigError` when ``scenario``'s ``[measurements] file`` is not a readable file,
    ``rows_per_part`` (``--rows-per-part``) is not a count of at least 1, or the environment's
    ``$CISTRACK_NUM_THREADS`` or kernel cache directory cannot serve a run."""
    if rows_per_part is not None:
        check_count(rows_per_part, "--rows-per-part", 1, 10 ** 9)
    check_environment()
    f = getattr(scenario, "measurements_file", None)
    why = None if f is None else not_a_file(f)
    if why is not None:
        raise ConfigError(f"{scenario.source}: [measurements] file = {f}: {why}; nothing was run")


def check_environment() -> None:
    """The thread count, the background-compile switch and the kernel cache directory a run will use, checked (and the cache made)
    before a results directory is; a cache directory that cannot be made is left to the run (it
    compiles in memory and says so)."""
    from cistrack.env_flags import env_flag
    from cistrack.propagation.kernels import secure_cache_dir
    from cistrack.threads import thread_setting

    thread_setting()
    env_flag("CISTRACK_BACKGROUND_COMPILE")  # read only when a kernel compiles: checked for every run here
    try:
        secure_cache_dir()  # ConfigError: not a directory, another user's, writable by others
    except OSError:  # cannot be made: the run compiles in memory, slower to start, and its warning says why
        pass

