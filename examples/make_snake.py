"""Write the scene file of the N-link nonholonomic snake.

Usage::

    python examples/make_snake.py N [PATH]

writes ``snake_<N>.toml`` (or PATH; ``-`` for standard output). The system
is :func:`nhham.models.snake` (N uniform links, a knife edge at each link's
centre, coordinates x, y, theta1..thetaN). The initial state is the straight
snake along the x axis moving forward with link rates alternating +-1/2,
which satisfies every constraint exactly: with all angles 0, constraint i
reads y' + (l/2)(theta1' + 2 theta2' + ... + 2 theta_{i-1}' + theta_i') = 0.
"""

from __future__ import annotations

import sys
from fractions import Fraction
from pathlib import Path

import sympy as sp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from scene_output import SIMULATE, write_scene  # noqa: E402
from nhham.system.models import snake  # noqa: E402


def initial_state(N):
    """Straight snake, x' = 1, y' = 0, theta_i' alternating with theta1' = 1/2 (exact)."""
    rates = [Fraction(1, 2)]
    for i in range(1, N):
        # theta_i' = -(theta_1' + 2 theta_2' + ... + 2 theta_{i-1}')
        rates.append(-(rates[0] + 2 * sum(rates[1:i])))
    state = {"x": 0.0, "y": 0.0}
    state.update({f"theta{i + 1}": 0.0 for i in range(N)})
    state.update({"x_dot": 1.0, "y_dot": 0.0})
    state.update({f"theta{i + 1}_dot": float(r) for i, r in enumerate(rates)})
    return state


def check_initial(system, state):
    """Every constraint vanishes exactly (rational arithmetic) at ``state``."""
    point = {s: sp.Rational(str(state[s.name])) for s in system.state}
    point.update({p: sp.Rational(str(v)) for p, v in system.parameter_values.items()})
    for i, c in enumerate(system.constraints):
        residual = sp.nsimplify(c.xreplace(point))
        if residual != 0:
            raise AssertionError(f"constraints[{i}] = {residual} at the initial state")


def header(N):
    """What `nhham classify` should report for the N-link snake."""
    second = 2 * (N // 2)
    return "\n".join([
        f"# The {N}-link nonholonomic snake (written by examples/make_snake.py {N}).",
        "# N uniform links (mass m, length l, inertia m l^2/12) joined by pin joints, a",
        "# knife edge at every link's centre; x, y = centre of link 1, theta_i = link angles.",
        "#",
        "# What `nhham classify` should report:",
        f"#   regular: yes; W positive definite and mu of rank {N}, so C = -mu W^-1 mu^T is",
        f"#     negative definite: rank C = {N}",
        "#   constraint algorithm: M_f = M_1 (one stage); status: determined;",
        "#     free multipliers: 0",
        "#   integrability: not integrable (each knife edge is nonholonomic)",
        f"#   Hamiltonian side: {N} final constraints; their bracket matrix is antisymmetric,",
        f"#     of rank 2 floor(N/2) = {second} at generic points of M_1 (computed",
        "#     numerically for N = 1..8): "
        f"{N - second} first class, {second} second class",
        "#   [initial]: the straight snake moving forward with link rates +-1/2.",
        "",
    ])


def scene_text(N):
    system = snake(N)
    state = initial_state(N)
    check_initial(system, state)
    try:
        from nhham.system.scene_dump import dump_scene
    except ImportError:  # scene.py not there yet: write the TOML here
        body = _dump(system, state)
    else:
        body = dump_scene(system, initial=state, simulate=SIMULATE)
    return header(N) + body


def _dump(system, state):
    """Minimal TOML writer (DESIGN.md §3) for when nhham.scene is unavailable."""
    from nhham.system.expressions import to_text

    def string(s):
        return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'

    params = ", ".join(f"{p.name} = {v!r}" for p, v in system.parameter_values.items())
    lines = [
        f"name = {string(system.name)}",
        "coordinates = [" + ", ".join(string(q.name) for q in system.coordinates) + "]",
        f"parameters = {{ {params} }}",
        f"lagrangian = {string(to_text(system.lagrangian))}",
        "constraints = [",
        *[f"    {string(to_text(c))}," for c in system.constraints],
        "]",
        "holonomic = []",
        "",
        "[initial]",
        *[f"{k} = {v!r}" for k, v in state.items()],
        "",
        "[simulate]",
        *[f"{k} = {string(v) if isinstance(v, str) else repr(v)}" for k, v in SIMULATE.items()],
    ]
    return "\n".join(lines) + "\n"


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if not argv or len(argv) > 2 or not argv[0].isdigit() or int(argv[0]) < 1:
        print("usage: python examples/make_snake.py N [PATH]   (N >= 1; PATH '-' for stdout)",
              file=sys.stderr)
        return 2
    N = int(argv[0])
    text = scene_text(N)
    target = argv[1] if len(argv) == 2 else f"snake_{N}.toml"
    write_scene(text, target)
    if target != "-":
        print(f"wrote {target}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
