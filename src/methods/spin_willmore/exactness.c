/*
 * Exactness constraint of the spin-willmore flow (Crane, Pinkall, Schroeder
 * 2013, App. C) on closed surfaces of genus > 0 and free-boundary surfaces
 * that are not disks: the harmonic 1-forms of the input, their re-projection
 * onto the current metric, and the constraint columns - App. C.1's Z_i
 * (exactness_linearized = 0) or, by default, the discrete linearisation of
 * "the transformed edges have no periods" (docs/spin.md, "Exactness").
 */
#include "methods/spin_willmore/spin_flow.h"
#include "curvflow/ops.h"

#include <string.h>

/* The discrete flow keeps the conformal structure only up to the mesh's
 * resolution, so 1-forms harmonic on the input drift away from harmonic on
 * the current surface, and Z_i built from them stop spanning the periods
 * (a bumped torus at tau 0.1 blew up after 62 steps, its integrability
 * error growing from 4e-4 to 4e-2). Each form is re-projected onto the
 * harmonic forms of the current cotan metric within its cohomology class:
 * omega <- omega - d u with L u = -div omega, (div omega)_i = sum_j w_ij
 * omega_ij, so that the result is co-closed and still closed with the same
 * periods. The current L is refilled every step for H; its factorisation is
 * shared with the position solve only when that uses the current metric
 * (input_metric = 0). */
static cf_status update_harmonic_forms(cf_flow *flow, cfi_spin_state *s, double *factor_seconds, double *solve_seconds)
{
    const cf_mesh *mesh = flow->mesh;
    int32_t nv = s->nv, ne = s->ne, dim = s->harmonic_dim;
    double *div = s->zrhs, *u = s->zsol; /* scratch: at least nv x dim each */
    memset(div, 0, (size_t)nv * dim * sizeof(double));
    for (int32_t g = 0; g < dim; ++g) {
        const double *w = s->harmonic + (int64_t)g * ne;
        double *d = div + (int64_t)g * nv;
        for (int32_t e = 0; e < ne; ++e) {
            int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
            double flux = cf_edge_poisson_weight(s->poisson, e) * w[e]; /* w_ij omega_ij, the edge runs i -> j */
            d[i] -= flux;                              /* right-hand side -div */
            d[j] += flux;
        }
        /* L's range is orthogonal to the constants; the rounding left in the
         * sum would come back multiplied by 1 / shift as a constant in u,
         * whose cancellation in d u then costs digits */
        double mean = 0.0;
        for (int32_t i = 0; i < nv; ++i) mean += d[i];
        mean /= nv;
        for (int32_t i = 0; i < nv; ++i) d[i] -= mean;
    }
    cf_solver_timings tm = {0.0, 0.0, 0.0};
    cf_status st = cf_edge_poisson_solve_scalar(s->poisson, dim, div, u, &tm);
    *factor_seconds += tm.factorize_seconds;
    *solve_seconds += tm.solve_seconds;
    if (st != CF_OK) return st;
    for (int32_t g = 0; g < dim; ++g) {
        double *w = s->harmonic + (int64_t)g * ne;
        const double *ug = u + (int64_t)g * nv;
        for (int32_t e = 0; e < ne; ++e) w[e] -= ug[mesh->edge_vertices[2 * e + 1]] - ug[mesh->edge_vertices[2 * e]];
    }
    return CF_OK;
}

/* Fills X(0) + eps M at the current surface x (the Dirac matrix without
 * rho) and factorises it into chol0: both exactness variants solve with it. */
static cf_status factorize_x0(cf_flow *flow, cfi_spin_state *s, const double *x, double *factor_seconds)
{
    double t0 = cfi_now_seconds();
    cf_status st = cfi_dirac_fill(s->dirac, flow->mesh, x, NULL, s->eps);
    if (st == CF_OK) st = cfi_dirac_factorize(s->dirac, s->chol0);
    *factor_seconds += cfi_now_seconds() - t0;
    return st;
}

/* Z_i of App. C.1 on the current surface x: face vectors v from the 2 x 2
 * systems, right-hand side D^* A v (vertex i gets sum_k e_i v_k / 2), and
 * solves with X(0). Fills columns of s->basis from `col` with the imaginary
 * parts of each Z_i; returns the new column count. */
static cf_status exactness_columns(cf_flow *flow, cfi_spin_state *s, const double *x, int32_t *col,
                                   double *factor_seconds, double *solve_seconds)
{
    const cf_mesh *mesh = flow->mesh;
    int32_t nv = s->nv, dim = s->harmonic_dim;
    if (s->opt.harmonic_update) {
        cf_status sth = update_harmonic_forms(flow, s, factor_seconds, solve_seconds);
        if (sth != CF_OK) return sth;
    }
    cf_status st = factorize_x0(flow, s, x, factor_seconds);
    if (st != CF_OK) return st;
    double t1 = cfi_now_seconds();
    memset(s->zrhs, 0, 4 * (size_t)nv * dim * sizeof(double));
    for (int32_t f = 0; f < s->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        const int32_t *he = mesh->halfedge_edge + 3 * f;
        double e[3][3];
        for (int m = 0; m < 3; ++m)
            for (int c = 0; c < 3; ++c) e[m][c] = x[3 * t[(m + 2) % 3] + c] - x[3 * t[(m + 1) % 3] + c];
        /* halfedge 3f+k runs t[k] -> t[k+1] = edge opposite corner k+2, i.e. e[(k+2)%3] */
        double a11 = 0, a12 = 0, a22 = 0;
        const double *e1 = e[2], *e2 = e[0];   /* halfedges 0 (t0->t1) and 1 (t1->t2) */
        for (int c = 0; c < 3; ++c) {
            a11 += e1[c] * e1[c];
            a12 += e1[c] * e2[c];
            a22 += e2[c] * e2[c];
        }
        double det = a11 * a22 - a12 * a12;
        if (!(det > 0.0)) return cfi_error(flow->ctx, CF_ERR_DEGENERATE_FACE, "face %d: degenerate in exactness", f);
        for (int32_t g = 0; g < dim; ++g) {
            const double *w = s->harmonic + (int64_t)g * s->ne;
            /* 1-form values along the halfedges: the edge runs i < j */
            double om[2];
            for (int h = 0; h < 2; ++h) {
                int32_t ed = he[h];
                double sgn = mesh->edge_vertices[2 * ed] == t[h] ? 1.0 : -1.0;
                om[h] = sgn * w[ed];
            }
            double a1 = (a22 * om[0] - a12 * om[1]) / det, a2 = (a11 * om[1] - a12 * om[0]) / det;
            double v[3];
            for (int c = 0; c < 3; ++c) v[c] = a1 * e1[c] + a2 * e2[c];
            double *r = s->zrhs + (int64_t)g * 4 * nv;
            for (int m = 0; m < 3; ++m) {
                /* e_m v = -<e_m, v> + e_m x v */
                const double *em = e[m];
                double *ri = r + 4 * t[m];
                ri[0] += -0.5 * (em[0] * v[0] + em[1] * v[1] + em[2] * v[2]);
                ri[1] += 0.5 * (em[1] * v[2] - em[2] * v[1]);
                ri[2] += 0.5 * (em[2] * v[0] - em[0] * v[2]);
                ri[3] += 0.5 * (em[0] * v[1] - em[1] * v[0]);
            }
        }
    }
    st = cf_cholesky_solve(s->chol0, dim, s->zrhs, s->zsol);
    *solve_seconds += cfi_now_seconds() - t1;
    if (st != CF_OK) return st;
    for (int32_t g = 0; g < dim; ++g) {
        const double *z = s->zsol + (int64_t)g * 4 * nv;
        for (int c = 1; c < 4; ++c) {
            double *b = s->basis + (int64_t)(*col) * nv;
            for (int32_t i = 0; i < nv; ++i) b[i] = z[4 * i + c];
            ++*col;
        }
    }
    return CF_OK;
}

/* q u for the unit quaternion u = i, j, k (uc = 0, 1, 2) or u = 1 (uc < 0),
 * q = (w, x, y, z): q i = (-x, w, z, -y), q j = (-y, -z, w, x),
 * q k = (-z, y, -x, w). out may not alias q. */
static inline void times_unit(const double q[4], int uc, double out[4])
{
    if (uc == 0) {
        out[0] = -q[1], out[1] = q[0], out[2] = q[3], out[3] = -q[2];
    } else if (uc == 1) {
        out[0] = -q[2], out[1] = -q[3], out[2] = q[0], out[3] = q[1];
    } else if (uc == 2) {
        out[0] = -q[3], out[1] = q[2], out[2] = -q[1], out[3] = q[0];
    } else {
        memcpy(out, q, 4 * sizeof(double));
    }
}

/* The path before the solves were shared (test hook s->x0_full_solves):
 * zrhs's column 3 g + c becomes B_g u_c (from B_g in column g; zrhs has
 * 3 dim columns) and all 3 dim columns are solved. */
static cf_status solve_each_column(cfi_spin_state *s, int32_t dim)
{
    int64_t n = 4 * (int64_t)s->nv;
    for (int32_t g = dim - 1; g >= 0; --g) /* downward: column g is read before 3 g .. 3 g + 2 are written */
        for (int32_t i = 0; i < s->nv; ++i) {
            double q[4], out[4];
            memcpy(q, s->zrhs + g * n + 4 * i, sizeof q);
            for (int c = 0; c < 3; ++c) {
                times_unit(q, c, out);
                memcpy(s->zrhs + (3 * g + c) * n + 4 * i, out, sizeof out);
            }
        }
    return cf_cholesky_solve(s->chol0, 3 * dim, s->zrhs, s->zsol);
}

/* zsol = X(0)^-1 B_g for each harmonic form g (or, with the test hook
 * x0_full_solves, X(0)^-1 (B_g u_c) for every c): B_g = -sum_e w h_g(e) e
 * at both ends of each edge, at the surface x. */
static cf_status solve_x0_sources(const cf_mesh *mesh, cfi_spin_state *s, const double *x)
{
    int32_t nv = s->nv, dim = s->harmonic_dim;
    memset(s->zrhs, 0, 4 * (size_t)nv * dim * sizeof(double));
    /* form by form, along its rows of s->harmonic and zrhs (edge by edge
     * over all forms touched both strided: a cache miss per form and edge
     * with 99 forms); each entry sums its edges in the same order */
    for (int32_t g = 0; g < dim; ++g) {
        const double *h = s->harmonic + (int64_t)g * s->ne;
        double *r = s->zrhs + (int64_t)g * 4 * nv;
        for (int32_t e = 0; e < s->ne; ++e) {
            int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
            double v[3] = {x[3 * j] - x[3 * i], x[3 * j + 1] - x[3 * i + 1], x[3 * j + 2] - x[3 * i + 2]};
            double wh = s->hweights[e] * h[e];
            for (int c = 0; c < 3; ++c) {
                r[4 * i + 1 + c] -= wh * v[c]; /* B_g: the imaginary quaternion -w h_g e */
                r[4 * j + 1 + c] -= wh * v[c];
            }
        }
    }
    s->diag.x0_solve_columns = s->x0_full_solves ? 3 * dim : dim;
    return s->x0_full_solves ? solve_each_column(s, dim) : cf_cholesky_solve(s->chol0, dim, s->zrhs, s->zsol);
}

/* Whether this step may take its exactness directions from the factor of
 * X(0) made at an earlier step (option exactness_refresh). Only with the
 * period corrections, which measure what older directions miss (the
 * harmonic part of e~ before them); only while the surface has moved
 * little since the factorisation, and after a step whose periods were
 * small. Measured on bob_5k: directions from the previous step's X(0)
 * leave 23-58 % of their norm outside the current span after step 1
 * (scale change 0.29), 3-10 % after step 3 (0.014), 1-3 % after step 4
 * (0.004). An attempt on such directions whose periods exceed
 * period_tolerance, or that is rejected, is made again with a new factor
 * (renew_direction, flow_method.c): without that, a bumped torus that moves
 * 0.04-0.06 per step left periods of up to 1.1e-2 in reused steps (7e-4
 * with a new factor), and elephant_g3_3k, under a variant that reused while
 * the last periods were below the whole tolerance with no bound on the
 * movement, reused after its large second step (0.39) and stalled at step 4
 * (W/4pi 9.57 against 8.22; with the renewal it renews steps 3-5 and
 * reaches 8.2153). With the default bound 0.1: bob reuses in steps 4-10,
 * elephant in 6-9, the torus in 3 steps and renews 2 (test x0_reuse).
 * docs/spin.md, "Reusing X(0)". */
static int x0_reusable(const cfi_spin_state *s)
{
    /* (zcount: the last step had exactness directions, so its periods were measured) */
    return s->period_newton && s->x0_factored && s->zcount > 0 && s->opt.exactness_refresh > 0.0 &&
           s->x0_scale_since <= s->opt.exactness_refresh && s->x0_period_first <= 0.5 * s->opt.period_tolerance;
}

/* Exactness by linearising "no periods" through the discrete step; the
 * default, and the only way on a surface with free boundary: App. C's step "<D Z a,
 * lambda> = <Z a, D lambda>" needs D to be self-adjoint, which fails with
 * the natural boundary condition (Green's formula leaves a boundary
 * integral); measured on annuli, the Z_i constraint does not reduce the
 * period of the transformed edges at all (docs/spin.md). Instead the
 * condition <e~, h_g>_*1 = 0 (no harmonic part = no period around any
 * hole, as h_g spans the Neumann harmonic fields, ops.md) is linearised
 * through the discrete pipeline of one step:
 *  - lambda = X(tau rhodot)^-1 M 1 with X(0) 1 = eps M 1 (D 1 = 0), so to
 *    first order lambda ~ 1 + tau mu, mu = -X(0)^-1 K rhodot, where
 *    K rhodot = X_1(rhodot) 1 = -(1/6) sum_faces e_m (rho_0 + rho_1 + rho_2)
 *    at corner m (App. G: the rho-linear term (rho_m e_n - rho_n e_m) / 6,
 *    sum_n e_n = 0);
 *  - the edge transform (dirac.c) changes by d e~ = (a_i + a_j) e +
 *    e x (u_i + u_j) for mu = (a, u);
 *  - so <d e~, h_g>^c = G_gc . mu, and the constraint is rhodot orthogonal
 *    (in M) to M^-1 K^T X(0)^-1 G_gc, three columns per harmonic form.
 * Exact to first order in tau for one inverse power iteration (the
 * default); an approximation for more.
 * The three G_gc of a form are one quaternion field right-multiplied by
 * i, j, k: G_gc = B_g u_c with B_g = -sum_e w h_g(e) e at both ends of
 * each edge (e u_c = -<e, u_c> + e x u_c, so -e u_c = (e_c, u_c x e), the
 * entries below). X's blocks multiply from the left, which commutes with a
 * constant right factor, so X(0)^-1 G_gc = (X(0)^-1 B_g) u_c: one solve per
 * form instead of three (bob_5k: 2 columns instead of 6, the solve's time
 * a third; docs/spin.md, "Measured figures"). */
static cf_status exactness_columns_linearized(cf_flow *flow, cfi_spin_state *s, const double *x, int32_t *col,
                                              double *factor_seconds, double *solve_seconds)
{
    const cf_mesh *mesh = flow->mesh;
    int32_t nv = s->nv, dim = s->harmonic_dim, ncol = 3 * dim;
    /* A step that reuses the factor also keeps its solution X(0)^-1 B_g,
     * made at the positions of the factorising step: B_g moves with the
     * surface as X(0) does, so the bound on the movement that admits the
     * factor covers both (K^T below takes the current positions). Measured
     * on bob_5k, 10 default steps: the reused steps lose their X(0) solve
     * (2 columns, about 4.5 of their 33 ms); W/4pi 1.84946 -> 1.84934, the
     * periods before corrections after step 10 5.0e-4 -> 6.0e-4 (tolerance
     * 3e-3); docs/spin.md, "Reusing X(0)". */
    s->diag.x0_reused = x0_reusable(s);
    if (s->diag.x0_reused) {
        s->diag.x0_solve_columns = 0;
    } else {
        s->x0_factored = 0; /* until the new factor exists */
        cf_status st = factorize_x0(flow, s, x, factor_seconds);
        if (st != CF_OK) return st;
        s->x0_factored = 1;
        s->x0_scale_since = 0.0;
        double t1 = cfi_now_seconds();
        st = solve_x0_sources(mesh, s, x);
        *solve_seconds += cfi_now_seconds() - t1;
        if (st != CF_OK) return st;
    }
    /* the three columns of a form in one pass over the faces (they share
     * X(0)^-1 B_g; the hook's columns one by one) */
    int32_t per_pass = s->x0_full_solves ? 1 : 3;
    for (int32_t k0 = 0; k0 < ncol; k0 += per_pass) {
        /* X(0)^-1 B_g, times u_c below (the hook: X(0)^-1 (B_g u_c) itself) */
        const double *y = s->zsol + (int64_t)(s->x0_full_solves ? k0 : k0 / 3) * 4 * nv;
        double *b[3];
        for (int32_t k = 0; k < per_pass; ++k) {
            b[k] = s->basis + (int64_t)(*col + k) * nv;
            memset(b[k], 0, (size_t)nv * sizeof(double));
        }
        /* K^T y: face f adds -(1/6) sum_m <Im y_tri[m], e_m> to each corner */
        for (int32_t f = 0; f < s->nf; ++f) {
            const int32_t *t = mesh->triangles + 3 * f;
            for (int32_t k = 0; k < per_pass; ++k) {
                int uc = s->x0_full_solves ? -1 : k;
                double sum = 0.0;
                for (int m = 0; m < 3; ++m) {
                    const double *a = x + 3 * t[(m + 1) % 3], *bb = x + 3 * t[(m + 2) % 3];
                    double ym[4];
                    times_unit(y + 4 * t[m], uc, ym);
                    for (int c = 0; c < 3; ++c) sum += ym[1 + c] * (bb[c] - a[c]);
                }
                for (int m = 0; m < 3; ++m) b[k][t[m]] -= sum / 6.0;
            }
        }
        for (int32_t k = 0; k < per_pass; ++k)
            for (int32_t i = 0; i < nv; ++i) b[k][i] /= s->area[i];
        *col += per_pass;
    }
    return CF_OK;
}


cf_status cfi_spin_exactness_dimension(cf_flow *flow, const cf_spin_willmore_options *o, int32_t *dim)
{
    const cf_mesh *mesh = flow->mesh;
    int32_t has_boundary = mesh->boundary_loop_count > 0;
    /* exactness: harmonic 1-forms of the input (App. C.1, steps I-III), on
     * closed surfaces of genus > 0 and on free-boundary surfaces that are
     * not disks (dim 2g + b - 1 > 0). Harmonic forms depend only on the
     * conformal structure, which the flow preserves, so the basis is
     * computed once. Not with fixed boundaries (the transformed boundary
     * edges are the input's, so the periods around the boundary loops vanish
     * identically) nor with prescribed / cmc ones (lambda is not near 1 on
     * the boundary and App. C's Z_i were measured to increase the periods
     * there), see docs/spin.md. */
    *dim = 0;
    if (o->exactness && (has_boundary ? o->boundary_mode == CF_SPIN_BOUNDARY_FREE : mesh->genus > 0))
        return cf_harmonic_basis(flow->ctx, mesh, flow->positions, dim, NULL);
    return CF_OK;
}

cf_status cfi_spin_exactness_init(cf_flow *flow, cfi_spin_state *s)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    int32_t dim2 = 0;
    cf_status st = cf_harmonic_basis(ctx, mesh, flow->positions, &dim2, s->harmonic);
    if (st != CF_OK) return st;
    if (CF_NEVER(dim2 != s->harmonic_dim))
        return cfi_error(ctx, CF_ERR_NUMERICAL, "spin-willmore: harmonic basis dimension changed");
    if (s->linearized) return cf_cotan_weights_floored(ctx, mesh, flow->positions, s->opt.weight_floor, s->hweights);
    return CF_OK;
}

cf_status cfi_spin_exactness_columns(cf_flow *flow, cfi_spin_state *s, const double *x, int32_t *col,
                                     double *factor_seconds, double *solve_seconds)
{
    s->diag.x0_solve_columns = s->linearized ? 0 : s->harmonic_dim;
    return s->linearized ? exactness_columns_linearized(flow, s, x, col, factor_seconds, solve_seconds)
                         : exactness_columns(flow, s, x, col, factor_seconds, solve_seconds);
}

cf_status cfi_spin_willmore_set_x0_full_solves(cf_flow *flow, int32_t full)
{
    if (!flow || flow->method != &cfi_spin_willmore_method || !flow->impl) return CF_ERR_INVALID_ARG;
    ((cfi_spin_state *)flow->impl)->x0_full_solves = full != 0;
    return CF_OK;
}
