"""A third party's component whose constructor fails with its own exception (a missing optional
library, a bug, ``sys.exit``) is refused while the scenario is validated, as a ConfigError naming
the table, the component, its distribution and the error: never a traceback."""
from __future__ import annotations

import pytest

from cistrack.errors import ConfigError
from cistrack.plugin.registry import load_registry
from cistrack.plugins.filters.ukf import UKFFilter
from cistrack.scenario.loading import load_scenario


class InitRaise(UKFFilter):
    """A filter whose constructor fails."""

    def __init__(self, alpha: float = 1.0):
        raise RuntimeError("boom in init")


class InitExit(UKFFilter):
    """A filter whose constructor calls a library that calls sys.exit."""

    def __init__(self, alpha: float = 1.0):
        raise SystemExit(3)


def _load(cls):
    reg = load_registry(autoload_third_party=False)
    reg.add("filter", "h-init", cls, "hplug", "0.1", "hplug")
    return load_scenario("quick", reg, overrides={"filter": {"name": "h-init"}})


def test_a_constructor_raising_its_own_error_is_a_config_error_naming_the_component_and_its_distribution():
    with pytest.raises(ConfigError, match=r"\[filter\]: filter 'h-init' \(hplug 0\.1\): could not be constructed: "
                                          r"RuntimeError: boom in init$"):
        _load(InitRaise)


def test_a_constructor_calling_sys_exit_is_a_config_error_not_the_end_of_the_process():
    with pytest.raises(ConfigError, match=r"filter 'h-init' \(hplug 0\.1\): could not be constructed: "
                                          r"SystemExit: it called sys\.exit\(3\)$"):
        _load(InitExit)
