"""Linearisations in one batch against independent values and against ``linearize``.

- The bicycle in the benchmark's parameters (examples/whipple_bicycle_benchmark.toml):
  eigenvalues at speeds, trails and head angles far from the benchmark's against the
  closed form of Meijaard et al. (2007, Appendix A; tests/bicycle_benchmark.py, written
  from the paper), to 1e-10.
- A small system: the batch equals ``linearize`` state by state; states off M_1 or not
  steady get their status instead of an exception.
"""

import numpy as np
import pytest

from bicycle_benchmark import BENCHMARK, benchmark_state_matrix
from nhham.numerics.batch_linearization import linearize_batch
from nhham.numerics.codegen import numeric_model
from nhham.numerics.linearization import linearize
from nhham.system.models import chaplygin_sleigh


def matched(a, b):
    """max distance between two eigenvalue multisets (greedy nearest matching)."""
    b = list(b)
    worst = 0.0
    for z in a:
        j = int(np.argmin([abs(z - w) for w in b]))
        worst = max(worst, abs(z - b.pop(j)))
    return worst


def _states(scene, model, rows):
    names = model.parameter_names
    P = np.tile(np.asarray(model.parameter_values, dtype=float), (len(rows), 1))
    for i, row in enumerate(rows):
        for k, v in row.items():
            P[i, names.index(k)] = v
    Y = np.array([model.state(scene.steady.values(dict(zip(names, p)))) for p in P])
    return Y, P


def test_bicycle_far_from_the_benchmark_matches_its_closed_form(benchmark_bicycle):
    scene, model = benchmark_bicycle
    ref = linearize(model, scene.steady.values(model.parameters),
                    family=scene.steady.family(model.parameters))
    rows = [dict(v=0.5, c=0.0), dict(v=3.0, c=0.2), dict(v=9.0, c=-0.04),
            dict(v=5.0, c=0.08, lam=0.45), dict(v=2.0, c=0.12, lam=0.05, w=1.3),
            dict(v=6.0, c=0.06, mB=40.0, zB=-1.1)]
    Y, P = _states(scene, model, rows)
    batch = linearize_batch(model, Y, P, reference=ref)
    assert batch.coordinates == ("phi", "delta", "phi_dot", "delta_dot")
    assert (batch.status == 0).all()
    for row, ev, verdict in zip(rows, batch.eigenvalues, batch.verdicts):
        p = dict(BENCHMARK, **{k: v for k, v in row.items() if k != "v"})
        expected = np.linalg.eigvals(benchmark_state_matrix(row["v"], p))
        assert matched(ev, expected) < 1e-10 * max(1.0, np.abs(expected).max())
        assert verdict == (1 if expected.real.max() < 0 else 0)


def test_the_batch_is_linearize_state_by_state():
    model = numeric_model(chaplygin_sleigh())
    n = model.n
    speeds = [0.5, 1.0, -0.7, 2.0]
    states = []
    for u in speeds:   # straight-line motion along the sleigh's axis: x' = u, theta = 0
        state = dict.fromkeys(model.names, 0.0)
        state[model.names[n]] = u
        states.append(model.state(state))
    ref = linearize(model, states[0])
    batch = linearize_batch(model, np.array(states), reference=ref)
    for y, A, ev, verdict in zip(states, batch.matrices, batch.eigenvalues, batch.verdicts):
        lin = linearize(model, y, independent=ref.chart, neutral=list(ref.neutral))
        assert np.allclose(A, lin.matrix, rtol=1e-13, atol=1e-13)
        assert np.allclose(ev, lin.eigenvalues, rtol=1e-13, atol=1e-13)
        assert verdict == {True: 1, False: 0, None: -1}[lin.stable]


def test_states_off_the_manifold_or_moving_get_a_status():
    model = numeric_model(chaplygin_sleigh())
    n = model.n
    good = dict.fromkeys(model.names, 0.0)
    good[model.names[n]] = 1.0
    ref = linearize(model, good)
    off = dict(good)
    off[model.names[n + 1]] = 0.3           # a sideways velocity: the constraint fails,
    # and the chart's dependent velocity y' is solved from it (y' = a theta' = 0): the
    # good state's linearisation
    turning = dict(good)
    turning[model.names[n + 2]] = 0.5        # turning while moving (on M_1): not steady
    turning[model.names[n + 1]] = 0.5 * 0.5  # y' = a theta'  (a = 0.5)
    nowhere = dict(good)
    nowhere[model.names[n]] = np.nan         # no state at all
    states = np.array([model.state(s) for s in (good, off, turning, nowhere)])
    batch = linearize_batch(model, states, reference=ref)
    assert list(batch.status) == [0, 0, 2, 1]
    assert np.allclose(batch.matrices[1], batch.matrices[0], atol=1e-12)
    assert np.isnan(batch.eigenvalues[2:]).all() and list(batch.verdicts[2:]) == [-1, -1]
    assert batch.acceleration_residuals[2] > 0.01


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_both_kernels_give_the_same_jacobians(backend, benchmark_bicycle):
    scene, model = benchmark_bicycle
    if backend == "numpy":
        model = numeric_model(scene.system, backend="numpy")
    ref = linearize(model, scene.steady.values(model.parameters),
                    family=scene.steady.family(model.parameters))
    Y, P = _states(scene, model, [dict(v=4.0, c=0.1)])
    batch = linearize_batch(model, Y, P, reference=ref)
    p = dict(BENCHMARK, c=0.1)
    expected = np.linalg.eigvals(benchmark_state_matrix(4.0, p))
    assert matched(batch.eigenvalues[0], expected) < 1e-10
