"""A name that moved keeps importing from its old path, with a DeprecationWarning."""
from __future__ import annotations

import pytest


def test_for_stream_still_imports_from_cli_main_with_a_warning():
    from cistrack.cli import text_width

    with pytest.warns(DeprecationWarning, match="moved to cistrack.cli.text_width.for_stream"):
        from cistrack.cli.main import for_stream
    assert for_stream is text_width.for_stream


def test_an_unknown_name_of_cli_main_is_still_an_attribute_error():
    import cistrack.cli.main as main

    with pytest.raises(AttributeError):
        main.no_such_name  # noqa: B018
