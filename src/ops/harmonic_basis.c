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

/* cotan Laplacian plus its mean diagonal at the first vertex of each
 * component (scale-matched pin) */
static cf_status pinned_laplacian(cf_context *ctx, const cf_mesh *mesh, const double *positions, cf_sparse **out)
{
    cf_status s = cf_cotan_laplacian(ctx, mesh, positions, out);
    if (s != CF_OK) return s;
    cf_sparse *l = *out;
    double mean_diag = 0.0;
    for (int32_t v = 0; v < mesh->nv; ++v) {
        int64_t k = cf_sparse_find(l, v, v);
        if (k >= 0) mean_diag += l->values[k];
    }
    mean_diag /= mesh->nv;
    uint8_t *pinned = CFI_ALLOC(ctx, uint8_t, mesh->component_count);
    if (!pinned) {
        cf_sparse_destroy(out);
        return CF_ERR_NOMEM;
    }
    for (int32_t v = 0; v < mesh->nv; ++v) {
        int32_t c = mesh->vertex_component[v];
        if (pinned[c]) continue;
        pinned[c] = 1;
        int64_t k = cf_sparse_find(l, v, v);
        if (CF_NEVER(k < 0)) continue;
        l->values[k] += mean_diag;
    }
    CFI_FREE(ctx, pinned, mesh->component_count);
    return CF_OK;
}

static cf_status factor(cf_context *ctx, const cf_sparse *a, cf_cholesky **out)
{
    cf_status s = cf_cholesky_create(ctx, a, NULL, out);
    if (s == CF_OK) s = cf_cholesky_factorize(*out, a);
    return s;
}

cf_status cf_harmonic_basis(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t *dimension,
                            double *basis)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, dimension, "harmonic_basis");
    if (s != CF_OK) return s;
    /* components that touch the boundary */
    uint8_t *open = CFI_ALLOC(ctx, uint8_t, mesh->component_count);
    if (!open) return CF_ERR_NOMEM;
    int32_t closed_count = mesh->component_count;
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
    int64_t k64 = (int64_t)mesh->ne - mesh->nv - mesh->nf + mesh->component_count + closed_count;
    if (CF_NEVER(k64 < 0 || k64 > mesh->ne)) {
        CFI_FREE(ctx, open, mesh->component_count);
        return cfi_error(ctx, CF_ERR_NUMERICAL, "harmonic_basis: inconsistent first Betti number %lld", (long long)k64);
    }
    int32_t k = (int32_t)k64;
    *dimension = k;
    if (!basis || k == 0) {
        CFI_FREE(ctx, open, mesh->component_count);
        return CF_OK;
    }

    int32_t ne = mesh->ne, nf = mesh->nf, nv = mesh->nv;
    cf_sparse *b = NULL, *l = NULL;
    cf_cholesky *cb = NULL, *cl = NULL;
    double *w = CFI_ALLOC(ctx, double, ne);
    double *rf = CFI_ALLOC(ctx, double, (int64_t)nf * k);
    double *rv = CFI_ALLOC(ctx, double, (int64_t)nv * k);
    if (!w || !rf || !rv) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    if ((s = cf_cotan_weights(ctx, mesh, positions, w)) != CF_OK) goto done;
    if ((s = dual_laplacian(ctx, mesh, open, &b)) != CF_OK) goto done;
    if ((s = pinned_laplacian(ctx, mesh, positions, &l)) != CF_OK) goto done;
    if ((s = factor(ctx, b, &cb)) != CF_OK) goto done;
    if ((s = factor(ctx, l, &cl)) != CF_OK) goto done;

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
        if ((s = cf_cholesky_solve(cb, k, rf, rf)) != CF_OK) goto done;
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
                double y = w[e] * om[e];
                r[mesh->edge_vertices[2 * e + 1]] += y;
                r[mesh->edge_vertices[2 * e]] -= y;
            }
        }
        if ((s = cf_cholesky_solve(cl, k, rv, rv)) != CF_OK) goto done;
        for (int32_t c = 0; c < k; ++c) {
            double *om = basis + (int64_t)ne * c, *a = rv + (int64_t)nv * c;
            for (int32_t e = 0; e < ne; ++e)
                om[e] -= a[mesh->edge_vertices[2 * e + 1]] - a[mesh->edge_vertices[2 * e]];
        }
    }
    /* III. Gram-Schmidt under *1 */
    int32_t rank = 0;
    cf_orthonormalize(ne, k, basis, w, 1e-8, &rank);
    if (rank != k)
        s = cfi_error(ctx, CF_ERR_NUMERICAL, "harmonic_basis: only %d of %d harmonic forms are independent", rank,
                      k);
done:
    cf_cholesky_destroy(&cb);
    cf_cholesky_destroy(&cl);
    cf_sparse_destroy(&b);
    cf_sparse_destroy(&l);
    CFI_FREE(ctx, w, ne);
    CFI_FREE(ctx, rf, (int64_t)nf * k);
    CFI_FREE(ctx, rv, (int64_t)nv * k);
    CFI_FREE(ctx, open, mesh->component_count);
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
