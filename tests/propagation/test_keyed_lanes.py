"""Keyed stages with lanes in different records: one lane loop with each lane's own record, the
same numbers as when every lane shares a record, and step key rows that say which stages can
skip their own pass."""
from __future__ import annotations

import numpy as np
import pytest

from .table_model import Parity, stage_output, table_stage_case

RECORD = 0.25  # the Table model's record length (its p[0])


def _times(mod, w):
    return w[mod.ROW_T * mod.LANES:(mod.ROW_T + 1) * mod.LANES]


def _step_key(mod, w, stage):
    """(flag, key) of ``stage`` in the step key rows written by ``_lanes_keys``."""
    i = mod.ROW_STEP_KEY * mod.LANES + 2 * stage
    return w[i], w[i + 1]


@pytest.mark.parametrize("stage", [1, 8, 12])
def test_lanes_in_four_records_get_the_numbers_each_would_get_with_all_lanes_in_its_record(stage):
    mod, p, w = table_stage_case()
    spread = w.copy()
    records = np.arange(mod.LANES) % 4 + 3
    _times(mod, spread)[:] = (records + 0.5) * RECORD
    mod._lanes_keys(spread, p)
    getattr(mod, f"_lanes_stage{stage}")(spread, p)
    assert _step_key(mod, spread, stage)[0] == 0.0  # the lanes took the per-lane loop
    for record in range(3, 7):
        alone = w.copy()
        _times(mod, alone)[:] = (record + 0.5) * RECORD
        mod._lanes_keys(alone, p)
        getattr(mod, f"_lanes_stage{stage}")(alone, p)
        lanes = records == record
        assert np.array_equal(stage_output(mod, spread, stage)[:, lanes], stage_output(mod, alone, stage)[:, lanes])


def test_a_lane_whose_record_changes_gets_its_column_of_the_scratch_rows_refilled():
    mod, p, w = table_stage_case()
    reused, fresh = w.copy(), w.copy()
    fresh[mod.ROW_KEY * mod.LANES:] = 0.0  # nothing held
    _times(mod, reused)[0] = 10.5 * RECORD
    mod._lanes_keys(reused, p)
    mod._lanes_stage5(reused, p)  # lane 0 holds record 10, the others record 4
    for work in (reused, fresh):
        _times(mod, work)[:2] = (4.5 * RECORD, 10.5 * RECORD)  # lanes 0 and 1 swap records
        mod._lanes_keys(work, p)
        mod._lanes_stage5(work, p)
    assert np.array_equal(stage_output(mod, reused, 5), stage_output(mod, fresh, 5))


def test_the_step_key_rows_mark_the_stages_whose_lanes_share_a_record():
    """Every lane 0.6 of a step before a record's end: stages at c < 0.6 are in record 4, those
    at c > 0.6 (stages 8, 10, 11, 12) in record 5; one lane a little later splits stage 9 (c = 0.6)."""
    mod, p, w = table_stage_case()
    h = 1e-2
    w[mod.ROW_H * mod.LANES:(mod.ROW_H + 1) * mod.LANES] = h
    _times(mod, w)[:] = 5 * RECORD - 0.6 * h - 1e-5
    _times(mod, w)[3] += 2e-5
    mod._lanes_keys(w, p)
    flags = {s: _step_key(mod, w, s) for s in range(1, 13)}
    assert all(flags[s] == (1.0, 4.0) for s in (1, 2, 3, 4, 5, 6, 7))
    assert all(flags[s] == (1.0, 5.0) for s in (8, 10, 11, 12))
    assert flags[9][0] == 0.0


@pytest.mark.parametrize("stage", [1, 9, 12])
def test_a_step_split_between_records_gives_the_numbers_of_stages_run_without_step_keys(stage):
    """With the step key rows (some stages in one record, stage 9 split) and without them (every
    stage's own pass): the same derivatives bit for bit."""
    mod, p, w = table_stage_case()
    h = 1e-2
    w[mod.ROW_H * mod.LANES:(mod.ROW_H + 1) * mod.LANES] = h
    _times(mod, w)[:] = 5 * RECORD - 0.6 * h - 1e-5
    _times(mod, w)[3] += 2e-5
    keyed, own = w.copy(), w.copy()
    own[mod.ROW_KEY * mod.LANES:] = 0.0  # no step keys, nothing held
    mod._lanes_keys(keyed, p)
    getattr(mod, f"_lanes_stage{stage}")(keyed, p)
    getattr(mod, f"_lanes_stage{stage}")(own, p)
    assert np.array_equal(stage_output(mod, keyed, stage), stage_output(mod, own, stage))


def test_a_record_key_shared_by_every_lane_over_the_whole_step_sets_every_stage_flag():
    """The LaneRecord exit of ``_lanes_keys``: lanes whose first and last stage times are in
    record 4 get every stage's flag and key, whatever the rows held before."""
    mod, p, w = table_stage_case()
    w[mod.ROW_STEP_KEY * mod.LANES:(mod.ROW_STEP_KEY + 1) * mod.LANES] = -7.0
    mod._lanes_keys(w, p)
    assert all(_step_key(mod, w, s) == (1.0, 4.0) for s in range(1, 13))


def test_a_key_that_goes_back_within_a_step_is_taken_at_every_stage_time():
    """A periodic index (LaneUniform, not LaneRecord) with the step's first and last stage times
    in records 4 and 6 (index 0) and stages 8 and 9 (c = 0.65 and 0.6) in record 5 (index 1):
    the first and last stage times alone would miss them."""
    mod, p, w = table_stage_case(model=Parity(np.r_[RECORD, 1.0, -1.0]))
    h = 2.0 * RECORD
    w[mod.ROW_H * mod.LANES:(mod.ROW_H + 1) * mod.LANES] = h
    _times(mod, w)[:] = 4 * RECORD
    mod._lanes_keys(w, p)
    assert _step_key(mod, w, 1) == (1.0, 0.0) and _step_key(mod, w, 12) == (1.0, 0.0)
    assert _step_key(mod, w, 8) == (1.0, 1.0) and _step_key(mod, w, 9) == (1.0, 1.0)
