"""The first/second-class split at exact points of M_f (nhham.hamiltonian.classes_at_points).

The rank of the bracket matrix proved modulo p where it is the largest an antisymmetric
matrix can have, checked against the canonical bracket on T*Q at float points (a second
formulation); the first-class combination's coefficients by construction.
"""

import pytest

from nhham import Policy, models
from nhham.hamiltonian.classification import classify_constraints


@pytest.mark.parametrize("links", [3, 5])
def test_odd_number_of_constraints_rank_proved_modulo_p(links):
    """k odd: an antisymmetric B has rank at most k - 1, so rank k - 1 modulo p at one point
    of M_1 is a proof (the 17-link snake spent 34 s in rational arithmetic without it). The
    rank agrees with the canonical bracket on T*Q at float points (a second formulation)."""
    system = models.snake(links)
    # the combinations are not formed in closed form (combination_size 0; their forming is
    # tested in test_combinations.py): the rank and the coefficients at the points are
    policy = Policy(combination_size=0)
    c = classify_constraints(system, policy=policy)
    k = len(c.labels)
    assert k == links and c.rank == k - 1 and c.first_class == 1
    assert c.decisions["rank"].method == "exact" and c.decisions["rank"].error_bound == 0.0
    sampled = classify_constraints(system, method="sampled", policy=policy)
    assert sampled.rank == c.rank
    # the first-class combination: coefficient 1 on the constraint outside R
    (coeffs,) = c.combination_coefficients
    (outside,) = [a for a in c.labels if a not in c.second_class_set]
    assert all(abs(x - 1.0) < 1e-12 for x in coeffs[outside])


def test_W_singular_on_all_of_M1_is_refused_at_the_float_points():
    """W = diag(2, theta'^2, e^theta) (k = 0): regular on TQ, singular wherever
    theta' = 0, which is all of M_1. The bracket's float points met a singular solve (a
    ZeroDivisionError: an internal error of derive); now the refusal says so."""
    import nhham
    from nhham.errors import InputError
    from nhham.verdict.values import classification_at_values

    system = nhham.System(["q1", "theta", "q2"], "2*q1_dot**2/2 + k*theta_dot**2/2 "
                          "+ exp(theta)*q2_dot**2/2 + theta_dot**4/12", ["pi*theta_dot"],
                          parameters={"k": 0.0})
    with pytest.raises(InputError, match="W = d2L/dv dv is singular at every one of 6 points "
                                         "of M_1"):
        classification_at_values(system)
