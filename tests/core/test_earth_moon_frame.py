"""The real Earth-Moon rotating frame: exact inverse transforms, an orthonormal right-handed
rotation, the Moon on the +x axis at rest, and velocity transport terms that match finite
differences of the positions."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.astro.ephemeris import DAY_S
from cistrack.astro.earth_moon import EarthMoonFrame

JD0 = (2_461_041.5, 0.0)  # 2026-01-01 00:00 TDB
T = np.linspace(0.0, 8.0, 17)  # TU (~35 days: a full lunar month)


@pytest.fixture(scope="module")
def frame():
    return EarthMoonFrame(JD0)


@pytest.fixture
def states(rng):
    s = rng.normal(size=(T.size, 6))
    s[:, :3] *= 0.5
    s[:, 0] += 1.0
    return s


def test_synodic_gcrs_round_trip_is_exact(frame, states):
    back = frame.gcrs_to_synodic(frame.synodic_to_gcrs(states, T), T)
    assert np.max(np.abs(back - states)) < 1e-12


def test_pulsating_gcrs_round_trip_is_exact(frame, states):
    back = frame.gcrs_to_pulsating(frame.pulsating_to_gcrs(states, T), T)
    assert np.max(np.abs(back - states)) < 1e-12


def test_rotation_is_orthonormal_and_right_handed(frame):
    rot = frame.axes(T).rotation
    eye = np.einsum("kji,kjl->kil", rot, rot)
    assert np.max(np.abs(eye - np.eye(3))) < 1e-14
    assert np.allclose(np.linalg.det(rot), 1.0, atol=1e-14)


def test_moon_sits_on_the_x_axis_at_rest(frame):
    dd = T * units.TU_S / DAY_S
    r, v = frame.ephemeris.moon(JD0[0], JD0[1] + dd)
    moon = frame.gcrs_to_synodic(np.hstack([r, v]), T)
    d = np.linalg.norm(r, axis=1)
    np.testing.assert_allclose(moon[:, 0], (1.0 - frame.mu) * d / units.LU_KM, rtol=1e-14)
    assert np.max(np.abs(moon[:, 1:3])) < 1e-14
    # in the constant-unit frame the Moon moves only along x, at (1 - mu) d'
    assert np.max(np.abs(moon[:, 4:6])) < 1e-12
    np.testing.assert_allclose(moon[:, 0], frame.moon_synodic(T)[:, 0], rtol=1e-15)
    assert 0.92 < moon[:, 0].min() and moon[:, 0].max() < 1.06


def test_earth_and_moon_are_fixed_in_the_pulsating_frame(frame):
    dd = T * units.TU_S / DAY_S
    r, v = frame.ephemeris.moon(JD0[0], JD0[1] + dd)
    moon = frame.gcrs_to_pulsating(np.hstack([r, v]), T)
    earth = frame.gcrs_to_pulsating(np.zeros((T.size, 6)), T)
    expect_moon = np.array([1.0 - frame.mu, 0, 0, 0, 0, 0])
    expect_earth = np.array([-frame.mu, 0, 0, 0, 0, 0])
    assert np.max(np.abs(moon - expect_moon)) < 1e-13
    assert np.max(np.abs(earth - expect_earth)) < 1e-13


@pytest.mark.parametrize("scaling", ["synodic", "pulsating"])
def test_gcrs_velocity_is_the_derivative_of_gcrs_position_along_a_frame_fixed_path(frame, scaling):
    """A point moving with constant frame coordinates: its GCRS velocity (transport terms) must
    equal the finite difference of its GCRS positions."""
    to_gcrs = getattr(frame, f"{scaling}_to_gcrs")
    rho = np.array([1.1, -0.05, 0.2])
    rho_dot = np.array([0.01, -0.02, 0.03])  # frame units of velocity
    h = 1e-4  # TU (37.5 s)
    for t in (0.3, 2.0, 5.7):
        if scaling == "synodic":
            path = lambda tt: np.concatenate([rho + rho_dot * (tt - t), rho_dot])  # noqa: E731
        else:
            # pulsating velocity unit is d h/d^2 per second: integrate rho in that clock
            rate = frame.axes(t).angular_rate[0] * units.TU_S
            path = lambda tt: np.concatenate([rho + rho_dot * rate * (tt - t), rho_dot])  # noqa: E731
        xp = to_gcrs(path(t + h), t + h)
        xm = to_gcrs(path(t - h), t - h)
        x0 = to_gcrs(path(t), t)
        fd = (xp[:3] - xm[:3]) / (2.0 * h * units.TU_S)
        assert np.max(np.abs(fd - x0[3:])) < 1e-7  # km/s (|v| ~ 1 km/s)


def test_synodic_and_pulsating_agree_where_distance_is_lu_and_rate_is_one_over_tu(frame):
    """The two scalings differ only by d/LU and (h/d)/VU: check the relation directly."""
    ax = frame.axes(1.0)
    s = np.array([0.9, 0.1, -0.1, 0.02, 0.01, 0.0])
    g = frame.pulsating_to_gcrs(s, 1.0)
    syn = frame.gcrs_to_synodic(g, 1.0)
    d = ax.distance[0]
    np.testing.assert_allclose(syn[:3], s[:3] * d / units.LU_KM, rtol=1e-13)


def test_malformed_states_are_refused(frame):
    with pytest.raises(ValueError, match="shape"):
        frame.synodic_to_gcrs(np.zeros((3, 5)), 0.0)
    with pytest.raises(ValueError, match="one time per state"):
        frame.synodic_to_gcrs(np.zeros((3, 6)), [0.0, 1.0])
    with pytest.raises(ValueError, match="finite"):
        frame.synodic_to_gcrs(np.full(6, np.nan), 0.0)


def test_the_frame_at_one_time_is_kept_read_only_and_equals_a_fresh_evaluation():
    frame = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    first = frame.axes(1.25)
    assert frame.axes(np.float64(1.25)) is first and frame.axes(np.array([1.25])) is first
    fresh = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")._evaluate_axes(np.array([1.25]))
    for name, arr in vars(first).items():
        assert not arr.flags.writeable
        assert np.array_equal(arr, getattr(fresh, name))
    with pytest.raises(ValueError, match="read-only"):
        first.rotation[0, 0, 0] = 0.0


@pytest.fixture
def nothing_kept(monkeypatch):
    """An empty table of kept axes for the test (other tests' frames share the process's one)."""
    from cistrack.astro import earth_moon

    monkeypatch.setattr(earth_moon, "_kept_by_frame", {})
    return earth_moon


def test_at_most_axes_kept_times_are_kept_the_oldest_going_first(monkeypatch, nothing_kept):
    monkeypatch.setattr(nothing_kept, "AXES_KEPT", 3)
    frame = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    kept = [frame.axes(t) for t in (0.0, 0.1, 0.2, 0.3)]
    assert frame.axes(0.3) is kept[3] and frame.axes(0.1) is kept[1]
    assert frame.axes(0.0) is not kept[0]  # dropped when the fourth time came


def test_several_times_at_once_are_evaluated_together_and_kept_as_a_set(nothing_kept):
    frame = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    both = frame.axes(np.array([0.5, 0.6]))
    assert both.rotation.shape == (2, 3, 3) and not both.rotation.flags.writeable
    assert frame.axes(np.array([0.5, 0.6])) is both
    fresh = frame._evaluate_axes(np.array([0.5, 0.6]))
    assert all(np.array_equal(getattr(both, n), getattr(fresh, n)) for n in vars(fresh))
    assert frame.axes(0.5) is frame.axes(0.5) and frame.axes(0.5) is not both


def test_a_vector_longer_than_the_kept_length_is_evaluated_each_time(monkeypatch, nothing_kept):
    monkeypatch.setattr(nothing_kept, "SET_SIZE_KEPT", 2)
    frame = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    times = np.array([0.5, 0.6, 0.7])
    assert frame.axes(times) is not frame.axes(times) and frame.axes(times).rotation.flags.writeable


def test_frames_of_one_epoch_and_ephemeris_share_what_they_keep(monkeypatch, nothing_kept):
    evaluated = []
    real = EarthMoonFrame._evaluate_axes
    monkeypatch.setattr(EarthMoonFrame, "_evaluate_axes", lambda self, t: evaluated.append(t.size) or real(self, t))
    first = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    one, several = first.axes(1.5), first.axes(np.array([1.5, 1.6]))
    second = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    assert second.axes(1.5) is one and second.axes(np.array([1.5, 1.6])) is several
    assert evaluated == [1, 2]  # the second frame evaluated nothing


def test_frames_of_another_epoch_keep_their_own(nothing_kept):
    first = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    other = EarthMoonFrame.from_utc("2026-01-02T00:00:00Z")
    a, b = first.axes(1.5), other.axes(1.5)
    assert a is not b and not np.array_equal(a.rotation, b.rotation)


def test_a_pickled_frame_leaves_its_kept_axes_behind_and_gives_the_same_ones(nothing_kept):
    import pickle

    frame = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    before = frame.axes(2.0)
    assert "_kept" not in frame.__getstate__()
    copy = pickle.loads(pickle.dumps(frame))
    assert all(np.array_equal(a, b) for a, b in zip(vars(copy.axes(2.0)).values(), vars(before).values()))


@pytest.mark.parametrize("kept", [3, 4096])
def test_states_at_many_times_convert_as_at_each_time_alone(monkeypatch, nothing_kept, rng, kept):
    """Beyond AXES_KEPT times (here 3, then the default) the frames are evaluated in blocks: the
    same conversion as one time at a time, to rounding."""
    monkeypatch.setattr(nothing_kept, "AXES_KEPT", kept)
    monkeypatch.setattr(nothing_kept, "SET_SIZE_KEPT", 4)
    frame = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    times = np.linspace(0.0, 2.0, 11)
    s = rng.normal(size=(times.size, 2, 6)) * 0.5 + np.array([1.0, 0, 0, 0, 0, 0])
    each = np.stack([frame.gcrs_to_synodic(s[k], t, unit="lu") for k, t in enumerate(times)])
    np.testing.assert_allclose(frame.gcrs_to_synodic_each(s, times, unit="lu"), each, rtol=1e-13, atol=1e-14)


@pytest.mark.parametrize("per_time", [1, 3])
def test_states_at_kept_times_convert_bit_for_bit_as_at_each_time_alone(nothing_kept, rng, per_time):
    """Up to AXES_KEPT times each time's own frame converts its states: the numbers a fit gets do
    not depend on how its propagations group their output times."""
    frame = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    times = np.linspace(0.0, 2.0, 11)
    s = rng.normal(size=(times.size, per_time, 6)) * 0.5 + np.array([1.0, 0, 0, 0, 0, 0])
    each = np.stack([frame.gcrs_to_synodic(s[k], t, unit="lu") for k, t in enumerate(times)])
    np.testing.assert_array_equal(frame.gcrs_to_synodic_each(s, times, unit="lu"), each)
    np.testing.assert_array_equal(frame.gcrs_to_synodic_each(s, times, unit="lu"), each)  # the kept stack


def test_states_at_many_times_must_have_one_row_per_time(nothing_kept):
    frame = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    with pytest.raises(ValueError, match=r"\(K, N, 6\) with K = 3"):
        frame.gcrs_to_synodic_each(np.ones((2, 1, 6)), np.array([0.0, 0.1, 0.2]))


def test_states_at_many_times_refuse_a_non_finite_one(monkeypatch, nothing_kept):
    monkeypatch.setattr(nothing_kept, "AXES_KEPT", 1)
    frame = EarthMoonFrame.from_utc("2026-01-01T00:00:00Z")
    s = np.ones((2, 1, 6))
    s[1, 0, 2] = np.nan
    with pytest.raises(ValueError, match="finite"):
        frame.gcrs_to_synodic_each(s, np.array([0.0, 0.1]))
