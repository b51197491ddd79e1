"""Files are small and named for what they hold: no module in core/ or plugins/ is much longer
than 300 lines unless its docstring says why (a sentence starting "(Above 300 lines")."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LIMIT = 330  # "about 300": a file a little over is not worth splitting for its own sake


# Files another piece of work is still shaping; listed here, not exempted silently.
_IN_PROGRESS: dict[str, str] = {}


def _modules():
    for folder in ("core", "plugins"):
        for p in sorted((ROOT / folder).rglob("*.py")):
            if "__pycache__" not in p.parts:
                rel = str(p.relative_to(ROOT))
                marks = [pytest.mark.xfail(reason=_IN_PROGRESS[rel], strict=False)] if rel in _IN_PROGRESS else []
                yield pytest.param(p, id=rel, marks=marks)


@pytest.mark.parametrize("path", list(_modules()))
def test_module_is_short_or_says_why(path):
    text = path.read_text()
    n = text.count("\n")
    if n <= LIMIT:
        return
    doc = ast.get_docstring(ast.parse(text)) or ""
    assert "(Above 300 lines" in doc, (f"{path.relative_to(ROOT)} has {n} lines: split it by what it holds, "
                                       "or give the reason in its docstring ('(Above 300 lines ...')")
