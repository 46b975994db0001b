"""Long expressions in a terminal: wrapped at the width, elided past a number of lines
(the tables they sit in: test_report.py)."""

import re

from conftest import long_expression
from nhham.cli import layout


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
