"""Plain-text rendering (nhham.render.text): tables whose last cell is wrapped without
padding the other rows, matrices listed by entry when they do not fit, and the record of
the steps a command took."""

from conftest import long_expression
from nhham.render.text import Steps, labelled, matrix_table, table


def test_a_long_cell_does_not_pad_the_other_rows():
    """The bicycle's stage table padded every row to a 3,000-character constraint."""
    rows = [("holonomic[0]", long_expression()), ("constraints[0]", "x_dot - y_dot")]
    out = table(rows, total=100)
    lines = out.splitlines()
    assert all(len(line) <= 100 for line in lines)
    assert lines[-1] == "  constraints[0]  x_dot - y_dot"
    assert "more characters" in out


def test_a_matrix_that_does_not_fit_is_listed_by_entry():
    cells = [["m", "0", long_expression(3)], ["0", "m", "c"], [long_expression(3), "c", "I"]]
    out = matrix_table(cells, "W", ["x", "y", "t"], ["x", "y", "t"])
    assert "W[x, t]  =  " in out and "W[t, x]" not in out   # symmetric: upper triangle
    assert "W[x, y]" not in out and "(symmetric" in out     # zeros not listed
    small = matrix_table([["1", "0"], ["0", "2"]], "C", ["1", "2"], ["1", "2"])
    assert small.splitlines() == ["  1  0", "  0  2"]


def test_a_table_aligns_its_columns_under_a_header():
    out = table([("x", "1"), ("theta", "x_dot + 2")], header=("name", "value"), total=80)
    assert out.splitlines() == ["  name   value",
                                "  -----  ---------",
                                "  x      1",
                                "  theta  x_dot + 2"]
    assert table([]) == ""


def test_a_small_matrix_is_a_grid_and_a_label_hangs_its_text(monkeypatch):
    assert matrix_table([["m", "0"], ["0", "I"]], "W", ["x", "y"], ["x", "y"]).splitlines() \
        == ["  m  0", "  0  I"]
    monkeypatch.setenv("COLUMNS", "60")
    text = labelled("lambda_1", long_expression(3))
    lines = text.splitlines()
    assert lines[0].startswith("lambda_1: k0*sin(q0)")
    assert all(line.startswith(" " * 10) for line in lines[1:]) and len(lines) > 1
    assert "".join(line.strip() for line in lines).replace(" ", "") == \
        ("lambda_1:" + long_expression(3)).replace(" ", "")


def test_steps_record_what_was_finished():
    """A step interrupted (the budget ran out) is current while it runs and not recorded."""
    steps = Steps()
    assert steps.decided() == "nothing yet" and steps.current is None
    with steps.step("load the scene"):
        assert steps.current == "load the scene"
    steps.note("C regular (exact)")
    try:
        with steps.step("the constraint algorithm"):
            raise KeyboardInterrupt
    except KeyboardInterrupt:
        pass
    assert steps.current is None
    assert steps.decided() == "load the scene; C regular (exact)"
    rendered = steps.render().splitlines()
    assert rendered[0] == "derived (in order):"
    assert rendered[1].endswith(" ms  load the scene") and rendered[2].strip() == "C regular (exact)"
