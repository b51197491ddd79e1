"""The machine a benchmark ran on, printed at the top of every benchmark table."""
from __future__ import annotations

import os
import platform


def _usable() -> int:
    """Cores this process may run on (``taskset -c 0,1`` gives 2)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover
        return os.cpu_count() or 1


def machine_lines() -> list[str]:
    """CPU model, core count, OS and library versions, one fact per line."""
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    import numpy
    import scipy
    try:
        import numba
        nb = numba.__version__
        threads = numba.config.NUMBA_NUM_THREADS
    except ImportError:  # pragma: no cover
        nb, threads = "-", "-"
    try:
        import sklearn
        skl = sklearn.__version__
    except ImportError:  # pragma: no cover
        skl = "-"
    try:
        load = "%.2f %.2f %.2f" % os.getloadavg()
    except OSError:  # pragma: no cover
        load = "-"
    return [
        f"machine: {cpu} | {os.cpu_count()} logical cores ({_usable()} usable by this process) | "
        f"{platform.system()} {platform.release()}",
        f"python {platform.python_version()} | numpy {numpy.__version__} | scipy {scipy.__version__} | "
        f"numba {nb} ({threads} threads) | scikit-learn {skl}",
        f"load average at start: {load}",
    ]
