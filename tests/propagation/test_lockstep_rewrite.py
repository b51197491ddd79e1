"""Right-hand sides written with ordinary Python (loops, ``_`` names, a table indexed by time) run
on the SIMD-lockstep kernel and give the one-particle kernel's results bit for bit."""
from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from cistrack import units
from cistrack.plugins.dynamics.cr3bp import CR3BP
from cistrack.plugins.dynamics.ephemeris import EphemerisDynamics
from cistrack.plugins.dynamics.ephemeris_rhs import ephemeris_rhs
from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.propagation.dop853_lanes_source import RESERVED
from cistrack.propagation.lane_rhs import LaneUniform, lane_body

from .kernel_runs import run_kernel, same_results
from .table_model import N_TABLE, Model, Parity, Table, stage_output, table_stage_case

@njit
def loop_rhs(t, y, p, out):
    """Oscillator written with a constant-range loop and a run-time loop with ``_``."""
    c = p[0]
    for _ in range(int(p[1])):  # c <- c * (1 + t / 8), as often as p[1] says
        c = c + c * t * 0.125
    for i in range(3):
        out[i] = y[i + 3]
        out[i + 3] = -c * y[i]


class Loops(Model):
    rhs = loop_rhs


def _spread(n, seed=5):
    """Amplitudes from 0.1 to 3: the particles take different steps, so lanes drift apart in time."""
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, 6)) * np.linspace(0.1, 3.0, n)[:, None]


def _lockstep_equals_one_particle(dyn, states, times):
    mod = dyn._kernels()
    assert hasattr(mod, "propagate_lanes_kernel")
    return same_results(run_kernel(mod.propagate_kernel, dyn, states, times),
                        run_kernel(mod.propagate_lanes_kernel, dyn, states, times))


def test_a_constant_range_loop_is_unrolled_into_fixed_state_slots():
    body, why = lane_body(loop_rhs, RESERVED)
    assert why == "" and "_y3" in body.text and "__OUT__[5]" in body.text and "for i" not in body.text


def test_a_loop_over_a_run_time_range_with_an_underscore_variable_stays_a_loop():
    body, why = lane_body(loop_rhs, RESERVED)
    assert why == "" and "for _u_ in range(int(_p[1]))" in body.text


@pytest.mark.parametrize("times", [np.array([0.7, 3.0]), np.array([-2.5])], ids=["forward", "backward"])
def test_loops_give_the_one_particle_results_bit_for_bit(times):
    assert _lockstep_equals_one_particle(Loops([1.0, 3.0]), _spread(37), times)


@pytest.mark.parametrize("times", [np.array([1.3, 7.9]), np.array([-6.0])], ids=["forward", "backward"])
def test_a_time_table_keyed_by_lane_uniform_gives_the_one_particle_results_bit_for_bit(times):
    force = np.random.default_rng(1).normal(size=N_TABLE)
    table = Table(np.r_[0.25, force])
    assert _lockstep_equals_one_particle(table, _spread(45), times)


@pytest.mark.slow  # its own kernel, ~50 s of compile on 2 cores; the time table above covers lane-uniform keys
@pytest.mark.parametrize("times", [np.array([1.3, 7.9]), np.array([-6.0])], ids=["forward", "backward"])
def test_a_periodic_table_keyed_by_lane_uniform_gives_the_one_particle_results_bit_for_bit(times):
    assert _lockstep_equals_one_particle(Parity(np.r_[0.25, 1.0, -1.0]), _spread(45), times)


def test_a_record_index_is_marked_monotonic_and_a_lane_uniform_one_is_not():
    from .table_model import parity_rhs, table_rhs

    assert lane_body(table_rhs, RESERVED)[0].key.monotonic
    assert not lane_body(parity_rhs, RESERVED)[0].key.monotonic
    assert lane_body(ephemeris_rhs, RESERVED)[0].key.monotonic


def test_the_keyed_lane_loop_reads_no_parameter_inside_the_loop():
    """What makes LLVM vectorise it: every params load is done once before the lane loop."""
    body, why = lane_body(ephemeris_rhs, RESERVED)
    assert why == "" and body.key.name == "k"
    assert "_p[" not in body.text and "_p[" in body.key.per_key


def test_the_keyed_lane_loop_loads_a_parameter_named_twice_once():
    """ephemeris_rhs reads p[GM_M] and p[GM_S] in two terms each: one load (and one scratch row)
    per parameter."""
    body, _ = lane_body(ephemeris_rhs, RESERVED)
    loads = [line.split(" = ", 1)[1] for line in body.key.per_key.splitlines() if " = _p[" in line]
    assert loads.count("_p[GM_M]") == 1 and loads.count("_p[GM_S]") == 1
    assert len(loads) == len(set(loads))


def test_the_scratch_rows_hold_the_loads_the_loop_reads_and_the_index_arithmetic_stays_scalar():
    """Loads the lane loop reads come from scratch rows; what stays before the loop is the index
    arithmetic and the loads that a lane-invariant test reads (J2's switch stays a branch)."""
    from cistrack.propagation.dop853_lanes_keyed import scratch_plan

    body, _ = lane_body(ephemeris_rhs, RESERVED)
    replicated, kept = scratch_plan(body)
    assert replicated and all(name in body.text for name in replicated)
    kept_loads = [line.split(" = ", 1)[0] for line in kept if " = _p[" in line]
    tests = [line for line in kept if " = _p[" not in line and "!= 0.0" in line]
    assert tests and kept_loads
    assert all(any(name in line for line in tests) for name in kept_loads)


def _key_nested(t, y, p, out):
    if t > 0.0:
        k: LaneUniform = int(t)
        out[0] = p[k]


def _key_after_state(t, y, p, out):
    x = y[0]
    k: LaneUniform = int(t + x)
    out[0] = p[k]


@pytest.mark.parametrize("func,reason", [(_key_nested, "top level"), (_key_after_state, "reads the state")])
def test_a_lane_uniform_key_that_may_differ_by_state_or_branch_is_refused(func, reason):
    body, why = lane_body(func, RESERVED)
    assert body is None and reason in why


def _nrho_cloud_with_moon_divers(dyn, times, n, seed, spread, divers):
    """Kernel states (n, 6): the 9:2 NRHO with normal scatter ``spread`` (position, velocity; LU,
    VU), and particles ``divers`` = [(index, direction, km above the surface, km/s toward the
    Moon)] placed above the moving Moon at t = 0 and falling onto it."""
    rng = np.random.default_rng(seed)
    syn = ORBITS["nrho-9-2"].state + rng.normal(size=(n, 6)) * np.r_[[spread[0]] * 3, [spread[1]] * 3]
    dyn._ensure_window(min(0.0, times.min()), max(0.0, times.max()))
    states = dyn.to_inertial(syn, 0.0)
    moon, moon_v = dyn.frame.ephemeris.moon(*dyn.frame.epoch_tdb)  # GCRS km, km/s
    for i, aim, height, fall in divers:
        down = np.array(aim) / np.linalg.norm(aim)
        states[i] = units.state_from_km(np.r_[moon + (dyn.moon_radius_km + height) * down, moon_v - fall * down])
    return states


@pytest.mark.parametrize("perturbed", [False, True], ids=["point-masses", "j2-srp"])
@pytest.mark.parametrize("times", [np.array([0.9, 1.5121]), np.array([-0.8])], ids=["forward", "backward"])
def test_ephemeris_lockstep_results_equal_the_one_particle_kernel_bit_for_bit(times, perturbed):
    dyn = EphemerisDynamics(epoch="2026-01-01T00:00:00Z", j2=perturbed,
                            srp_area_to_mass_m2_kg=0.01 if perturbed else 0.0)
    states = _nrho_cloud_with_moon_divers(dyn, times, 41, 11, (3e-5, 1e-4), [(5, [0.3, -0.5, 0.81], 2000.0, 2.0)])
    mod = dyn._kernels()
    one = run_kernel(mod.propagate_kernel, dyn, states, times)
    lock = run_kernel(mod.propagate_lanes_kernel, dyn, states, times)
    assert same_results(one, lock)
    if times[-1] > 0:
        assert (one[3] == 1).sum() >= 1  # an impact on the moving Moon was exercised


@pytest.mark.parametrize("stage", [1, 5, 12])
def test_a_keyed_stage_gives_each_lane_the_same_numbers_whether_or_not_all_lanes_share_a_record(stage):
    """All lanes in one record take the stage's one-pass branch; one lane moved to another record
    sends the rest through the per-record passes: the other lanes' derivatives stay bit for bit.
    Each stage runs as in a step: after ``_lanes_keys``."""
    mod, p, w = table_stage_case()
    one_record, two_records = w.copy(), w.copy()
    two_records[mod.ROW_T * mod.LANES] = 2.6  # lane 0 in record 10
    for work in (one_record, two_records):
        mod._lanes_keys(work, p)
        getattr(mod, f"_lanes_stage{stage}")(work, p)
    a, b = stage_output(mod, one_record, stage), stage_output(mod, two_records, stage)
    assert np.array_equal(a[:, 1:], b[:, 1:]) and not np.array_equal(a[:, 0], b[:, 0])


@pytest.mark.parametrize("stage", [1, 7, 12])
def test_a_keyed_stage_gives_the_same_numbers_with_the_steps_key_as_with_its_own_pass(stage):
    """``_lanes_keys`` found one key for the whole step (the stage skips its own pass), or it did
    not run (the stage computes every lane's key itself): the same derivatives bit for bit."""
    mod, p, w = table_stage_case()
    with_step_key, own_pass = w.copy(), w.copy()
    mod._lanes_keys(with_step_key, p)
    own_pass[mod.ROW_KEY * mod.LANES:] = 0.0  # no step key, no scratch rows filled
    getattr(mod, f"_lanes_stage{stage}")(with_step_key, p)
    getattr(mod, f"_lanes_stage{stage}")(own_pass, p)
    assert with_step_key[mod.ROW_STEP_KEY * mod.LANES + 2 * stage] == 1.0  # the stage had one key
    assert np.array_equal(stage_output(mod, with_step_key, stage), stage_output(mod, own_pass, stage))


def test_a_keyed_stage_refills_its_scratch_rows_when_the_record_changes():
    """The per-record loads are kept in scratch rows between stage calls: a stage in record 10
    after one in record 4 gives the numbers of a fresh work array in record 10."""
    mod, p, w = table_stage_case()
    lanes = mod.LANES
    reused, fresh = w.copy(), w.copy()
    fresh[mod.ROW_KEY * lanes:] = 0.0
    mod._lanes_keys(reused, p)
    mod._lanes_stage5(reused, p)  # fills the scratch rows with record 4's loads
    record4 = stage_output(mod, reused, 5).copy()
    assert reused[mod.ROW_SCRATCH_KEY * lanes:mod.ROW_SCRATCH_KEY * lanes + 2].tolist() == [1.0, 4.0]
    for work in (reused, fresh):
        work[mod.ROW_T * lanes:(mod.ROW_T + 1) * lanes] += 1.5  # every lane in record 10
        mod._lanes_keys(work, p)
        mod._lanes_stage5(work, p)
    assert np.array_equal(stage_output(mod, reused, 5), stage_output(mod, fresh, 5))
    assert not np.array_equal(stage_output(mod, reused, 5), record4)  # record 10's force, not 4's


def test_a_keyed_right_hand_side_gets_the_wider_batch_and_a_plain_one_the_default():
    from cistrack.propagation.dop853_lanes_source import DEFAULT_LANES, KEYED_LANES

    assert EphemerisDynamics(epoch="2026-01-01T00:00:00Z")._kernels().LANES == KEYED_LANES
    assert Table(np.r_[0.25, np.zeros(N_TABLE)])._kernels().LANES == KEYED_LANES
    assert CR3BP()._kernels().LANES == DEFAULT_LANES


def _lanes_with_bodies(dyn, states, times, pos):
    n = states.shape[0]
    out = np.empty((times.size, n, 6))
    ib, it, st = np.full(n, -1), np.full(n, np.inf), np.zeros(n, dtype=np.int64)
    _, rad = dyn._bodies_arrays()
    dyn._kernels().propagate_lanes_kernel(0, n, np.ascontiguousarray(states), dyn._params(), 0.0, times, dyn.rtol,
                                          dyn.atol, pos, rad, 5_000_000, np.zeros(n), out, ib, it, st)
    return out, ib, it, st


def _moon_divers_case():
    dyn = EphemerisDynamics(epoch="2026-01-01T00:00:00Z")
    times = np.array([0.2, 0.7, 1.5121])
    divers = [(7 * i, aim, 3000.0 * (i + 1), 1.0 + i)
              for i, aim in enumerate(([0.3, -0.5, 0.81], [-0.7, 0.1, 0.2], [0.0, 0.9, -0.4]))]
    states = _nrho_cloud_with_moon_divers(dyn, times, 70, 12, (3e-4, 1e-3), divers)
    pos, _ = dyn._bodies_arrays()
    return dyn, states, times, pos


def test_the_ephemeris_declares_the_earth_at_rest_and_bounds_the_moons_speed_and_acceleration():
    pos = _moon_divers_case()[3]
    assert pos.shape[1] == 5 and np.all(pos[0, 3:] == 0.0)  # Earth at rest
    assert 1.0 < pos[1, 3] < 2.0  # Moon ~1.5 km/s in VU
    assert 1.0 < pos[1, 4] < 2.0  # and ~4e-6 km/s^2 in LU/TU^2


@pytest.mark.parametrize("earth_km, moon_km", [(0.0, 0.0), (0.0, 1737.4), (6378.1, 0.0)])
def test_the_ephemeris_bounds_block_follows_the_impact_bodies_it_has(earth_km, moon_km):
    """No impact body (both radii 0) gives one empty row and no radii; one body, its own row."""
    dyn = EphemerisDynamics(epoch="2026-01-01T00:00:00Z", earth_radius_km=earth_km, moon_radius_km=moon_km)
    pos, rad = dyn._bodies_arrays()
    assert pos.shape == (max(rad.size, 1), 5) and rad.size == (earth_km > 0) + (moon_km > 0)
    if earth_km > 0:
        assert np.all(pos[0, 3:] == 0.0)  # the Earth at rest
    if moon_km > 0:
        assert np.all(pos[-1, 3:] > 0.0)  # the Moon bounded
    assert np.all(np.isfinite(dyn.propagate(ORBITS["nrho-9-2"].state[None], 0.0, 0.1).states))


def test_the_moving_moons_bounds_skip_evaluations_without_changing_any_result():
    """The lockstep driver evaluates the moving Moon on a grid of times and skips its series when
    a particle is farther from the grid's chord than the radius plus what the speed or
    acceleration bound allows: with either bound alone, both unknown (inf, negative, NaN), or the
    columns missing, the results agree bit for bit, the Moon impacts included."""
    dyn, states, times, pos = _moon_divers_case()
    bounded = _lanes_with_bodies(dyn, states, times, pos)
    assert (bounded[1] == 1).sum() >= 3  # the aimed particles hit the moving Moon
    variants = [np.ascontiguousarray(pos[:, :3]), np.ascontiguousarray(pos[:, :4])]
    for column in (3, 4):
        for unknown in (np.inf, -1.0, np.nan):
            odd = pos.copy()
            odd[1, column] = unknown
            variants.append(odd)
    both_unknown = pos.copy()
    both_unknown[1, 3:] = np.inf
    variants.append(both_unknown)
    for other in variants:
        assert same_results(bounded, _lanes_with_bodies(dyn, states, times, other))


def test_the_moons_bounds_change_no_result_backwards_in_time():
    """The same backwards (the grid runs from t0 down), with particles rising from the Moon at
    t = 0, which backwards in time fall onto it."""
    dyn = EphemerisDynamics(epoch="2026-01-01T00:00:00Z")
    times = np.array([-0.2, -0.7])
    risers = [(7 * i, aim, 3000.0 * (i + 1), -1.0 - i)
              for i, aim in enumerate(([0.3, -0.5, 0.81], [-0.7, 0.1, 0.2], [0.0, 0.9, -0.4]))]
    states = _nrho_cloud_with_moon_divers(dyn, times, 70, 13, (3e-4, 1e-3), risers)
    pos, _ = dyn._bodies_arrays()
    bounded = _lanes_with_bodies(dyn, states, times, pos)
    unknown = pos.copy()
    unknown[1, 3:] = np.inf
    assert same_results(bounded, _lanes_with_bodies(dyn, states, times, unknown))
    assert (bounded[1] == 1).sum() >= 3


@pytest.mark.parametrize("column", [3, 4], ids=["speed", "acceleration"])
def test_a_false_bound_on_the_moons_motion_changes_the_results(column):
    """Over a long span the grid's times are far apart (0.24 TU here), and a chord of the Moon's
    orbit is thousands of km off it: a speed or acceleration bound the Moon breaks (1e-6) then
    passes particles inside the Moon as outside, so the bounds are what keeps the results."""
    dyn = EphemerisDynamics(epoch="2026-01-01T00:00:00Z")
    times = np.array([0.2, 1000.0])
    divers = [(i, aim, 3000.0 * (i + 1), 1.0 + i)
              for i, aim in enumerate(([0.3, -0.5, 0.81], [-0.7, 0.1, 0.2], [0.0, 0.9, -0.4]))]
    states = _nrho_cloud_with_moon_divers(dyn, times, 3, 12, (0.0, 0.0), divers)
    pos, _ = dyn._bodies_arrays()
    bounded = _lanes_with_bodies(dyn, states, times, pos)
    assert np.all(bounded[1] == 1)  # all three hit the Moon within the first day
    wrong = pos.copy()
    wrong[1, 3:] = np.inf
    wrong[1, column] = 1e-6
    assert not same_results(bounded, _lanes_with_bodies(dyn, states, times, wrong))


def test_the_moons_acceleration_bound_holds_over_de421():
    """MOON_ACCELERATION_BOUND_KMS2 against DE421's own second derivative of the geocentric
    Moon, every 0.25 day over the whole ephemeris (1899-2053)."""
    from cistrack.astro.ephemeris import de421
    from cistrack.plugins.dynamics.ephemeris_rhs import MOON_ACCELERATION_BOUND_KMS2

    d = de421()
    jd = np.arange(d.first_jd + 1.0, d.last_jd - 1.0, 0.25)
    peak = np.linalg.norm(d.moon_acceleration(jd), axis=1).max()
    assert 3.0e-6 < peak < MOON_ACCELERATION_BOUND_KMS2


def test_bodies_at_rest_have_speed_zero_and_bodies_moved_by_the_model_an_unknown_speed():
    pos, _ = CR3BP()._bodies_arrays()
    assert pos.shape[1] == 5 and np.all(pos[:, 3:] == 0.0)

    class Moved(CR3BP):
        body_motion = CR3BP.body_motion or (lambda *a: None)

    assert np.all(np.isinf(Moved()._bodies_arrays()[0][:, 3:]))


@pytest.mark.parametrize("model", ["cr3bp", "ephemeris"])
def test_every_public_name_a_generated_kernel_module_defines_is_reserved(model):
    """A model's right-hand side that read a module constant of the same name (``ROW_T``, say)
    would be imported into the kernel module and then overwritten by the kernel's own: the
    rewriter refuses a body that reads any name in RESERVED, so RESERVED must hold them all."""
    import ast
    from pathlib import Path

    dyn = CR3BP() if model == "cr3bp" else EphemerisDynamics(epoch="2026-01-01T00:00:00Z")
    tree = ast.parse(Path(dyn._kernels().__file__).read_text())
    defined = set()
    for node in tree.body:
        if isinstance(node, ast.Assign):
            defined |= {t.id for t in node.targets if isinstance(t, ast.Name)}
        elif isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            defined.add(node.name)
    public = {name for name in defined if not name.startswith("_")}
    assert public - RESERVED == set()


ROW_T = 2.0  # a model constant that shares its name with a row of the kernel's work array


def _reads_row_t(t, y, p, out):
    for i in range(3):
        out[i] = y[i + 3]
        out[i + 3] = -ROW_T * y[i]


def test_a_body_reading_a_constant_named_like_a_kernel_row_is_refused():
    body, why = lane_body(_reads_row_t, RESERVED)
    assert body is None and "ROW_T" in why
