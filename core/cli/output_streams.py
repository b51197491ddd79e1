"""The command's standard output and standard error as it writes them: errors name the stream, and a
stream whose reader has gone (``cistrack fit ... 2>&1 | head``) or that cannot be written at all
(a closed or read-only descriptor) stops receiving text while the command finishes its work."""
from __future__ import annotations

import errno
import os

__all__ = ["NamedOutput"]

_GONE = (errno.EPIPE, errno.EBADF)
"""Errors saying nobody will ever read the stream: its reader closed the pipe, or the descriptor
is closed or open for reading only (a script started with ``2>&-`` may hold its own file there)."""


class NamedOutput:
    """A text stream whose write and flush errors name it (``standard output: No space left on
    device``, where the bare OSError named nothing).

    Once the stream is gone (a closed pipe, a closed or read-only descriptor) later text is
    dropped, so the command goes on and writes its results: its messages are not its work, and
    a log viewer closed early must not end a fit or a run. ``drop_all_errors`` (for standard
    error, where an error could not be reported anyway) drops the text after any write error."""

    def __init__(self, stream, label: str, drop_all_errors: bool = False):
        self._stream, self._label, self._drop_all = stream, label, drop_all_errors
        self.gone = False

    def write(self, text: str) -> int:
        return len(text) if self.gone else self._named(self._stream.write, text)

    def flush(self) -> None:
        if not self.gone:
            self._named(self._stream.flush)

    def _named(self, call, *args):
        try:
            return call(*args)
        except OSError as exc:
            if exc.errno in _GONE or isinstance(exc, BrokenPipeError) or self._drop_all:
                self._stop()
                return len(args[0]) if args else None
            raise OSError(exc.errno, exc.strerror or str(exc), self._label) from exc

    def _stop(self) -> None:
        """Drop what is left and point the descriptor at the null device, so that Python's own
        flush at exit has nowhere to fail."""
        self.gone = True
        try:
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, self._stream.fileno())
            os.close(null)
        except (OSError, ValueError, AttributeError):  # no descriptor (a test's StringIO): nothing to point
            pass

    def __getattr__(self, name: str):
        return getattr(self._stream, name)
