"""Published problems: nonholonomic benchmarks with their sources and reference values.

Each problem (``catalog.toml``) is a scene of the package (``scenes/``, the examples'
own), the source (authors, title, venue, where in it, and what the reference was checked
against) and the quantities the source prints, each with its published value and
precision and the measure that computes nhham's value (:data:`MEASURES`).
:func:`run` computes them: ``nhham problems`` prints the table (docs/problems.md).

Examples
--------
>>> from nhham.problems import problems
>>> len(problems()) >= 15
True
"""

from nhham.problems.catalog import Problem, Quantity, problem, problems
from nhham.problems.measures import MEASURES
from nhham.problems.runner import ProblemRow, ProblemsReport, run

__all__ = ["Problem", "Quantity", "problem", "problems", "MEASURES", "ProblemRow",
           "ProblemsReport", "run"]
