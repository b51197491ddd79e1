"""The maneuver entities of a recording (issue 52, item 6), read back from a real run of the
built-in scenario example-1-burn (1 m/s burn at 3.62 d, detected at 5.11 d; PGM with 2,000
particles, which still detects it): the truth burn at its time in the text log, on the NEES and
detector panels and as an arrow in the scene; the detector's statistic and threshold; detection
markers after the burn; the estimated burn at the end; and the panels of the default blueprint.
A run without a burn (the shared small run of conftest) records no burn entity."""
from __future__ import annotations

from datetime import timedelta

import numpy as np
import pytest
from rerun.chunk import RrdReader

from cistrack import units
from cistrack.plugin.registry import load_registry
from cistrack.plugins.recorders import maneuver_marks as mm
from cistrack.plugins.recorders.run_series import nees_y_range
from cistrack.results.store import read_steps
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.scenario.settings import apply_settings
from cistrack.units import LU_KM, TU_S, parse_utc

from .rrd_reading import component, last_per_step, read_entities

SMALL = ["filter.n_particles=2000", "iod.n_particles=2000"]


@pytest.fixture(scope="module")
def burn_run(tmp_path_factory):
    reg = load_registry()
    scen = apply_settings(load_scenario("example-1-burn", reg), SMALL)
    d = tmp_path_factory.mktemp("burn")
    rec = reg.create("recorder", "rerun", path=str(d / "burn.rrd"), max_points=200)
    res = run_scenario(scen, registry=reg, observers=[rec], output_dir=d / "out")
    return res, read_entities(d / "burn.rrd"), read_steps(d / "out"), d / "burn.rrd"


def _utc_ns(ctx, t_tu: float) -> int:
    """``t_tu`` on the ``utc`` timeline as the reader returns it (ns since the unix epoch)."""
    t = parse_utc(ctx.epoch) + timedelta(seconds=float(t_tu) * TU_S)
    return round(t.timestamp() * 1e9)


def _texts(rows) -> list[str]:
    return [str(r.components["TextLog:text"][0]) for r in rows]


def _scalars(rows) -> list[tuple[dict, float]]:
    return [(r.times, float(component(r, "Scalars:scalars")[0])) for r in rows if "Scalars:scalars" in r.components
            and r.components["Scalars:scalars"] is not None]


def view_names(rrd) -> set[str]:
    """The names of the default blueprint's views."""
    reader = RrdReader(str(rrd))
    out = set()
    for chunk in reader.stream(store=reader.blueprints()[0]):
        batch = chunk.to_record_batch()
        if "ViewBlueprint:display_name" in batch.schema.names:
            out.update(n for v in batch.column("ViewBlueprint:display_name").to_pylist() if v for n in v)
    return out


def test_the_burn_is_on_the_timeline_at_its_time(burn_run):
    res, ent, table, _ = burn_run
    ctx = res.context
    (imp,) = ctx.truth_impulses
    at = _utc_ns(ctx, imp.t)
    rows = ent[f"/{mm.TRUTH_LOG}"]
    assert [r.times for r in rows] == [{"utc": at}]  # on utc only: the burn is no step of the filter
    assert _texts(rows) == ["truth burn: 1 m/s in-track (rtn-moon), at 3.620 d, |dv| 1 m/s"]
    nees = _scalars(ent[f"/{mm.NEES_BURNS}/1"])
    assert {tuple(t.items()) for t, _ in nees} == {(("utc", at),)}
    assert [v for _, v in nees] == pytest.approx(list(nees_y_range()))  # across the NEES panel
    stat = _scalars(ent[f"/{mm.STATISTIC_BURNS}/1"])
    assert {t["utc"] for t, _ in stat} == {at}
    # from 0 to the detector panel's whole height: the run's largest statistic, at least twice the threshold
    largest = np.nanmax(np.asarray(table.column("maneuver_statistic").to_pylist(), dtype=float))
    top = max(largest, 2.0 * res.context.maneuvers.detector.threshold)
    assert [min(v for _, v in stat), max(v for _, v in stat)] == pytest.approx([0.0, top])
    style = [r for r in ent[f"/{mm.NEES_BURNS}/1"] if not r.times][0]
    assert style.components["SeriesLines:aggregation_policy"] is not None  # off: the line stays drawn


def test_the_burn_arrow_starts_at_the_truth_and_points_along_its_velocity_jump(burn_run):
    res, ent, _, _ = burn_run
    ctx = res.context
    (imp,) = ctx.truth_impulses
    (row,) = ent[f"/{mm.BURN_ARROWS}"]
    assert not row.times  # static, like the truth trajectory
    np.testing.assert_allclose(component(row, "Arrows3D:origins")[0], ctx.truth_at(imp.t)[:3] * LU_KM, rtol=1e-6)
    vec = component(row, "Arrows3D:vectors")[0]
    assert np.linalg.norm(vec) == pytest.approx(mm.BURN_ARROW_KM, rel=1e-6)
    assert vec @ imp.dv / (np.linalg.norm(vec) * np.linalg.norm(imp.dv)) == pytest.approx(1.0, abs=1e-6)


def test_the_burn_is_named_off_the_earth_moon_line_where_the_moon_label_sits(burn_run):
    res, ent, _, _ = burn_run
    (arrow,) = ent[f"/{mm.BURN_ARROWS}"]
    assert "Arrows3D:labels" not in arrow.components or not arrow.components["Arrows3D:labels"]
    (row,) = ent[f"/{mm.BURN_LABELS}"]
    assert row.components["Points3D:labels"] == ["burn: 1 m/s in-track (rtn-moon)"]
    at = component(row, "Points3D:positions")[0]
    origin = component(arrow, "Arrows3D:origins")[0]
    moon = component(ent["/world/moon"][0], "Ellipsoids3D:centers")[0]
    # the system view looks down on the x-y plane: screen distance is the x-y distance
    assert abs(at[1] - origin[1]) == pytest.approx(mm.BURN_LABEL_OFFSET_KM)
    assert np.linalg.norm((at - moon)[:2]) >= mm.BURN_LABEL_OFFSET_KM - abs(origin[1])
    assert abs(at[1]) > abs(origin[1])  # moved away from the line of Earth, Moon and L1..L5 labels


def test_the_statistic_and_its_threshold_are_series_at_every_update(burn_run):
    _, ent, table, _ = burn_run
    steps = np.asarray(table.column("step").to_pylist())
    stat = np.asarray(table.column("maneuver_statistic").to_pylist(), dtype=float)
    expected = {int(s): v for s, v in zip(steps, stat) if np.isfinite(v)}
    assert len(expected) > 20
    values = [r for r in ent[f"/{mm.STATISTIC}"] if "Scalars:scalars" in r.components]  # not the line breaks
    logged = {s: float(component(r, "Scalars:scalars")[0]) for s, r in last_per_step(values).items()}
    assert logged == expected
    thresholds = {float(component(r, "Scalars:scalars")[0]) for r in ent[f"/{mm.THRESHOLD}"] if r.times}
    assert thresholds == {4.0}  # -log10 of the detector's false-alarm probability 1e-4
    assert len(last_per_step(ent[f"/{mm.THRESHOLD}"])) == len(expected)


def test_the_statistic_line_ends_at_the_last_update_of_each_pass_but_the_last(burn_run):
    res, ents, steps, _ = burn_run
    cols = {c: steps.column(c).to_pylist() for c in ("pass_index", "t_tu", "maneuver_statistic")}
    last: dict[int, float] = {}
    for p, t, stat in zip(cols["pass_index"], cols["t_tu"], cols["maneuver_statistic"]):
        if stat is not None and np.isfinite(stat):
            last[int(p)] = max(last.get(int(p), -np.inf), float(t))
    last_of_pass = sorted(last.values())[:-1]
    assert len(last_of_pass) >= 4
    clears = [r for r in ents[f"/{mm.STATISTIC}"] if any("Clear" in k for k in r.components)]
    assert sorted(r.times["utc"] for r in clears) == [_utc_ns(res.context, t) for t in last_of_pass]
    by_time = {r.times["utc"]: r for r in ents[f"/{mm.STATISTIC}"] if "Scalars:scalars" in r.components}
    for c in clears:  # logged after the pass's last value, at its step and event too
        value = by_time[c.times["utc"]]
        assert (c.times["step"], c.times["event"]) == (value.times["step"], value.times["event"])
        assert c.row_id > value.row_id


def test_each_detection_is_marked_on_the_statistic_and_the_nees_after_the_burn(burn_run):
    res, ent, table, _ = burn_run
    ctx = res.context
    (imp,) = ctx.truth_impulses
    steps = table.column("step").to_pylist()
    fired = [s for s, d in zip(steps, table.column("maneuver_detected").to_pylist()) if d == 1.0]
    assert fired, "the run must detect the burn"
    on_stat = last_per_step(ent[f"/{mm.DETECTIONS}"])
    assert sorted(on_stat) == fired
    stat = dict(zip(steps, table.column("maneuver_statistic").to_pylist()))
    nees = dict(zip(steps, table.column("nees").to_pylist()))
    for s, r in on_stat.items():
        assert r.times["utc"] > _utc_ns(ctx, imp.t)
        assert float(component(r, "Scalars:scalars")[0]) == pytest.approx(stat[s])
    on_nees = last_per_step(ent[f"/{mm.NEES_DETECTIONS}"])
    assert sorted(on_nees) == fired
    for s, r in on_nees.items():
        assert float(component(r, "Scalars:scalars")[0]) == pytest.approx(np.log10(nees[s]))
    texts = _texts(ent[f"/{mm.DETECTION_LOG}"])
    assert len(texts) == len(fired) and all("maneuver detected at" in t and "> threshold 4" in t for t in texts)
    styles = [r for r in ent[f"/{mm.DETECTIONS}"] if not r.times]
    assert styles and styles[0].components["SeriesPoints:names"] == ["detection"]


def test_the_estimated_burns_are_logged_at_the_end(burn_run):
    res, ent, _, _ = burn_run
    ctx = res.context
    estimates = res.summary.maneuvers
    assert estimates and estimates[0]["confirmed"]
    texts = _texts(ent[f"/{mm.ESTIMATE_LOG}"])
    assert texts == [mm.estimate_text(m) for m in estimates]
    first = estimates[0]
    assert texts[0].startswith(f"estimated burn at {first['t_burn_days']:.3f} d")
    assert f"delta-v {first['delta_v_ms']:.3g} ± " in texts[0] and texts[0].endswith("confirmed")
    (mark,) = [r for r in ent[f"/{mm.ESTIMATED_BURNS}"] if r.times]
    assert mark.times == {"utc": _utc_ns(ctx, units.days_to_tu(first["t_burn_days"]))}


def test_the_blueprint_shows_the_maneuver_panels(burn_run):
    names = view_names(burn_run[3])
    assert any(n.startswith("Maneuver test -log10 p") for n in names)
    assert "Maneuvers: truth burns, detections, estimates" in names
    assert any(n.startswith("log10 NEES") and "burns orange" in n for n in names)


def test_a_run_without_a_burn_records_no_burn_entity(recorded_run):
    ent = read_entities(recorded_run.full_rrd)
    assert not recorded_run.result.context.truth_impulses
    assert not [e for e in ent if "burn" in e or e.startswith("/maneuvers")]
    names = view_names(recorded_run.full_rrd)
    assert "Maneuvers: truth burns, detections, estimates" not in names
    assert not any("burn" in n and "NEES" in n for n in names)
    # the run watches for maneuvers (the default, without a [maneuvers] table): the statistic and
    # its panel are there; no detection, so no marker
    assert recorded_run.result.context.maneuvers is not None
    assert {f"/{mm.STATISTIC}", f"/{mm.THRESHOLD}"} <= set(ent)
    assert any(n.startswith("Maneuver test") for n in names)
    assert not {f"/{mm.DETECTIONS}", f"/{mm.NEES_DETECTIONS}"} & set(ent)


def test_the_estimate_text_says_when_there_is_no_delta_v():
    text = mm.estimate_text({"t_days": 5.1, "t_burn_days": None, "delta_v_ms": None, "delta_v_sigma_ms": None,
                             "confirmed": False})
    assert text == "burn time not estimated (detected at 5.100 d): no delta-v estimate, unconfirmed"


def test_the_estimate_text_gives_the_burn_time_its_sigma_and_the_delta_v():
    text = mm.estimate_text({"t_days": 5.112, "t_burn_days": 3.692, "t_burn_sigma_days": 0.081, "delta_v_ms": 1.02,
                             "delta_v_sigma_ms": 0.095, "confirmed": True})
    assert text == "estimated burn at 3.692 d ± 1.9 h (detected at 5.112 d): delta-v 1.02 ± 0.095 m/s, confirmed"
