"""Every public function and class of ``nhham`` (``nhham.__all__``) carries an
``Examples`` section, and its examples run and print what they say (doctest, on the
object's own docstring: methods are not collected).

The examples start from a fresh namespace (each imports what it uses), so that they
can be pasted as they stand; an exception's example raises it. A module exported as a
name (``nhham.models``) is left out.
"""

import doctest
import importlib
import inspect
import re

import pytest

import nhham

_FLAGS = doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS
_SECTION = re.compile(r"^Examples\n-{8,}\n", re.M)


def _documented(name):
    """The object ``nhham.<name>`` when it needs an Examples section, else None."""
    obj = getattr(nhham, name)
    if not (inspect.isfunction(obj) or inspect.isclass(obj)):
        return None
    return obj


@pytest.mark.parametrize("name", nhham.__all__)
def test_public_name_has_running_examples(name):
    obj = _documented(name)
    if obj is None:
        pytest.skip(f"{name} is a module")
    assert _SECTION.search(inspect.getdoc(obj) or ""), f"{name}: no Examples section"
    finder = doctest.DocTestFinder(recurse=False)
    module = importlib.import_module(obj.__module__)
    tests = [t for t in finder.find(obj, name, module=module, globs={}) if t.examples]
    assert tests, f"{name}: the Examples section has no example"
    runner = doctest.DocTestRunner(optionflags=_FLAGS)
    report = []
    for test in tests:
        runner.run(test, out=report.append)
    assert runner.failures == 0, "".join(report)


def test_a_missing_or_failing_example_is_caught():
    """The checks above fail on a docstring without the section and on a wrong output."""
    def bare():
        """Nothing to show."""

    def wrong():
        """Two.

        Examples
        --------
        >>> 1 + 1
        3
        """

    assert not _SECTION.search(inspect.getdoc(bare))
    runner = doctest.DocTestRunner(optionflags=_FLAGS)
    for test in doctest.DocTestFinder(recurse=False).find(wrong, "wrong", globs={}):
        runner.run(test, out=lambda _: None)
    assert runner.failures == 1
