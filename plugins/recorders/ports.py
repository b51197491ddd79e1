"""TCP ports on 127.0.0.1: whether one is free before a server is started on it, and whether the
process we started (or one of its children) is the one listening on it afterwards.

A port is in use when something accepts a connection on it, or when binding it fails. Knowing
who listens matters because a server that could not bind its port exits a moment later, while
whatever already holds the port answers connections at once: "something answers" is not "ours
answers". On Linux the listening socket is found in ``/proc/net/tcp`` (and ``tcp6``) and matched
to the file descriptors of the process and its descendants; elsewhere the owner is unknown.
"""
from __future__ import annotations

import errno
import os
import socket
from pathlib import Path

from cistrack.errors import CistrackError

__all__ = ["LOOPBACK", "PortInUseError", "ensure_port_free", "free_port", "in_use_message", "listened_by"]

LOOPBACK = "127.0.0.1"
"""The only address the recorder's servers and viewers listen on."""

_TCP_LISTEN = "0A"  # the socket state column of /proc/net/tcp for LISTEN


class PortInUseError(CistrackError, OSError):
    """The port asked for on 127.0.0.1 is held by another process (or may not be bound here)."""


def free_port() -> int:
    """A port on 127.0.0.1 that is free now (to suggest; another process may take it later)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((LOOPBACK, 0))
        return int(s.getsockname()[1])


def in_use_message(port: int, option: str) -> str:
    """The error for a busy ``port``, naming the ``option`` that chose it and a free one instead."""
    return (f"{option} {port}: port {port} on {LOOPBACK} is already in use by another process "
            f"(perhaps another viewer); choose another port, e.g. {option} {free_port()}")


def ensure_port_free(port: int, option: str) -> None:
    """Refuse ``port`` (with :class:`PortInUseError` naming ``option``) when a process listens on
    127.0.0.1:``port`` or the port cannot be bound here; checked before anything is started on it."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.settimeout(1.0)
        answered = s.connect_ex((LOOPBACK, port)) == 0
    if answered:
        raise PortInUseError(in_use_message(port, option))
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        # servers set SO_REUSEADDR, so a connection of an earlier server in TIME_WAIT is no obstacle
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((LOOPBACK, port))
            s.listen(1)
        except OSError as exc:
            if exc.errno == errno.EADDRINUSE:
                raise PortInUseError(in_use_message(port, option)) from None
            if exc.errno == errno.EACCES:
                raise PortInUseError(f"{option} {port}: this user may not listen on port {port} "
                                     f"(ports below 1024 need administrator rights); choose one "
                                     f"from 1024 to 65535, e.g. {option} {free_port()}") from None
            raise PortInUseError(f"{option} {port}: cannot listen on {LOOPBACK}:{port}: "
                                 f"{exc.strerror or exc}") from None


def _listening_inodes(port: int) -> set[str] | None:
    """Inodes of the sockets listening on TCP ``port`` (any address); None without /proc/net."""
    found: set[str] = set()
    readable = False
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            lines = Path(table).read_text().splitlines()[1:]
        except OSError:
            continue
        readable = True
        for line in lines:
            cols = line.split()
            if len(cols) > 9 and cols[3] == _TCP_LISTEN and int(cols[1].rsplit(":", 1)[1], 16) == port:
                found.add(cols[9])
    return found if readable else None


def _process_tree(pid: int) -> set[int]:
    """``pid`` and every process descended from it (read from /proc/*/stat)."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])  # the name in (...) may hold spaces
        children.setdefault(ppid, []).append(int(entry))
    tree, todo = set(), [pid]
    while todo:
        p = todo.pop()
        if p not in tree:
            tree.add(p)
            todo.extend(children.get(p, ()))
    return tree


def _socket_inodes(pids: set[int]) -> set[str]:
    inodes: set[str] = set()
    for pid in pids:
        try:
            fds = os.listdir(f"/proc/{pid}/fd")
        except OSError:
            continue
        for fd in fds:
            try:
                link = os.readlink(f"/proc/{pid}/fd/{fd}")
            except OSError:
                continue
            if link.startswith("socket:["):
                inodes.add(link[len("socket:["):-1])
    return inodes


def listened_by(port: int, pid: int) -> bool | None:
    """Whether process ``pid`` (or one of its descendants) holds the socket listening on TCP
    ``port``; None where the system does not say (no ``/proc/net/tcp``)."""
    listening = _listening_inodes(port)
    if listening is None:
        return None
    return bool(listening & _socket_inodes(_process_tree(pid)))
