"""The on-disk copy of astropy's parsed IERS table (cistrack.astro.iers_cache): the same table and
the same Earth orientation as astropy's own parse, and a clean fall-back to that parse whenever
the copy is stale, corrupt or cannot be written."""
from __future__ import annotations

import os
import shutil

import numpy as np
import pytest
from astropy.utils import iers

from cistrack.astro import iers_cache
from cistrack.astro import timescales as ts


@pytest.fixture(scope="module")
def parsed():
    """astropy's own parse of the default table (never through the cache)."""
    return iers.IERS_Auto.read()


@pytest.fixture
def fresh():
    """No default table chosen yet in this process; the previous one is put back afterwards."""
    kept = iers.IERS_Auto.iers_table
    iers.IERS_Auto.iers_table = None
    yield
    iers.IERS_Auto.iers_table = kept


def _values(col) -> np.ndarray:
    return np.asarray(getattr(col, "value", col))


def _assert_same_table(a, b) -> None:
    assert type(a) is type(b) and a.colnames == b.colnames
    for name in a.colnames:
        x, y = a[name], b[name]
        assert type(x) is type(y), name
        assert getattr(x, "unit", None) == getattr(y, "unit", None), name
        assert (x.info.description, x.info.format) == (y.info.description, y.info.format), name
        assert _values(x).dtype == _values(y).dtype, name
        assert np.array_equal(_values(x), _values(y), equal_nan=_values(x).dtype.kind == "f"), name
        assert np.array_equal(getattr(x, "mask", False), getattr(y, "mask", False)), name
    assert dict(a.meta) == dict(b.meta)
    assert [type(v) for v in a.meta.values()] == [type(v) for v in b.meta.values()]


def _cache_files(directory) -> list[str]:
    return sorted(p.name for p in directory.glob("iers-*.npz"))


def test_the_cached_table_is_the_parsed_one_column_for_column(parsed, fresh, tmp_path):
    assert iers_cache.install(tmp_path) is False                  # parsed, and written
    iers.IERS_Auto.iers_table = None
    assert iers_cache.install(tmp_path) is True                   # read back
    _assert_same_table(iers.IERS_Auto.iers_table, parsed)


def test_the_cached_table_interpolates_to_the_same_bits(parsed, fresh, tmp_path):
    """UT1-UTC, polar motion and the CIP offsets, with their status, over 1973-2027 and past
    the table's end (the offline fallback's side)."""
    iers_cache.save_table(parsed, tmp_path / "t.npz", "k")
    cached = iers_cache.load_table(tmp_path / "t.npz", "k")
    mjd = np.linspace(41684.0, 62500.0, 200_001)
    for method in ("ut1_utc", "pm_xy", "dcip_xy"):
        want = getattr(parsed, method)(mjd, 0.25, return_status=True)
        got = getattr(cached, method)(mjd, 0.25, return_status=True)
        for w, g in zip(want, got):
            assert np.array_equal(_values(w), _values(g), equal_nan=True), method


def test_time_scales_are_bit_identical_through_the_cache(parsed, fresh, tmp_path):
    seconds = np.linspace(0.0, 40 * 86400.0, 97)
    iers.IERS_Auto.iers_table = parsed
    want = ts.time_scales("2025-01-10T03:00:00Z", seconds)
    iers_cache.save_table(parsed, iers_cache.cache_path(tmp_path), iers_cache.cache_key())
    iers.IERS_Auto.iers_table = None
    assert iers_cache.install(tmp_path) is True
    got = ts.time_scales("2025-01-10T03:00:00Z", seconds)
    for scale in ("utc", "tt", "tdb", "ut1"):
        assert all(np.array_equal(w, g) for w, g in zip(getattr(want, scale), getattr(got, scale))), scale
    for field in ("ut1_minus_utc", "xp", "yp", "tabulated"):
        assert np.array_equal(getattr(want.orientation, field), getattr(got.orientation, field)), field


def test_a_stale_copy_is_parsed_again_and_replaced(parsed, fresh, tmp_path):
    path = iers_cache.cache_path(tmp_path)
    shifted = parsed.copy()
    shifted["UT1_UTC"] = shifted["UT1_UTC"] + 1.0 * shifted["UT1_UTC"].unit   # wrong values ...
    iers_cache.save_table(shifted, path, "an-older-key")                        # ... under another key
    assert iers_cache.install(tmp_path) is False
    _assert_same_table(iers.IERS_Auto.iers_table, parsed)
    iers.IERS_Auto.iers_table = None
    assert iers_cache.install(tmp_path) is True                    # rewritten under the current key
    _assert_same_table(iers.IERS_Auto.iers_table, parsed)


@pytest.mark.parametrize("content", [b"", b"PK\x03\x04 not a zip", b"\x93NUMPY garbage"], ids=["empty", "zip", "npy"])
def test_a_corrupt_copy_is_parsed_again_and_replaced(parsed, fresh, tmp_path, content):
    path = iers_cache.cache_path(tmp_path)
    path.write_bytes(content)
    assert iers_cache.install(tmp_path) is False
    _assert_same_table(iers.IERS_Auto.iers_table, parsed)
    iers.IERS_Auto.iers_table = None
    assert iers_cache.install(tmp_path) is True


def test_a_cache_directory_that_cannot_be_made_falls_back_to_the_parse(parsed, fresh, tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a directory")
    assert iers_cache.install(blocker / "cache") is False
    _assert_same_table(iers.IERS_Auto.iers_table, parsed)


def test_a_directory_writable_by_others_is_neither_read_nor_written(parsed, fresh, tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir()
    iers_cache.save_table(parsed, shared / f"iers-{iers_cache.cache_key()}.npz", iers_cache.cache_key())
    os.chmod(shared, 0o777)
    before = _cache_files(shared)
    assert iers_cache.install(shared) is False                     # the planted copy is not read
    _assert_same_table(iers.IERS_Auto.iers_table, parsed)
    assert _cache_files(shared) == before


def test_an_unwritable_copy_leaves_the_parsed_table_and_no_temporary_file(parsed, fresh, tmp_path):
    """The copy's name is taken by a directory: writing fails, the parse is used, nothing is left."""
    iers_cache.cache_path(tmp_path).mkdir()
    assert iers_cache.install(tmp_path) is False
    _assert_same_table(iers.IERS_Auto.iers_table, parsed)
    assert [p.name for p in tmp_path.iterdir()] == [iers_cache.cache_path(tmp_path).name]


def test_the_key_follows_the_source_files(fresh, tmp_path, monkeypatch):
    copy = tmp_path / "finals2000A.all"
    shutil.copyfile(iers.IERS_A_FILE, copy)
    monkeypatch.setattr(iers, "IERS_A_FILE", str(copy))
    key = iers_cache.cache_key()
    os.utime(copy, ns=(0, 10**18))
    assert iers_cache.cache_key() != key


def test_a_finals_file_in_the_working_directory_is_left_to_astropy(fresh, tmp_path, monkeypatch):
    """astropy reads ./finals2000A.all instead of the bundled table: no copy stands in for it."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "finals2000A.all").write_text("")
    assert iers_cache.install(tmp_path / "cache") is False
    assert iers.IERS_Auto.iers_table is None
    assert not (tmp_path / "cache").exists()


def test_a_table_already_chosen_is_kept(parsed, fresh, tmp_path):
    iers.IERS_Auto.iers_table = parsed
    assert iers_cache.install(tmp_path) is False
    assert iers.IERS_Auto.iers_table is parsed
    assert _cache_files(tmp_path) == []
