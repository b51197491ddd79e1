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


def cpu_description(cpuinfo: str | None = None) -> str:
    """CPU model name with its family and model numbers and widest vector instructions, e.g.
    "AMD EPYC (family 26, model 2; AVX-512)": cloud machines report only "AMD EPYC" as the name,
    and two generations behind that one name differ by 1.5x in these benchmarks' ratios.
    ``cpuinfo``: the text of /proc/cpuinfo (default: read it)."""
    cpu = platform.processor() or ""
    if cpuinfo is None:
        try:
            with open("/proc/cpuinfo") as fh:
                cpuinfo = fh.read()
        except OSError:
            return cpu
    info: dict[str, str] = {}
    for line in cpuinfo.splitlines():
        if not line.strip() and info:
            break  # the first processor's block is enough
        key, _, value = line.partition(":")
        key = key.strip()
        if key in ("model name", "cpu family", "model", "flags") and key not in info:
            info[key] = value.strip()
    cpu = info.get("model name", cpu)
    flags = set(info.get("flags", "").split())
    isa = "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "SSE" if flags else "?"
    if "cpu family" in info:
        cpu += f" (family {info['cpu family']}, model {info.get('model', '?')}; {isa})"
    return cpu


def machine_lines() -> list[str]:
    """CPU model, core count, OS and library versions, one fact per line."""
    cpu = cpu_description()
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
