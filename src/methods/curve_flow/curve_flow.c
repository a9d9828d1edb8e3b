/*
 * Isometric curve flow of closed planar polylines: Crane, Pinkall, Schroeder
 * 2013, "Robust Fairing via Conformal Curvature Flow", Sec. 5, 5.1, 5.2 and
 * App. A (Table 1, left column).
 *
 * One step: curvature kappa_i = turning angle / dual length; kappadot = -2
 * kappa projected (under the dual-length inner product) off {1, f^x, f^y};
 * kappa <- kappa + tau kappadot; tangent angles by cumulative sums (Sec. 5.2),
 * rotated so that their mean change is zero (Sec. 5.1); new edges
 * T~_i = l_i (cos theta_i, sin theta_i) with the input lengths l_i; positions
 * from L f~ = b (Sec. 5.2), translated to keep the centroid. L depends only
 * on the input lengths, so it is factorised once.
 */
#include "curvflow/curve_flow.h"
#include "curvflow/linalg.h"
#include "core/core.h"

#include <math.h>
#include <string.h>

#define CFI_PI 3.14159265358979323846


struct cf_curve_flow {
    cf_context *ctx;
    cfi_workspace ws;  /* the arrays below (points ... sol) */
    int32_t n;
    double tau;
    double *points;    /* 2 n */
    double *len;       /* n: l_i of edge (i, i+1), input */
    double *dual;      /* n */
    double *kappa;     /* n */
    double *kdot;      /* n */
    double *theta;     /* n */
    double *basis;     /* 3 n */
    double *rhs;       /* 2 n column-major */
    double *sol;       /* 2 n */
    cf_sparse *l;
    cf_cholesky *chol;
    int64_t iteration;
    double energy0;        /* sum kappa^2 l* of the input (divergence check) */
    int32_t turning0;      /* turning number of the input, kept by every step */
};

void cf_curve_flow_options_default(cf_curve_flow_options *o)
{
    if (!o) return;
    memset(o, 0, sizeof *o);
    o->time_step = 0.5;
}

void cf_curve_flow_destroy(cf_curve_flow **pf)
{
    if (!pf || !*pf) return;
    cf_curve_flow *f = *pf;
    cf_context *ctx = f->ctx;
    cf_cholesky_destroy(&f->chol);
    cf_sparse_destroy(&f->l);
    cfi_workspace_free_all(&f->ws);
    CFI_FREE(ctx, f, 1);
    *pf = NULL;
}

/* Signed turning angle at vertex i of the current points. */
static double turning(const double *p, int32_t n, int32_t i)
{
    int32_t a = (i + n - 1) % n, b = (i + 1) % n;
    double u[2] = {p[2 * i] - p[2 * a], p[2 * i + 1] - p[2 * a + 1]};
    double v[2] = {p[2 * b] - p[2 * i], p[2 * b + 1] - p[2 * i + 1]};
    return atan2(u[0] * v[1] - u[1] * v[0], u[0] * v[0] + u[1] * v[1]);
}

/* Energy sum kappa_i^2 l*_i (kappa_i = turning angle / l*_i) of the points p
 * and, if asked, their turning number. */
static double energy_of(const double *p, int32_t n, const double *dual, int32_t *turning_number)
{
    double e = 0.0, turn = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        double phi = turning(p, n, i), k = phi / dual[i];
        e += k * k * dual[i];
        turn += phi;
    }
    if (turning_number) *turning_number = (int32_t)lround(turn / (2.0 * CFI_PI));
    return e;
}

/* kappa and energy of the current state. */
static double curvature(cf_curve_flow *f)
{
    double e = 0.0;
    for (int32_t i = 0; i < f->n; ++i) {
        f->kappa[i] = turning(f->points, f->n, i) / f->dual[i];
        e += f->kappa[i] * f->kappa[i] * f->dual[i];
    }
    return e;
}

cf_status cf_curve_flow_create(cf_context *ctx, int32_t n, const double *points,
                               const cf_curve_flow_options *options, cf_curve_flow **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out || !points) return cfi_error(ctx, CF_ERR_INVALID_ARG, "curve_flow: points and out are required");
    *out = NULL;
    if (n < 3) return cfi_error(ctx, CF_ERR_INVALID_ARG, "curve_flow: need at least 3 points, got %d", n);
    cf_curve_flow_options defaults;
    cf_curve_flow_options_default(&defaults);
    if (!options) options = &defaults;
    if (!(options->time_step > 0.0) || !isfinite(options->time_step))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "curve_flow: time_step must be > 0, got %g", options->time_step);
    for (int32_t i = 0; i < 2 * n; ++i) {
        if (!isfinite(points[i])) return cfi_error(ctx, CF_ERR_NONFINITE, "point %d: not finite", i / 2);
        if (fabs(points[i]) > CF_MAX_COORDINATE)
            return cfi_error(ctx, CF_ERR_NONFINITE, "point %d: coordinate %.3g is out of range (|x| > %.0e)", i / 2,
                             points[i], CF_MAX_COORDINATE);
    }
    cf_curve_flow *f = CFI_ALLOC(ctx, cf_curve_flow, 1);
    if (!f) return CF_ERR_NOMEM;
    f->ctx = ctx;
    cfi_workspace_init(&f->ws, ctx);
    f->n = n;
    f->tau = options->time_step;
    f->points = CFI_WS_ALLOC(&f->ws, double, 2 * (int64_t)n);
    f->len = CFI_WS_ALLOC(&f->ws, double, n);
    f->dual = CFI_WS_ALLOC(&f->ws, double, n);
    f->kappa = CFI_WS_ALLOC(&f->ws, double, n);
    f->kdot = CFI_WS_ALLOC(&f->ws, double, n);
    f->theta = CFI_WS_ALLOC(&f->ws, double, n);
    f->basis = CFI_WS_ALLOC(&f->ws, double, 3 * (int64_t)n);
    f->rhs = CFI_WS_ALLOC(&f->ws, double, 2 * (int64_t)n);
    f->sol = CFI_WS_ALLOC(&f->ws, double, 2 * (int64_t)n);
    /* the Laplacian's triplets, for create only */
    int32_t *ri = CFI_ALLOC(ctx, int32_t, 4 * (int64_t)n);
    int32_t *ci = CFI_ALLOC(ctx, int32_t, 4 * (int64_t)n);
    double *vv = CFI_ALLOC(ctx, double, 4 * (int64_t)n);
    cf_status st = CF_OK;
    if (!f->points || !f->len || !f->dual || !f->kappa || !f->kdot || !f->theta || !f->basis || !f->rhs || !f->sol ||
        !ri || !ci || !vv) {
        st = CF_ERR_NOMEM;
        goto done;
    }
    memcpy(f->points, points, 2 * (size_t)n * sizeof(double));
    double total = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        int32_t j = (i + 1) % n;
        f->len[i] = hypot(points[2 * j] - points[2 * i], points[2 * j + 1] - points[2 * i + 1]);
        if (!(f->len[i] > 0.0)) {
            st = cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "edge %d (points %d, %d): zero length", i, i, j);
            goto done;
        }
        if (f->len[i] < CF_MIN_EDGE_LENGTH) {
            st = cfi_error(ctx, CF_ERR_DEGENERATE_FACE,
                           "edge %d (points %d, %d): length %.3g is below %.0e, the range of lengths this library "
                           "computes with; rescale the curve",
                           i, i, j, f->len[i], CF_MIN_EDGE_LENGTH);
            goto done;
        }
        total += f->len[i];
    }
    for (int32_t i = 0; i < n; ++i) {
        /* a turn of exactly 180 degrees has no signed angle (+pi or -pi), so
         * neither the curvature nor the turning number is defined there */
        int32_t a = (i + n - 1) % n, b = (i + 1) % n;
        double u[2] = {points[2 * i] - points[2 * a], points[2 * i + 1] - points[2 * a + 1]};
        double v[2] = {points[2 * b] - points[2 * i], points[2 * b + 1] - points[2 * i + 1]};
        if (u[0] * v[1] - u[1] * v[0] == 0.0 && u[0] * v[0] + u[1] * v[1] < 0.0) {
            st = cfi_error(ctx, CF_ERR_DEGENERATE_FACE,
                           "point %d: the curve turns back on itself (a 180 degree turn has no signed angle)", i);
            goto done;
        }
    }
    for (int32_t i = 0; i < n; ++i) f->dual[i] = 0.5 * (f->len[(i + n - 1) % n] + f->len[i]);
    /* Sec. 5.2: L_ij = -1/l_ij, L_ii = 1/l_{i-1,i} + 1/l_{i,i+1}; a shift of
     * 1e-10 of the mean diagonal removes the constant null space (the
     * centroid is fixed afterwards). */
    double shift = 0.0;
    for (int32_t i = 0; i < n; ++i) shift += 2.0 / f->len[i];
    shift *= 1e-10 / n;
    int64_t t = 0;
    for (int32_t i = 0; i < n; ++i) {
        int32_t j = (i + 1) % n;
        double w = 1.0 / f->len[i];
        ri[t] = i; ci[t] = i; vv[t++] = w + shift * 0.5;
        ri[t] = j; ci[t] = j; vv[t++] = w + shift * 0.5;
        ri[t] = i; ci[t] = j; vv[t++] = -w;
        ri[t] = j; ci[t] = i; vv[t++] = -w;
    }
    st = cf_sparse_from_triplets(ctx, n, n, t, ri, ci, vv, 1, &f->l, NULL);
    if (st != CF_OK) goto done;
    cf_cholesky_options co;
    cf_cholesky_options_default(&co);
    co.block_size = 1;
    st = cf_cholesky_create(ctx, f->l, &co, &f->chol);
    if (st == CF_OK) st = cf_cholesky_factorize(f->chol, f->l);
    (void)total;
    if (st == CF_OK) f->energy0 = energy_of(points, n, f->dual, &f->turning0);
done:
    CFI_FREE(ctx, ri, 4 * (int64_t)n);
    CFI_FREE(ctx, ci, 4 * (int64_t)n);
    CFI_FREE(ctx, vv, 4 * (int64_t)n);
    if (st != CF_OK) {
        cf_curve_flow_destroy(&f);
        return st;
    }
    *out = f;
    return CF_OK;
}

cf_status cf_curve_flow_step(cf_curve_flow *f, cf_curve_flow_info *info)
{
    if (!f) return CF_ERR_INVALID_ARG;
    int32_t n = f->n;
    double *p = f->points;
    curvature(f);
    /* Sec. 4: kappadot = -2 kappa, projected off {1, f^x, f^y} (App. A) */
    for (int32_t i = 0; i < n; ++i) {
        f->kdot[i] = -2.0 * f->kappa[i];
        f->basis[i] = 1.0;
        f->basis[n + i] = p[2 * i];
        f->basis[2 * n + i] = p[2 * i + 1];
    }
    double k0 = sqrt(cf_dot(n, f->kdot, f->kdot, f->dual));
    int32_t rank = 0;
    cf_orthonormalize(n, 3, f->basis, f->dual, 1e-12, &rank);
    cf_project_out(n, rank, f->basis, f->dual, f->kdot);
    double resid = 0.0;
    for (int32_t j = 0; j < rank; ++j) {
        double r = k0 > 0.0 ? fabs(cf_dot(n, f->kdot, f->basis + (int64_t)j * n, f->dual)) / k0 : 0.0;
        if (r > resid) resid = r;
    }
    /* Eq. (3) / Sec. 5.2: cumulative angles of the new curvature, and of the
     * current one (to remove the mean rotation, Sec. 5.1) */
    double theta0 = atan2(p[3] - p[1], p[2] - p[0]);
    double th_new = theta0, th_old = theta0, mean_diff = 0.0, len_sum = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        if (i > 0) {
            th_new += f->dual[i] * (f->kappa[i] + f->tau * f->kdot[i]);
            th_old += f->dual[i] * f->kappa[i];
        }
        f->theta[i] = th_new;
        mean_diff += f->len[i] * (th_old - th_new);
        len_sum += f->len[i];
    }
    mean_diff /= len_sum;
    double gap[2] = {0.0, 0.0};
    double c_old[2] = {0.0, 0.0};
    for (int32_t i = 0; i < n; ++i) {
        c_old[0] += p[2 * i];
        c_old[1] += p[2 * i + 1];
        f->theta[i] += mean_diff;
    }
    /* b_i = T~_{i-1}/l_{i-1} - T~_i/l_i = unit tangent differences */
    for (int32_t i = 0; i < n; ++i) {
        int32_t a = (i + n - 1) % n;
        double ci = cos(f->theta[i]), si = sin(f->theta[i]);
        f->rhs[i] = cos(f->theta[a]) - ci;
        f->rhs[n + i] = sin(f->theta[a]) - si;
        gap[0] += f->len[i] * ci;
        gap[1] += f->len[i] * si;
    }
    cf_status st = cf_cholesky_solve(f->chol, 2, f->rhs, f->sol);
    if (st != CF_OK) return st;
    double c_new[2] = {0.0, 0.0};
    for (int32_t i = 0; i < n; ++i) {
        c_new[0] += f->sol[i];
        c_new[1] += f->sol[n + i];
    }
    /* the candidate goes to rhs (free after the solve); the state changes
     * only if the step is good, so a failed step keeps the last good curve */
    double *cand = f->rhs;
    for (int32_t i = 0; i < n; ++i) {
        double x = f->sol[i] + (c_old[0] - c_new[0]) / n, y = f->sol[n + i] + (c_old[1] - c_new[1]) / n;
        if (!isfinite(x) || !isfinite(y))
            return cfi_error(f->ctx, CF_ERR_NUMERICAL, "iteration %lld: point %d: not finite",
                             (long long)f->iteration + 1, i);
        cand[2 * i] = x;
        cand[2 * i + 1] = y;
    }
    /* Above the stability limit (tau near 1 and beyond, Sec. 4) the explicit
     * step on kappa overshoots: the energy climbs and the curve can wind
     * differently. Both contradict the flow (energy descent, turning number
     * kept), so they are failures rather than results. */
    int32_t winding = 0;
    double e_new = energy_of(cand, n, f->dual, &winding);
    if (winding != f->turning0)
        return cfi_error(f->ctx, CF_ERR_NUMERICAL,
                         "iteration %lld: the turning number changed from %d to %d: time_step %g is above the "
                         "stability limit (about 1)",
                         (long long)f->iteration + 1, f->turning0, winding, f->tau);
    if (e_new > f->energy0 * (1.0 + 1e-9))
        return cfi_error(f->ctx, CF_ERR_NUMERICAL,
                         "iteration %lld: the energy rose to %.6g, above its starting value %.6g: the flow diverges "
                         "(time_step %g is above the stability limit, about 1)",
                         (long long)f->iteration + 1, e_new, f->energy0, f->tau);
    memcpy(p, cand, 2 * (size_t)n * sizeof(double));
    ++f->iteration;
    if (info) {
        info->iteration = f->iteration;
        info->energy = e_new; /* of the accepted points, now p */
        info->closure_gap = hypot(gap[0], gap[1]) / len_sum;
        info->constraint_residual = resid;
        double maxerr = 0.0;
        for (int32_t i = 0; i < n; ++i) {
            int32_t j = (i + 1) % n;
            double l = hypot(p[2 * j] - p[2 * i], p[2 * j + 1] - p[2 * i + 1]);
            double e = fabs(l - f->len[i]) / f->len[i];
            if (e > maxerr) maxerr = e;
        }
        info->max_length_error = maxerr;
        info->turning_number = winding;
    }
    return CF_OK;
}

const double *cf_curve_flow_points(const cf_curve_flow *f) { return f ? f->points : NULL; }
int32_t cf_curve_flow_size(const cf_curve_flow *f) { return f ? f->n : 0; }

double cf_curve_flow_energy(const cf_curve_flow *f)
{
    if (!f) return NAN;
    return energy_of(f->points, f->n, f->dual, NULL);
}
