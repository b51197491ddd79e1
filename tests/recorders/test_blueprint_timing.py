"""The blueprint's time settings: playback that plays a run in about a minute, series x axes
whose end dates are drawn whole."""
from __future__ import annotations

from datetime import timedelta

import numpy as np
import pytest

from cistrack.plugins.recorders.blueprint import AXIS_MARGIN, PLAYBACK_S, axis_range_s, playback_speed
from cistrack.plugins.recorders.run_extents import utc_range_s
from cistrack.units import TU_S, parse_utc


def test_playback_speed_plays_the_whole_run_in_about_a_minute(recorded_run):
    ctx = recorded_run.result.context
    epoch = parse_utc(ctx.epoch)
    start, end = utc_range_s(ctx, epoch)
    for ev in recorded_run.log.events:  # every step lies in the range
        t = (epoch + timedelta(seconds=ev.t * TU_S)).timestamp()
        assert start - 1e-3 <= t <= end + 1e-3
    assert (end - start) / playback_speed((start, end)) == pytest.approx(PLAYBACK_S)
    assert playback_speed(None) == 1.0


@pytest.mark.parametrize("start_h, span_h", [(0.0, 24.0), (1.35, 46.6), (23.9, 30.0), (12.0, 6.0), (5.0, 90.0)])
def test_axis_range_keeps_half_day_ticks_off_the_edges(start_h, span_h):
    t0 = parse_utc("2026-01-01T00:00:00Z").timestamp()
    start, end = t0 + start_h * 3600.0, t0 + (start_h + span_h) * 3600.0
    lo, hi = axis_range_s(start, end)
    assert lo <= start and hi >= end
    assert (hi - lo) < 2.0 * (end - start) + 86_400.0
    ticks = np.arange(np.ceil(lo / 43_200.0), np.floor(hi / 43_200.0) + 1) * 43_200.0
    margin = AXIS_MARGIN * (hi - lo)
    assert np.all((ticks >= lo + margin * 0.999) & (ticks <= hi - margin * 0.999))


def test_a_long_run_is_padded_on_both_sides():
    lo, hi = axis_range_s(0.0, 100 * 86_400.0)
    assert lo == pytest.approx(-AXIS_MARGIN * 100 * 86_400.0) and hi == pytest.approx(100 * 86_400.0 * (1 + AXIS_MARGIN))


@pytest.mark.parametrize("live", [False, True])
@pytest.mark.parametrize("with_inputs", [False, True])
def test_the_blueprint_builds_in_strict_mode(live, with_inputs):
    """rerun turns some bad blueprint arguments (shapes, types) into logged warnings; strict mode
    raises them."""
    import rerun as rr

    from cistrack.plugins.recorders.blueprint import default_blueprint

    system = np.array([[-4671.0, 0.0, 0.0], [3.8e5, 0.0, 0.0], [4.4e5, 0.0, 0.0]]) if with_inputs else None
    span = (1.7e9, 1.7e9 + 2 * 86_400.0) if with_inputs else None
    strict = rr.strict_mode()
    rr.set_strict_mode(True)
    try:
        default_blueprint(system, span, live=live)
    finally:
        rr.set_strict_mode(strict)
