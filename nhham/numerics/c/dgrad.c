/* ---- the energy-exact discrete gradient (see nhham.numerics.discrete_gradient) ----
   Only where L = v^T W(q) v / 2 + b(q) . v - V(q) (NHHAM_DGRAD: the kernels potential,
   and linear where b != 0). The same equations, guesses and Newton iterations as
   EnergyExactStepper; the unknowns z = (q1, p1, lambda, nu). */
#ifdef NHHAM_DGRAD
#define NZD (2 * NQ + NC + NH)
#define DG_ROUNDING 1e-13   /* nhham.numerics.discrete_gradient.ROUNDING */
#define DG_FLOOR 1e-9       /* nhham.numerics.discrete_gradient.FLOOR */
#define NGD (NQ * NQ + NC * NQ + NC + NH)

/* b(q) of p = W v + b (zero without linear terms). */
static void dg_offset(const double *q, const double *p, double *b) {
#ifdef NHHAM_LINEAR_TERMS
    linear(q, p, b);
#else
    (void)q; (void)p;
    for (int i = 0; i < NQ; ++i) b[i] = 0.0;
#endif
}

/* x = W^-1 b (W copied). Returns 1 when W is singular. */
static int dg_wsolve(const double *W, const double *b, double *x) {
    double A[NQ * NQ];
    for (int i = 0; i < NQ * NQ; ++i) A[i] = W[i];
    for (int i = 0; i < NQ; ++i) x[i] = b[i];
    return gsolve(NQ, A, x, 0.0);
}

/* H = v^T W v / 2 + V(q) and v = W^-1 (P - b(q)) at (q, P); geo = geometry(q). */
static int dg_hamiltonian(const double *q, const double *P, const double *p, double *geo,
                          double *v, double *H) {
    double b[NQ], r[NQ], V;
    geometry(q, p, geo);
    dg_offset(q, p, b);
    for (int i = 0; i < NQ; ++i) r[i] = P[i] - b[i];
    if (dg_wsolve(geo, r, v)) return 1;
    potential(q, p, &V);
    double T = 0.0;
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int j = 0; j < NQ; ++j) s += geo[i * NQ + j] * v[j];
        T += v[i] * s;
    }
    *H = 0.5 * T + V;
    return 0;
}

/* The residual (NZD) at z, and the reactions' work h h_m . lambda; returns 1 when a W is
   singular. As EnergyExactStepper.residual. */
static int dg_residual(const double *q0, const double *P0, double H0, double h,
                       const double *z, const double *p, double *r, double *work,
                       double *terms) {
    const double *Q1 = z, *P1 = z + NQ, *lam = z + 2 * NQ, *nu = z + 2 * NQ + NC;
    double geo1[NGD], geom[NGD], V1[NQ], Vm[NQ], Qm[NQ], Pm[NQ], H1, Hm, y[2 * NQ], gq[NQ];
    double dq[NQ], dp[NQ], dHq[NQ], dHp[NQ], w[NQ], c[NCX];
    if (dg_hamiltonian(Q1, P1, p, geo1, V1, &H1)) return 1;
    for (int i = 0; i < NQ; ++i) { Qm[i] = 0.5 * (q0[i] + Q1[i]); Pm[i] = 0.5 * (P0[i] + P1[i]); }
    if (dg_hamiltonian(Qm, Pm, p, geom, Vm, &Hm)) return 1;
    for (int i = 0; i < NQ; ++i) { y[i] = Qm[i]; y[NQ + i] = Vm[i]; }
    lagr_q(y, p, gq);
    double size2 = 0.0, rest = H1 - H0;
    for (int i = 0; i < NQ; ++i) {
        gq[i] = -gq[i];                       /* dH/dq = -dL/dq */
        dq[i] = Q1[i] - q0[i]; dp[i] = P1[i] - P0[i];
        size2 += dq[i] * dq[i] + dp[i] * dp[i];
    }
    for (int i = 0; i < NQ; ++i) rest -= gq[i] * dq[i];
    for (int i = 0; i < NQ; ++i) rest -= Vm[i] * dp[i];
    const double s = size2 > 0.0 ? rest / size2 : 0.0;
    for (int i = 0; i < NQ; ++i) { dHq[i] = gq[i] + s * dq[i]; dHp[i] = Vm[i] + s * dp[i]; }
    const double *Wm = geom, *mum = geom + NQ * NQ, *hm = mum + NC * NQ;
    double ww = 0.0;
    for (int i = 0; i < NQ; ++i) {
        double a = 0.0;
        for (int j = 0; j < NQ; ++j) a += Wm[i * NQ + j] * dHp[j];
        w[i] = a;
        ww += dHp[i] * a;
    }
    double cl = 0.0, wk = 0.0;
    for (int a = 0; a < NC; ++a) {
        double t = hm[a];
        for (int j = 0; j < NQ; ++j) t += mum[a * NQ + j] * dHp[j];
        c[a] = ww > 0.0 ? t / ww : 0.0;
        cl += c[a] * lam[a];
        wk += hm[a] * lam[a];
    }
    *work = h * wk;
    for (int j = 0; j < NQ; ++j) {
        double react = -w[j] * cl;
        for (int a = 0; a < NC; ++a) react += mum[a * NQ + j] * lam[a];
        r[j] = dq[j] - h * dHp[j];
        r[NQ + j] = dp[j] + h * dHq[j] + h * react;
        if (terms) {
            terms[j] = fabs(dq[j]) + h * fabs(dHp[j]);
            terms[NQ + j] = fabs(dp[j]) + h * (fabs(dHq[j]) + fabs(react));
        }
    }
    const double *mu1 = geo1 + NQ * NQ, *h1 = mu1 + NC * NQ, *g1 = h1 + NC;
    for (int a = 0; a < NC; ++a) {
        double t = h1[a], ab = fabs(h1[a]);
        for (int j = 0; j < NQ; ++j) { t += mu1[a * NQ + j] * V1[j]; ab += fabs(mu1[a * NQ + j] * V1[j]); }
        r[2 * NQ + a] = t;
        if (terms) terms[2 * NQ + a] = ab;
    }
#if NH > 0
    {   /* g(q1) = 0 by a position correction along W^-1 G^T made orthogonal to dH_q */
        double sq[NQ], D[NQ], qq = 0.0;
        if (dg_wsolve(Wm, dHq, sq)) return 1;
        for (int i = 0; i < NQ; ++i) qq += dHq[i] * sq[i];
        for (int a = 0; a < NH; ++a) {
            if (dg_wsolve(Wm, mum + a * NQ, D)) return 1;
            double e = 0.0;
            for (int i = 0; i < NQ; ++i) e += dHq[i] * D[i];
            e = qq > 0.0 ? e / qq : 0.0;
            for (int i = 0; i < NQ; ++i) r[i] += (D[i] - sq[i] * e) * nu[a];
            r[2 * NQ + NC + a] = g1[a];
            if (terms) terms[2 * NQ + NC + a] = fabs(g1[a]);
        }
    }
#else
    (void)nu; (void)g1;
#endif
    for (int i = 0; i < NZD; ++i) if (!isfinite(r[i])) return 2;
    return 0;
}

/* One step from (q, v) (y, updated in place, work in y[2n] added to); hist: the last
   three z (count *nh), J the kept Jacobian (*haveJ). Returns a status. */
static int dg_step(double *y, double h, const double *p, double tol, int maxiter,
                   double *hist, long *nh, double *J, long *haveJ, long *newton) {
    double q0[NQ], P0[NQ], geo[NGD], b[NQ], z[NZD], r[NZD], scale[NZD], size[NZD], A[NZD * NZD];
    double terms[NZD];
    double work = 0.0;
    for (int i = 0; i < NQ; ++i) q0[i] = y[i];
    geometry(q0, p, geo);
    dg_offset(q0, p, b);
    double V0, T0 = 0.0;
    potential(q0, p, &V0);
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int j = 0; j < NQ; ++j) s += geo[i * NQ + j] * y[NQ + j];
        P0[i] = s + b[i];
        T0 += y[NQ + i] * s;
    }
    const double H0 = 0.5 * T0 + V0;
    if (*nh >= 3) {
        for (int i = 0; i < NZD; ++i) z[i] = 3.0 * hist[2 * NZD + i] - 3.0 * hist[NZD + i] + hist[i];
    } else if (*nh == 2) {
        for (int i = 0; i < NZD; ++i) z[i] = 2.0 * hist[NZD + i] - hist[i];
    } else {   /* a Taylor step of the field, its multipliers */
        double out[NRES];
        int st = rhs_one(y, p, 0.0, 0.0, out, out + 2 * NQ, out + 2 * NQ + NC);
        if (st) return st;
        double q1[NQ], v1[NQ], g1[NGD], b1[NQ];
        for (int i = 0; i < NQ; ++i) {
            q1[i] = y[i] + h * y[NQ + i] + 0.5 * h * h * out[NQ + i];
            v1[i] = y[NQ + i] + h * out[NQ + i];
        }
        geometry(q1, p, g1);
        dg_offset(q1, p, b1);
        for (int i = 0; i < NQ; ++i) {
            double s = b1[i];
            for (int j = 0; j < NQ; ++j) s += g1[i * NQ + j] * v1[j];
            z[i] = q1[i]; z[NQ + i] = s;
        }
        for (int a = 0; a < NC; ++a) z[2 * NQ + a] = out[2 * NQ + a];
        for (int a = 0; a < NH; ++a) z[2 * NQ + NC + a] = 0.0;
    }
    /* scales and row sizes one each, as EnergyExactStepper._scale and _row_size */
    double sq = 1.0;
    for (int i = 0; i < NQ; ++i) sq = fmax(sq, 1.0 + fabs(q0[i]));
    for (int i = 0; i < NQ; ++i) {
        scale[i] = size[i] = 1.0 + fabs(q0[i]);
        scale[NQ + i] = size[NQ + i] = 1.0 + fabs(P0[i]);
    }
    {
        const double *mu0 = geo + NQ * NQ, *h0 = mu0 + NC * NQ;
        for (int a = 0; a < NC; ++a) {
            double t = 1.0 + fabs(h0[a]);
            for (int j = 0; j < NQ; ++j) t += fabs(mu0[a * NQ + j] * y[NQ + j]);
            scale[2 * NQ + a] = 1.0 + fabs(z[2 * NQ + a]);
            size[2 * NQ + a] = t;
        }
    }
    for (int a = 0; a < NH; ++a) { scale[2 * NQ + NC + a] = sq; size[2 * NQ + NC + a] = sq; }
    double block[NZD];   /* each block's largest size (EnergyExactStepper._block_size) */
    {
        const int lo[4] = {0, NQ, 2 * NQ, 2 * NQ + NC}, hi[4] = {NQ, 2 * NQ, 2 * NQ + NC, NZD};
        for (int b = 0; b < 4; ++b) {
            double mx = 0.0;
            for (int i = lo[b]; i < hi[b]; ++i) mx = fmax(mx, size[i]);
            for (int i = lo[b]; i < hi[b]; ++i) block[i] = mx;
        }
    }
    double best = INFINITY;
    int it, fresh = 0;
    for (it = 0; it < maxiter; ++it) {
        int st = dg_residual(q0, P0, H0, h, z, p, r, &work, terms);
        if (st == 1) return NHHAM_SINGULAR;
        if (st == 2) return NHHAM_NONFINITE;
        double err = 0.0, errb = 0.0;   /* by row; against each block's largest size */
        for (int i = 0; i < NZD; ++i) {
            err = fmax(err, fabs(r[i]) / fmax(size[i], terms[i]));
            errb = fmax(errb, fabs(r[i]) / block[i]);
        }
        /* no longer halving: at rounding (DG_ROUNDING, relative), or stuck even with a
           Jacobian of the last iterate */
        if (it > 0 && err >= 0.5 * best) {
            if (errb <= DG_ROUNDING || (fresh && errb <= DG_FLOOR)) break;
            if (fresh) return NHHAM_NOT_CONVERGED;
        }
        if (it == maxiter - 1) { if (errb > DG_FLOOR) return NHHAM_NOT_CONVERGED; break; }
        /* the last Jacobian is kept from step to step while it contracts ten-fold */
        fresh = !*haveJ || (it > 0 && err > 0.1 * best && err > DG_ROUNDING);
        if (fresh) {
            const double root_eps = 1.4901161193847656e-08;
            double zj[NZD], rj[NZD], wj;
            for (int j = 0; j < NZD; ++j) {
                const double e = root_eps * fmax(fabs(z[j]), scale[j]);
                for (int i = 0; i < NZD; ++i) zj[i] = z[i];
                zj[j] += e;
                st = dg_residual(q0, P0, H0, h, zj, p, rj, &wj, NULL);
                if (st == 1) return NHHAM_SINGULAR;
                if (st == 2) return NHHAM_NONFINITE;
                for (int i = 0; i < NZD; ++i) J[i * NZD + j] = (rj[i] - r[i]) / e;
            }
            *haveJ = 1;
        }
        if (err < best) best = err;
        for (int i = 0; i < NZD * NZD; ++i) A[i] = J[i];
        if (gsolve(NZD, A, r, 0.0)) return NHHAM_SINGULAR;
        double upd = 0.0;
        for (int i = 0; i < NZD; ++i) { z[i] -= r[i]; upd = fmax(upd, fabs(r[i]) / scale[i]); }
        ++*newton;
        if (upd <= tol) break;    /* the update is at rounding */
    }
    /* v1 = W(q1)^-1 (p1 - b(q1)) */
    double v1[NQ], H1;
    if (dg_hamiltonian(z, z + NQ, p, geo, v1, &H1)) return NHHAM_SINGULAR;
    for (int i = 0; i < NQ; ++i) {
        y[i] = z[i]; y[NQ + i] = v1[i];
        if (!isfinite(y[i]) || !isfinite(v1[i]) || fabs(y[i]) > 1e150 || fabs(v1[i]) > 1e150)
            return NHHAM_NONFINITE;
    }
    y[2 * NQ] += work;
    if (*nh >= 3) {
        for (int i = 0; i < 2 * NZD; ++i) hist[i] = hist[NZD + i];
        for (int i = 0; i < NZD; ++i) hist[2 * NZD + i] = z[i];
    } else {
        for (int i = 0; i < NZD; ++i) hist[*nh * NZD + i] = z[i];
        ++*nh;
    }
    return NHHAM_SUCCESS;
}

/* Steps of size h from y (2n + 1: q, v, the reactions' work; in place) until info[0] =
   nsteps, a failure, or pause_s seconds. Every stride-th step goes to out (rows of
   2n + 1) until cap rows are there. wsp: 3 NZD (the last z's) + NZD^2 (the Jacobian),
   carried from call to call with info = [steps done, Newton iterations, rows stored by
   this call, z's kept, Jacobian kept]. Returns as nhham_rattle. */
int nhham_dgrad(double *y, double h, long nsteps, long stride, double *out, long cap,
                const double *pext, double *wsp, double tol, int maxiter, double pause_s,
                long *info) {
    const double wall_pause = wall_seconds() + pause_s;
    int status = NHHAM_SUCCESS, stepped = 0;
    info[2] = 0;
    while (info[0] < nsteps) {
        if (info[2] >= cap || (stepped && wall_seconds() >= wall_pause)) {
            status = NHHAM_PAUSED;
            break;
        }
        status = dg_step(y, h, pext, tol, maxiter, wsp, &info[3], wsp + 3 * NZD, &info[4],
                         &info[1]);
        if (status == NHHAM_NOT_CONVERGED) {   /* once more from the field's own guess */
            info[3] = 0; info[4] = 0;
            status = dg_step(y, h, pext, tol, maxiter, wsp, &info[3], wsp + 3 * NZD,
                             &info[4], &info[1]);
        }
        if (status) break;
        ++info[0];
        stepped = 1;
        if (info[0] % stride == 0) {
            double *o = out + info[2] * (2 * NQ + 1);
            for (int i = 0; i < 2 * NQ + 1; ++i) o[i] = y[i];
            ++info[2];
        }
    }
    return status;
}
#endif
