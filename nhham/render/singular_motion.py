"""Text and JSON of ``simulate`` and ``linearize`` on a singular Lagrangian (the motion on
M_f, :mod:`nhham.journeys.singular_motion`): the keys of the regular commands' results
(``$defs/simulate``, ``$defs/linearize``), those without meaning here null, and
``singular``."""

from __future__ import annotations

import numpy as np

from nhham.render.schema import jsonable
from nhham.settings import json_number

__all__ = ["singular_simulate_data", "singular_simulate_text", "singular_linearize_data",
           "singular_linearize_text", "run_arrays"]


def _singular(motion) -> dict:
    chain = motion.chain
    return {"phase_space": True,
            "final_constraints": dict(zip(motion.labels,
                                          (str(c) for c in chain.run.final_constraints))),
            "gauge": [str(c) for c in chain.gauge],
            "first_class": chain.first_class,
            "second_class": chain.second_class}


def run_arrays(motion, sol) -> tuple:
    """(states (N, K), work (K,), H_c (K,)) of the run ``sol`` of ``motion``: the work of
    the forces and reactions rides along as the last component where they may do any."""
    Z = np.asarray(sol.y, dtype=float)
    work = Z[-1] if motion.does_work else np.zeros(Z.shape[1])
    Z = Z[:-1] if motion.does_work else Z
    energy = np.array([motion.energy(z, t) for z, t in zip(Z.T, sol.t)])
    return Z, work, energy


def singular_simulate_data(motion, sol, method: str, t_span, wall: float, settings) -> dict:
    """The ``result`` of ``nhham simulate`` for the run ``sol`` (scipy's OdeResult) of
    ``motion`` (a :class:`~nhham.hamiltonian.phase_motion.PhaseMotion`)."""
    Z, work, energy = run_arrays(motion, sol)
    residuals = np.array([np.max(np.abs(motion.constraints(z, t)), initial=0.0)
                          for z, t in zip(Z.T, sol.t)])
    scales = np.maximum(1.0, np.max(np.abs(Z), axis=0))
    drift = float(np.max(np.abs(energy - energy[0]))) if energy.size else 0.0
    balance = (float(np.max(np.abs(energy - energy[0] - work))) if motion.does_work and energy.size
               else None)
    data = {
        "method": method,
        "success": bool(sol.success),
        "status": "success" if sol.success else "step_failed",
        "status_code": int(sol.status),
        "message": str(sol.message),
        "t_span": [float(t_span[0]), float(t_span[1])],
        "t_final": json_number(sol.t[-1]),
        "state": list(motion.names),
        "y_final": jsonable(Z[:, -1]),
        "steps": max(len(sol.t) - 1, 0),
        "nfev": int(sol.nfev),
        "njev": int(sol.njev),
        "nlu": int(sol.nlu),
        "wall_time_s": json_number(wall),
        "constraint_residual_max": json_number(float(residuals.max(initial=0.0))),
        "constraint_residual_rel_max": json_number(float((residuals / scales).max(initial=0.0))),
        "energy_drift": json_number(drift),
        "energy_drift_rel": json_number(drift / max(1.0, abs(float(energy[0]))) if energy.size
                                        else 0.0),
        "energy_balance_residual": json_number(balance),
        "cond_c_max": None,
        "cond_w_max": None,
        "kkt_solve": None,
        "kkt_ratio_max": None,
        "settings": jsonable({k: v for k, v in settings.items() if k != "t_eval"}),
        "initial_projection": None,
        "storage": None,
        "singularity": None,
        "singular": dict(_singular(motion),
                         velocities_final=jsonable(motion.velocities(Z[:, -1], sol.t[-1])),
                         energy_initial=json_number(float(energy[0]))),
    }
    return data


def singular_simulate_text(title: str, data: dict) -> str:
    """The text report of ``nhham simulate`` on a singular Lagrangian."""
    from nhham.numerics.run import final_state_text
    from nhham.render.text import paragraph

    s = data["singular"]
    names = data["state"]
    n = len(names) // 2
    gauge = f", gauge {'; '.join(s['gauge'])} = 0" if s["gauge"] else ""
    lines = [
        paragraph(f"{title}: the motion on the final surface M_f of T*Q "
                  f"({len(s['final_constraints'])} final constraints{gauge})"),
        f"{data['method']}: {data['message'].rstrip('.')} (status {data['status_code']}) at "
        f"t = {data['t_final']:.10g}",
        f"  steps {data['steps']}, right-hand-side evaluations {data['nfev']}, wall time "
        f"{data['wall_time_s']:.3g} s",
        f"  max residual of the final constraints {data['constraint_residual_max']:.2e} "
        f"(scaled {data['constraint_residual_rel_max']:.2e}; measured, not imposed)",
        (f"  change of H_c (the energy) {data['energy_drift']:.2e}: the work of the forces and "
         f"reactions (and dH_c/dt); energy balance residual {data['energy_balance_residual']:.2e}"
         if data["energy_balance_residual"] is not None else
         f"  drift of H_c (the energy) {data['energy_drift']:.2e} (relative "
         f"{data['energy_drift_rel']:.2e})"),
        final_state_text(dict(zip(names, data["y_final"]))),
        final_state_text({f"{k}_dot": v for k, v in zip(names[:n], s["velocities_final"])},
                         "velocities"),
    ]
    return "\n".join(lines)


def singular_linearize_data(scene, lin, motion, phase) -> dict:
    """The ``result`` of ``nhham linearize`` at an equilibrium on M_f: ``lin`` (a
    :class:`~nhham.numerics.linearization.Linearization` in the chart of phase
    coordinates) as for a regular L, and ``singular``."""
    from nhham.render.linearize import linearize_data

    data = linearize_data(scene, lin, None, None)
    for key in ("kkt_solve", "kkt_ratio"):   # no constrained accelerations are solved
        data.pop(key, None)
    data["singular"] = dict(_singular(motion), tangent_residual=phase.tangent_residual,
                            rank=phase.rank)
    return data


def singular_linearize_text(title: str, scene, lin, data: dict) -> str:
    """The text report of ``nhham linearize`` on a singular Lagrangian: the regular one,
    said to be on M_f in T*Q, with the gauge and the tangency check."""
    from nhham.render.linearize import linearize_text

    s = data["singular"]
    rows = [("phase space", "(q, p) on the final surface M_f of the Dirac-Bergmann chain")]
    if s["gauge"]:
        rows.append(("gauge", "; ".join(s["gauge"]) + " = 0"))
    rows.append(("tangency", "the motion is tangent to M_f there (|J T - T A| <= 1e-12)"
                 if s["tangent_residual"] <= 1e-12 else
                 f"|J T - T A| = {s['tangent_residual']:.1e}: the motion is not tangent to "
                 f"M_f there to rounding"))
    return linearize_text(title, scene, lin, None, rows_before=rows)
