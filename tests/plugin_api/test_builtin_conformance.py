"""Every built-in component (distribution "cistrack") passes the conformance suite.

One test per (component, check); the registry is the real one, built-ins only.
"""
from __future__ import annotations

import pytest

from cistrack.plugin.registry import load_registry
from cistrack.testing import iter_checks

_REG = load_registry(autoload_third_party=False)

_SLOW: set[tuple[str, str]] = set()  # (kind, name) of built-ins too slow for the default run
# Components that cannot be built with defaults alone: the parameters the check uses.
_PARAMS = {("recorder", "rerun"): lambda tmp: {"path": str(tmp / "conformance.rrd")}}


def _cases():
    for kind in _REG.kinds():
        for entry in _REG.entries(kind):
            marks = [pytest.mark.slow] if (kind, entry.name) in _SLOW else []
            factory = entry.factory
            if (kind, entry.name) in _PARAMS:
                yield pytest.param(kind, entry.name, None, id=f"{kind}-{entry.name}", marks=marks)
                continue
            for check_name, check in iter_checks(factory, kind):
                yield pytest.param(kind, entry.name, check, id=f"{kind}-{entry.name}-{check_name}", marks=marks)


def test_builtins_load_without_failures():
    assert not _REG.failures, "\n".join(str(f) for f in _REG.failures)


@pytest.mark.parametrize(("kind", "name", "check"), list(_cases()))
def test_builtin_passes_conformance_check(kind, name, check, tmp_path):
    if check is None:  # components needing parameters: run all their checks on one instance
        from cistrack.testing import check_registered
        results = check_registered(name, kind, _REG, params=_PARAMS[(kind, name)](tmp_path))
        failed = [str(r) for r in results if not r.passed]
        assert not failed, "\n".join(failed)
        return
    check()
