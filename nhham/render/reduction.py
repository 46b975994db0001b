"""Text of ``nhham reduce`` and ``nhham hamiltonize`` (from their JSON results)."""

from __future__ import annotations

from nhham.render import latex as tex
from nhham.render.text import table

__all__ = ["reduce_text", "hamiltonize_text", "reduce_latex", "hamiltonize_latex"]


def _stage_rows(data: dict) -> list:
    """One row per reduction step (JSON ``stages``), and the level the result holds on."""
    rows = []
    stages = data.get("stages", [])
    if len(stages) > 1:
        for i, st in enumerate(stages, 1):
            how = st["by"] + ("" if not st["level"] else " " + ", ".join(
                f"p_{c} = {v}" for c, v in st["level"].items()))
            rows.append((f"step {i}", f"reduce {', '.join(st['reduced_coordinates'])} by "
                                      f"{how}; shape {', '.join(st['shape_coordinates'])}"))
    if data.get("level"):
        rows.append(("on the level", ", ".join(f"p_{c} = {v}" for c, v in data["level"].items())
                     + " only (the motion off it is not described)"))
    return rows


def _stage_latex(data: dict) -> str:
    level = data.get("level") or {}
    if not level:
        return ""
    return tex.text(" on the level " + ", ".join(f"p_{c} = {v}" for c, v in level.items()))


def reduce_text(title: str, data: dict) -> str:
    """The reduced data, one row each, in the notation of the module docstring of
    :mod:`nhham.lagrangian.chaplygin`."""
    shape, sym = data["shape_coordinates"], data["symmetry_coordinates"]
    rows = [("shape r", ", ".join(shape)), ("symmetry s", ", ".join(sym))] + _stage_rows(data)
    rows.append(("L_c(r, r')", data["reduced_lagrangian"]))
    last = data.get("stages", [{"reduced_coordinates": sym}])[-1]["reduced_coordinates"]
    rows += [(f"{s}' (reconstruction)", e) for s, e in zip(last, data["reconstruction"])]
    rows += [(f"J_{s}", e) for s, e in zip(last, data["momenta"])]
    rows += [(f"Q_{r}", e) for r, e in zip(shape, data.get("forces", [])) if e != "0"]
    rows += [("constraint on S", f"{e} = 0") for e in data.get("shape_constraints", [])]
    for s, B in zip(last, data["curvature"]):
        rows += [(f"B^{s}_({shape[i]},{shape[j]})", B[i][j])
                 for i in range(len(shape)) for j in range(i + 1, len(shape)) if B[i][j] != "0"]
    rows += [(f"{r}''", e) for r, e in zip(shape, data["accelerations"])]
    rows += [(f"d/dt p_{m['coordinate']}", f"{m['rate']}   (p_{m['coordinate']} = "
              f"{m['momentum']})") for m in data["momentum_equations"]]
    check = data["check"]
    rows.append(("lifted field = P(xi_L)",
                 f"{'yes' if check['agrees'] else 'NO'} ({check['method']})"))
    return f"{title}: Chaplygin reduction to the shape space\n" + table(rows)


def hamiltonize_text(title: str, data: dict) -> str:
    """Whether a conformal factor exists, and what it is or why not."""
    rows = [("shape r", ", ".join(data["shape_coordinates"])),
            ("symmetry s", ", ".join(data["symmetry_coordinates"]))] + _stage_rows(data)
    rows += [("H_c", data["hamiltonian"]),
            ("hamiltonizable", "yes" if data["hamiltonizable"] else "no")]
    if data["conformal_factor"] is not None:
        rows += [("conformal factor f", data["conformal_factor"] + "  (d(f Omega_nh) = 0)"),
                 ("invariant measure", f"({data['invariant_measure_density']}) dr dp, "
                                       f"div = {data['divergence']}")]
    if data["obstruction"]:
        rows.append(("obstruction", data["obstruction"]))
    if data["theta"] is not None:
        rows.append(("theta", ", ".join(f"d{z}: {e}" for z, e in zip(data["variables"],
                                                                     data["theta"])
                                        if e != "0") or "0"))
    before = data["jacobiator_before"]
    rows.append(("Jacobiator before", "; ".join(
        f"({', '.join(j['triple'])}): {j['value']}" for j in before) or "0"))
    if data["jacobiator_after"] is not None:
        rows.append(("Jacobiator after", "; ".join(
            f"({', '.join(j['triple'])}): {j['value']}" for j in data["jacobiator_after"])
            or "0 (Poisson)"))
    return f"{title}: Chaplygin's multiplier\n" + table(rows)


def reduce_latex(title: str, data: dict, parse) -> str:
    """The reduced data in the notation of the literature (L_c, J_a, B^a, the reduced
    equations' accelerations, the reconstruction)."""
    shape, sym = data["shape_coordinates"], data["symmetry_coordinates"]
    sym = data.get("stages", [{"reduced_coordinates": sym}])[-1]["reduced_coordinates"]
    rows = [("L_c", tex.latex(parse(data["reduced_lagrangian"])))]
    rows += [(rf"\dot{{{tex.name_latex(s)}}}", tex.latex(parse(e)))
             for s, e in zip(sym, data["reconstruction"])]
    rows += [(f"J_{{{tex.name_latex(s)}}}", tex.latex(parse(e)))
             for s, e in zip(sym, data["momenta"])]
    for s, B in zip(sym, data["curvature"]):
        rows += [(f"B^{{{tex.name_latex(s)}}}_{{{tex.name_latex(shape[i])}"
                  f"{tex.name_latex(shape[j])}}}", tex.latex(parse(B[i][j])))
                 for i in range(len(shape)) for j in range(i + 1, len(shape)) if B[i][j] != "0"]
    rows += [(rf"\ddot{{{tex.name_latex(r)}}}", tex.latex(parse(e)))
             for r, e in zip(shape, data["accelerations"])]
    return (tex.text(f"{title}: Chaplygin reduction") + _stage_latex(data) + "\n"
            + tex.aligned(rows))


def hamiltonize_latex(title: str, data: dict, parse) -> str:
    """f with d(f Omega_nh) = 0, or the obstruction."""
    head = tex.text(f"{title}: ") + _stage_latex(data)
    if data["conformal_factor"] is None:
        return head + tex.text("no conformal factor: " + data["obstruction"])
    rows = [("f", tex.latex(parse(data["conformal_factor"]))),
            (r"\rho", tex.latex(parse(data["invariant_measure_density"])))]
    return head + r"d(f\,\Omega_{nh}) = 0" + "\n" + tex.aligned(rows)
