"""The cross-check's results: one check (CheckResult), the report (CrossCheckReport)
with its text and JSON, and the stage summaries both sides are compared by."""

import json
from types import SimpleNamespace

from nhham import models
from nhham.hamiltonian.checks import CheckResult, CrossCheckReport, stage_summaries
from nhham.hamiltonian.crosscheck import cross_check


def test_exact_report_values_and_json():
    report = cross_check(models.two_particle_rod())
    assert report.method == "exact" and report.exact and report.agree
    assert report.tolerance == 1e-9 and report.precision == "float64"
    d = json.loads(json.dumps(report.to_dict()))
    for key in ("agree", "exact", "max_abs_difference", "samples", "tolerance"):
        assert key in d
    assert d["checks"]["field"]["agree"]
    assert "cancels" in report.detail["Poisson map"].detail
    assert "Leg_* xi_L = X_H o Leg" in report.detail["field"].detail


def _report(*checks, skipped=0):
    return CrossCheckReport(
        agree=all(c.agree for c in checks), exact=all(c.exact for c in checks),
        max_abs_difference=max(c.max_abs_difference for c in checks),
        max_rel_difference=max(c.max_rel_difference for c in checks), samples=4,
        tolerance=1e-9, precision="float64", method="sampled", checks=checks,
        lagrangian_stages=({"index": 1},), hamiltonian_stages=({"index": 1},),
        statuses=("determined", "determined"), seconds=0.5, skipped_points=skipped)


def test_how_a_check_was_decided():
    """``how`` is the method given, else "exact" or "sampled" from ``exact``."""
    assert CheckResult("field", True, True).how == "exact"
    assert CheckResult("field", True, False).how == "sampled"
    assert CheckResult("field", True, False, method="points").how == "points"
    assert CheckResult("field", True, False, 1e-3, 1e-4, 3, "d").to_dict() == {
        "agree": True, "exact": False, "max_abs_difference": 1e-3, "max_rel_difference": 1e-4,
        "samples": 3, "detail": "d", "method": "sampled"}


def test_report_text_and_json_of_a_disagreement():
    field = CheckResult("field", False, False, 2e-6, 1e-7, 4, "differs at 4 points")
    form = CheckResult("symplectic form", True, True, detail="cancels")
    report = _report(field, form, skipped=1)
    assert report.detail == {"field": field, "symplectic form": form}
    assert report.describe().splitlines() == [
        "cross-check (sampled, float64): DISAGREE; max |difference| 2e-06 (relative 1e-07) "
        "at 4 seeded points of M_f, tolerance 1e-09 (1 non-generic point(s) skipped)",
        "  field: DIFFERS (sampled): differs at 4 points",
        "  symplectic form: agrees (exact): cancels"]
    d = json.loads(json.dumps(report.to_dict()))
    assert d["agree"] is False and d["checks"]["symplectic form"]["method"] == "exact"
    assert d["statuses"] == ["determined", "determined"] and d["skipped_points"] == 1
    agreeing = _report(form)
    assert "AGREE exactly;" in agreeing.describe() and "skipped" not in agreeing.describe()


def test_stage_summaries():
    stages = [SimpleNamespace(index=1, constraints=("a", "b"), rank=0, augmented_rank=1,
                              labels=("constraints[0]", "holonomic[0]")),
              SimpleNamespace(index=2, constraints=("a", "b", "c"), rank=1, augmented_rank=1,
                              labels=("constraints[0]", "holonomic[0]", "secondary[0]"))]
    assert stage_summaries(stages) == (
        {"index": 1, "constraints": 2, "rank": 0, "augmented_rank": 1,
         "labels": ["constraints[0]", "holonomic[0]"]},
        {"index": 2, "constraints": 3, "rank": 1, "augmented_rank": 1,
         "labels": ["constraints[0]", "holonomic[0]", "secondary[0]"]})
