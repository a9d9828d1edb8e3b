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

/* The weighted centroid of each connected component of x (3 per
 * component) and each one's total weight (mass: one per component). */
static void component_centroids(const cf_mesh *mesh, const double *weight, const double *x, double *mass,
                               double *centroid)
{
    int32_t nc = mesh->component_count;
    for (int32_t c = 0; c < nc; ++c) mass[c] = centroid[3 * c] = centroid[3 * c + 1] = centroid[3 * c + 2] = 0.0;
    for (int32_t i = 0; i < mesh->nv; ++i) {
        int32_t c = mesh->vertex_component[i];
        mass[c] += weight[i];
        for (int d = 0; d < 3; ++d) centroid[3 * c + d] += weight[i] * x[3 * i + d];
    }
    for (int32_t c = 0; c < nc; ++c)
        for (int d = 0; d < 3; ++d) centroid[3 * c + d] /= mass[c];
}

/* On a mesh of several connected components: lambda (4 nv) rescaled on each
 * component to sum M |lambda|^2 = that component's sum of M. X is block
 * diagonal over the components, so an eigenvector of the whole matrix would
 * put all its weight on the component of the smallest eigenvalue and shrink
 * the others to a point; per component, each keeps its size. sums: 2 x the
 * component count of scratch. (Flows do not need this: the flow layer runs
 * one flow per component, methods/flow_parts.c.) */
static void normalize_components(const cf_mesh *mesh, const double *mass, double *lambda, double *sums)
{
    int32_t nc = mesh->component_count;
    double *component_mass = sums, *component_norm = sums + nc;
    for (int32_t c = 0; c < nc; ++c) component_mass[c] = component_norm[c] = 0.0;
    for (int32_t i = 0; i < mesh->nv; ++i) {
        const double *l = lambda + 4 * (int64_t)i;
        int32_t c = mesh->vertex_component[i];
        component_mass[c] += mass[i];
        component_norm[c] += mass[i] * (l[0] * l[0] + l[1] * l[1] + l[2] * l[2] + l[3] * l[3]);
    }
    for (int32_t c = 0; c < nc; ++c)
        component_norm[c] = component_norm[c] > 0.0 ? sqrt(component_mass[c] / component_norm[c]) : 1.0;
    for (int32_t i = 0; i < mesh->nv; ++i)
        for (int k = 0; k < 4; ++k) lambda[4 * (int64_t)i + k] *= component_norm[mesh->vertex_component[i]];
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
    double lo[3], hi[3];
    cfi_bounding_box(positions, nv, lo, hi);
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
    /* several components: each one's lambda scale and centroids (7 per component) */
    int32_t nc = mesh->component_count;
    double *sums = nc > 1 ? CFI_ALLOC(ctx, double, 7 * (int64_t)nc) : NULL;
    cf_status st = CF_OK;
    if (!mass || !lambda || !work || !edges || (nc > 1 && !sums)) {
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
        /* normalised to sum M |lambda|^2 = area (mean |lambda|^2 = 1) */
        st = cf_inverse_iteration_blocks(chol, mass, 4, 1, area, lambda, work);
        if (st != CF_OK) goto done;
        if (nc > 1) normalize_components(mesh, mass, lambda, sums);
        double q = cf_rayleigh_quotient_blocks(dirac->x, mass, 4, lambda, work);
        double gamma = isnan(q) ? 0.0 : q - eps;
        if (fabs(gamma - gamma_old) <= 1e-12 * (fabs(gamma) + eps)) break;
        gamma_old = gamma;
    }
    cfi_spin_transform_edges(mesh, positions, lambda, edges);
    /* the flow's floor on the recovery's weights: a near-duplicate vertex
     * would cost the solve its accuracy (the star of test thin_faces with
     * one at 1e-12 of an edge: the result off by 0.24 of the diagonal; 0.011
     * with the floor, what the moved vertex itself changes) */
    st = cf_edge_poisson_create_floored(ctx, mesh, positions, 0, NULL, CFI_SPIN_WEIGHT_FLOOR, &poisson);
    if (st == CF_OK) st = cf_edge_poisson_solve(poisson, edges, NULL, out_positions, NULL);
    if (st != CF_OK) goto done;
    /* keep the area-weighted centroid (of each component: the Poisson
     * problem fixes each one's positions only up to its own translation) */
    if (nc > 1) {
        double *mass_c = sums, *c_in = sums + nc, *c_out = c_in + 3 * (int64_t)nc;
        component_centroids(mesh, mass, positions, mass_c, c_in);
        component_centroids(mesh, mass, out_positions, mass_c, c_out);
        for (int32_t i = 0; i < nv; ++i) {
            int32_t c = mesh->vertex_component[i];
            for (int d = 0; d < 3; ++d) out_positions[3 * i + d] += c_in[3 * c + d] - c_out[3 * c + d];
        }
    } else {
        double c_in[3] = {0, 0, 0}, c_out[3] = {0, 0, 0};
        for (int32_t i = 0; i < nv; ++i)
            for (int c = 0; c < 3; ++c) {
                c_in[c] += mass[i] * positions[3 * i + c];
                c_out[c] += mass[i] * out_positions[3 * i + c];
            }
        for (int32_t i = 0; i < nv; ++i)
            for (int c = 0; c < 3; ++c) out_positions[3 * i + c] += (c_in[c] - c_out[c]) / area;
    }
done:
    cf_cholesky_destroy(&chol);
    cfi_dirac_destroy(ctx, &dirac);
    cf_edge_poisson_destroy(&poisson);
    CFI_FREE(ctx, mass, nv);
    CFI_FREE(ctx, lambda, 4 * (int64_t)nv);
    CFI_FREE(ctx, work, 4 * (int64_t)nv);
    CFI_FREE(ctx, edges, 3 * (int64_t)mesh->ne);
    if (sums) CFI_FREE(ctx, sums, 7 * (int64_t)nc);
    return st;
}
