/*
 * Basis of harmonic 1-forms (Crane, Pinkall & Schroeder 2013, App. C.1,
 * steps I-III) and the per-face vector field of a 1-form (Whitney
 * interpolation at the barycentre; for closed forms it equals the vector v
 * of App. C.1 with <v, e> = omega(e) on every edge of the face).
 *
 * The basis spans the first de Rham cohomology H^1(M): dimension 2g on a
 * closed component and 2g + b - 1 on a component with b > 0 boundary loops
 * (0 on a disk). With boundary the representatives are the Neumann harmonic
 * fields: closed (d1 h = 0 on every face) and co-closed at EVERY vertex,
 * boundary vertices included (d0^T *1 h = 0). At a boundary vertex that row
 * is the discrete natural condition "no flux through the boundary"
 * (*h = 0 along the boundary). These are the right test forms for
 * exactness: by the Hodge-Morrey-Friedrichs decomposition the closed forms
 * are dOmega^0 (+) H_N, so a closed form is exact iff it is *1-orthogonal to
 * every Neumann harmonic field (for an annulus: iff its period around the
 * hole vanishes).
 *
 * Hodge decomposition (Desbrun et al. 2008), done in two solves that both
 * stay positive definite on any mesh:
 *  1. closed part: omega1 = omega - d1^T gamma with (d1 d1^T) gamma = d1 omega.
 *     The combinatorial dual Laplacian d1 d1^T is used instead of
 *     d1 *1^-1 d1^T because cotan weights may be zero or negative (obtuse
 *     pairs), which makes the latter indefinite or undefined. Any closed
 *     form is fine here: only its cohomology class matters.
 *  2. exact part: h = omega1 - d0 alpha with L alpha = d0^T *1 omega1
 *     (Neumann Laplacian: every vertex is a row), so h is closed
 *     (d1 d0 = 0) and co-closed at every vertex: harmonic.
 * The cotan Laplacian has one constant per connected component in its
 * kernel, d1 d1^T one per CLOSED component (on a component with boundary
 * d1 is onto: a face function g with d1^T g = 0 is constant and vanishes
 * at a boundary edge). Adding 1 to the diagonal at one element of each such
 * component makes them definite without changing the solution, because the
 * right-hand sides sum to zero there (then that element's value is forced
 * to 0); components with boundary must not be pinned, or d1 h would be
 * nonzero at the pinned face.
 * Finally the forms are orthonormalised under <a, b> = sum_e *1_e a_e b_e,
 * which is positive definite on closed forms (it equals the L2 norm of the
 * per-face vector field, boundary edges included) even where some *1_e < 0.
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

#include <string.h>

/* face-sign of halfedge h: +1 if it runs along its edge's orientation */
static double halfedge_sign(const cf_mesh *mesh, int64_t h)
{
    return mesh->triangles[h] == mesh->edge_vertices[2 * mesh->halfedge_edge[h]] ? 1.0 : -1.0;
}

/* d1 d1^T: 3 on the diagonal, -1 between faces sharing an edge (opposite
 * traversal), plus the pin on the first face of each closed component
 * (open[c] != 0 marks a component with boundary: no pin). */
static cf_status dual_laplacian(cf_context *ctx, const cf_mesh *mesh, const uint8_t *open, cf_sparse **out)
{
    int64_t n = (int64_t)mesh->nf + 2 * (int64_t)mesh->ne;
    int32_t *rows = CFI_ALLOC(ctx, int32_t, n);
    int32_t *cols = CFI_ALLOC(ctx, int32_t, n);
    double *vals = CFI_ALLOC(ctx, double, n);
    uint8_t *pinned = CFI_ALLOC(ctx, uint8_t, mesh->component_count);
    cf_status s = CF_OK;
    if (!rows || !cols || !vals || !pinned) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    int64_t k = 0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        int32_t c = mesh->face_component[f];
        rows[k] = cols[k] = f;
        vals[k++] = pinned[c] || open[c] ? 3.0 : 4.0;
        pinned[c] = 1;
    }
    for (int32_t e = 0; e < mesh->ne; ++e) {
        int32_t f = mesh->edge_faces[2 * e], g = mesh->edge_faces[2 * e + 1];
        if (f < 0 || g < 0) continue;
        rows[k] = f;
        cols[k] = g;
        vals[k++] = -1.0;
        rows[k] = g;
        cols[k] = f;
        vals[k++] = -1.0;
    }
    s = cf_sparse_from_triplets(ctx, mesh->nf, mesh->nf, k, rows, cols, vals, 1, out, NULL);
done:
    CFI_FREE(ctx, rows, n);
    CFI_FREE(ctx, cols, n);
    CFI_FREE(ctx, vals, n);
    CFI_FREE(ctx, pinned, mesh->component_count);
    return s;
}

/* The pin of the cotan Laplacian: its mean diagonal added at the first
 * vertex of each component (scale-matched); diag[v] is vertex v's diagonal
 * slot in l->values. */
static void pin_laplacian(const cf_mesh *mesh, cf_sparse *l, const int64_t *diag, const int32_t *pin_vertex,
                          int32_t pins)
{
    double mean_diag = 0.0;
    for (int32_t v = 0; v < mesh->nv; ++v) mean_diag += l->values[diag[v]];
    mean_diag /= mesh->nv;
    for (int32_t p = 0; p < pins; ++p)
        if (pin_vertex[p] >= 0) l->values[diag[pin_vertex[p]]] += mean_diag;
}

/* The first Betti number (the basis' dimension) and, in open (one byte per
 * component), which components touch the boundary. */
static cf_status first_betti_number(cf_context *ctx, const cf_mesh *mesh, uint8_t *open, int64_t *k64)
{
    int32_t closed_count = mesh->component_count;
    memset(open, 0, (size_t)mesh->component_count);
    for (int32_t v = 0; v < mesh->nv; ++v) {
        int32_t c = mesh->vertex_component[v];
        if (mesh->vertex_on_boundary[v] && !open[c]) {
            open[c] = 1;
            --closed_count;
        }
    }
    /* dim ker d1 - dim im d0 = (ne - rank d1) - (nv - #components) with
     * rank d1 = nf - #closed components: sum over components of 2g on closed
     * ones and 2g + b - 1 on ones with boundary. */
    *k64 = (int64_t)mesh->ne - mesh->nv - mesh->nf + mesh->component_count + closed_count;
    if (CF_NEVER(*k64 < 0 || *k64 > mesh->ne))
        return cfi_error(ctx, CF_ERR_NUMERICAL, "harmonic_basis: inconsistent first Betti number %lld",
                         (long long)*k64);
    return CF_OK;
}

struct cf_harmonic_workspace {
    cf_context *ctx;
    const cf_mesh *mesh;
    int32_t dim;
    cf_sparse *dual, *laplacian; /* d1 d1^T (pinned, fixed), the pinned cotan Laplacian (NULL until the
                                  * first compute, then refilled) */
    cf_cholesky *dual_factor, *laplacian_factor;
    int64_t *slots;              /* the Laplacian's refill map: vertex v's diagonal at slots[v] */
    int64_t slot_count;
    int32_t *pin_vertex;         /* the first vertex of each component */
    double *weights, *rf, *rv;   /* *1 (ne), face and vertex right-hand sides (nf dim, nv dim) */
};

void cf_harmonic_workspace_destroy(cf_harmonic_workspace **wp)
{
    cf_harmonic_workspace *w = wp ? *wp : NULL;
    if (!w) return;
    cf_context *ctx = w->ctx;
    const cf_mesh *mesh = w->mesh;
    cf_cholesky_destroy(&w->dual_factor);
    cf_cholesky_destroy(&w->laplacian_factor);
    cf_sparse_destroy(&w->dual);
    cf_sparse_destroy(&w->laplacian);
    CFI_FREE(ctx, w->slots, w->slot_count);
    CFI_FREE(ctx, w->pin_vertex, mesh->component_count);
    CFI_FREE(ctx, w->weights, mesh->ne);
    CFI_FREE(ctx, w->rf, (int64_t)mesh->nf * w->dim);
    CFI_FREE(ctx, w->rv, (int64_t)mesh->nv * w->dim);
    cfi_free(ctx, w, sizeof *w);
    *wp = NULL;
}

int32_t cf_harmonic_workspace_dimension(const cf_harmonic_workspace *w) { return w ? w->dim : 0; }

cf_status cf_harmonic_workspace_create(cf_context *ctx, const cf_mesh *mesh, cf_harmonic_workspace **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "harmonic_workspace: out is NULL");
    *out = NULL;
    if (!mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "harmonic_workspace: mesh is NULL");
    cf_harmonic_workspace *w = cfi_malloc(ctx, sizeof *w);
    if (!w) return CF_ERR_NOMEM;
    memset(w, 0, sizeof *w);
    w->ctx = ctx;
    w->mesh = mesh;
    /* components that touch the boundary */
    uint8_t *open = CFI_ALLOC(ctx, uint8_t, mesh->component_count);
    if (!open) {
        cfi_free(ctx, w, sizeof *w);
        return CF_ERR_NOMEM;
    }
    int64_t k64 = 0;
    cf_status s = first_betti_number(ctx, mesh, open, &k64);
    w->dim = s == CF_OK ? (int32_t)k64 : 0;
    if (s == CF_OK && w->dim > 0) {
        w->slot_count = cf_cotan_laplacian_slot_count(mesh);
        w->slots = CFI_ALLOC(ctx, int64_t, w->slot_count);
        w->pin_vertex = CFI_ALLOC(ctx, int32_t, mesh->component_count);
        w->weights = CFI_ALLOC(ctx, double, mesh->ne);
        w->rf = CFI_ALLOC(ctx, double, (int64_t)mesh->nf * w->dim);
        w->rv = CFI_ALLOC(ctx, double, (int64_t)mesh->nv * w->dim);
        if (!w->slots || !w->pin_vertex || !w->weights || !w->rf || !w->rv) s = CF_ERR_NOMEM;
        if (s == CF_OK) {
            /* each component's first vertex */
            for (int32_t c = 0; c < mesh->component_count; ++c) w->pin_vertex[c] = -1;
            for (int32_t v = 0; v < mesh->nv; ++v)
                if (w->pin_vertex[mesh->vertex_component[v]] < 0) w->pin_vertex[mesh->vertex_component[v]] = v;
        }
        if (s == CF_OK) s = dual_laplacian(ctx, mesh, open, &w->dual);
        if (s == CF_OK) s = cf_cholesky_create(ctx, w->dual, NULL, &w->dual_factor);
        if (s == CF_OK) s = cf_cholesky_factorize(w->dual_factor, w->dual);
        if (s == CF_OK) s = cf_cholesky_reserve_solve(w->dual_factor, w->dim);
        /* the cotan Laplacian: built and analysed at the first compute */
    }
    CFI_FREE(ctx, open, mesh->component_count);
    if (s != CF_OK) {
        cf_harmonic_workspace_destroy(&w);
        return s;
    }
    *out = w;
    return CF_OK;
}

cf_status cf_harmonic_workspace_compute(cf_harmonic_workspace *w, const double *positions, double *basis)
{
    if (!w) return CF_ERR_INVALID_ARG;
    cf_context *ctx = w->ctx;
    const cf_mesh *mesh = w->mesh;
    cf_status s = cfi_ops_check(ctx, mesh, positions, basis, "harmonic_basis");
    if (s != CF_OK || w->dim == 0) return s;
    int32_t ne = mesh->ne, nf = mesh->nf, nv = mesh->nv, k = w->dim;
    double *rf = w->rf, *rv = w->rv, *wt = w->weights;
    if ((s = cf_cotan_weights(ctx, mesh, positions, wt)) != CF_OK) return s;
    /* the first compute builds L from its positions (as cf_cotan_laplacian,
     * bit for bit) and analyses it; later ones refill it, which sums the
     * diagonal in another order (1 ulp apart on bob_5k) */
    if (w->laplacian) {
        s = cf_cotan_laplacian_refill(w->laplacian, mesh, positions, w->slots);
    } else {
        s = cf_cotan_laplacian_with_slots(ctx, mesh, positions, &w->laplacian, w->slots);
        if (s == CF_OK) s = cf_cholesky_create(ctx, w->laplacian, NULL, &w->laplacian_factor);
        if (s == CF_OK) s = cf_cholesky_reserve_solve(w->laplacian_factor, w->dim);
        if (s != CF_OK) {
            cf_cholesky_destroy(&w->laplacian_factor);
            cf_sparse_destroy(&w->laplacian);
        }
    }
    if (s != CF_OK) return s;
    pin_laplacian(mesh, w->laplacian, w->slots, w->pin_vertex, mesh->component_count);
    if ((s = cf_cholesky_factorize(w->laplacian_factor, w->laplacian)) != CF_OK) return s;

    /* I. random 1-forms (fixed-seed LCG, so the basis is deterministic) */
    uint64_t state = 0x2545f4914f6cdd1dull;
    for (int64_t i = 0; i < (int64_t)ne * k; ++i) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        basis[i] = (double)(state >> 11) / 9007199254740992.0 * 2.0 - 1.0;
    }
    /* II. Hodge decomposition, applied twice: the harmonic part of a random
     * form is small next to its exact/coexact parts, so one pass leaves
     * round-off of the size of the whole form (~1e-10 relative to h); the
     * second pass works on h itself and removes it. */
    for (int pass = 0; pass < 2; ++pass) {
        /* II.1 remove the part that is not closed: rf = d1 omega */
        for (int32_t c = 0; c < k; ++c) {
            double *om = basis + (int64_t)ne * c, *r = rf + (int64_t)nf * c;
            for (int32_t f = 0; f < nf; ++f) {
                r[f] = 0.0;
                for (int j = 0; j < 3; ++j) {
                    int64_t h = 3 * (int64_t)f + j;
                    r[f] += halfedge_sign(mesh, h) * om[mesh->halfedge_edge[h]];
                }
            }
        }
        if ((s = cf_cholesky_solve(w->dual_factor, k, rf, rf)) != CF_OK) return s;
        for (int32_t c = 0; c < k; ++c) {
            double *om = basis + (int64_t)ne * c, *g = rf + (int64_t)nf * c;
            for (int64_t h = 0; h < 3 * (int64_t)nf; ++h)
                om[mesh->halfedge_edge[h]] -= halfedge_sign(mesh, h) * g[h / 3];
        }
        /* II.2 remove the exact part: rv = d0^T *1 omega1, alpha = L^-1 rv */
        for (int32_t c = 0; c < k; ++c) {
            double *om = basis + (int64_t)ne * c, *r = rv + (int64_t)nv * c;
            for (int32_t v = 0; v < nv; ++v) r[v] = 0.0;
            for (int32_t e = 0; e < ne; ++e) {
                double y = wt[e] * om[e];
                r[mesh->edge_vertices[2 * e + 1]] += y;
                r[mesh->edge_vertices[2 * e]] -= y;
            }
        }
        if ((s = cf_cholesky_solve(w->laplacian_factor, k, rv, rv)) != CF_OK) return s;
        for (int32_t c = 0; c < k; ++c) {
            double *om = basis + (int64_t)ne * c, *a = rv + (int64_t)nv * c;
            for (int32_t e = 0; e < ne; ++e)
                om[e] -= a[mesh->edge_vertices[2 * e + 1]] - a[mesh->edge_vertices[2 * e]];
        }
    }
    /* III. Gram-Schmidt under *1 */
    int32_t rank = 0;
    cf_orthonormalize(ne, k, basis, wt, 1e-8, &rank);
    if (rank != k)
        return cfi_error(ctx, CF_ERR_NUMERICAL, "harmonic_basis: only %d of %d harmonic forms are independent", rank,
                         k);
    return CF_OK;
}

cf_status cf_harmonic_basis(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t *dimension,
                            double *basis)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, dimension, "harmonic_basis");
    if (s != CF_OK) return s;
    if (!basis) {
        /* the dimension alone, without the factorisations */
        uint8_t *open = CFI_ALLOC(ctx, uint8_t, mesh->component_count);
        if (!open) return CF_ERR_NOMEM;
        int64_t k64 = 0;
        s = first_betti_number(ctx, mesh, open, &k64);
        CFI_FREE(ctx, open, mesh->component_count);
        if (s == CF_OK) *dimension = (int32_t)k64;
        return s;
    }
    cf_harmonic_workspace *w = NULL;
    if ((s = cf_harmonic_workspace_create(ctx, mesh, &w)) != CF_OK) return s;
    *dimension = w->dim;
    if (w->dim > 0) s = cf_harmonic_workspace_compute(w, positions, basis);
    cf_harmonic_workspace_destroy(&w);
    return s;
}

/* Whitney 1-form at the barycentre (phi = 1/3):
 * W = sum_{halfedges a->b} omega_ab (phi_a grad phi_b - phi_b grad phi_a)
 *   = (1/3) sum omega_ab (grad phi_b - grad phi_a). */
cf_status cf_one_form_to_vector_field(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                      const double *one_form, double *field)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, field, "one_form_to_vector_field");
    if (s != CF_OK) return s;
    if (!one_form) return cfi_error(ctx, CF_ERR_INVALID_ARG, "one_form_to_vector_field: one_form is NULL");
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double g[9];
        s = cfi_face_hat_gradients(ctx, mesh, positions, f, g, NULL);
        if (s != CF_OK) return s;
        double v[3] = {0.0, 0.0, 0.0};
        for (int j = 0; j < 3; ++j) {
            int64_t h = 3 * (int64_t)f + j;
            double om = halfedge_sign(mesh, h) * one_form[mesh->halfedge_edge[h]];
            /* halfedge j runs corner j -> corner j+1 */
            for (int c = 0; c < 3; ++c) v[c] += om * (g[3 * ((j + 1) % 3) + c] - g[3 * j + c]);
        }
        for (int c = 0; c < 3; ++c) field[3 * f + c] = v[c] / 3.0;
    }
    return CF_OK;
}
