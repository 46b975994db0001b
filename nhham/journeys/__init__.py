"""What a user does with a scene, one function each: the layer the command and the
studies share.

Each journey takes a scene (a :class:`~nhham.system.scene.Scene`, a scene file's path or
a :class:`~nhham.System`) and its options, and returns an
:class:`~nhham.journeys.answer.Answer`: the JSON-ready result ``nhham COMMAND --json``
prints (:meth:`~nhham.journeys.answer.Answer.to_dict`), its text, its warnings and the
library objects it came from. The command is parse -> journey -> render
(:mod:`nhham.cli`); a study (:mod:`nhham.study`) evaluates its points with the same
journey functions, so that a point of a study is what the command gives there.

========================  =========================================================
:func:`classify`          the verdict at the scene's values, with the classes on T*Q
:func:`classify_parametric`  the verdict for every value of the parameters
:func:`derive`            the constrained dynamics (closed or implicit form)
:func:`compare`           the Lagrangian/Hamiltonian cross-check
:func:`linearize`         the stability of the ``[steady]`` motion, and sweeps
:func:`simulate`          a run from ``[initial]``, with the ``[control]`` laws
:func:`bench`             the work-precision study of the integrators
:func:`reduce`            the Chaplygin reduction to the shape space
:func:`hamiltonize`       Chaplygin's multiplier (Hamiltonian after a change of time?)
========================  =========================================================
"""

from nhham.lazy import by_module, lazy_exports

_LAZY = by_module({
    "answer": ("Answer",),
    "verdict": ("classify", "classify_parametric"),
    "derivation": ("derive",),
    "comparison": ("compare",),
    "stability": ("linearize",),
    "simulation": ("simulate",),
    "benchmark": ("bench",),
    "reduction": ("reduce", "hamiltonize"),
})

__all__ = list(_LAZY)

__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
