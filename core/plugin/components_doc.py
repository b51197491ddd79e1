"""``python -m cistrack.plugin.components_doc > docs/components.md``: the reference of every
built-in component and its parameters, written from their docstrings
(:func:`cistrack.plugin.param_docs.components_markdown`)."""
from __future__ import annotations

import os

from cistrack.plugin.param_docs import components_markdown
from cistrack.plugin.registry import load_registry


def main() -> None:
    os.environ.setdefault("CISTRACK_DISABLE_PLUGIN_AUTOLOAD", "1")
    print(components_markdown(load_registry(autoload_third_party=False)), end="")


if __name__ == "__main__":
    main()
