"""The constraint algorithm's trace as text and LaTeX (for ``nhham.report`` and the
command): the stages, their ranks and decisions, and the outcome.

The exact layers keep the results (:class:`~nhham.lagrangian.records.AlgorithmRun`,
:class:`~nhham.lagrangian.analysis.ConstraintAnalysis`); how they read is decided here.
"""

from __future__ import annotations

import sympy as sp

from nhham.errors import BudgetExceeded
from nhham.lagrangian.engine import Policy

__all__ = ["dot_names", "latex_summary", "report_lines", "run_text", "run_latex",
           "analysis_text", "analysis_latex"]


def dot_names(system) -> dict:
    """LaTeX names \\dot{q} for the velocity symbols q_dot."""
    return {v: rf"\dot{{{sp.latex(q)}}}" for q, v in zip(system.coordinates,
                                                          system.velocities)}


def latex_summary(status, rank, labels, constraints, free, stages, names=None) -> str:
    """$$-wrapped LaTeX: the verdict line and the constraints defining M_f."""
    names = names or {}
    rows = [rf"\text{{{status}}},\ \operatorname{{rank}} = {rank},\ {stages}"
            rf"\ \text{{stage(s)}},\ \text{{free}}: "
            + (", ".join(sp.latex(s) for s in free) or r"\text{none}")]
    rows += [rf"\text{{{lab}}}: &\ {sp.latex(c, symbol_names=names)} = 0"
             for lab, c in zip(labels, constraints)]
    return "$$\\begin{aligned}" + r" \\ ".join(rows) + "\\end{aligned}$$"


def report_lines(res, header: str, preamble=(), variables: int | None = None) -> list:
    """The report of a run or an analysis as lines: stages, decisions, outcome, warnings.

    Parameters
    ----------
    res : AlgorithmRun or ConstraintAnalysis
        Anything with stages, status, final constraints, multipliers and warnings.
    header : str
    preamble : sequence of str
        Lines printed after the header.
    variables : int, optional
        Number of variables N (closed forms are printed only for N <= 2 n, n the
        policy's ``closed_form_size``: the run's, or the default).
    """
    lines = [f"{header}: {res.status}", *preamble]
    size = getattr(res, "policy", Policy()).closed_form_size
    small = variables is not None and variables <= 2 * size
    for st in res.stages:
        lines.append(f"Stage {st.index}: M_{st.index} defined by {len(st.constraints)} "
                     f"constraint(s); rank (Z_i(chi_j)) = {st.rank}, augmented rank "
                     f"{st.augmented_rank}")
        for lab, chi in zip(st.labels, st.constraints):
            lines.append(f"    {lab}: {chi}")
        if st.block[0]:
            lines.append(f"  regular block: rows {', '.join(st.block[0])}; multipliers "
                         f"{', '.join(str(s) for s in st.block[1])}")
        for ev in st.decisions:
            lines.append("  - " + ev.describe())
        for lab, chi in zip(st.new_labels, st.new_constraints):
            lines.append(f"  new: {lab} = {chi}")
    if res.inconsistency:
        lines.append(f"INCONSISTENT: {res.inconsistency}")
    else:
        lines.append(f"M_f: {len(res.final_constraints)} constraint(s), dimension "
                     f"{res.dimension}")
        closed = "multipliers" in res.__dict__ or small
        if closed:
            for s, e in res.multipliers.items():
                lines.append(f"  {s} = {e}")
        else:
            lines.append("  multipliers and dynamics: not formed in closed form (W^-1 of a "
                         "large system); ask for .multipliers / .dynamics")
        lines.append("free multipliers: " + (", ".join(str(s) for s in
                                                    res.free_multiplier_symbols) or "none"))
        if closed and res.dynamics is not None:
            lines.append(f"dynamics: {list(res.dynamics)}")
    if not res.converged:
        lines.append("NOT CONVERGED: the stage bound was hit")
    for w in res.warnings:
        lines.append(f"WARNING: {w}")
    return lines


def run_text(run) -> str:
    """The trace of one run of the algorithm (:class:`AlgorithmRun`)."""
    return "\n".join(report_lines(run, header="Constraint algorithm",
                                   variables=len(run.variables)))


def run_latex(run) -> str:
    """The verdict and M_f of a run, $$-wrapped LaTeX."""
    return latex_summary(run.status, run.rank, run.final_labels, run.final_constraints,
                         run.free_multiplier_symbols, len(run.stages))


def analysis_latex(analysis) -> str:
    """M_f and the verdict of an analysis in the paper's notation (for notebooks)."""
    return latex_summary(analysis.status, analysis.rank_C, analysis.final_labels,
                         analysis.final_constraints, analysis.free_multiplier_symbols,
                         len(analysis.stages), dot_names(analysis.system))


def analysis_text(analysis) -> str:
    """The trace of a constraint analysis: stages, ranks, decisions with their evidence,
    the outcome, warnings and the integrability of the constraint distribution."""
    sysm = analysis.system
    lines = report_lines(analysis, header=f"Constraint analysis of {sysm!r}", preamble=[
        f"n = {sysm.n}, m = {sysm.m}; rank C on M_1 = {analysis.rank_C} "
        f"({'regular' if analysis.regular else 'singular'}); options: "
        + ", ".join(f"{k}={v}" for k, v in analysis.options.items())],
        variables=2 * sysm.n)
    if analysis.dropped:
        lines.insert(1, "dropped redundant constraints: " + "; ".join(
            f"{d.label} = " + " + ".join(f"({c})*{k}" for k, c in d.combination.items())
            for d in analysis.dropped))
    for b in analysis.blocks:
        delta = b.run.denominator
        if delta is not None and delta != 1:
            where = f" of [{', '.join(q.name for q in b.coordinates)}]" \
                if len(analysis.blocks) > 1 else ""
            lines.insert(1, f"tangency equations{where} multiplied by delta = {delta} "
                         f"(det W up to factors, the denominator of W^-1): the results "
                         f"hold where delta != 0")
    if len(analysis.blocks) > 1:
        lines.insert(1, f"{len(analysis.blocks)} independent blocks: " + "; ".join(
            f"[{', '.join(q.name for q in b.coordinates)}] with "
            f"{', '.join(b.constraint_labels) or 'no constraints'}: {b.run.status}"
            for b in analysis.blocks))
    try:
        integ = analysis.integrability.describe()
    except BudgetExceeded:  # an expiry is not an undecided integrability
        raise
    except Exception as exc:  # pragma: no cover - report must not fail
        integ = f"not decided ({exc})"
    lines.append(f"integrability of the constraint distribution: {integ}")
    return "\n".join(lines)
