"""``python -m nhham``: the command (see :mod:`nhham.cli`)."""

import sys

from nhham.cli import main

sys.exit(main())
