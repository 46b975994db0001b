"""The top layer: the ``nhham`` command, its reports and the plots.

Modules: ``main`` (argument parsing, the commands, exit codes), ``report``
(text tables, expression text, progress of long steps), ``plotting``
(figures; needs the ``plot`` extra).
"""

from nhham.cli.main import main

__all__ = ["main"]
