"""Running a study's runs through an executor, and what each run left on disk afterwards.

A worker's answer is not the truth about a run: a run whose results could not be written (a full
disk) still returns a summary, a killed worker returns nothing, and a run can be left "running".
So after the executor has finished, every run is checked where its results are
(:func:`cistrack.studies.resume.run_state`), and a run that is not done there is reported with the
reason: its manifest's status and failure, or what its worker said when no manifest was written.
"""
from __future__ import annotations

import concurrent.futures as cf
import socket
import struct
from pathlib import Path
from typing import Any, Callable, Sequence

from cistrack.errors import ConfigError
from cistrack.results.atomic_files import write_text_atomic
from cistrack.results.run_status import run_status
from cistrack.results.store import read_manifest
from cistrack.runs.progress import eprint
from cistrack.studies.resume import run_state

__all__ = ["run_all", "run_problems", "shutdown", "check_dask_scheduler", "DASK_TIMEOUT_S"]

DASK_TIMEOUT_S = 10.0
"""Seconds ``--dask ADDRESS`` is given to accept a connection, and then to greet (each)."""
_DASK_PORT = 8786
"""A Dask scheduler's port when the address names none."""
_GREETING_MAX = 1 << 20
"""Bytes a scheduler's greeting (its handshake message, some hundred bytes) may announce at most."""


def run_all(ex: cf.Executor, todo: Sequence[Any], fn: Callable[[Any], Any], bar: Any = None) -> dict[str, str]:
    """Submit ``fn(spec)`` for every spec of ``todo`` and wait for all; returns what each run's
    worker said that was not a normal end (run id -> text), e.g. "status failed: ..." or the
    exception it raised. A run raising an exception never stops the others; its reason goes to
    ``error.txt`` in its directory (when it can be written) and to stderr."""
    said: dict[str, str] = {}
    futures = {ex.submit(fn, s): s for s in todo}
    for fut in cf.as_completed(futures):
        spec = futures[fut]
        try:
            summary = fut.result()
            if summary.status not in ("finished", "filter-failed"):
                said[spec.run_id] = f"{summary.status}" + (f": {summary.failure}" if summary.failure else "")
            if bar is not None:
                bar.set_postfix_str(f"{spec.run_id}: {summary.status}, {summary.verdict.kind}")
        except Exception as exc:  # one failing run must not stop the study
            said[spec.run_id] = f"{type(exc).__name__}: {exc}"
            try:
                Path(spec.out_dir).mkdir(parents=True, exist_ok=True)
                write_text_atomic(Path(spec.out_dir) / "error.txt", f"{type(exc).__name__}: {exc}\n")
            except OSError:  # a full disk: the reason is still printed and reported
                pass
            eprint(f"run {spec.run_id} failed: {type(exc).__name__}: {exc}")
        if bar is not None:
            bar.update(1)
    return said


STOP_SECONDS = 30.0
"""How long an interrupted study waits at most for a terminated worker to record its run as
interrupted (merge its completed steps, write its manifest) before killing it. A worker takes well
under a second on an idle machine and several on a loaded one; one killed before it has written its
manifest leaves its run "running"."""
_SAY_AFTER_S = 2.0
"""Seconds of waiting on stopped workers after which the study says what it is waiting for."""


def shutdown(ex: cf.Executor, cancel: bool) -> None:
    """Shut ``ex`` down, waiting for its workers; ``cancel`` (the study was interrupted): runs not
    started yet never start, and a local pool's worker processes are terminated, so that the
    interrupt ends the study at once (a worker that caught the interrupt itself could otherwise take
    the next run, and waiting on a pool whose workers were interrupted can hang). A run they leave
    unfinished says "running" in its manifest with a process that is gone: the next 'study run'
    runs it again."""
    if cancel and isinstance(ex, cf.ProcessPoolExecutor):
        _stop_workers(ex)
        return
    try:
        ex.shutdown(wait=True, cancel_futures=cancel)
    except TypeError:  # an executor whose shutdown takes no cancel_futures (older Dask)
        ex.shutdown(wait=True)


def _stop_workers(ex: cf.ProcessPoolExecutor) -> None:
    """Terminate the pool's workers, give each up to :data:`STOP_SECONDS` s to record its run as
    interrupted (saying so when that takes longer than :data:`_SAY_AFTER_S` s), then kill it."""
    procs = list((getattr(ex, "_processes", None) or {}).values())  # CPython's pool keeps them here
    for p in procs:
        if p.is_alive():
            p.terminate()
    ex.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        p.join(timeout=_SAY_AFTER_S)
    alive = [p for p in procs if p.is_alive()]
    if alive:
        eprint(f"waiting for {len(alive)} stopped worker(s) to record their runs as interrupted "
               f"(at most {STOP_SECONDS:.0f} s)")
    for p in alive:
        p.join(timeout=STOP_SECONDS - _SAY_AFTER_S)
        if p.is_alive():
            p.kill()
            p.join(timeout=STOP_SECONDS)


def run_problems(specs: Sequence[Any], said: dict[str, str]) -> list[tuple[str, str]]:
    """(run id, why) for every run of ``specs`` that is not done on disk now, in plan order."""
    out = []
    for s in specs:
        if run_state(s.out_dir, s.fingerprint) == "done":
            continue
        out.append((s.run_id, _why(Path(s.out_dir), s.fingerprint, said.get(s.run_id))))
    return out


def _why(d: Path, fingerprint: str, said: str | None) -> str:
    """Why the run in ``d`` is not done, from its manifest, else from what its worker said."""
    worker = f"; its worker said: {said}" if said else ""
    if not (d / "manifest.json").is_file():
        return f"no manifest.json was written in {d}" + (worker or "; the run never started")
    try:
        status, reason = run_status(d)
        man = read_manifest(d)
    except (OSError, ValueError) as exc:
        return f"its manifest {d / 'manifest.json'} cannot be read ({exc}){worker}"
    if man.get("status") == "running":
        proc = man.get("process") or {}
        gone = ", which is gone" if status == "interrupted" else ""
        return (f"its manifest still says 'running' (process {proc.get('pid', '?')} on {proc.get('host', '?')}"
                f"{gone}): the end of the run was never recorded{worker}")
    if status in ("finished", "filter-failed"):
        if fingerprint and man.get("fingerprint") != fingerprint:
            return f"its results are of another scenario or seed (fingerprint differs){worker}"
        return f"{status}, but {d / 'steps.parquet'} is missing" + (f" ({reason})" if reason else "") + worker
    return status + (f": {reason}" if reason else "") + ("" if reason else worker)


def check_dask_scheduler(address: str, timeout_s: float = DASK_TIMEOUT_S) -> None:
    """Refuse (ConfigError naming ``address``) a ``--dask`` address of the TCP transport
    (``tcp://HOST:PORT`` or ``HOST:PORT``) where no Dask scheduler answers: nothing accepts a
    connection within ``timeout_s`` s, or what does accept does not greet the way a scheduler does
    (a scheduler sends its handshake first: a length of 8 bytes in the machine's byte order, then that many
    bytes of frames) within ``timeout_s`` s. A Dask client given such a service would wait forever
    (an HTTP server sends nothing) or try to allocate the length it read (exbibytes). Addresses of
    other transports (``tls://``, ``ucx://``, ...) are left to Dask."""
    scheme, sep, place = address.partition("://")
    if not sep:
        scheme, place = "tcp", address
    if scheme != "tcp":
        return
    host, port = _host_port(address, place)
    expected = "a Dask scheduler (e.g. tcp://127.0.0.1:8786 from 'dask scheduler'), or 'local'"
    try:
        sock = socket.create_connection((host, port), timeout=timeout_s)
    except OSError as exc:
        why = "no answer" if isinstance(exc, TimeoutError) else (exc.strerror or str(exc))
        raise ConfigError(f"--dask {address}: cannot connect to {host}:{port} within {timeout_s:g} s ({why}); "
                          f"give the address of {expected}") from None
    with sock:
        problem = _greeting_problem(sock, timeout_s)
    if problem:
        raise ConfigError(f"--dask {address}: what answers at {host}:{port} is not a Dask scheduler: {problem}; "
                          f"give the address of {expected}")


def _host_port(address: str, place: str) -> tuple[str, int]:
    """(host, port) of ``HOST:PORT``, ``HOST``, ``[IPV6]:PORT`` or ``[IPV6]`` (port 8786 by default)."""
    bad = ConfigError(f"--dask {address}: not an address: give tcp://HOST:PORT (PORT 1 to 65535; an IPv6 host "
                      "in brackets, [::1]), or 'local'")
    if place.startswith("["):
        host, closed, tail = place[1:].partition("]")
        if not closed or (tail and not tail.startswith(":")):
            raise bad
        port = tail[1:]
    else:
        host, sep, port = place.rpartition(":")
        if not sep:
            host, port = port, ""
        if ":" in host:
            raise bad
    if not host or not (port == "" or (port.isascii() and port.isdigit() and 0 < int(port) < 65536)):
        raise bad
    return host, int(port) if port else _DASK_PORT


def _greeting_problem(sock: socket.socket, timeout_s: float) -> str:
    """What is wrong with the first bytes the peer on ``sock`` sends ("" when they look like a Dask
    scheduler's handshake: a length, then a frame count and frame lengths that fit in it)."""
    sock.settimeout(timeout_s)
    try:
        head = _read(sock, 8)
        if len(head) < 8:
            return "it closed the connection without a greeting" if not head else "it sent only a few bytes"
        (n,) = struct.unpack("=Q", head)
        if not 16 <= n <= _GREETING_MAX:
            return (f"its first bytes {head!r} announce a message of {n} bytes, not a handshake of 16 bytes to "
                    f"{_GREETING_MAX // 1024} KiB")
        body = _read(sock, 8)
        (frames,) = struct.unpack("=Q", body) if len(body) == 8 else (0,)
        if not 1 <= frames <= (n - 8) // 8:
            return f"its message of {n} bytes does not begin with a count of Dask frames"
    except TimeoutError:
        return (f"it sent nothing within {timeout_s:g} s (a scheduler greets first; e.g. an HTTP server waits for a "
                "request)")
    except OSError as exc:
        return f"the connection failed ({exc.strerror or exc})"
    return ""


def _read(sock: socket.socket, n: int) -> bytes:
    """Up to ``n`` bytes from ``sock`` (fewer when the peer closes the connection)."""
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            break
        data += chunk
    return data
