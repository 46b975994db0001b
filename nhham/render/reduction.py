"""Text of ``nhham reduce`` and ``nhham hamiltonize`` (from their JSON results)."""

from __future__ import annotations

from nhham.render.text import table

__all__ = ["reduce_text", "hamiltonize_text"]


def reduce_text(title: str, data: dict) -> str:
    """The reduced data, one row each, in the notation of the module docstring of
    :mod:`nhham.lagrangian.chaplygin`."""
    shape, sym = data["shape_coordinates"], data["symmetry_coordinates"]
    rows = [("shape r", ", ".join(shape)), ("symmetry s", ", ".join(sym)),
            ("L_c(r, r')", data["reduced_lagrangian"])]
    rows += [(f"{s}' (reconstruction)", e) for s, e in zip(sym, data["reconstruction"])]
    rows += [(f"J_{s}", e) for s, e in zip(sym, data["momenta"])]
    for s, B in zip(sym, data["curvature"]):
        rows += [(f"B^{s}_({shape[i]},{shape[j]})", B[i][j])
                 for i in range(len(shape)) for j in range(i + 1, len(shape)) if B[i][j] != "0"]
    rows += [(f"{r}''", e) for r, e in zip(shape, data["accelerations"])]
    check = data["check"]
    rows.append(("lifted field = P(xi_L)",
                 f"{'yes' if check['agrees'] else 'NO'} ({check['method']})"))
    return f"{title}: Chaplygin reduction to the shape space\n" + table(rows)


def hamiltonize_text(title: str, data: dict) -> str:
    """Whether a conformal factor exists, and what it is or why not."""
    rows = [("shape r", ", ".join(data["shape_coordinates"])),
            ("symmetry s", ", ".join(data["symmetry_coordinates"])),
            ("H_c", data["hamiltonian"]),
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
