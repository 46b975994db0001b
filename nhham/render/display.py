"""Rich displays of nhham's results: ``nhham.report(obj)`` in a notebook.

:func:`report` wraps a result (a constraint analysis or classification, the
Lagrangian geometry, the Hamiltonian side, a cross-check, a simulation, a
work-precision study, a linearisation, or any sympy expression or matrix) in a
:class:`Report` whose ``_repr_latex_`` / ``_repr_html_`` Jupyter shows, with
the same data, labels and notation as the ``nhham`` command (the builders of
:mod:`nhham.render.results`), and whose ``repr`` is one short line.

>>> import nhham
>>> disk = nhham.models.rolling_disk(symbolic=True)
>>> r = nhham.report(nhham.analyze_constraints(disk))
>>> r
<nhham report: vertical rolling disk: n = 4 coordinates, m = 2 velocity constraints>
>>> r.latex.splitlines()[0]
'\\\\begin{aligned}'
"""

from __future__ import annotations

import html as _html
from typing import Any

import sympy as sp

from nhham.render import latex as tex
from nhham.render import trace

__all__ = ["Report", "report"]


class Report:
    """Text, LaTeX and HTML of one result.

    Attributes
    ----------
    title : str
    text : str
        What the ``nhham`` command prints.
    latex : str or None
        Math-mode LaTeX (no ``$$``), or None for numeric results.
    html : str or None
        An HTML table, for numeric results.
    """

    def __init__(self, title: str, text: str, latex: str | None = None,
                 html: str | None = None):
        self.title, self.text, self.latex, self.html = title, text, latex, html

    def __repr__(self) -> str:
        return f"<nhham report: {_heading(self.text) if self.text else self.title}>"

    def __str__(self) -> str:
        return self.text

    def _repr_latex_(self):
        return None if self.latex is None else f"$$\n{self.latex}\n$$"

    def _repr_html_(self):
        if self.html is not None:
            return self.html
        return None if self.latex is not None else f"<pre>{_html.escape(self.text)}</pre>"


def _names(system) -> list:
    from nhham.system.naming import momentum_symbol, multiplier_symbol

    return ([q.name for q in system.coordinates] + [v.name for v in system.velocities]
            + [momentum_symbol(q).name for q in system.coordinates]
            + [p.name for p in system.parameters]
            + [multiplier_symbol(i + 1).name for i in range(max(system.m, 1))])


def _parser(system):
    from nhham.system.expressions import parse_expression

    names = _names(system)
    return lambda text: parse_expression(text, names)


def _title(system) -> str:
    return getattr(system, "name", "") or "system"


def _html_table(rows, header=None) -> str:
    def cells(row, tag):
        return "".join(f"<{tag}>{_html.escape(str(c))}</{tag}>" for c in row)
    head = f"<tr>{cells(header, 'th')}</tr>" if header else ""
    body = "".join(f"<tr>{cells(r, 'td')}</tr>" for r in rows)
    return f"<table>{head}{body}</table>"


def _heading(text: str) -> str:
    """The text's heading on one line: its first line, and where the width wrapped it (a
    first line filled to the width), the next line, indented by the hang."""
    from nhham.render.layout import width

    lines = text.splitlines()
    wrapped = len(lines) > 1 and width() - 20 < len(lines[0]) <= width() \
        and lines[1].startswith("  ") \
        and not lines[1].startswith("   ") and "  " not in lines[1].strip()
    return f"{lines[0]} {lines[1].strip()}" if wrapped else lines[0]


def report(obj) -> Report:
    """A :class:`Report` of ``obj`` for notebooks and printing.

    Parameters
    ----------
    obj
        ConstraintAnalysis (the classification table and the algorithm's trace),
        AlgorithmRun (the trace), ConstraintClasses (from any method of
        :func:`nhham.classify_constraints`), LagrangianGeometry,
        HamiltonianSide, CrossCheckReport, SimulationResult,
        WorkPrecisionResult, Linearization, or a sympy expression or matrix.

    Raises
    ------
    TypeError
        For anything else.

    Examples
    --------
    >>> from nhham import models, analyze_constraints, report
    >>> r = report(analyze_constraints(models.rolling_disk()))
    >>> "determined" in r.text, "rank" in r.latex
    (True, True)
    """
    from nhham.render import results as R

    kind = type(obj).__name__
    analysis: Any = None
    classes: Any = None
    if isinstance(obj, (sp.MatrixBase, sp.Basic)):
        return Report("expression", sp.sstr(obj), tex.matrix_latex(obj)
                      if isinstance(obj, sp.MatrixBase) else tex.latex(obj))
    if kind == "ConstraintClasses":
        # Classified without the constraint algorithm (M_f = M_1 decided numerically):
        # its verdict is run here for the rest of the table.
        from nhham.lagrangian.analysis import ConstraintAnalysis, analyze_constraints

        analysis = obj.analysis if isinstance(obj.analysis, ConstraintAnalysis) else \
            analyze_constraints(obj.side.system)
        classes = obj
    elif kind == "ConstraintAnalysis":
        analysis = obj
    if analysis is not None:
        data = R.classify_data(analysis, classes)
        title = _title(analysis.system)
        # The table, then the trace of the algorithm (stages, decisions, evidence).
        text = R.classify_text(title, data) + "\n\n" + trace.analysis_text(analysis)
        return Report(title, text,
                      R.classify_latex(title, data, _parser(analysis.system)))
    if kind == "AlgorithmRun":
        return Report("constraint algorithm", trace.run_text(obj),
                      trace.run_latex(obj).strip("$"))
    if kind in ("LagrangianGeometry", "HamiltonianSide"):
        system = obj.system
        side, state, energy = (("lagrangian", system.state, obj.energy)
                               if kind == "LagrangianGeometry" else
                               ("hamiltonian", obj.variables, obj.H))
        data = R.derive_data(side, state, list(obj.projected_field), list(obj.multipliers),
                             obj.constraint_matrix, energy, ())
        title = _title(system)
        return Report(title, R.derive_text(title, data), R.derive_latex(data, _parser(system)))
    if kind == "CrossCheckReport":
        data = R.compare_data(obj, None)
        title = "cross-check"
        return Report(title, obj.describe(), R.compare_latex(title, data, lambda t: sp.S(t)))
    if kind == "SimulationResult":
        data = R.simulation_data(obj, (obj.t[0], obj.t[-1]))
        keys = ("method", "status", "t_final", "steps", "nfev", "wall_time_s",
                "constraint_residual_max", "energy_drift", "cond_c_max")
        rows: list = [(k, data[k]) for k in keys]
        rows += [(n, f"{v:.10g}") for n, v in zip(data["state"], data["y_final"])]
        return Report(obj.method, obj.describe(), None, _html_table(rows, ("", "value")))
    if kind == "WorkPrecisionResult":
        data = R.bench_data(obj)
        wp_rows = [(r["method"], r["setting"], f"{r['error']:.2e}" if r["error"] is not None
                 else "-", f"{1e3 * r['wall_time_s']:.3f}", r["nfev"],
                 f"{r['constraint_residual']:.1e}") for r in data["rows"]]
        return Report(obj.name, obj.describe(), None, _html_table(
            wp_rows, ("method", "setting", "error", "wall time [ms]", "evaluations",
                   "constraint residual")))
    if kind == "Linearization":
        rows = [(name, *[f"{x:.10g}" for x in row]) for name, row in zip(obj.coordinates,
                                                                      obj.matrix)]
        eig = [(f"{z.real:.12g}", f"{z.imag:+.12g}i") for z in obj.eigenvalues]
        return Report(obj.verdict, f"linearisation ({obj.method}): {obj.verdict}", None,
                      _html_table(rows, ("", *obj.coordinates))
                      + _html_table(eig, ("Re eigenvalue", "Im eigenvalue")))
    raise TypeError(f"nhham.report: no report for {kind} objects (see help(nhham.report))")
