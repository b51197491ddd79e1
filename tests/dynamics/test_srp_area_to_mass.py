"""The ephemeris model's ``area_to_mass_m2_kg`` (C_R A/m of the cannonball radiation pressure):
its acceleration against the formula in plain numpy (DE421's Sun read through jplephem), its
effect on a propagated orbit against scipy's DOP853 at tight tolerance, zero changing nothing,
and ``with_parameters`` giving the same model as the constructor."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.errors import CistrackError
from cistrack.plugins.dynamics.ephemeris import EphemerisDynamics
from cistrack.plugins.dynamics.ephemeris_point_mass_rhs import ephemeris_point_mass_rhs
from cistrack.plugins.dynamics.ephemeris_rhs import ephemeris_rhs

from . import reference_ephemeris as ref

EPOCH = "2026-01-01T00:00:00Z"
AU_KM = float(ref._EPH.AU)
P_N_M2 = 4.56e-6
DRO = np.array([0.7957, 0.0, 0.0, 0.0, 0.53181952, 0.0])


def _srp_kms2(r_km: np.ndarray, sun_km: np.ndarray, cr_am: float) -> np.ndarray:
    """C_R (A/m) P (1 AU / |r - s|)^2 unit(r - s), km/s^2 (P in N/m^2 -> m/s^2 per m^2/kg; / 1000)."""
    d = r_km - sun_km
    n = np.linalg.norm(d)
    return cr_am * P_N_M2 / 1000.0 * (AU_KM / n) ** 2 * d / n


def _srp_rhs(jd0, cr_am: float):
    base = ref.rhs(jd0)

    def f(t, y):
        out = base(t, y)
        out[3:] += _srp_kms2(y[:3], ref.moon_sun(jd0[0], jd0[1] + t / ref.DAY)[1], cr_am)
        return out
    return f


@pytest.mark.parametrize("t_tu", [0.0, 1.3, 5.7])
def test_the_acceleration_is_the_cannonball_formula_at_several_states(t_tu):
    cr_am = 0.0123
    dyn = EphemerisDynamics(epoch=EPOCH, area_to_mass_m2_kg=cr_am)
    base = EphemerisDynamics(epoch=EPOCH)
    y = np.array([[0.5, 0.2, -0.1, 0.0, 0.0, 0.0], [-0.9, 0.3, 0.05, 0.1, 0.0, 0.0], [0.1, -1.2, 0.4, 0.0, 0.2, 0.0]])
    a = (dyn.inertial_derivatives(t_tu, y) - base.inertial_derivatives(t_tu, y))[:, 3:] * units.LU_KM / units.TU_S ** 2
    jd1, jd2 = dyn.frame.epoch_tdb
    sun = ref.moon_sun(jd1, jd2 + t_tu * units.TU_S / ref.DAY)[1]
    want = np.array([_srp_kms2(r * units.LU_KM, sun, cr_am) for r in y[:, :3]])
    np.testing.assert_allclose(a, want, rtol=1e-9)


def test_the_product_parameter_equals_reflectivity_times_area_to_mass():
    a = EphemerisDynamics(epoch=EPOCH, srp_area_to_mass_m2_kg=0.01, srp_reflectivity=1.0)
    b = EphemerisDynamics(epoch=EPOCH, area_to_mass_m2_kg=0.01)
    np.testing.assert_array_equal(a.params_vector(), b.params_vector())
    assert b.parameter("area_to_mass_m2_kg") == 0.01 and a.parameter("area_to_mass_m2_kg") == 0.01


def test_zero_is_the_point_mass_model_bit_for_bit():
    a = EphemerisDynamics(epoch=EPOCH)
    b = EphemerisDynamics(epoch=EPOCH, area_to_mass_m2_kg=0.0)
    c = a.with_parameters(area_to_mass_m2_kg=0.0)
    assert a._rhs() is ephemeris_point_mass_rhs and b._rhs() is ephemeris_point_mass_rhs
    assert c._rhs() is ephemeris_point_mass_rhs
    np.testing.assert_array_equal(a.params_vector(), b.params_vector())
    np.testing.assert_array_equal(a.params_vector(), c.params_vector())


def test_with_parameters_is_the_constructed_model_and_leaves_the_original():
    base = EphemerisDynamics(epoch=EPOCH, srp_area_to_mass_m2_kg=0.02, srp_reflectivity=1.3)
    base.params_vector()
    new = base.with_parameters(area_to_mass_m2_kg=-0.004)
    want = EphemerisDynamics(epoch=EPOCH, area_to_mass_m2_kg=-0.004)
    assert new._rhs() is ephemeris_rhs
    np.testing.assert_array_equal(new.params_vector(), want.params_vector())
    assert base.parameter("area_to_mass_m2_kg") == pytest.approx(0.026, rel=1e-15)
    x = DRO[None]
    np.testing.assert_array_equal(new.propagate(x, 0.0, 2.0).final, want.propagate(x, 0.0, 2.0).final)


def test_copies_with_new_values_build_the_ephemeris_records_once(monkeypatch):
    """A fit solving for the ratio makes a copy per trial value; each had rebuilt the same DE421
    records (a third of a burn fit's time). The copies share them and the frame, and each still
    integrates with its own value: the constructed model's parameters, bit for bit."""
    import cistrack.plugins.dynamics.ephemeris as ephemeris

    built = []
    monkeypatch.setattr(ephemeris, "pack_params", lambda *a, **k: built.append(1) or ephemeris_rhs_pack(*a, **k))
    base = EphemerisDynamics(epoch=EPOCH)
    copies = [base.with_parameters(area_to_mass_m2_kg=v) for v in (0.01, 0.02, -0.03)]
    for c, v in zip(copies, (0.01, 0.02, -0.03)):
        np.testing.assert_array_equal(c.params_vector(), EphemerisDynamics(epoch=EPOCH, area_to_mass_m2_kg=v).params_vector())
        assert c.frame is base.frame
    assert len(built) == 1 + 3  # the first copy's, then the three constructed models' own


def ephemeris_rhs_pack(*args, **kwargs):
    from cistrack.plugins.dynamics.ephemeris_rhs import pack_params

    return pack_params(*args, **kwargs)


def test_bad_values_are_refused_by_name():
    with pytest.raises(CistrackError, match="area_to_mass_m2_kg"):
        EphemerisDynamics(area_to_mass_m2_kg=float("nan"))
    with pytest.raises(CistrackError, match="area_to_mass_m2_kg"):
        EphemerisDynamics().with_parameters(area_to_mass_m2_kg=5e3)
    with pytest.raises(CistrackError, match="mass_kg"):
        EphemerisDynamics().with_parameters(mass_kg=1.0)


def test_the_propagated_effect_agrees_with_scipy_at_tight_tolerance():
    """A DRO over 7 days: the displacement radiation pressure causes (with minus without) in the
    compiled model and in scipy's DOP853 (rtol 1e-13, numpy right-hand side) agree to 1 m in
    ~2.7 km (and each model's orbit to the other's to a few metres)."""
    cr_am = 0.01
    dyn = EphemerisDynamics(epoch=EPOCH, area_to_mass_m2_kg=cr_am)
    base = EphemerisDynamics(epoch=EPOCH)
    x0 = base.frame.gcrs_to_synodic(base.frame.pulsating_to_gcrs(DRO, 0.0), 0.0)
    t = np.array([3.5, 7.0]) * 86400.0 / units.TU_S
    g0 = base.frame.synodic_to_gcrs(x0, 0.0)
    mine = [np.array([m.frame.synodic_to_gcrs(m.propagate(x0[None], 0.0, t).states[k, 0], tk)
                      for k, tk in enumerate(t)]) for m in (dyn, base)]
    from scipy.integrate import solve_ivp

    jd0 = base.frame.epoch_tdb
    sec = t * units.TU_S
    sol = solve_ivp(_srp_rhs(jd0, cr_am), (0.0, sec[-1]), g0, method="DOP853", rtol=1e-13, atol=1e-9, t_eval=sec)
    with_srp, without = sol.y.T, ref.propagate_km(g0, jd0, sec)
    effect_mine = (mine[0] - mine[1])[:, :3]
    effect_ref = (with_srp - without)[:, :3]
    assert np.linalg.norm(effect_ref[-1]) > 1.0                       # km: a real effect
    assert np.abs(effect_mine - effect_ref).max() * 1000.0 < 1.0, (effect_mine, effect_ref)
    assert np.abs(mine[0][:, :3] - with_srp[:, :3]).max() * 1000.0 < 10.0


NRHO = np.array([1.02, 0.0, -0.18, 0.0, -0.1, 0.0])


def _central_difference(make, p0: float, times: np.ndarray, h: float = 1e-4) -> np.ndarray:
    """d x / d p (K, 6) of models ``make(p)`` built afresh, by a central difference of step ``h``."""
    from cistrack.least_squares.trajectory import arc_states

    up, down = (arc_states(make(p0 + s * h), NRHO, 0.0, times) for s in (1.0, -1.0))
    return (up - down) / (2.0 * h)


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_the_integrated_sensitivity_to_area_to_mass_matches_a_central_difference(direction):
    times = direction * np.linspace(0.1, 6.0, 12)
    make = lambda p: EphemerisDynamics(epoch=EPOCH, area_to_mass_m2_kg=p)  # noqa: E731
    _, _, sens = make(0.006).propagate_with_sensitivity(NRHO, 0.0, times, "area_to_mass_m2_kg")
    want = _central_difference(make, 0.006, times)
    assert np.abs(want).max() > 1e-3  # LU per m^2/kg: about 400 km per m^2/kg over 6 TU
    np.testing.assert_allclose(sens, want, rtol=0, atol=1e-5 * np.abs(want).max())


def test_the_sensitivity_is_carried_across_an_impulsive_burn():
    from cistrack.interfaces.maneuvers import Impulse
    from cistrack.propagation.impulses import ImpulsiveDynamics

    times = np.linspace(0.1, 6.0, 12)
    burn = [Impulse(2.05, np.array([0.0, 2e-3, 1e-3]), "burn 1")]
    make = lambda p: ImpulsiveDynamics(EphemerisDynamics(epoch=EPOCH, area_to_mass_m2_kg=p), burn)  # noqa: E731
    _, _, sens = make(0.0).propagate_with_sensitivity(NRHO, 0.0, times, "area_to_mass_m2_kg")
    np.testing.assert_allclose(sens, _central_difference(make, 0.0, times), rtol=0,
                               atol=1e-5 * np.abs(sens).max())


def test_a_parameter_without_an_integrated_sensitivity_is_refused_by_name():
    with pytest.raises(CistrackError, match="no sensitivity of 'gm_moon'"):
        EphemerisDynamics(epoch=EPOCH).propagate_with_sensitivity(NRHO, 0.0, np.array([1.0]), "gm_moon")


def test_a_model_without_integrated_sensitivities_refuses_them_by_default():
    from cistrack.plugin.registry import default_registry

    cr3bp = default_registry().create("dynamics", "cr3bp")
    assert cr3bp.sensitivity_parameters == ()
    with pytest.raises(CistrackError, match="no integrated sensitivity of 'area_to_mass_m2_kg'"):
        cr3bp.propagate_with_sensitivity(NRHO, 0.0, np.array([1.0]), "area_to_mass_m2_kg")
