"""``simulate``'s options: the common ones, each family's own, checked against the method once.

:class:`RunOptions` holds what every method takes (output, memory, projection, backend,
loop, progress, limits, contacts, controls); :class:`AdaptiveOptions`,
:class:`FixedStepOptions` and :class:`ReferenceOptions` what one family takes
(:data:`~nhham.numerics.methods.FAMILY_OPTIONS`). :func:`split_options` builds them from
``simulate``'s keywords; :func:`check_method_options` is the one place that refuses an
option the method does not take, for the library (keywords: ``step``) and for the command
line (options: ``--step``), with the same words: the :class:`Spelling` says how the
options are written where they came from.

Like :mod:`nhham.numerics.methods`, this module imports neither numpy nor scipy (the
command line checks its options before the numerics are imported).

Examples
--------
>>> from nhham.numerics.simulate_options import split_options
>>> common, own = split_options("rk4", step=0.01, projection=True)
>>> own, common.projection
(FixedStepOptions(step=0.01), True)
>>> split_options("rattle", step=0.01, rtol=1e-6)
Traceback (most recent call last):
...
nhham.errors.InputError: rtol applies to the adaptive methods, not to the fixed-step 'rattle'; \
choose its step instead
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import Any, Callable, Collection, Union

from nhham.errors import InputError
from nhham.numerics.methods import (DEFAULT_METHOD, FAMILIES, FAMILY_OPTIONS, Method,
                                   lookup, names)

__all__ = ["RunOptions", "AdaptiveOptions", "FixedStepOptions", "ReferenceOptions",
           "MethodOptions", "Spelling", "KEYWORDS", "split_options", "check_method_options"]


@dataclass(frozen=True)
class RunOptions:
    """What every method takes (see :func:`~nhham.numerics.integrate.simulate` for each).

    Examples
    --------
    >>> RunOptions(save_every=10).max_points is None
    True
    """

    t_eval: Any = None
    dense_output: bool = False
    events: Any = None
    projection: bool = False
    baumgarte: Any = None
    project_initial: bool = False
    initial_tol: float = 1e-10
    residual_tol: float | None = None
    save_every: int = 1
    max_points: int | None = None
    backend: str = "auto"
    warn: bool = True
    progress: bool = False
    loop: str = "auto"
    time_limit: float | None = None
    contacts: Any = ()
    controls: Any = None
    reduced: Any = None     # method hamiltonized: the scene's HamiltonizedField


@dataclass(frozen=True)
class AdaptiveOptions:
    """The adaptive (scipy) methods': tolerances and step bounds.

    Examples
    --------
    >>> AdaptiveOptions(rtol=1e-6)
    AdaptiveOptions(rtol=1e-06, atol=1e-12, max_step=inf, first_step=None)
    """

    rtol: float = 1e-9
    atol: float = 1e-12
    max_step: float = math.inf
    first_step: float | None = None


@dataclass(frozen=True)
class FixedStepOptions:
    """The fixed-step methods': the step (required).

    Examples
    --------
    >>> FixedStepOptions(0.01).step
    0.01
    """

    step: float


@dataclass(frozen=True)
class ReferenceOptions:
    """The reference's: its digits (``simulate``'s ``reference_digits``).

    Examples
    --------
    >>> ReferenceOptions().digits
    30
    """

    digits: int = 30


MethodOptions = Union[AdaptiveOptions, FixedStepOptions, ReferenceOptions]

#: Each family's options class (in the order of
#: :data:`~nhham.numerics.methods.FAMILIES`), and ``simulate``'s keyword for each field.
_FAMILY = dict(zip(FAMILIES, (
    (AdaptiveOptions, {"rtol": "rtol", "atol": "atol", "max_step": "max_step",
                       "first_step": "first_step"}),
    (FixedStepOptions, {"step": "step"}),
    (ReferenceOptions, {"reference_digits": "digits"}))))
assert {f: tuple(k) for f, (_, k) in _FAMILY.items()} == dict(FAMILY_OPTIONS)
_COMMON = frozenset(f.name for f in fields(RunOptions))
_FAMILY_KEYWORDS = frozenset(k for _, spelled in _FAMILY.values() for k in spelled)

#: Common options that a method may refuse, and when they count as given.
_FLAGS = {"projection": bool, "baumgarte": lambda v: v is not None,
          "t_eval": lambda v: v is not None, "dense_output": bool,
          "events": lambda v: v is not None}


@dataclass(frozen=True)
class Spelling:
    """How options are written where they came from: ``key`` an option's name,
    ``assign`` an option with a value, ``method`` a method's name; ``error`` the exception
    raised.

    Examples
    --------
    >>> KEYWORDS.assign("step", "0.01"), KEYWORDS.method("rk4")
    ('step=0.01', "'rk4'")
    """

    key: Callable[[str], str]
    assign: Callable[[str, str], str]
    method: Callable[[str], str]
    error: type = InputError


#: ``simulate``'s keywords (``step=0.01``).
KEYWORDS = Spelling(key=str, assign=lambda k, v: f"{k}={v}", method=repr)


def split_options(method=DEFAULT_METHOD, options: RunOptions | None = None,
                  method_options: MethodOptions | None = None,
                  **keywords) -> tuple[RunOptions, MethodOptions]:
    """``simulate``'s keywords as (common options, the method family's options), checked
    against the method (:func:`check_method_options`).

    A keyword overrides the same field of ``options``/``method_options``; a family
    keyword counts as given when it is not None.

    Raises
    ------
    TypeError
        For a keyword ``simulate`` does not have.
    InputError
        An unknown method, or an option it does not take (see
        :func:`check_method_options`).

    Examples
    --------
    >>> split_options("reference", reference_digits=40)[1]
    ReferenceOptions(digits=40)
    """
    spec = lookup(method)
    family = {k: v for k, v in keywords.items() if k not in _COMMON}
    for key in family:
        if key not in _FAMILY_KEYWORDS:
            raise TypeError(f"simulate() got an unexpected keyword argument {key!r}")
    mine = {k: v for k, v in keywords.items() if k in _COMMON}
    # (simulate runs this at every call: no copy of options when nothing replaces a field)
    common = (RunOptions(**mine) if options is None else
              replace(options, **mine) if mine else options)
    given = {k for k, v in family.items() if v is not None}
    given |= {k for k, counts in _FLAGS.items() if counts(getattr(common, k))}
    cls, spelled = _FAMILY[spec.family]
    if method_options is not None and not isinstance(method_options, cls):
        raise InputError(f"method_options: {type(method_options).__name__} is not for "
                         f"{spec.family} methods such as {spec.name!r} (use {cls.__name__})",
                         key="method_options")
    if method_options is not None:
        given |= {k for k, name in spelled.items()
                  if getattr(method_options, name) != getattr(cls, name, None)}
    check_method_options(spec, given)
    own = {name: family[k] for k, name in spelled.items() if family.get(k) is not None}
    if method_options is not None:
        return common, replace(method_options, **own)
    return common, cls(**own)


def check_method_options(method: Method | str, given: Collection[str],
                         available: Collection[str] | None = None,
                         spelling: Spelling = KEYWORDS) -> None:
    """Refuse what ``method`` does not take: the one place where options meet the method.

    Parameters
    ----------
    method : Method or str
    given : collection of str
        The options the user gave (``simulate``'s keyword names; the common flags
        ``projection``, ``baumgarte``, ``t_eval``, ``dense_output``, ``events`` when set).
    available : collection of str, optional
        The options that have a value, given or defaulted elsewhere (a scene's table);
        default ``given``. A fixed-step method needs ``step`` among them.
    spelling : Spelling
        How the options are named in the messages, and the exception raised.

    Raises
    ------
    InputError (or ``spelling.error``)
        Naming the option (``key``) in the way the user wrote it.

    Examples
    --------
    >>> check_method_options("DOP853", {"rtol", "projection"})
    >>> check_method_options("reference", {"projection"})
    Traceback (most recent call last):
    ...
    nhham.errors.InputError: projection: not applicable to 'reference', which keeps the \
constraints itself; use it without projection
    """
    spec = lookup(method)
    given = set(given)
    available = given if available is None else set(available) | given
    sp, name = spelling, spelling.method(spec.name)

    def refuse(key, text):
        raise sp.error(text, key=sp.key(key))

    if spec.fixed_step and "step" not in available:
        refuse("step", f"{sp.assign('method', name)} is a fixed-step method and needs "
                       f"{sp.assign('step', 'DT')} (e.g. {sp.assign('step', '0.01')})")
    if "step" in given and not spec.fixed_step:
        fixed = ", ".join(names(lambda m: m.fixed_step))
        bound = (f"; use {sp.key('max_step')} to bound its steps"
                 if "max_step" in spec.options else "")
        refuse("step", f"{sp.key('step')} applies to the fixed-step methods ({fixed}), not "
                       f"to {name}{bound}")
    for key in _FAMILY[FAMILIES[0]][1]:   # the adaptive family's
        if key in given and not spec.adaptive:
            # The reference integrates to its own digits: tolerances would be ignored.
            why = (f"the fixed-step {name}; choose its {sp.key('step')} instead"
                   if spec.fixed_step else
                   f"{name}, which integrates to {ReferenceOptions().digits} digits")
            refuse(key, f"{sp.key(key)} applies to the adaptive methods, not to {why}")
    if "reference_digits" in given and not spec.reference:
        refuse("reference_digits", f"{sp.key('reference_digits')} applies to the reference "
                                   f"method, not to {name}")
    for key in ("projection", "baumgarte"):
        if key in given and not spec.takes_projection:
            refuse(key, f"{sp.key(key)}: not applicable to {name}, which keeps the "
                        f"constraints itself; use it without {sp.key(key)}")
    if "t_eval" in given and not spec.takes_t_eval:
        refuse("t_eval", f"{sp.key('t_eval')}: the fixed-step method {name} keeps its grid "
                         f"points (every save_every-th step); t_eval is for the adaptive "
                         f"methods")
    for key in ("dense_output", "events"):
        if key in given and not spec.scipy_loop:
            scipy = ", ".join(names(lambda m: m.scipy_loop, cheapest_first=True))
            refuse(key, f"{sp.key('dense_output')}/{sp.key('events')}: only with the scipy "
                        f"methods ({scipy}), not {name}")
