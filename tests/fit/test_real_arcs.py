"""The real-data development set of 2025-010D (public-domain astrometry compiled by Project
Pluto; credits in its header and docs/data-credits.md): it reads, its sites are all MPC codes
of the bundled list, it holds nothing of the reserved final arc (2026-07-23 on), and (slow)
`cistrack fit` with no option fits its 2026 arcs as one orbit without throwing away whole nights."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from cistrack import units
from cistrack.astro.sites import observatory
from cistrack.cli.main import main
from cistrack.runs.observation_files import read_observations

DEV = Path(__file__).resolve().parents[2] / "core" / "scenarios" / "real_data" / "2025-010D-dev.psv"
_EPOCH = "2025-01-20T00:00:00Z"


@pytest.fixture(scope="module")
def dev():
    return read_observations(DEV, _EPOCH)


def _utc(ms, i) -> str:
    return units.format_utc(units.tu_to_utc(units.parse_utc(_EPOCH), ms.times[i]))


def test_dev_set_reads_with_its_stations(dev):
    assert len(dev) == 327
    assert dev.meta["object"] == "25010D"
    counts = {k: int((dev.sites == k).sum()) for k in sorted(dev.site_table)}
    assert counts == {"718": 7, "970": 4, "P13": 32, "W05": 3, "W68": 4, "Y82": 277}
    for code, site in dev.site_table.items():
        assert observatory(code) == site


def test_dev_set_holds_no_reserved_observation(dev):
    last = max(_utc(dev, i) for i in range(len(dev)))
    assert last < "2026-07-01"
    text = DEV.read_text()
    for reserved in ("2026-07", "2026-08"):
        assert reserved not in "".join(ln for ln in text.splitlines() if not ln.startswith(("#", "!")))


def test_dev_set_arcs(dev):
    months = sorted({_utc(dev, i)[:7] for i in range(len(dev))})
    assert months == ["2025-01", "2025-12", "2026-04", "2026-05"]
    discovery = [i for i in range(len(dev)) if _utc(dev, i).startswith("2025-01")]
    assert len(discovery) == 4 and {str(dev.sites[i]) for i in discovery} == {"W68"}


def test_dev_set_credits_observers_and_compiler():
    head = [ln for ln in DEV.read_text().splitlines() if ln.startswith(("#", "!"))]
    text = "\n".join(head)
    for name in ("Bill Gray", "Project Pluto", "public domain", "J. Tonry", "G. Privett", "P. Wiggins",
                 "N. James", "J.-F. Gout", "Z. Wang", "S. Tilley"):
        assert name in text


@pytest.mark.slow
def test_fit_of_dev_set_keeps_its_arcs(tmp_path):
    """No option: the development set's 2026-04 and 2026-05 arcs (22.5 days apart) fit as one orbit
    with at most 5 % of their observations rejected. A fit of real data has no truth; what it must
    do is agree with the observations it was given, across the arcs.

    History (2026-11-28): before the tracklet-ranging IOD the fit stopped at the IOD (4 exposures in
    the first night); after it (422c74d) it 'converged' with 99 of 327 rejected, whole nights; with
    a 10 % cap (f4c3d47) 28 rejected, still whole nights; fitting the latest arc (88c8e17): 311 of
    311 used from 2026-04-11 to 05-22, the 2025-01 and 2025-12 arcs predicted and reported as
    broken links (RMS miss 3.8e4" and 127")."""
    code = main(["fit", str(DEV), "--out", str(tmp_path / "fit"), "--quiet"])
    rec = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert code == 0 and rec["converged"], rec.get("failure")
    assert rec["arc"]["first_utc"] < "2026-04-12" and rec["arc"]["last_utc"] > "2026-05-22"
    assert rec["n_rejected"] <= 0.05 * (rec["n_used"] + rec["n_rejected"]), rec["n_rejected"]
