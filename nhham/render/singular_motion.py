"""Text and JSON of ``simulate`` and ``linearize`` on a singular Lagrangian (the motion on
M_f, :mod:`nhham.journeys.singular_motion`): the keys of the regular commands' results
(``$defs/simulate``, ``$defs/linearize``), those without meaning here null, and
``singular``."""

from __future__ import annotations

import numpy as np

from nhham.render.schema import jsonable
from nhham.settings import json_number

__all__ = ["singular_simulate_data", "singular_simulate_text", "singular_linearize_data",
           "singular_linearize_text"]


def _singular(motion) -> dict:
    chain = motion.chain
    return {"phase_space": True,
            "final_constraints": dict(zip(motion.labels,
                                          (str(c) for c in chain.run.final_constraints))),
            "gauge": [str(c) for c in chain.gauge],
            "first_class": chain.first_class,
            "second_class": chain.second_class}


def singular_simulate_data(motion, sol, method: str, t_span, wall: float, settings) -> dict:
    """The ``result`` of ``nhham simulate`` for the run ``sol`` (scipy's OdeResult) of
    ``motion`` (a :class:`~nhham.hamiltonian.phase_motion.PhaseMotion`)."""
    Z = np.asarray(sol.y, dtype=float)
    residuals = np.array([np.max(np.abs(motion.constraints(z)), initial=0.0) for z in Z.T])
    scales = np.maximum(1.0, np.max(np.abs(Z), axis=0))
    energy = np.array([motion.energy(z) for z in Z.T])
    drift = float(np.max(np.abs(energy - energy[0]))) if energy.size else 0.0
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
        "energy_balance_residual": None,
        "cond_c_max": None,
        "cond_w_max": None,
        "kkt_solve": None,
        "kkt_ratio_max": None,
        "settings": jsonable({k: v for k, v in settings.items() if k != "t_eval"}),
        "initial_projection": None,
        "storage": None,
        "singularity": None,
        "singular": dict(_singular(motion),
                         velocities_final=jsonable(motion.velocities(Z[:, -1])),
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
        f"  drift of H_c (the energy) {data['energy_drift']:.2e} (relative "
        f"{data['energy_drift_rel']:.2e})",
        final_state_text(dict(zip(names, data["y_final"]))),
        final_state_text({f"{k}_dot": v for k, v in zip(names[:n], s["velocities_final"])},
                         "velocities"),
    ]
    return "\n".join(lines)


def singular_linearize_data(motion, lin, z, rate, eigenvalues, margins, tolerance: float,
                            verdict: int, verdict_text: str) -> dict:
    """The ``result`` of ``nhham linearize`` at the equilibrium z on M_f."""
    names = motion.names
    stable = {1: True, 0: False}.get(verdict)
    return {
        "coordinates": list(lin.chart),
        "matrix": [[float(x) + 0.0 for x in row] for row in lin.matrix],
        "eigenvalues": [[float(e.real) + 0.0, float(e.imag) + 0.0] for e in eigenvalues],
        "margins": [float(m) for m in margins],
        "stable": stable,
        "spectrally_stable": bool(np.all(eigenvalues.real <= margins)),
        "verdict": verdict_text,
        "method": "exact",
        "precision": "float64, exact Jacobian of the motion on M_f, LAPACK eigenvalues of "
                     f"its restriction to T M_f; |Re| <= {tolerance:.1e} counts as 0",
        "tolerance": tolerance,
        "chart": list(lin.chart),
        "neutral": [],
        "dependent": list(lin.dependent),
        "steady_state": {k: float(v) for k, v in zip(names, z)},
        "residuals": {lab: float(r) for lab, r in zip(motion.labels, motion.constraints(z))},
        "acceleration_residual": float(np.max(np.abs(rate), initial=0.0)),
        "sweep": None,
        "plot": None,
        "loop": "open",
        "control": {},
        "open_loop": None,
        "singular": dict(_singular(motion), tangent_residual=lin.tangent_residual,
                         rank=lin.rank),
    }


def singular_linearize_text(title: str, data: dict) -> str:
    """The text report of ``nhham linearize`` on a singular Lagrangian."""
    from nhham.render.text import paragraph, table

    s = data["singular"]
    rows = [("state", "(q, p) on M_f in T*Q, " + ", ".join(
                f"{k} = {v:.10g}" for k, v in data["steady_state"].items())),
            ("independent (chart)", ", ".join(data["chart"]) or "none"),
            ("dependent", ", ".join(data["dependent"]) or "none"),
            ("verdict", data["verdict"]),
            ("precision", data["precision"]),
            ("tangency", f"|J T - T A| = {s['tangent_residual']:.1e} (the motion tangent to "
                         f"M_f)")]
    if s["gauge"]:
        rows.insert(1, ("gauge", "; ".join(s["gauge"]) + " = 0"))
    lines = [paragraph(f"{title}: linearisation on the final surface M_f of the "
                       f"Dirac-Bergmann chain"), table(rows)]
    # rounding shown as 0 (as linearize does for a regular L): --json has the values
    floor = 1e-14 * max([1.0] + [abs(x) for row in data["matrix"] for x in row])
    hidden = False

    def num(x, spec):
        nonlocal hidden
        hidden |= 0 < abs(x) <= floor
        return format(0.0 if abs(x) <= floor else x, spec)

    if data["matrix"]:
        lines.append("state matrix:")
        lines.append(table([[num(x, ".10g") for x in row] for row in data["matrix"]],
                           header=data["coordinates"]))
    lines.append("eigenvalues:")
    lines.append(table([(num(re, ".12g"), num(im, "+.12g") + "i")
                        for re, im in data["eigenvalues"]] or [("none",)]))
    if hidden:
        lines.append(f"  (values of magnitude <= {floor:.1e} are shown as 0: rounding; --json "
                     f"has them as computed)")
    return "\n".join(lines)
