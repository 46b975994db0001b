/* dy = (v, a), lam = multipliers, power = -lam . (mu v) (= dE/dt exactly).
   alpha2, beta2: Baumgarte terms (2 alpha, beta^2); zero for none.
   The saddle-point system is solved by ksolve (the null-space solve: the small
   accelerations to rounding at extreme mass ratios, in any units). Returns NHHAM_SUCCESS, NHHAM_SINGULAR or NHHAM_NONFINITE
   (the codes of nhham.numerics.status.Status). */
static int rhs_one(const double *y, const double *p, double alpha2, double beta2,
                   double *dy, double *lam, double *power) {
    double out[NOUT > 0 ? NOUT : 1], bot[NCX], muv[NCX];
    saddle(y, p, out);
    const double *W = out, *F = out + NQ * NQ, *mu = F + NQ, *drift = mu + NC * NQ;
    const double *h = drift + NC, *g = h + NC;
    const double *v = y + NQ;
    for (int c = 0; c < NC; ++c) {
        double mv = 0.0;
        for (int j = 0; j < NQ; ++j) mv += mu[c * NQ + j] * v[j];
        muv[c] = mv;
        double rhs = -drift[c];
        if (alpha2 != 0.0) rhs -= alpha2 * (mv + h[c]);
        if (beta2 != 0.0 && c < NH) rhs -= beta2 * g[c];
        bot[c] = rhs;
    }
    (void)h; (void)g;
    if (ksolve(NC, W, mu, F, bot, dy + NQ, lam)) return NHHAM_SINGULAR;
    double pw = 0.0;
    for (int i = 0; i < NQ; ++i) dy[i] = v[i];
    for (int c = 0; c < NC; ++c) pw -= lam[c] * muv[c];
#ifdef NHHAM_FORCED
    pw += out[NHHAM_FORCED];           /* the applied power Q . v */
#endif
    *power = pw;
    for (int i = 0; i < 2 * NQ; ++i) if (!isfinite(dy[i])) return NHHAM_NONFINITE;
    return NHHAM_SUCCESS;
}

/* pext = [parameters..., 2 alpha, beta^2]; out = [dy (2n), lam (m), power]. */
int nhham_rhs(const double *y, double *out, const double *pext) {
    return rhs_one(y, pext, pext[NPAR], pext[NPAR + 1], out, out + 2 * NQ, out + 2 * NQ + NC);
}

/* k states in Y (k x 2n row-major), OUT (k x NRES); returns the number of failed states. */
int nhham_rhs_batch(int k, const double *Y, double *OUT, const double *pext) {
    int bad = 0;
    for (int s = 0; s < k; ++s) {
        double *o = OUT + (long)s * NRES;
        bad += rhs_one(Y + (long)s * 2 * NQ, pext, pext[NPAR], pext[NPAR + 1],
                       o, o + 2 * NQ, o + 2 * NQ + NC) != 0;
    }
    return bad;
}
