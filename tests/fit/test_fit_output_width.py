"""What `cistrack fit` prints fits in 120 columns: the weights notes and the error of a failed fit
on stdout, the stages of each object on stderr, long ones wrapped with their continuation lines
indented under their first (nothing lost). A four-observation MPC file (two tracklets of two,
from the shipped example) fails quickly with long messages on both streams."""
from __future__ import annotations

import contextlib
import io

import pytest

from cistrack.cli.main import main

MAX = 120
FOUR = """\
     cis0001  C2026 03 01.94097209 21 56.561+08 01 17.71                     809
     cis0001  C2026 03 01.97058009 23 09.488+07 55 50.38                     809
     cis0001  C2026 03 06.46233712 51 44.856-19 36 48.53                     809
     cis0001  C2026 03 06.50177112 53 08.106-19 48 25.08                     809
"""


@pytest.fixture(scope="module")
def printed(tmp_path_factory):
    """(exit status, stdout, stderr) of `cistrack fit` of two MPC tracklets of two observations."""
    d = tmp_path_factory.mktemp("width")
    src = d / "four.obs"
    src.write_text(FOUR)
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(["fit", str(src), "--out", str(d / "fit")])
    return rc, out.getvalue(), err.getvalue()


def _too_wide(text: str) -> list[str]:
    return [line for line in text.splitlines() if len(line) > MAX]


def _flat(text: str) -> str:
    return " ".join(text.split())


def test_the_error_of_a_failed_fit_is_wrapped_within_120_columns(printed):
    rc, out, _ = printed
    error = out[out.index("  error: "):].split("\n  no orbit")[0]
    assert rc == 3 and _too_wide(error) == [] and "before it, with the template's IOD" in _flat(error)


def test_the_weights_note_is_wrapped_within_120_columns_under_its_first_line(printed):
    _, out, _ = printed
    lines = out.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("  weights: "))
    assert _too_wide("\n".join(lines[:k + 2])) == [] and lines[k + 1].startswith("    ")
    assert "set [measurements] reader.sigma_arcsec to your data's noise" in _flat(out)


def test_the_stage_lines_on_stderr_fit_in_120_columns(printed):
    _, _, err = printed
    assert _too_wide(err) == [] and "Task more measurements in the first pass" in _flat(err)
