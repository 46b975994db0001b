"""The one status vocabulary: the enum, its messages, the C codes made from it, the
failure exception, and every result's ``status`` a member of it."""

from __future__ import annotations

import re

import numpy as np
import pytest

import nhham
from nhham.errors import ComputationError, NhhamError
from nhham.numerics.codegen import c_compiler, numeric_model
from nhham.numerics.codegen.emit import RUNTIME_FILES, runtime_source
from nhham.numerics.integrate import simulate
from nhham.numerics.integrators import rattle, rk4
from nhham.numerics.reference import reference_solution
from nhham.numerics.status import NumericalFailure, Status, c_defines

from test_exact_solutions import chaplygin_sleigh, sleigh_state


def test_members_codes_and_messages():
    # the public codes documented for SimulationResult.status (scipy's 0 / 1 / -1 kept)
    assert [int(s) for s in (Status.SUCCESS, Status.EVENT, Status.STEP_FAILED, Status.NONFINITE,
                             Status.SINGULAR, Status.NOT_CONVERGED)] == [0, 1, -1, -2, -3, -4]
    assert all(s.message for s in Status) and len({s.message for s in Status}) == len(Status)
    assert Status(-3) is Status.SINGULAR and Status.SUCCESS == 0


def test_one_failure_exception_rooted_at_nhham_error():
    exc = NumericalFailure(-3)
    assert isinstance(exc, ComputationError) and isinstance(exc, NhhamError)
    assert exc.status is Status.SINGULAR and str(exc) == Status.SINGULAR.message
    assert str(NumericalFailure(Status.NONFINITE, "at t = 1")) == "at t = 1"


def test_c_codes_are_generated_from_the_enum():
    defines = dict(re.findall(r"#define (NHHAM_\w+) \((-?\d+)\)", c_defines()))
    assert defines == {f"NHHAM_{s.name}": str(int(s)) for s in Status}
    model = numeric_model(chaplygin_sleigh(), backend="numpy")
    assert c_defines() in model.c_source
    # the runtime returns only named codes: no bare negative status is left in the files
    for name in RUNTIME_FILES:
        text = runtime_source(name)
        assert not re.search(r"return -\d", text), name
    assert all("NHHAM_" in runtime_source(name) for name in ("rhs.c", "rattle.c", "erk.c"))


def test_failures_carry_the_status():
    """A constraint one-form that vanishes at the origin: C is singular there."""
    system = nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2", ["x*x_dot + y*y_dot"])
    for backend in (["numpy", "c"] if c_compiler() else ["numpy"]):
        model = numeric_model(system, backend=backend)
        assert model.evaluate(np.zeros(4))[3] is Status.SINGULAR
        with pytest.raises(NumericalFailure) as info:
            model.rhs(0.0, np.zeros(4))
        assert info.value.status is Status.SINGULAR
        res = simulate(model, (0, 1), np.zeros(4), method="RK45", warn=False)
        assert res.status is Status.SINGULAR and not res.success


def test_every_result_status_is_a_member():
    model = numeric_model(chaplygin_sleigh())
    y0 = sleigh_state()
    runs = [rattle(model, y0, 0.0, 0.5, 0.05), rk4(model, y0, 0.0, 0.5, 0.05),
            reference_solution(model, y0, (0.0, 0.2), digits=20)]
    runs += [simulate(model, (0, 0.5), y0, method=m, warn=False, **kw)
             for m, kw in (("DOP853", {}), ("Radau", {}), ("rattle", {"step": 0.05}))]
    for run in runs:
        assert type(run.status) is Status and run.status == 0
        assert run.y.shape[0] == 6 and run.y.shape[1] == len(run.t)  # (2n, K), as scipy
