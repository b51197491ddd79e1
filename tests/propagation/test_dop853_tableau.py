"""Our DOP853 coefficients are the Dormand-Prince 8(5,3) tableau: equal to an independent copy
(scipy's private module, imported here only as a reference) and satisfying the order conditions."""
import numpy as np
import pytest

from cistrack.propagation import dop853_tableau as tab
from cistrack.propagation.dop853_source import TABLEAU

scipy_dop = pytest.importorskip("scipy.integrate._ivp.dop853_coefficients")


def test_stage_matrix_equals_scipys_to_the_last_bit():
    np.testing.assert_array_equal(tab.stage_matrix(), scipy_dop.A[:tab.N_STAGES, :tab.N_STAGES])


@pytest.mark.parametrize("name", ["B", "C", "E3", "E5"])
def test_weights_nodes_and_error_estimators_equal_scipys(name):
    ours = getattr(tab, name)
    ref = getattr(scipy_dop, name)[: ours.size]
    np.testing.assert_array_equal(ours, ref)


def test_integrator_source_uses_our_tableau():
    np.testing.assert_array_equal(TABLEAU["A"], tab.stage_matrix())
    np.testing.assert_array_equal(TABLEAU["B"], tab.B)


def test_rows_of_the_stage_matrix_sum_to_the_nodes():
    # consistency condition c_s = sum_j a_sj of every explicit Runge-Kutta method
    np.testing.assert_allclose(tab.stage_matrix().sum(axis=1), tab.C, atol=1e-14)


def test_weights_meet_the_order_conditions_up_to_eight_for_the_quadrature():
    # sum_i b_i c_i^(q-1) = 1/q for q = 1..8 (the quadrature conditions of an order-8 method)
    for q in range(1, 9):
        assert np.dot(tab.B, tab.C ** (q - 1)) == pytest.approx(1.0 / q, abs=1e-13)


def test_the_tableau_is_read_only():
    with pytest.raises(ValueError):
        tab.B[0] = 1.0


def test_dense_output_stages_and_weights_equal_scipys_to_the_last_bit():
    for e, row in enumerate(tab.A_EXTRA_ROWS):
        s = tab.N_STAGES + 1 + e
        np.testing.assert_array_equal(np.array(row), scipy_dop.A[s, :s])
        assert tab.C_EXTRA[e] == scipy_dop.C[s]
    np.testing.assert_array_equal(tab.D, scipy_dop.D)
    assert tab.INTERPOLATOR_POWER == scipy_dop.INTERPOLATOR_POWER


def test_extra_stage_rows_sum_to_their_nodes():
    for e, row in enumerate(tab.A_EXTRA_ROWS):
        assert abs(sum(row) - tab.C_EXTRA[e]) < 1e-14
