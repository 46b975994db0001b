"""``nhham reduce SCENE`` and ``nhham hamiltonize SCENE``: the Chaplygin reduction and
Chaplygin's multiplier (:mod:`nhham.journeys.reduction`).

JSON (the ``result`` of the envelope, schema ``$defs/reduce`` and ``$defs/hamiltonize``):
see :func:`nhham.journeys.reduction.reduce` and :func:`nhham.journeys.reduction.hamiltonize`.
"""

from __future__ import annotations

__all__ = ["REDUCE_HELP", "HAMILTONIZE_HELP", "add_arguments", "cmd_reduce",
           "cmd_hamiltonize"]

#: (short help, description, example) for ``nhham reduce --help``.
REDUCE_HELP = (
    "the Chaplygin reduction to the shape space",
    "Reduce an abelian Chaplygin system (cyclic coordinates s whose velocities the "
    "constraints solve, s' = -A(r) r') to its shape space: L_c, the momenta J, the "
    "curvature B, the reduced equations d/dt dL_c/dr' - dL_c/dr = J B r' and the "
    "reconstruction; the reduced field lifted back is checked against P(xi_L).",
    "nhham reduce examples/rolling_disc_3d.toml")

#: (short help, description, example) for ``nhham hamiltonize --help``.
HAMILTONIZE_HELP = (
    "Chaplygin's multiplier: Hamiltonian after a change of time?",
    "Decide whether the reduced system of a Chaplygin scene has a conformal factor f(r) "
    "with d(f Omega_nh) = 0 (Hamiltonian after dtau = dt/f): solve theta ^ Omega_nh = "
    "-d Omega_nh exactly, f = exp of theta's potential when theta is closed and free of "
    "the momenta; otherwise the obstruction. Jacobiators before and after, the invariant "
    "measure f^(k-1).",
    "nhham hamiltonize examples/nonholonomic_particle.toml --json")


def add_arguments(p) -> None:
    """reduce, hamiltonize: the symmetry coordinates."""
    p.add_argument("--symmetry", default=None, metavar="S1,S2",
                   help="the symmetry coordinates s (default: found among the cyclic ones)")
    p.add_argument("--then", default=None, metavar="C1,C2",
                   help="a second step: reduce these shape coordinates of the first step "
                        "by the constraints left on the shape space (e.g. the rubber ball's "
                        "no twist), or by their momentum level with --level")
    p.add_argument("--level", default=None, metavar="C=0",
                   help="reduce C on the level p_C = 0 of its conserved momentum (the "
                        "results then hold on that level only); implies --then C")
    p.add_argument("--latex", action="store_true",
                   help="print LaTeX instead of text")


def _symmetry(args):
    return None if args.symmetry is None else [s.strip() for s in args.symmetry.split(",")
                                               if s.strip()]


def _names(text):
    return None if text is None else [s.strip() for s in text.split(",") if s.strip()]


def _level(args):
    """--level C=V,... as {C: V}; a malformed item exits 2 naming the option."""
    from nhham.errors import InputError

    if args.level is None:
        return None
    found = {}
    for item in _names(args.level) or [""]:
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise InputError(f"--level: expected C=VALUE, got {item!r}", key="level")
        found[name.strip()] = value.strip()
    return found


def _run(args, steps, journey):
    from nhham.cli.envelope import CommandOutput, scene_info
    from nhham.cli.loading import load_for

    with steps.step(f"load scene {args.scene}"):
        scene = load_for(args, check_initial=False)
    args.loaded_scene = scene  # the envelope of a later failure names the scene
    answer = journey(scene, symmetry=_symmetry(args), then=_names(args.then),
                     level=_level(args), steps=steps)
    text = answer.latex_text if args.latex else answer.render
    return CommandOutput(result=answer.to_dict(), text=text, scene=scene_info(scene),
                         warnings=list(answer.warnings), failure=answer.failure)


def cmd_reduce(args, steps):
    """The Chaplygin reduction of the scene."""
    from nhham.journeys.reduction import reduce

    return _run(args, steps, reduce)


def cmd_hamiltonize(args, steps):
    """Chaplygin's multiplier of the scene."""
    from nhham.journeys.reduction import hamiltonize

    return _run(args, steps, hamiltonize)
