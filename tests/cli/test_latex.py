"""LaTeX in the paper's notation for derive, classify and compare."""

import re

import sympy as sp

from nhham.render.latex import latex, name_latex

from conftest import EXAMPLES, run_inprocess


def text_of(*args):
    rc, out, err = run_inprocess(*args)
    assert rc == 0, err
    return out


def balanced(s):
    depth = 0
    for ch in s.replace(r"\{", "").replace(r"\}", ""):
        depth += {"{": 1, "}": -1}.get(ch, 0)
        if depth < 0:
            return False
    return depth == 0


def test_names_in_the_papers_notation():
    assert name_latex("x_dot") == r"\dot{x}"
    assert name_latex("theta_ddot") == r"\ddot{\theta}"
    assert name_latex("p_phi") == r"p_{\phi}"
    assert name_latex("lambda_2") == r"\lambda_{2}"
    # the dot over the symbol, not over its subscript
    assert name_latex("q1_dot") == r"\dot{q}_{1}"
    assert name_latex("theta2_ddot") == r"\ddot{\theta}_{2}"
    assert name_latex("p_q1") == r"p_{q_{1}}"
    assert name_latex("I2") == "I_{2}"
    th, thd = sp.symbols("theta theta_dot")
    assert latex(sp.sin(th) * thd) == r"\dot{\theta} \sin{\left(\theta \right)}"


def test_derive_latex_rolling_disk():
    """x'' = -R phi' theta' sin(theta) (paper Example 2.1): printed as \\ddot{x} = ..."""
    out = text_of("derive", str(EXAMPLES / "rolling_disk.toml"), "--latex")
    assert r"\begin{aligned}" in out and balanced(out)
    assert re.search(r"\\ddot\{x\} &= - R \\dot\{\\phi\} \\dot\{\\theta\} \\sin", out), out
    assert r"\lambda_{1} &=" in out and r"E_L &=" in out and r"C &= \begin{bmatrix}" in out
    assert "_{dot}" not in out and "dot}}" not in out.replace(r"\dot{", "")


def test_derive_latex_hamiltonian_side_prints_H():
    out = text_of("derive", str(EXAMPLES / "chaplygin_sleigh.toml"), "--latex", "--side",
                  "hamiltonian")
    assert r"H &=" in out and r"\dot{p}_{x} &=" in out and r"\dot{\theta} &=" in out
    assert "E &=" not in out and balanced(out)
    # the sleigh's parameter I is a symbol, not the imaginary unit
    assert r"i " not in out


def test_classify_latex_paper_3_2_stages():
    out = text_of("classify", str(EXAMPLES / "paper_3_2.toml"), "--latex")
    assert balanced(out)
    for k in (1, 2, 3):
        assert f"M_{{{k}}}" in out
    assert r"\psi_{1} &= q_{1}" in out and r"\psi_{2} &= \dot{q}_{1}" in out
    assert r"M_{3} &= \{\phi_{1} = \psi_{1} = \psi_{2} = 0\}" in out
    assert r"p_{q_{3}}" in out  # the first-class combination


def test_compare_latex():
    out = text_of("compare", str(EXAMPLES / "chaplygin_sleigh.toml"), "--latex")
    assert r"\begin{array}" in out and balanced(out)
    assert r"(X_D - X)" in out  # nonholonomic: the Dirac flow is not the dynamics


def test_every_aligned_row_has_its_ampersand():
    """The title row of classify's aligned block had none."""
    out = text_of("classify", str(EXAMPLES / "paper_3_2.toml"), "--latex")
    body = out.split("\\begin{aligned}\n", 1)[1].split("\n\\end{aligned}", 1)[0]
    rows = body.split(" \\\\\n")
    assert len(rows) > 5 and all("&" in row for row in rows), rows[:2]
    assert rows[0].startswith(r"& \text{paper Example 3.2: }")


def test_constraint_labels_never_take_a_letter_the_scene_prints():
    """The rolling disk's coordinate phi: its constraints are Phi_1, Phi_2 (not \\phi_1,
    which reads as the coordinate); paper 3.2 (coordinates q1..q3) keeps the paper's
    phi_1 (test above)."""
    out = text_of("classify", str(EXAMPLES / "rolling_disk.toml"), "--latex")
    assert r"\Phi_{1} &= - R \dot{\phi}" in out and r"\Phi_{2} &=" in out
    assert r"M_{1} &= \{\Phi_{1} = \Phi_{2} = 0\}" in out
    assert r"\phi_{1}" not in out


def test_label_letters_fall_back_to_one_no_name_prints(tmp_path):
    """Coordinates phi, Phi and varphi and a parameter g in a holonomic constraint: the
    constraints are \\mathsf{c}_i and the holonomic one \\mathsf{g}_1 (no name prints
    \\mathsf)."""
    from nhham.render.latex import free_letter
    from nhham.render.results import label_letters

    assert free_letter([r"\phi", r"\Phi"], {r"\varphi", r"\dot{x}"}) == r"\phi"
    assert free_letter([r"\phi", r"\Phi"], {r"\dot{\phi}_{2}"}) == r"\Phi"
    assert label_letters({r"\phi", r"\Phi", r"\varphi", "g", r"\psi"}) == {
        "constraints": r"\mathsf{c}", "secondary": r"\Psi", "holonomic": r"\mathsf{g}"}
    path = tmp_path / "letters.toml"
    path.write_text('coordinates = ["phi", "Phi", "varphi"]\nparameters = { g = 1.0 }\n'
                    'lagrangian = "(phi_dot**2 + Phi_dot**2 + varphi_dot**2)/2"\n'
                    'constraints = ["phi_dot - Phi*varphi_dot"]\n'
                    'holonomic = ["g*phi + Phi - varphi"]\n')
    out = text_of("classify", str(path), "--latex")
    assert r"\mathsf{c}_{1} &= " in out and r"\mathsf{g}_{1} &= \Phi + g \phi" in out, out
