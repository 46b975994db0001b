"""The results of the commands as data, text and LaTeX, built in one place.

Each ``*_data`` function turns library results into the JSON-ready ``result``
of the envelope (see :mod:`nhham.cli.envelope` and the schema); ``*_text``
and ``*_latex`` render the same data for people. The commands and the
notebook displays (:func:`nhham.report`) both use these, so a key, a label
or a notation is defined once.
"""

from __future__ import annotations

import sympy as sp

from nhham.render import latex as tex
from nhham.render.schema import jsonable
from nhham.settings import json_number
from nhham.render.text import expr_text, labelled, matrix_table, paragraph, table
from nhham.render.layout import grid_fits as table_fits
from nhham.render.simplify import display_form
from nhham.numerics.methods import lookup, names
from nhham.system.chetaev import CHETAEV

__all__ = [
    "classify_data", "classify_text", "classify_latex", "classify_rows",
    "derive_data", "derive_text", "derive_latex",
    "implicit_data", "implicit_text", "implicit_latex",
    "compare_data", "compare_text", "compare_latex",
    "simulation_data", "simulation_failure", "status_name",
    "bench_data", "bench_failure", "bench_failure_data",
]


# ---------------------------------------------------------------- classify
def classify_data(analysis, classes=None) -> dict:
    """The ``result`` of ``nhham classify`` from a ConstraintAnalysis (and ConstraintClasses)."""
    from nhham.system.naming import momentum_symbol

    system = analysis.system
    momenta = [momentum_symbol(q) for q in system.coordinates]
    formed = classes is not None and classes.first_class_combinations is not None
    state = set(system.coordinates) | set(momenta)
    combos = [expr_text(_combination_form(c, momenta, state))
              for c in classes.first_class_combinations] if formed else []
    coefficients = [[{"label": lab, "coefficient": expr_text(display_form(c, momenta))}
                     for lab, c in d.items()]
                    for d in classes.combination_coefficients] if formed else None
    given = set(system.holonomic) | set(system.phi)

    def shown(c):  # the scene's own constraints as given, derived ones simplified
        return expr_text(c if c in given else display_form(c, system.velocities))

    out = analysis.to_dict(expressions=False)
    for stage in out["stages"]:
        stage["constraints"] = [shown(c) for c in stage["constraints"]]
    out["final_constraints"] = [shown(c) for c in out["final_constraints"]]
    inconsistency = out.pop("inconsistency")
    out.update({
        "first_class": None if classes is None else int(classes.first_class),
        "second_class": None if classes is None else int(classes.second_class),
        "second_class_set": [] if classes is None else list(classes.second_class_set),
        "first_class_combinations": combos,
        "first_class_coefficients": coefficients,
        "inconsistency": inconsistency,
    })
    if system.time is not None:  # (only then: autonomous answers keep their keys)
        out["time"] = time_data(system)
    return out


def time_data(system) -> dict:
    """The question a verdict in t answers: a generic instant (DESIGN.md §2)."""
    return {"name": str(system.time), "question": "generic instant (for all t but a proper "
            "algebraic subset; t a parameter without a value)",
            "lagrangian": bool(system.lagrangian_depends_on_time)}


def classify_warnings(analysis, classes=None) -> list:
    return list(analysis.warnings) + ([] if classes is None else
                                      list(getattr(classes, "warnings", ())))


def _integrable_text(data: dict) -> str:
    """What the Frobenius test of ker mu says about the constraints themselves."""
    if "integrability" in data:  # nonlinear (Chetaev) constraints
        return data["integrability"]
    if (verdict := data["integrable"]) is None:
        return "undecided"
    if not verdict:
        return "no (truly nonholonomic)"
    moving = [r["time_dependent"] for r in data["constraint_kinds"] if r["kind"] == "affine"]
    if all(moving):  # h != 0 only where t enters: holonomic at each instant
        return f"yes (holonomic in disguise{' at each instant, moving with t' * bool(moving)})"
    return "yes, the linear parts (affine h(q) != 0: rheonomic, not holonomic)"


def classify_text(title: str, data: dict) -> str:
    lines = [paragraph(f"{title}: n = {data['n']} coordinates, m = {data['m']} velocity constraints")]
    free = data["free_multipliers"]
    rows = [
        ("C regular on M_1", "yes" if data["regular"] else "no"),
        ("rank C on M_1", f"{data['rank_c']} ({data['rank_c_method']})"),
        ("status", data["status"]),
        ("stages", str(len(data["stages"]))),
        ("free multipliers", f"{free}" + (f" ({', '.join(data['free_multiplier_symbols'])})"
                                          if free else "")),
        ("redundant (dropped)", ", ".join(data["redundant"]) or "none"),
        ("integrable (Frobenius)", _integrable_text(data)),
    ]
    if any(r["kind"] == CHETAEV or r["time_dependent"] for r in data["constraint_kinds"]):
        rows += [(f"  {r['label']}", r["kind"] + ", in t" * r["time_dependent"])
                 for r in data["constraint_kinds"]]
    if data["first_class"] is not None:
        rows += [("first class", str(data["first_class"])),
                 ("second class", str(data["second_class"]))]
    if data.get("time"):
        timed = [c["label"] for c in data["constraint_kinds"] if c["time_dependent"]]
        rows += [("time t", data["time"]["question"]),
                 ("depends on t", ", ".join((["L"] if data["time"]["lagrangian"] else [])
                                            + timed) or "the forces only")]
        split = data["time"].get("class_split")  # where the split changes (the journey's)
        rows += [("class split in t", split["text"])] if split else []
    lines.append(table(rows))
    lines.append("stages:")
    lines.append(table([(f"M_{s['index']}", f"rank {s['rank']}", ", ".join(s["labels"]))
                        for s in data["stages"]]))
    final = f"M_{data['stages'][-1]['index']}" if data["stages"] else "M_f"
    lines.append(f"final constraints ({final}):")
    lines.append(table(list(zip(data["final_labels"], data["final_constraints"]))))
    shown = dict(zip(data["final_labels"], data["final_constraints"]))
    earlier = {lab: c for s in data["stages"] for lab, c in zip(s["labels"], s["constraints"])
               if shown.get(lab) != c}
    if earlier:
        lines.append("constraints of earlier stages:")
        lines.append(table(list(earlier.items())))
    if data["first_class_combinations"]:
        lines.append("first-class combinations (in q, p):")
        combo_rows: list = []
        combos = data["first_class_combinations"]
        coefficients = data.get("first_class_coefficients") or [None] * len(combos)
        for i, (c, coeffs) in enumerate(zip(combos, coefficients)):
            name = f"gamma_{i + 1}"
            if coeffs and len(coeffs) > 1:  # the combination of the labels, then in (q, p)
                combo_rows += [(name, "=", _combination_text(coeffs)), ("", "=", c)]
            else:
                combo_rows.append((name, "=", c))
        lines.append(table(combo_rows))
    elif data["first_class"]:
        lines.append("first-class combinations: not formed in closed form (see the warning)")
    if data["inconsistency"]:
        lines.append(f"inconsistent: {data['inconsistency']}")
    return "\n".join(lines)


def _combination_form(gamma, momenta, state):
    """A combination for display: term by term when it is a sum of constraints whose
    coefficients have denominators in the state (over one denominator it would be far
    longer, and forming it takes seconds: the segway's), else as a whole."""
    terms = sp.Add.make_args(gamma)
    if len(terms) > 1 and any(sp.fraction(sp.together(t))[1].free_symbols & state
                              for t in terms):
        return sp.Add(*[display_form(t, momenta) for t in terms])
    return display_form(gamma, momenta)


def _combination_text(coefficients: list) -> str:
    """``[{label, coefficient}]`` as ``c1*label1 + c2*label2`` (unit coefficients left out)."""
    terms = []
    for item in coefficients:
        label, c = item["label"], item["coefficient"]
        if c == "1":
            terms.append(label)
        elif c == "-1":
            terms.append(f"-{label}")
        else:
            terms.append(f"({c})*{label}")
    return " + ".join(terms).replace("+ -", "- ")


#: The letters of the constraints' labels, the paper's first; the last of each is one no
#: name of a scene prints (``\mathsf``), taken when the others are the scene's own.
LABEL_LETTERS = {"constraints": (r"\phi", r"\Phi", r"\varphi", r"\mathsf{c}"),
                 "secondary": (r"\psi", r"\Psi", r"\mathsf{s}"),
                 "holonomic": ("g", r"\mathsf{g}")}


def label_letters(used) -> dict:
    """``{kind: letter}`` of :data:`LABEL_LETTERS`: for each kind the first letter none of
    the printed names ``used`` shows (a coordinate ``phi`` moves the constraints to
    ``\varphi``), no two kinds the same."""
    out: dict = {}
    for kind, candidates in LABEL_LETTERS.items():
        out[kind] = tex.free_letter(candidates, set(used) | set(out.values()))
    return out


def _label_latex(label: str, letters=None) -> str:
    """``constraints[0]`` -> phi_1, ``secondary[1]`` -> psi_2, ``holonomic[0]`` -> g_1
    (``.lift``: g_1^c), others as text; ``letters`` from :func:`label_letters`."""
    import re

    letters = letters or {kind: c[0] for kind, c in LABEL_LETTERS.items()}
    m = re.fullmatch(r"(constraints|secondary)\[(\d+)\]", label)
    if m:
        return rf"{letters[m.group(1)]}_{{{int(m.group(2)) + 1}}}"
    m = re.fullmatch(r"holonomic\[(\d+)\](\.lift)?", label)
    if m:
        base = rf"{letters['holonomic']}_{{{int(m.group(1)) + 1}}}"
        return base + "^{c}" if m.group(2) else base
    return tex.text(label)


def _printed_names(exprs) -> set:
    """The LaTeX of every name in ``exprs`` (sympy expressions)."""
    return {tex.name_latex(s.name) for e in exprs for s in e.free_symbols
            if isinstance(s, sp.Symbol)}


def classify_latex(title: str, data: dict, parse) -> str:
    """The verdict, the stages M_k, the final constraints and first-class combinations.

    ``parse`` reads an expression string of ``data`` back (the scene's names).
    """
    return tex.aligned(classify_rows(title, data, parse))


def classify_rows(title: str, data: dict, parse) -> list:
    """The (left, right) rows of :func:`classify_latex`."""
    rows = [(tex.text(f"{title}: ") + rf"n = {data['n']},\ m = {data['m']}", None),
            (r"\operatorname{rank} C|_{M_1}", f"{data['rank_c']}"
             + (r"\ (\text{regular})" if data["regular"] else r"\ (\text{singular})")),
            (tex.text("status"), tex.text(data["status"]))]
    defined: set = set()
    shown = [parse(c) for s in data["stages"] for c in s["constraints"]] + \
        [parse(c) for c in data["first_class_combinations"]]
    letters = label_letters(_printed_names(shown) | {
        tex.name_latex(n) for n in data["free_multiplier_symbols"]})
    for s in data["stages"]:
        for lab, c in zip(s["labels"], s["constraints"]):
            if lab not in defined:
                defined.add(lab)
                rows.append((_label_latex(lab, letters), tex.latex(parse(c))))
        zero = " = ".join(_label_latex(lab, letters) for lab in s["labels"]) or r"\emptyset"
        rows.append((f"M_{{{s['index']}}}", r"\{" + zero + r" = 0\},\quad "
                     + rf"\operatorname{{rank}} (Z_i(\chi_j)) = {s['rank']}"))
    if data["free_multiplier_symbols"]:
        rows.append((tex.text("free multipliers"),
                     ", ".join(tex.name_latex(n) for n in data["free_multiplier_symbols"])))
    if data["first_class"] is not None:
        rows.append((tex.text("first / second class"),
                     f"{data['first_class']}\\ /\\ {data['second_class']}"))
    for c in data["first_class_combinations"]:
        rows.append((tex.text("first class (T*Q)"), tex.latex(parse(c))))
    if data["inconsistency"]:
        rows.append((tex.text("inconsistent"), tex.text(data["inconsistency"])))
    return rows


# ------------------------------------------------------------------ derive
def derive_data(side: str, variables, field, multipliers, C, energy, free) -> dict:
    """The ``result`` of ``nhham derive`` (expressions simplified for display,
    :func:`nhham.render.simplify.display_form`, grouped by the velocities or momenta)."""
    group = list(variables)[len(variables) // 2:]
    field = [display_form(f, group) for f in field]
    multipliers = [display_form(f, group) for f in multipliers]
    C = sp.Matrix(C).applyfunc(lambda e: display_form(e, group))
    return {
        "side": side,
        "state": [s.name for s in variables],
        "field": [expr_text(f) for f in field],
        "multipliers": [expr_text(f) for f in multipliers],
        "constraint_matrix": [[expr_text(C[i, j]) for j in range(C.cols)]
                              for i in range(C.rows)],
        "energy": expr_text(energy),
        "energy_name": "H" if side == "hamiltonian" else "E_L",
        "free_multiplier_symbols": [s.name for s in free],
    }


def derive_text(title: str, data: dict) -> str:
    what = "Hamiltonian field on T*Q" if data["side"] == "hamiltonian" else \
        "projected field P(xi_L) on TQ"
    if data.get("generalized_forces") and data["side"] != "hamiltonian":
        what = "projected field P(xi_L + F^v) on TQ (F^v: the forces' vertical lift)"
    lines = [paragraph(f"{title}: {what}")]
    lines.append(table([(f"{n}'", "=", t) for n, t in zip(data["state"], data["field"])]))
    if data["multipliers"]:
        lines.append("multipliers:")
        lines.append(table([(f"lambda_{i + 1}", "=", t)
                            for i, t in enumerate(data["multipliers"])]))
        lines.append("constraint matrix C:")
        index = [str(i + 1) for i in range(len(data["constraint_matrix"]))]
        lines.append(matrix_table([list(row) for row in data["constraint_matrix"]], "C",
                                  index, index))
    if data["free_multiplier_symbols"]:
        lines.append("free multipliers: " + ", ".join(data["free_multiplier_symbols"]))
    label = "Hamiltonian H" if data["side"] == "hamiltonian" else "energy E_L"
    lines.append(labelled(label, data["energy"]))
    return "\n".join(lines)


def derive_latex(data: dict, parse) -> str:
    """Equations of motion in the paper's notation.

    Lagrangian side: the second-order part, ẍ = ... (q̇ = v is implied); Hamiltonian
    side: q̇ and ṗ. Then λ_i, the energy E_L or H, and C.
    """
    state = data["state"]
    rows = []
    if data["side"] == "hamiltonian":
        for name, f in zip(state, data["field"]):
            rows.append((rf"\dot{{{tex.name_latex(name)}}}" if not name.startswith("p_")
                         else rf"\dot{{p}}_{{{tex.name_latex(name[2:])}}}",
                         tex.latex(parse(f))))
    else:
        half = len(state) // 2
        for name, f in zip(state[half:], data["field"][half:]):
            rows.append((tex.name_latex(name[:-4] + "_ddot"), tex.latex(parse(f))))
    for i, f in enumerate(data["multipliers"]):
        rows.append((rf"\lambda_{{{i + 1}}}", tex.latex(parse(f))))
    rows.append(("H" if data["side"] == "hamiltonian" else "E_L",
                 tex.latex(parse(data["energy"]))))
    if data["constraint_matrix"]:
        C = [[parse(c) for c in row] for row in data["constraint_matrix"]]
        rows.append(("C^{H}" if data["side"] == "hamiltonian" else "C", tex.matrix_latex(C)))
    return tex.aligned(rows)


#: Implicit-form entries up to this many nodes are simplified for display (larger
#: ones, the bulk of a big system's forcing, would cost more than they give).
IMPLICIT_DISPLAY_LIMIT = 400


def implicit_data(G) -> dict:
    """W, F, mu and mu a = -(dphi/dq) v of a LagrangianGeometry (JSON-ready strings,
    entries of moderate size simplified for display)."""
    system = G.system
    group = system.velocities
    seen: dict = {}   # W is symmetric: each entry above the diagonal is shown twice

    def shown(e):
        if e not in seen:
            seen[e] = expr_text(display_form(e, group, limit=IMPLICIT_DISPLAY_LIMIT))
        return seen[e]

    rhs = -G.drift if system.m else sp.zeros(0, 1)
    W, mu = G.hessian, system.mu
    return {
        "mass_matrix": [[shown(W[i, j]) for j in range(system.n)] for i in range(system.n)],
        "forcing": [shown(f) for f in G.forcing],
        "constraint_jacobian": [[shown(mu[i, j]) for j in range(system.n)]
                                for i in range(system.m)],
        "constraint_rhs": [shown(r) for r in rhs],
    }


def contact_data(system, contacts) -> dict | None:
    """derive's contact forces in implicit form (JSON-ready), None without contacts: per
    contact point the constraints it carries, their multipliers and J_P = dv_P/dv (text),
    with f_P defined by J_P^T f_P = -mu_c^T lambda_c
    (:mod:`nhham.numerics.contact_forces`)."""
    if not contacts:
        return None
    from nhham.system.contacts import contact_rows, velocity_jacobian
    from nhham.system.naming import multiplier_symbol

    out = {}
    for contact in contacts:
        J = velocity_jacobian(system, contact)
        out[contact.name] = {
            "constraints": list(contact.constraints),
            "multipliers": [multiplier_symbol(i + 1).name for i in contact_rows(system, contact)],
            "velocity_jacobian": [[expr_text(J[i, j]) for j in range(J.cols)]
                                  for i in range(J.rows)],
            "relation": "J_P^T f_P = -mu_c^T lambda_c",
        }
    return out


def contact_text(data: dict | None) -> str:
    """One line per contact point of :func:`contact_data` ("" without contacts)."""
    if not data:
        return ""
    lines = ["contact forces (J_P = dv_P/dv, in --json):"]
    for name, item in data.items():
        terms = " + ".join(f"{lam} mu[{label}]" for lam, label in
                           zip(item["multipliers"], item["constraints"]))
        lines.append(f"  {name}: J_P^T f_{name} = -({terms})^T")
    return "\n".join(lines)


def implicit_text(title: str, data: dict) -> str:
    """derive without closed forms: W a + mu^T lambda = F, mu a = rhs, and M_f."""
    q = [n[:-4] for n in data["state"][len(data["state"]) // 2:]]
    lines = [paragraph(f"{title}: dynamics in implicit form (W a + mu^T lambda = F, "
                       f"mu a = rhs), a = ({', '.join(data['accelerations'])})")]
    lines.append("mass matrix W (rows and columns: " + ", ".join(q) + "):")
    lines.append(matrix_table(data["mass_matrix"], "W", q, q))
    lines.append("forcing F (the row of each coordinate):")
    lines.append(table([(f"F[{n}]", "=", f) for n, f in zip(q, data["forcing"])]))
    if data["constraint_jacobian"]:
        lines.append("constraint rows mu (mu a = rhs):")
        rows = [list(row) + ["|", r] for row, r in zip(data["constraint_jacobian"],
                                                       data["constraint_rhs"])]
        index = [str(i + 1) for i in range(len(rows))]
        if table_fits(rows):
            lines.append(table(rows))
        else:
            lines.append(matrix_table(data["constraint_jacobian"], "mu", index, q))
            lines.append(table([(f"rhs[{i}]", "=", r) for i, r in zip(index,
                                                                     data["constraint_rhs"])]))
    if data["secondary_constraints"]:
        lines.append("secondary constraints (M_f):")
        lines.append(table([(c,) for c in data["secondary_constraints"]]))
    if data["free_multiplier_symbols"]:
        lines.append("free multipliers: " + ", ".join(data["free_multiplier_symbols"]))
    lines.append(f"status: {data['status']}")
    lines.append(labelled("energy E_L", data["energy"]))
    lines.append(labelled("note", data["note"]))
    return "\n".join(lines)


def implicit_latex(data: dict, parse) -> str:
    """W a + mu^T lambda = F, mu a = rhs (a the accelerations), with W, F, mu, rhs and E_L."""
    def mat(rows):
        return tex.matrix_latex([[parse(c) for c in row] for row in rows])

    rows = [(r"W \ddot{q} + \mu^{T} \lambda", "F"), (r"\mu \ddot{q}", r"-\frac{\partial \phi}"
            r"{\partial q} \dot{q}"), ("W", mat(data["mass_matrix"])),
            ("F", mat([[f] for f in data["forcing"]]))]
    if data["constraint_jacobian"]:
        rows.append((r"\mu", mat(data["constraint_jacobian"])))
        rows.append((r"-\frac{\partial \phi}{\partial q} \dot{q}",
                     mat([[r] for r in data["constraint_rhs"]])))
    rows.append(("E_L", tex.latex(parse(data["energy"]))))
    return tex.aligned(rows)


# ----------------------------------------------------------------- compare
def _snake(name: str) -> str:
    import re

    return re.sub(r"[^0-9a-z]+", "_", name.lower()).strip("_")


def compare_data(report, dirac=None) -> dict:
    """The ``result`` of ``nhham compare`` from a CrossCheckReport (and Dirac report)."""
    raw = report.to_dict()
    checks = []
    for name, c in raw.get("checks", {}).items():
        checks.append({"name": _snake(name), "agree": bool(c["agree"]),
                       "exact": bool(c["exact"]),
                       "max_abs_difference": json_number(c["max_abs_difference"]),
                       "max_rel_difference": json_number(c["max_rel_difference"]),
                       "samples": int(c["samples"]), "detail": str(c["detail"]),
                       "method": str(c["method"])})

    def stages(rows):
        return [{"index": int(s["index"]), "constraint_count": int(s["constraints"]),
                 "rank": int(s["rank"]), "augmented_rank": int(s["augmented_rank"]),
                 "labels": list(s.get("labels", []))} for s in rows]

    statuses = list(raw.get("statuses", [])) + [None, None]
    data = {
        "agree": bool(raw["agree"]), "exact": bool(raw["exact"]),
        "max_abs_difference": json_number(raw["max_abs_difference"]),
        "max_rel_difference": json_number(raw["max_rel_difference"]),
        "samples": int(raw["samples"]), "tolerance": json_number(raw["tolerance"]),
        "precision": str(raw["precision"]), "method": str(raw["method"]),
        "checks": checks,
        "lagrangian_stages": stages(raw.get("lagrangian_stages", [])),
        "hamiltonian_stages": stages(raw.get("hamiltonian_stages", [])),
        "lagrangian_status": statuses[0], "hamiltonian_status": statuses[1],
        "wall_time_s": json_number(raw.get("seconds")),
        "skipped_points": int(raw.get("skipped_points", 0)),
        "dirac_vs_projected": None,
    }
    if dirac is not None:
        diff = dirac.difference
        data["dirac_vs_projected"] = {
            "equal": bool(dirac.equal),
            "state": [str(z) for z in dirac.classes.side.variables],
            "difference": None if diff is None else [expr_text(display_form(d)) for d in diff],
            "max_abs_difference": json_number(dirac.max_abs_difference),
            "samples": int(dirac.samples),
            "notes": [str(n) for n in dirac.notes],
            "components": [str(z) for z in dirac.components],
            "method": _dirac_method(dirac),
            "error_bound": json_number(_dirac_error_bound(dirac)),
        }
    return data


def _dirac_method(dirac) -> str:
    """How X_D - X was decided: the least exact of its decisions."""
    methods = {d.method for d in dirac.decisions}
    for m in ("sampled", "exact at points"):
        if m in methods:
            return m
    return "exact"


def _dirac_error_bound(dirac):
    """The error bound of a verdict decided at exact points (0 for a proof), else None."""
    bounds = [d.error_bound for d in dirac.decisions if d.error_bound is not None]
    return max(bounds) if bounds and _dirac_method(dirac) != "sampled" else None


def compare_text(title: str, report, dirac) -> str:
    """The reports' own lines, each wrapped (and elided) to the width of the terminal."""
    from nhham.render.layout import width, wrap

    lines = [paragraph(f"{title}: Lagrangian vs Hamiltonian")]
    for line in [report.describe()] + ([] if dirac is None else [dirac.describe()]):
        for part in line.splitlines():
            hang = " " * (len(part) - len(part.lstrip()) + 4)
            pieces = wrap(part, width() - len(hang))
            lines += pieces[:1] + [hang + p for p in pieces[1:]]
    if dirac is not None:
        for note in dirac.notes:
            pieces = wrap(f"  note: {note}", width() - 4)
            lines += pieces[:1] + ["    " + p for p in pieces[1:]]
    return "\n".join(lines)


def compare_latex(title: str, data: dict, parse) -> str:
    """The checks through the Legendre map, and X_D - X on M_f."""
    def num(x):
        return "-" if x is None else f"{x:.2g}"

    head = (r"\begin{array}{lccc}" + "\n" + tex.text("check") + r" & "
            + tex.text("agree") + r" & " + tex.text("decided") + r" & \max|\Delta| \\ \hline")
    body = [f"{tex.text(c['name'].replace('_', ' '))} & {tex.text('yes' if c['agree'] else 'NO')}"
            f" & {tex.text('exactly' if c['exact'] else 'at samples')} & "
            f"{num(c['max_abs_difference'])} \\\\" for c in data["checks"]]
    parts = [tex.text(f"{title}: ") + r"\mathrm{Leg}_*(P(\xi_L)) = X \circ \mathrm{Leg}"
             + (r"\ \text{holds}" if data["agree"] else r"\ \text{FAILS}"),
             head + "\n" + "\n".join(body) + "\n" + r"\end{array}"]
    d = data.get("dirac_vs_projected")
    if d is not None:
        if d["equal"]:
            parts.append(r"X_D = X\ \text{on}\ M_f")
        elif d["difference"] is not None:
            rows = [(rf"(X_D - X)({tex.name_latex(z)})", tex.latex(parse(e)))
                    for z, e in zip(d["state"], d["difference"]) if e != "0"]
            parts.append(tex.aligned(rows))
        else:
            parts.append(rf"X_D \neq X\ \text{{on}}\ M_f\ (\max|X_D - X| = "
                         rf"{num(d['max_abs_difference'])})")
    return "\n".join(parts)


# ---------------------------------------------------------------- simulate
# The names of nhham.numerics.status.Status, for results that carry a plain int.
_STATUS_NAMES = {0: "success", 1: "event", -1: "step_failed", -2: "nonfinite", -3: "singular",
                 -4: "not_converged", -5: "time_limit"}


def status_name(status) -> str:
    """The snake_case name of a numerics status (``Status.SINGULAR`` -> ``"singular"``)."""
    name = getattr(status, "name", None)
    if isinstance(name, str):
        return name.lower()
    return _STATUS_NAMES.get(int(status), f"status_{int(status)}".replace("-", "minus_"))


def simulation_data(result, t_span) -> dict:
    """The ``result`` of ``nhham simulate`` from a SimulationResult."""
    d = result.diagnostics
    data = {
        "method": str(result.method),
        "success": bool(result.success),
        "status": status_name(result.status),
        "status_code": int(result.status),
        "message": str(result.message),
        "t_span": [float(t_span[0]), float(t_span[1])],
        "t_final": json_number(result.t[-1]),
        "state": list(result.names),
        "y_final": jsonable(result.y[:, -1]),
        "steps": int(result.nsteps),
        "nfev": int(result.nfev),
        "njev": int(result.njev),
        "nlu": int(result.nlu),
        "wall_time_s": json_number(result.wall_time_s),
        "constraint_residual_max": json_number(d.constraint_residual_max),
        "constraint_residual_rel_max": json_number(d.constraint_residual_rel_max),
        "energy_drift": json_number(d.energy_drift),
        "energy_drift_rel": json_number(d.energy_drift_rel),
        "energy_balance_residual": json_number(d.energy_balance_residual),
        "cond_c_max": json_number(d.cond_C_max),
        "cond_w_max": json_number(d.cond_W_max),
        "kkt_solve": str(d.kkt_solve),
        "kkt_ratio_max": json_number(d.kkt_ratio_max),
        "settings": jsonable({k: v for k, v in result.settings.items() if k != "method_choice"}),
        "method_choice": jsonable(result.settings.get("method_choice")),
        "initial_projection": None,
        "storage": None if result.storage is None else jsonable(result.storage.to_dict()),
        "singularity": None,
    }
    found = result.singularity
    if found is not None:
        data["singularity"] = {
            "part": found.part, "description": found.describe(),
            "cond_w": json_number(found.cond_W), "cond_mu": json_number(found.cond_mu),
            "cond_c": json_number(found.cond_C), "rank_mu": int(found.rank_mu),
            "state": jsonable(found.state)}
    p = result.initial_projection
    if p is not None:
        data["initial_projection"] = {
            "residual_before": json_number(p.residual_before),
            "residual_after": json_number(p.residual_after),
            "displacement_q": json_number(p.displacement_q),
            "displacement_v": json_number(p.displacement_v)}
    return data


def simulation_failure(result, scene_path: str, free_multipliers=()) -> str:
    """One line: why the run stopped, what was singular there, and what to do."""
    t = float(result.t[-1])
    code = int(result.status)
    where = f"at t = {t:.6g}"
    singular = result.singularity
    if singular is not None and singular.part in ("W", "mu"):
        todo = ("start from other [initial] data" if t == float(result.t[0]) else
                f"stop before it (--t-end below {t:.6g}) or start from [initial] data whose "
                f"motion avoids it")
        return (f"simulation stopped {where}: {singular.describe()}; the dynamics is not "
                f"defined there: {todo}")
    if code == -3 or singular is not None:
        why = (f"free multiplier {', '.join(free_multipliers)}: " if free_multipliers else "")
        what = (singular.describe() if singular is not None else
                "the constraint matrix C is singular")
        return (f"simulation stopped {where}: {why}{what}, so the multipliers are not "
                f"determined; run `nhham classify {scene_path}` to see the free multipliers "
                f"or secondary constraints, or where the rank of C drops")
    if code == -6:
        return f"interrupted (Ctrl-C) {where}: the states up to there are in the output"
    if code == -2:
        return (f"simulation stopped {where}: the state became non-finite; check the "
                f"parameters and [initial] data, or try a smaller --max-step")
    if code == -4:
        todo = "a smaller --step" if result.settings.get("step") else "a smaller --rtol or --max-step"
        return (f"simulation stopped {where}: the Newton iteration of the step (or of the "
                f"projection onto the constraints) did not converge; try {todo}")
    stiff = "" if lookup(result.method).stiff else f"--method {names(lambda m: m.stiff)[0]} or "
    return f"simulation stopped {where}: {result.message}; try {stiff}a looser --rtol"


# ------------------------------------------------------------------- bench
def bench_data(result) -> dict:
    """The ``result`` of ``nhham bench`` from a WorkPrecisionResult."""
    rows = []
    for r in result.rows:
        rows.append({"method": str(r.method), "setting": str(r.setting),
                     "error": json_number(r.error), "wall_time_s": json_number(r.wall_time_s),
                     "runs": int(r.runs), "nfev": int(r.nfev),
                     "constraint_residual": json_number(r.constraint_residual),
                     "energy_drift": json_number(r.energy_drift),
                     "energy_balance_residual": json_number(r.energy_balance_residual),
                     "success": int(r.status) == 0,
                     "status": status_name(r.status), "status_code": int(r.status)})
    tts = []
    for target in (1e-6, 1e-10):
        for method, wall in result.time_to_solution(target).items():
            tts.append({"target": target, "method": method, "wall_time_s": json_number(wall)})
    return {"t_span": [float(x) for x in result.t_span], "backend": str(result.backend),
            "reference": str(result.reference),
            "reference_digits": int(result.reference_digits),
            "reference_error_estimate": json_number(result.reference_error_estimate),
            "reference_wall_time_s": json_number(result.reference_wall_time_s),
            "rows": rows, "time_to_solution": tts,
            "kkt_solve": str(result.kkt_solve),
            "kkt_ratio_max": json_number(result.kkt_ratio_max), "energy_change": str(result.forced),
            "skipped": [{"method": m, "setting": s, "reason": why}
                        for m, s, why in result.skipped]}


def bench_failure(exc, scene_path: str) -> str:
    """One line: why there is no reference solution, and what to run."""
    return (f"bench stopped: {exc}; run `nhham classify {scene_path}` and `nhham simulate "
            f"{scene_path}` to see why")


def bench_failure_data(t_span, reference_digits: int) -> dict:
    """The ``result`` of a bench whose reference could not be computed: no rows."""
    return {"t_span": [float(x) for x in t_span], "backend": "none", "reference": "none",
            "reference_digits": int(reference_digits), "reference_error_estimate": None,
            "reference_wall_time_s": None, "rows": [], "time_to_solution": [], "skipped": [],
            "kkt_solve": None, "kkt_ratio_max": None, "energy_change": None, "plot": None}

