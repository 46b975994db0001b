"""The JSON Schema of the command's output (``render/schemas/output.schema.json``).

The envelope every ``nhham COMMAND --json`` prints, and each command's ``result``: what
the journeys' ``to_dict()`` give (:mod:`nhham.journeys`), so that library users and the
command share one documented form.
"""

from __future__ import annotations

import json
from functools import lru_cache
from importlib import resources
from typing import Any

from nhham.settings import json_number

__all__ = ["output_schema", "jsonable"]


@lru_cache(maxsize=1)
def _schema_text() -> str:
    return resources.files("nhham.render").joinpath("schemas/output.schema.json").read_text(
        encoding="utf-8")


def output_schema() -> dict:
    """The JSON Schema (draft 2020-12) of the envelope and of each command's result.

    Returns
    -------
    dict
        A fresh copy (changing it changes nothing here).

    Examples
    --------
    >>> from nhham import output_schema
    >>> schema = output_schema()
    >>> schema["$schema"]
    'https://json-schema.org/draft/2020-12/schema'
    >>> sorted(schema["required"])
    ['command', 'error', 'nhham_version', 'result', 'scene', 'warnings']
    """
    return json.loads(_schema_text())


def jsonable(value: Any) -> Any:
    """Plain JSON data: numpy scalars and arrays, tuples and mappings converted."""
    import numpy as np

    if isinstance(value, dict) or hasattr(value, "items"):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        seq = value.tolist() if isinstance(value, np.ndarray) else value
        return [jsonable(v) for v in seq]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return json_number(value)
    if value is None or isinstance(value, str):
        return value
    return str(value)
