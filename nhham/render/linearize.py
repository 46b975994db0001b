"""The report of a linearisation (``nhham linearize``): its JSON result and its text."""

from __future__ import annotations

import textwrap

from nhham.lagrangian.jacobian import EXACT_DIGITS

__all__ = ["linearize_data", "linearization_data", "linearize_text", "rounding_level"]


def linearize_data(scene, lin, opened, swept) -> dict:
    """The ``result`` of ``nhham linearize --json``."""
    from nhham.system.expressions import to_text

    data = linearization_data(lin)
    data["loop"] = "closed" if scene.control else "open"
    data["control"] = {u: to_text(law) for u, law in scene.control.items()}
    data["open_loop"] = None if opened is None else linearization_data(opened)
    data["sweep"] = None if swept is None else swept.to_dict()
    data["plot"] = None
    return data


def linearization_data(lin) -> dict:
    """A :class:`~nhham.numerics.linearization.Linearization` as JSON data."""
    data = lin.to_dict()
    # -0.0 is 0.0 (x + 0.0 turns the one into the other; every other value is kept)
    data["matrix"] = [[x + 0.0 for x in row] for row in data["matrix"]]
    data["eigenvalues"] = [[re + 0.0, im + 0.0] for re, im in data["eigenvalues"]]
    return data


def linearize_text(title, scene, lin, swept, opened=None, rows_before=()) -> str:
    """The text report of ``nhham linearize`` (``rows_before``: (name, text) rows put first
    in its table: a singular L's phase space)."""
    from nhham.render.text import paragraph, table
    from nhham.system.expressions import to_text

    closed = opened is not None
    lines = [paragraph(f"{title}: linearisation about the [steady] motion"
                       + (", the loop closed by its [control] laws" if closed else ""))]
    rows = [
        *rows_before,
        ("method", lin.method),
        ("independent (chart)", ", ".join(lin.chart)),
        ("dependent", ", ".join(lin.dependent) or "none"),
        ("neutral (removed)", ", ".join(lin.neutral) or "none"),
        ("coordinates", ", ".join(lin.coordinates)),
        ("verdict", lin.verdict + (" (closed loop)" if closed else "")),
    ]
    if lin.relative is not None:
        rows += _relative_rows(lin.relative)
    if closed:
        rows += [("control", "; ".join(f"{u} = {to_text(law)}"
                                       for u, law in scene.control.items())),
                 ("open loop", opened.verdict + " (inputs held at their [steady] values)")]
    rows.append(("precision", lin.precision))
    lines.append(table(rows))
    lines += _matrices(lin, "state matrix" + (" of the closed loop" if closed else ""))
    if closed:
        lines.append("open loop (inputs held at their [steady] values):")
        lines.append(textwrap.indent("\n".join(_matrices(opened, "state matrix A")), "  "))
    if swept is not None:
        lines.append(f"sweep over {swept.parameter}: {len(swept.values)} values from "
                     f"{swept.values[0]:g} to {swept.values[-1]:g}")
        stable = [v for v, s in zip(swept.values, swept.stable) if s]
        lines.append(f"  stable at {len(stable)} of them"
                     + (f" (from {min(stable):g} to {max(stable):g})" if stable else ""))
        if swept.crossings:
            lines.append("crossings (Re of an eigenvalue changes sign):")
            lines.append(table([(f"{swept.parameter} = {c.value:.10f}", c.kind,
                                 "to Re > 0" if c.direction > 0 else "to Re < 0",
                                 f"lambda = {c.eigenvalue.real:.1e} {c.eigenvalue.imag:+.6f}i")
                                for c in swept.crossings]))
        else:
            lines.append("  no crossings")
    return "\n".join(lines)


def _relative_rows(relative) -> list:
    """The rows saying that the state matrix is X - w Xi's (a relative equilibrium)."""
    xi = " + ".join(f"({e}) d/d{q}" for q, e in relative["generator"].items())
    rows = [("symmetry", f"xi = {xi} ([symmetry])")]
    checked = relative.get("invariance") or {}
    if checked:
        how = ", ".join(sorted(set(checked.values())))
        rows.append(("invariant", f"{', '.join(checked)} ({how})"))
    divided = [what for key, what in (("orbit", "its orbit Xi(y0) (orbit(xi))"),
                                      ("momentum", "the level of its conserved momentum "
                                                   "J = (dL/dv) . xi (level(J))"))
               if relative.get(key)]
    if divided:
        rows.append(("symmetry divided out", " and ".join(divided)))
    if relative["rate"] == 0.0:
        return rows + [("relative equilibrium", "no: the motion does not move along xi "
                        "(w = 0), the state matrix is X's")]
    if not relative["turning"]:
        return rows + [("relative equilibrium",
                        f"v = w xi with w = {relative['rate']:.10g} and xi constant (cyclic "
                        f"coordinates): the state matrix is X's")]
    rows.append(("relative equilibrium",
                 f"yes: v = w xi(q) with w = {relative['rate']:.10g}; co-moving variables "
                 f"(the state matrix is X - w Xi's)"))
    if relative["group"]:
        ev = ", ".join(f"{z.real:.6g}{z.imag:+.6g}i" for z in relative["group_eigenvalues"])
        rows.append(("group directions", f"{', '.join(relative['group'])} divided out "
                     f"(their block turns at w: eigenvalues {ev})"))
    return rows


def _matrices(lin, title) -> list:
    """The state matrix, B and the eigenvalues of ``lin`` as lines of text."""
    from nhham.render.text import table

    lines = []
    floor = rounding_level(lin)
    shown_as_zero = False

    def num(x, digits, sign=""):
        nonlocal shown_as_zero
        if abs(x) <= floor:
            shown_as_zero |= x != 0
            return f"{0:{sign}.{digits}g}"
        return f"{x:{sign}.{digits}g}"

    if lin.matrix.size:
        lines.append(f"{title}:")
        lines.append(table([[num(x, 10) for x in row] for row in lin.matrix],
                           header=list(lin.coordinates)))
    if lin.inputs and lin.matrix.size:
        lines.append("input matrix B (x' = A x + B u, inputs at their [steady] values):")
        lines.append(table([[name] + [num(x, 10) for x in row]
                            for name, row in zip(lin.coordinates, lin.input_matrix)],
                           header=["", *lin.inputs]))
    lines.append("eigenvalues:")
    lines.append(table([(num(z.real, 12), num(z.imag, 12, "+") + "i")
                        for z in lin.eigenvalues] or [("none",)]))
    if shown_as_zero:
        lines.append(f"  (values of magnitude <= {floor:.1e} are shown as 0: rounding at this "
                     f"precision; --json has them as computed)")
    return lines


def rounding_level(lin) -> float:
    """The magnitude below which a number of ``lin`` is rounding, not a value.

    A complex-step Jacobian is exact up to rounding in each entry (about
    machine epsilon times the largest entry); eigenvalues from LAPACK are
    backward stable (errors about epsilon times the norm). 64 times that for
    float64; the exact method's matrix is exact and its eigenvalues are computed
    at :data:`~nhham.lagrangian.jacobian.EXACT_DIGITS` digits.
    """
    import numpy as np

    scale = max(1.0, float(np.abs(lin.matrix).max(initial=0.0)))
    eps = 10.0 ** -EXACT_DIGITS if lin.method == "exact" else float(np.finfo(float).eps)
    return 64 * eps * scale



