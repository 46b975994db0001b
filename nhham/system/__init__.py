"""What the user describes: the first layer, beneath every other.

Modules: ``naming`` (generated symbol names), ``expressions`` (the safe
parser and its printer), ``numbers`` (which numbers are data: real, within
double precision), ``screening`` (what a System's expressions may contain),
``polynomial`` (structure of expressions in the velocities), ``evaluation``
(the one route from sympy to numbers), ``description`` (:class:`System` and its
validation; ``sampled_checks`` its checks at seeded points), ``scene`` (TOML scene
files; ``scene_structure`` their keys, types and names), ``mechanics`` (the
sympy.physics.mechanics adapter; ``dynamicsymbols`` and ``loads`` its pieces),
``models`` (ready-made systems).
"""

from nhham.lazy import by_module, lazy_exports

_LAZY = by_module({
    "description": ("System",),
    "sampled_checks": ("DroppedConstraint",),
    "expressions": ("parse_expression", "to_text"),
    "scene": ("load_scene", "loads_scene", "Scene"),
    "scene_dump": ("dump_scene",),
    "mechanics": ("from_mechanics", "from_lagranges_method", "to_lagranges_method"),
    "models": ("models",),
})
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
