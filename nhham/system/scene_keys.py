"""Every key of a scene file: what it holds, whether it takes expressions, which commands
read it, and an example (the one home of the scene format's reference).

The structure check (:mod:`nhham.system.scene_structure`) takes its top-level keys from
:data:`SCENE_KEYS`, and ``docs/scene.rst`` is :func:`reference` written out
(``python -m nhham.system.scene_keys > docs/scene.rst``); a test checks both, so a key the
reader accepts cannot be missing from the page. Each example is a fragment added to the
scene of :data:`BASE` and loaded by the tests.

Examples
--------
>>> from nhham.system.scene_keys import SCENE_KEYS, key
>>> key("simulate.t_end").read_by
('simulate', 'bench', 'sweep --what simulate')
>>> [k.name for k in SCENE_KEYS if k.required]
['coordinates', 'lagrangian']
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["SceneKey", "SCENE_KEYS", "BASE", "key", "top_level_keys", "reference",
           "example_scene", "EVERY_COMMAND"]

#: What "read by every command" means in :attr:`SceneKey.read_by`.
EVERY_COMMAND = ("every command",)

#: The scene the examples extend: a Chaplygin sleigh (x, y, heading theta).
BASE = '''coordinates = ["x", "y", "theta"]
parameters = { m = 1.0, I = 0.25, a = 0.5 }
lagrangian = "m*(x_dot**2 + y_dot**2)/2 + I*theta_dot**2/2"
constraints = ["-sin(theta)*x_dot + cos(theta)*y_dot - a*theta_dot"]
'''

_STATE_EXPRESSIONS = "coordinates, velocities (``<q>_dot``), parameters, ``t``"
_PARAMETER_EXPRESSIONS = "parameters"
_SIMULATION = ("simulate", "bench", "sweep --what simulate")
_STABILITY = ("linearize", "sweep --what linearize")


@dataclass(frozen=True)
class SceneKey:
    """One key of a scene file.

    Attributes
    ----------
    name : str
        The key's path (``simulate.t_end`` for a key of a table).
    kind : str
        What its value is, in TOML terms.
    summary : str
        What it means.
    expressions : str
        The names an expression there may use ("": it takes none).
    read_by : tuple of str
        The commands that read it (:data:`EVERY_COMMAND`: all of them); a table read by
        some commands only is checked by those only (its problems do not stop the others).
    example : str
        A TOML fragment (added after :data:`BASE`; a table's keys follow its header).
    required : bool
        The scene must give it.
    """

    name: str
    kind: str
    summary: str
    expressions: str = ""
    read_by: tuple = EVERY_COMMAND
    example: str = ""
    required: bool = False


SCENE_KEYS: tuple = (
    SceneKey("name", "string", "The scene's name, the heading of every report.",
             example='name = "Chaplygin sleigh"'),
    SceneKey("description", "string", "A sentence about the system, kept with the scene "
             "(``Scene.description``) and written back by ``dump_scene``.",
             example='description = "a blade that cannot slide sideways"'),
    SceneKey("coordinates", "array of names", "The generalized coordinates q. A coordinate "
             "``x`` has the velocity ``x_dot``, the acceleration ``x_ddot`` and the momentum "
             "``p_x``.", required=True, example='coordinates = ["x", "y", "theta"]'),
    SceneKey("parameters", "table of name = number or expression",
             "The parameters with their values. A value may be an expression in the other "
             "parameters (``I = \"m*a**2\"``), evaluated in the order they depend on each "
             "other; ``--set NAME=VALUE`` replaces a value for one run.",
             expressions=_PARAMETER_EXPRESSIONS,
             example='parameters = { m = 1.0, a = 0.5, I = "m*a**2" }'),
    SceneKey("symbolic_parameters", "array of names", "Parameters without a value: the "
             "answers keep them as symbols (``classify --parametric`` splits the verdict by "
             "their values); a command that needs numbers refuses them by name.",
             example='symbolic_parameters = ["k"]'),
    SceneKey("lagrangian", "string (expression)", "L(q, v, t), regular (its Hessian in the "
             "velocities invertible).", expressions=_STATE_EXPRESSIONS, required=True,
             example='lagrangian = "m*(x_dot**2 + y_dot**2)/2 + I*theta_dot**2/2"'),
    SceneKey("constraints", "array of strings (expressions)", "Velocity constraints "
             "phi(q, v, t) = 0: affine in the velocities, or nonlinear (Chetaev's rule, "
             "reaction along d phi/d v). Named ``constraints[i]`` in every report.",
             expressions=_STATE_EXPRESSIONS,
             example='constraints = ["-sin(theta)*x_dot + cos(theta)*y_dot - a*theta_dot"]'),
    SceneKey("holonomic", "array of strings (expressions)", "Position constraints "
             "g(q, t) = 0 (their time derivatives are imposed on the velocities). Named "
             "``holonomic[i]``.", expressions="coordinates, parameters, ``t``",
             example="holonomic = []"),
    SceneKey("inputs", "array of names", "Inputs u the forces and the dissipation may use "
             "(generic constants for the exact answers; laws in ``[control]``, values in "
             "``[steady]``).", example='inputs = ["F"]'),
    SceneKey("forces", "table of coordinate = expression, or one expression (the 1-form in "
             "``d<q>``)", "Generalized forces Q_A(q, v, t, u) on the right of "
             "d/dt dL/dv - dL/dq = Q - mu^T lambda.",
             expressions=_STATE_EXPRESSIONS + ", inputs",
             example='inputs = ["F"]\nforces = { x = "F*cos(theta)", y = "F*sin(theta)" }'),
    SceneKey("dissipation", "string (expression)", "A Rayleigh function R(q, v): adds "
             "-dR/dv to the forces.", expressions=_STATE_EXPRESSIONS + ", inputs",
             example='dissipation = "c*theta_dot**2/2"\nsymbolic_parameters = ["c"]'),
    SceneKey("initial", "table of state name = number, expression or { guess = number }",
             "The initial state: the independent coordinates and velocities; those left out "
             "are solved (velocities exactly from the constraints, coordinates by Newton on "
             "the holonomic ones from 0 or from ``{ guess = ... }``) and named in a "
             "warning. A full table off the constraints is refused unless "
             "``simulate --project-initial``.", expressions=_PARAMETER_EXPRESSIONS,
             read_by=_SIMULATION,
             example='[initial]\nx = 0.0\ny = 0.0\ntheta = "pi/4"\nx_dot = 1.0\n'
                     'theta_dot = "1/a"'),
    SceneKey("simulate", "table", "Defaults of ``nhham simulate`` (its options replace "
             "them).", read_by=_SIMULATION,
             example='[simulate]\nt_end = 10.0\nmethod = "DOP853"\nrtol = 1e-10'),
    SceneKey("simulate.t_end", "number or expression", "Final time (> 0; default 10).",
             expressions=_PARAMETER_EXPRESSIONS, read_by=_SIMULATION,
             example='[simulate]\nt_end = "20*pi*a"'),
    SceneKey("simulate.method", "string", "The integration method (``nhham simulate "
             "--help`` lists them).", read_by=_SIMULATION,
             example='[simulate]\nmethod = "rattle"\nstep = 0.01'),
    SceneKey("simulate.rtol", "number or expression", "Relative tolerance of the adaptive "
             "methods (at least 100 machine epsilons, below 1).",
             expressions=_PARAMETER_EXPRESSIONS, read_by=_SIMULATION,
             example="[simulate]\nrtol = 1e-9"),
    SceneKey("simulate.atol", "number or expression", "Absolute tolerance of the adaptive "
             "methods (> 0).", expressions=_PARAMETER_EXPRESSIONS, read_by=_SIMULATION,
             example="[simulate]\natol = 1e-12"),
    SceneKey("simulate.step", "number or expression", "Step of the fixed-step methods "
             "(0 < step <= t_end, at most 1e8 steps).", expressions=_PARAMETER_EXPRESSIONS,
             read_by=_SIMULATION, example='[simulate]\nmethod = "rk4"\nstep = "a/50"'),
    SceneKey("simulate.max_step", "number or expression", "Largest step of the adaptive "
             "methods (> 0).", expressions=_PARAMETER_EXPRESSIONS, read_by=_SIMULATION,
             example="[simulate]\nmax_step = 0.1"),
    SceneKey("simulate.symmetry", "list of coordinate names", "The symmetry coordinates "
             "of the reduction that ``method = \"hamiltonized\"`` integrates (as ``nhham "
             "hamiltonize --symmetry``; default: found among the cyclic ones).",
             read_by=("simulate",),
             example='[simulate]\nmethod = "hamiltonized"\nstep = 0.05\nsymmetry = ["x", "y"]'),
    SceneKey("simulate.then", "list of coordinate names", "A second reduction step for "
             "``method = \"hamiltonized\"`` (as ``nhham hamiltonize --then``: the rubber "
             "ball's no-twist constraint).", read_by=("simulate",),
             example='[simulate]\nmethod = "hamiltonized"\nstep = 0.05\n'
                     'symmetry = ["x", "y"]\nthen = ["yaw"]'),
    SceneKey("steady", "table of state name (and input) = number or expression",
             "A steady (or relative steady) motion: a value for every coordinate, velocity "
             "and input; ``linearize`` checks it and linearises about it.",
             expressions=_PARAMETER_EXPRESSIONS, read_by=_STABILITY,
             example='[steady]\nx = 0.0\ny = 0.0\ntheta = 0.0\nx_dot = 1.0\ny_dot = 0.0\n'
                     'theta_dot = 0.0'),
    SceneKey("symmetry", "table of coordinate = expression", "The generator xi of a "
             "one-parameter symmetry group by coordinate (omitted: 0), checked to leave L, "
             "the constraints and the forces invariant; ``linearize`` divides out its orbit "
             "and linearises a relative equilibrium about it.",
             expressions="coordinates, parameters", read_by=_STABILITY,
             example='[symmetry]\nx = "-y"\ny = "x"\ntheta = "1"'),
    SceneKey("gauge", "table", "Gauge conditions of a singular Lagrangian whose "
             "Dirac-Bergmann chain leaves multipliers free (first-class constraints): "
             "``simulate`` and ``linearize`` add them to the chain, where they must fix every "
             "multiplier; ``classify`` ignores them (the classes are the Lagrangian's).",
             read_by=("simulate", "linearize"),
             example='lagrangian = "((x_dot + theta*y)**2 + (y_dot - theta*x)**2)/2"\n'
                     '[gauge]\nconditions = ["theta", "y"]'),
    SceneKey("gauge.conditions", "array of expressions", "The conditions chi(q) = 0, "
             "one string each.", expressions="coordinates, parameters",
             read_by=("simulate", "linearize"),
             example='lagrangian = "((x_dot + theta*y)**2 + (y_dot - theta*x)**2)/2"\n'
                     '[gauge]\nconditions = ["theta", "y"]'),
    SceneKey("control", "table of input = expression", "Laws of the inputs, closing the "
             "loop that ``simulate`` integrates and ``linearize`` linearises (the open "
             "loop's (A, B) beside it).", expressions=_STATE_EXPRESSIONS,
             read_by=_SIMULATION + _STABILITY,
             example='inputs = ["F"]\nforces = { x = "F*cos(theta)", y = "F*sin(theta)" }\n'
                     '[control]\nF = "-x_dot"'),
    SceneKey("contacts", "table of [contacts.<name>] tables", "Contact points whose force "
             "``simulate`` (``contact_forces``) and ``derive`` report.",
             read_by=("simulate", "derive"),
             example='[contacts.blade]\nvelocity = ["x_dot + a*sin(theta)*theta_dot", '
                     '"y_dot - a*cos(theta)*theta_dot", "0"]\nconstraints = ["constraints[0]"]'),
    SceneKey("contacts.<name>.velocity", "array of three expressions", "The material "
             "velocity of the body at the contact point, in the inertial frame.",
             expressions=_STATE_EXPRESSIONS, read_by=("simulate", "derive")),
    SceneKey("contacts.<name>.constraints", "array of constraint labels", "The constraints "
             "the contact carries (``constraints[i]``, ``holonomic[i]``).",
             read_by=("simulate", "derive")),
)


def key(name: str) -> SceneKey:
    """The :class:`SceneKey` named ``name`` (KeyError if there is none)."""
    for k in SCENE_KEYS:
        if k.name == name:
            return k
    raise KeyError(name)


def example_scene(entry: SceneKey) -> str:
    """The scene of an example: :data:`BASE` with the fragment added (a top-level key the
    fragment gives replaces the base's line).

    >>> print(example_scene(key("simulate.rtol")))
    coordinates = ["x", "y", "theta"]
    parameters = { m = 1.0, I = 0.25, a = 0.5 }
    lagrangian = "m*(x_dot**2 + y_dot**2)/2 + I*theta_dot**2/2"
    constraints = ["-sin(theta)*x_dot + cos(theta)*y_dot - a*theta_dot"]
    [simulate]
    rtol = 1e-9
    <BLANKLINE>
    """
    lines = entry.example.splitlines()
    first_table = next((i for i, line in enumerate(lines) if line.startswith("[")), len(lines))
    given = {line.split("=")[0].strip() for line in lines[:first_table] if "=" in line}
    base = [line for line in BASE.splitlines() if line.split("=")[0].strip() not in given]
    return "\n".join(lines[:first_table] + base + lines[first_table:]) + "\n"


def top_level_keys() -> tuple:
    """The keys a scene may have at its top level, in the reference's order."""
    return tuple(k.name for k in SCENE_KEYS if "." not in k.name)


def reference() -> str:
    """The reference page (reStructuredText) of every key, made from :data:`SCENE_KEYS`."""
    from nhham.system.expressions import CONSTANTS, FUNCTIONS

    names = " ".join(FUNCTIONS)
    constants = ", ".join(f"``{c}``" for c in CONSTANTS)
    lines = [
        "Scene files",
        "===========",
        "",
        ".. This page is generated: python -m nhham.system.scene_keys > docs/scene.rst",
        "",
        "A scene is a TOML file describing one system. Expressions are strings parsed "
        f"against a symbol table (the scene's names, the functions {names} and "
        f"{constants}); nothing is "
        "evaluated as Python, and ``I``, ``E``, ``S``, ``N`` are ordinary names. Unknown "
        "keys and names are errors naming the key, with the closest known one. Where a "
        "number is read, an expression in the parameters may be given instead. A table "
        "that only some commands read is checked by those commands only.",
        "",
        "Every example below is a fragment added to this scene (a Chaplygin sleigh; a key the "
        "fragment gives replaces the line of the scene):",
        "",
        ".. code-block:: toml",
        "",
        *("   " + line for line in BASE.splitlines()),
        "",
        ".. list-table::",
        "   :header-rows: 1",
        "   :widths: 20 25 15 20",
        "",
        "   * - key",
        "     - value",
        "     - expressions in",
        "     - read by",
    ]
    for k in SCENE_KEYS:
        lines += [f"   * - ``{k.name}``" + (" (required)" if k.required else ""),
                  f"     - {k.kind}",
                  f"     - {k.expressions or '—'}",
                  f"     - {', '.join(k.read_by)}"]
    for k in SCENE_KEYS:
        title = f"``{k.name}``"
        lines += ["", title, "-" * len(title), "", k.summary, ""]
        if k.example:
            lines += [".. code-block:: toml", "", *("   " + x for x in k.example.splitlines())]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":  # pragma: no cover - writes docs/scene.rst
    print(reference(), end="")
