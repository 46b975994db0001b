/* ---- projection onto M_1 and the explicit Runge-Kutta loop ---- */
#define NZ (2 * NQ + 1)   /* state and the work of the forces (constraint, applied) */
#define SEXT 16           /* DOP853 stages with the dense-output extras */

/* z (q, v) onto M_1 exactly as NumericModel.project: Newton iterations for the
   holonomic rows (the step of least kinetic length), then the velocities in
   the kinetic metric (one solve and one refinement). NHHAM_SUCCESS, NHHAM_SINGULAR or
   NHHAM_NOT_CONVERGED (Newton did not converge). */
static int project_state(double *z, const double *p, double tol, int maxiter) {
    double geo[NGEO], zero[NQ], dq[NQ], lam[NCX], r[NCX];
    double *q = z, *v = z + NQ;
    for (int i = 0; i < NQ; ++i) zero[i] = 0.0;
    if (NH > 0) {
        double best = INFINITY;
        int done = 0;
        for (int it = 1; it <= maxiter; ++it) {
            geometry(q, p, geo);
            const double *g = geo + NQ * NQ + NC * NQ + NC;
            double err = 0.0, scale = 0.0;
            for (int c = 0; c < NH; ++c) if (fabs(g[c]) > err) err = fabs(g[c]);
            for (int i = 0; i < NQ; ++i) if (fabs(q[i]) > scale) scale = fabs(q[i]);
            if (err <= tol * (1.0 + scale)) { done = 1; break; }
            if (it > 3 && err >= best) break;
            if (err < best) best = err;
            for (int c = 0; c < NH; ++c) r[c] = -g[c];
            if (ksolve(NH, geo, geo + NQ * NQ, zero, r, dq, lam)) return NHHAM_SINGULAR;
            for (int i = 0; i < NQ; ++i) q[i] += dq[i];
        }
        if (!done) {
            geometry(q, p, geo);
            const double *g = geo + NQ * NQ + NC * NQ + NC;
            double err = 0.0, scale = 0.0;
            for (int c = 0; c < NH; ++c) if (fabs(g[c]) > err) err = fabs(g[c]);
            for (int i = 0; i < NQ; ++i) if (fabs(q[i]) > scale) scale = fabs(q[i]);
            if (!(err <= fmax(tol, 1e-12) * (1.0 + scale))) return NHHAM_NOT_CONVERGED;
        }
    }
#ifdef NHHAM_GEOMETRY_V
    /* A nonlinear (Chetaev) constraint: mu = d phi/d v and h = phi - mu v read v (the
       geometry kernel reads z = (q, v)), so the metric step is a Newton step, repeated
       until phi stops decreasing (as nhham.numerics.chetaev.velocities_newton). */
    double best_v = INFINITY;
    for (int pass = 0; pass < maxiter && NC > 0; ++pass) {
        geometry(z, p, geo);
        const double *W = geo, *mu = geo + NQ * NQ, *h = mu + NC * NQ;
        double err = 0.0;
        for (int c = 0; c < NC; ++c) {
            double s = 0.0;
            for (int j = 0; j < NQ; ++j) s += mu[c * NQ + j] * v[j];
            r[c] = -(s + h[c]);
            if (fabs(r[c]) > err) err = fabs(r[c]);
        }
        if (err == 0.0 || err >= best_v) break;
        best_v = err;
        if (ksolve(NC, W, mu, zero, r, dq, lam)) return NHHAM_SINGULAR;
        for (int i = 0; i < NQ; ++i) v[i] += dq[i];
    }
#else
    geometry(q, p, geo);
    const double *W = geo, *mu = geo + NQ * NQ, *h = mu + NC * NQ;
    for (int pass = 0; pass < 2 && NC > 0; ++pass) {
        int any = 0;
        for (int c = 0; c < NC; ++c) {
            double s = 0.0;
            for (int j = 0; j < NQ; ++j) s += mu[c * NQ + j] * v[j];
            r[c] = -(s + h[c]);
            any |= r[c] != 0.0;
        }
        if (!any) break;
        if (ksolve(NC, W, mu, zero, r, dq, lam)) return NHHAM_SINGULAR;
        for (int i = 0; i < NQ; ++i) v[i] += dq[i];
    }
#endif
    for (int i = 0; i < 2 * NQ; ++i) if (!isfinite(z[i])) return NHHAM_NOT_CONVERGED;
    return NHHAM_SUCCESS;
}

/* project_state onto M_1 at the time t: a time-dependent constraint reads t from its
   parameter slot. */
static int project_at(double *z, const double *pext, double t, double tol, int maxiter) {
#ifdef NHHAM_TIME_SLOT
    double pt[NPAR + 2];
    for (int i = 0; i < NPAR + 2; ++i) pt[i] = pext[i];
    pt[NHHAM_TIME_SLOT] = t;
    return project_state(z, pt, tol, maxiter);
#else
    (void)t;
    return project_state(z, pext, tol, maxiter);
#endif
}

/* f = (dy, power) at z; on failure the time and state go to fail. */
static int erk_field(const double *z, double t, const double *pext, double *f, long *nfev,
                     double *fail) {
    double lam[NCX];
    ++*nfev;
#ifdef NHHAM_TIME_SLOT
    /* a time-dependent force reads t from its parameter slot */
    double pt[NPAR + 2];
    for (int i = 0; i < NPAR + 2; ++i) pt[i] = pext[i];
    pt[NHHAM_TIME_SLOT] = t;
    int st = rhs_one(z, pt, pt[NPAR], pt[NPAR + 1], f, lam, f + 2 * NQ);
#else
    int st = rhs_one(z, pext, pext[NPAR], pext[NPAR + 1], f, lam, f + 2 * NQ);
#endif
    if (!st) return NHHAM_SUCCESS;
    fail[0] = t;
    for (int i = 0; i < NZ; ++i) fail[1 + i] = z[i];
    return st;
}

/* Dense output at t_old + x h (scipy's RkDenseOutput / Dop853DenseOutput). */
static void erk_dense(int dop, int s, int np_, const double *K, const double *P,
                      const double *F, const double *zold, double h, double x, double *zd) {
    if (dop) {
        for (int i = 0; i < NZ; ++i) {
            double y = 0.0;
            for (int j = 6; j >= 0; --j) {
                y += F[j * NZ + i];
                y *= ((6 - j) % 2 == 0) ? x : 1.0 - x;
            }
            zd[i] = y + zold[i];
        }
    } else {
        for (int i = 0; i < NZ; ++i) {
            double y = 0.0, pw = 1.0;
            for (int c = 0; c < np_; ++c) {
                double qc = 0.0;
                for (int k = 0; k <= s; ++k) qc += K[k * NZ + i] * P[k * np_ + c];
                pw *= x;
                y += qc * pw;
            }
            zd[i] = h * y + zold[i];
        }
    }
}

/* scipy's RK23 / RK45 / DOP853 (RungeKutta._step_impl, select_initial_step,
   the error norms and the dense output) with the compiled field, projection
   onto M_1 after every step (and at the dense points) and the storage of the
   steps or of the t_eval points, all in one call.

   info = [stages s, dop853?, columns of P, error estimator order, first call?]
   tab = A (s x s), B (s), C (s), E (s+1; E5 for DOP853), E3 (s+1), P ((s+1) x np),
         A_EXTRA (3 x 16), C_EXTRA (3), D (4 x 16)
   st = [t, h_abs, z (NZ), f (NZ)]: the state carried from call to call
        (h_abs <= 0 on the first call: select the initial step).
   Without t_eval every stride-th step (counted from the start of the run) is stored,
   until the buffer (cap rows) is full.
   Returns NHHAM_SUCCESS (t_bound reached), NHHAM_PAUSED (pause_s seconds of wall time
   passed, or the step buffer is full: call again to go on), NHHAM_STEP_FAILED (step size too small), NHHAM_NONFINITE
   (non-finite or overflowing state or field), NHHAM_SINGULAR (singular saddle
   matrix, or singular matrix in the projection), NHHAM_NOT_CONVERGED (projection
   failed). A failure of the field (not of the projection or the state) also
   writes its time and state to `fail`, whose time is NaN until then.
   Long on purpose: it follows scipy's RungeKutta step by step (initial step, stages,
   error norm, step-size control, dense output) so that the two can be compared line by
   line, and keeps the stage buffers on this function's stack. */
int nhham_erk(const int *info, const double *tab, double *st, double t_bound, double rtol,
              const double *atol, double max_step, int projection, double proj_tol,
              int proj_maxiter, const double *t_eval, long n_eval, long *i_eval,
              double *out_t, double *out_z, long cap, long *nout, long stride,
              double pause_s, const double *pext, long *counts, double *fail) {
    const int s = info[0], dop = info[1], np_ = info[2];
    const double err_exp = -1.0 / (info[3] + 1);
    const double *A = tab, *B = A + s * s, *C = B + s, *E = C + s, *E3 = E + s + 1;
    const double *P = E3 + s + 1, *Aext = P + (s + 1) * np_, *Cext = Aext + 3 * SEXT;
    const double *D = Cext + 3;
    double K[SEXT * NZ], F[7 * NZ], znew[NZ], zold[NZ], ztmp[NZ], scale[NZ];
    double *t = st, *habs = st + 1, *z = st + 2, *f = st + 2 + NZ;
    long *nfev = counts, *nsteps = counts + 1;
    const double dir = t_bound >= *t ? 1.0 : -1.0;
    const double wall_pause = wall_seconds() + pause_s;
    int status, stepped = 0;
    if (info[4]) {
        if ((status = erk_field(z, *t, pext, f, nfev, fail))) return status;
        if (!(*habs > 0.0)) {  /* select_initial_step */
            double interval = fabs(t_bound - *t), d0 = 0.0, d1 = 0.0, d2 = 0.0, h0, h1;
            if (interval == 0.0) {
                *habs = 0.0;
            } else {
                for (int i = 0; i < NZ; ++i) {
                    scale[i] = atol[i] + fabs(z[i]) * rtol;
                    d0 += (z[i] / scale[i]) * (z[i] / scale[i]);
                    d1 += (f[i] / scale[i]) * (f[i] / scale[i]);
                }
                d0 = sqrt(d0 / NZ); d1 = sqrt(d1 / NZ);
                h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
                if (h0 > interval) h0 = interval;
                for (int i = 0; i < NZ; ++i) ztmp[i] = z[i] + h0 * dir * f[i];
                if ((status = erk_field(ztmp, *t + h0 * dir, pext, K, nfev, fail))) return status;
                for (int i = 0; i < NZ; ++i) {
                    double e = (K[i] - f[i]) / scale[i];
                    d2 += e * e;
                }
                d2 = sqrt(d2 / NZ) / h0;
                if (d1 <= 1e-15 && d2 <= 1e-15) h1 = fmax(1e-6, h0 * 1e-3);
                else h1 = pow(0.01 / fmax(d1, d2), 1.0 / (info[3] + 1));
                double hh = 100 * h0;
                if (h1 < hh) hh = h1;
                if (interval < hh) hh = interval;
                if (max_step < hh) hh = max_step;
                *habs = hh;
            }
        }
    }
    for (;;) {
        if (*t == t_bound) return NHHAM_SUCCESS;
        if (n_eval == 0 && *nout >= cap) return NHHAM_PAUSED;
        if (stepped && wall_seconds() >= wall_pause) return NHHAM_PAUSED;
        stepped = 1;
        const double t0 = *t;
        const double min_step = 10.0 * fabs(nextafter(t0, dir * INFINITY) - t0);
        double h_abs = *habs > max_step ? max_step : (*habs < min_step ? min_step : *habs);
        double h, t_new;
        int rejected = 0;
        for (;;) {
            if (h_abs < min_step) return NHHAM_STEP_FAILED;
            h = h_abs * dir;
            t_new = t0 + h;
            if (dir * (t_new - t_bound) > 0.0) t_new = t_bound;
            h = t_new - t0;
            h_abs = fabs(h);
            for (int i = 0; i < NZ; ++i) K[i] = f[i];
            for (int j = 1; j < s; ++j) {
                for (int i = 0; i < NZ; ++i) {
                    double acc = 0.0;
                    for (int k = 0; k < j; ++k) acc += K[k * NZ + i] * A[j * s + k];
                    ztmp[i] = z[i] + acc * h;
                }
                if ((status = erk_field(ztmp, t0 + C[j] * h, pext, K + j * NZ, nfev, fail)))
                    return status;
            }
            for (int i = 0; i < NZ; ++i) {
                double acc = 0.0;
                for (int k = 0; k < s; ++k) acc += K[k * NZ + i] * B[k];
                znew[i] = z[i] + h * acc;
            }
            if ((status = erk_field(znew, t0 + h, pext, K + s * NZ, nfev, fail))) return status;
            double errn;
            if (dop) {
                double e5 = 0.0, e3 = 0.0;
                for (int i = 0; i < NZ; ++i) {
                    double a5 = 0.0, a3 = 0.0;
                    for (int k = 0; k <= s; ++k) { a5 += K[k * NZ + i] * E[k]; a3 += K[k * NZ + i] * E3[k]; }
                    double sc = atol[i] + fmax(fabs(z[i]), fabs(znew[i])) * rtol;
                    a5 /= sc; a3 /= sc;
                    e5 += a5 * a5; e3 += a3 * a3;
                }
                errn = (e5 == 0.0 && e3 == 0.0) ? 0.0 : h_abs * e5 / sqrt((e5 + 0.01 * e3) * NZ);
            } else {
                double e = 0.0;
                for (int i = 0; i < NZ; ++i) {
                    double a = 0.0;
                    for (int k = 0; k <= s; ++k) a += K[k * NZ + i] * E[k];
                    a = a * h / (atol[i] + fmax(fabs(z[i]), fabs(znew[i])) * rtol);
                    e += a * a;
                }
                errn = sqrt(e / NZ);
            }
            if (errn < 1.0) {
                double factor = errn == 0.0 ? 10.0 : fmin(10.0, 0.9 * pow(errn, err_exp));
                if (rejected) factor = fmin(1.0, factor);
                h_abs *= factor;
                break;
            }
            h_abs *= fmax(0.2, 0.9 * pow(errn, err_exp));
            rejected = 1;
        }
        for (int i = 0; i < NZ; ++i) { zold[i] = z[i]; z[i] = znew[i]; f[i] = K[s * NZ + i]; }
        *t = t_new;
        *habs = h_abs;
        ++*nsteps;
        for (int i = 0; i < 2 * NQ; ++i) if (!isfinite(z[i]) || fabs(z[i]) > 1e150) return NHHAM_NONFINITE;
        if (projection) {
            if ((status = project_at(z, pext, *t, proj_tol, proj_maxiter))) return status;
            if ((status = erk_field(z, *t, pext, f, nfev, fail))) return status;
        }
        if (n_eval == 0) {
            if (*nsteps % stride != 0) continue;
            out_t[*nout] = *t;
            for (int i = 0; i < NZ; ++i) out_z[*nout * NZ + i] = z[i];
            ++*nout;
            continue;
        }
        int ready = 0;
        while (*i_eval < n_eval && (dir > 0 ? t_eval[*i_eval] <= *t : t_eval[*i_eval] >= *t)) {
            if (!ready) {
                ready = 1;
                if (dop) {
                    for (int j = s + 1; j < SEXT; ++j) {
                        const double *a = Aext + (j - s - 1) * SEXT;
                        for (int i = 0; i < NZ; ++i) {
                            double acc = 0.0;
                            for (int k = 0; k < j; ++k) acc += K[k * NZ + i] * a[k];
                            ztmp[i] = zold[i] + acc * h;
                        }
                        if ((status = erk_field(ztmp, t0 + Cext[j - s - 1] * h, pext,
                                                K + j * NZ, nfev, fail))) return status;
                    }
                    for (int i = 0; i < NZ; ++i) {
                        double dz = z[i] - zold[i];
                        F[i] = dz;
                        F[NZ + i] = h * K[i] - dz;
                        F[2 * NZ + i] = 2.0 * dz - h * (f[i] + K[i]);
                        for (int r = 0; r < 4; ++r) {
                            double acc = 0.0;
                            for (int k = 0; k < SEXT; ++k) acc += D[r * SEXT + k] * K[k * NZ + i];
                            F[(3 + r) * NZ + i] = h * acc;
                        }
                    }
                }
            }
            double *o = out_z + *nout * NZ;
            erk_dense(dop, s, np_, K, P, F, zold, h, (t_eval[*i_eval] - t0) / h, o);
            if (projection && (status = project_at(o, pext, t_eval[*i_eval], proj_tol,
                                                   proj_maxiter)))
                return status;
            out_t[*nout] = t_eval[*i_eval];
            ++*nout;
            ++*i_eval;
        }
    }
}
