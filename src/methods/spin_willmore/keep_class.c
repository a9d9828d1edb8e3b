/*
 * Option keep_class of the spin-willmore flow: each attempt's positions are
 * moved back onto the input's conformal class before its W is judged
 * (docs/spin.md, "The conformal class the flow keeps").
 *
 * The flow keeps the class only up to the discretisation: elephant_g3_3k
 * drifts by 0.78 (the distance of cf_conformal_class_distance) in 10
 * default steps, first order in the edge length. With G(x) the Gram matrix
 * of the harmonic forms dual to the marked cycles (cf_conformal_class_
 * gram_gradient) and G0 the input's, each Gauss-Newton step solves
 *   min |dx|_S^-1  subject to  J dx = -(G(x) - G0)   (J = dG/dx, upper triangle),
 * i.e. dx = -S J^T y with (J S J^T) y = G(x) - G0 (least squares: the
 * scale of G is not free on a discrete surface, so the system may be one
 * short of full rank). S = (I + kappa L)^-1 with the cotan Laplacian L of
 * the positions projected and unit vertex weights (kappa =
 * CFI_SPIN_CLASS_SMOOTHING) makes the correction smooth: with S = M^-1 the
 * correction is rough and raised bob's W/4pi from 1.85 to 8.7 in a
 * measured projection of a finished run; with the input's L instead of the
 * current one the flow stalled sooner (elk: W/4pi 12.84 after 10 steps
 * against 10.50, elephant 7.40 in 7 steps against 6.33 in 6). S is applied
 * through a Cholesky factor of L + I / kappa (y's scale does not change
 * dx; L is PSD as a P1 stiffness matrix, whatever its weights' signs),
 * refilled and refactorised each Gauss-Newton step on the pattern made at
 * create, all 3 x pairs columns in one solve.
 */
#include "methods/spin_willmore/spin_flow.h"
#include "curvflow/linalg.h"
#include "curvflow/metrics.h"
#include "curvflow/ops.h"

#include <math.h>
#include <string.h>

struct cfi_spin_class {
    int32_t dim, pairs, nv;
    double *target;        /* dim x dim: G of the input */
    double *gram;          /* dim x dim: G of the positions projected */
    double *jacobian;      /* pairs x 3 nv: dG_kl / dx */
    double *smoothed;      /* pairs x 3 nv: S applied to each row */
    double *system;        /* pairs x pairs: J S J^T */
    double *rhs;           /* pairs: G - G0, then y */
    double *work;          /* the least squares' */
    int64_t work_size, slot_count;
    double *columns;       /* 3 pairs x nv: the Jacobian's rows by coordinate, column-major */
    cf_sparse *laplacian;  /* L of the positions projected (pattern of the input's) */
    int64_t *slots;        /* its refill map */
    cf_cholesky *smoother; /* L + I / kappa */
};

void cfi_spin_class_destroy(cf_context *ctx, cfi_spin_class **cp)
{
    cfi_spin_class *c = cp ? *cp : NULL;
    if (!c) return;
    int64_t n2 = (int64_t)c->dim * c->dim, rows = (int64_t)c->pairs * 3 * c->nv;
    CFI_FREE(ctx, c->target, n2);
    CFI_FREE(ctx, c->gram, n2);
    CFI_FREE(ctx, c->jacobian, rows);
    CFI_FREE(ctx, c->smoothed, rows);
    CFI_FREE(ctx, c->system, (int64_t)c->pairs * c->pairs);
    CFI_FREE(ctx, c->rhs, c->pairs);
    CFI_FREE(ctx, c->work, c->work_size);
    CFI_FREE(ctx, c->columns, rows);
    cf_cholesky_destroy(&c->smoother);
    cf_sparse_destroy(&c->laplacian);
    if (c->slots) cfi_free(ctx, c->slots, (size_t)c->slot_count * sizeof *c->slots);
    cfi_free(ctx, c, sizeof *c);
    *cp = NULL;
}

cf_status cfi_spin_class_create(cf_flow *flow, cfi_spin_class **out)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    *out = NULL;
    cfi_spin_class *c = cfi_malloc(ctx, sizeof *c);
    if (!c) return CF_ERR_NOMEM;
    memset(c, 0, sizeof *c);
    c->dim = 2 * cf_mesh_genus(mesh);
    c->pairs = c->dim * (c->dim + 1) / 2;
    c->nv = mesh->nv;
    int64_t n2 = (int64_t)c->dim * c->dim, rows = (int64_t)c->pairs * 3 * c->nv;
    c->work_size = cf_dense_least_squares_work_size(c->pairs, c->pairs);
    c->target = CFI_ALLOC(ctx, double, n2);
    c->gram = CFI_ALLOC(ctx, double, n2);
    c->jacobian = CFI_ALLOC(ctx, double, rows);
    c->smoothed = CFI_ALLOC(ctx, double, rows);
    c->system = CFI_ALLOC(ctx, double, (int64_t)c->pairs * c->pairs);
    c->rhs = CFI_ALLOC(ctx, double, c->pairs);
    c->work = CFI_ALLOC(ctx, double, c->work_size);
    c->columns = CFI_ALLOC(ctx, double, rows);
    c->slot_count = cf_cotan_laplacian_slot_count(mesh);
    c->slots = CFI_ALLOC(ctx, int64_t, c->slot_count);
    cf_status st = c->target && c->gram && c->jacobian && c->smoothed && c->system && c->rhs && c->work &&
                           c->columns && c->slots
                       ? CF_OK
                       : CF_ERR_NOMEM;
    /* the input's class (the rest positions, also when the run starts
     * elsewhere: the class the flow is judged by) */
    if (st == CF_OK) st = cf_conformal_class_gram_gradient(ctx, mesh, cf_mesh_positions(mesh), c->target, NULL);
    if (st == CF_OK)
        st = cf_cotan_laplacian_with_slots(ctx, mesh, cf_mesh_positions(mesh), &c->laplacian, c->slots);
    if (st == CF_OK) st = cf_cholesky_create(ctx, c->laplacian, NULL, &c->smoother);
    if (st != CF_OK) {
        cfi_spin_class_destroy(ctx, &c);
        return st;
    }
    *out = c;
    return CF_OK;
}

cf_status cfi_spin_class_project(cf_flow *flow, cfi_spin_class *c, double *x, double *residual)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    int32_t dim = c->dim, pairs = c->pairs;
    int64_t len = 3 * (int64_t)c->nv;
    for (int it = 0; it < CFI_SPIN_CLASS_ITERATIONS; ++it) {
        cf_status st = cf_conformal_class_gram_gradient(ctx, mesh, x, c->gram, c->jacobian);
        if (st != CF_OK) return st;
        double r2 = 0.0;
        int32_t p = 0;
        for (int32_t l = 0; l < dim; ++l)
            for (int32_t k = 0; k <= l; ++k, ++p) {
                c->rhs[p] = c->gram[k + (int64_t)l * dim] - c->target[k + (int64_t)l * dim];
                r2 += c->rhs[p] * c->rhs[p];
            }
        if (residual) *residual = sqrt(r2);
        int32_t nv = c->nv;
        st = cf_cotan_laplacian_refill(c->laplacian, mesh, x, c->slots);
        if (st == CF_OK) st = cf_cholesky_factorize_shifted(c->smoother, c->laplacian, 1.0 / CFI_SPIN_CLASS_SMOOTHING);
        if (st != CF_OK) return st;
        for (int32_t i = 0; i < pairs; ++i)
            for (int32_t v = 0; v < nv; ++v)
                for (int q = 0; q < 3; ++q)
                    c->columns[((int64_t)3 * i + q) * nv + v] = c->jacobian[i * len + 3 * (int64_t)v + q];
        st = cf_cholesky_solve(c->smoother, 3 * pairs, c->columns, c->columns);
        if (st != CF_OK) return st;
        for (int32_t i = 0; i < pairs; ++i)
            for (int32_t v = 0; v < nv; ++v)
                for (int q = 0; q < 3; ++q)
                    c->smoothed[i * len + 3 * (int64_t)v + q] = c->columns[((int64_t)3 * i + q) * nv + v];
        for (int32_t i = 0; i < pairs; ++i)
            for (int32_t j = 0; j <= i; ++j) {
                double sum = 0.0;
                const double *a = c->jacobian + i * len, *b = c->smoothed + j * len;
                for (int64_t q = 0; q < len; ++q) sum += a[q] * b[q];
                c->system[i + (int64_t)j * pairs] = c->system[j + (int64_t)i * pairs] = sum;
            }
        int32_t rank = 0;
        st = cf_dense_least_squares(pairs, pairs, c->system, c->rhs, 1e-10, c->work, c->work_size, &rank);
        if (st != CF_OK) return cfi_error(ctx, CF_ERR_NUMERICAL, "spin-willmore: keep_class: the class's Jacobian is not finite");
        for (int32_t i = 0; i < pairs; ++i) {
            const double *b = c->smoothed + i * len;
            double y = c->rhs[i];
            for (int64_t q = 0; q < len; ++q) x[q] -= y * b[q];
        }
    }
    return CF_OK;
}
