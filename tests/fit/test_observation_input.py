"""Observation files for `cistrack fit`: formats, several files merged, several objects split."""
from __future__ import annotations

import math
from datetime import datetime, timedelta

import numpy as np
import pytest

from cistrack.errors import ConfigError, MeasurementError
from cistrack.fitting.observation_input import read_object_observations
from cistrack.plugin.registry import default_registry
from cistrack.runs.observation_files import SeveralObjectsError, read_observations
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"


def _psv_lines():
    return (DATA / "observations.psv").read_text().splitlines()


def _two_objects(tmp_path):
    """The shipped file with every observation also given for a second object at the same times."""
    lines = _psv_lines()
    header, rows = lines[:2], lines[2:]
    p = tmp_path / "two.psv"
    p.write_text("\n".join(header + rows + [r.replace("cis0001", "cis0002", 1) for r in rows]) + "\n")
    return p


def test_a_file_of_one_object_gives_one_set_with_its_designation():
    objs = read_object_observations([DATA / "observations.psv"], default_registry())
    assert [o.designation for o in objs] == ["cis0001"]
    assert len(objs[0].measurements) == 65


def test_a_file_of_two_objects_gives_one_set_per_object(tmp_path):
    objs = read_object_observations([_two_objects(tmp_path)], default_registry())
    assert [o.designation for o in objs] == ["cis0001", "cis0002"]
    assert [len(o.measurements) for o in objs] == [65, 65]


def test_a_reader_refuses_several_objects_naming_them_and_the_parameter(tmp_path):
    with pytest.raises(SeveralObjectsError, match="cis0002.*designation"):
        read_observations(_two_objects(tmp_path), "2026-03-01T00:00:00Z")


def test_the_designation_parameter_reads_one_object(tmp_path):
    ms = read_observations(_two_objects(tmp_path), "2026-03-01T00:00:00Z", designation="cis0002")
    assert len(ms) == 65 and ms.meta["object"] == "cis0002"


def test_two_files_of_one_object_merge_in_time_order(tmp_path):
    lines = _psv_lines()
    header, rows = lines[:2], lines[2:]
    a, b = tmp_path / "a.psv", tmp_path / "b.psv"
    a.write_text("\n".join(header + rows[::2]) + "\n")
    b.write_text("\n".join(header + rows[1::2]) + "\n")
    objs = read_object_observations([a, b], default_registry())
    whole = read_object_observations([DATA / "observations.psv"], default_registry())[0].measurements
    assert len(objs) == 1
    np.testing.assert_array_equal(objs[0].measurements.times, whole.times)
    np.testing.assert_array_equal(objs[0].measurements.sites, whole.sites)


def test_the_same_observations_in_two_files_are_used_once_and_the_dropped_copies_counted():
    objs = read_object_observations([DATA / "observations.psv", DATA / "observations.tdm"], default_registry())
    assert len(objs[0].measurements) == 65
    assert "observations.tdm: 65 observations dropped as duplicates of those in observations.psv" in objs[0].notes[-1]


def test_a_file_without_a_known_suffix_is_read_by_its_content(tmp_path):
    p = tmp_path / "observations.txt"
    p.write_text((DATA / "observations.psv").read_text())
    objs = read_object_observations([p], default_registry())
    assert len(objs[0].measurements) == 65


def test_files_of_one_name_in_different_folders_are_told_apart_in_the_notes(tmp_path):
    copies = []
    for folder in ("night1", "night2"):
        (tmp_path / folder).mkdir()
        copies.append(tmp_path / folder / "observations.psv")
        copies[-1].write_text((DATA / "observations.psv").read_text())
    notes = read_object_observations(copies, default_registry())[0].notes
    assert notes[0].startswith("night1/observations.psv: 65 observations of cis0001")
    assert notes[-1].startswith("night2/observations.psv: 65 observations dropped as duplicates of those in "
                                "night1/observations.psv")


@pytest.mark.parametrize("second", ["same", "spelled", "link"])
def test_one_file_given_twice_is_refused_naming_both(tmp_path, monkeypatch, second):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "night").mkdir()
    first = tmp_path / "night" / "obs.psv"
    first.write_text((DATA / "observations.psv").read_text())
    if second == "link":
        (tmp_path / "link.psv").symlink_to(first)
    other = {"same": first, "spelled": "./night/../night/obs.psv", "link": "link.psv"}[second]
    with pytest.raises(ConfigError, match=f"{other}: the same file as {first}, given before it; give each file once"):
        read_object_observations([first, other], default_registry())


def test_a_file_no_reader_reads_is_refused_with_each_readers_reason(tmp_path):
    p = tmp_path / "notes.txt"
    p.write_text("hello\n")
    with pytest.raises(MeasurementError, match="no reader reads its content.*ades-psv"):
        read_object_observations([p], default_registry())


def test_a_copy_with_its_times_rounded_to_the_second_is_a_duplicate(tmp_path):
    out = []
    for line in (DATA / "observations.psv").read_text().splitlines():
        f = line.split("|")
        if len(f) > 5 and f[3].endswith("Z") and "T" in f[3]:
            t = datetime.strptime(f[3], "%Y-%m-%dT%H:%M:%S.%fZ") + timedelta(microseconds=500_000)
            f[3] = t.strftime("%Y-%m-%dT%H:%M:%SZ")  # to the nearest second
            f[4], f[5] = f"{float(f[4]):.5f}", f"{float(f[5]):.5f}"
        out.append("|".join(f))
    rounded = tmp_path / "rounded.psv"
    rounded.write_text("\n".join(out) + "\n")
    objs = read_object_observations([DATA / "observations.psv", rounded], default_registry())
    assert len(objs[0].measurements) == 65
    assert "rounded.psv: 65 observations dropped as duplicates" in objs[0].notes[-1]


def test_a_reader_parameter_of_one_format_goes_to_that_formats_files_only():
    objs = read_object_observations([DATA / "observations.psv", DATA / "observations.tdm"], default_registry(),
                                    reader_params={"check_degrees": False})
    assert len(objs) == 1 and len(objs[0].measurements) > 0


def test_a_reader_parameter_no_reader_of_the_files_takes_is_refused_by_name():
    with pytest.raises(ConfigError, match="reader parameter 'range_alpha': no reader of the files given takes it"):
        read_object_observations([DATA / "observations.psv", DATA / "observations.tdm"], default_registry(),
                                 reader_params={"range_alpha": 0.1})


def _shifted(row: str, seconds: float, dec_arcsec: float = 0.0, ra_arcsec: float = 0.0) -> str:
    """``row`` ``seconds`` later, its dec and ra (on the sky) moved by ``dec_arcsec`` and ``ra_arcsec``."""
    f = row.split("|")
    f[3] = (datetime.strptime(f[3], "%Y-%m-%dT%H:%M:%S.%fZ") + timedelta(seconds=seconds)).strftime(
        "%Y-%m-%dT%H:%M:%S.%fZ")
    if ra_arcsec:
        f[4] = repr(float(f[4]) + ra_arcsec / 3600.0 / math.cos(math.radians(float(f[5]))))
    if dec_arcsec:
        f[5] = repr(float(f[5]) + dec_arcsec / 3600.0)
    return "|".join(f)


def _again(tmp_path, seconds: float, dec_arcsec: float = 0.0):
    """The shipped file (65 rows) read with every row given again ``seconds`` later, its dec moved by ``dec_arcsec``."""
    lines = _psv_lines()
    header, rows = lines[:2], [r for r in lines[2:] if r]
    p = tmp_path / "again.psv"
    p.write_text("\n".join(header + rows + [_shifted(r, seconds, dec_arcsec) for r in rows]) + "\n")
    return read_object_observations([p], default_registry())[0]


def test_observations_repeated_within_one_file_are_used_once_and_the_repeats_counted(tmp_path):
    """Probe L5: every row given again 0.2 s later in the same file, its angles as they were, had been
    used twice without a word (the cross-file duplicate rule did not look inside one file); now the
    later copy is dropped and a note names the file, the count and the rule."""
    lines = _psv_lines()
    header, rows = lines[:2], [r for r in lines[2:] if r]
    p = tmp_path / "twice.psv"
    p.write_text("\n".join(header + rows + [_shifted(r, 0.2) for r in rows]) + "\n")
    objs = read_object_observations([p], default_registry())
    whole = read_object_observations([DATA / "observations.psv"], default_registry())[0].measurements
    np.testing.assert_array_equal(objs[0].measurements.times, whole.times)
    assert objs[0].measurements.meta["duplicates_dropped"] == 65
    assert ("twice.psv: 65 observations dropped as repeats within the file (the same site and type as an earlier "
            "row, times within 1 s at the same position to 0.001 arcsec") in objs[0].notes[-1]


@pytest.mark.parametrize("seconds", [0.3, 0.864, 1.0])
def test_rows_given_again_at_the_same_position_within_a_second_are_used_once(tmp_path, seconds):
    """Probe M7: every row given again 0.3 s or 1 s later with the same angles (one measurement
    reduced twice, its time rounded otherwise) had been used twice without a word, the sigmas
    shrinking by sqrt(2)."""
    obj = _again(tmp_path, seconds)
    assert len(obj.measurements) == 65 and obj.measurements.meta["duplicates_dropped"] == 65
    assert "again.psv: 65 observations dropped as repeats within the file" in obj.notes[-1]


def test_exposures_a_tenth_of_a_second_apart_at_other_positions_are_all_kept(tmp_path):
    """Probe N12: a dense survey's or video's frames 0.1 s apart, 0.4 arcsec apart by noise, had
    been dropped as repeats (438 of 6,000); a repeat is the same position, not a near one."""
    obj = _again(tmp_path, 0.1, dec_arcsec=0.4)
    assert len(obj.measurements) == 130 and not any("repeat" in n for n in obj.notes)


def test_rows_exactly_a_second_apart_at_the_same_position_are_all_repeats(tmp_path):
    """Probe M7: at the rule's limit the float times must not keep some pairs (at 0.25 s 16 of 80 had been kept)."""
    obj = _again(tmp_path, 1.0)
    assert len(obj.measurements) == 65 and obj.measurements.meta["duplicates_dropped"] == 65


def test_the_old_repeat_time_is_still_importable_with_a_deprecation_warning():
    import cistrack.fitting.observation_input as oi

    with pytest.warns(DeprecationWarning, match="REPEAT_S no longer sets a rule"):
        assert oi.REPEAT_S == 0.25


def test_the_repeat_note_does_not_claim_each_observation_is_used_once(tmp_path):
    assert "each observation is used once" not in " ".join(_again(tmp_path, 0.2).notes)


def test_rows_of_one_file_a_second_apart_at_other_positions_are_not_repeats(tmp_path):
    """A moving object's exposures a second apart: 0.3 arcsec of motion or noise apart, both kept."""
    obj = _again(tmp_path, 1.0, dec_arcsec=0.3)
    assert len(obj.measurements) == 130 and not any("repeat" in n for n in obj.notes)


def test_exposures_0_4_s_apart_of_a_moving_object_are_all_kept(tmp_path):
    """The cadence of benchmarks/bench_fit.py --make-dense: each row's twin 0.4 s later has moved
    0.2 arcsec in RA (0.5 arcsec/s) and carries its own 0.5 arcsec noise in dec (seeded)."""
    lines = _psv_lines()
    header, rows = lines[:2], [r for r in lines[2:] if r]
    noise = np.random.default_rng(20261201).normal(0.0, 0.5, len(rows))
    p = tmp_path / "dense.psv"
    p.write_text("\n".join(header + rows + [_shifted(r, 0.4, float(d), 0.2) for r, d in zip(rows, noise)]) + "\n")
    assert len(read_object_observations([p], default_registry())[0].measurements) == 130


def _mpc_to_five_decimals(path) -> None:
    """``path`` (MPC 80-column) with each time rounded to 1e-5 day, as many programs write it."""
    lines = []
    for line in path.read_text().splitlines():
        day = f"{round(float(line[23:32]), 5):08.5f}"
        lines.append(line[:23] + day + " " + line[32:])
    path.write_text("\n".join(lines) + "\n")


def test_a_copy_in_mpc_80_column_with_times_to_1e_5_day_is_used_once(tmp_path):
    """Probe N (M7 across formats): the shipped ADES observations given again as MPC 80-column with
    times rounded to 1e-5 day (0.864 s) had been used twice but for 5 of them: the format's own
    resolution (1e-6 day) was taken for the file's."""
    from cistrack.runs.observation_files import write_observations

    ms = read_observations(DATA / "observations.psv", "2026-03-01T00:00:00Z")
    write_observations(tmp_path / "copy.obs", ms, "2026-03-01T00:00:00Z")
    _mpc_to_five_decimals(tmp_path / "copy.obs")
    [obj] = read_object_observations([DATA / "observations.psv", tmp_path / "copy.obs"], default_registry())
    assert len(obj.measurements) == len(ms) and obj.measurements.meta["duplicates_dropped"] == len(ms)


def _case_twins_file(tmp_path):
    """The shipped file with its odd rows given for the same designation in upper case."""
    lines = _psv_lines()
    header, rows = lines[:2], lines[2:]
    p = tmp_path / "case.psv"
    p.write_text("\n".join(header + rows[::2] + [r.replace("cis0001", "CIS0001", 1) for r in rows[1::2]]) + "\n")
    return p


def test_designations_differing_only_in_case_are_two_objects_and_said_so(tmp_path):
    said = []
    objs = read_object_observations([_case_twins_file(tmp_path)], default_registry(), log=said.append)
    assert [o.designation for o in objs] == ["cis0001", "CIS0001"]
    assert any("'cis0001' and 'CIS0001' differ only in letter case" in m for m in said)
    assert all(any("differ only in letter case" in n for n in o.notes) for o in objs)


def test_distinct_designations_are_not_said_to_differ_in_case(tmp_path):
    said = []
    read_object_observations([_two_objects(tmp_path)], default_registry(), log=said.append)
    assert not any("letter case" in m for m in said)
