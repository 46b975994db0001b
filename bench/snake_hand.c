/* The N-link snake's right-hand side written by hand in C (bench/rhs.py).

   An independent, hand-fused baseline for nhham's generated code: the same
   system as nhham.models.snake (N links of mass m, length l, a knife edge at
   every link centre; q = (x, y, theta_1..theta_N)), derived by hand from the
   link Jacobians instead of from the Lagrangian:

     c_i = (x, y) + (l/2) sum_j k_ij e(theta_j),  e = (cos, sin), e' = (-sin, cos)
     W   = sum_i m J_i^T J_i + diag(0, 0, m l^2/12, ...),  J_i = d c_i / dq
     F   = -sum_i m J_i^T (dJ_i/dt v)      (centripetal terms; L is kinetic only)
     mu_i v = e'(theta_i) . c_i'            (no sideways slip at link i)
     drift_i = -theta_i' e(theta_i) . c_i' + e'(theta_i) . (dJ_i/dt v)

   One pass over the links (O(N) for velocities and centripetal terms, O(N^2)
   for W and mu, one sincos per angle), then the saddle-point system
   [[W, mu^T], [mu, 0]] [a; lambda] = [F; -drift] by Cholesky of W and of the
   Schur complement mu W^-1 mu^T: the best dense method for this structure.
   Compile with -DNL=<links>. */
#include <math.h>

#define NQ (NL + 2)
#define NC NL

static double Kw[NL][NL];   /* k_ij */
static double Ksum[NL];     /* K_j = sum_i k_ij */
static double Sjk[NL][NL];  /* S_jk = sum_i k_ij k_ik */
static int ready = 0;

static void tables(void) {
    for (int i = 0; i < NL; ++i)
        for (int j = 0; j < NL; ++j) Kw[i][j] = 0.0;
    for (int i = 1; i < NL; ++i) {
        for (int j = 0; j < NL; ++j) Kw[i][j] = Kw[i - 1][j];
        Kw[i][i - 1] += 1.0;
        Kw[i][i] += 1.0;
    }
    for (int j = 0; j < NL; ++j) {
        Ksum[j] = 0.0;
        for (int i = 0; i < NL; ++i) Ksum[j] += Kw[i][j];
        for (int k = 0; k < NL; ++k) {
            Sjk[j][k] = 0.0;
            for (int i = 0; i < NL; ++i) Sjk[j][k] += Kw[i][j] * Kw[i][k];
        }
    }
    ready = 1;
}

/* y = (q, v), p = (m, l); out = (v, a) (2 NQ). Returns 0, or 1 if not SPD. */
static int hand_one(const double *y, const double *p, double *out) {
    const double m = p[0], l = p[1], hl = 0.5 * l;
    const double *th = y + 2, *v = y + NQ, *w = y + NQ + 2;
    double s[NL], c[NL], W[NQ * NQ], F[NQ], mu[NC * NQ], b[NC];
    double Px[NL], Py[NL], Qx[NL], Qy[NL];
    for (int j = 0; j < NL; ++j) { s[j] = sin(th[j]); c[j] = cos(th[j]); }
    /* P_i = sum_j k_ij w_j e'(theta_j), Q_i = sum_j k_ij w_j^2 e(theta_j), by recursion */
    Px[0] = Py[0] = Qx[0] = Qy[0] = 0.0;
    for (int i = 1; i < NL; ++i) {
        const double a0 = w[i - 1], a1 = w[i];
        Px[i] = Px[i - 1] - a0 * s[i - 1] - a1 * s[i];
        Py[i] = Py[i - 1] + a0 * c[i - 1] + a1 * c[i];
        Qx[i] = Qx[i - 1] + a0 * a0 * c[i - 1] + a1 * a1 * c[i];
        Qy[i] = Qy[i - 1] + a0 * a0 * s[i - 1] + a1 * a1 * s[i];
    }
    /* W */
    const double mh = m * hl, ml4 = m * hl * hl, I = m * l * l / 12.0;
    W[0] = W[NQ + 1] = NL * m;
    W[1] = W[NQ] = 0.0;
    for (int j = 0; j < NL; ++j) {
        const double wx = -mh * Ksum[j] * s[j], wy = mh * Ksum[j] * c[j];
        W[2 + j] = W[(2 + j) * NQ] = wx;
        W[NQ + 2 + j] = W[(2 + j) * NQ + 1] = wy;
        for (int k = 0; k <= j; ++k) {
            double t = ml4 * Sjk[j][k] * (c[j] * c[k] + s[j] * s[k]);
            if (k == j) t += I;
            W[(2 + j) * NQ + 2 + k] = W[(2 + k) * NQ + 2 + j] = t;
        }
    }
    /* F = -sum_i m J_i^T (dJ_i/dt v), dJ_i/dt v = -hl Q_i */
    double sx = 0.0, sy = 0.0;
    for (int i = 0; i < NL; ++i) { sx += Qx[i]; sy += Qy[i]; }
    F[0] = mh * sx;
    F[1] = mh * sy;
    for (int j = 0; j < NL; ++j) {
        double acc = 0.0;
        for (int i = j; i < NL; ++i) acc += Kw[i][j] * (-s[j] * Qx[i] + c[j] * Qy[i]);
        F[2 + j] = ml4 * acc;
    }
    /* mu and the right-hand side -drift */
    for (int i = 0; i < NC; ++i) {
        double *r = mu + i * NQ;
        r[0] = -s[i];
        r[1] = c[i];
        for (int j = 0; j < NL; ++j) r[2 + j] = hl * Kw[i][j] * (c[i] * c[j] + s[i] * s[j]);
        const double vx = v[0] + hl * Px[i], vy = v[1] + hl * Py[i];
        const double drift = -w[i] * (c[i] * vx + s[i] * vy) - hl * (-s[i] * Qx[i] + c[i] * Qy[i]);
        b[i] = -drift;
    }
    /* Cholesky W = L L^T (diagonal of L holds 1 / L_jj) */
    double L[NQ * NQ], Z[(NC + 1) * NQ], G[(NC + 1) * (NC + 1)], r[NC], x[NQ];
    for (int j = 0; j < NQ; ++j) {
        double t = W[j * NQ + j];
        for (int k = 0; k < j; ++k) t -= L[j * NQ + k] * L[j * NQ + k];
        if (!(t > 0.0)) return 1;
        const double inv = 1.0 / sqrt(t);
        L[j * NQ + j] = inv;
        for (int i = j + 1; i < NQ; ++i) {
            double u = W[i * NQ + j];
            for (int k = 0; k < j; ++k) u -= L[i * NQ + k] * L[j * NQ + k];
            L[i * NQ + j] = u * inv;
        }
    }
    /* [Z | u] = L^-1 [mu^T | F] */
    for (int col = 0; col <= NC; ++col) {
        double *z = Z + col * NQ;
        const double *rhs = col < NC ? mu + col * NQ : F;
        for (int i = 0; i < NQ; ++i) {
            double t = rhs[i];
            for (int k = 0; k < i; ++k) t -= L[i * NQ + k] * z[k];
            z[i] = t * L[i * NQ + i];
        }
    }
    /* S = Z^T Z, Z^T u; Cholesky of S; S lambda = Z^T u - b */
    for (int i = 0; i <= NC; ++i)
        for (int k = 0; k <= i && k < NC; ++k) {
            double t = 0.0;
            for (int j = 0; j < NQ; ++j) t += Z[i * NQ + j] * Z[k * NQ + j];
            G[i * (NC + 1) + k] = t;
        }
    for (int j = 0; j < NC; ++j) {
        double t = G[j * (NC + 1) + j];
        for (int k = 0; k < j; ++k) t -= G[j * (NC + 1) + k] * G[j * (NC + 1) + k];
        if (!(t > 0.0)) return 1;
        const double inv = 1.0 / sqrt(t);
        G[j * (NC + 1) + j] = inv;
        for (int i = j + 1; i < NC; ++i) {
            double u = G[i * (NC + 1) + j];
            for (int k = 0; k < j; ++k) u -= G[i * (NC + 1) + k] * G[j * (NC + 1) + k];
            G[i * (NC + 1) + j] = u * inv;
        }
    }
    for (int i = 0; i < NC; ++i) {
        double t = G[NC * (NC + 1) + i] - b[i];
        for (int k = 0; k < i; ++k) t -= G[i * (NC + 1) + k] * r[k];
        r[i] = t * G[i * (NC + 1) + i];
    }
    for (int i = NC - 1; i >= 0; --i) {
        double t = r[i];
        for (int k = i + 1; k < NC; ++k) t -= G[k * (NC + 1) + i] * r[k];
        r[i] = t * G[i * (NC + 1) + i];
    }
    /* a = L^-T (u - Z lambda) */
    for (int i = 0; i < NQ; ++i) x[i] = Z[NC * NQ + i];
    for (int col = 0; col < NC; ++col)
        for (int i = 0; i < NQ; ++i) x[i] -= Z[col * NQ + i] * r[col];
    for (int i = NQ - 1; i >= 0; --i) {
        const double xi = x[i] * L[i * NQ + i];
        x[i] = xi;
        for (int k = 0; k < i; ++k) x[k] -= L[i * NQ + k] * xi;
    }
    for (int i = 0; i < NQ; ++i) { out[i] = v[i]; out[NQ + i] = x[i]; }
    return 0;
}

int hand_rhs(const double *y, double *out, const double *p) {
    if (!ready) tables();
    return hand_one(y, p, out);
}

int hand_rhs_batch(int k, const double *Y, double *OUT, const double *p) {
    if (!ready) tables();
    int bad = 0;
    for (int s = 0; s < k; ++s) bad += hand_one(Y + (long)s * 2 * NQ, p, OUT + (long)s * 2 * NQ);
    return bad;
}
