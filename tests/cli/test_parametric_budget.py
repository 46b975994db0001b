"""``classify --parametric`` within its budget (issue 43, item 8): the generic verdict
always comes; a search for cases cut by the budget leaves the cases found, says which
search was cut and why, and exits 0 with a warning; 3 only when not even the generic
verdict came.

The expiry is planted where the timer would deliver it (a run of the classification, a
lower-dimensional search): no timing in the assertions.

The scene is examples/parametric_null_constraint.toml (L = (a q1'^2 + q2'^2 - q3'^2)/2,
phi = q2' + b q3', a = b = 1). By hand: W = diag(a, 1, -1), mu = (0, 1, b), so
C = -mu W^-1 mu^T = -(1 - b^2): for generic a, b C is regular (rank 1), lambda is
determined and M_1 has one stage; on T*Q phi^H = p_q2 - b p_q3 brackets to 0 with
itself: 1 first class, 0 second class. Its exceptional sets are a = 0 (det W = a) and
b - 1 = 0, b + 1 = 0 (C = 0).
"""

from __future__ import annotations

import json
import time

import jsonschema

import nhham
from nhham.errors import BudgetExceeded
from tests.cli.conftest import EXAMPLES
from tests.cli.conftest import run_fresh as run

SCENE = str(EXAMPLES / "parametric_null_constraint.toml")


def expire_at_call(monkeypatch, module, name, call):
    """``module.name`` raises the budget's expiry at its ``call``-th call (1-based)."""
    real = getattr(module, name)
    calls = []

    def planted(*args, **kwargs):
        calls.append(1)
        if len(calls) == call:
            raise BudgetExceeded("the budget of 600 s ran out")
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, planted)


def test_a_search_cut_keeps_the_generic_verdict_and_exits_0(monkeypatch, schema):
    """The expiry in the first case's run (the second classification): before, exit 3
    and no verdict at all."""
    from nhham.verdict import parametric

    expire_at_call(monkeypatch, parametric, "classified", 2)
    rc, out, err = run("classify", SCENE, "--parametric", "--json")
    assert rc == 0
    env = json.loads(out)
    jsonschema.validate(env, schema)
    r = env["result"]
    g = r["generic"]
    assert (g["regular"], g["rank_c"], g["status"], len(g["stages"]), g["first_class"],
            g["second_class"]) == (True, 1, "determined", 1, 1, 0)
    search = r["search"]
    assert search["complete"] is False and search["allowed_s"] > 0
    (cut,) = search["cut"]
    assert cut["search"].startswith("run b - 1 = 0")  # the run that was cut
    assert "kept for the report" in cut["why"]
    # a = 0 needs no run (W singular: invalid); b - 1 = 0 was cut; b + 1 = 0 never began
    assert [c["conditions"] for c in r["cases"]] == [["a"]]
    assert r["cases"][0]["verdict"]["status"] == "invalid"
    assert sorted(search["pending"]) == [["b + 1"], ["b - 1"]]
    (warning,) = [w for w in env["warnings"] if "search for exceptional cases" in w]
    assert "during 'run b - 1 = 0" in warning and "--budget" in warning
    assert "2 exceptional sets found but not examined" in warning


def test_the_text_lists_what_was_not_examined(monkeypatch):
    from nhham.verdict import parametric

    expire_at_call(monkeypatch, parametric, "classified", 2)
    rc, out, err = run("classify", SCENE, "--parametric")
    assert rc == 0
    assert "generic (where no case below holds):" in out
    assert "search cut: run b - 1 = 0" in out
    assert "  not examined: b + 1 = 0" in out and "  not examined: b - 1 = 0" in out
    assert "warning: the search for exceptional cases was cut" in err


def test_an_expiry_before_the_generic_verdict_exits_3(monkeypatch):
    from nhham.verdict import parametric

    expire_at_call(monkeypatch, parametric, "classified", 1)
    rc, out, err = run("classify", SCENE, "--parametric", "--json")
    assert rc == 3
    env = json.loads(out)
    assert env["result"] is None and env["error"]["kind"] == "budget"


def test_a_case_whose_run_fails_leaves_the_others(monkeypatch, schema):
    """The roller racer met a RecursionError in the run of one case (I1 = -d1^2 m2,
    I2 = d2^2 m2) and the command ended with an internal error, after minutes, without
    the generic verdict. Planted here in the run of b - 1 = 0: the case b + 1 = 0 is
    still examined (by hand C = 0 and xi_L(phi) = 0 there: underdetermined, 1 free
    multiplier), and the failure is named."""
    from nhham.verdict import parametric

    real, calls = parametric.classified, []

    def planted(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise RecursionError("maximum recursion depth exceeded during compilation")
        return real(*args, **kwargs)

    monkeypatch.setattr(parametric, "classified", planted)
    rc, out, err = run("classify", SCENE, "--parametric", "--json")
    assert rc == 0
    env = json.loads(out)
    jsonschema.validate(env, schema)
    r = env["result"]
    assert r["generic"]["status"] == "determined"
    assert [c["conditions"] for c in r["cases"]] == [["a"], ["b + 1"]]
    v = r["cases"][1]["verdict"]
    assert (v["status"], v["free_multipliers"]) == ("underdetermined", 1)
    assert r["search"]["complete"] is False and r["search"]["cut"] == []
    assert r["search"]["failed"] == [{"search": "run b - 1 = 0",
                                      "why": "RecursionError: maximum recursion depth "
                                             "exceeded during compilation"}]
    assert any("failed in 'run b - 1 = 0' (RecursionError" in w for w in env["warnings"])


def test_a_lower_dimensional_search_cut_by_its_share_leaves_the_others(monkeypatch):
    """mu = (0, 1, b): its maximal minors 1 and b have no common zero, a search of
    codimension > 1 (a Groebner basis, [1]) that finds nothing. Cut by its share, it is
    named; the cases of codimension 1 (a, b - 1, b + 1) are all there."""
    from nhham.lagrangian.components import LowerDimensional

    def planted(self):
        raise BudgetExceeded("the budget of 1 s ran out")

    monkeypatch.setattr(LowerDimensional, "solve", planted)
    system = nhham.load_scene(SCENE).system
    with nhham.time_budget(600):
        pv = nhham.parametric_classification(system)
    assert sorted(str(c.conditions[0]) for c in pv.cases) == ["a", "b + 1", "b - 1"]
    assert not pv.search.complete and not pv.search.pending
    (what, why), = pv.search.cut
    assert "the constraint one-forms become dependent" in what
    assert "(codimension > 1): 2 polynomials" in what and why.startswith("its share")


def test_without_a_budget_the_search_is_not_bounded():
    system = nhham.load_scene(SCENE).system
    pv = nhham.parametric_classification(system)
    assert pv.search.complete and pv.search.allowed is None and not pv.warnings


def test_a_part_is_shown_on_a_terminal_only_once_it_has_run_long_enough(capsys):
    """progress.part(after=...): a quick part leaves no line, a long one is announced
    (with the note as it is then); both are named for a budget and recorded."""
    from nhham.progress import part, reporting
    from nhham.render.text import Steps

    steps = Steps(progress=True)
    with reporting(steps), steps.step("verdicts"):
        with part("quick", after=1000.0):
            assert steps.where() == "verdicts: quick"
        with part("long", lambda: "an estimate", after=0.01):
            time.sleep(0.5)
    err = capsys.readouterr().err
    assert err == "nhham: verdicts ...\nnhham:   long (an estimate)\n"
    assert [w for w, _ in steps.records] == ["verdicts", "  quick", "  long"]

