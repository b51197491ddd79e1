"""First runs: the lockstep kernel can be compiled in a second process while this one works, and
a handful of particles, or a lone state once the lockstep kernel exists, goes through the lockstep
kernel (no one-particle kernel to compile)."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from cistrack.lazy import lazy_njit
from cistrack.plugins.dynamics.cr3bp import CR3BP
from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.propagation import background_compile
from cistrack.propagation.compiled import LOCKSTEP_MIN_PARTICLES

from .kernel_runs import run_kernel

NRHO = ORBITS["nrho-9-2"]


def test_a_few_particles_go_through_the_lockstep_kernel_with_the_one_particle_results():
    dyn = CR3BP()
    states = NRHO.state + np.random.default_rng(2).normal(size=(LOCKSTEP_MIN_PARTICLES, 6)) * 1e-5
    times = np.array([0.4, 1.1])
    got = dyn.propagate(states, 0.0, times)
    one = run_kernel(dyn._kernels().propagate_kernel, dyn, states, times)
    assert np.array_equal(got.states, one[0]) and dyn._kernels().propagate_lanes_kernel.signatures


def test_a_lone_state_goes_through_the_lockstep_kernel_once_it_exists():
    dyn = CR3BP()
    mod = dyn._kernels()
    dyn.propagate(NRHO.state + np.zeros((LOCKSTEP_MIN_PARTICLES, 6)), 0.0, 0.1)
    assert background_compile.lockstep_available(mod)
    assert dyn._propagate_kernel(1) is mod.propagate_lanes_kernel


@lazy_njit(cache=True)
def spring_rhs(t, y, p, out):
    """A harmonic oscillator only this test uses: its kernels are in no cache."""
    out[0] = y[1]
    out[1] = -p[0] * y[0]


def test_a_lockstep_kernel_neither_compiled_nor_cached_is_not_available(monkeypatch, tmp_path):
    from cistrack.propagation import kernels

    monkeypatch.setenv("CISTRACK_KERNEL_DIR", str(tmp_path))
    monkeypatch.setattr(kernels, "_KERNELS", {})
    mod = kernels.kernels_for(spring_rhs, 2)
    assert mod.propagate_lanes_kernel is not None
    assert not background_compile.lockstep_available(mod)  # a lone state takes the one-particle kernel


def test_no_second_process_when_the_setting_says_no(monkeypatch):
    monkeypatch.setenv("CISTRACK_BACKGROUND_COMPILE", "0")
    assert not background_compile.idle_core()
    monkeypatch.setenv("CISTRACK_BACKGROUND_COMPILE", "1")
    assert background_compile.idle_core()


def test_the_estimate_grows_with_the_load(monkeypatch):
    monkeypatch.setattr(background_compile.os, "getloadavg", lambda: (0.0, 0.0, 0.0))
    idle = background_compile.estimate_seconds(("dense_kernel", "propagate_lanes_kernel"), parallel=False)
    monkeypatch.setattr(background_compile.os, "getloadavg", lambda: (8.0, 8.0, 8.0))
    busy = background_compile.estimate_seconds(("dense_kernel", "propagate_lanes_kernel"), parallel=False)
    each = background_compile.COMPILE_CPU_SECONDS
    assert busy > idle >= each["dense_kernel"] + each["propagate_lanes_kernel"]  # one after the other


@pytest.mark.slow
def test_a_kernel_compiled_in_the_second_process_is_loaded_here_not_compiled_again(tmp_path):
    """Fresh caches; the child compiles the lockstep kernel, this process only loads it."""
    script = textwrap.dedent('''
        import numpy as np
        from numba.core import event
        from cistrack.plugins.dynamics.cr3bp import CR3BP
        from cistrack.plugins.dynamics.orbit_catalog import ORBITS
        from cistrack.propagation import background_compile
        compiled = []
        class L(event.Listener):
            def on_start(self, ev):
                compiled.append(ev.data["dispatcher"].py_func.__name__)
            def on_end(self, ev):
                pass
        event.register("numba:compile", L())
        dyn, x = CR3BP(), ORBITS["nrho-9-2"].state
        assert background_compile.start(dyn, x)
        p = dyn.propagate(x + np.zeros((20, 6)), 0.0, 1.0)
        print(int("propagate_lanes_kernel" in compiled), repr(float(p.states[-1, 0, 0])))
    ''')
    env = {**__import__("os").environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
           "CISTRACK_KERNEL_DIR": str(tmp_path / "kernels"), "CISTRACK_BACKGROUND_COMPILE": "1"}
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
    compiled_here, value = out.stdout.split()
    reference = CR3BP().propagate(NRHO.state[None], 0.0, 1.0).states[-1, 0, 0]
    assert compiled_here == "0" and float(value) == reference


@pytest.mark.slow
def test_a_first_run_compiles_no_one_particle_step(tmp_path):
    """Fresh caches: the truth's dense kernel, a cloud with impacts through the lockstep kernel and
    a lone state after it compile neither the one-particle kernel nor its step: the impact search
    takes the dense step, and the lone state the lockstep kernel."""
    script = textwrap.dedent('''
        import numpy as np
        from cistrack.plugins.dynamics.cr3bp import CR3BP
        from cistrack.plugins.dynamics.orbit_catalog import ORBITS
        dyn, x = CR3BP(), ORBITS["nrho-9-2"].state
        moon = np.array([1.0 - dyn.mu, 0.0, 0.0])
        into_moon = np.r_[moon + [0.0, 0.05, 0.01], [0.02, -0.5, 0.0]]
        dyn.dense_trajectory(into_moon, 0.0, 2.0)
        p = dyn.propagate(into_moon + np.zeros((20, 6)), 0.0, 2.0)
        dyn.propagate(x, 0.0, 1.0)
        mod = dyn._kernels()
        print(int(p.alive.any()), len(mod._rk_step.signatures), len(mod.propagate_kernel.signatures))
    ''')
    env = {**__import__("os").environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
           "CISTRACK_KERNEL_DIR": str(tmp_path / "kernels"), "CISTRACK_BACKGROUND_COMPILE": "0"}
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["0", "0", "0"]
