"""nhham: mechanical systems with non-holonomic constraints.

The package is layered (a tree: ``numerics`` stands beside the exact side, on
``lagrangian``); each layer imports only from those beneath it:

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
``nhham.render``
    the text, LaTeX and JSON forms of results, and their figures;
``nhham.journeys``
    what a user does with a scene, one function each (classify, derive, compare,
    linearize, simulate, bench): what the command runs and the studies evaluate;
``nhham.study``
    parameter studies: grids and samples evaluated in chunks on Dask, results as
    labelled xarray Datasets written as they come;
``nhham.cli``
    the ``nhham`` command: its options, and the envelope of its output.

Public names are re-exported here explicitly, each imported on first use
(PEP 562), so that ``import nhham`` is quick (the command
loads sympy inside its Ctrl-C handler) and a command which only classifies never
imports the numerical integrators.
"""

from nhham.lazy import by_module, lazy_exports

from nhham.settings import __version__ as __version__

# module that defines them -> public names
_LAZY = by_module({
    # what a user does with a scene, named like the commands (``nhham.journeys``)
    "journeys.answer": ("Answer",),
    "journeys.verdict": ("classify", "classify_parametric"),
    "journeys.derivation": ("derive",),
    "journeys.comparison": ("compare",),
    "journeys.benchmark": ("bench",),
    "journeys.reduction": ("reduce", "hamiltonize"),
    # the exceptions, rooted at NhhamError
    "errors": (
        "NhhamError", "InputError", "ParseError", "SceneError", "ValidationError",
        "SingularLagrangianError", "NonAffineConstraintError", "RedundantConstraintError",
        "MissingParameterValueError", "InconsistentInitialDataError",
        "OptionalDependencyError", "ComputationError", "BudgetExceeded", "NhhamWarning"),
    # the system description
    "system.description": ("System",),
    "system.sampled_checks": ("DroppedConstraint",),
    # Lagrangian side (paper Sections 2, 4, 5)
    "lagrangian.geometry": ("lagrangian_geometry", "LagrangianGeometry", "DynamicsIngredients"),
    "lagrangian.submanifold": ("Submanifold",),
    "lagrangian.decision": ("Decision",),
    "lagrangian.engine": ("Policy",),
    "lagrangian.symmetries": ("constant_of_motion", "cyclic_constants", "lie_symmetry",
                              "complete_lift"),
    # constraint algorithm (Section 3)
    "lagrangian.analysis": ("analyze_constraints", "ConstraintAnalysis"),
    "lagrangian.algorithm": ("run_algorithm",),
    "lagrangian.integrability": ("integrability",),
    # verdicts for every parameter value
    "verdict.parametric": ("parametric_classification",),
    "verdict.values": ("classification_at_values",),
    "lagrangian.exceptional": ("exceptional_conditions",),
    "verdict.results": ("Verdict", "ParametricVerdict", "ValuesVerdict"),
    # Hamiltonian side (Section 6)
    "hamiltonian.legendre": ("legendre_map", "LegendreMap"),
    "hamiltonian.brackets": ("canonical_bracket", "BracketAlgebra"),
    "hamiltonian.side": ("hamiltonian_side", "HamiltonianSide"),
    "hamiltonian.almost_poisson": ("nonholonomic_bracket",),
    "hamiltonian.classification": ("classify_constraints",),
    "hamiltonian.classes": ("ConstraintClasses",),
    "hamiltonian.dirac": ("dirac_bracket", "dirac_vs_projected"),
    "hamiltonian.crosscheck": ("cross_check",),
    # singular Lagrangians: the Dirac-Bergmann chain and the chain on TQ
    "hamiltonian.primary": ("legendre_image", "LegendreImage"),
    "hamiltonian.dirac_bergmann": ("dirac_bergmann", "DiracBergmann"),
    "hamiltonian.phase_motion": ("phase_motion", "PhaseMotion"),
    "lagrangian.singular": ("lagrangian_chain",),
    "hamiltonian.checks": ("CrossCheckReport",),
    # numbers
    "numerics.codegen": ("numeric_model",),
    "numerics.model": ("NumericModel",),
    "numerics.integrate": ("simulate", "SimulationResult"),
    "numerics.workprecision": ("work_precision",),
    "numerics.ensemble": ("simulate_many", "EnsembleResult"),
    # forces of the constraints at the points they act on
    "system.contacts": ("ContactPoint",),
    "numerics.contact_forces": ("contact_forces", "ContactForces"),
    # a bound on the time of a computation (the command's --budget)
    "budget": ("time_budget",),
    # stability of steady motions
    "numerics.linearization": ("linearize_many", "Linearization"),
    "numerics.batch_linearization": ("linearize_batch", "LinearizationBatch", "ChartChoice"),
    "numerics.steady_sweep": ("sweep_steady", "Sweep"),
    "journeys.stability": ("linearize", "open_loop", "linearize_scene", "relative_generator"),
    # parameter studies on Dask (the study extra)
    "study.sweep": ("sweep", "SweepResult"),
    "study.plots": ("plot_study", "plot_stability_map", "plot_ensemble", "plot_cases"),
    # input and output
    "system.scene": ("load_scene", "loads_scene", "Scene"),
    "system.scene_dump": ("dump_scene",),
    "system.expressions": ("parse_expression",),
    "system.mechanics": ("from_mechanics", "from_lagranges_method"),
    "system.models": ("models",),
    # reports, figures and the command's JSON contract
    "render.display": ("report",),
    "render.plotting": ("plot_trajectory", "plot_work_precision", "plot_root_locus"),
    "render.schema": ("output_schema",),
})

__all__ = list(_LAZY)

__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
