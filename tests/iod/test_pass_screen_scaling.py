"""The first-pass screen costs a fixed number of polynomial fits, however many rows the pass has,
and flags what trying every measurement and every pair left out, each with a fit of its own,
flags (plugins/iod/pass_screen.py)."""
from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest

from cistrack.plugins.iod import pass_screen
from cistrack.plugins.iod.pass_screen import MAX_PAIR_CANDIDATES, screen_pass
from cistrack.units import ARCSEC_RAD

HOUR_TU = 3600.0 / 375_190.0


def _pass(n, hours=6.0, sigma_arcsec=1.5, seed=0):
    """Times (n,) TU, noisy lines of sight (n, 3) to a target at lunar distance seen from the
    rotating Earth, and their sigmas (n,) rad (varying by up to a factor 2)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, hours * HOUR_TU, n)
    w_earth = 2 * np.pi / (24 * HOUR_TU)
    target = np.stack([384_400.0 * np.cos(0.23 * t), 384_400.0 * np.sin(0.23 * t), 30_000.0 + 0 * t], axis=1)
    observer = 6378.0 * np.stack([0.8 * np.cos(w_earth * t), 0.8 * np.sin(w_earth * t), 0.6 + 0 * t], axis=1)
    u = target - observer
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    sig = sigma_arcsec * ARCSEC_RAD * rng.uniform(0.7, 1.4, n)
    u = u + rng.normal(size=u.shape) * sig[:, None] / np.sqrt(2)
    return t, u / np.linalg.norm(u, axis=1, keepdims=True), sig


def _displaced(u, where, arcsec, seed):
    rng = np.random.default_rng(seed)
    out = u.copy()
    for i, a in zip(where, arcsec):
        d = np.cross(u[i], rng.normal(size=3))
        out[i] = u[i] + a * ARCSEC_RAD * d / np.linalg.norm(d)
        out[i] /= np.linalg.norm(out[i])
    return out


def _residuals(t, u, keep, order):
    basis = np.vander((t - t[keep].mean()) / np.ptp(t[keep]), order + 1)
    coef, *_ = np.linalg.lstsq(basis[keep], u[keep], rcond=None)
    return np.linalg.norm(u - basis @ coef, axis=1)


def _one_fit_per_choice(t, u, s, order, need):
    """The screen's rule with a fit of its own for every measurement and every pair left out."""
    n = t.shape[0]
    for m in (1, 2):
        if n - m < max(need, order + 3):
            break
        scored = []
        for out in combinations(range(n), m):
            keep = np.isin(np.arange(n), out, invert=True)
            res = _residuals(t, u, keep, order)
            scored.append((float(np.sqrt(np.mean((res[keep] / s[keep]) ** 2))), out, keep, res))
        rms, out, keep, res = min(scored, key=lambda x: x[0])
        if rms > pass_screen.CONSISTENT_RMS:
            continue
        spread = np.sqrt(np.mean(res[keep] ** 2))
        loo = max(_residuals(t, u, keep & (np.arange(n) != j), order)[j] for j in np.nonzero(keep)[0])
        far = all(res[i] >= max(pass_screen.MIN_OFFSET_SIGMA * s[i], pass_screen.MIN_OFFSET_RMS * spread,
                                pass_screen.MIN_OFFSET_LOO * loo) for i in out)
        return [(i, float(res[i])) for i in out] if far else []
    return []


class _CountedCalls:
    def __init__(self, function):
        self.function, self.calls = function, 0

    def __call__(self, *args, **kwargs):
        self.calls += 1
        return self.function(*args, **kwargs)


def _fits_made(monkeypatch, t, u, s):
    """Least-squares solves, QR factorisations and linear solves numpy is asked for by one screen."""
    counters = {name: _CountedCalls(getattr(np.linalg, name)) for name in ("lstsq", "qr", "solve", "inv", "pinv")}
    with monkeypatch.context() as m:
        for name, counter in counters.items():
            m.setattr(np.linalg, name, counter)
        found = screen_pass(t, u, s, order=4, need=8)
    return sum(c.calls for c in counters.values()), found


def test_the_number_of_fits_does_not_grow_with_the_rows_of_the_pass(monkeypatch):
    made = {}
    for n in (40, 400):
        t, u, s = _pass(n, seed=n)
        made[n], found = _fits_made(monkeypatch, t, _displaced(u, [n // 5, 3 * n // 5], [3600.0, 5000.0], 1), s)
        assert sorted(i for i, _ in found) == [n // 5, 3 * n // 5]
    assert made[400] == made[40] <= 8


CASES = [(n, hours, k, least, seed) for seed, (n, hours, k, least) in enumerate(
    [(10, 6.0, 0, 0), (12, 6.0, 1, 1.5), (14, 6.0, 2, 1.5), (16, 12.0, 0, 0), (16, 12.0, 1, 1.5), (20, 3.0, 2, 1.5),
     (25, 8.0, 1, 1.5), (30, 6.0, 2, 1.5), (12, 6.0, 2, 1.5), (9, 4.0, 1, 1.5), (14, 6.0, 2, 3.2), (40, 8.0, 2, 3.2),
     (MAX_PAIR_CANDIDATES + 16, 6.0, 2, 1.5), (MAX_PAIR_CANDIDATES + 16, 6.0, 2, 3.2)])]


@pytest.mark.parametrize("n, hours, outliers, least, seed", CASES)
def test_the_screen_flags_what_a_fit_per_choice_flags(n, hours, outliers, least, seed):
    """``outliers`` measurements 10**least to 10**3.8 arcsec off."""
    rng = np.random.default_rng(seed)
    t, u, s = _pass(n, hours=hours, seed=seed)
    where = rng.choice(n, size=outliers, replace=False)
    u = _displaced(u, where, 10 ** rng.uniform(least, 3.8, outliers), seed)
    expected = _one_fit_per_choice(t, u, s, 4, 8)
    found = screen_pass(t, u, s, order=4, need=8)
    assert [i for i, _ in found] == [i for i, _ in expected]
    assert [off for _, off in found] == pytest.approx([off for _, off in expected], rel=1e-9)


def test_two_gross_outliers_in_a_pass_of_thousands_of_rows_are_both_left_out():
    t, u, s = _pass(5000, seed=7)
    found = screen_pass(t, _displaced(u, [17, 3100], [5000.0, 3600.0], 2), s, order=4, need=8)
    assert [i for i, _ in found] == [17, 3100]
    assert [off / ARCSEC_RAD for _, off in found] == pytest.approx([5000.0, 3600.0], rel=0.01)
