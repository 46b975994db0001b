"""Derive a scene's constrained dynamics: ``nhham derive``.

On TQ (``side="lagrangian"``) the projected field P(ξ_L), the multipliers, C and E_L in
closed form where W⁻¹ is cheap (or asked for), else the implicit (mass-matrix) form
W a + μᵀ λ = F, μ a = −(∂φ/∂q) v with the verdict on M_f; on T*Q
(``side="hamiltonian"``) the projected Hamiltonian field. Singular C: the dynamics the
constraint algorithm leaves on M_f. The answer is for the scene's parameter values.
"""

from __future__ import annotations

import dataclasses
import functools

from nhham.errors import InputError
from nhham.journeys.answer import Answer, as_scene, quiet_steps
from nhham.journeys.verdict import at_values, with_case
from nhham.lagrangian.engine import Policy

__all__ = ["derive", "SIDES"]

#: The sides the dynamics is derived on.
SIDES = ("lagrangian", "hamiltonian")


def derive(scene, *, side: str = "lagrangian", explicit: bool = False,
           policy: Policy | None = None, steps=None) -> Answer:
    """The constrained dynamics of a scene at its parameter values (``nhham derive``).

    Parameters
    ----------
    scene : Scene, System or str
    side : {"lagrangian", "hamiltonian"}
    explicit : bool
        Form the closed forms on TQ even where W⁻¹ is expensive.
    policy : Policy, optional
    steps : Steps, optional

    Returns
    -------
    Answer
        ``data``: the ``result`` of ``nhham derive --json`` (``field``, ``multipliers``,
        ``constraint_matrix``, ``energy``, ``form``, the implicit form's ``mass_matrix``,
        ``forcing``..., ``generalized_forces``, ``contact_forces``, ``parameter_case``).

    Raises
    ------
    InputError
        An unknown side; inconsistent constraints (no dynamics to derive).

    Examples
    --------
    >>> from nhham import models
    >>> from nhham.journeys import derive
    >>> answer = derive(models.rolling_disk())
    >>> answer.data["form"], answer.data["state"][:4]
    ('explicit', ['x', 'y', 'theta', 'phi'])
    >>> answer.data["multipliers"]   # by hand: lambda = m R theta' phi' (sin, -cos)(theta)
    ['R*m*phi_dot*theta_dot*sin(theta)', '-R*m*phi_dot*theta_dot*cos(theta)']
    """
    if side not in SIDES:
        raise InputError(f"derive: side {side!r} is not one of {', '.join(SIDES)}", key="side")
    scene = as_scene(scene)
    steps = quiet_steps(steps)
    policy = Policy() if policy is None else policy
    if not scene.system.regular_lagrangian:
        return _singular(scene, side, policy, steps)
    if side == "lagrangian":
        from nhham.lagrangian.geometry import lagrangian_geometry

        # One geometry for the journey: the analysis at the values takes this one.
        lagrangian_geometry(scene.system, closed_form=True, policy=Policy(precision=policy.precision))
    at = at_values(scene, policy, steps)
    system = scene.system if at is None else at.system
    if side == "hamiltonian":
        answer = _hamiltonian(scene, system, policy, steps)
    else:
        answer = _lagrangian(scene, system, at, explicit, policy, steps)
    return with_case(_with_forces(answer, system), at)


def _singular(scene, side, policy, steps) -> Answer:
    """derive of a singular Lagrangian: on TQ the motion of the constraint algorithm with
    q' = v built in (:func:`~nhham.lagrangian.singular.lagrangian_chain`), on T*Q the one
    the Dirac-Bergmann chain leaves."""
    from nhham.hamiltonian.dirac_bergmann import dirac_bergmann
    from nhham.render.singular import (singular_derive_data, singular_derive_latex,
                                       singular_derive_text)

    title = scene.name or str(scene.source)
    if side == "lagrangian":
        from nhham.hamiltonian.dirac_bergmann import at_parameter_values
        from nhham.lagrangian.singular import lagrangian_chain
        from nhham.render.singular import singular_lagrangian_derive_data

        system = at_parameter_values(scene.system)
        with steps.step("the constraint algorithm on TQ (q' = v built in) at the values"):
            run = lagrangian_chain(system, policy=policy)
        if run.status == "inconsistent":
            raise _inconsistent(scene, run)
        with steps.step("the motion on M_f and its multipliers"):
            data = singular_lagrangian_derive_data(run, system)
        data["parameter_case"] = None
        return Answer("derive", data, functools.partial(singular_derive_text, title, data),
                      latex=functools.partial(singular_derive_latex, data),
                      warnings=tuple(run.warnings), system=scene.system)
    with steps.step("Dirac-Bergmann chain at the parameter values"):
        db = dirac_bergmann(scene.system, policy=policy)
    if not db.consistent:
        raise _inconsistent(scene, db.run)
    with steps.step("the motion on M_f, its multipliers and the Dirac bracket"):
        data = singular_derive_data(db)
    data["parameter_case"] = None
    return Answer("derive", data, functools.partial(singular_derive_text, title, data),
                  latex=functools.partial(singular_derive_latex, data),
                  warnings=tuple(db.warnings), system=scene.system)


def _hamiltonian(scene, system, policy, steps) -> Answer:
    from nhham.hamiltonian.side import hamiltonian_side

    side = hamiltonian_side(system, closed_form=True, policy=Policy(precision=policy.precision))
    with steps.step("Legendre map and Hamiltonian H = E_L o Leg^-1"):
        side.energy
    answer = _closed_form(scene, side, "hamiltonian", side.analysis, steps)
    return answer.with_data(form="explicit", mass_matrix=None, forcing=None,
                            constraint_jacobian=None, constraint_rhs=None,
                            contact_forces=None)


def _lagrangian(scene, system, at, explicit, policy, steps) -> Answer:
    from nhham.lagrangian.analysis import analyze_constraints
    from nhham.lagrangian.geometry import lagrangian_geometry
    from nhham.render.results import implicit_data

    # derive forms closed forms only where it decided to (W cheap, or explicit asked):
    # the budget bounds them, not the library's size guard.
    G = lagrangian_geometry(system, closed_form=True, policy=Policy(precision=policy.precision))
    with steps.step("energy E_L"):
        energy = G.energy
    with steps.step("implicit form: W, F, mu and mu a = -(dphi/dq) v"):
        implicit = implicit_data(G)
    analysis = None if at is None else at.verdict.analysis
    if not (explicit or G.closed_form_affordable):
        return _with_contacts(_implicit(scene, G, implicit, energy, analysis, policy, steps),
                              scene)

    def algorithm():
        if analysis is not None:
            return analysis
        return analyze_constraints(system, policy=policy)

    answer = _closed_form(scene, G, "lagrangian", algorithm, steps)
    return _with_contacts(answer.with_data(form="explicit", **implicit), scene)


def _closed_form(scene, side, name, algorithm, steps) -> Answer:
    """The closed forms of one side (``LagrangianGeometry`` or ``HamiltonianSide``: the
    same names on both): C, its rank on M_1, and P(xi) with the multipliers when C is
    regular, else the dynamics the constraint algorithm (``algorithm()``) leaves on M_f."""
    from nhham.render.results import derive_data, derive_latex, derive_text

    system = side.system
    with steps.step("constraint matrix C = Z_i(phi_j)"):
        C = side.constraint_matrix
    with steps.step("rank of C on M_1"):
        rank = side.constraint_rank
    steps.note(f"rank C on M_1: {rank.describe()}")
    free: tuple = ()
    warnings = list(rank.warnings)
    if rank.value == system.m:
        with steps.step("multipliers lambda = -C^{-T} xi(phi) and the projected field"):
            field, multipliers = list(side.projected_field), list(side.multipliers)
    else:
        # C is singular: the dynamics is whatever the constraint algorithm leaves.
        with steps.step("C singular: constraint algorithm for the dynamics on M_f"):
            analysis = algorithm()
        if analysis.dynamics is None:
            raise _inconsistent(scene, analysis)
        field = list(analysis.dynamics)
        free = analysis.free_multiplier_symbols
        multipliers = [analysis.multipliers.get(s, s) for s in side.multiplier_symbols]
        warnings += list(analysis.warnings)
    with steps.step("display simplification"):
        data = derive_data(name, side.state, field, multipliers, C, side.energy, free)
    title = scene.name or str(scene.source)
    return Answer("derive", data, functools.partial(derive_text, title, data),
                  latex=functools.partial(derive_latex, data), warnings=tuple(warnings),
                  system=scene.system)


def _inconsistent(scene, analysis) -> InputError:
    return InputError(f"{scene.source}: the constraints are inconsistent "
                      f"({analysis.inconsistency}); there is no dynamics to derive "
                      f"(run `nhham classify {scene.source}` for the stages)")


def _implicit(scene, G, implicit, energy, analysis, policy, steps) -> Answer:
    """derive without closed forms: the mass-matrix form and the verdict on M_f
    (``analysis``: the one already run at the parameter values)."""
    from nhham.lagrangian.analysis import analyze_constraints
    from nhham.render.results import implicit_latex, implicit_text
    from nhham.render.text import expr_text

    system = G.system
    if analysis is None:
        with steps.step("constraint algorithm at exact points (M_f, free multipliers)"):
            analysis = analyze_constraints(system, policy=policy)
    if analysis.status == "inconsistent":
        raise _inconsistent(scene, analysis)
    primary = set(system.holonomic) | set(system.phi)
    secondary = [c for c in analysis.final_constraints if c not in primary]
    data = {
        "side": "lagrangian", "form": "implicit",
        "state": [s.name for s in system.state],
        "field": None, "multipliers": None, "constraint_matrix": None,
        "energy": expr_text(energy), "energy_name": "E_L",
        "free_multiplier_symbols": [s.name for s in analysis.free_multiplier_symbols],
        **implicit,
        "accelerations": [s.name for s in G.acceleration_symbols],
        "multiplier_symbols": [s.name for s in G.multiplier_symbols],
        "secondary_constraints": [expr_text(c) for c in secondary],
        "status": analysis.status,
        "note": (f"closed forms of P(xi_L), lambda and C need W^-1 of a {system.n} x "
                 f"{system.n} matrix of functions: not formed; --explicit forms them"),
    }
    title = scene.name or str(scene.source)
    return Answer("derive", data, functools.partial(implicit_text, title, data),
                  latex=functools.partial(implicit_latex, data),
                  warnings=tuple(analysis.warnings), system=scene.system)


def _with_forces(answer: Answer, system) -> Answer:
    """``answer`` with the generalized forces Q (dissipation included) and the inputs:
    ``generalized_forces`` (null without forces) and ``inputs``, and a text section (rows
    of the aligned block in LaTeX); the text names the field P(xi_L + F^v)."""
    from nhham.render.forces import forces_latex, forces_text
    from nhham.render.text import expr_text

    inputs = [u.name for u in system.inputs]
    if not system.has_forces:
        return answer.with_data(inputs=inputs, generalized_forces=None)
    forces = [expr_text(f) for f in system.generalized_forces]
    render, latex = answer.render, answer.latex
    return dataclasses.replace(
        answer.with_data(inputs=inputs, generalized_forces=forces),
        render=lambda: render() + "\n" + forces_text(system, forces),
        latex=None if latex is None else (lambda parse: forces_latex(latex(parse), system)))


def _with_contacts(answer: Answer, scene) -> Answer:
    """``answer`` with the scene's contact forces in implicit form (data and text)."""
    from nhham.render.results import contact_data, contact_text

    data = contact_data(scene.system, scene.contacts)
    answer = answer.with_data(contact_forces=data)
    if not data:
        return answer
    render = answer.render
    return dataclasses.replace(answer, render=lambda: render() + "\n" + contact_text(data))
