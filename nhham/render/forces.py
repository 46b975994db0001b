"""The generalized forces Q and the inputs in ``derive``'s text and LaTeX."""

from __future__ import annotations

from nhham.render import latex as tex
from nhham.render.text import labelled, paragraph, table

__all__ = ["forces_text", "forces_latex"]


def forces_text(system, forces) -> str:
    """The text section of the generalized forces Q (``forces``: their printed forms) and
    the inputs."""
    lines = [paragraph("generalized forces Q (in F; d/dt dL/dv - dL/dq = Q - mu^T "
                       "lambda):"),
             table([(f"Q[{q.name}]", "=", f) for q, f in zip(system.coordinates, forces)])]
    if system.inputs:
        lines.append(labelled("inputs", ", ".join(u.name for u in system.inputs)))
    return "\n".join(lines)


def forces_latex(body: str, system) -> str:
    """``body`` (a LaTeX report ending in an aligned block) with the rows of Q and the
    inputs added to its block."""
    rows = [f"Q &= {tex.matrix_latex([[f] for f in system.generalized_forces])}"]
    if system.inputs:
        rows.append(tex.text("inputs: " + ", ".join(u.name for u in system.inputs)))
    head, end = body.rsplit("\\end{aligned}", 1)
    return head.rstrip("\n") + " \\\\\n" + " \\\\\n".join(rows) + "\n\\end{aligned}" + end
