"""What ``ct.fit`` returns prints in a few lines: the object, its outcome, the method, the
observations used and rejected, the weighted RMS and the fit epoch (it printed 104,000 characters
of nested arrays, the whole filter run included); ``.report()`` is the full summary that
``cistrack fit`` prints. Fitted: the shipped real-data example and a lone tracklet."""
from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest

import cistrack as ct
from cistrack import units
from cistrack.cli.main import main

EXAMPLE = str(Path(__file__).resolve().parents[2] / "core/scenarios/real_data/observations.psv")
LONE = ("# version=2022\ntrkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat\n"
        "halo|CCD|711|2026-08-08T10:10:54.459251Z|79.45130697317135|28.619129966967737|0.648|0.648|Gaia3\n"
        "halo|CCD|711|2026-08-08T10:14:32.774891Z|79.49241394217094|28.6267601916247|0.648|0.648|Gaia3\n"
        "halo|CCD|711|2026-08-08T10:18:01.093644Z|79.53137355766705|28.634043338470014|0.648|0.648|Gaia3\n")


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    [one] = ct.fit(EXAMPLE, out=tmp_path_factory.mktemp("fit") / "example")
    return one


def test_the_printed_form_of_the_example_fit_is_short(example):
    assert len(repr(example)) < 2000
    assert str(example) == repr(example)
    assert len(repr([example])) < 2000  # as a notebook shows ``ct.fit(...)``'s list
    assert len(repr(example).splitlines()) <= 6


def test_the_printed_form_says_object_outcome_method_counts_rms_and_epoch(example):
    text, r = repr(example), example.result
    epoch = units.format_utc(units.tu_to_utc(example.scenario.epoch, r.epoch))[:19] + "Z"
    assert text.startswith(f"<ObjectFit {example.designation}: converged")
    assert f"IOD '{example.seeding['method']}'" in text and "filter 'pgm'" in text
    assert f"{r.n_used} used, {r.n_rejected} rejected" in text
    assert f"weighted RMS {r.rms:.3f}" in text and epoch in text


def test_report_is_the_summary_cistrack_fit_prints(example, tmp_path):
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(io.StringIO()):
        assert main(["fit", EXAMPLE, "--out", str(tmp_path / "cli")]) == 0
    report = example.report()
    printed = buf.getvalue().replace(str(tmp_path / "cli"), str(example.directory))
    assert report in printed
    assert "chi-square" in report and "1-sigma at the fit epoch" in report and len(report) > len(repr(example))


def test_an_undetermined_fit_prints_short_too(tmp_path):
    f = tmp_path / "lone.psv"
    f.write_text(LONE)
    [one] = ct.fit(f, out=tmp_path / "out")
    assert repr(one).startswith(f"<ObjectFit {one.designation}: UNDETERMINED")
    assert len(repr(one)) < 2000
    assert "UNDETERMINED" in one.report() and "admissible region" in one.report()
