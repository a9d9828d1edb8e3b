/*
 * Option keep_class of the spin-willmore flow: each attempt's positions are
 * moved back onto the input's conformal class before its W is judged
 * (docs/spin.md, "The conformal class the flow keeps").
 *
 * The flow keeps the class only up to the discretisation: elephant_g3_3k
 * drifts by 0.78 (the distance of cf_conformal_class_distance) in 10
 * default steps, first order in the edge length. The constraint is
 * c(x) = G^(x) - G^0 (keep_class 1: the class alone, the normalised Gram
 * matrix of cf_conformal_class_normalize, g (g + 1) degrees of freedom in
 * its g (2g + 1) entries) or c(x) = G(x) - G0 (keep_class 2: the Gram matrix
 * of cf_conformal_class_gram_gradient itself, which adds the discrete
 * star's defect, a property of the triangles: measured, holding it keeps
 * elk's triangles (mean Q 1.35 against 1.71 with the class alone) and
 * stalls the knotted tubes, whose W falls by crowding). Each Gauss-Newton
 * step solves
 *   min |dx|_S^-1  subject to  C dx = -c(x)   (C = dc/dx, upper triangle),
 * i.e. dx = -S C^T y with (C S C^T) y = c(x) (least squares: rank g (g + 1)
 * for the class alone, and G's scale is not free on a discrete surface),
 * and is halved until |c| falls; the projection stops below
 * CFI_SPIN_CLASS_TOLERANCE |G^0| and fails the attempt (the layer retries
 * at a smaller step) above CFI_SPIN_CLASS_ACCEPT |G^0|. Session 37 held all
 * of G with two plain Gauss-Newton steps: the correction of the star's
 * defect is what cost the knotted tubes their W (a step's W decrease
 * undone by the projection at every tau; the class alone: the script's
 * trefoil 10.80 -> 5.58 in 10 steps, against 10.79); without the halving
 * the class-alone projection diverged on elephant's second step (0.68 after
 * a Gauss-Newton step) and the run stopped after 3.
 * S = (I + kappa L)^-1 with the cotan Laplacian L of the positions
 * projected and unit vertex weights (kappa = CFI_SPIN_CLASS_SMOOTHING)
 * makes the correction smooth: with S = M^-1 the correction is rough and
 * raised bob's W/4pi from 1.85 to 8.7 in a measured projection of a
 * finished run; with the input's L instead of the current one the flow
 * stalled sooner (session 37). S is applied through a Cholesky factor of
 * L + I / kappa (y's scale does not change dx; L is PSD as a P1 stiffness
 * matrix, whatever its weights' signs), refilled and refactorised each
 * Gauss-Newton step on the pattern made at create, all 3 x pairs columns in
 * one solve.
 */
#include "methods/spin_willmore/spin_flow.h"
#include "curvflow/linalg.h"
#include "curvflow/metrics.h"
#include "curvflow/ops.h"

#include <math.h>
#include <string.h>

struct cfi_spin_class {
    int32_t dim, pairs, nv;
    double *target;        /* dim x dim: G^ (G with whole_gram) of the input */
    double *gram;          /* dim x dim: G of the positions projected */
    double *normalized;    /* dim x dim: their G^ (G with whole_gram) */
    double *form;          /* dim x dim: the intersection form */
    double *chain;         /* pairs x pairs: d G^ / d G */
    double *jacobian;      /* pairs x 3 nv: dG^_kl / dx (dG_kl / dx) */
    double *smoothed;      /* pairs x 3 nv: S applied to each row */
    double *system;        /* pairs x pairs: J S J^T */
    double *rhs;           /* pairs: G - G0, then y */
    double *work;          /* the least squares' */
    int64_t work_size, slot_count;
    double *columns;       /* 3 pairs x nv: the Jacobian's rows by coordinate, column-major */
    double *step, *trial;  /* 3 nv: a Gauss-Newton correction, the positions it is tried at */
    double scale;          /* |G0^| (Frobenius) */
    int32_t whole_gram;    /* keep_class 2: G itself rather than G^ */
    cf_conformal_class_workspace *class_workspace; /* G and dG/dx of each position set */
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
    CFI_FREE(ctx, c->normalized, n2);
    CFI_FREE(ctx, c->form, n2);
    CFI_FREE(ctx, c->chain, (int64_t)c->pairs * c->pairs);
    CFI_FREE(ctx, c->jacobian, rows);
    CFI_FREE(ctx, c->smoothed, rows);
    CFI_FREE(ctx, c->system, (int64_t)c->pairs * c->pairs);
    CFI_FREE(ctx, c->rhs, c->pairs);
    CFI_FREE(ctx, c->work, c->work_size);
    CFI_FREE(ctx, c->columns, rows);
    CFI_FREE(ctx, c->step, 3 * (int64_t)c->nv);
    CFI_FREE(ctx, c->trial, 3 * (int64_t)c->nv);
    cf_conformal_class_workspace_destroy(&c->class_workspace);
    cf_cholesky_destroy(&c->smoother);
    cf_sparse_destroy(&c->laplacian);
    if (c->slots) cfi_free(ctx, c->slots, (size_t)c->slot_count * sizeof *c->slots);
    cfi_free(ctx, c, sizeof *c);
    *cp = NULL;
}

cf_status cfi_spin_class_create(cf_flow *flow, int32_t whole_gram, cfi_spin_class **out)
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
    c->normalized = CFI_ALLOC(ctx, double, n2);
    c->form = CFI_ALLOC(ctx, double, n2);
    c->chain = CFI_ALLOC(ctx, double, (int64_t)c->pairs * c->pairs);
    c->jacobian = CFI_ALLOC(ctx, double, rows);
    c->smoothed = CFI_ALLOC(ctx, double, rows);
    c->system = CFI_ALLOC(ctx, double, (int64_t)c->pairs * c->pairs);
    c->rhs = CFI_ALLOC(ctx, double, c->pairs);
    c->work = CFI_ALLOC(ctx, double, c->work_size);
    c->columns = CFI_ALLOC(ctx, double, rows);
    c->step = CFI_ALLOC(ctx, double, 3 * (int64_t)c->nv);
    c->trial = CFI_ALLOC(ctx, double, 3 * (int64_t)c->nv);
    c->slot_count = cf_cotan_laplacian_slot_count(mesh);
    c->slots = CFI_ALLOC(ctx, int64_t, c->slot_count);
    cf_status st = c->target && c->gram && c->normalized && c->form && c->chain && c->jacobian && c->smoothed &&
                           c->system && c->rhs && c->work && c->columns && c->step && c->trial && c->slots
                       ? CF_OK
                       : CF_ERR_NOMEM;
    /* the input's class (the rest positions, also when the run starts
     * elsewhere: the class the flow is judged by) */
    if (st == CF_OK) st = cf_conformal_class_intersection_form(ctx, mesh, cf_mesh_positions(mesh), c->form);
    if (st == CF_OK) st = cf_conformal_class_workspace_create(ctx, mesh, &c->class_workspace);
    if (st == CF_OK) st = cf_conformal_class_workspace_gram_gradient(c->class_workspace, cf_mesh_positions(mesh), c->gram, NULL);
    c->whole_gram = whole_gram != 0;
    if (st == CF_OK && c->whole_gram) memcpy(c->target, c->gram, (size_t)n2 * sizeof(double));
    if (st == CF_OK && !c->whole_gram)
        st = cf_conformal_class_normalize(ctx, c->dim, c->form, c->gram, c->target, NULL);
    if (st == CF_OK) {
        double s2 = 0.0;
        for (int64_t q = 0; q < n2; ++q) s2 += c->target[q] * c->target[q];
        c->scale = sqrt(s2);
    }
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

/* G, G^ and the rows of d G^ / dx = (d G^ / d G) (d G / dx) at x into c,
 * the residual G^ - G0^ into c->rhs and its norm into *norm. */
static cf_status evaluate(cf_context *ctx, const cf_mesh *mesh, cfi_spin_class *c, const double *x, double *norm)
{
    int32_t dim = c->dim, pairs = c->pairs;
    int64_t len = 3 * (int64_t)c->nv;
    cf_status st = cf_conformal_class_workspace_gram_gradient(c->class_workspace, x, c->gram, c->jacobian);
    if (st == CF_OK && c->whole_gram) memcpy(c->normalized, c->gram, (size_t)dim * dim * sizeof(double));
    if (st == CF_OK && !c->whole_gram)
        st = cf_conformal_class_normalize(ctx, dim, c->form, c->gram, c->normalized, c->chain);
    if (st != CF_OK) return st;
    for (int32_t i = 0; i < pairs && !c->whole_gram; ++i) {
        double *row = c->smoothed + i * len; /* scratch here */
        memset(row, 0, (size_t)len * sizeof(double));
        for (int32_t j = 0; j < pairs; ++j) {
            double w = c->chain[i + (int64_t)j * pairs];
            if (w == 0.0) continue;
            const double *gj = c->jacobian + j * len;
            for (int64_t q = 0; q < len; ++q) row[q] += w * gj[q];
        }
    }
    if (!c->whole_gram) memcpy(c->jacobian, c->smoothed, (size_t)pairs * len * sizeof(double));
    double r2 = 0.0;
    int32_t p = 0;
    for (int32_t l = 0; l < dim; ++l)
        for (int32_t k = 0; k <= l; ++k, ++p) {
            c->rhs[p] = c->normalized[k + (int64_t)l * dim] - c->target[k + (int64_t)l * dim];
            r2 += c->rhs[p] * c->rhs[p];
        }
    *norm = sqrt(r2);
    return CF_OK;
}

/* The Gauss-Newton correction at the x evaluate() saw, into c->step. */
static cf_status correction(cf_context *ctx, const cf_mesh *mesh, cfi_spin_class *c, const double *x)
{
    int32_t pairs = c->pairs, nv = c->nv;
    int64_t len = 3 * (int64_t)nv;
    cf_status st = cf_cotan_laplacian_refill(c->laplacian, mesh, x, c->slots);
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
    if (st != CF_OK)
        return cfi_error(ctx, CF_ERR_NUMERICAL, "spin-willmore: keep_class: the class's Jacobian is not finite");
    memset(c->step, 0, (size_t)len * sizeof(double));
    for (int32_t i = 0; i < pairs; ++i) {
        const double *b = c->smoothed + i * len;
        double y = c->rhs[i];
        for (int64_t q = 0; q < len; ++q) c->step[q] -= y * b[q];
    }
    return CF_OK;
}

cf_status cfi_spin_class_project(cf_flow *flow, cfi_spin_class *c, double *x, double *residual)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    int64_t len = 3 * (int64_t)c->nv;
    double r = 0.0;
    cf_status st = evaluate(ctx, mesh, c, x, &r);
    for (int it = 0; st == CF_OK && it < CFI_SPIN_CLASS_ITERATIONS && r > CFI_SPIN_CLASS_TOLERANCE * c->scale; ++it) {
        st = correction(ctx, mesh, c, x);
        if (st != CF_OK) break;
        /* the step halved until the residual falls (a face that the trial
         * degenerates counts as no fall) */
        int accepted = 0;
        double alpha = 1.0;
        for (int h = 0; h <= CFI_SPIN_CLASS_HALVINGS && !accepted; ++h, alpha *= 0.5) {
            for (int64_t q = 0; q < len; ++q) c->trial[q] = x[q] + alpha * c->step[q];
            double rt = 0.0;
            cf_status sv = evaluate(ctx, mesh, c, c->trial, &rt);
            if (sv == CF_ERR_NOMEM) return sv;
            if (sv != CF_OK) cf_context_clear_error(ctx);
            if (sv == CF_OK && rt < r) {
                memcpy(x, c->trial, (size_t)len * sizeof(double));
                r = rt;
                accepted = 1;
            }
        }
        if (!accepted) break;
    }
    if (residual) *residual = r;
    if (st != CF_OK) return st;
    if (!(r <= CFI_SPIN_CLASS_ACCEPT * c->scale))
        return cfi_error(ctx, CF_ERR_NUMERICAL, "spin-willmore: keep_class: the positions stay %.3g from the class", r);
    return CF_OK;
}
