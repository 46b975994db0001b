"""The decision engine: the cascade's order, the policy, and the arithmetics checked
against each other (a wrong formula planted in one of them is caught)."""

import ast
import importlib
import inspect
import warnings
from pathlib import Path

import pytest

import nhham
from nhham import load_scene
from nhham.lagrangian import engine
from nhham.errors import InputError
from nhham.lagrangian.domains import ModP, NotExact
from nhham.lagrangian.engine import (
    STEPS,
    AtExactPoints,
    Policy,
    ProvedModuloP,
    Reduced,
    Sampled,
    answers_by_step,
    decide,
    offers,
    policy_of,
)
from nhham.lagrangian.geometry import LagrangianGeometry
from nhham.lagrangian.submanifold import Submanifold
from nhham.lagrangian.tangency import Tangency

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


class Recorder:
    """A quantity whose steps answer as told and record that they ran."""

    def __init__(self, answers, log):
        self.answers, self.log = answers, log

    def reduced(self, manifold, policy):
        self.log.append("reduced")
        return self.answers.get("reduced")

    def sampled(self, manifold, policy):
        self.log.append("sampled")
        return self.answers.get("sampled")


def test_the_cascade_stops_at_the_first_step_that_answers():
    log = []
    assert decide(Recorder({"reduced": "R", "sampled": "S"}, log), None, Policy()) == "R"
    assert log == ["reduced"]
    log.clear()
    assert decide(Recorder({"sampled": "S"}, log), None, Policy()) == "S"
    assert log == ["reduced", "sampled"]
    log.clear()
    assert decide(Recorder({}, log), None, Policy()) is None


def _tangency(name):
    system = load_scene(EXAMPLES / f"{name}.toml", drop_redundant=True).system
    geo = LagrangianGeometry(system)
    exprs = tuple(system.holonomic) + tuple(system.phi)
    return system, geo, exprs, Submanifold(system, exprs)


def test_exact_false_skips_the_steps_at_exact_points():
    system, geo, exprs, M = _tangency("rolling_disk")
    exact = decide(Tangency(system, geo.hessian, geo.forcing, exprs), M,
                   Policy(closed_form_size=0))
    assert exact.rank.method == "exact" and exact.rank.samples == 1  # proof modulo p
    sampled = decide(Tangency(system, geo.hessian, geo.forcing, exprs), M,
                     Policy(closed_form_size=0, exact=False))
    assert sampled.rank.method == "sampled" and sampled.rank.value == 2


def test_no_exact_points_gives_way_to_the_next_step():
    class NoPoints(Recorder):
        def observe(self, value):
            raise AssertionError("never reached: the value raises")

        def value(self, env, degrees=False):
            raise NotExact("a parameter value inside a sine")

        def pending_error(self, degrees, count, bound):
            raise AssertionError("never reached: the value raises")

        def conclude(self, count, degrees, bound):
            raise AssertionError("never reached: the value raises")

    assert offers(NoPoints({}, []), AtExactPoints)  # the step is tried, and gives way

    system, geo, exprs, M = _tangency("rolling_disk")
    log = []
    assert decide(NoPoints({"sampled": "S"}, log), M, Policy()) == "S"
    assert log == ["reduced", "sampled"]


# rank C on M_1 derived by hand: the rolling disk's C is 2 x 2 regular (two rolling
# constraints, W diagonal); the Chaplygin sleigh's 1 x 1 C = mu W^-1 mu^T > 0; the
# snakeboard's two wheel constraints give a regular 2 x 2 C; in the paper's Example
# 3.2 the constraint's velocity coefficients are annihilated by W^-1: C = 0.
RANK_C = {"rolling_disk": 2, "chaplygin_sleigh": 1, "snakeboard": 2, "paper_3_2": 0}


@pytest.mark.parametrize("name", sorted(RANK_C))
def test_every_arithmetic_gives_the_hand_derived_rank(name):
    system, geo, exprs, M = _tangency(name)
    answers = answers_by_step(lambda: Tangency(system, geo.hessian, geo.forcing, exprs), M,
                              Policy(closed_form_size=0))
    assert {"exact points", "sampled"} <= set(answers)
    assert {step: a.rank.value for step, a in answers.items()} == \
        {step: RANK_C[name] for step in answers}


class ModularDefect(Tangency):
    """Tangency with a wrong formula in one arithmetic: over GF(p) the bordered
    matrix K gets a 1 in its lower-right zero block (a sign or index slip)."""

    def value(self, env, degrees=False):
        K, c, J = super().value(env, degrees)
        if any(isinstance(x, ModP) for x in env.values()):  # a point over GF(p)
            K = [list(row) for row in K]
            K[-1][-1] = K[-1][-1] + 1
        return K, c, J


def test_a_wrong_formula_planted_in_one_arithmetic_is_caught():
    system, geo, exprs, M = _tangency("paper_3_2")
    policy = Policy(closed_form_size=0)
    # Alone, the engine would trust the planted proof: rank 1, C "regular".
    planted = decide(ModularDefect(system, geo.hessian, geo.forcing, exprs), M, policy)
    assert planted.rank.value == 1
    # The steps compared with each other expose it, and name the arithmetic.
    answers = answers_by_step(lambda: ModularDefect(system, geo.hessian, geo.forcing, exprs),
                              M, policy)
    ranks = {step: a.rank.value for step, a in answers.items()}
    assert ranks["proof modulo p"] == 1
    assert ranks["exact points"] == ranks["sampled"] == RANK_C["paper_3_2"]


@pytest.mark.parametrize("key, value", [("samples", 0), ("precision", 3), ("tol", -1.0),
                                        ("max_points", -1), ("target_error", 2.0),
                                        ("budget", 0.0), ("closed_form_size", 1.5)])
def test_a_bad_policy_is_refused_naming_the_key(key, value):
    with pytest.raises(InputError) as info:
        Policy(**{key: value})
    assert key in str(info.value)


def test_a_policy_and_a_differing_keyword_together_are_refused():
    with pytest.warns(DeprecationWarning, match=r"f: samples= is deprecated"):
        assert policy_of(None, "f", samples=9).samples == 9
    given = Policy(samples=9)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a policy alone is not deprecated
        assert policy_of(given, "f", samples=6) is given  # 6 is the default: not given
        assert policy_of(None, "f", samples=6, exact=True) == Policy()
    with pytest.raises(InputError, match="seed"):
        policy_of(given, "f", seed=3)


class Stop(Exception):
    """Raised right after the deprecation warning: the call goes no further."""


# The public functions that took loose decision keywords, each called with one.
LOOSE = {
    "analyze_constraints": lambda **kw: nhham.analyze_constraints(DISK, **kw),
    "integrability": lambda **kw: nhham.integrability(DISK, **kw),
    "classify_constraints": lambda **kw: nhham.classify_constraints(DISK, **kw),
    "cross_check": lambda **kw: nhham.cross_check(DISK, **kw),
    "dirac_vs_projected": lambda **kw: nhham.dirac_vs_projected(DISK, **kw),
    "classification_at_values": lambda **kw: nhham.classification_at_values(DISK, **kw),
    "parametric_classification": lambda **kw: nhham.parametric_classification(DISK, **kw),
    "lagrangian_geometry": lambda **kw: nhham.lagrangian_geometry(DISK, **kw),
    "hamiltonian_side": lambda **kw: nhham.hamiltonian_side(DISK, **kw),
    "nonholonomic_bracket": lambda **kw: nhham.nonholonomic_bracket(DISK, **kw),
}
DISK = nhham.models.rolling_disk()


@pytest.mark.parametrize("name", sorted(LOOSE))
def test_a_loose_decision_keyword_is_deprecated_naming_the_policy(monkeypatch, name):
    def stop(*args, **kwargs):
        raise Stop

    monkeypatch.setattr(engine, "check_options", stop)  # policy_of's next step
    with pytest.warns(DeprecationWarning) as caught, pytest.raises(Stop):
        LOOSE[name](seed=3, precision=30)
    ours = [w for w in caught if w.category is DeprecationWarning]
    assert [str(w.message) for w in ours] == [
        f"{name}: precision= and seed= are deprecated; pass "
        f"policy=nhham.Policy(precision=30, seed=3) instead"]
    assert ours[0].filename == __file__  # the warning names the caller's line


# ------------------------------------------------------- the quantity protocol
PACKAGE = Path(__file__).resolve().parents[2] / "nhham"
# The members that make a step of its own (``value`` is shared by steps 2 and 3).
OWN = {Reduced: ("reduced",), ProvedModuloP: ("proved_modulo_p",),
       AtExactPoints: ("observe", "pending_error", "conclude"), Sampled: ("sampled",)}


def quantity_classes() -> dict:
    """``{name: class}`` of every class of the package that sets ``what`` in its body and
    has a member of a step of the engine: the quantities :func:`decide` is given."""
    members = {name for names in STEPS.values() for name in names}
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if not isinstance(node, ast.ClassDef):
                continue
            body = {t.id for n in node.body if isinstance(n, ast.Assign)
                    for t in n.targets if isinstance(t, ast.Name)}
            body |= {n.target.id for n in node.body
                     if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)}
            defs = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
            if "what" in body and defs & members:
                module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
                found[node.name] = getattr(importlib.import_module(module), node.name)
    return found


def protocol_problems(cls) -> list:
    """How ``cls`` breaks the engine's quantity protocol (``nhham.lagrangian.engine``)."""
    problems = []
    if not isinstance(getattr(cls, "what", None), str):
        problems.append(f"{cls.__name__}: no what (str)")
    offered = [step for step in STEPS if offers(cls.__new__(cls), step)]
    for step, own in OWN.items():
        present = [n for n in own if getattr(cls, n, None) is not None]
        if present and step not in offered:
            missing = [n for n in STEPS[step] if getattr(cls, n, None) is None]
            problems.append(f"{cls.__name__}: {step.__name__} without {', '.join(missing)}")
    if getattr(cls, "value", None) is not None and not {ProvedModuloP, AtExactPoints} & set(
            offered):
        problems.append(f"{cls.__name__}: value without a step at exact points")
    if not offered:
        problems.append(f"{cls.__name__}: offers no step")
    for step in offered:
        for name in STEPS[step]:
            ours, theirs = inspect.getattr_static(cls, name), getattr(step, name)
            if isinstance(ours, property) or isinstance(theirs, property):
                continue
            have = ", ".join(inspect.signature(ours).parameters)
            need = ", ".join(inspect.signature(theirs).parameters)
            if have.count(",") != need.count(","):
                problems.append(f"{cls.__name__}.{name}: parameters ({have}), the "
                                f"protocol's ({need})")
    return problems


def test_the_quantities_are_found():
    assert {"Vanishing", "Rank", "Tangency", "Frobenius", "BracketRank",
            "DiracDifference"} <= set(quantity_classes())


@pytest.mark.parametrize("name, cls", sorted(quantity_classes().items()))
def test_every_quantity_offers_whole_steps_of_the_protocol(name, cls):
    assert protocol_problems(cls) == []


def test_a_quantity_with_half_a_step_is_reported():
    class Half:
        what = "half"

        def value(self, env, degrees=False):
            return 0

        def observe(self, value):
            return True

        def sampled(self, manifold):  # one parameter short
            return None

    assert protocol_problems(Half) == [
        "Half: AtExactPoints without pending_error, conclude",
        "Half: value without a step at exact points",
        "Half.sampled: parameters (self, manifold), the protocol's (self, manifold, policy)"]
