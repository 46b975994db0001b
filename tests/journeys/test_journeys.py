"""The journeys: each answer against hand-derived values, and the command printing it.

The rolling disk (x' = R cos(theta) phi', y' = R sin(theta) phi'; L = m (x'^2 + y'^2)/2 +
I1 theta'^2/2 + I2 phi'^2/2): C = -(mu W^-1 mu^T) = -diag(1/m + R^2/I2 cos^2, ...) is
regular; the constraints are not integrable (their Frobenius term is R phi' ...); on T*Q
psi_1 = p_x/m - R cos(theta) p_phi/I2 and psi_2 = p_y/m - R sin(theta) p_phi/I2 have
{psi_1, psi_2} = 0 (neither depends on p_theta), so both are first class. The multipliers:
m x'' = -lambda_1, m y'' = -lambda_2, I2 phi'' = R (lambda_1 cos + lambda_2 sin) and the
differentiated constraints give phi'' = 0 and lambda_1 = m R theta' phi' sin(theta).
"""

import dataclasses
import json

import pytest
import sympy as sp

import nhham
from nhham.cli.main import main
from nhham.errors import InputError
from nhham.journeys.answer import as_scene

DISK = "examples/rolling_disk.toml"


def command(capsys, *argv):
    capsys.readouterr()
    status = main([*argv, "--json"])
    return status, json.loads(capsys.readouterr().out)


def test_classify_answers_the_hand_derived_verdict():
    data = nhham.classify(nhham.models.rolling_disk()).data
    assert (data["status"], data["regular"], data["integrable"]) == ("determined", True, False)
    assert (data["first_class"], data["second_class"], data["rank_c"]) == (2, 0, 2)


def test_derive_gives_the_hand_derived_multiplier():
    data = nhham.derive(nhham.models.rolling_disk()).data
    names = {n: sp.Symbol(n) for n in ("I2", "m", "R", "phi_dot", "theta_dot", "theta")}
    got = nhham.parse_expression(data["multipliers"][0], list(names))
    want = (names["m"] * names["R"] * names["phi_dot"] * names["theta_dot"]
            * sp.sin(names["theta"]))
    assert sp.simplify(got - want) == 0


@pytest.mark.parametrize("journey, command_name", [
    (nhham.classify, "classify"), (nhham.derive, "derive"), (nhham.compare, "compare")])
def test_the_command_prints_the_journey_s_answer(capsys, journey, command_name):
    status, envelope = command(capsys, command_name, DISK)
    answer = journey(nhham.load_scene(DISK, check_initial=False))
    timing = ("wall_time_s",)   # compare's own measurement
    got = {k: v for k, v in envelope["result"].items() if k not in timing}
    want = {k: v for k, v in json.loads(json.dumps(answer.to_dict())).items() if k not in timing}
    assert status == 0 and got == want
    if command_name == "compare":   # its text reports its own wall time
        return
    capsys.readouterr()
    assert main([command_name, DISK]) == 0
    assert capsys.readouterr().out.strip() == answer.text().strip()


def test_an_answer_is_frozen_and_its_dict_a_copy():
    answer = nhham.classify(nhham.models.rolling_disk())
    with pytest.raises(dataclasses.FrozenInstanceError):
        answer.data = {}
    copy = answer.to_dict()
    copy["status"] = "changed"
    assert answer.data["status"] == "determined"


def test_a_journey_takes_a_path_a_scene_or_a_system():
    by_path = nhham.classify(DISK).data
    assert nhham.classify(nhham.load_scene(DISK)).data == by_path
    assert nhham.classify(nhham.load_scene(DISK).system).data["status"] == by_path["status"]
    with pytest.raises(nhham.InputError, match="expected a Scene, a System"):
        as_scene(42)


def test_linearize_without_a_steady_table_names_the_key():
    with pytest.raises(nhham.InputError) as info:
        nhham.linearize(DISK)
    assert info.value.key == "steady"


def test_the_old_model_level_linearize_still_answers_with_a_warning():
    from nhham.numerics.codegen import numeric_model

    scene = nhham.loads_scene('coordinates = ["x"]\nlagrangian = "x_dot**2/2 - 4*x**2/2"\n'
                              'constraints = []\n')
    model = numeric_model(scene.system)
    with pytest.warns(DeprecationWarning, match="nhham.numerics.linearization.linearize"):
        lin = nhham.linearize(model, [0.0, 0.0])
    assert sorted(abs(z.imag) for z in lin.eigenvalues) == pytest.approx([2.0, 2.0])


def test_a_law_in_t_is_named_before_a_missing_steady_table():
    """examples/snakeboard_gait.toml has neither a steady motion of its closed loop (its law
    uses t) nor a [steady] table: the root cause, the law, is what linearize names."""
    with pytest.raises(InputError) as info:
        nhham.linearize("examples/snakeboard_gait.toml")
    assert info.value.key == "control" and "the law uses t" in str(info.value)
