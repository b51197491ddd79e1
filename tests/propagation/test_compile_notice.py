"""A first propagation that must compile kernels says so (one line, through logging)."""
from __future__ import annotations

import logging

from cistrack.lazy import lazy_njit
from cistrack.propagation import kernels


@lazy_njit(cache=True)
def decay_rhs(t, y, p, out):
    """dy/dt = -p[0] y: a model only this test uses, so its kernels are never cached elsewhere."""
    for i in range(y.shape[0]):
        out[i] = -p[0] * y[i]


def _kernels_logged(monkeypatch, tmp_path, caplog, dim: int):
    monkeypatch.setenv("CISTRACK_KERNEL_DIR", str(tmp_path))
    monkeypatch.setattr(kernels, "_KERNELS", {})
    with caplog.at_level(logging.INFO, logger="cistrack.propagation"):
        mod = kernels.kernels_for(decay_rhs, dim)
    return mod, [r.getMessage() for r in caplog.records if r.name == "cistrack.propagation"]


def test_uncached_kernels_announce_the_one_time_compilation(monkeypatch, tmp_path, caplog):
    _, messages = _kernels_logged(monkeypatch, tmp_path, caplog, dim=2)
    assert len(messages) == 1
    assert messages[0].startswith("compiling propagation kernels for")
    assert "decay_rhs" in messages[0] and "one-time" in messages[0]


def test_kernels_in_numba_cache_load_silently(monkeypatch, tmp_path, caplog):
    mod, _ = _kernels_logged(monkeypatch, tmp_path, caplog, dim=3)
    caplog.clear()
    # numba's index file for the propagation kernel, as numba writes it after compiling
    pyc = tmp_path / "__pycache__"
    pyc.mkdir(exist_ok=True)
    (pyc / f"{mod.__name__}.propagate_kernel-1.py311.nbi").write_bytes(b"")
    _, messages = _kernels_logged(monkeypatch, tmp_path, caplog, dim=3)
    assert messages == []
