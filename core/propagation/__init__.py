"""Compiled ensemble propagation: the machinery any dynamics model can build on (public API).

- :class:`CompiledDynamics` (:mod:`.compiled`): base class of models given by a numba right-hand
  side; supplies per-particle adaptive DOP853 propagation with impacts on bodies.
- :class:`DenseTrajectory` (:mod:`.dense`): one propagated trajectory evaluated at any time.
- :func:`kernels_for`, :func:`kernel_cache_dir`, :func:`num_threads` (:mod:`.kernels`): generated
  integrator modules, their on-disk cache and the worker threads.
- :mod:`.dop853_tableau`: the Dormand-Prince 8(5,3) coefficients; :mod:`.dop853_source`: the
  generator of the straight-line integrator around one right-hand side.
"""
from cistrack.errors import PropagationError, StateError

from cistrack.propagation.compiled import CompiledDynamics
from cistrack.propagation.dense import DenseTrajectory
from cistrack.propagation.kernels import kernel_cache_dir, kernels_for, num_threads

__all__ = ["CompiledDynamics", "DenseTrajectory", "PropagationError", "StateError", "kernel_cache_dir", "kernels_for",
           "num_threads"]
