/* ---- nonholonomic RATTLE (see nhham.numerics.integrators): constant W and W(q) ---- */
#define NGEO (NQ * NQ + NC * NQ + NC + NH)
#define NZG (2 * NQ + NC)       /* the unknowns (p_h, q1, lam0) of a step with W(q) */

/* The end of a step, whatever W: the second half kick and the exact end constraint,
       W1 v1 + (h/2) mu1^T lam1 = p_h + (h/2) L_q(q1, u1),   mu1 v1 = -h1,
   with u1 = W1^-1 p_h and geo1 = geometry(q1) (W1, mu1, h1, g1). Writes (q1, v1) into
   (q, v) and lam1 into lam. Returns NHHAM_SUCCESS, NHHAM_SINGULAR or NHHAM_NONFINITE. */
static int rattle_finish(double *q, double *v, const double *q1, const double *ph,
                         const double *u1, double h, double *lam, const double *p,
                         const double *W1, const double *geo1) {
    double y[2 * NQ], Lq[NQ], top[NQ], bot[NCX], v1[NQ], nu[NCX];
    const double *mu1 = geo1 + NQ * NQ, *h1 = mu1 + NC * NQ;
    for (int i = 0; i < NQ; ++i) { y[i] = q1[i]; y[NQ + i] = u1[i]; }
    lagr_q(y, p, Lq);
    for (int i = 0; i < NQ; ++i) top[i] = ph[i] + 0.5 * h * Lq[i];
    for (int c = 0; c < NC; ++c) bot[c] = -h1[c];
    /* A velocity-level solve (the unknown v is O(1), its step increments are not): the
       null-space solve does not keep those increments better, and measured on a mass
       ratio of 1e16 kept them 3-10x worse; so the saddle solve, whatever W's diagonal
       (as RattleStepper.step). */
    if (ksolve_saddle(NC, W1, mu1, top, bot, v1, nu)) return NHHAM_SINGULAR;
    /* Iterative refinement of the constraint rows when their residual is above
       round-off (LU is only normwise backward stable: extreme mass ratios). */
    {
        double rr[NCX], zero[NQ], dv[NQ], dnu[NCX], big = 0.0, size = 0.0;
        for (int c = 0; c < NC; ++c) {
            double s = h1[c], a = fabs(h1[c]);
            for (int j = 0; j < NQ; ++j) { s += mu1[c * NQ + j] * v1[j]; a += fabs(mu1[c * NQ + j] * v1[j]); }
            rr[c] = -s;
            if (fabs(s) > big) big = fabs(s);
            if (a > size) size = a;
        }
        if (NC > 0 && big > 4.0 * 2.220446049250313e-16 * size) {
            for (int i = 0; i < NQ; ++i) zero[i] = 0.0;
            if (ksolve_saddle(NC, W1, mu1, zero, rr, dv, dnu)) return NHHAM_SINGULAR;
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

/* One step (q, v) -> (q1, v1) in place for constant W (W and its inverse given); lam:
   in = guess for lam0, out = lam1. Returns NHHAM_SUCCESS, NHHAM_NOT_CONVERGED (Newton
   failed), NHHAM_SINGULAR or NHHAM_NONFINITE. Newton's method for lam0 alone (q1 is
   affine in it; analytic Jacobian), then rattle_finish: the equations of
   nhham.numerics.integrators' module docstring, as _RattleStepper._step_constant. */
static int rattle_step(double *q, double *v, double h, double *lam, const double *p,
                       const double *W, const double *Winv, double tol, int maxiter,
                       long *newton) {
    double geo[NGEO], y[2 * NQ], p0[NQ], Lq[NQ], base[NQ], qf[NQ], dq[NQ * NCX];
    double q1[NQ], qm[NQ], u[NQ], r[NCX], J[NCX * NCX], Jp[NCX * NQ], Jq[NCX * NQ];
    double mu0[NCX * NQ];
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
        if (gsolve(NC, J, r, 0.0)) return NHHAM_SINGULAR;
        for (int c = 0; c < NC; ++c) lam[c] -= r[c];
        ++*newton;
    }
    /* half kick with lam0, then the exact end constraint */
    double ph[NQ], u1[NQ];
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int c = 0; c < NC; ++c) s += mu0[c * NQ + i] * lam[c];
        ph[i] = base[i] - 0.5 * h * s;
    }
    geometry(q1, p, geo);
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int j = 0; j < NQ; ++j) s += Winv[i * NQ + j] * ph[j];
        u1[i] = s;
    }
    return rattle_finish(q, v, q1, ph, u1, h, lam, p, W, geo);
}

/* ---- W(q): Newton's method on z = (p_h, q1, lam0), as _RattleStepper._step_general ---- */

/* What the residual of a step with W(q) needs from the step's start. */
typedef struct {
    double q0[NQ], p0[NQ], W0[NQ * NQ], mu0[NCX * NQ], h;
    const double *p;
} rattle_start;

/* x = W^-1 b (W is copied: gsolve works in place). Returns 1 when W is singular. */
static int wsolve(const double *W, const double *b, double *x) {
    double A[NQ * NQ];
    for (int i = 0; i < NQ * NQ; ++i) A[i] = W[i];
    for (int i = 0; i < NQ; ++i) x[i] = b[i];
    return gsolve(NQ, A, x, 0.0);
}

/* The pieces of the residual at z = (p_h, q1, lam0): what depends on p_h (u0 = W0^-1
   p_h, L_q(q0, u0)), on q1 (geometry at q1 and at qm = (q0 + q1)/2), on both (u1 =
   W(q1)^-1 p_h); none depends on lam0. A column of the Jacobian recomputes only the
   pieces its unknown enters (the same operations on the same numbers as the whole
   residual, so the same bits): n calls of lagr_q and 2n of geometry a Jacobian instead
   of 3 (2n + m) kernel calls. */
typedef struct {
    double U0[NQ], Lq0[NQ], U1[NQ], geo1[NGEO], geom[NGEO];
} rattle_parts;

static int parts_of_p(const rattle_start *s, const double *z, rattle_parts *pt) {
    double y[2 * NQ];
    if (wsolve(s->W0, z, pt->U0)) return 1;
    for (int i = 0; i < NQ; ++i) { y[i] = s->q0[i]; y[NQ + i] = pt->U0[i]; }
    lagr_q(y, s->p, pt->Lq0);
    return 0;
}

static void parts_of_q(const rattle_start *s, const double *z, rattle_parts *pt) {
    double qm[NQ];
    geometry(z + NQ, s->p, pt->geo1);
    for (int i = 0; i < NQ; ++i) qm[i] = 0.5 * (s->q0[i] + z[NQ + i]);
    if (NC > 0) geometry(qm, s->p, pt->geom);
}

/* The residuals r (2n + m) of the step's equations at z from its pieces:
     p_h - p0 - h/2 [L_q(q0, W0^-1 p_h) - mu0^T lam0],
     q1 - q0 - h/2 [W0^-1 + W(q1)^-1] p_h,
     mu(qm) (q1 - q0)/h + h(qm), qm = (q0 + q1)/2 (nonholonomic rows), g(q1) (holonomic),
   and, when size is not NULL, the size of each constraint row's terms, which its
   round-off is relative to (as _RattleStepper._r3). */
static void assemble(const rattle_start *s, const double *z, const rattle_parts *pt,
                     double *r, double *size) {
    const double *P = z, *Q1 = z + NQ, *lam = z + 2 * NQ, h = s->h;
    double u[NQ];
    for (int i = 0; i < NQ; ++i) {
        double a = 0.0;
        for (int c = 0; c < NC; ++c) a += lam[c] * s->mu0[c * NQ + i];
        r[i] = P[i] - s->p0[i] - 0.5 * h * (pt->Lq0[i] - a);
        r[NQ + i] = Q1[i] - s->q0[i] - 0.5 * h * (pt->U0[i] + pt->U1[i]);
        u[i] = (Q1[i] - s->q0[i]) / h;
    }
    const double *mum = pt->geom + NQ * NQ, *hm = mum + NC * NQ;
    const double *mu1 = pt->geo1 + NQ * NQ, *g1 = mu1 + NC * NQ + NC;
    for (int c = 0; c < NC; ++c) {
        double t = 0.0, a = 1.0 + fabs(hm[c]);
        for (int j = 0; j < NQ; ++j) {
            t += mum[c * NQ + j] * u[j];
            a += fabs(mum[c * NQ + j]) * (fabs(u[j]) + fabs(Q1[j]) / fabs(h));
        }
        r[2 * NQ + c] = t + hm[c];
        if (size) size[c] = a;
    }
    for (int c = 0; c < NH; ++c) {
        r[2 * NQ + c] = g1[c];
        if (size) {
            double a = 1.0;
            for (int j = 0; j < NQ; ++j) a += fabs(mu1[c * NQ + j]) * fabs(Q1[j]);
            size[c] = a;
        }
    }
}

/* The whole residual at z (its pieces in pt). Returns 1 when a W is singular. */
static int rattle_residual(const rattle_start *s, const double *z, rattle_parts *pt,
                           double *r, double *size) {
    parts_of_q(s, z, pt);
    if (parts_of_p(s, z, pt) || wsolve(pt->geo1, z, pt->U1)) return 1;
    assemble(s, z, pt, r, size);
    return 0;
}

/* The forward-difference Jacobian at z (r: the residual there, base: its pieces), steps
   sqrt(eps) max(|z_j|, scale_j) as _RattleStepper._fd_jacobian. Returns 1 when a W is
   singular. */
static int rattle_jacobian(const rattle_start *s, const double *z, const double *r,
                           const rattle_parts *base, const double *scale, double *J) {
    const double root_eps = 1.4901161193847656e-08;   /* sqrt(2^-52) */
    double zj[NZG], rj[NZG];
    rattle_parts pt;
    for (int j = 0; j < NZG; ++j) {
        const double e = root_eps * fmax(fabs(z[j]), scale[j]);
        for (int i = 0; i < NZG; ++i) zj[i] = z[i];
        zj[j] += e;
        pt = *base;
        if (j < 2 * NQ) {
            if (j >= NQ) parts_of_q(s, zj, &pt);
            else if (parts_of_p(s, zj, &pt)) return 1;
            if (wsolve(pt.geo1, zj, pt.U1)) return 1;
        }
        assemble(s, zj, &pt, rj, NULL);
        for (int i = 0; i < NZG; ++i) J[i * NZG + j] = (rj[i] - r[i]) / e;
    }
    return 0;
}

/* One step (q, v) -> (q1, v1) in place for W(q); lam: in = guess for lam0, out = lam1.
   The unknowns z = (p_h, q1, lam0) by Newton's method from the explicit guess (a half
   kick with the guess, a drift with W(q0)), with a forward-difference Jacobian (steps
   sqrt(eps) max(|z_j|, scale_j)), kept while the residual falls ten-fold an iteration;
   the residual is relative to the scale of p0, q0 and lam (constraint rows: to the size
   of their terms). Then rattle_finish. Returns as rattle_step. */
static int rattle_step_general(double *q, double *v, double h, double *lam, const double *p,
                               double tol, int maxiter, long *newton) {
    rattle_start s;
    double geo[NGEO], y[2 * NQ], Lq[NQ], z[NZG], r[NZG], scale[NZG], size[NCX];
    double J[NZG * NZG], A[NZG * NZG];
    s.h = h; s.p = p;
    geometry(q, p, geo);
    for (int i = 0; i < NQ * NQ; ++i) s.W0[i] = geo[i];
    for (int i = 0; i < NC * NQ; ++i) s.mu0[i] = geo[NQ * NQ + i];
    double pmax = 0.0, qmax = 0.0, lmax = 0.0;
    for (int i = 0; i < NQ; ++i) {
        double a = 0.0;
        for (int j = 0; j < NQ; ++j) a += s.W0[i * NQ + j] * v[j];
        s.p0[i] = a; s.q0[i] = q[i]; y[i] = q[i]; y[NQ + i] = v[i];
        if (fabs(a) > pmax) pmax = fabs(a);
        if (fabs(q[i]) > qmax) qmax = fabs(q[i]);
    }
    for (int c = 0; c < NC; ++c) if (fabs(lam[c]) > lmax) lmax = fabs(lam[c]);
    lagr_q(y, p, Lq);
    for (int i = 0; i < NQ; ++i) {
        double a = 0.0;
        for (int c = 0; c < NC; ++c) a += s.mu0[c * NQ + i] * lam[c];
        z[i] = s.p0[i] + 0.5 * h * (Lq[i] - a);
        scale[i] = 1.0 + pmax;
        scale[NQ + i] = 1.0 + qmax;
    }
    if (wsolve(s.W0, z, z + NQ)) return NHHAM_SINGULAR;
    for (int i = 0; i < NQ; ++i) z[NQ + i] = q[i] + h * z[NQ + i];
    for (int c = 0; c < NC; ++c) { z[2 * NQ + c] = lam[c]; scale[2 * NQ + c] = 1.0 + lmax; }
    rattle_parts base;
    double best = INFINITY;
    int have_J = 0, it;
    for (it = 0; it < maxiter; ++it) {
        if (rattle_residual(&s, z, &base, r, size)) return NHHAM_SINGULAR;
        double err = 0.0;
        for (int i = 0; i < NZG; ++i) {
            double e = fabs(r[i]) / (i < 2 * NQ ? scale[i]
                                     : fmax(size[i - 2 * NQ], 1.0 + pmax));
            if (!isfinite(e)) return NHHAM_NONFINITE;
            if (e > err) err = e;
        }
        if (err <= tol) break;
        if (it > 3 && err >= best) { if (err > 1e-9) return NHHAM_NOT_CONVERGED; break; }
        if (!have_J || err > 0.1 * best) {
            if (rattle_jacobian(&s, z, r, &base, scale, J)) return NHHAM_SINGULAR;
            have_J = 1;
        }
        if (err < best) best = err;
        for (int i = 0; i < NZG * NZG; ++i) A[i] = J[i];
        if (gsolve(NZG, A, r, 0.0)) return NHHAM_SINGULAR;
        for (int i = 0; i < NZG; ++i) z[i] -= r[i];
        ++*newton;
    }
    if (it == maxiter) return NHHAM_NOT_CONVERGED;
    /* the pieces at the last z: geometry(q1) and u1 = W(q1)^-1 p_h */
    return rattle_finish(q, v, z + NQ, z, base.U1, h, lam, p, base.geo1, base.geo1);
}

/* Steps of size h from y (2n: q, v; updated in place) until info[0] = nsteps, a
   failure, or pause_s seconds of wall time; composition 0: RATTLE, 1: triple jump
   (order 4); general 0: constant W (rattle_step), 1: W(q) (rattle_step_general). Every
   stride-th step (counted from the start of the run) is stored in out (row-major, .. x
   2n) until cap rows are there. lam: the multiplier guess carried from step to step;
   wsp: W and its inverse (2 n*n), computed when first is set and W is constant (unused
   for W(q)). info = [steps done, Newton iterations (both carried from call to call),
   rows stored by this call]. Returns NHHAM_SUCCESS (nsteps done), NHHAM_PAUSED (call
   again to go on) or the failure's status, with y the state after the last good step. */
int nhham_rattle(double *y, double h, long nsteps, long stride, int composition,
                 int general, double *out, long cap, const double *pext, double *lam, double *wsp,
                 int first, double tol, int maxiter, double pause_s, long *info) {
    double *W = wsp, *Winv = wsp + NQ * NQ, geo[NGEO], q[NQ], v[NQ];
    const double wall_pause = wall_seconds() + pause_s;
    if (first && !general) {
        geometry(y, pext, geo);
        for (int i = 0; i < NQ * NQ; ++i) W[i] = geo[i];
        for (int c = 0; c < NQ; ++c) {
            double A[NQ * NQ], e[NQ];
            for (int i = 0; i < NQ * NQ; ++i) A[i] = W[i];
            for (int i = 0; i < NQ; ++i) e[i] = (i == c);
            if (gsolve(NQ, A, e, 0.0)) return NHHAM_SINGULAR;
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
        const double sub[3] = {composition ? g1 * h : h, g2 * h, g1 * h};
        for (int j = 0; j < (composition ? 3 : 1) && !status; ++j)
            status = general ? rattle_step_general(q, v, sub[j], lam, pext, tol, maxiter, &newton)
                             : rattle_step(q, v, sub[j], lam, pext, W, Winv, tol, maxiter, &newton);
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
