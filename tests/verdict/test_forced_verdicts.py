"""Verdicts at the parameter values and for every value keep the forces (the systems of a
parameter case are rebuilt with them), and the inputs are not split into cases.

Example 3.2 with L = (q1'² + q2'² - b q3'²)/2 + q1²/2, q1' + q3' = 0 and a damper -k q1' on
q1 (by hand): Z = (-1, 0, 1/b) on (v1, v2, v3), C = -1 + 1/b, so C is regular for b ≠ 1;
at b = 1 the damper makes χ2 = q1 - k q1' with Z(χ2) = k: two stages for k ≠ 0, and the
paper's three (χ2 = q1, χ3 = q1') for k = 0.
"""

import nhham
from nhham.verdict.parametric import parametric_classification
from nhham.verdict.values import classification_at_values

L = "(q1_dot**2 + q2_dot**2 - b*q3_dot**2)/2 + q1**2/2"


def damped(k, b, inputs=()):
    return nhham.System(["q1", "q2", "q3"], L, constraints=["q1_dot + q3_dot"],
                        parameters={"k": k, "b": b}, forces={"q1": "-k*q1_dot"},
                        inputs=inputs)


def test_the_verdict_at_values_on_an_exceptional_set_keeps_the_force():
    at = classification_at_values(damped(0.5, 1.0))
    assert at.verdict.stages == 2 and at.verdict.first_class == 0
    assert at.verdict.second_class == 2
    assert classification_at_values(damped(0.0, 1.0)).verdict.stages == 3


def test_every_case_keeps_the_force_and_no_case_splits_an_input():
    system = nhham.System(["q1", "q2", "q3"], L, constraints=["q1_dot + q3_dot"],
                          parameters=["k", "b"], forces={"q1": "-k*q1_dot", "q2": "u"},
                          inputs=["u"])
    verdict = parametric_classification(system)
    stages = {tuple(sorted(str(e) for e in case.conditions)): case.verdict.stages
              for case in verdict.cases}
    assert stages[("b - 1",)] == 2
    assert stages[("b - 1", "k")] == 3
    assert all("u" not in key for conds in stages for key in conds)


def test_a_case_whose_secondary_constraint_holds_an_input_is_not_classified_alone():
    """C = 1 - b^2 by hand (W = diag(1, 1, -1), mu = (0, 1, b)); at b = +-1 the tangency
    condition reads q2'' + b q3'' = q1 + u (the multiplier drops out): a secondary
    constraint in the input u, which nhham does not take. Those two cases are reported as
    not classified, with the reason; the generic verdict stands (the run used to stop)."""
    import nhham

    system = nhham.System(["q1", "q2", "q3"], "(q1_dot**2 + q2_dot**2 - q3_dot**2)/2",
                          ["q2_dot + b*q3_dot"], parameters={"b": 0.5},
                          forces={"q2": "u + q1"}, inputs=["u"])
    verdicts = nhham.parametric_classification(system)
    assert verdicts.generic.status == "determined" and verdicts.generic.rank_C == 1
    assert sorted(str(c.conditions[0]) for c in verdicts.cases) == ["b + 1", "b - 1"]
    for case in verdicts.cases:
        assert case.verdict.status == "invalid"
        assert "not classified in this case" in case.verdict.note
        assert "q1 + u depends on u" in case.verdict.note
    assert verdicts.scene_case is None        # b = 0.5 is generic
