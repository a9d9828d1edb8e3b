/*
 * Facewise quaternionic matrix X(rho) of Crane, Pinkall, Schroeder 2013,
 * App. G, as a real symmetric 4 nv x 4 nv matrix (each quaternion entry is
 * the 4 x 4 matrix of left multiplication, Le Folgoc Eq. (7)), plus the edge
 * transformation of the vertex-based spin transformation (Crane et al. 2011).
 * The pattern and a slot per 4 x 4 block column are computed once; every
 * fill then writes values in place without allocating.
 */
#include "methods/spin_willmore/spin_internal.h"

#include <math.h>
#include <string.h>

/* The complex form: the vertex graph from the edges (i < j, upper
 * triangle) and the diagonal, its cf_quat_sparse pattern, and the complex
 * entry of each edge's and vertex's block: block k of block column J
 * starts at colptr[2 J] + 2 k (curvflow/linalg.h), and graph slot q of
 * column J is that block k = q - gcp[J]. The same pairs as the faces'
 * (every edge and vertex lies on a face), so the same pattern. */
static cf_status create_complex(cf_context *ctx, const cf_mesh *mesh, cfi_dirac *d)
{
    int32_t nv = mesh->nv, ne = mesh->ne;
    int64_t npair = (int64_t)ne + nv;
    int32_t *rows = CFI_ALLOC(ctx, int32_t, npair);
    int32_t *cols = CFI_ALLOC(ctx, int32_t, npair);
    int64_t *slots = CFI_ALLOC(ctx, int64_t, npair);
    cf_sparse *g = NULL;
    d->zslot = CFI_ALLOC(ctx, int32_t, ne);
    d->zdiag = CFI_ALLOC(ctx, int32_t, nv);
    cf_status st = CF_OK;
    if (!rows || !cols || !slots || !d->zslot || !d->zdiag) {
        st = CF_ERR_NOMEM;
        goto done;
    }
    /* pairs 0 .. ne - 1: the edges; ne + i: vertex i */
    for (int32_t e = 0; e < ne; ++e) {
        rows[e] = mesh->edge_vertices[2 * e];
        cols[e] = mesh->edge_vertices[2 * e + 1];
    }
    for (int32_t i = 0; i < nv; ++i) rows[(int64_t)ne + i] = cols[(int64_t)ne + i] = i;
    st = cf_sparse_from_triplets(ctx, nv, nv, npair, rows, cols, NULL, 0, &g, slots);
    if (st == CF_OK) st = cf_quat_sparse_create(ctx, g, &d->z);
    if (st != CF_OK) goto done;
    const int32_t *zcp = d->z->colptr, *gcp = g->colptr;
    for (int64_t q = 0; q < npair; ++q) {
        int32_t j = cols[q];
        int32_t entry = zcp[2 * j] + 2 * (int32_t)(slots[q] - gcp[j]);
        if (q < ne) d->zslot[q] = entry;
        else d->zdiag[j] = entry;
    }
done:
    cf_sparse_destroy(&g);
    CFI_FREE(ctx, rows, npair);
    CFI_FREE(ctx, cols, npair);
    CFI_FREE(ctx, slots, npair);
    return st;
}

/* The real form: the vertex graph with a dense 4 x 4 block per entry,
 * assembled from 9 vertex pairs per face and lifted, instead of from 144
 * triplets per face (at 655k vertices those took 6 GB of index and sort
 * arrays and 20 s; docs/memory.md). Same pattern and slots. */
static cf_status create_real(cf_context *ctx, const cf_mesh *mesh, cfi_dirac *d)
{
    int32_t nv = mesh->nv, nf = mesh->nf;
    int64_t npair = (int64_t)nf * 9;
    int32_t *rows = CFI_ALLOC(ctx, int32_t, npair);
    int32_t *cols = CFI_ALLOC(ctx, int32_t, npair);
    int64_t *slots = CFI_ALLOC(ctx, int64_t, npair);
    cf_sparse *g = NULL;
    d->block_slot = CFI_ALLOC(ctx, int64_t, (int64_t)nf * 36);
    d->diag_slot = CFI_ALLOC(ctx, int64_t, (int64_t)nv * 4);
    cf_status st = CF_OK;
    if (!rows || !cols || !slots || !d->block_slot || !d->diag_slot) {
        st = CF_ERR_NOMEM;
        goto done;
    }
    /* pair p = k * 9 + m * 3 + n: vertices (tri[m], tri[n]) of face k */
    for (int32_t k = 0; k < nf; ++k) {
        const int32_t *tri = mesh->triangles + 3 * k;
        for (int m = 0; m < 3; ++m)
            for (int n = 0; n < 3; ++n) {
                rows[(int64_t)k * 9 + m * 3 + n] = tri[m];
                cols[(int64_t)k * 9 + m * 3 + n] = tri[n];
            }
    }
    st = cf_sparse_from_triplets(ctx, nv, nv, npair, rows, cols, NULL, 1, &g, slots);
    if (st == CF_OK) st = cf_sparse_kron_dense(ctx, g, 4, &d->x);
    if (st != CF_OK) goto done;
    /* entry (4 i + r, 4 j + c) of the vertex pair in slot q of g (column j)
     * sits at X.colptr[4 j + c] + 4 (q - g.colptr[j]) + r (cf_sparse_kron_dense) */
    const int32_t *xcp = d->x->colptr, *gcp = g->colptr;
    for (int32_t k = 0; k < nf; ++k)
        for (int p = 0; p < 9; ++p) {
            int64_t pair = (int64_t)k * 9 + p;
            int32_t j = mesh->triangles[3 * k + p % 3];
            for (int c = 0; c < 4; ++c) d->block_slot[pair * 4 + c] = xcp[4 * j + c] + 4 * (slots[pair] - gcp[j]);
        }
    for (int32_t k = 0; k < nf; ++k)
        for (int m = 0; m < 3; ++m) {
            int32_t i = mesh->triangles[3 * k + m];
            int64_t q = slots[(int64_t)k * 9 + m * 4];
            for (int c = 0; c < 4; ++c) d->diag_slot[4 * i + c] = xcp[4 * i + c] + 4 * (q - gcp[i]) + c;
        }
done:
    cf_sparse_destroy(&g);
    CFI_FREE(ctx, rows, npair);
    CFI_FREE(ctx, cols, npair);
    CFI_FREE(ctx, slots, npair);
    return st;
}

cf_status cfi_dirac_create_form(cf_context *ctx, const cf_mesh *mesh, int32_t complex_form, cfi_dirac **out)
{
    *out = NULL;
    int32_t nv = mesh->nv;
    if ((int64_t)nv * 4 > INT32_MAX) return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin: mesh too large (%d vertices)", nv);
    cfi_dirac *d = CFI_ALLOC(ctx, cfi_dirac, 1);
    if (!d) return CF_ERR_NOMEM;
    d->nv = nv;
    d->nf = mesh->nf;
    d->ne = mesh->ne;
    cf_status st = complex_form ? create_complex(ctx, mesh, d) : create_real(ctx, mesh, d);
    if (st != CF_OK) {
        cfi_dirac_destroy(ctx, &d);
        return st;
    }
    *out = d;
    return CF_OK;
}

cf_status cfi_dirac_create(cf_context *ctx, const cf_mesh *mesh, cfi_dirac **out)
{
    return cfi_dirac_create_form(ctx, mesh, 0, out);
}

void cfi_dirac_destroy(cf_context *ctx, cfi_dirac **d)
{
    if (!d || !*d) return;
    cfi_dirac *p = *d;
    cf_sparse_destroy(&p->x);
    cf_quat_sparse_destroy(&p->z);
    cf_min_quad_destroy(&p->fixed);
    CFI_FREE(ctx, p->known, p->nknown);
    CFI_FREE(ctx, p->known_values, p->nknown);
    CFI_FREE(ctx, p->block_slot, (int64_t)p->nf * 36);
    CFI_FREE(ctx, p->diag_slot, (int64_t)p->nv * 4);
    CFI_FREE(ctx, p->zslot, p->ne);
    CFI_FREE(ctx, p->zdiag, p->nv);
    CFI_FREE(ctx, p, 1);
    *d = NULL;
}

cf_status cfi_dirac_analyse(cf_context *ctx, const cfi_dirac *d, const cf_cholesky_options *co, cf_cholesky **out)
{
    return d->z ? cf_cholesky_create_quat(ctx, d->z, co, out) : cf_cholesky_create(ctx, d->x, co, out);
}

cf_status cfi_dirac_factorize(const cfi_dirac *d, cf_cholesky *chol)
{
    return d->z ? cf_cholesky_factorize_quat(chol, d->z) : cf_cholesky_factorize(chol, d->x);
}

double cfi_dirac_quotient(const cfi_dirac *d, const double *area, const double *lambda, double *work)
{
    if (!d->z) return cf_rayleigh_quotient_blocks(d->x, area, 4, lambda, work);
    /* the sums of cf_rayleigh_quotient_blocks */
    cf_quat_sparse_multiply(d->z, lambda, work);
    double num = 0.0, den = 0.0;
    for (int32_t i = 0; i < d->nv; ++i)
        for (int c = 0; c < 4; ++c) {
            int64_t k = 4 * (int64_t)i + c;
            num += lambda[k] * work[k];
            den += area[i] * lambda[k] * lambda[k];
        }
    return den > 0.0 ? num / den : NAN;
}

/* Hamilton product of (w, x, y, z) arrays: cf_quat_mul's arithmetic in the
 * same order, inline because the edge transform runs 8 products per edge
 * per step and the rho-derivative 3 per face plus 3 per face and direction (the library
 * calls cost +150 % instructions in cfi_spin_transform_edges, 1-2 ms per
 * step on spot_3k; test spin_transform checks the edges against
 * cf_quat_conj_sandwich). */
static inline void qmul(const double *a, const double *b, double *o)
{
    o[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    o[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    o[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    o[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

/* The edges e[m] of triangle tri (opposite corner m, running
 * counter-clockwise) and its area: the face data of App. G's X_mn, shared
 * by the fill and its rho-derivative. */
static inline double face_edges(const double *positions, const int32_t *tri, double e[3][3])
{
    for (int m = 0; m < 3; ++m) {
        const double *a = positions + 3 * tri[(m + 1) % 3];
        const double *b = positions + 3 * tri[(m + 2) % 3];
        for (int c = 0; c < 3; ++c) e[m][c] = b[c] - a[c];
    }
    double nrm[3] = {e[2][1] * e[0][2] - e[2][2] * e[0][1], e[2][2] * e[0][0] - e[2][0] * e[0][2],
                     e[2][0] * e[0][1] - e[2][1] * e[0][0]};
    return 0.5 * sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
}

void cfi_dirac_rho_derivative(const cf_mesh *mesh, const double *positions, const double *rho, int32_t count,
                              const double *drho, const double *lambda, double *out)
{
    int64_t nv = mesh->nv, n4 = 4 * nv;
    memset(out, 0, (size_t)(n4 * count) * sizeof(double));
    for (int32_t k = 0; k < mesh->nf; ++k) {
        const int32_t *tri = mesh->triangles + 3 * k;
        double e[3][3];
        double area = face_edges(positions, tri, e);
        /* X_mn's derivative along drho is linear in it:
         *   q_mn = dr_m (A r_n / 9, e_n / 6) + dr_n (A r_m / 9, -e_m / 6),
         * so sum_n q_mn lambda_n = dr_m u + p_m s with the face's
         *   u = sum_n (A r_n / 9, e_n / 6) lambda_n,  p_m = (A r_m / 9, -e_m / 6),
         * and s = sum_n dr_n lambda_n the only part that depends on the
         * direction: the geometry once per face for every direction. */
        const double *lam[3] = {lambda + 4 * (int64_t)tri[0], lambda + 4 * (int64_t)tri[1],
                                lambda + 4 * (int64_t)tri[2]};
        double u[4] = {0.0, 0.0, 0.0, 0.0}, p[3][4];
        for (int n = 0; n < 3; ++n) {
            double r = rho ? rho[tri[n]] : 0.0;
            double c[4] = {area * r / 9.0, e[n][0] / 6.0, e[n][1] / 6.0, e[n][2] / 6.0}, cl[4];
            qmul(c, lam[n], cl);
            for (int q = 0; q < 4; ++q) u[q] += cl[q];
            p[n][0] = c[0];
            for (int q = 1; q < 4; ++q) p[n][q] = -c[q];
        }
        for (int32_t l = 0; l < count; ++l) {
            const double *dl = drho + l * nv;
            double dr[3] = {dl[tri[0]], dl[tri[1]], dl[tri[2]]}, sl[4];
            for (int q = 0; q < 4; ++q) sl[q] = dr[0] * lam[0][q] + dr[1] * lam[1][q] + dr[2] * lam[2][q];
            for (int m = 0; m < 3; ++m) {
                double *o = out + l * n4 + 4 * (int64_t)tri[m], ps[4];
                qmul(p[m], sl, ps);
                for (int q = 0; q < 4; ++q) o[q] += dr[m] * u[q] + ps[q];
            }
        }
    }
}

void cfi_dirac_multiply(const cfi_dirac *d, const double *lambda, double *out)
{
    if (d->z)
        cf_quat_sparse_multiply(d->z, lambda, out);
    else
        cf_sparse_multiply(d->x, lambda, out);
}

/* Crane 2013, App. G: the quaternion X_mn of face k's corners m, n
 * (e: the face's ccw edges opposite each corner, r: rho at the corners):
 * X_mn = -e_m e_n / (4A) + (rho_m e_n - rho_n e_m) / 6 + A rho_m rho_n / 9;
 * for imaginary e: e_m e_n = -<e_m, e_n> + e_m x e_n. Plus the shift on
 * the diagonal. One function for both forms: the same arithmetic. */
static inline void face_quaternion(double e[3][3], const double r[3], double area, double shift, int m, int n,
                                   double q[4])
{
    const double *em = e[m], *en = e[n];
    q[0] = (em[0] * en[0] + em[1] * en[1] + em[2] * en[2]) / (4.0 * area) + area * r[m] * r[n] / 9.0;
    double cr[3] = {em[1] * en[2] - em[2] * en[1], em[2] * en[0] - em[0] * en[2], em[0] * en[1] - em[1] * en[0]};
    for (int c = 0; c < 3; ++c) q[1 + c] = -cr[c] / (4.0 * area) + (r[m] * en[c] - r[n] * em[c]) / 6.0;
    if (m == n) q[0] += shift * area / 3.0;
}

cf_status cfi_dirac_fill(cfi_dirac *d, const cf_mesh *mesh, const double *positions, const double *rho,
                         double shift)
{
    double *val = d->z ? d->z->values : d->x->values;
    memset(val, 0, (size_t)(d->z ? 2 * cf_quat_sparse_nnz(d->z) : cf_sparse_nnz(d->x)) * sizeof(double));
    const int32_t *zcp = d->z ? d->z->colptr : NULL;
    for (int32_t k = 0; k < mesh->nf; ++k) {
        const int32_t *tri = mesh->triangles + 3 * k;
        double e[3][3];
        double area = face_edges(positions, tri, e);
        if (!(area > 0.0)) return cfi_error(mesh->ctx, CF_ERR_DEGENERATE_FACE, "face %d: zero area in the Dirac matrix", k);
        double r[3] = {0.0, 0.0, 0.0};
        if (rho)
            for (int m = 0; m < 3; ++m) r[m] = rho[tri[m]];
        if (d->z) {
            /* The upper blocks only (tri[m] <= tri[n]; the lower one is its
             * conjugate), as q = a + b i + c j + d k -> [[a + b i, -c - d i],
             * [c - d i, a - b i]]. Each complex entry receives the same
             * component sums, in the same face order, as the real form's
             * entries that its conversion reads. The diagonal blocks' imaginary
             * parts vanish exactly (e x e = 0) and are not written. */
            for (int m = 0; m < 3; ++m)
                for (int n = 0; n < 3; ++n) {
                    if (tri[m] > tri[n]) continue;
                    double q[4];
                    face_quaternion(e, r, area, shift, m, n, q);
                    int32_t j = tri[n];
                    /* corners {0, 1}, {1, 2}, {2, 0}: halfedges 0, 1, 2 of the face
                     * (halfedge 3 k + h runs tri[h] -> tri[h + 1]) */
                    int h = m + n == 2 ? 2 : (m + n) / 2;
                    int64_t d0 = m == n ? d->zdiag[j] : d->zslot[mesh->halfedge_edge[3 * (int64_t)k + h]];
                    int64_t d2 = d0 + (zcp[2 * j + 1] - zcp[2 * j]);
                    if (m == n) {
                        val[2 * d0] += q[0];
                        val[2 * d2 + 2] += q[0];
                        continue;
                    }
                    val[2 * d0] += q[0];
                    val[2 * d0 + 1] += q[1];
                    val[2 * d0 + 2] += q[2];
                    val[2 * d0 + 3] -= q[3];
                    val[2 * d2] -= q[2];
                    val[2 * d2 + 1] -= q[3];
                    val[2 * d2 + 2] += q[0];
                    val[2 * d2 + 3] -= q[1];
                }
            continue;
        }
        for (int m = 0; m < 3; ++m) {
            for (int n = 0; n < 3; ++n) {
                double q[4];
                face_quaternion(e, r, area, shift, m, n, q);
                /* columns of the left-multiplication matrix of q (cf_quat_left_matrix,
                 * Le Folgoc Eq. (7)), written out here: the library call per block
                 * (a 32-byte struct by value, no inlining across the library) cost
                 * +30 % instructions in this fill, about 1 ms per step on spot_3k */
                const int64_t *s = d->block_slot + ((int64_t)k * 9 + m * 3 + n) * 4;
                double *c0 = val + s[0], *c1 = val + s[1], *c2 = val + s[2], *c3 = val + s[3];
                c0[0] += q[0]; c0[1] += q[1]; c0[2] += q[2]; c0[3] += q[3];
                c1[0] -= q[1]; c1[1] += q[0]; c1[2] += q[3]; c1[3] -= q[2];
                c2[0] -= q[2]; c2[1] -= q[3]; c2[2] += q[0]; c2[3] += q[1];
                c3[0] -= q[3]; c3[1] += q[2]; c3[2] -= q[1]; c3[3] += q[0];
            }
        }
    }
    return CF_OK;
}

cf_status cfi_dirac_fixed_create(cf_context *ctx, cfi_dirac *d, const cf_mesh *mesh, int32_t complex_form)
{
    int32_t nb = 0;
    for (int32_t i = 0; i < d->nv; ++i) nb += mesh->vertex_on_boundary[i] != 0;
    d->nknown = 4 * nb;
    d->known = CFI_ALLOC(ctx, int32_t, d->nknown);
    d->known_values = CFI_ALLOC(ctx, double, d->nknown);
    if (!d->known || !d->known_values) return CF_ERR_NOMEM;
    int32_t k = 0;
    for (int32_t i = 0; i < d->nv; ++i) {
        if (!mesh->vertex_on_boundary[i]) continue;
        for (int c = 0; c < 4; ++c) {
            d->known[k + c] = 4 * i + c;
            d->known_values[k + c] = c == 0 ? 1.0 : 0.0;
        }
        k += 4;
    }
    cf_min_quad_options o;
    cf_min_quad_options_default(&o);
    o.block_size = 4;
    o.quaternion_blocks = complex_form != 0;
    o.ordering = CF_ORDERING_AUTO_REFACTORISED; /* refactorised every step, as X (flow_method.c) */
    return cf_min_quad_create(ctx, d->x, d->nknown, d->known, NULL, &o, &d->fixed);
}

cf_status cfi_dirac_fixed_factorize(cfi_dirac *d) { return cf_min_quad_factorize(d->fixed, d->x, NULL); }

cf_status cfi_dirac_fixed_solve(cfi_dirac *d, const cf_mesh *mesh, const double *area, double eps, double *b,
                                double *lambda)
{
    /* minimise 1/2 l^T X l + b^T l with b = -eps M 1 on the interior: the
     * eps M 1 keeps the shift from biasing lambda toward 0 (flow_method.c) */
    memset(b, 0, 4 * (size_t)d->nv * sizeof *b);
    for (int32_t i = 0; i < d->nv; ++i)
        if (!mesh->vertex_on_boundary[i]) b[4 * i] = -eps * area[i];
    return cf_min_quad_solve(d->fixed, 1, b, d->known_values, NULL, lambda);
}

double cfi_dirac_fixed_quotient(const cfi_dirac *d, const cf_mesh *mesh, const double *area, const double *lambda,
                                double *work)
{
    const cf_sparse *x = d->x;
    const uint8_t *onb = mesh->vertex_on_boundary;
    int32_t n = x->ncols;
    memset(work, 0, (size_t)n * sizeof *work);
    for (int32_t col = 0; col < n; ++col) {
        int cb = onb[col / 4];
        for (int32_t p = x->colptr[col]; p < x->colptr[col + 1]; ++p) {
            int32_t row = x->rowind[p];
            double v = (cb || onb[row / 4]) ? (row == col ? 1.0 : 0.0) : x->values[p];
            work[row] += v * lambda[col];
        }
    }
    double num = 0.0, den = 0.0;
    for (int32_t k = 0; k < n; ++k) {
        num += lambda[k] * work[k];
        den += area[k / 4] * lambda[k] * lambda[k];
    }
    return den > 0.0 ? num / den : NAN;
}

/* imaginary part of conj(a) v b for imaginary v (a, b: (w, x, y, z) arrays) */
static inline void sandwich(const double *a, const double *v, const double *b, double *o)
{
    double ac[4] = {a[0], -a[1], -a[2], -a[3]}, vq[4] = {0.0, v[0], v[1], v[2]}, t[4], u[4];
    qmul(ac, vq, t);
    qmul(t, b, u);
    o[0] = u[1];
    o[1] = u[2];
    o[2] = u[3];
}

void cfi_spin_transform_edges(const cf_mesh *mesh, const double *positions, const double *lambda, double *out)
{
    for (int32_t e = 0; e < mesh->ne; ++e) {
        int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
        double v[3] = {positions[3 * j] - positions[3 * i], positions[3 * j + 1] - positions[3 * i + 1],
                       positions[3 * j + 2] - positions[3 * i + 2]};
        const double *li = lambda + 4 * i, *lj = lambda + 4 * j;
        double aa[3], ab[3], ba[3], bb[3];
        sandwich(li, v, li, aa);
        sandwich(li, v, lj, ab);
        sandwich(lj, v, li, ba);
        sandwich(lj, v, lj, bb);
        /* Crane et al. 2011 (NOTES.md): average of the similarity transforms at both ends */
        for (int c = 0; c < 3; ++c) out[3 * e + c] = (aa[c] + bb[c]) / 3.0 + (ab[c] + ba[c]) / 6.0;
    }
}

void cfi_spin_transform_edges_derivative(const cf_mesh *mesh, const double *positions, const double *lambda,
                                         int32_t count, const double *dlambda, int32_t first, int32_t n, double *out)
{
    int64_t n4 = 4 * (int64_t)mesh->nv;
    for (int32_t e = first; e < first + n; ++e) {
        int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
        double vq[4] = {0.0, positions[3 * j] - positions[3 * i], positions[3 * j + 1] - positions[3 * i + 1],
                        positions[3 * j + 2] - positions[3 * i + 2]};
        const double *a = lambda + 4 * i, *b = lambda + 4 * j;
        double ac[4] = {a[0], -a[1], -a[2], -a[3]}, bc[4] = {b[0], -b[1], -b[2], -b[3]}, ta[4], tb[4];
        qmul(ac, vq, ta);
        qmul(bc, vq, tb);
        /* With S(p, q) = Im(conj(p) v q), which is symmetric for imaginary
         * v (conj(conj(p) v q) = -conj(q) v p), the transform above is
         * e~ = (S(a, a) + S(b, b) + S(a, b)) / 3, whose derivative is
         * (2 S(a, da) + 2 S(b, db) + S(b, da) + S(a, db)) / 3
         *   = Im(ta (2 da + db) + tb (2 db + da)) / 3. */
        double *o = out + (int64_t)(e - first) * 3 * count;
        for (int32_t l = 0; l < count; ++l) {
            const double *da = dlambda + l * n4 + 4 * i, *db = dlambda + l * n4 + 4 * j;
            double u[4], w[4], tu[4], tw[4];
            for (int q = 0; q < 4; ++q) {
                u[q] = 2.0 * da[q] + db[q];
                w[q] = 2.0 * db[q] + da[q];
            }
            qmul(ta, u, tu);
            qmul(tb, w, tw);
            for (int c = 0; c < 3; ++c) o[3 * l + c] = (tu[1 + c] + tw[1 + c]) / 3.0;
        }
    }
}

void cfi_dirac_restrict_boundary(cfi_dirac *d, const cf_mesh *mesh, const double *frames)
{
    cf_sparse *x = d->x;
    const uint8_t *onb = mesh->vertex_on_boundary;
    for (int32_t j = 0; j < d->nv; ++j) {
        int32_t c0 = 4 * j;
        for (int32_t p = x->colptr[c0]; p < x->colptr[c0 + 1]; p += 4) {
            int32_t i = x->rowind[p] / 4;
            if (!onb[i] && !onb[j]) continue;
            int32_t k = p - x->colptr[c0];
            double b[16], t[16], o[16];
            for (int c = 0; c < 4; ++c)
                for (int r = 0; r < 4; ++r) b[4 * r + c] = x->values[x->colptr[c0 + c] + k + r];
            /* t = b Q_j */
            if (onb[j]) {
                const double *q = frames + 16 * (int64_t)j;
                for (int r = 0; r < 4; ++r)
                    for (int c = 0; c < 4; ++c) {
                        double s = 0.0;
                        for (int m = 0; m < 4; ++m) s += b[4 * r + m] * q[4 * m + c];
                        t[4 * r + c] = s;
                    }
            } else {
                memcpy(t, b, sizeof t);
            }
            /* o = Q_i^T t */
            if (onb[i]) {
                const double *q = frames + 16 * (int64_t)i;
                for (int r = 0; r < 4; ++r)
                    for (int c = 0; c < 4; ++c) {
                        double s = 0.0;
                        for (int m = 0; m < 4; ++m) s += q[4 * m + r] * t[4 * m + c];
                        o[4 * r + c] = s;
                    }
            } else {
                memcpy(o, t, sizeof o);
            }
            /* components 2, 3 of boundary vertices are fixed to zero */
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) {
                    int zr = onb[i] && r >= 2, zc = onb[j] && c >= 2;
                    double v = o[4 * r + c];
                    if (zr || zc) v = (i == j && r == c) ? 1.0 : 0.0;
                    x->values[x->colptr[c0 + c] + k + r] = v;
                }
        }
    }
}
