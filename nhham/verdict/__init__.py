"""The whole-system verdict, above the Hamiltonian layer.

Modules: ``results`` (:class:`Verdict` at one parameter case, :class:`Case`,
:class:`ParametricVerdict`, :class:`ValuesVerdict`), ``values`` (the verdict at the
scene's parameter values: what plain ``nhham classify`` answers), ``parametric`` (the
verdict for every parameter value, ``--parametric``), ``substitution`` (conditions
substituted into a system). The exceptional sets they explore are computed in
:mod:`nhham.lagrangian.exceptional`; the first/second-class split comes from
:mod:`nhham.hamiltonian.classification`.
"""

from nhham.lazy import lazy_exports

_LAZY = {
    "Verdict": "results",
    "Case": "results",
    "ParametricVerdict": "results",
    "ValuesVerdict": "results",
    "parametric_classification": "parametric",
    "classification_at_values": "values",
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
