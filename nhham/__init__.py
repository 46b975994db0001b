"""nhham: mechanical systems with non-holonomic constraints.

The package is layered; each layer imports only from those beneath it:

``nhham.system``
    what the user describes: :class:`System`, the safe expression parser,
    scene files, the sympy.physics.mechanics adapter, ready-made models;
``nhham.lagrangian``
    the paper on TQ: decisions on M_k, the geometry of Sections 2 and 4, the
    constraint algorithm of Section 3, integrability, Section 5 symmetries;
``nhham.hamiltonian``
    Section 6 on T*Q: Legendre map, brackets, first/second class, Dirac and
    nonholonomic brackets, the Lagrangian/Hamiltonian cross-check;
``nhham.verdict``
    the whole-system verdict: at the scene's parameter values, and for every value;
``nhham.numerics``
    numbers without sympy (generated kernels, integrators, reference,
    diagnostics, work-precision); its ``codegen`` is the one bridge in;
``nhham.cli``
    the ``nhham`` command, its text and JSON reports, and the plots.

Public names are re-exported here explicitly, each imported on first use
(PEP 562), so that ``import nhham`` is quick (the command
loads sympy inside its Ctrl-C handler) and a command which only classifies never
imports the numerical integrators.
"""

from nhham.lazy import lazy_exports

from nhham.settings import __version__ as __version__

# name -> module that defines it
_LAZY = {
    # the exceptions, rooted at NhhamError
    **{name: "errors" for name in (
        "NhhamError", "InputError", "ParseError", "SceneError", "ValidationError",
        "SingularLagrangianError", "NonAffineConstraintError", "RedundantConstraintError",
        "MissingParameterValueError", "InconsistentInitialDataError",
        "OptionalDependencyError", "ComputationError", "BudgetExceeded", "NhhamWarning")},
    # the system description
    "System": "system.description",
    "DroppedConstraint": "system.description",
    # Lagrangian side (paper Sections 2, 4, 5)
    "lagrangian_geometry": "lagrangian.geometry",
    "LagrangianGeometry": "lagrangian.geometry",
    "DynamicsIngredients": "lagrangian.geometry",
    "Submanifold": "lagrangian.submanifold",
    "Decision": "lagrangian.decision",
    "constant_of_motion": "lagrangian.symmetries",
    "cyclic_constants": "lagrangian.symmetries",
    "lie_symmetry": "lagrangian.symmetries",
    "complete_lift": "lagrangian.symmetries",
    # constraint algorithm (Section 3)
    "analyze_constraints": "lagrangian.analysis",
    "ConstraintAnalysis": "lagrangian.analysis",
    "run_algorithm": "lagrangian.algorithm",
    "integrability": "lagrangian.integrability",
    # verdicts for every parameter value
    "parametric_classification": "verdict.parametric",
    "classification_at_values": "verdict.values",
    "exceptional_conditions": "lagrangian.exceptional",
    "Verdict": "verdict.results",
    "ParametricVerdict": "verdict.results",
    "ValuesVerdict": "verdict.results",
    # Hamiltonian side (Section 6)
    "legendre_map": "hamiltonian.legendre",
    "LegendreMap": "hamiltonian.legendre",
    "canonical_bracket": "hamiltonian.brackets",
    "BracketAlgebra": "hamiltonian.brackets",
    "hamiltonian_side": "hamiltonian.side",
    "HamiltonianSide": "hamiltonian.side",
    "nonholonomic_bracket": "hamiltonian.side",
    "classify_constraints": "hamiltonian.classification",
    "ConstraintClasses": "hamiltonian.classes",
    "dirac_bracket": "hamiltonian.dirac",
    "dirac_vs_projected": "hamiltonian.dirac",
    "cross_check": "hamiltonian.crosscheck",
    "CrossCheckReport": "hamiltonian.checks",
    # numbers
    "numeric_model": "numerics.codegen",
    "NumericModel": "numerics.model",
    "simulate": "numerics.integrate",
    "SimulationResult": "numerics.integrate",
    "work_precision": "numerics.workprecision",
    # a bound on the time of a computation (the command's --budget)
    "time_budget": "budget",
    # stability of steady motions
    "linearize": "numerics.linearization",
    "Linearization": "numerics.linearization",
    "sweep_steady": "numerics.steady_sweep",
    "Sweep": "numerics.steady_sweep",
    "linearize_scene": "cli.linearize_command",
    "plot_root_locus": "cli.linearize_command",
    # input and output
    "load_scene": "system.scene",
    "loads_scene": "system.scene",
    "dump_scene": "system.scene_dump",
    "Scene": "system.scene",
    "parse_expression": "system.expressions",
    "from_mechanics": "system.mechanics",
    "from_lagranges_method": "system.mechanics",
    "models": "system.models",
    # reports, figures and the command's JSON contract
    "report": "cli.display",
    "plot_trajectory": "cli.plotting",
    "plot_work_precision": "cli.plotting",
    "output_schema": "cli.envelope",
}

__all__ = list(_LAZY)

__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
