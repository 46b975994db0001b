"""The constraint algorithm's trace as text and LaTeX (nhham.render.trace): stages, ranks,
how each decision was made, the multipliers."""

from handmade import example_3_2 as ex32
from nhham.lagrangian.engine import Policy
from nhham.render.trace import analysis_latex, analysis_text
from nhham.lagrangian.analysis import analyze_constraints


def test_report_prints_stages_ranks_and_evidence():
    text = analysis_text(analyze_constraints(ex32()))
    for piece in ["Stage 1", "Stage 2", "Stage 3", "rank (Z_i(chi_j)) = 1", "secondary[1]",
                  "(exact, exact)", "lambda_1 = q1", "integrab"]:
        assert piece in text
    sampled = analysis_text(analyze_constraints(ex32(), policy=Policy(exact=False, precision=30)))
    assert "sampled, mpmath:30" in sampled and "seeded points" in sampled


def test_compact_repr_and_latex_of_the_analysis():
    from nhham.system.models import rolling_disk

    a = analyze_constraints(rolling_disk(symbolic=True))
    assert len(repr(a)) < 200 and "determined" in repr(a)
    tex = analysis_latex(a)
    assert tex.startswith("$$") and r"\dot{x}" in tex and r"\dot{\phi}" in tex
