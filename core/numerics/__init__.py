"""Numerical routines a run needs without scipy's heavier modules: the chi-square distribution,
the incomplete gamma functions and log-sum-exp (:mod:`.special_functions`), and LAPACK's
Cholesky factor as scipy.linalg computes it (:mod:`.cholesky`)."""
