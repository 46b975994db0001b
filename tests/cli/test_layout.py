"""Long expressions in a terminal: wrapped at the width, elided past a number of lines,
never padding the other rows of their table."""

import re

from nhham.cli import layout
from nhham.cli.report import matrix_table, table
from nhham.cli.results import classify_text


def long_expression(terms=300):
    return " + ".join(f"k{i}*sin(q{i % 7})*(a + b*cos(q{i % 5}))" for i in range(terms))


def test_wrap_keeps_every_character_and_the_width():
    text = long_expression(12)
    lines = layout.wrap(text, 60, max_lines=100)
    assert all(len(line) <= 60 for line in lines)
    assert "".join(lines).replace(" ", "") == text.replace(" ", "")
    # breaks before a binary operator, never right after one
    assert not any(line.endswith((" +", " -")) for line in lines)


def test_elided_with_a_pointer_and_the_count():
    text = long_expression()
    lines = layout.wrap(text, 80, max_lines=5)
    assert len(lines) == 5
    shown = sum(len(line) for line in lines[:4])
    match = re.search(r"\.\.\. \[([\d,]+) more characters: the whole expression is in --json "
                      r"and --latex\]", lines[-1])
    assert match, lines[-1]
    left = int(match.group(1).replace(",", ""))
    # what is counted as left out is what was not shown (up to the spaces at the breaks)
    assert 0 <= len(text) - shown - left <= len(lines)
    assert layout.wrap("short", 80) == ["short"]


def test_width_from_columns(monkeypatch):
    monkeypatch.setenv("COLUMNS", "132")
    assert layout.width() == 132
    monkeypatch.setenv("COLUMNS", "20")
    assert layout.width() == 60                  # never narrower than 60


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


def test_classify_text_lists_each_constraint_once():
    data = {"n": 8, "m": 5, "regular": True, "rank_c": 5, "rank_c_method": "sampled",
            "status": "determined", "free_multipliers": 0, "free_multiplier_symbols": [],
            "redundant": [], "integrable": False, "first_class": 0, "second_class": 6,
            "stages": [{"index": 1, "labels": ["holonomic[0]", "constraints[0]"],
                        "constraints": [long_expression(), "x_dot"], "rank": 5}],
            "final_labels": ["holonomic[0]", "constraints[0]"],
            "final_constraints": [long_expression(), "x_dot"],
            "first_class_combinations": [], "first_class_coefficients": None,
            "inconsistency": None}
    out = classify_text("bicycle", data)
    assert out.count("k0*sin(q0)") == 1
    assert "  M_1  rank 5  holonomic[0], constraints[0]" in out
    assert max(len(line) for line in out.splitlines()) <= layout.width()
