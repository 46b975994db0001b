/* ---- nonholonomic RATTLE for constant W (see nhham.numerics.integrators) ---- */
#define NGEO (NQ * NQ + NC * NQ + NC + NH)

/* One step (q, v) -> (q1, v1) in place; lam: in = guess for lam0, out = lam1.
   Returns NHHAM_SUCCESS, NHHAM_NOT_CONVERGED (Newton failed), NHHAM_SINGULAR or
   NHHAM_NONFINITE. One function on purpose: the Newton iteration for lam0, the half
   kick and the end constraint share the step's arrays (on the stack), in the order of
   the equations of nhham.numerics.integrators' module docstring. */
static int rattle_step(double *q, double *v, double h, double *lam, const double *p,
                       const double *W, const double *Winv, double tol, int maxiter,
                       long *newton) {
    double geo[NGEO], y[2 * NQ], p0[NQ], Lq[NQ], base[NQ], qf[NQ], dq[NQ * NCX];
    double q1[NQ], qm[NQ], u[NQ], r[NCX], J[NCX * NCX], Jp[NCX * NQ], Jq[NCX * NQ];
    double mu0[NCX * NQ], mu1h[NCX * NQ], top[NQ], bot[NCX], v1[NQ], nu[NCX];
    geometry(q, p, geo);
    for (int i = 0; i < NC * NQ; ++i) mu0[i] = geo[NQ * NQ + i];
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int j = 0; j < NQ; ++j) s += W[i * NQ + j] * v[j];
        p0[i] = s; y[i] = q[i]; y[NQ + i] = v[i];
    }
    lagr_q(y, p, Lq);
    for (int i = 0; i < NQ; ++i) base[i] = p0[i] + 0.5 * h * Lq[i];
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int j = 0; j < NQ; ++j) s += Winv[i * NQ + j] * base[j];
        qf[i] = q[i] + h * s;
        for (int c = 0; c < NC; ++c) {
            double a = 0.0;
            for (int j = 0; j < NQ; ++j) a += Winv[i * NQ + j] * mu0[c * NQ + j];
            dq[i * NCX + c] = -0.5 * h * h * a;
        }
    }
    double best = INFINITY;
    int it = 0;
    for (;; ++it) {
        for (int i = 0; i < NQ; ++i) {
            double s = qf[i];
            for (int c = 0; c < NC; ++c) s += dq[i * NCX + c] * lam[c];
            q1[i] = s; qm[i] = 0.5 * (q[i] + s); u[i] = (s - q[i]) / h;
        }
        if (NC == 0) break;
        geometry(qm, p, geo);
        const double *mum = geo + NQ * NQ, *hm = mum + NC * NQ;
        /* Each row's residual relative to the size of its terms: u = (q1 - q)/h carries
           the round-off of q1, eps |q1| / |h|, which grows with the coordinates (an angle
           that has turned 1e4 times), so an absolute test would fail on long runs. */
        double err = 0.0, size[NCX];
        for (int c = 0; c < NC; ++c) {
            double s = hm[c], a = 1.0 + fabs(hm[c]);
            for (int j = 0; j < NQ; ++j) {
                s += mum[c * NQ + j] * u[j];
                a += fabs(mum[c * NQ + j]) * (fabs(u[j]) + fabs(q1[j]) / fabs(h));
            }
            r[c] = s;
            size[c] = a;
        }
        for (int c = 0; c < NC; ++c) for (int j = 0; j < NQ; ++j) Jq[c * NQ + j] = mum[c * NQ + j] / h;
        double yy[2 * NQ];
        for (int j = 0; j < NQ; ++j) { yy[j] = qm[j]; yy[NQ + j] = u[j]; }
        jphi(yy, p, Jp);
        for (int c = 0; c < NC; ++c) for (int j = 0; j < NQ; ++j) Jq[c * NQ + j] += 0.5 * Jp[c * NQ + j];
        if (NH > 0) {
            double geo1[NGEO];
            geometry(q1, p, geo1);
            const double *g1 = geo1 + NQ * NQ + NC * NQ + NC;
            for (int c = 0; c < NH; ++c) {
                r[c] = g1[c];
                size[c] = 1.0;
                for (int j = 0; j < NQ; ++j) {
                    Jq[c * NQ + j] = geo1[NQ * NQ + c * NQ + j];
                    size[c] += fabs(Jq[c * NQ + j] * q1[j]);
                }
            }
        }
        for (int c = 0; c < NC; ++c) if (fabs(r[c]) / size[c] > err) err = fabs(r[c]) / size[c];
        if (!(err == err)) return NHHAM_NONFINITE;
        if (err <= tol) break;
        if (it > 2 && err >= best) { if (err > 1e-9) return NHHAM_NOT_CONVERGED; break; }
        if (it >= maxiter) return NHHAM_NOT_CONVERGED;
        if (err < best) best = err;
        for (int c = 0; c < NC; ++c)
            for (int e = 0; e < NC; ++e) {
                double s = 0.0;
                for (int j = 0; j < NQ; ++j) s += Jq[c * NQ + j] * dq[j * NCX + e];
                J[c * NC + e] = s;
            }
        if (gsolve(NC, J, r)) return NHHAM_SINGULAR;
        for (int c = 0; c < NC; ++c) lam[c] -= r[c];
        ++*newton;
    }
    /* half kick with lam0, then the exact end constraint */
    double ph[NQ];
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int c = 0; c < NC; ++c) s += mu0[c * NQ + i] * lam[c];
        ph[i] = base[i] - 0.5 * h * s;
    }
    geometry(q1, p, geo);
    for (int i = 0; i < NC * NQ; ++i) mu1h[i] = geo[NQ * NQ + i];
    const double *h1 = geo + NQ * NQ + NC * NQ;
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int j = 0; j < NQ; ++j) s += Winv[i * NQ + j] * ph[j];
        y[i] = q1[i]; y[NQ + i] = s;
    }
    lagr_q(y, p, Lq);
    for (int i = 0; i < NQ; ++i) top[i] = ph[i] + 0.5 * h * Lq[i];
    for (int c = 0; c < NC; ++c) bot[c] = -h1[c];
    /* A velocity-level solve (the unknown v is O(1), its step increments are not): the
       null-space solve does not keep those increments better, and measured on a mass
       ratio of 1e16 kept them 3-10x worse; so the saddle solve, whatever W's diagonal
       (as RattleStepper.step). */
    if (ksolve_saddle(NC, W, mu1h, top, bot, v1, nu)) return NHHAM_SINGULAR;
    /* Iterative refinement of the constraint rows when their residual is above
       round-off (LU is only normwise backward stable: extreme mass ratios). */
    {
        double rr[NCX], zero[NQ], dv[NQ], dnu[NCX], big = 0.0, size = 0.0;
        for (int c = 0; c < NC; ++c) {
            double s = h1[c], a = fabs(h1[c]);
            for (int j = 0; j < NQ; ++j) { s += mu1h[c * NQ + j] * v1[j]; a += fabs(mu1h[c * NQ + j] * v1[j]); }
            rr[c] = -s;
            if (fabs(s) > big) big = fabs(s);
            if (a > size) size = a;
        }
        if (NC > 0 && big > 4.0 * 2.220446049250313e-16 * size) {
            for (int i = 0; i < NQ; ++i) zero[i] = 0.0;
            if (ksolve_saddle(NC, W, mu1h, zero, rr, dv, dnu)) return NHHAM_SINGULAR;
            for (int i = 0; i < NQ; ++i) v1[i] += dv[i];
            for (int c = 0; c < NC; ++c) nu[c] += dnu[c];
        }
    }
    for (int c = 0; c < NC; ++c) lam[c] = 2.0 * nu[c] / h;
    for (int i = 0; i < NQ; ++i) {
        q[i] = q1[i]; v[i] = v1[i];
        if (!isfinite(q[i]) || !isfinite(v[i]) || fabs(q[i]) > 1e150 || fabs(v[i]) > 1e150) return NHHAM_NONFINITE;
    }
    return NHHAM_SUCCESS;
}

/* Steps of size h from y (2n: q, v; updated in place) until info[0] = nsteps, a
   failure, or pause_s seconds of wall time; composition 0: RATTLE, 1: triple jump
   (order 4). Every stride-th step (counted from the start of the run) is stored in out
   (row-major, .. x 2n) until cap rows are there. lam: the multiplier guess carried from
   step to step; wsp: W and its inverse (2 n*n), computed when first is set (W is
   constant). info = [steps done, Newton iterations (both carried from call to call),
   rows stored by this call]. Returns NHHAM_SUCCESS (nsteps done), NHHAM_PAUSED (call
   again to go on) or the failure's status, with y the state after the last good step. */
int nhham_rattle(double *y, double h, long nsteps, long stride, int composition,
                 double *out, long cap, const double *pext, double *lam, double *wsp,
                 int first, double tol, int maxiter, double pause_s, long *info) {
    double *W = wsp, *Winv = wsp + NQ * NQ, geo[NGEO], q[NQ], v[NQ];
    const double wall_pause = wall_seconds() + pause_s;
    if (first) {
        geometry(y, pext, geo);
        for (int i = 0; i < NQ * NQ; ++i) W[i] = geo[i];
        for (int c = 0; c < NQ; ++c) {
            double A[NQ * NQ], e[NQ];
            for (int i = 0; i < NQ * NQ; ++i) A[i] = W[i];
            for (int i = 0; i < NQ; ++i) e[i] = (i == c);
            if (gsolve(NQ, A, e)) return NHHAM_SINGULAR;
            for (int i = 0; i < NQ; ++i) Winv[i * NQ + c] = e[i];
        }
    }
    const double g1 = 1.0 / (2.0 - cbrt(2.0)), g2 = 1.0 - 2.0 * g1;
    long newton = info[1];
    int status = NHHAM_SUCCESS, stepped = 0;
    info[2] = 0;
    while (info[0] < nsteps) {
        if (info[2] >= cap || (stepped && wall_seconds() >= wall_pause)) {
            status = NHHAM_PAUSED;
            break;
        }
        for (int i = 0; i < NQ; ++i) { q[i] = y[i]; v[i] = y[NQ + i]; }
        if (composition == 0) {
            status = rattle_step(q, v, h, lam, pext, W, Winv, tol, maxiter, &newton);
        } else {
            status = rattle_step(q, v, g1 * h, lam, pext, W, Winv, tol, maxiter, &newton);
            if (!status) status = rattle_step(q, v, g2 * h, lam, pext, W, Winv, tol, maxiter, &newton);
            if (!status) status = rattle_step(q, v, g1 * h, lam, pext, W, Winv, tol, maxiter, &newton);
        }
        if (status) break;
        for (int i = 0; i < NQ; ++i) { y[i] = q[i]; y[NQ + i] = v[i]; }
        ++info[0];
        stepped = 1;
        if (info[0] % stride == 0) {
            double *o = out + info[2] * 2 * NQ;
            for (int i = 0; i < 2 * NQ; ++i) o[i] = y[i];
            ++info[2];
        }
    }
    info[1] = newton;
    return status;
}
