"""First-class combinations in closed form, by polynomial arithmetic (``DESIGN.md`` §2).

A classification decided at points of M_f (:mod:`nhham.hamiltonian.classification`)
knows r = rank B and a maximal second-class set R. Each k outside R gives the
first-class combination

    gamma_k = chi_k - sum_{a in R} (B_RR^{-1} B_Rk)_a chi_a

whose coefficients matter only on M_f: {gamma_k, chi_b} = sum_a c_a {chi_a, chi_b}
there (the terms {c_a, chi_b} chi_a vanish), and B c = 0 on M_f where B_RR is
invertible and rank B = |R|. So the entries of B on R + {k} are needed, not
reduced on M_f, and no W^{-1} is written. For L quadratic in v (p = W v + a(q)),
with delta = det W and Y = adj(W) (p - a):

* chi_a o Leg^{-1} = chi_a(q, Y / delta) = A_a / F_a with A_a a polynomial in the
  generators (parameters, coordinates, sines and cosines, momenta) and F_a one in q
  alone (delta^{deg_v chi_a} times the constraint's own denominator); a denominator of
  parameters alone (r/(2 d)) is a constant factor s_a, and the constraint is taken as
  s_a chi_a, so that such constraints share one F;
* E_ab = {A_a, A_b} = {F_a chi_a, F_b chi_b} = F_a F_b {chi_a, chi_b} on M_f, where
  every chi (hence every A) vanishes: the entries of B with one factor per row and
  column, without the products by F and by {F, A} that the exact identity needs (they
  vanish on M_f; with them the segway's entries ran past 20,000 terms);
* E restricted to R + {k} is antisymmetric of odd size with rank |R| on M_f: its
  kernel is spanned by c'_a = (-1)^i Pf(E without row and column a), the signed
  sub-Pfaffians (c'_k = Pf E_RR, nonzero); c_a = F_a c'_a (c' itself for one F)
  solves B c = 0 on M_f, and gamma_k = sum_a c_a chi_a / c_k, over one denominator
  where that stays small, else as the sum of the constraints with their coefficients.

Every polynomial is kept reduced modulo sin(u)^2 + cos(u)^2 - 1 (cos^2 -> 1 - sin^2)
after each product, so nothing grows beyond what the identities allow.
"""

from __future__ import annotations

import time

import sympy as sp
from sympy.polys.rings import sring

from nhham.lagrangian.algebra import POLYNOMIAL_ERRORS, trig_reduce
from nhham.system.naming import momentum_symbol

__all__ = ["closed_form_combinations", "NotFormed"]


# num/den with more terms than this are not cancelled by a gcd.
_CANCEL_TERMS = 2000

# A product of polynomials with more pairs of terms than this is not formed (about a
# second of sympy's sparse multiplication): the 3-link snake's bracket entries would
# have taken 100 s to reach the term bound.
MAX_PRODUCT_TERMS = 1_000_000

# gamma_k = sum_a c_a chi_a is expanded over one denominator only up to this many products
# of terms (c_a by chi_a o Leg^-1); beyond, it is given as the sum.
MAX_EXPANDED_PRODUCTS = 20_000

# num/den are cancelled by a gcd only up to this product of their numbers of terms (the
# segway's 653- and 456-term coefficients: 8 s of gcd for an 11-term factor).
_CANCEL_PRODUCT = 20_000

# The closed forms are for display: they are given up after this many CPU seconds.
TIME_LIMIT = 2.0


class NotFormed(Exception):
    """The combinations cannot be formed in closed form here (the reason is the message)."""


class OutOfTime(NotFormed):
    """Given up at the time limit (a second attempt by the same steps would be too)."""


def closed_form_combinations(system, constraints, second_class, max_terms: int = 20000,
                             time_limit: float = TIME_LIMIT,
                             max_coefficient_terms: int | None = None):
    """The first-class combinations gamma_k (k outside ``second_class``) in (q, p).

    Parameters
    ----------
    system : System
        With L quadratic in the velocities.
    constraints : sequence of sympy.Expr
        The final constraints chi_a on TQ (functions of q and v).
    second_class : sequence of int
        Indices of a maximal second-class set R (B_RR invertible on M_f).
    max_terms : int
        Give up (NotFormed) when a polynomial on the way has more terms (or a product
        more than MAX_PRODUCT_TERMS pairs of terms).
    time_limit : float
        Give up (NotFormed) after this many seconds.
    max_coefficient_terms : int, optional
        Give up (NotFormed) when a coefficient's numerator (a sub-Pfaffian) has more
        terms, before it is written out: the caller then forms the coefficients reduced
        on M_f (:mod:`nhham.hamiltonian.reduced_combinations`), far shorter there.

    Returns
    -------
    (tuple of sympy.Expr, tuple of dict)
        gamma_k for each k not in R, in order, and the coefficients
        ``{index: c_a}`` of each (c_k = 1), as expressions in (q, p).

    Raises
    ------
    NotFormed
        L not quadratic in v, a constraint or W not polynomial in the
        generators, a polynomial over ``max_terms`` terms, or out of time.
    """
    ctx = _Context(system, constraints, max_terms, time_limit)
    R = list(second_class)
    A, F = zip(*[ctx.hamiltonian(i) for i in range(len(ctx.constraints))])
    uniform = all(f == F[0] for f in F)
    entries: dict = {}

    def E(a, b):
        """{A_a, A_b}: F_a F_b {chi_a, chi_b} on M_f (where every A vanishes), so
        proportional to B_ab there with one factor per row and column."""
        if (a, b) not in entries:
            entries[a, b] = ctx.reduce(ctx.bracket(A[a], A[b]))
            entries[b, a] = -entries[a, b]
        return entries[a, b]

    gammas, coefficients = [], []
    zero = ctx.ring.zero
    for k in (i for i in range(len(A)) if i not in R):
        # E on R + [k] is antisymmetric of odd size: its kernel (on M_f, where its rank
        # is |R|) is spanned by the signed Pfaffians of the blocks without one index
        idx = R + [k]
        c = {a: ctx.reduce((-1) ** (len(idx) - 1 - i) * ctx.pfaffian(
            [[E(x, y) for y in idx if y != a] for x in idx if x != a]))
            for i, a in enumerate(idx)}
        if not c[k]:
            raise NotFormed("the bracket block of the second-class set vanishes identically")
        if max_coefficient_terms is not None and \
                max(len(x) for x in c.values()) > max_coefficient_terms:
            raise NotFormed(f"a coefficient of more than {max_coefficient_terms} terms")
        c = ctx.without_common_factor(c)
        # B' c = 0 on M_f for c_a = c'_a (uniform F) or F_a c'_a, B' the brackets of the
        # scaled constraints s_a chi_a; gamma_k = sum_a c_a s_a chi_a / (c_k s_k)
        S = ctx.scales
        weight = {a: (ctx.ring.one if uniform else F[a]) * S[a] for a in idx}
        coeffs = {a: ctx.expression(ctx.reduce(weight[a] * c[a]), ctx.reduce(weight[k] * c[k]))
                  for a in sorted(idx) if c[a]}
        coefficients.append(coeffs)
        if sum(len(c[a]) * len(A[a]) for a in idx) <= MAX_EXPANDED_PRODUCTS:
            num = sum((c[a] * A[a] for a in idx), zero)
            gammas.append(ctx.expression(ctx.reduce(num), ctx.reduce(F[k] * c[k] * S[k])))
        else:
            # Expanded over one denominator it would be far larger than its parts (the
            # segway: 830,000 characters): the combination of the constraints in (q, p).
            gammas.append(sp.Add(*[coeffs[a] * ctx.expression(A[a], F[a] * S[a])
                                   for a in coeffs]))
    return tuple(gammas), tuple(coefficients)


class _Context:
    """One polynomial ring for W, a(q), the constraints and the momenta."""

    def __init__(self, system, constraints, max_terms, time_limit=TIME_LIMIT):
        self.deadline = time.process_time() + time_limit
        self.time_limit = time_limit
        q, v = list(system.coordinates), list(system.velocities)
        p = [momentum_symbol(s) for s in q]
        L = sp.expand(system.lagrangian)
        try:
            if sp.Poly(L, *v).total_degree() > 2:
                raise NotFormed("L is not quadratic in the velocities")
        except sp.PolynomialError:
            raise NotFormed("L is not polynomial in the velocities") from None
        n = len(q)
        grad = [sp.diff(L, s) for s in v]
        W = [[sp.diff(grad[i], v[j]) for j in range(n)] for i in range(n)]
        zero = {s: 0 for s in v}
        a = [g.xreplace(zero) for g in grad]
        nums, dens, scales = [], [], []
        for c in constraints:
            num, den = sp.fraction(sp.together(sp.sympify(c)))
            if den.free_symbols & set(v):
                raise NotFormed("a final constraint is not polynomial in the velocities")
            # A denominator of parameters alone (r/(2 d)) is a constant factor: the
            # constraint is taken as num (= den chi), so that every chi o Leg^-1 shares
            # one denominator (F^3 {chi_a, chi_b} instead of F_a^2 F_b^2 {chi_a, chi_b}).
            scale = den if not den.free_symbols & set(q) else sp.S.One
            nums.append(num)
            dens.append(den / scale)
            scales.append(scale)
        flat = [e for row in W for e in row] + a + nums + dens + scales + q + v + p
        # every sine with its cosine (and back): the derivatives stay in the ring
        angles = {f.args[0] for e in flat for f in sp.sympify(e).atoms(sp.sin, sp.cos)}
        flat += [f(u) for u in sorted(angles, key=sp.default_sort_key) for f in (sp.sin, sp.cos)]
        try:
            self.ring, polys = sring(flat)
        except POLYNOMIAL_ERRORS as exc:
            raise NotFormed(f"not polynomial in its generators ({exc})") from None
        self.max_terms = max_terms
        self.q, self.v, self.p = q, v, p
        self.state = set(q) | set(v) | set(p)
        k = len(constraints)
        it = iter(polys)
        self.W = [[self.reduce(next(it)) for _ in range(n)] for _ in range(n)]
        self.a = [self.reduce(next(it)) for _ in range(n)]
        self.constraints = [self.reduce(next(it)) for _ in range(k)]
        self.denominators = [self.reduce(next(it)) for _ in range(k)]
        self.scales = [next(it) for _ in range(k)]
        self.gq, self.gv, self.gp = ([next(it) for _ in range(n)] for _ in range(3))
        self._dq = [self._coordinate_derivatives(s) for s in q]

    # -------------------------------------------------------- arithmetic
    def reduce(self, poly):
        poly = trig_reduce(poly)
        if len(poly) > self.max_terms:
            raise NotFormed(f"a polynomial of more than {self.max_terms} terms")
        if time.process_time() > self.deadline:
            raise OutOfTime(f"not formed within {self.time_limit:g} s of CPU time")
        return poly

    def mul(self, f, g):
        """f g, refused (NotFormed) when it would take more than MAX_PRODUCT_TERMS
        products of terms."""
        if len(f) * len(g) > MAX_PRODUCT_TERMS:
            raise NotFormed(f"a product of polynomials of {len(f)} and {len(g)} terms")
        return f * g

    def adj_det(self, rows):
        """(adjugate as rows, determinant) of a square matrix of ring elements.

        Faddeev-LeVerrier: M_k = A M_{k-1} + c_{n-k+1} I, c_{n-k} = -tr(A M_k) / k
        (exact integer divisions), det A = (-1)^n c_0, adj A = (-1)^(n-1) M_n; only
        products and sums, so every step may be reduced modulo sin^2 + cos^2 = 1.
        """
        n, zero = len(rows), self.ring.zero
        M = [[zero] * n for _ in range(n)]
        c = self.ring.one
        for k in range(1, n + 1):
            M = [[self.reduce(sum((self.mul(rows[i][j], M[j][l]) for j in range(n)), zero)
                              + (c if i == l else zero)) for l in range(n)] for i in range(n)]
            trace = sum((self.mul(rows[i][j], M[j][i]) for i in range(n) for j in range(n)),
                        zero)
            c = -self.reduce(trace).quo_ground(k)  # exact: the normal form of k c
        sign = -1 if n % 2 else 1
        return [[-sign * e for e in row] for row in M], sign * c

    def pfaffian(self, rows):
        """The Pfaffian of an antisymmetric matrix of ring elements (expansion along
        the first row; 1 for the empty matrix)."""
        n = len(rows)
        if n == 0:
            return self.ring.one
        if n % 2:
            return self.ring.zero
        total = self.ring.zero
        for j in range(1, n):
            if rows[0][j]:
                keep = [i for i in range(1, n) if i != j]
                minor = [[rows[x][y] for y in keep] for x in keep]
                total += (-1) ** (j - 1) * self.mul(rows[0][j], self.pfaffian(minor))
        return self.reduce(total)

    def expression(self, num, den) -> sp.Expr:
        """num/den, their common factor in the parameters divided out, and cancelled
        when small (a gcd of large polynomials costs more than it gives)."""
        num, den = self.without_common_factor({0: num, 1: den}).values()
        if len(num) + len(den) <= _CANCEL_TERMS and len(num) * len(den) <= _CANCEL_PRODUCT:
            num, den = num.cancel(den)
        return num.as_expr() / den.as_expr()

    def without_common_factor(self, polys: dict) -> dict:
        """``polys`` divided by the gcd of all their coefficients as polynomials in the
        state generators (q, v, p and the sines and cosines) over the parameters: a
        polynomial in the parameters alone, found by gcds of small polynomials."""
        state = [i for i, g in enumerate(self.ring.symbols)
                 if g in self.state or isinstance(g, (sp.sin, sp.cos))]
        common = None
        for poly in polys.values():
            parts: dict = {}
            for mon, coeff in poly.terms():
                key = tuple(mon[i] for i in state)
                rest = tuple(0 if i in state else e for i, e in enumerate(mon))
                parts.setdefault(key, {})[rest] = coeff
            for rest in parts.values():
                part = self.ring.from_dict(rest)
                common = part if common is None else common.gcd(part)
                if common.is_ground:
                    return polys
        if common is None or common.is_ground:
            return polys
        return {key: poly.exquo(common) for key, poly in polys.items()}

    # ------------------------------------------------------ Legendre map
    def hamiltonian(self, index):
        """(chit, den): chi o Leg^{-1} = chit / den for the constraint ``index``, both
        polynomials (den = the constraint's own denominator times delta^{deg_v chi})."""
        if not hasattr(self, "_Y"):
            adj, self.delta = self.adj_det(self.W)
            rhs = [self.gp[i] - self.a[i] for i in range(len(self.p))]
            self._Y = [self.reduce(sum((self.mul(adj[i][j], rhs[j]) for j in range(len(rhs))),
                                       self.ring.zero)) for i in range(len(rhs))]
        chi = self.constraints[index]
        vpos = [self.ring.gens.index(g) for g in self.gv]
        degree = max((sum(m[i] for i in vpos) for m in chi.monoms()), default=0)
        out = self.ring.zero
        for mon, coeff in chi.terms():
            term = self.ring({tuple(0 if i in vpos else e for i, e in enumerate(mon)): coeff})
            j = 0
            for i, pos in enumerate(vpos):
                for _ in range(mon[pos]):
                    term = self.reduce(self.mul(term, self._Y[i]))
                    j += 1
            out += term * self.delta ** (degree - j)
        return self.reduce(out), self.reduce(self.denominators[index] * self.delta ** degree)

    # ------------------------------------------------------------ bracket
    def _coordinate_derivatives(self, q):
        """[(generator index, d generator / dq as a ring element)] for generators with q."""
        out = []
        for i, g in enumerate(self.ring.symbols):
            if g.has(q) and g not in self.p:
                try:
                    out.append((i, self.ring(sp.diff(g, q))))
                except (*POLYNOMIAL_ERRORS, sp.polys.polyerrors.GeneratorsError):
                    raise NotFormed(f"d({g})/d{q} is not a polynomial in the generators") \
                        from None
        return out

    def depends_on_q(self, f) -> bool:
        """True when the polynomial ``f`` involves a generator that depends on q."""
        used = {i for i, e in enumerate(f.degrees()) if e}
        return any(i in used for pairs in self._dq for i, _ in pairs)

    def _dq_of(self, f, A):
        return self.reduce(sum((f.diff(self.ring.gens[i]) * dg for i, dg in self._dq[A]),
                               self.ring.zero))

    def bracket(self, f, g):
        """{f, g} = f_q . g_p - f_p . g_q on polynomials in the generators."""
        total = self.ring.zero
        for A in range(len(self.q)):
            fp, gp = f.diff(self.gp[A]), g.diff(self.gp[A])
            if gp:
                total += self.mul(self._dq_of(f, A), gp)
            if fp:
                total -= self.mul(fp, self._dq_of(g, A))
            total = self.reduce(total)
        return total
