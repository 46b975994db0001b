"""``nhham linearize SCENE``: stability of the scene's ``[steady]`` motion.

Usage::

    nhham linearize SCENE [--json] [--exact | --numeric] [--sweep P=START:STOP:COUNT]
                          [--plot FILE]

The steady motion is linearised in independent coordinates on M_1
(:mod:`nhham.numerics.linearization`): state matrix, eigenvalues, verdict. Small
systems (n <= :data:`EXACT_MAX_N`) get the exact Jacobian
(:mod:`nhham.lagrangian.jacobian`) in the same chart, eigenvalues from it at
:data:`EXACT_DIGITS` digits; larger ones the complex-step Jacobian. With
``--sweep`` the parameter P takes COUNT values from START to STOP (the steady
state moves with it when its ``[steady]`` entries use P), and the crossings of
the imaginary axis are located (:mod:`nhham.numerics.crossings`, from the same
batches as ``nhham sweep --what linearize``). ``--plot`` draws the root
locus (needs the optional matplotlib extra; no global backend is set).

JSON (the ``result`` of the envelope, schema ``$defs/linearize``):
``coordinates``, ``matrix``, ``eigenvalues`` ([re, im] pairs), ``stable``
(bool or null), ``spectrally_stable``, ``method``, ``precision``, ``neutral``,
``dependent``, ``chart``, ``steady_state``; ``loop`` (``closed``: the scene's
``[control]`` laws replace its inputs, the keys above are the closed loop's),
``control``, ``open_loop`` (null, or the open loop's linearisation with
``inputs`` and ``input_matrix``); ``sweep`` (null without
``--sweep``) = {``parameter``, ``values``, ``eigenvalues``, ``crossings``
[{``value``, ``kind``}]}; ``plot`` (the file written, or null).
"""

from __future__ import annotations

import re

from nhham.errors import InputError

__all__ = ["add_arguments", "cmd_linearize", "parse_sweep", "LINEARIZE_HELP"]

#: (short help, description, example) for ``nhham linearize --help``.
LINEARIZE_HELP = (
    "stability of the [steady] motion: state matrix, eigenvalues, sweeps",
    "Linearise the constrained dynamics about the scene's [steady] motion (an equilibrium or "
    "a steady motion, checked to lie on M_1 and to be steady) in independent coordinates, "
    "neutral directions divided out: state matrix, eigenvalues and a stability verdict "
    "(exact for small systems, complex-step otherwise); with [control] laws the closed loop, "
    "and the open loop's (A, B) under it. --sweep moves a parameter (and the "
    "steady motion with it) and locates where an eigenvalue crosses the imaginary axis.",
    "nhham linearize examples/whipple_bicycle.toml --sweep v=0:10:101 --plot locus.png")

_SWEEP = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*=\s*([^:]+):([^:]+):([^:]+)\s*$")


def add_arguments(parser) -> None:
    """The command's own options (the common ones are added by ``main``)."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--exact", dest="method", action="store_const", const="exact",
                       help="exact (symbolic) Jacobian whatever the size")
    group.add_argument("--numeric", dest="method", action="store_const", const="complex-step",
                       help="complex-step Jacobian whatever the size")
    parser.set_defaults(method="auto")
    parser.add_argument("--sweep", metavar="P=START:STOP:COUNT", default=None,
                        help="eigenvalues along parameter P, with crossings located")
    parser.add_argument("--plot", metavar="FILE", default=None,
                        help="root-locus plot of the sweep (needs matplotlib)")


def parse_sweep(text: str):
    """``"v=0:10:101"`` -> ``("v", array of 101 values)``.

    Raises
    ------
    InputError
        Naming what is wrong with the option.
    """
    import numpy as np

    match = _SWEEP.match(text or "")
    if not match:
        raise InputError(f"--sweep: expected PARAMETER=START:STOP:COUNT (e.g. v=0:10:101), "
                         f"got {text!r}")
    name, a, b, c = match.groups()
    try:
        start, stop = float(a), float(b)
        count = int(c)
    except ValueError:
        raise InputError(f"--sweep: START and STOP must be numbers and COUNT an integer, "
                         f"got {text!r}") from None
    if not (np.isfinite(start) and np.isfinite(stop)) or count < 2 or stop <= start:
        raise InputError(f"--sweep: need finite START < STOP and COUNT >= 2, got {text!r}")
    if count > 100000:
        raise InputError(f"--sweep: COUNT {count} is too large (at most 100000)")
    return name, np.linspace(start, stop, count)


def cmd_linearize(args, steps):
    """The command: load, :func:`nhham.journeys.stability.linearize`, plot; a
    :class:`~nhham.cli.envelope.CommandOutput`."""
    from nhham.cli.envelope import CommandOutput, scene_info
    from nhham.cli.loading import load_for
    from nhham.journeys.stability import linearize

    with steps.step(f"load scene {args.scene}"):
        scene = load_for(args, check_initial=False, singular=True)  # [steady], not [initial]
    args.loaded_scene = scene  # the envelope of a later failure names the scene
    sweep = parse_sweep(args.sweep) if args.sweep else None
    if args.plot and sweep is None:
        raise InputError("--plot draws the root locus of a sweep: give --sweep too")
    if args.plot:
        from nhham.render.plotting import require_matplotlib

        require_matplotlib()  # fail before the work when the extra is missing
    answer = linearize(scene, method=args.method, sweep=sweep, steps=steps)
    if args.plot:
        from nhham.render.plotting import plot_root_locus

        with steps.step(f"plot {args.plot}"):
            answer = answer.with_data(plot=plot_root_locus(answer.payload["sweep"], args.plot,
                                                           title=scene.name))
    return CommandOutput(result=answer.to_dict(), text=answer.render, scene=scene_info(scene),
                         warnings=list(answer.warnings))
