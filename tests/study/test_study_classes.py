"""Classification studies: each point's verdict against the verdict at its values."""

import pytest

import nhham
from nhham.study.classes import STATUS_CODES
from nhham.study.sweep import sweep

SCENE = "examples/parametric_null_constraint.toml"


def test_points_on_exceptional_sets_get_their_verdict_not_the_generic_one(tmp_path):
    result = sweep(SCENE, "classify", ["b=-2:2:9", "a=0:2:3"], workers=1)
    ds = result.dataset
    assert result.complete and list(ds["b"].values) == [-2, -1.5, -1, -0.5, 0, 0.5, 1, 1.5, 2]
    # by hand (the scene's header): a = 0 singular; b = +-1 underdetermined; else determined
    for i, b in enumerate(ds["b"].values):
        for j, a in enumerate(ds["a"].values):
            status = int(ds["status"].values[i, j])
            if a == 0:
                # W singular: the chain, point by point. p_q1 = 0 (u_1 free); the constraint
                # at v = dH_T/dp is p_q2 - b p_q3 = 0, whose tangency gives
                # lambda_1 (b**2 - 1) = 0: lambda_1 free too where b = +-1.
                assert status == STATUS_CODES["underdetermined"]
                assert ds["free_multipliers"].values[i, j] == (2 if abs(b) == 1 else 1)
            elif abs(b) == 1:
                assert status == STATUS_CODES["underdetermined"]
                assert ds["free_multipliers"].values[i, j] == 1 and ds["rank_C"].values[i, j] == 0
            else:
                assert status == STATUS_CODES["determined"] and ds["case"].values[i, j] == -1
                assert ds["first_class"].values[i, j] == 1


@pytest.mark.parametrize("b", [1.0, 0.5])
def test_a_point_agrees_with_the_classification_at_its_values(tmp_path, b):
    """The independent route: the scene with the point's values, classified as a scene."""
    text = open(SCENE).read().replace("b = 1.0", f"b = {b}")
    scene = tmp_path / "s.toml"
    scene.write_text(text)
    at = nhham.classification_at_values(nhham.load_scene(scene).system).verdict
    ds = sweep(SCENE, "classify", [f"b={b},3"], workers=1).dataset
    assert int(ds["status"].values[0]) == STATUS_CODES[at.status]
    assert int(ds["rank_C"].values[0]) == at.rank_C
    assert int(ds["free_multipliers"].values[0]) == at.free_multipliers


def test_only_parameters_with_values_are_swept():
    with pytest.raises(nhham.InputError, match="'q1' is not a parameter"):
        sweep(SCENE, "classify", ["q1=0:1:2"], workers=1)
