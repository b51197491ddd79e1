"""The ranging IOD says what it is doing while it runs (probe N16).

`cistrack fit` of a 30-observation file sat 22-37 s in the tracklet-ranging IOD with no word: the
IOD spoke only when one range trial fitted 5,000 observations or more, and its 10 s clock started
afresh at every seed, each under 10 s. A line now comes every ``RangingProgress.every_s`` seconds
(10) from the IOD's start, across its seeds, naming the seed tracklet and the trials fitted. Here
the interval is set to 0 so that the real IOD, on the shipped campaign's first two nights, says a
line at each seed."""
from __future__ import annotations

from pathlib import Path

from cistrack.cli.main import main
from cistrack.plugins.iod.ranging_search import RangingProgress

SHIPPED = Path(__file__).parents[2] / "core/scenarios/real_data/observations.psv"


def test_the_ranging_iod_says_which_seed_it_ranges_from(tmp_path, capsys, monkeypatch):
    lines = [r for r in SHIPPED.read_text().splitlines() if r and not r.startswith("#")]
    data = tmp_path / "two_nights.psv"
    data.write_text("\n".join([lines[0], *[r for r in lines[1:] if r.split("|")[3] < "2026-03-03"]]) + "\n")
    monkeypatch.setattr(RangingProgress, "every_s", 0.0)
    main(["fit", str(data), "--out", str(tmp_path / "out"), "--set", "iod.name=tracklet-ranging"])
    err = capsys.readouterr().err
    assert "iod 'tracklet-ranging': ranging from seed tracklet 1 (3 observations; seed trial 1 of up to" in err


def test_the_interval_is_ten_seconds():
    assert RangingProgress.every_s == 10.0
