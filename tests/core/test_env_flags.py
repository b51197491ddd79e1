"""Yes/no environment variables read one way: common spellings of yes and no, anything else named."""
from __future__ import annotations

import pytest

from cistrack.env_flags import env_flag
from cistrack.errors import ConfigError
from cistrack.propagation.background_compile import idle_core
from cistrack.propagation.kernels import kernel_cache_dir


@pytest.mark.parametrize("value, meaning", [("1", True), ("Yes", True), ("on", True), ("0", False), ("false", False),
                                            ("OFF", False), ("no", False), ("", None), ("auto", None)])
def test_yes_no_and_unset_are_read(monkeypatch, value, meaning):
    monkeypatch.setenv("CISTRACK_TEST_FLAG", value)
    assert env_flag("CISTRACK_TEST_FLAG") is meaning


def test_anything_else_is_refused_naming_the_variable(monkeypatch):
    monkeypatch.setenv("CISTRACK_TEST_FLAG", "maybe")
    with pytest.raises(ConfigError, match="CISTRACK_TEST_FLAG='maybe'"):
        env_flag("CISTRACK_TEST_FLAG")


def test_background_compile_false_means_no_second_process(monkeypatch):
    monkeypatch.setenv("CISTRACK_BACKGROUND_COMPILE", "false")
    assert idle_core() is False


def test_a_relative_xdg_cache_home_is_ignored(monkeypatch):
    monkeypatch.delenv("CISTRACK_KERNEL_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", "relcache")
    assert kernel_cache_dir().is_absolute() and "relcache" not in str(kernel_cache_dir())
