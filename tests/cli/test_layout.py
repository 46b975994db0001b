"""Long expressions in a terminal: wrapped at the width, elided past a number of lines
(the tables they sit in: test_report.py)."""

import re

from conftest import long_expression
from nhham.render import layout


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


# A product without spaces (sympy prints none around * and /): names and numbers of
# several characters, calls and powers.
PRODUCT = ("d*mc*theta_dot**2*cos(theta)*sin(phi)*x_dot*y_dot*Ic*Iw*phiL_dot*phiR_dot*"
           "cos(phi)*sin(theta)*2.5e-10*x_dot**2*(mc/2 + mw)*1.25e+3*omega_12")


def _tokens(text):
    """Names and numbers, by hand (a regular expression independent of the layout's)."""
    return re.findall(r"[0-9.]+e[+-]\d+|[0-9.]+|[A-Za-z_][A-Za-z_0-9]*", text)


def test_a_line_breaks_between_tokens_never_inside_a_name_or_a_number():
    for room in range(30, 90, 3):
        lines = layout.wrap(PRODUCT, room, max_lines=100)
        assert all(len(line) <= room for line in lines), (room, lines)
        # every line is made of whole names and numbers: the tokens of the lines are
        # those of the text, in order
        assert [t for line in lines for t in _tokens(line)] == _tokens(PRODUCT), (room, lines)
        # calls and powers stay whole: no line ends in a name that a '(' continues,
        # nor starts or ends inside '**'
        for a, b in zip(lines, lines[1:]):
            assert not (re.search(r"\w$", a) and b.startswith("(")), (a, b)
            assert not a.endswith("**") and not b.startswith("**"), (a, b)


def test_a_name_longer_than_the_line_is_kept_whole():
    assert layout.wrap("a" * 80, 30) == ["a" * 80]
    assert layout.wrap("x*" + "b" * 40 + "*y", 30) == ["x*", "b" * 40, "*y"]


def test_report_headings_and_the_final_state_keep_the_width(monkeypatch, capsys):
    """At COLUMNS=80 the headings of classify and linearize and simulate's final state
    wrap (the roller racer's: 95, 128 and 196 characters on one line), every value next to
    its name; only the one-line warnings on stderr may be longer."""
    from nhham.__main__ import run

    monkeypatch.setenv("COLUMNS", "80")
    scene = "examples/roller_racer.toml"
    for argv in (["classify", scene], ["linearize", scene],
                 ["simulate", scene, "--t-end", "0.5"]):
        assert run(argv) == 0
        out = capsys.readouterr().out
        assert max(map(len, out.splitlines())) <= 80, argv
    state = out[out.index("final state:"):]
    names = re.findall(r"(\w+) = [-\d.e+]+", state)
    assert names == ["x", "y", "theta", "phi", "x_dot", "y_dot", "theta_dot", "phi_dot"]
