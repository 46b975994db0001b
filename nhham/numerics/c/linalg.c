/* ---- small dense linear algebra (row-major) ---- */

/* Solve A x = b (d x d) in place by LU with partial pivoting.
   Returns 0 on success, 1 if a pivot is at or below tol (0: exactly zero). */
static int gsolve(int d, double *A, double *b, double tol) {
    for (int c = 0; c < d; ++c) {
        int piv = c;
        double best = fabs(A[c * d + c]);
        for (int r = c + 1; r < d; ++r) if (fabs(A[r * d + c]) > best) { best = fabs(A[r * d + c]); piv = r; }
        if (best <= tol) return 1;
        if (piv != c) {
            for (int j = 0; j < d; ++j) { double t = A[c * d + j]; A[c * d + j] = A[piv * d + j]; A[piv * d + j] = t; }
            double t = b[c]; b[c] = b[piv]; b[piv] = t;
        }
        double inv = 1.0 / A[c * d + c];
        for (int r = c + 1; r < d; ++r) {
            double f = A[r * d + c] * inv;
            if (f == 0.0) continue;
            for (int j = c + 1; j < d; ++j) A[r * d + j] -= f * A[c * d + j];
            b[r] -= f * b[c];
        }
    }
    for (int r = d - 1; r >= 0; --r) {
        double s = b[r];
        for (int j = r + 1; j < d; ++j) s -= A[r * d + j] * b[j];
        b[r] = s / A[r * d + r];
    }
    return 0;
}

/* The scaled saddle matrix [[D W D, (E M D)^T], [E M D, 0]] by LU with partial
   pivoting (the fallback of ksolve). */
static int lu_solve(int mm, const double *W, const double *mu, const double *d,
                     const double *e, const double *top, const double *bottom,
                     double *x, double *y) {
    const int nn = NQ + mm;
    double K[NNX * NNX], b[NNX];
    for (int i = 0; i < NQ; ++i) {
        for (int j = 0; j < NQ; ++j) K[i * nn + j] = W[i * NQ + j] * d[i] * d[j];
        for (int c = 0; c < mm; ++c) {
            double t = mu[c * NQ + i] * d[i] * e[c];
            K[i * nn + NQ + c] = t;
            K[(NQ + c) * nn + i] = t;
        }
        b[i] = top[i] * d[i];
    }
    for (int c = 0; c < mm; ++c) {
        for (int k = 0; k < mm; ++k) K[(NQ + c) * nn + NQ + k] = 0.0;
        b[NQ + c] = bottom[c] * e[c];
    }
    if (gsolve(nn, K, b, 0.0)) return 1;
    for (int i = 0; i < NQ; ++i) x[i] = b[i] * d[i];
    for (int c = 0; c < mm; ++c) y[c] = b[NQ + c] * e[c];
    return 0;
}

/* X <- Q X for X (NQ x cols, row stride cols), Q = P_0 H_0 .. P_{mm-1} H_{mm-1} the
   reflections (v_c = V + c NQ, beta_c) and row swaps (piv) of nullspace_solve's QR: Q is
   never formed (m reflections of NQ x cols against NQ^2 entries). */
static void q_times(int mm, const double *V, const double *beta, const int *piv, double *X,
                    int cols) {
    for (int c = mm - 1; c >= 0; --c) {
        const double *v = V + c * NQ;
        for (int j = 0; j < cols; ++j) {
            double sd = 0.0;
            for (int i = c; i < NQ; ++i) sd += v[i] * X[i * cols + j];
            sd *= beta[c];
            for (int i = c; i < NQ; ++i) X[i * cols + j] -= sd * v[i];
        }
        if (piv[c] != c)
            for (int j = 0; j < cols; ++j) {
                const double u = X[c * cols + j];
                X[c * cols + j] = X[piv[c] * cols + j];
                X[piv[c] * cols + j] = u;
            }
    }
}

/* The null-space solve of [[W, mu^T], [mu, 0]] [x; y] = [top; bottom] (the steps of
   nhham.numerics.nullspace.solve_null_space): D = diag(W)^-1/2, Householder QR with row
   pivoting (mu D)^T = [Q1 Q2] [R; 0], s = Q1 R^-T bottom, (Q2^T D W D Q2) z = Q2^T (D top -
   D W D s) by LU, x = D (s + Q2 z), R y = Q1^T (D top - D W D D^-1 x). Where W's
   diagonal spans orders of magnitude (a light coordinate tied to a heavy one) it keeps
   the small accelerations that the saddle solve obtains as a difference of nearly equal
   terms. The rows of mu D are scaled to unit length first (y scaled back), so that
   |R_cc| <= 1; mu counts as rank deficient where |R_cc| <= NHHAM_RANK_TOL NQ, and the
   reduced matrix as singular where an LU pivot is at or below NHHAM_RANK_TOL NQ times
   its largest entry (nhham.numerics.nullspace.RANK_TOLERANCE: singular to rounding).
   Returns 0, or 1 when mu is rank deficient or the reduced matrix singular. */
#define NHHAM_RANK_TOL (64 * 2.220446049250313e-16)
#if defined(__GNUC__)
__attribute__((noinline))   /* one copy, not one per caller */
#endif
static int nullspace_solve(int mm, const double *W, const double *mu, const double *top,
                         const double *bottom, double *x, double *y) {
    enum { MX = NCX };
    double d[NQ], Ws[NQ * NQ], A[NQ * MX], V[MX * NQ], beta[MX], Q2[NQ * NQ];
    double s[NQ], t[NQ], WQ[NQ * NQ], H[NQ * NQ], z[NQ], w[MX];
    int piv[MX];
    const int r = NQ - mm;
    for (int i = 0; i < NQ; ++i) {
        double a = fabs(W[i * NQ + i]);
        d[i] = a > 0.0 ? 1.0 / sqrt(a) : 1.0;
    }
    for (int i = 0; i < NQ; ++i)
        for (int j = 0; j < NQ; ++j) Ws[i * NQ + j] = W[i * NQ + j] * d[i] * d[j];
    double e[MX];
    for (int c = 0; c < mm; ++c) {
        double nc = 0.0;
        for (int i = 0; i < NQ; ++i) {
            A[i * MX + c] = mu[c * NQ + i] * d[i];
            nc += A[i * MX + c] * A[i * MX + c];
        }
        e[c] = nc > 0.0 ? 1.0 / sqrt(nc) : 1.0;
        for (int i = 0; i < NQ; ++i) A[i * MX + c] *= e[c];
    }
    /* Householder reflections H_c = I - beta_c v_c v_c^T with row pivoting (the swap P_c
       of rows c and piv_c first: the largest remaining entry of column c, so that a
       kernel direction near a coordinate axis keeps its small components to relative
       accuracy, see nhham.numerics.nullspace.householder_rows):
       A = P_0 H_0 .. P_{mm-1} H_{mm-1} [R; 0]. */
    for (int c = 0; c < mm; ++c) {
        double norm = 0.0, vv = 0.0, *v = V + c * NQ, big = -1.0;
        for (int i = c; i < NQ; ++i)
            if (fabs(A[i * MX + c]) > big) { big = fabs(A[i * MX + c]); piv[c] = i; }
        if (piv[c] != c)
            for (int k = 0; k < mm; ++k) {
                const double t = A[c * MX + k];
                A[c * MX + k] = A[piv[c] * MX + k];
                A[piv[c] * MX + k] = t;
            }
        for (int i = c; i < NQ; ++i) norm += A[i * MX + c] * A[i * MX + c];
        norm = sqrt(norm);
        if (!(norm > NHHAM_RANK_TOL * NQ)) return 1;
        const double alpha = A[c * MX + c] >= 0.0 ? -norm : norm;
        for (int i = 0; i < NQ; ++i) v[i] = i < c ? 0.0 : A[i * MX + c];
        v[c] -= alpha;                 /* no cancellation: alpha has the other sign */
        for (int i = c; i < NQ; ++i) vv += v[i] * v[i];
        beta[c] = 2.0 / vv;
        for (int k = c + 1; k < mm; ++k) {
            double sd = 0.0;
            for (int i = c; i < NQ; ++i) sd += v[i] * A[i * MX + k];
            sd *= beta[c];
            for (int i = c; i < NQ; ++i) A[i * MX + k] -= sd * v[i];
        }
        A[c * MX + c] = alpha;
    }
    /* R^T w = bottom (R = the upper triangle of A), s = Q1 w = Q [w; 0]. */
    for (int c = 0; c < mm; ++c) {
        double a = bottom[c] * e[c];
        for (int k = 0; k < c; ++k) a -= A[k * MX + c] * w[k];
        w[c] = a / A[c * MX + c];
    }
    for (int i = 0; i < NQ; ++i) s[i] = i < mm ? w[i] : 0.0;
    q_times(mm, V, beta, piv, s, 1);
    for (int i = 0; i < NQ; ++i) {
        double a = top[i] * d[i];
        for (int j = 0; j < NQ; ++j) a -= Ws[i * NQ + j] * s[j];
        t[i] = a;
    }
    /* Q2 = Q [0; I] (NQ x r, row stride r); (Q2^T Ws Q2) z = Q2^T t. */
    for (int i = 0; i < NQ; ++i)
        for (int b = 0; b < r; ++b) Q2[i * r + b] = i == mm + b ? 1.0 : 0.0;
    q_times(mm, V, beta, piv, Q2, r);
    for (int i = 0; i < NQ; ++i)
        for (int b = 0; b < r; ++b) {
            double a = 0.0;
            for (int j = 0; j < NQ; ++j) a += Ws[i * NQ + j] * Q2[j * r + b];
            WQ[i * r + b] = a;
        }
    double hmax = 0.0;
    for (int a = 0; a < r; ++a) {
        double ra = 0.0;
        for (int i = 0; i < NQ; ++i) ra += Q2[i * r + a] * t[i];
        z[a] = ra;
        for (int b = 0; b < r; ++b) {
            double h = 0.0;
            for (int i = 0; i < NQ; ++i) h += Q2[i * r + a] * WQ[i * r + b];
            H[a * r + b] = h;
            if (fabs(h) > hmax) hmax = fabs(h);
        }
    }
    if (r > 0 && gsolve(r, H, z, NHHAM_RANK_TOL * NQ * hmax)) return 1;
    for (int i = 0; i < NQ; ++i) {
        double a = s[i];
        for (int b = 0; b < r; ++b) a += Q2[i * r + b] * z[b];
        s[i] = a;                      /* D^-1 x */
        x[i] = a * d[i];
    }
    /* R y = Q1^T (D top - Ws D^-1 x): the first mm entries of Q^T (...). */
    for (int i = 0; i < NQ; ++i) {
        double a = top[i] * d[i];
        for (int j = 0; j < NQ; ++j) a -= Ws[i * NQ + j] * s[j];
        t[i] = a;
    }
    for (int c = 0; c < mm; ++c) {      /* Q^T = H_{mm-1} P_{mm-1} .. H_0 P_0 */
        const double *v = V + c * NQ;
        if (piv[c] != c) { const double u = t[c]; t[c] = t[piv[c]]; t[piv[c]] = u; }
        double sd = 0.0;
        for (int i = c; i < NQ; ++i) sd += v[i] * t[i];
        sd *= beta[c];
        for (int i = c; i < NQ; ++i) t[i] -= sd * v[i];
    }
    for (int c = mm - 1; c >= 0; --c) {
        double a = t[c];
        for (int k = c + 1; k < mm; ++k) a -= A[c * MX + k] * y[k];
        y[c] = a / A[c * MX + c];
    }
    for (int c = 0; c < mm; ++c) y[c] *= e[c];
    return 0;
}

/* Smallest accepted Cholesky pivot of W relative to its diagonal entry (a
   pivot of the unit-diagonal scaled W; the smallest pivot bounds the
   smallest eigenvalue from above, a cheap condition estimate): below it W
   is indefinite or nearly singular and the saddle matrix is solved by LU
   instead. The range-space method loses about log10 cond(W) digits, LU on
   the scaled saddle matrix does not depend on cond(W). The N-link snake's
   smallest pivots are 0.4 (N = 2) .. 0.04 (N = 16). */
#define CHOL_MIN 1e-4
#if defined(__GNUC__)
#define HOT static inline __attribute__((always_inline))
#else
#define HOT static inline
#endif

/* Cholesky A = L L^T of the leading n x n block of the symmetric A (row stride lda)
   into the lower part of L (row stride ldl; L may be A, factored in place). The
   diagonal of L holds 1 / L_jj. A pivot is accepted when it is finite and above
   ratio times its diagonal entry of A (ratio 0: positive). Returns 0, or 1 at the
   first pivot refused. Forced inline, like ksolve which factors W and S with it. */
HOT int cholesky(int n, const double *A, int lda, double *L, int ldl, double ratio) {
    for (int j = 0; j < n; ++j) {
        const double ajj = A[j * lda + j];
        double s = ajj;
        for (int k = 0; k < j; ++k) s -= L[j * ldl + k] * L[j * ldl + k];
        if (!(s > ratio * ajj) || !isfinite(s)) return 1;
        const double inv = 1.0 / sqrt(s);
        L[j * ldl + j] = inv;
        for (int i = j + 1; i < n; ++i) {
            double t = A[i * lda + j];
            for (int k = 0; k < j; ++k) t -= L[i * ldl + k] * L[j * ldl + k];
            L[i * ldl + j] = t * inv;
        }
    }
    return 0;
}

/* The saddle-point solve of ksolve (below): [[W, mu^T], [mu, 0]] [x; y] = [top; bottom]
   with the first mm rows of mu (row stride NQ); W symmetric.

   When W = L L^T (Cholesky, every pivot above CHOL_MIN times its diagonal
   entry) the range-space method: [Z | u] = L^-1 [mu^T | top], the Schur
   complement S = Z^T Z = mu W^-1 mu^T (positive definite when mu has full
   rank) by Cholesky, S y = Z^T u - bottom, L^T x = u - Z y. That is about
   n^3/6 + (m+1) n^2/2 + (m+1)^2 n/2 multiply-adds against (n+m)^3/3 for LU,
   with no pivot search; Cholesky and the triangular solves are invariant
   under the diagonal scaling that LU needs, so none is applied.
   Otherwise (W indefinite, e.g. a Lorentzian metric, or nearly singular; S
   not numerically positive definite, e.g. mu rank deficient): LU with partial
   pivoting on the symmetrically scaled saddle matrix (unit diagonal of W,
   unit rows of mu), backward stable at extreme mass ratios (an acceleration that is
   a difference of nearly equal terms keeps only its absolute accuracy).
   Returns 0, or 1 when the matrix is singular.
   Forced inline (with the Cholesky it calls) on purpose: it is the innermost call of every
   field evaluation, and the Cholesky factors live on its stack for the LU fallback's decision. */
HOT int ksolve_saddle(int mm, const double *W, const double *mu, const double *top,
                      const double *bottom, double *x, double *y) {
    enum { M1 = NCX + 1 };
    double L[NQ * NQ], Z[M1 * NQ], G[M1 * M1], r[NCX];
    /* Cholesky W = L L^T. */
    if (cholesky(NQ, W, NQ, L, NQ, CHOL_MIN)) goto lu;
    /* [Z | u] = L^-1 [mu^T | top]: row c of Z holds column c (c = mm: u). */
    for (int c = 0; c <= mm; ++c) {
        double *zc = Z + c * NQ;
        const double *b = c < mm ? mu + c * NQ : top;
        for (int i = 0; i < NQ; ++i) {
            double s = b[i];
            for (int k = 0; k < i; ++k) s -= L[i * NQ + k] * zc[k];
            zc[i] = s * L[i * NQ + i];
        }
    }
    /* G = [Z | u]^T [Z | u] (lower part): S = G[:mm, :mm], Z^T u = G[mm, :mm]. */
    for (int c = 0; c <= mm; ++c)
        for (int e = 0; e <= c && e < mm; ++e) {
            const double *zc = Z + c * NQ, *ze = Z + e * NQ;
            double s = 0.0;
            for (int i = 0; i < NQ; ++i) s += zc[i] * ze[i];
            G[c * M1 + e] = s;
        }
    /* Cholesky of S in place; S y = Z^T u - bottom. */
    if (cholesky(mm, G, M1, G, M1, 0.0)) goto lu;
    for (int i = 0; i < mm; ++i) {
        double s = G[mm * M1 + i] - bottom[i];
        for (int k = 0; k < i; ++k) s -= G[i * M1 + k] * r[k];
        r[i] = s * G[i * M1 + i];
    }
    for (int i = mm - 1; i >= 0; --i) {
        double s = r[i];
        for (int k = i + 1; k < mm; ++k) s -= G[k * M1 + i] * r[k];
        r[i] = s * G[i * M1 + i];
        y[i] = r[i];
    }
    /* x = L^-T (u - Z y), column-oriented back substitution. */
    for (int i = 0; i < NQ; ++i) x[i] = Z[mm * NQ + i];
    for (int c = 0; c < mm; ++c) {
        const double *zc = Z + c * NQ, rc = r[c];
        for (int i = 0; i < NQ; ++i) x[i] -= zc[i] * rc;
    }
    for (int i = NQ - 1; i >= 0; --i) {
        const double xi = x[i] * L[i * NQ + i];
        x[i] = xi;
        for (int k = 0; k < i; ++k) x[k] -= L[i * NQ + k] * xi;
    }
    return 0;
lu:
    {
        double d[NQ], e[NCX];
        for (int i = 0; i < NQ; ++i) {
            double a = fabs(W[i * NQ + i]);
            d[i] = a > 0.0 ? 1.0 / sqrt(a) : 1.0;
        }
        for (int c = 0; c < mm; ++c) {
            double s = 0.0;
            for (int j = 0; j < NQ; ++j) { double t = mu[c * NQ + j] * d[j]; s += t * t; }
            e[c] = s > 0.0 ? 1.0 / sqrt(s) : 1.0;
        }
        return lu_solve(mm, W, mu, d, e, top, bottom, x, y);
    }
}

/* [[W, mu^T], [mu, 0]] [x; y] = [top; bottom] with the first mm rows of mu (row stride
   NQ), W symmetric: the constrained accelerations and the projections onto the
   constraints, by the null-space solve at every state (nhham.numerics.nullspace: free of
   the coordinates' units, to rounding at any mass ratio); without constraints the
   Cholesky solve of W (ksolve_saddle). Returns 0, or 1 when the matrix is singular. */
HOT int ksolve(int mm, const double *W, const double *mu, const double *top,
               const double *bottom, double *x, double *y) {
    if (mm == 0) return ksolve_saddle(0, W, mu, top, bottom, x, y);
    return nullspace_solve(mm, W, mu, top, bottom, x, y);
}
