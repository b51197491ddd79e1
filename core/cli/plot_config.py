"""Where matplotlib keeps its configuration and font cache when cistrack draws plots: a temporary
folder, removed at exit, when its default place hangs off a home or XDG folder that is missing,
empty or not a directory. Otherwise matplotlib creates a missing ``$HOME`` (``$HOME/.config``,
``$HOME/.cache``), or prints its own "mkdir -p failed" and MPLCONFIGDIR advice around cistrack's
single warning about its kernel cache."""
from __future__ import annotations

import atexit
import os
import shutil
import tempfile

__all__ = ["set_plot_config_dir"]


def _unusable(path: str | None) -> bool:
    """Whether ``path`` (an environment variable's value; None when unset) is set but cannot hold a
    folder: empty, missing, or not a directory."""
    return path is not None and (not path.strip() or not os.path.isdir(path))


def set_plot_config_dir() -> None:
    """Set ``MPLCONFIGDIR`` to a temporary folder (removed at exit) when it is unset and ``$HOME``,
    ``$XDG_CONFIG_HOME`` or ``$XDG_CACHE_HOME`` is set but unusable (:func:`_unusable`)."""
    if os.environ.get("MPLCONFIGDIR"):
        return
    if not any(_unusable(os.environ.get(k)) for k in ("HOME", "XDG_CONFIG_HOME", "XDG_CACHE_HOME")):
        return
    folder = tempfile.mkdtemp(prefix="cistrack-matplotlib-")
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    os.environ["MPLCONFIGDIR"] = folder
