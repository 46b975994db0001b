"""``nhham classify`` of a singular Lagrangian: the Dirac–Bergmann chain as data and text.

The data has the keys of every classify result (``$defs/classify`` of the schema: status,
stages, final constraints, first and second class, ...) and those of the chain:
``lagrangian_rank``, ``hamiltonian`` (H_c, H_T), ``generations`` (constraints in (q, p),
primary first), ``independent``, ``degrees_of_freedom``, ``gauge_generators``,
``irregular`` and ``dirac_bracket``.
"""

from __future__ import annotations

import sympy as sp

from nhham.render import latex as tex
from nhham.render.results import classify_rows
from nhham.render.simplify import display_form
from nhham.render.text import expr_text, labelled, paragraph, table

__all__ = ["singular_data", "singular_text", "singular_latex", "singular_warnings",
           "singular_parametric_data", "singular_parametric_text", "singular_derive_data",
           "singular_derive_text", "singular_derive_latex", "singular_compare_data",
           "singular_compare_text", "singular_lagrangian_derive_data"]

#: Why the Frobenius test says nothing here.
NO_VELOCITY_CONSTRAINTS = ("not applicable: no velocity constraints (a singular Lagrangian: "
                           "the Dirac-Bergmann chain)")


def singular_data(db) -> dict:
    """The ``result`` of ``nhham classify`` for a :class:`~nhham.hamiltonian.dirac_bergmann.
    DiracBergmann` chain."""
    run, image = db.run, db.image
    momenta = image.momenta

    def shown(c):
        return expr_text(display_form(c, momenta))

    stages = []
    for s in run.stages:
        d = s.to_dict(expressions=False)
        d["constraints"] = [shown(c) for c in d["constraints"]]
        stages.append(d)
    first = run.stages[0] if run.stages else None
    classes = db.classes
    formed = classes is not None and classes.first_class_combinations is not None
    combos = [shown(c) for c in classes.first_class_combinations] if formed else []
    coefficients = [[{"label": lab, "coefficient": shown(c)} for lab, c in d.items()]
                    for d in classes.combination_coefficients] if formed else None
    return {
        "n": int(db.n),
        "m": 0,
        "regular": bool(first is not None and first.rank == len(db.multipliers)),
        "rank_c": int(first.rank) if first else 0,
        "rank_c_method": (first.decisions[0].decision.method
                          if first and first.decisions else "exact"),
        "status": str(run.status),
        "stages": stages,
        "final_labels": list(run.final_labels),
        "final_constraints": [shown(c) for c in run.final_constraints],
        "free_multipliers": len(run.free_multiplier_symbols),
        "free_multiplier_symbols": [s.name for s in run.free_multiplier_symbols],
        "redundant": [],
        "integrable": None,
        "integrability": NO_VELOCITY_CONSTRAINTS,
        "constraint_kinds": [{"label": f"holonomic[{i}]", "kind": "holonomic",
                              "time_dependent": False}
                             for i in range(len(db.system.holonomic))],
        "first_class": db.first_class,
        "second_class": db.second_class,
        "second_class_set": [] if classes is None else list(classes.second_class_set),
        "first_class_combinations": combos,
        "first_class_coefficients": coefficients,
        "inconsistency": run.inconsistency,
        "lagrangian_rank": {"rank": int(image.rank), "n": int(db.n),
                            "null_vectors": [[expr_text(e) for e in k]
                                             for k in image.null_vectors],
                            "drops_where": [expr_text(f) for f in image.rank_drops]},
        "hamiltonian": {"canonical": shown(image.canonical_hamiltonian),
                        "total": expr_text(db.total_hamiltonian),
                        "multipliers": [s.name for s in db.multipliers]},
        "generations": [[shown(c) for c in gen] for gen in db.generations],
        "generation_labels": [list(g) for g in db.generation_labels],
        "independent": db.independent,
        "degrees_of_freedom": _number(db.degrees_of_freedom),
        "velocity_constraints": [{"label": lab, "condition": shown(c)}
                                 for lab, c in _velocity_constraints(db)],
        "velocities_as_state": [u.name for u in db.velocities_as_state],
        "gauge_generators": [_generator(g, shown) for g in
                             (db.gauge_generators if db.consistent else ())],
        "irregular": [{"label": lab, "constraint": expr_text(g), "regular_equivalent":
                       expr_text(r)} for lab, g, r in db.replaced]
        + [{"label": lab, "constraint": shown(db.named_constraints[lab]),
            "regular_equivalent": None} for lab in db.irregular],
        "dirac_bracket": _dirac(db),
    }


def _number(x):
    if x is None or isinstance(x, int):
        return x
    return float(x)  # a Fraction: half-integer counts say something is off, shown as is


def _generator(g, shown) -> dict:
    return {"parameter": g.parameter.name,
            "generator": expr_text(g.expression),
            "terms": [{"derivative": int(k), "function": shown(f)} for k, f in g.terms],
            "transformations": {str(z): expr_text(d) for z, d in g.transformations},
            "first_class": g.checked.to_dict(value=True)}


def _dirac(db):
    D = db.dirac_bracket if db.consistent else None
    if D is None:
        return None
    z = db.algebra.variables
    return {"coordinates": [str(s) for s in z],
            "matrix": [[expr_text(D[i, j]) for j in range(D.cols)] for i in range(D.rows)]}


def _velocity_constraints(db) -> list:
    """(label, expression) of the velocity constraints at v = dH_T/dp: conditions on the
    motion, or constraints on (q, p, u) where the u^a are state."""
    if not db.velocities_as_state:
        return list(db.conditions)
    labels = db.system.constraint_labels[len(db.system.holonomic):]
    return [(lab, db.named_constraints[lab]) for lab in labels if lab in db.named_constraints]


def singular_warnings(db) -> list:
    return list(db.warnings)


def singular_text(title: str, data: dict) -> str:
    """The chain's report: the verdict, generations, classes, gauge generators, the Dirac
    bracket's non-canonical entries."""
    rank = data["lagrangian_rank"]
    lines = [paragraph(f"{title}: n = {data['n']} coordinates, a singular Lagrangian "
                       f"(rank W = {rank['rank']} of {rank['n']}): the Dirac-Bergmann chain")]
    free = data["free_multipliers"]
    rows: list = [("status", data["status"]),
            ("generations", str(len(data["generations"]))),
            ("free multipliers", f"{free}" + (f" ({', '.join(data['free_multiplier_symbols'])})"
                                              if free else ""))]
    if data["first_class"] is not None:
        rows += [("independent constraints", str(data["independent"])),
                 ("first class", str(data["first_class"])),
                 ("second class", str(data["second_class"])),
                 ("degrees of freedom", _dof_text(data))]
        for item in data["irregular"]:
            regular = item["regular_equivalent"]
            rows.append((f"irregular {item['label']}", f"{item['constraint']} = 0, "
                         + (f"replaced by {regular} = 0 (the same zero set)" if regular
                            else "no regular equivalent: no count")))
    lines.append(table(rows))
    lines.append(f"H_c = {data['hamiltonian']['canonical']}")
    state = data.get("velocities_as_state") or []
    lines.append("generations (in q, p" + "".join(f", {u}" for u in state) + "):")
    gens: list = []
    for k, (labs, cons) in enumerate(zip(data["generation_labels"], data["generations"])):
        for i, (lab, c) in enumerate(zip(labs, cons)):
            gens.append((f"{k + 1}" + (" (primary)" if k == 0 else "") if i == 0 else "",
                         lab, c))
    lines.append(table(gens))
    if data["velocity_constraints"] and state:
        lines.append("velocity constraints at v = dH_c/dp + u^a dphi_a/dp (constraints on "
                     f"(q, p, {', '.join(state)}): the velocities along ker W are state):")
        lines.append(table([(c["label"], c["condition"]) for c in data["velocity_constraints"]]))
    elif data["velocity_constraints"]:
        lines.append("velocity constraints at v = dH_T/dp (conditions on the motion, each "
                     "fixing multipliers or adding constraints):")
        lines.append(table([(c["label"], c["condition"]) for c in data["velocity_constraints"]]))
    if data["first_class_combinations"]:
        lines.append("first-class combinations (in q, p):")
        lines.append(table([(f"gamma_{i + 1}", "=", c)
                            for i, c in enumerate(data["first_class_combinations"])]))
    if data["second_class_set"]:
        lines.append("maximal second-class set: " + ", ".join(data["second_class_set"]))
    if data["gauge_generators"]:
        lines.append("gauge generators (delta z = {z, G}):")
        rows = []
        for g in data["gauge_generators"]:
            moves = ", ".join(f"delta {z} = {d}" for z, d in g["transformations"].items())
            rows += [(f"G({g['parameter']})", "=", g["generator"]), ("", "", moves)]
        lines.append(table(rows))
    dirac = data["dirac_bracket"]
    if dirac and data["second_class"]:
        z, M = dirac["coordinates"], dirac["matrix"]
        n = len(z) // 2
        rows = [(f"{{{z[i]}, {z[j]}}}_D", "=", M[i][j]) for i in range(len(z))
                for j in range(i + 1, len(z)) if M[i][j] != ("1" if j == i + n else "0")]
        lines.append("Dirac bracket (the entries that differ from the canonical ones):")
        lines.append(table(rows) if rows else "  none")
    if data["inconsistency"]:
        lines.append(f"inconsistent: {data['inconsistency']}")
    return "\n".join(lines)


# ----------------------------------------------------------------------- compare
def singular_compare_data(db, seconds: float) -> dict:
    """The ``result`` of ``nhham compare`` for a singular Lagrangian: the Lagrangian chain
    on TQ against the Dirac-Bergmann chain through Leg (``$defs/compare``'s keys, the
    three checks as ``checks``, the comparison itself as ``lagrangian_side``)."""
    eq = db.equivalence
    side = eq.to_dict()
    into = all(d["value"] for d in side["into"])
    onto = bool(side["ranks"]) and all(r == side["expected_rank"] for r in side["ranks"])
    residual = None if side["why_not"] else side["motion_residual"]
    checks = [
        {"name": "leg_maps_final_manifolds", "agree": into and not side["why_not"],
         "exact": all(d["method"] != "sampled" for d in side["into"]),
         "max_abs_difference": None, "max_rel_difference": None, "samples": side["points"],
         "detail": "every final constraint of T*Q pulled back by Leg vanishes on M_f^L",
         "method": "exact" if all(d["method"] == "exact" for d in side["into"]) else "points"},
        {"name": "leg_onto", "agree": onto, "exact": False, "max_abs_difference": None,
         "max_rel_difference": None, "samples": side["points"],
         "detail": f"the rank of Leg on T M_f^L is dim M_f^H = {side['expected_rank']} at "
                   f"every point: {side['ranks']}", "method": "sampled"},
        {"name": "motions_correspond", "agree": bool(eq.agree), "exact": False,
         "max_abs_difference": None, "max_rel_difference": residual,
         "samples": side["points"], "detail": "Leg_* of every Lagrangian motion is a "
         "Hamiltonian one (the free directions included)", "method": "sampled"},
    ]
    run = eq.lagrangian

    def stages(r):
        return [] if r is None else [
            {"index": s.index, "constraint_count": len(s.constraints), "rank": s.rank,
             "augmented_rank": s.augmented_rank, "labels": list(s.labels)} for s in r.stages]

    return {
        "agree": bool(eq.agree), "exact": False, "max_abs_difference": None,
        "max_rel_difference": residual, "samples": side["points"], "tolerance": 1e-8,
        "precision": "float64", "method": "sampled", "checks": checks,
        "lagrangian_stages": stages(run), "hamiltonian_stages": stages(db.run),
        "lagrangian_status": None if run is None else run.status,
        "hamiltonian_status": db.run.status, "wall_time_s": round(seconds, 3),
        "skipped_points": 0, "dirac_vs_projected": None, "lagrangian_side": side,
    }


def singular_compare_text(title: str, data: dict) -> str:
    return "\n".join([paragraph(f"{title}: the Lagrangian chain on TQ against the "
                                 f"Dirac-Bergmann chain through Leg"),
                       _lagrangian_side_text(data["lagrangian_side"])])


def _lagrangian_side_text(side: dict) -> str:
    """The chain on TQ and its comparison through Leg, a few lines."""
    if side["why_not"]:
        return paragraph(f"not compared: the chain on TQ did not run: {side['why_not']}")
    into = all(d["value"] for d in side["into"])
    onto = all(r == side["expected_rank"] for r in side["ranks"])
    rows = [("status", f"{side['lagrangian_status']}, dim M_f = {side['lagrangian_dimension']}"
             + (f", free accelerations {', '.join(side['free_accelerations'])}"
                if side["free_accelerations"] else ""))]
    rows += [(c["label"], c["constraint"]) for c in side["lagrangian_constraints"]]
    rows += [("Leg(M_f^L) in M_f^H", "yes" if into else "no"),
             ("onto (rank of Leg)", f"{'yes' if onto else 'no'} ({side['expected_rank']} "
              f"at {side['points']} points)"),
             ("motions correspond", f"{'yes' if side['agree'] else 'no'} (residual "
              f"{side['motion_residual']:.1e})")]
    return "Lagrangian side (TQ, q' = v built in):\n" + table(rows)


def _dof_text(data: dict) -> str:
    if data["degrees_of_freedom"] is not None:
        return str(data["degrees_of_freedom"])
    if data.get("velocities_as_state"):
        return (f"not counted: the velocities along ker W ({', '.join(data['velocities_as_state'])}) "
                f"are state variables of the chain (a velocity constraint or force nonlinear "
                f"in them)")
    if data["velocity_constraints"]:
        return ("not counted: velocity constraints restrict the motion on M_f, not T*Q "
                "((2n - 2 FC - SC)/2 does not apply)")
    return "not stated (irregular constraints)"


def singular_latex(title: str, data: dict, parse) -> str:
    """classify's LaTeX rows with the chain's counts and gauge generators."""
    rows = classify_rows(title, data, parse)
    # the stage-1 rank is that of the primaries' brackets, not of a matrix C
    rows[1] = (r"\operatorname{rank} \{\chi_j, \varphi_a\}|_{M_1}", f"{data['rank_c']}")
    rows.insert(1, (r"\operatorname{rank} W", f"{data['lagrangian_rank']['rank']}"))
    rows.append((r"H_c", tex.latex(parse(data["hamiltonian"]["canonical"]))))
    if data["degrees_of_freedom"] is not None:
        rows.append((tex.text("degrees of freedom"), str(data["degrees_of_freedom"])))
    for g in data["gauge_generators"]:
        rows.append((tex.text("gauge generator"), tex.latex(parse(g["generator"]))))
    return tex.aligned(rows)


# ------------------------------------------------------------------ --parametric
def singular_parametric_data(pv) -> dict:
    """The ``result`` of ``nhham classify --parametric`` for a singular Lagrangian (the
    keys of ``$defs/classify_parametric``; each verdict a chain's classify result)."""
    def verdict(db):
        return {**singular_data(db), "note": None}

    cases: list[dict] = []
    for case in pv.cases:
        v = verdict(case.chain) if case.chain is not None else {
            "status": "invalid", "note": case.failure}
        cases.append({"conditions": [expr_text(c) for c in case.conditions], "excluding": [],
                      "reasons": list(case.reasons), "verdict": v})
    return {
        "parameters": [s.name for s in pv.symbolic],
        "positive": [],
        "values": {p.name: float(v) for p, v in pv.values.items()},
        "held": {k: float(v) for k, v in pv.held.items()},
        "generic": verdict(pv.generic),
        "cases": cases,
        "scene_case": pv.scene_case(),
        "dropped": [],
        "notes": [],
        "search": {"complete": True, "seconds": round(pv.seconds, 3), "allowed_s": None,
                   "cut": [], "pending": [], "unsolved": [], "failed": [
                       {"search": ", ".join(c["conditions"]), "why": c["verdict"]["note"]}
                       for c in cases if c["verdict"]["status"] == "invalid"]},
    }


def _verdict_line(v: dict) -> str:
    if v["status"] == "invalid":
        return f"invalid: {v['note']}"
    if v["status"] == "inconsistent":
        return "inconsistent"
    dof = v["degrees_of_freedom"]
    return (f"{v['status']}, {len(v['generations'])} generation(s), {v['first_class']} first "
            f"class, {v['second_class']} second class, "
            + ("degrees of freedom not stated (irregular)" if dof is None
               else f"{dof} degree(s) of freedom"))


def singular_parametric_text(title: str, data: dict) -> str:
    """The generic chain and each case, a line each, then the scene's case."""
    names = ", ".join(data["parameters"]) or "(none symbolic)"
    lines = [paragraph(f"{title}: the Dirac-Bergmann chain for every value of the "
                       f"parameters {names}")]
    lines.append("generic (where no case below holds):")
    lines.append(table([("verdict", _verdict_line(data["generic"]))]))
    for i, case in enumerate(data["cases"]):
        lines.append(f"case {i}: " + ", ".join(f"{c} = 0" for c in case["conditions"]))
        lines.append(table([("verdict", _verdict_line(case["verdict"])),
                            ("why", "; ".join(case["reasons"]))]))
    if data["values"]:
        shown = ", ".join(f"{k} = {v:g}" for k, v in data["values"].items())
        where = "generic" if data["scene_case"] is None else f"case {data['scene_case']}"
        lines.append(f"scene values {shown}: {where}")
    return "\n".join(lines)


# ------------------------------------------------------------------------ derive
def singular_derive_data(db) -> dict:
    """The ``result`` of ``nhham derive --side hamiltonian`` for a singular Lagrangian: the
    motion z' = {z, H_c} + u^a {z, phi_a} (+ lambda^i {z, g_i}) with the multipliers the
    chain determined put in and the free ones as symbols, H_c and H_T, the final
    constraints and their bracket matrix, and the Dirac bracket of the phase coordinates."""
    momenta = db.image.momenta

    def shown(c):
        return expr_text(display_form(c, momenta))

    run = db.run
    fixed = db.fixed_multipliers
    classes = db.classes
    B = classes.bracket_matrix if classes is not None else None
    return {
        "side": "hamiltonian",
        "form": "explicit",
        "state": [s.name for s in db.variables],
        "field": [shown(f) for f in db.motion],
        "multipliers": [shown(fixed.get(s, s)) for s in db.multipliers],
        "multiplier_symbols": [s.name for s in db.multipliers],
        "free_multiplier_symbols": [s.name for s in run.free_multiplier_symbols],
        "constraint_matrix": ([[shown(B[i, j]) for j in range(B.cols)] for i in range(B.rows)]
                              if B is not None else None),
        "energy": shown(db.image.canonical_hamiltonian),
        "energy_name": "H_c",
        "total_hamiltonian": expr_text(db.total_hamiltonian),
        "final_constraints": [shown(c) for c in run.final_constraints],
        "status": run.status,
        "dirac_bracket": _dirac(db),
        "mass_matrix": None, "forcing": None, "constraint_jacobian": None,
        "constraint_rhs": None, "contact_forces": None,
    }


def singular_lagrangian_derive_data(run, system) -> dict:
    """``nhham derive`` (on TQ) of a singular Lagrangian: the motion of the chain on TQ
    (q' = v, v' = a with the accelerations it fixed, the free ones as symbols), the
    multipliers, E_L and the final constraints (the Lagrangian ones among them)."""
    v = system.velocities

    def shown(c):
        return expr_text(display_form(c, v))

    fixed = dict(run.multipliers)
    energy = sum((s * sp.diff(system.lagrangian, s) for s in v), sp.S.Zero) - system.lagrangian
    return {
        "side": "lagrangian", "form": "explicit",
        "state": [s.name for s in run.variables],
        "field": [shown(f) for f in run.dynamics],
        "multipliers": [shown(fixed.get(s, s)) for s in run.multiplier_symbols],
        "multiplier_symbols": [s.name for s in run.multiplier_symbols],
        "free_multiplier_symbols": [s.name for s in run.free_multiplier_symbols],
        "constraint_matrix": None, "energy": shown(sp.expand(energy)), "energy_name": "E_L",
        "final_constraints": [shown(c) for c in run.final_constraints],
        "status": run.status, "mass_matrix": None, "forcing": None,
        "constraint_jacobian": None, "constraint_rhs": None, "contact_forces": None,
    }


def singular_derive_text(title: str, data: dict) -> str:
    if data["side"] == "lagrangian":
        what = ("the motion on TQ of a singular Lagrangian on M_f (q' = v, the "
                "accelerations the chain on TQ fixed put in)")
    else:
        what = ("the Hamiltonian motion of a singular Lagrangian on M_f (z' = {z, H_T}, "
                "the multipliers the chain fixed put in)")
    lines = [paragraph(f"{title}: {what}")]
    lines.append(table([(f"{n}'", "=", t) for n, t in zip(data["state"], data["field"])]))
    rows = [(s, "=", v) for s, v in zip(data["multiplier_symbols"], data["multipliers"])
            if s != v]
    if rows:
        lines.append("multipliers fixed by the chain:")
        lines.append(table(rows))
    if data["free_multiplier_symbols"]:
        lines.append("free multipliers (gauge): " + ", ".join(data["free_multiplier_symbols"]))
    if data["side"] == "lagrangian":
        lines.append(labelled("energy E_L", data["energy"]))
    else:
        lines.append(labelled("canonical Hamiltonian H_c", data["energy"]))
        lines.append(labelled("total Hamiltonian H_T", data["total_hamiltonian"]))
    lines.append("final constraints: " + ", ".join(f"{c} = 0" for c in data["final_constraints"]))
    dirac = data.get("dirac_bracket")
    if dirac:
        z, M = dirac["coordinates"], dirac["matrix"]
        lines.append("Dirac bracket {z_i, z_j}_D (nonzero entries, i < j):")
        rows = [(f"{{{z[i]}, {z[j]}}}_D", "=", M[i][j]) for i in range(len(z))
                for j in range(i + 1, len(z)) if M[i][j] != "0"]
        lines.append(table(rows) if rows else "  none")
    return "\n".join(lines)


def singular_derive_latex(data: dict, parse) -> str:
    """z' = ..., the multipliers, H_c and H_T."""
    rows = []
    half = len(data["state"]) // 2
    pairs = list(zip(data["state"], data["field"]))
    for name, f in (pairs[half:] if data["side"] == "lagrangian" else pairs):
        if data["side"] == "lagrangian":  # q' = v is implied: the accelerations
            head = tex.name_latex(name[:-4] + "_ddot")
        elif name.startswith("p_"):
            head = rf"\dot{{p}}_{{{tex.name_latex(name[2:])}}}"
        else:
            head = rf"\dot{{{tex.name_latex(name)}}}"
        rows.append((head, tex.latex(parse(f))))
    for s, v in zip(data["multiplier_symbols"], data["multipliers"]):
        if s != v:
            rows.append((tex.name_latex(s), tex.latex(parse(v))))
    if data["side"] == "lagrangian":
        rows.append(("E_L", tex.latex(parse(data["energy"]))))
    else:
        rows.append(("H_c", tex.latex(parse(data["energy"]))))
        rows.append(("H_T", tex.latex(parse(data["total_hamiltonian"]))))
    return tex.aligned(rows)
