"""Eigenvalues of state matrices and what counts as 0: the one home of the stability
verdict, for one linearisation and for a batch (``DESIGN.md`` §2, "Relative equilibria").

A computed eigenvalue is the exact eigenvalue of A + E with |E| of the order of
eps |A| (LAPACK's QR algorithm is backward stable), so it is known to about
eps |A| kappa_i, kappa_i = |y_i| |x_i| / |y_i^H x_i| its condition number (x_i, y_i
the right and left eigenvectors). That is rounding for a simple eigenvalue, but a
cluster of p eigenvalues that almost coincide (a pair ±sigma meeting at 0, an upright
hoop at its critical spin beside the zero of its neighbouring circles) is perturbed by
up to (eps |A|)^(1/p) |A|^(1 - 1/p): at the hoop's critical spin LAPACK returns
5e-6 +- 9e-6 i and -1e-5 for 0, 0, 0. So each eigenvalue has its own *margin*: the
verdict's tolerance ``1e-9 max(1, max |A|)``, or where larger its error estimate
``8 eps |A|_F kappa_i``, at most :data:`MARGIN_CAP` |A|_F (a triple cluster's error). A real
part within the margin counts as 0: the eigenvalue is on the imaginary axis to the
precision of the numbers, neither stable nor unstable.

:func:`spectra` gives the sorted eigenvalues, their margins, the tolerances and the
verdicts of N matrices at once; :func:`unstable_counts` is the number of eigenvalues with
Re above their margin, which is what a crossing of the imaginary axis changes
(:mod:`nhham.numerics.crossings` counts with it). No sympy.
"""

from __future__ import annotations

import numpy as np

__all__ = ["EIGENVALUE_TOLERANCE", "MARGIN_CAP", "spectra", "unstable_counts", "verdicts",
           "sort_eigenvalues", "VERDICT_TEXT"]

#: |Re lambda| <= this * max(1, max |A|) counts as zero in a stability verdict.
EIGENVALUE_TOLERANCE = 1e-9

#: The largest margin, relative to |A|_F: the perturbation of a triple defective
#: eigenvalue by rounding, eps^(1/3) (a larger cluster at the axis is not resolved).
MARGIN_CAP = float(np.finfo(float).eps) ** (1.0 / 3.0)

#: The verdict codes (a study's ``verdict`` variable) and their meaning.
VERDICT_TEXT = {1: "asymptotically stable: every eigenvalue has Re < 0",
                0: "unstable: an eigenvalue has Re > 0",
                -1: "not decided by the linearisation (an eigenvalue on the imaginary axis "
                    "to the precision, no eigenvalue left, or no linearisation)"}

_EPS = float(np.finfo(float).eps)


def sort_eigenvalues(ev, *others):
    """``ev`` (..., d) sorted by decreasing real part (rounded to 12 digits), then
    decreasing imaginary part; ``others`` (arrays of the same shape) in the same order."""
    ev = np.asarray(ev, dtype=complex)
    order = np.lexsort((-ev.imag, -np.round(ev.real, 12)), axis=-1)
    out = [np.take_along_axis(ev, order, axis=-1)]
    out += [np.take_along_axis(np.asarray(o), order, axis=-1) for o in others]
    return out[0] if not others else tuple(out)


def spectra(A, tolerance=None) -> tuple:
    """Eigenvalues, margins, tolerances and verdicts of N state matrices.

    Parameters
    ----------
    A : array_like, shape (N, d, d)
        Finite real matrices.
    tolerance : array_like, shape (N,), optional
        The verdict's tolerance of each; default ``1e-9 max(1, max |A|)``.

    Returns
    -------
    eigenvalues : ndarray of complex, shape (N, d)
        Sorted (:func:`sort_eigenvalues`).
    margins : ndarray, shape (N, d)
        A real part at or below this (in absolute value) counts as 0 (module docstring).
    tolerances : ndarray, shape (N,)
    verdicts : ndarray of int8, shape (N,)
        :data:`VERDICT_TEXT`'s codes.

    Examples
    --------
    A centre, a stable focus, and a Jordan block at 0 whose rounding LAPACK returns as
    +-1e-8 (inside its margin: not "unstable"):

    >>> import numpy as np
    >>> from nhham.numerics.spectra import spectra
    >>> A = np.array([[[0.0, 1.0], [-1.0, 0.0]], [[-1.0, 1.0], [-1.0, -1.0]],
    ...               [[0.0, 1.0], [1e-16, 0.0]]])
    >>> ev, margins, tol, verdict = spectra(A)
    >>> verdict.tolist()
    [-1, 1, -1]
    >>> bool(margins[2].min() > 1e-8)
    True
    """
    A = np.asarray(A, dtype=float)
    N, d = A.shape[0], A.shape[-1]
    tol = (EIGENVALUE_TOLERANCE * np.maximum(1.0, np.abs(A).max(axis=(1, 2), initial=0.0))
           if tolerance is None else np.broadcast_to(np.asarray(tolerance, dtype=float), (N,)))
    if not d:
        return (np.zeros((N, 0), dtype=complex), np.zeros((N, 0)), tol,
                np.full(N, -1, dtype=np.int8))
    ev, V = np.linalg.eig(A)
    margins = np.maximum(tol[:, None], _errors(A, V))
    ev, margins = sort_eigenvalues(ev, margins)
    return ev, margins, tol, verdicts(ev, margins)


def _errors(A, V):
    """8 eps |A|_F kappa_i, at most MARGIN_CAP |A|_F, for the eigenvectors V (columns of
    unit length): kappa_i = |row i of V^-1| (inf where V is singular)."""
    norm = np.sqrt(np.sum(np.abs(A) ** 2, axis=(1, 2)))[:, None]
    kappa = np.full(V.shape[:2], np.inf)
    with np.errstate(all="ignore"):
        for i in range(V.shape[0]):
            try:
                kappa[i] = np.linalg.norm(np.linalg.inv(V[i]), axis=1)
            except np.linalg.LinAlgError:
                pass
        kappa = np.where(np.isfinite(kappa), kappa, np.inf)
        return np.minimum(8.0 * _EPS * norm * kappa, MARGIN_CAP * norm)


def unstable_counts(eigenvalues, margins) -> np.ndarray:
    """How many eigenvalues have a real part above their margin, shape (...,) over the
    leading dimensions (-1 where an eigenvalue is not finite: no spectrum)."""
    ev = np.asarray(eigenvalues)
    count = np.sum(ev.real > np.asarray(margins), axis=-1)
    finite = np.isfinite(ev).all(axis=-1)
    return np.where(finite, count, -1)


def verdicts(eigenvalues, margins) -> np.ndarray:
    """1 every real part below minus its margin, 0 one above its margin, -1 otherwise
    (and where there is no eigenvalue), shape (...,)."""
    ev = np.asarray(eigenvalues)
    re, m = ev.real, np.asarray(margins)
    out = np.full(ev.shape[:-1], -1, dtype=np.int8)
    if ev.shape[-1]:
        with np.errstate(invalid="ignore"):
            out[np.all(re < -m, axis=-1)] = 1
            out[np.any(re > m, axis=-1)] = 0
    return out
