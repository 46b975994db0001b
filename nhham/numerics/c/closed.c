/* Closed-form path: accelerations and multipliers of the symbolic P(xi_L). */
static int closed_one(const double *y, const double *p, double *o) {
    double out[NQ + NC];
    closed(y, p, out);
    for (int i = 0; i < NQ; ++i) { o[i] = y[NQ + i]; o[NQ + i] = out[i]; }
    for (int c = 0; c < NC; ++c) o[2 * NQ + c] = out[NQ + c];
    o[2 * NQ + NC] = 0.0;  /* power is computed by the caller */
    for (int i = 0; i < 2 * NQ; ++i) if (!isfinite(o[i])) return NHHAM_NONFINITE;
    return NHHAM_SUCCESS;
}

int nhham_closed(const double *y, double *out, const double *pext) {
    return closed_one(y, pext, out);
}

int nhham_closed_batch(int k, const double *Y, double *OUT, const double *pext) {
    int bad = 0;
    for (int s = 0; s < k; ++s)
        bad += closed_one(Y + (long)s * 2 * NQ, pext, OUT + (long)s * NRES) != 0;
    return bad;
}
