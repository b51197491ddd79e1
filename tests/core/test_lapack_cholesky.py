"""cistrack.numerics.cholesky.upper_cholesky: scipy.linalg.cholesky's upper factor, the same
numbers bit for bit (scipy's dpotrf, called through cython_lapack's exported pointer), so that
a run need not import scipy.linalg."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import cholesky

from cistrack.numerics import cholesky as module
from cistrack.numerics.cholesky import upper_cholesky


def _covariances(rng: np.random.Generator, count: int, n: int = 6) -> np.ndarray:
    """Positive definite matrices whose scales span 1e-7..1e7 (as a cloud's km and km/s do),
    each nudged off exact symmetry in one upper entry (only the upper triangle is read)."""
    a = rng.normal(size=(count, n, n)) * np.exp(rng.uniform(-8.0, 8.0, size=(count, n, 1)))
    P = a @ np.swapaxes(a, -1, -2) + 1e-12 * np.eye(n)
    P[:, 0, 1] *= 1.0 + 1e-15
    return P


def test_a_batch_is_scipys_factor_bit_for_bit():
    P = _covariances(np.random.default_rng(3), 500)
    assert np.array_equal(upper_cholesky(P), cholesky(P))


def test_one_matrix_is_scipys_factor_bit_for_bit():
    P = _covariances(np.random.default_rng(4), 1)[0]
    assert np.array_equal(upper_cholesky(P), cholesky(P))


def test_the_factor_is_upper_triangular_and_reproduces_the_matrix():
    P = _covariances(np.random.default_rng(5), 20, n=4)
    P = 0.5 * (P + np.swapaxes(P, -1, -2))
    U = upper_cholesky(P)
    assert np.all(np.tril(U, -1) == 0.0)
    scale = np.sqrt(np.einsum("kii->ki", P))
    assert np.allclose((np.swapaxes(U, -1, -2) @ U) / scale[:, :, None] / scale[:, None, :],
                       P / scale[:, :, None] / scale[:, None, :], rtol=0, atol=1e-12)


def test_a_matrix_that_is_not_positive_definite_is_refused_as_scipy_refuses_it():
    P = np.diag([1.0, -1.0, 1.0])
    with pytest.raises(np.linalg.LinAlgError, match="2-th leading minor"):
        upper_cholesky(P)
    with pytest.raises(np.linalg.LinAlgError, match="2-th leading minor"):
        cholesky(P)


def test_non_finite_and_non_square_input_are_refused():
    with pytest.raises(ValueError, match="infs or NaNs"):
        upper_cholesky(np.array([[1.0, np.nan], [np.nan, 1.0]]))
    with pytest.raises(ValueError, match=r"square matrices \(..., n, n\), got shape \(2, 3\)"):
        upper_cholesky(np.ones((2, 3)))


def test_a_lapack_exported_with_another_signature_falls_back_to_scipy_linalg(monkeypatch):
    # a 64-bit-integer LAPACK build names another C signature: its pointer must not be called
    monkeypatch.setattr(module, "_SIGNATURE", b"void (char *, long *, double *, long *, long *)")
    module._dpotrf.cache_clear()
    try:
        assert module._dpotrf() is None
        P = _covariances(np.random.default_rng(6), 3)
        assert np.array_equal(upper_cholesky(P), cholesky(P))
    finally:
        monkeypatch.undo()
        module._dpotrf.cache_clear()
