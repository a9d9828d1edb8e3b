/*
 * Vertex-scale fairing of positions: one implicit Laplacian step with the
 * cotan Laplacian L0 of a reference surface and unit vertex weights,
 *   x = argmin |x - f|^2 + kappa x^T L0 x   (held vertices keep f),
 * i.e. (I + kappa L0) x = f on the free vertices. L0's weights are
 * scale-free, so the step acts on every part of a surface at that part's
 * own size (a region shrunk by s moves by s times as much as before); an
 * eigenvector of L0 with eigenvalue mu is damped by 1 / (1 + kappa mu), so
 * for kappa of order one only modes that vary from one vertex to the next
 * (mu of order one) are damped and smooth ones (mu ~ 1 / nv) pass. Written
 * for spin-willmore's vertex-scale fairing (docs/spin.md, "Vertex-scale
 * fairing"); conventions: curvflow/ops.h.
 *
 * Solved by conjugate gradients with the diagonal as preconditioner, x, y
 * and z at once (cf_pcg_solve, curvflow/linalg.h): I + kappa L0 is well
 * conditioned for the kappa of a fairing (the identity dominates every
 * smooth mode), so no factorisation is kept; a factor would cost as much
 * memory as the position recovery's (0.4 GB at 655k vertices,
 * docs/memory.md) and a new one for every kappa.
 */
#include "curvflow/linalg.h"
#include "curvflow/ops.h"
#include "mesh/mesh_internal.h"
#include "ops/cotan_laplacian.h"

#include <math.h>
#include <string.h>

/* relative residual per coordinate at which the iteration stops, and its bound */
#define CFI_FAIRING_TOLERANCE 1e-12
#define CFI_FAIRING_MAX_ITERATIONS 2000

struct cf_vertex_fairing {
    cf_context *ctx;
    int32_t nv;
    cf_sparse *l0;         /* L0 (both triangles) */
    uint8_t *held;         /* nv: 1 = held at its input position */
    double *diag;          /* nv: L0's diagonal */
    double *r, *p, *q;     /* 3 nv each, interleaved like the positions */
    double *minv;          /* nv: the preconditioner 1 / (1 + kappa L0_ii), 0 where held */
    int32_t iterations;    /* of the last apply */
};

cf_status cf_vertex_fairing_create(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t hold_boundary,
                                   cf_vertex_fairing **out)
{
    return cf_vertex_fairing_create_floored(ctx, mesh, positions, hold_boundary, 0.0, out);
}

cf_status cf_vertex_fairing_create_floored(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                           int32_t hold_boundary, double weight_floor, cf_vertex_fairing **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out || !mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "vertex_fairing: mesh or out is NULL");
    *out = NULL;
    cf_status floor_ok = cfi_check_weight_floor(ctx, weight_floor, "vertex_fairing");
    if (floor_ok != CF_OK) return floor_ok;
    if (!positions) positions = mesh->positions;
    cf_vertex_fairing *f = CFI_ALLOC(ctx, cf_vertex_fairing, 1);
    if (!f) return CF_ERR_NOMEM;
    f->ctx = ctx;
    f->nv = mesh->nv;
    int64_t n3 = 3 * (int64_t)f->nv;
    f->held = CFI_ALLOC(ctx, uint8_t, f->nv);
    f->diag = CFI_ALLOC(ctx, double, f->nv);
    f->r = CFI_ALLOC(ctx, double, n3);
    f->minv = CFI_ALLOC(ctx, double, f->nv);
    f->p = CFI_ALLOC(ctx, double, n3);
    f->q = CFI_ALLOC(ctx, double, n3);
    cf_status st = CF_ERR_NOMEM;
    if (f->held && f->diag && f->r && f->minv && f->p && f->q) st = cfi_cotan_laplacian_pattern(ctx, mesh, positions, weight_floor, &f->l0, NULL);
    if (st != CF_OK) {
        cf_vertex_fairing_destroy(&f);
        return st;
    }
    for (int32_t i = 0; i < f->nv; ++i) {
        f->held[i] = hold_boundary && mesh->vertex_on_boundary[i];
        int64_t slot = cf_sparse_find(f->l0, i, i);
        f->diag[i] = slot >= 0 ? f->l0->values[slot] : 0.0;
    }
    *out = f;
    return CF_OK;
}

/* The operator of an apply: kappa with the fairing. */
typedef struct fairing_operator {
    const cf_vertex_fairing *f;
    double kappa;
} fairing_operator;

/* q = (I + kappa L0) p on the free vertices (q's held entries set to 0;
 * in the iteration p's held entries are 0 and stay 0), and pq[c] = p . q
 * per coordinate (cf_pcg_multiply_fn). L0 is symmetric, so column i of its
 * CSC form is row i. */
static void multiply(void *user, const double *p, double *q, double *pq)
{
    const fairing_operator *op = user;
    const cf_vertex_fairing *f = op->f;
    const cf_sparse *l = f->l0;
    pq[0] = pq[1] = pq[2] = 0.0;
    for (int32_t i = 0; i < f->nv; ++i) {
        double *qi = q + 3 * (int64_t)i;
        if (f->held[i]) {
            qi[0] = qi[1] = qi[2] = 0.0;
            continue;
        }
        double s[3] = {0.0, 0.0, 0.0};
        for (int32_t k = l->colptr[i]; k < l->colptr[i + 1]; ++k) {
            const double *pk = p + 3 * (int64_t)l->rowind[k];
            double a = l->values[k];
            s[0] += a * pk[0];
            s[1] += a * pk[1];
            s[2] += a * pk[2];
        }
        const double *pi = p + 3 * (int64_t)i;
        for (int c = 0; c < 3; ++c) {
            qi[c] = pi[c] + op->kappa * s[c];
            pq[c] += pi[c] * qi[c];
        }
    }
}

cf_status cf_vertex_fairing_apply(cf_vertex_fairing *f, double kappa, const double *in, double *out,
                                  cf_solver_timings *timings)
{
    if (!f || !in || !out) return CF_ERR_INVALID_ARG;
    if (!(kappa >= 0.0) || !isfinite(kappa))
        return cfi_error(f->ctx, CF_ERR_INVALID_ARG, "vertex_fairing: kappa must be finite and >= 0, got %g", kappa);
    int32_t nv = f->nv;
    int64_t n3 = 3 * (int64_t)nv;
    f->iterations = 0;
    for (int64_t i = 0; i < n3; ++i)
        if (!isfinite(in[i]))
            return cfi_error(f->ctx, CF_ERR_NUMERICAL, "vertex_fairing: vertex %lld: position is not finite",
                             (long long)(i / 3));
    if (kappa == 0.0) {
        if (out != in) memmove(out, in, (size_t)n3 * sizeof(double));
        return CF_OK;
    }
    double t0 = cfi_now_seconds();
    /* The unknown is the change d = out - in, with (I + kappa L0) d =
     * -kappa L0 in on the free vertices (held ones do not move), so that the
     * tolerance is relative to the change, whatever the coordinates'
     * offset. Preconditioner: the diagonal 1 + kappa L0_ii. */
    fairing_operator op = {f, kappa};
    double *r = f->r, unused[3];
    /* r = (I + kappa L0) in on the free rows, then in - r below; in's held
     * entries couple into the free rows, as they must (they stay put) */
    multiply(&op, in, r, unused);
    for (int32_t i = 0; i < nv; ++i) {
        f->minv[i] = f->held[i] ? 0.0 : 1.0 / (1.0 + kappa * f->diag[i]);
        for (int c = 0; c < 3; ++c) r[3 * i + c] = f->held[i] ? 0.0 : in[3 * i + c] - r[3 * i + c];
    }
    if (out != in) memmove(out, in, (size_t)n3 * sizeof(double));
    cf_pcg_result pcg;
    cf_status st = cf_pcg_solve(f->ctx, nv, 3, multiply, &op, f->minv, out, r, f->p, f->q, CFI_FAIRING_TOLERANCE,
                                CFI_FAIRING_MAX_ITERATIONS, &pcg);
    f->iterations = pcg.iterations;
    if (timings) timings->solve_seconds += cfi_now_seconds() - t0;
    if (st == CF_ERR_NOT_CONVERGED) return cfi_error_prefix(f->ctx, "vertex_fairing (kappa %g)", kappa);
    if (st != CF_OK) return st;
    for (int64_t i = 0; i < n3; ++i)
        if (!isfinite(out[i]))
            return cfi_error(f->ctx, CF_ERR_NUMERICAL, "vertex_fairing: vertex %lld: result is not finite",
                             (long long)(i / 3));
    return CF_OK;
}

int32_t cf_vertex_fairing_iterations(const cf_vertex_fairing *f) { return f ? f->iterations : 0; }

void cf_vertex_fairing_destroy(cf_vertex_fairing **fp)
{
    if (!fp || !*fp) return;
    cf_vertex_fairing *f = *fp;
    cf_context *ctx = f->ctx;
    int64_t n3 = 3 * (int64_t)f->nv;
    cf_sparse_destroy(&f->l0);
    if (f->held) CFI_FREE(ctx, f->held, f->nv);
    if (f->diag) CFI_FREE(ctx, f->diag, f->nv);
    if (f->r) CFI_FREE(ctx, f->r, n3);
    if (f->minv) CFI_FREE(ctx, f->minv, f->nv);
    if (f->p) CFI_FREE(ctx, f->p, n3);
    if (f->q) CFI_FREE(ctx, f->q, n3);
    CFI_FREE(ctx, f, 1);
    *fp = NULL;
}
