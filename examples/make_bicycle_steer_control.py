"""Write examples/bicycle_steer_control.toml: the Whipple bicycle with lean and steer torques
and a steer-torque feedback that holds it upright at 3 m/s, where it is not self-stable.

The scene is examples/whipple_bicycle.toml with

* inputs T_phi (a lean torque on the rear frame) and T_delta (the steer torque between the
  rear frame and the fork): generalized forces on phi and delta (Meijaard et al. 2007,
  M q'' + v C1 q' + (g K0 + v^2 K2) q = f with f = (T_phi, T_delta));
* the forward speed v = 3 m/s (the benchmark bicycle weaves unstably below 4.29 m/s);
* a full-state feedback T_delta = -K (phi, delta, phi_dot, delta_dot) with K from
  ``scipy.signal.place_poles`` on the (A, B) that ``nhham linearize`` returns for the steer
  torque alone (poles -2, -3, -4, -5 rad/s), T_phi = 0;
* an [initial] lean of 0.1 rad at that speed, projected onto M_1 (the pitch and the
  dependent velocities solved from the constraints).

Run from the repository root: ``python examples/make_bicycle_steer_control.py``;
``--figure docs/bicycle_steer_control.png`` also draws the controlled run (lean, steer and
the steer torque against time, with the uncontrolled bicycle from the same lean; needs
matplotlib, the plot extra).
"""

import argparse
from pathlib import Path

import numpy as np
from scipy import signal

from nhham.numerics.codegen import numeric_model
from nhham.numerics.linearization import linearize
from nhham.numerics.steady_sweep import with_steady_inputs
from nhham.system.scene import loads_scene

HERE = Path(__file__).resolve().parent
SPEED = 3.0
POLES = (-2.0, -3.0, -4.0, -5.0)
LEAN = 0.1

HEADER = f"""# The Whipple bicycle of whipple_bicycle.toml with a lean torque T_phi and a steer torque
# T_delta (inputs; generalized forces on phi and delta), ridden at v = {SPEED:g} m/s where it is
# not self-stable (weave below 4.29 m/s), held upright by a steer-torque feedback
# T_delta = -K (phi, delta, phi_dot, delta_dot): K from scipy.signal.place_poles on the (A, B)
# of `nhham linearize` (poles {", ".join(f"{p:g}" for p in POLES)}). Written by
# examples/make_bicycle_steer_control.py.
#
# What `nhham linearize` gives: B = [0; M^-1] with M the benchmark's mass matrix (Meijaard et
#   al. 2007; to 1e-10, tests/numerics/test_forced_numerics.py), A as in whipple_bicycle.toml.
# What `nhham simulate` shows: from a lean of {LEAN:g} rad the controlled bicycle returns
#   upright (phi, delta -> 0 within a few seconds; README "Forces and inputs").
"""


def _state_line(name, value):
    return f"{name} = {float(value)!r}"


def figure(path):
    """Lean and steer of the controlled and the uncontrolled bicycle, and the steer torque."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import nhham
    from nhham.system.scene import load_scene
    from nhham.system.evaluation import numeric_function

    scene = load_scene(HERE / "bicycle_steer_control.toml")
    closed = nhham.simulate(scene.system.closed_loop(scene.control),
                            **scene.simulate_options(t_end=6.0))
    free = nhham.simulate(scene.system.closed_loop({"T_phi": "0", "T_delta": "0"}),
                          **scene.simulate_options(t_end=6.0))
    law = scene.control["T_delta"]
    names = sorted(law.free_symbols, key=lambda s: s.name)
    torque = numeric_function(names, [law])(*[closed[s.name] for s in names])
    fig, axes = plt.subplots(2, 1, figsize=(7.0, 5.5), sharex=True)
    ax = axes[0]
    ax.plot(closed.t, closed["phi"], label="lean phi, controlled", color="tab:blue")
    ax.plot(closed.t, closed["delta"], label="steer delta, controlled", color="tab:orange")
    # the uncontrolled bicycle falls over (weave): drawn until its lean passes 0.45 rad
    fallen = np.flatnonzero(np.abs(free["phi"]) > 0.45)
    end = fallen[0] + 1 if fallen.size else len(free.t)
    ax.plot(free.t[:end], free["phi"][:end], "--", label="lean phi, no control (falls)",
            color="tab:blue", alpha=0.6)
    ax.set_ylim(-0.35, 0.5)
    ax.set_ylabel("angle [rad]")
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(True, alpha=0.3)
    ax = axes[1]
    ax.plot(closed.t, np.ravel(torque), color="tab:green")
    ax.set_ylabel("steer torque T_delta [N m]")
    ax.set_xlabel("time t [s]")
    ax.grid(True, alpha=0.3)
    fig.suptitle(f"Whipple bicycle at {SPEED:g} m/s from a lean of {LEAN:g} rad: "
                 f"steer-torque feedback (poles {', '.join(f'{p:g}' for p in POLES)})",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print("wrote", path)


def main():
    text = (HERE / "whipple_bicycle.toml").read_text()
    body = text[text.index('name = "Whipple bicycle"'):]
    body = body.replace('name = "Whipple bicycle"',
                        'name = "Whipple bicycle with a steer-torque controller"', 1)
    body = body.replace("v = 5.0 }", f"v = {SPEED!r} }}", 1)
    body = body.replace("holonomic = [", 'inputs = ["T_phi", "T_delta"]\n'
                        'forces = { phi = "T_phi", delta = "T_delta" }\nholonomic = [', 1)
    body = body.replace("[steady]\n", "[steady]\nT_phi = 0.0\nT_delta = 0.0\n", 1)
    open_loop = loads_scene(body, check_initial=False)
    model = numeric_model(open_loop.system)
    model, state = with_steady_inputs(model, open_loop.steady.values(model.parameters))
    lin = linearize(model, state, family=open_loop.steady.family(model.parameters))
    assert lin.coordinates == ("phi", "delta", "phi_dot", "delta_dot"), lin.coordinates
    B = lin.input_matrix[:, [lin.inputs.index("T_delta")]]
    K = signal.place_poles(lin.matrix, B, POLES).gain_matrix[0]
    law = " + ".join(f"{float(k)!r}*{s}" for k, s in zip(K, lin.coordinates))
    start = dict(state)
    start["phi"] = LEAN
    projected = model.project(model.state(start)).y
    initial = "\n".join(_state_line(s, x) for s, x in zip(model.names, projected))
    head, tail = body.split("[initial]\n", 1)
    tail = tail[tail.index("\n\n") + 2:]
    control = f'[control]\nT_phi = "0"\nT_delta = "-({law})"\n\n'
    tail = tail.replace("[simulate]\n", control + "[simulate]\n", 1)
    out = HEADER + head + "[initial]\n" + initial + "\n\n" + tail
    (HERE / "bicycle_steer_control.toml").write_text(out)
    closed = np.linalg.eigvals(lin.matrix - B @ K[None, :])
    print("K =", K, "closed-loop eigenvalues", np.sort_complex(closed))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figure", metavar="PNG", help="also draw the controlled run")
    args = parser.parse_args()
    main()
    if args.figure:
        figure(args.figure)
