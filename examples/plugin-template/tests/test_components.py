"""What each component does, checked against something independent."""
import numpy as np
import pytest

from cistrack import units
from cistrack.api import ParameterError, load_registry
from cistrack.testing import NRHO_9_2_APOLUNE, ReferenceCR3BP

from cistrack_template import BisectingClusterer, CR3BPSolarPressure
from cistrack_template.srp import srp_acceleration_lu_tu2


def test_srp_adds_the_cannonball_acceleration_to_the_cr3bp():
    x = NRHO_9_2_APOLUNE[None]
    dyn = CR3BPSolarPressure(area_to_mass_m2_per_kg=0.02, reflectivity=1.5, sun_angle_deg=90.0)
    diff = dyn.derivatives(0.0, x) - ReferenceCR3BP().derivatives(0.0, x)
    expected = 4.56e-6 * 1.5 * 0.02 / 1000.0 * units.TU_S**2 / units.LU_KM  # away from the Sun at +y
    np.testing.assert_allclose(diff[0, 3:], [0.0, -expected, 0.0], atol=1e-12 * expected + 1e-15)


def test_without_area_the_model_is_the_cr3bp():
    x = NRHO_9_2_APOLUNE[None]
    a = CR3BPSolarPressure(area_to_mass_m2_per_kg=0.0).propagate(x, 0.0, 0.5).final
    b = ReferenceCR3BP(rtol=1e-12).propagate(x, 0.0, 0.5).final
    np.testing.assert_allclose(a, b, atol=1e-8)


def test_srp_acceleration_is_about_6e8_m_per_s2_for_a_typical_spacecraft():
    a_m_s2 = srp_acceleration_lu_tu2(0.01, 1.3) * units.LU_KM * 1000.0 / units.TU_S**2
    assert a_m_s2 == pytest.approx(5.93e-8, rel=1e-3)


def test_bisecting_returns_the_number_of_clusters_asked_for():
    x = np.random.default_rng(0).standard_normal((500, 6))
    labels = BisectingClusterer(n_components=4).cluster(x, np.random.default_rng(0))
    assert sorted(np.unique(labels)) == [0, 1, 2, 3]


def test_reflectivity_outside_one_to_two_is_rejected_by_name():
    with pytest.raises(ParameterError, match="reflectivity"):
        CR3BPSolarPressure(reflectivity=3.0)


def test_components_are_registered_by_name_once_installed():
    reg = load_registry()
    if ("dynamics", "template-cr3bp-srp") not in reg:
        pytest.skip("cistrack-template is not installed (pip install -e .)")
    assert reg.get("clustering", "template-bisecting").distribution == "cistrack-template"
    assert ("iod", "template-two-point") in reg
