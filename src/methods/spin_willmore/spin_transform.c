/*
 * SpinXForm: spin transformation of a surface from a prescribed change of
 * mean curvature rho per vertex (Crane, Pinkall, Schroeder 2011, as used in
 * Crane, Pinkall, Schroeder 2013, Sec. 6 and App. G):
 *   1. assemble X(rho) (dirac.c) and factorise X + eps M (block size 4);
 *   2. smallest eigenvector lambda by inverse power iteration;
 *   3. transform the edges by lambda and solve the cotan Poisson problem.
 */
#include "methods/spin_willmore/spin_internal.h"
#include "curvflow/ops.h"

#include <math.h>
#include <string.h>

#define CFI_PI 3.14159265358979323846

cf_status cfi_spin_power_iteration(cf_cholesky *chol, const double *mass, int32_t nv, int32_t iterations,
                                   double *lambda, double *work)
{
    double total = 0.0;
    for (int32_t i = 0; i < nv; ++i) total += mass[i];
    for (int32_t it = 0; it < iterations; ++it) {
        for (int32_t i = 0; i < nv; ++i)
            for (int c = 0; c < 4; ++c) work[4 * i + c] = mass[i] * lambda[4 * i + c];
        cf_status st = cf_cholesky_solve(chol, 1, work, lambda);
        if (st != CF_OK) return st;
        double n2 = 0.0;
        for (int32_t i = 0; i < nv; ++i) {
            const double *l = lambda + 4 * i;
            n2 += mass[i] * (l[0] * l[0] + l[1] * l[1] + l[2] * l[2] + l[3] * l[3]);
        }
        if (!(n2 > 0.0) || !isfinite(n2)) return CF_ERR_NUMERICAL;
        double s = sqrt(total / n2);
        for (int32_t i = 0; i < 4 * nv; ++i) lambda[i] *= s;
    }
    return CF_OK;
}

double cfi_spin_rayleigh(const cf_sparse *x, const double *mass, int32_t nv, double eps, const double *lambda,
                         double *work)
{
    cf_sparse_multiply(x, lambda, work);
    double num = 0.0, den = 0.0;
    for (int32_t i = 0; i < nv; ++i)
        for (int c = 0; c < 4; ++c) {
            num += lambda[4 * i + c] * work[4 * i + c];
            den += mass[i] * lambda[4 * i + c] * lambda[4 * i + c];
        }
    return den > 0.0 ? num / den - eps : 0.0;
}

cf_status cf_spin_transform(cf_context *ctx, const cf_mesh *mesh, const double *positions, const double *rho,
                            double *out_positions)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!mesh || !rho || !out_positions)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin_transform: mesh, rho and out_positions are required");
    if (!positions) positions = mesh->positions;
    if (positions == out_positions)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin_transform: out_positions may not alias positions");
    int32_t nv = mesh->nv;
    for (int32_t i = 0; i < nv; ++i)
        if (!isfinite(rho[i])) return cfi_error(ctx, CF_ERR_NONFINITE, "vertex %d: rho is not finite", i);
    int64_t bad = cfi_first_unusable_point(positions, nv, 3);
    if (bad >= 0)
        return cfi_error(ctx, CF_ERR_NONFINITE, "vertex %d: position is not finite or beyond %.0e", (int)bad,
                         CF_MAX_COORDINATE);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t i = 0; i < nv; ++i)
        for (int c = 0; c < 3; ++c) {
            lo[c] = fmin(lo[c], positions[3 * i + c]);
            hi[c] = fmax(hi[c], positions[3 * i + c]);
        }
    /* rho is a curvature (1 / length): measured against the mesh's size it
     * must stay inside the range of lengths the library computes with, or its
     * square overflows in the matrix of App. G */
    double size = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    for (int32_t i = 0; i < nv; ++i)
        if (fabs(rho[i]) * size > CF_MAX_COORDINATE)
            return cfi_error(ctx, CF_ERR_NONFINITE,
                             "vertex %d: rho = %.3g is out of range (|rho| times the mesh size %.3g exceeds %.0e)", i,
                             rho[i], size, CF_MAX_COORDINATE);
    cfi_dirac *dirac = NULL;
    cf_edge_poisson *poisson = NULL;
    cf_cholesky *chol = NULL;
    double *mass = CFI_ALLOC(ctx, double, nv);
    double *lambda = CFI_ALLOC(ctx, double, 4 * (int64_t)nv);
    double *work = CFI_ALLOC(ctx, double, 4 * (int64_t)nv);
    double *edges = CFI_ALLOC(ctx, double, 3 * (int64_t)mesh->ne);
    cf_status st = CF_OK;
    if (!mass || !lambda || !work || !edges) {
        st = CF_ERR_NOMEM;
        goto done;
    }
    double area = 0.0;
    st = cf_vertex_areas(ctx, mesh, positions, CF_DUAL_AREA_BARYCENTRIC, mass);
    if (st != CF_OK) goto done;
    for (int32_t i = 0; i < nv; ++i) area += mass[i];
    double eps = CFI_SPIN_SHIFT * 4.0 * CFI_PI / area;
    st = cfi_dirac_create(ctx, mesh, &dirac);
    if (st == CF_OK) st = cfi_dirac_fill(dirac, mesh, positions, rho, eps);
    if (st != CF_OK) goto done;
    cf_cholesky_options co;
    cf_cholesky_options_default(&co);
    co.block_size = 4;
    co.quaternion_blocks = 1; /* X(rho) is Hermitian quaternionic: factorised in complex form */
    st = cf_cholesky_create(ctx, dirac->x, &co, &chol);
    if (st == CF_OK) st = cf_cholesky_factorize(chol, dirac->x);
    if (st != CF_OK) goto done;
    for (int32_t i = 0; i < nv; ++i) {
        lambda[4 * i] = 1.0;
        lambda[4 * i + 1] = lambda[4 * i + 2] = lambda[4 * i + 3] = 0.0;
    }
    /* converge the eigenvector (the flow itself takes one iteration per step) */
    double gamma_old = INFINITY;
    for (int it = 0; it < 50; ++it) {
        st = cfi_spin_power_iteration(chol, mass, nv, 1, lambda, work);
        if (st != CF_OK) goto done;
        double gamma = cfi_spin_rayleigh(dirac->x, mass, nv, eps, lambda, work);
        if (fabs(gamma - gamma_old) <= 1e-12 * (fabs(gamma) + eps)) break;
        gamma_old = gamma;
    }
    cfi_spin_transform_edges(mesh, positions, lambda, edges);
    st = cf_edge_poisson_create(ctx, mesh, positions, 0, NULL, &poisson);
    if (st == CF_OK) st = cf_edge_poisson_solve(poisson, edges, NULL, out_positions, NULL);
    if (st != CF_OK) goto done;
    /* keep the area-weighted centroid */
    double c_in[3] = {0, 0, 0}, c_out[3] = {0, 0, 0};
    for (int32_t i = 0; i < nv; ++i)
        for (int c = 0; c < 3; ++c) {
            c_in[c] += mass[i] * positions[3 * i + c];
            c_out[c] += mass[i] * out_positions[3 * i + c];
        }
    for (int32_t i = 0; i < nv; ++i)
        for (int c = 0; c < 3; ++c) out_positions[3 * i + c] += (c_in[c] - c_out[c]) / area;
done:
    cf_cholesky_destroy(&chol);
    cfi_dirac_destroy(ctx, &dirac);
    cf_edge_poisson_destroy(&poisson);
    CFI_FREE(ctx, mass, nv);
    CFI_FREE(ctx, lambda, 4 * (int64_t)nv);
    CFI_FREE(ctx, work, 4 * (int64_t)nv);
    CFI_FREE(ctx, edges, 3 * (int64_t)mesh->ne);
    return st;
}
