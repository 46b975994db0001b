/* The C runtime of nhham's generated models: what every translation unit shares.

   nhham.numerics.codegen.emit assembles one translation unit per model, in this order:

     1. generated definitions: NQ (coordinates), NC (affine constraints), NH (holonomic
        constraints), NN = NQ + NC, NOUT (outputs of the saddle kernel), NPAR (parameters),
        the status codes NHHAM_<NAME> of nhham.numerics.status.Status, and
        NHHAM_CLOSED_FORM on the closed-form path;
     2. this header;
     3. the generated kernels saddle, geometry, lagr_q, jphi (and closed; potential and
        linear where L = v^T W v / 2 + b . v - V, NHHAM_DGRAD);
     4. linalg.c, rhs.c, rattle.c, erk.c, dgrad.c, then closed.c (closed-form path) or pyext.c
        (saddle path; built as a CPython extension when NHHAM_PYEXT is defined).

   The files are package data (nhham/numerics/c/); the cache of compiled libraries is keyed
   by a hash of the assembled source, so editing a file here rebuilds every model. */

#ifndef NQ
#error "nhham runtime: compile the source assembled by nhham.numerics.codegen, not this file"
#endif

#ifdef NHHAM_PYEXT
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>
#endif
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L        /* clock_gettime under -std=c99 */
#endif
#include <math.h>
#include <time.h>

#define NCX (NC > 0 ? NC : 1)          /* array sizes that must not be zero */
#define NNX (NQ + NCX)
#define NRES (2 * NQ + NC + 1)         /* out of nhham_rhs: dy (2n), lambda (m), power */

/* Seconds on a monotonic clock: the integration loops return to Python every few ms
   (NHHAM_PAUSED) so that a signal (Ctrl-C, a time budget) is handled at once. */
static double wall_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The generated kernels (y = [q, v] or q; p = parameters; out as in emit.py):
   saddle:   W (n*n, row-major), F (n), mu (m*n), drift (m), h (m), g (k) at (q, v);
   geometry: W, mu, h, g at q;   lagr_q: dL/dq (n);   jphi: d(phi)/dq (m*n);
   closed:   accelerations (n) and multipliers (m) of the symbolic P(xi_L). */
static void saddle(const double *y, const double *p, double *out);
static void geometry(const double *y, const double *p, double *out);
static void lagr_q(const double *y, const double *p, double *out);
static void jphi(const double *y, const double *p, double *out);
#ifdef NHHAM_DGRAD
static void potential(const double *y, const double *p, double *out);
#endif
#ifdef NHHAM_LINEAR_TERMS
static void linear(const double *y, const double *p, double *out);
#endif
#ifdef NHHAM_CLOSED_FORM
static void closed(const double *y, const double *p, double *out);
#endif
