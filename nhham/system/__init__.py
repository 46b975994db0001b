"""What the user describes: the first layer, beneath every other.

Modules: ``naming`` (generated symbol names), ``expressions`` (the safe
parser and its printer), ``numbers`` (which numbers are data: real, within
double precision), ``screening`` (what a System's expressions may contain),
``polynomial`` (structure of expressions in the velocities), ``evaluation``
(the one route from sympy to numbers), ``description`` (:class:`System` and its
validation), ``scene`` (TOML scene files), ``mechanics`` (the
sympy.physics.mechanics adapter), ``models`` (ready-made systems).
"""

from nhham.lazy import lazy_exports

_LAZY = {
    "System": "description",
    "DroppedConstraint": "description",
    "parse_expression": "expressions",
    "to_text": "expressions",
    "load_scene": "scene",
    "loads_scene": "scene",
    "dump_scene": "scene_dump",
    "Scene": "scene",
    "from_mechanics": "mechanics",
    "from_lagranges_method": "mechanics",
    "to_lagranges_method": "mechanics",
    "models": "models",
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
