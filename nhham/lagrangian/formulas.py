"""The paper's formulas at one point, each written once for every arithmetic.

A formula here takes matrices of one kind (sympy ``DomainMatrix`` over QQ, GF(p) or
Q(params); :class:`~nhham.lagrangian.linalg.ListMatrix` of exact rationals, residues
or :class:`~nhham.lagrangian.domains.Degree` bounds;
:class:`~nhham.lagrangian.linalg.FloatMatrix` of float64 or mpmath numbers) and uses
only their ``*`` (matrix product), ``-``, ``transpose`` and a ``solve``: so the exact
decision, the proof modulo p, the degree bound of the Schwartz–Zippel lemma, the
parameter-field datum and the floating-point estimate are one computation, and a
defect in it shows in every arithmetic alike.
"""

from __future__ import annotations

from typing import Callable

from nhham.lagrangian.linalg import field_solve, zeros_like

__all__ = ["bordered_matrix", "bordered_system", "tangency_rows", "vertical_rows", "constrained_motion", "lagrangian_bracket",
           "dirac_difference", "frobenius_terms"]


def bordered_matrix(W, mu, Jv):
    """K = [[W, μᵀ], [∂χ/∂v, 0]]: the matrix of the tangency equations of χ on M_k.

    With a = v̇, W a + μᵀ λ = F and (∂χ_j/∂v) a = −(∂χ_j/∂q) v (DESIGN.md, inverse-free
    form): rank K − n is the rank of (Z_i(χ_j)) where W is regular, and
    det K = det W · det (Z_i(χ_j)) for as many χ as multipliers.

    Parameters
    ----------
    W : matrix, shape (n, n)
    mu : matrix, shape (m, n)
        The rows of the multipliers taken (all of μ, or a block of them).
    Jv : matrix, shape (r, n)
        ∂χ_j/∂v.

    Returns
    -------
    matrix, shape (n + r, n + m)
    """
    zero = zeros_like(Jv, (Jv.shape[0], mu.shape[0]))
    return W.hstack(mu.transpose()).vstack(Jv.hstack(zero))


def bordered_system(W, mu, F, Jq_v, Jv, Jt=None):
    """(K, c) of the tangency equations K [a; λ] = c of constraints χ: the one home of
    their inverse-free form.

    K = [[W, μᵀ], [∂χ/∂v, 0]] (:func:`bordered_matrix`) and c = [F; −∂χ/∂q · v − ∂χ/∂t],
    from W a + μᵀ λ = F and d/dt χ = (∂χ/∂q) v + (∂χ/∂v) a + ∂χ/∂t = 0. Eliminating a gives the rows
    A λ + b = 0 of :func:`tangency_rows` (A_ji = Z_i(χ_j), b_j = ξ_L(χ_j)), which are the
    rows :func:`nhham.lagrangian.projection.tangency_equations` forms from the fields.

    Parameters
    ----------
    W : matrix, shape (n, n)
    mu : matrix, shape (m, n)
    F : matrix, shape (n, 1)
    Jq_v : matrix, shape (k, 1)
        ∂χ/∂q · v.
    Jv : matrix, shape (k, n)
        ∂χ/∂v.
    Jt : matrix of shape (k, 1), or None
        ∂χ/∂t for constraints that depend on the time (None: autonomous).

    Returns
    -------
    K : matrix, shape (n + k, n + m)
    c : matrix, shape (n + k, 1)

    Examples
    --------
    A particle in the plane, W = I, one constraint χ = y_dot − x x_dot (μ = (−x, 1)):

    >>> from nhham.lagrangian.linalg import ListMatrix
    >>> K, c = bordered_system(ListMatrix([[1, 0], [0, 1]]), ListMatrix([[-2, 1]]),
    ...                        ListMatrix([[0], [0]]), ListMatrix([[-9]]),
    ...                        ListMatrix([[-2, 1]]))
    >>> K.rows, c.rows
    ([[1, 0, -2], [0, 1, 1], [-2, 1, 0]], [[0], [0], [9]])
    """
    rhs = -Jq_v if Jt is None else -(Jq_v + Jt)
    return bordered_matrix(W, mu, Jv), F.vstack(rhs)


def tangency_rows(W, mu, F, Jq_v, Jv, solve: Callable = field_solve):
    """(A, b) of the tangency equations A λ + b = 0 of constraints χ at one point.

    A_ji = Z_i(χ_j) = −(∂χ_j/∂v W⁻¹ μᵀ)_ji and b_j = ξ_L(χ_j) = (∂χ_j/∂q v)_j +
    (∂χ_j/∂v W⁻¹ F)_j (Z_i = −W^{AB} μ_iB ∂/∂v^A, ξ_L with W a = F: DESIGN.md). With
    χ = φ, A is C. The Schur complement of the bordered matrix
    :func:`bordered_matrix` (which avoids W⁻¹).

    Parameters
    ----------
    W : matrix, shape (n, n)
    mu : matrix, shape (m, n)
    F : matrix, shape (n,) or (n, 1)
    Jq_v : matrix, shape (k,) or (k, 1)
        ∂χ/∂q · v at the point.
    Jv : matrix, shape (k, n)
        ∂χ/∂v.
    solve : callable, optional
        ``solve(A, B) -> A⁻¹ B`` in the matrices' arithmetic.

    Returns
    -------
    A : matrix, shape (k, m)
    b : matrix, shape (k,) or (k, 1)
    """
    return vertical_rows(W, mu, Jv, solve), Jq_v + Jv * solve(W, F)


def vertical_rows(W, mu, Jv, solve: Callable = field_solve):
    """A_ji = Z_i(χ_j) = −(∂χ_j/∂v W⁻¹ μᵀ)_ji at one point: the λ-part of
    :func:`tangency_rows` (C for χ = φ), shape (k, m)."""
    return -(Jv * solve(W, mu.transpose()))


def constrained_motion(W, mu, F, drift, solve: Callable = field_solve):
    """The saddle solve [[W, μᵀ], [μ, 0]] [a; λ] = [F; −drift] by its Schur complement.

    C = −μ W⁻¹ μᵀ (= (Z_i(φ_j))), λ = −C⁻ᵀ (drift + μ W⁻¹ F) and
    a = W⁻¹ F − W⁻¹ μᵀ λ: the accelerations of P(ξ_L) and the multipliers, for
    φ = μ v + h with drift = ∂φ/∂q · v. The numeric kernels solve the same system
    scaled and in one LU (:mod:`nhham.numerics.saddle`, the C runtime).

    Parameters
    ----------
    W : matrix, shape (n, n)
    mu : matrix, shape (m, n)
    F : matrix, shape (n,) or (n, 1)
    drift : matrix, shape (m,) or (m, 1)
    solve : callable, optional

    Returns
    -------
    a : matrix, shape of F
    lam : matrix, shape of drift
    C : matrix, shape (m, m)
    """
    a = solve(W, F)
    Y = solve(W, mu.transpose())
    C = -(mu * Y)
    lam = -solve(C.transpose(), drift + mu * a)
    return a - Y * lam, lam, C


def lagrangian_bracket(Jq, Jv, W, M, solve: Callable = field_solve):
    """B_ab = {chi_a, chi_b}_L at one point, the Poisson bracket pulled back by Leg.

    {f, g}_L = f_q · W⁻¹ g_v − W⁻¹ f_v · g_q − (W⁻¹ f_v)ᵀ (M − Mᵀ) W⁻¹ g_v, with W the
    Hessian d²L/dv² and M the mixed Hessian d²L/dq dv (M_AB = ∂p_A/∂q^B); in matrices,
    with U = W⁻¹ J_vᵀ, B = J_q U − (J_q U)ᵀ − Uᵀ (M − Mᵀ) U.

    Parameters
    ----------
    Jq, Jv : matrix, shape (k, n)
        ∂chi_a/∂q and ∂chi_a/∂v at the point.
    W, M : matrix, shape (n, n)
        W and M at the point.
    solve : callable, optional
        ``solve(A, B) -> A⁻¹ B`` in the matrices' arithmetic (default
        :func:`~nhham.lagrangian.linalg.field_solve`).

    Returns
    -------
    matrix, shape (k, k)
        Antisymmetric, of the matrices' kind.
    """
    U = solve(W, Jv.transpose())
    JU = Jq * U
    return JU - JU.transpose() - U.transpose() * (M - M.transpose()) * U


def dirac_difference(W, M, mu, F, drift, v, Jq, Jv, solve: Callable = field_solve, Jt=None):
    """X_D − X at one point x of TQ, in the (q, p) components at Leg(x): shape (2n, 1).

    X_D = X_H − X_χa (B_RR⁻¹)^ab {χ_b, H} is the Dirac flow of H over a second-class set
    χ_R and X = X_H + λ^j Z_j^H the projected field (DESIGN.md §2), both pulled back by
    Leg, so no H and no Leg⁻¹ are needed: X_H(χ) = ξ_L(χ) = ∂χ/∂q v + ∂χ/∂v W⁻¹ F (the
    forced field where F has forces), B = {χ_a, χ_b}_L (:func:`lagrangian_bracket`), the
    Hamiltonian field of χ has the components (W⁻¹ χ_v, −(χ_q − Mᵀ W⁻¹ χ_v)) and
    X − X_H = (0, −μᵀ λ) (:func:`constrained_motion`). With U = W⁻¹ J_vᵀ and
    y = B⁻¹ X_H(χ):  X_D − X = (−U y, (J_qᵀ − Mᵀ U) y + μᵀ λ). Constraints that depend on
    the time keep themselves along X_D only with their ∂χ/∂t: X_D = X_H − X_χa (B_RR⁻¹)^ab
    ({χ_b, H} + ∂χ_b/∂t), so y = B⁻¹ (ξ_L(χ) + ∂χ/∂t) (``Jt``).

    Parameters
    ----------
    W, M : matrix, shape (n, n)
        The Hessian d²L/dv² and the mixed Hessian (M_AB = ∂p_A/∂q^B) at the point.
    mu, drift : matrix, shapes (m, n) and (m, 1)
        The affine constraints' rows and ∂φ/∂q · v.
    F, v : matrix, shape (n, 1)
        The forcing of W a + μᵀ λ = F and the velocities.
    Jq, Jv : matrix, shape (r, n)
        ∂χ/∂q and ∂χ/∂v of the second-class set (r = 0: X_D = X_H).
    solve : callable, optional
        ``solve(A, B) -> A⁻¹ B`` in the matrices' arithmetic.
    Jt : matrix, shape (r, 1), optional
        ∂χ/∂t at fixed (q, v) where the second-class set depends on the time t.

    Returns
    -------
    matrix, shape (2n, 1)
        ZeroDivisionError where C or B_RR is singular at the point.
    """
    n = W.shape[0]
    if mu.shape[0]:
        _, lam, _ = constrained_motion(W, mu, F, drift, solve)
        dp = mu.transpose() * lam
    else:
        dp = zeros_like(W, (n, 1))
    if not Jq.shape[0]:
        return zeros_like(W, (n, 1)).vstack(dp)
    U = solve(W, Jv.transpose())
    B = lagrangian_bracket(Jq, Jv, W, M, solve)
    rate = Jq * v + Jv * solve(W, F)
    y = solve(B, rate if Jt is None else rate + Jt)
    return (-(U * y)).vstack(dp + (Jq.transpose() - M.transpose() * U) * y)


def frobenius_terms(M, D, dep, solve: Callable = field_solve) -> dict:
    """dμ_i(X_a, X_b) for a basis X_a of ker μ at one point, in any arithmetic.

    The distribution ker μ is integrable exactly where every term vanishes (Frobenius:
    for X, Y in ker μ, dμ_i(X, Y) = −μ_i([X, Y])). The sign convention has this one
    home: dμ_i(X, Y) = X^A Y^B (∂_A μ_iB − ∂_B μ_iA).

    Parameters
    ----------
    M : matrix, shape (m, n)
        μ at the point (rows independent).
    D : sequence of m rows-of-rows, each (n, n)
        ``D[i][A][B]`` = ∂_A μ_iB − ∂_B μ_iA at the point.
    dep : sequence of int
        m columns of M that form an invertible block; the basis is X_a = e_(free a)
        − (M_dep)⁻¹ M_free e_a, one per other column.
    solve : callable, optional
        ``solve(A, B) -> A⁻¹ B`` in the matrices' arithmetic.

    Returns
    -------
    dict
        ``{(i, a, b): dμ_i(X_a, X_b)}`` for a < b, in the order of i, a, b.
    """
    m, n = M.shape
    free = [j for j in range(n) if j not in dep]
    rows = list(range(m))
    sol = solve(M.extract(rows, list(dep)), -M.extract(rows, free)).to_list()
    basis = [dict(sorted({j: 1, **{d: sol[t][a] for t, d in enumerate(dep)}}.items()))
             for a, j in enumerate(free)]
    out = {}
    for i, Di in enumerate(D):
        for a in range(len(free)):
            for b in range(a + 1, len(free)):
                X, Y = basis[a], basis[b]
                out[(i, a, b)] = sum((x * Di[A][B] * y for A, x in X.items()
                                      for B, y in Y.items() if Di[A][B] != 0), 0)
    return out
