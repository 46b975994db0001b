"""nhham.report: short reprs, LaTeX and HTML of the main results."""

import pytest

import nhham
from nhham.system.scene import load_scene

from conftest import EXAMPLES


@pytest.fixture(scope="module")
def disk():
    return nhham.models.rolling_disk(symbolic=True)


def test_reports_of_symbolic_results(disk):
    G = nhham.lagrangian_geometry(disk)
    for obj, must in [(G, r"\ddot{x} &="), (nhham.hamiltonian_side(disk), r"H &="),
                      (nhham.analyze_constraints(disk), r"M_{1} &="),
                      (nhham.cross_check(disk), r"\begin{array}"),
                      (G.constraint_matrix, r"\begin{bmatrix}")]:
        r = nhham.report(obj)
        assert len(repr(r)) < 200 and "\n" not in repr(r)
        latex = r._repr_latex_()
        assert latex.startswith("$$") and must in latex, (type(obj).__name__, latex[:300])


def test_reports_of_numeric_results():
    scene = load_scene(EXAMPLES / "chaplygin_sleigh.toml")
    run = nhham.simulate(scene.system, **scene.simulate_options(t_end=1.0))
    r = nhham.report(run)
    assert r._repr_latex_() is None and "<table>" in r._repr_html_()
    assert "theta_dot" in r._repr_html_() and "DOP853" in repr(r)


def test_report_of_a_classification_decided_at_points():
    """classify_constraints' docstring accepts a System; for the differential drive the
    classes are decided at points with no constraint analysis attached (it raised
    TypeError). The report runs the analysis for its table."""
    system = load_scene(EXAMPLES / "differential_drive.toml").system
    classes = nhham.classify_constraints(system)
    assert classes.analysis is None
    r = nhham.report(classes)
    assert "n = 5 coordinates, m = 3 velocity constraints" in repr(r)
    assert r"\text{first / second class} &= 1\ /\ 2" in r.latex
    assert "first class             1" in r.text


def test_report_of_a_linearization():
    lin = nhham.linearize(load_scene(EXAMPLES / "differential_drive.toml")).payload["linearization"]
    r = nhham.report(lin)
    assert "asymptotically stable" in repr(r) and "\n" not in repr(r)
    assert "<table>" in r._repr_html_() and "phiR_dot" in r._repr_html_()


def test_report_refuses_other_objects():
    with pytest.raises(TypeError, match="no report for"):
        nhham.report(object())


def test_scene_simulate_options():
    """The [simulate] table of the sleigh (t_end 20, DOP853, rtol 1e-10) as keywords,
    each overridable."""
    scene = load_scene(EXAMPLES / "chaplygin_sleigh.toml")
    opts = scene.simulate_options()
    assert opts["t_span"] == (0.0, 20.0) and opts["method"] == "DOP853"
    assert opts["rtol"] == 1e-10 and opts["y0"]["theta_dot"] == 1.0
    assert scene.simulate_options(t_end=2.0, rtol=1e-6)["t_span"] == (0.0, 2.0)
    assert scene.simulate_options(rtol=1e-6)["rtol"] == 1e-6


def test_the_trace_of_the_algorithm_is_in_the_report(disk):
    """The stages and decisions are rendered here (nhham.render.trace), not by the results:
    the analysis' report carries its trace, and a bare run of the algorithm has one."""
    analysis = nhham.analyze_constraints(disk)
    text = str(nhham.report(analysis))
    assert "Stage 1: M_1 defined by 2 constraint(s); rank (Z_i(chi_j)) = 2" in text
    run = analysis.blocks[0].run
    r = nhham.report(run)
    assert str(r).startswith("Constraint algorithm: determined")
    assert r._repr_latex_().startswith("$$") and r"\text{determined}" in r._repr_latex_()
