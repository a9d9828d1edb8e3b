/*
 * Energy model and local step of Zhao & Gortler, "A Report on Shape
 * Deformation with a Stretching and Bending Energy": the rotation terms of
 * the stretching energy (Eq. 5, one rotation per triangle), ARAP spokes
 * (Eq. 6) and spokes-and-rims (Eq. 7, one rotation per vertex), the
 * mean-curvature bending energy (Eq. 15), and the local phase (Sec. 4.2):
 * Procrustes rotations from the cross-covariance with determinant
 * correction (Eq. 24) and u' = normalised K x'.
 */
#include "methods/stretch_bend_edit/stretch_bend_internal.h"

#include "curvflow/ops.h"
#include "curvflow/quaternion.h"
#include "curvflow/svd3.h"

#include <math.h>
#include <string.h>

void cfi_stretch_bend_model_free(cfi_stretch_bend_model *m)
{
    if (!m || !m->ctx) return;
    cf_sparse_destroy(&m->k);
    cfi_workspace_free_all(&m->ws);
    m->ctx = NULL;
}

static void set_term(cfi_stretch_bend_model *m, int32_t t, int32_t i, int32_t j, double w, const double *rest)
{
    m->term_ij[2 * t] = i;
    m->term_ij[2 * t + 1] = j;
    m->term_w[t] = w;
    for (int d = 0; d < 3; ++d) m->term_e[3 * t + d] = rest[3 * i + d] - rest[3 * j + d];
}

/* Eq. 5: one term per halfedge v->w of face t with weight cot of the corner
 * opposite it, rotation R_t. */
static void build_stretch_terms(cfi_stretch_bend_model *m, const double *rest, const double *cot)
{
    const cf_mesh *mesh = m->mesh;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        m->rot_offsets[f] = 3 * f;
        /* Orthonormal rest frame (b1 along the first edge, n the normal,
         * b2 = n x b1): the rest edges are 2D in it, so C_t = P B^T with
         * P = sum w e' a^T (3 x 2) and B = [b1 b2]. */
        const int32_t *t = mesh->triangles + 3 * f;
        const double *p0 = rest + 3 * t[0], *p1 = rest + 3 * t[1], *p2 = rest + 3 * t[2];
        double u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        double v[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        double lu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]), ln = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        double *b = m->frames + 9 * f;
        for (int d = 0; d < 3; ++d) {
            b[d] = lu > 0.0 ? u[d] / lu : (d == 0);
            b[6 + d] = ln > 0.0 ? n[d] / ln : (d == 2);
        }
        b[3] = b[7] * b[2] - b[8] * b[1];
        b[4] = b[8] * b[0] - b[6] * b[2];
        b[5] = b[6] * b[1] - b[7] * b[0];
        for (int k = 0; k < 3; ++k) {
            int32_t h = 3 * f + k;
            int32_t vi = mesh->triangles[h], wi = mesh->triangles[cfi_he_next(h)];
            set_term(m, h, vi, wi, cot[cfi_he_prev(h)], rest);
            const double *e = m->term_e + 3 * h;
            m->term_a[2 * h] = e[0] * b[0] + e[1] * b[1] + e[2] * b[2];
            m->term_a[2 * h + 1] = e[0] * b[3] + e[1] * b[4] + e[2] * b[5];
        }
    }
    m->rot_offsets[mesh->nf] = 3 * mesh->nf;
}

/* Eq. 6 (spokes) and Eq. 7 (spokes and rims): rotation R_v per vertex over
 * the edges of its cell, each with the full edge weight W = cot a + cot b
 * (= 2 w_e of the project's L). The rims of v are the edges opposite v in
 * its faces; with the spokes they form the set E(v), each edge once. */
static void build_arap_terms(cfi_stretch_bend_model *m, const double *rest, const double *w_edge, int rims)
{
    const cf_mesh *mesh = m->mesh;
    int32_t t = 0;
    for (int32_t v = 0; v < mesh->nv; ++v) {
        m->rot_offsets[v] = t;
        for (int32_t k = mesh->ring_offsets[v]; k < mesh->ring_offsets[v + 1]; ++k) {
            int32_t e = mesh->ring_edges[k];
            set_term(m, t++, v, mesh->ring_neighbors[k], 2.0 * w_edge[e], rest);
        }
        if (!rims) continue;
        for (int32_t k = mesh->vface_offsets[v]; k < mesh->vface_offsets[v + 1]; ++k) {
            int32_t f = mesh->vface_faces[k];
            int32_t c = 0;
            while (c < 3 && mesh->triangles[3 * f + c] != v) ++c;
            if (CF_NEVER(c == 3)) continue;
            int32_t h = 3 * f + (c + 1) % 3; /* the halfedge opposite corner c */
            int32_t e = mesh->halfedge_edge[h];
            set_term(m, t++, mesh->triangles[h], mesh->triangles[cfi_he_next(h)], 2.0 * w_edge[e], rest);
        }
    }
    m->rot_offsets[mesh->nv] = t;
}

/* K = 2 L from the edge weights (K f)_v = sum_w W_vw (f_v - f_w) (Eq. 14
 * times M_v), assembled once. */
static cf_status build_k(cfi_stretch_bend_model *m, const double *w_edge)
{
    cf_context *ctx = m->ctx;
    const cf_mesh *mesh = m->mesh;
    int64_t n = 4 * (int64_t)mesh->ne;
    int32_t *rows = CFI_ALLOC(ctx, int32_t, n);
    int32_t *cols = CFI_ALLOC(ctx, int32_t, n);
    double *vals = CFI_ALLOC(ctx, double, n);
    cf_status st = (rows && cols && vals) ? CF_OK : CF_ERR_NOMEM;
    if (st == CF_OK) {
        for (int32_t e = 0; e < mesh->ne; ++e) {
            int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
            double w = 2.0 * w_edge[e];
            int64_t b = 4 * (int64_t)e;
            rows[b] = i; cols[b] = i; vals[b] = w;
            rows[b + 1] = j; cols[b + 1] = j; vals[b + 1] = w;
            rows[b + 2] = i; cols[b + 2] = j; vals[b + 2] = -w;
            rows[b + 3] = j; cols[b + 3] = i; vals[b + 3] = -w;
        }
        st = cf_sparse_from_triplets(ctx, mesh->nv, mesh->nv, n, rows, cols, vals, 1, &m->k, NULL);
    }
    CFI_FREE(ctx, rows, n);
    CFI_FREE(ctx, cols, n);
    CFI_FREE(ctx, vals, n);
    return st;
}

/* (K x)_v for interleaved positions x (K symmetric, both triangles
 * stored, so row v is column v; rows summing to zero): sum over w != v of
 * K_vw (x_w - x_v), from the differences of the positions, so that a mesh
 * far from the origin keeps its precision (cf_sparse_multiply_zero_row_sums;
 * through the diagonal, spot 1e6 away had |H| and u' off in their 6th
 * digit). */
static void k_apply3_at(const cf_sparse *k, const double *x, int32_t v, double out[3])
{
    const double xv0 = x[3 * (size_t)v], xv1 = x[3 * (size_t)v + 1], xv2 = x[3 * (size_t)v + 2];
    double a = 0.0, b = 0.0, c = 0.0;
    for (int32_t p = k->colptr[v]; p < k->colptr[v + 1]; ++p) {
        int32_t w = k->rowind[p];
        const double *xw = x + 3 * (size_t)w;
        double kw = w == v ? 0.0 : k->values[p];
        a += kw * (xw[0] - xv0);
        b += kw * (xw[1] - xv1);
        c += kw * (xw[2] - xv2);
    }
    out[0] = a;
    out[1] = b;
    out[2] = c;
}

/* out = K x for interleaved positions (k_apply3_at at every vertex). */
static void k_apply3(const cf_sparse *k, const double *x, double *out)
{
    for (int32_t v = 0; v < k->ncols; ++v) k_apply3_at(k, x, v, out + 3 * (size_t)v);
}

/* out += alpha K x, interleaved. */
static void k_apply3_add(const cf_sparse *k, double alpha, const double *x, double *out)
{
    for (int32_t v = 0; v < k->ncols; ++v) {
        double a = 0.0, b = 0.0, c = 0.0;
        for (int32_t p = k->colptr[v]; p < k->colptr[v + 1]; ++p) {
            const double *xw = x + 3 * (size_t)k->rowind[p];
            double w = k->values[p];
            a += w * xw[0];
            b += w * xw[1];
            c += w * xw[2];
        }
        out[3 * (size_t)v] += alpha * a;
        out[3 * (size_t)v + 1] += alpha * b;
        out[3 * (size_t)v + 2] += alpha * c;
    }
}

cf_status cfi_stretch_bend_model_init(cfi_stretch_bend_model *m, cf_context *ctx, const cf_mesh *mesh, const double *rest,
                             const cf_stretch_bend_options *o)
{
    memset(m, 0, sizeof *m);
    m->ctx = ctx;
    cfi_workspace_init(&m->ws, ctx);
    m->mesh = mesh;
    m->nv = mesh->nv;
    int32_t nv = mesh->nv, nf = mesh->nf, ne = mesh->ne;
    if (o->energy < 0 || o->energy >= CF_STRETCH_BEND_ENERGY_COUNT)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "stretch-bend-edit: energy %d out of range", (int)o->energy);
    if (!(o->lambda >= 0.0 && o->lambda <= 1.0))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "stretch-bend-edit: lambda %g is not in [0, 1]", o->lambda);
    m->energy = (cf_stretch_bend_energy_kind)o->energy;
    double lambda = o->energy == CF_STRETCH_BEND_STRETCH ? 1.0 : o->energy == CF_STRETCH_BEND_BEND ? 0.0 : o->lambda;
    int arap = m->energy == CF_STRETCH_BEND_ARAP || m->energy == CF_STRETCH_BEND_ARAP_RIMS;

    double *cot = CFI_ALLOC(ctx, double, 3 * (size_t)nf);
    double *w_edge = CFI_ALLOC(ctx, double, (size_t)ne);
    if (!cot || !w_edge) {
        CFI_FREE(ctx, cot, 3 * (size_t)nf);
        CFI_FREE(ctx, w_edge, (size_t)ne);
        return CF_ERR_NOMEM;
    }
    cf_status st = cf_corner_cotangents(ctx, mesh, rest, cot);
    if (st == CF_OK) st = cf_cotan_weights(ctx, mesh, rest, w_edge);
    if (st == CF_OK && arap) {
        if (o->arap_weights != CF_STRETCH_BEND_ARAP_COTAN && o->arap_weights != CF_STRETCH_BEND_ARAP_CLAMPED) {
            st = cfi_error(ctx, CF_ERR_INVALID_ARG, "stretch-bend-edit: arap_weights %d out of range",
                           (int)o->arap_weights);
            goto done;
        }
        /* the negative weights, for the flow's warning; clamped: set to 0 */
        m->most_negative_edge = -1;
        for (int32_t e = 0; e < ne; ++e) {
            if (!(w_edge[e] < 0.0)) continue;
            ++m->negative_edges;
            if (m->most_negative_edge < 0 || w_edge[e] < w_edge[m->most_negative_edge]) m->most_negative_edge = e;
        }
        if (m->negative_edges > 0)
            m->most_negative_weight = 2.0 * w_edge[m->most_negative_edge];
        if (o->arap_weights == CF_STRETCH_BEND_ARAP_CLAMPED)
            for (int32_t e = 0; e < ne; ++e) w_edge[e] = fmax(w_edge[e], 0.0);
        m->clamped = o->arap_weights == CF_STRETCH_BEND_ARAP_CLAMPED;
    }
    double area = 0.0;
    if (st == CF_OK) st = cf_total_area(ctx, mesh, rest, &area);
    if (st != CF_OK) goto done;
    if (arap) {
        m->alpha = 1.0;
        m->beta = 0.0;
    } else {
        m->alpha = lambda / (o->scale_free ? area : 1.0);
        m->beta = 1.0 - lambda;
    }

    if (m->energy == CF_STRETCH_BEND_ARAP) {
        m->rot_count = nv;
        m->term_count = 2 * ne;
    } else if (m->energy == CF_STRETCH_BEND_ARAP_RIMS) {
        m->rot_count = nv;
        m->term_count = 2 * ne + 3 * nf;
    } else if (m->alpha > 0.0) {
        m->rot_count = nf;
        m->term_count = 3 * nf;
        m->per_face = 1;
    }
    m->rot_offsets = CFI_WS_ALLOC(&m->ws, int32_t, (size_t)m->rot_count + 1);
    m->term_ij = CFI_WS_ALLOC(&m->ws, int32_t, 2 * (size_t)m->term_count);
    m->term_w = CFI_WS_ALLOC(&m->ws, double, (size_t)m->term_count);
    m->term_e = CFI_WS_ALLOC(&m->ws, double, 3 * (size_t)m->term_count);
    m->rest_sq = CFI_WS_ALLOC(&m->ws, double, (size_t)m->rot_count);
    m->rotations = CFI_WS_ALLOC(&m->ws, double, 9 * (size_t)m->rot_count);
    m->covariance = CFI_WS_ALLOC(&m->ws, double, 9 * (size_t)m->rot_count);
    m->xcol = CFI_WS_ALLOC(&m->ws, double, 3 * (size_t)nv);
    m->kx = CFI_WS_ALLOC(&m->ws, double, 3 * (size_t)nv);
    if (m->per_face) {
        m->frames = CFI_WS_ALLOC(&m->ws, double, 9 * (size_t)nf);
        m->term_a = CFI_WS_ALLOC(&m->ws, double, 2 * (size_t)m->term_count);
        if (!m->frames || !m->term_a) {
            st = CF_ERR_NOMEM;
            goto done;
        }
    } else if (m->rot_count > 0) {
        m->quats = CFI_WS_ALLOC(&m->ws, double, 4 * (size_t)m->rot_count);
        if (!m->quats) {
            st = CF_ERR_NOMEM;
            goto done;
        }
    }
    if (!m->rot_offsets || (m->term_count && (!m->term_ij || !m->term_w || !m->term_e || !m->rest_sq ||
                                              !m->rotations || !m->covariance)) ||
        !m->xcol || !m->kx) {
        st = CF_ERR_NOMEM;
        goto done;
    }
    if (m->energy == CF_STRETCH_BEND_ARAP || m->energy == CF_STRETCH_BEND_ARAP_RIMS)
        build_arap_terms(m, rest, w_edge, m->energy == CF_STRETCH_BEND_ARAP_RIMS);
    else if (m->term_count > 0)
        build_stretch_terms(m, rest, cot);
    else
        m->rot_offsets[0] = 0;
    for (int32_t r = 0; r < m->rot_count; ++r) {
        double s = 0.0;
        for (int32_t t = m->rot_offsets[r]; t < m->rot_offsets[r + 1]; ++t) {
            const double *e = m->term_e + 3 * t;
            s += m->term_w[t] * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        }
        m->rest_sq[r] = s;
        double *rot = m->rotations + 9 * r;
        memset(rot, 0, 9 * sizeof(double));
        rot[0] = rot[4] = rot[8] = 1.0;
        if (m->quats) {
            m->quats[4 * r] = 1.0;
            m->quats[4 * r + 1] = m->quats[4 * r + 2] = m->quats[4 * r + 3] = 0.0;
        }
    }

    if (m->beta > 0.0) {
        m->mass = CFI_WS_ALLOC(&m->ws, double, (size_t)nv);
        m->hm = CFI_WS_ALLOC(&m->ws, double, (size_t)nv);
        m->u = CFI_WS_ALLOC(&m->ws, double, 3 * (size_t)nv);
        if (!m->mass || !m->hm || !m->u) {
            st = CF_ERR_NOMEM;
            goto done;
        }
        st = cf_vertex_areas(ctx, mesh, rest,
                             o->mass == CF_STRETCH_BEND_MASS_BARYCENTRIC ? CF_DUAL_AREA_BARYCENTRIC
                                                                 : CF_DUAL_AREA_MIXED_VORONOI,
                             m->mass);
        if (st == CF_OK) st = build_k(m, w_edge);
        if (st != CF_OK) goto done;
        for (int32_t v = 0; v < nv; ++v) {
            if (!(m->mass[v] > 0.0)) {
                st = cfi_error(ctx, CF_ERR_BAD_MESH, "vertex %d: dual area %g is not positive", v, m->mass[v]);
                goto done;
            }
        }
        k_apply3(m->k, rest, m->kx);
        /* |H_v| M_v = |(K x)_v| (Sec. 3.2: "the norm of the mean curvature
         * vector"); u' starts as the rest direction, zero where K x = 0
         * (there |H_v| = 0 and u' does not enter the energy). */
        for (int32_t v = 0; v < nv; ++v) {
            double a = m->kx[3 * v], b = m->kx[3 * v + 1], c = m->kx[3 * v + 2];
            double n = sqrt(a * a + b * b + c * c);
            m->hm[v] = n;
            double s = n > 0.0 ? 1.0 / n : 0.0;
            m->u[3 * v] = a * s;
            m->u[3 * v + 1] = b * s;
            m->u[3 * v + 2] = c * s;
        }
    }
done:
    CFI_FREE(ctx, cot, 3 * (size_t)nf);
    CFI_FREE(ctx, w_edge, (size_t)ne);
    if (st != CF_OK) cfi_stretch_bend_model_free(m);
    return st;
}

static double trace_rt_c(const double r[9], const double c[9])
{
    double t = 0.0;
    for (int k = 0; k < 9; ++k) t += r[k] * c[k];
    return t;
}

/* Maximises f(R) = tr(R^T C) over rotations by Newton's method on SO(3)
 * from the warm start q: with R -> exp([d]x) R and M = C R^T,
 * f = f0 + d . w - d^T H d / 2 with w = sum_i r_i x c_i (columns) and
 * H = tr(M) I - sym(M), positive definite near the maximum; the step is
 * d = H^-1 w (a gradient step w / |tr M| where H is not positive
 * definite). Quadratic convergence from the previous iteration's rotation
 * takes 1-3 steps. Returns 1 when |d| fell below 1e-10 at a point where H
 * is positive definite (a maximum), else 0. */
static int polar_iterate(const double c[9], double q_io[4], double r[9])
{
    /* q stays a local cf_quat through the iterations: two calls into the
     * quaternion module per iteration (matrix, product) keep this hot loop
     * of the ARAP local step within a few percent of inline code */
    cf_quat q = {q_io[0], q_io[1], q_io[2], q_io[3]};
    int result = 0;
    for (int it = 0; it < 10; ++it) {
        cf_quat_to_rotation_matrix(q, r);
        double w[3] = {0, 0, 0};
        for (int i = 0; i < 3; ++i) {
            double a0 = r[i], a1 = r[3 + i], a2 = r[6 + i], b0 = c[i], b1 = c[3 + i], b2 = c[6 + i];
            w[0] += a1 * b2 - a2 * b1;
            w[1] += a2 * b0 - a0 * b2;
            w[2] += a0 * b1 - a1 * b0;
        }
        /* M = C R^T (row-major): M_ij = sum_k c_ik r_jk. */
        double m[9];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) m[3 * i + j] = c[3 * i] * r[3 * j] + c[3 * i + 1] * r[3 * j + 1] + c[3 * i + 2] * r[3 * j + 2];
        double trm = m[0] + m[4] + m[8];
        double h00 = trm - m[0], h11 = trm - m[4], h22 = trm - m[8];
        double h01 = -0.5 * (m[1] + m[3]), h02 = -0.5 * (m[2] + m[6]), h12 = -0.5 * (m[5] + m[7]);
        double c00 = h11 * h22 - h12 * h12, c01 = h02 * h12 - h01 * h22, c02 = h01 * h12 - h02 * h11;
        double det = h00 * c00 + h01 * c01 + h02 * c02;
        double d[3];
        int definite = h00 > 0.0 && h00 * h11 - h01 * h01 > 0.0 && det > 1e-14 * fabs(trm) * trm * trm;
        if (definite) {
            double c11 = h00 * h22 - h02 * h02, c12 = h01 * h02 - h00 * h12, c22 = h00 * h11 - h01 * h01;
            d[0] = (c00 * w[0] + c01 * w[1] + c02 * w[2]) / det;
            d[1] = (c01 * w[0] + c11 * w[1] + c12 * w[2]) / det;
            d[2] = (c02 * w[0] + c12 * w[1] + c22 * w[2]) / det;
        } else {
            double sc = 1.0 / (fabs(trm) + 1e-300);
            d[0] = w[0] * sc;
            d[1] = w[1] * sc;
            d[2] = w[2] * sc;
        }
        double angle = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (!(angle == angle)) goto done;
        /* Converged only at a maximum: a vanishing gradient where H is not
         * positive definite is a saddle of tr(R^T C) (e.g. a rotation by pi
         * of a flat ring's optimum), left to the SVD. */
        if (angle < 1e-10) {
            result = definite;
            goto done;
        }
        double scale = angle > 1.0 ? 1.0 / angle : 1.0; /* damp far from the optimum */
        angle *= scale;
        double s = sin(0.5 * angle) / (angle / scale), cw = cos(0.5 * angle);
        /* R <- exp([d]x) R is q <- dq q (Hamilton product), renormalised */
        cf_quat dq = {cw, s * d[0], s * d[1], s * d[2]};
        cf_quat nq = cf_quat_mul(dq, q);
        double n = sqrt(nq.w * nq.w + nq.x * nq.x + nq.y * nq.y + nq.z * nq.z);
        q = (cf_quat){nq.w / n, nq.x / n, nq.y / n, nq.z / n};
    }
    cf_quat_to_rotation_matrix(q, r);
done:
    q_io[0] = q.w;
    q_io[1] = q.x;
    q_io[2] = q.y;
    q_io[3] = q.z;
    return result;
}

/* Rank-2 Procrustes for a triangle (Eq. 24): with C_t = P B^T the optimal
 * rotation maps the rest frame (b1, b2, n) to (q1, q2, q1 x q2) where
 * [q1 q2] = P (P^T P)^(-1/2) is the polar factor of the 3 x 2 matrix P
 * (closed form of the 2 x 2 inverse square root). This is the SVD solution
 * with the determinant correction, since the third singular value of C_t
 * is zero. Returns 0 when P is (nearly) rank deficient. */
static int triangle_rotation(const double p[6], const double b[9], double r[9], double *trace)
{
    /* p: rows of the 3 x 2 matrix, p[2 i + j]. */
    double s11 = p[0] * p[0] + p[2] * p[2] + p[4] * p[4];
    double s22 = p[1] * p[1] + p[3] * p[3] + p[5] * p[5];
    double s12 = p[0] * p[1] + p[2] * p[3] + p[4] * p[5];
    double det = s11 * s22 - s12 * s12;
    double tr = s11 + s22;
    if (!(det > 1e-20 * tr * tr)) return 0;
    double sq = sqrt(det), t = sqrt(tr + 2.0 * sq);
    /* (P^T P)^(-1/2) = (sqrt(S))^-1, sqrt(S) = (S + sq I) / t, det sqrt(S) = sq. */
    double i11 = (s22 + sq) / (t * sq), i22 = (s11 + sq) / (t * sq), i12 = -s12 / (t * sq);
    double q1[3], q2[3];
    for (int i = 0; i < 3; ++i) {
        q1[i] = p[2 * i] * i11 + p[2 * i + 1] * i12;
        q2[i] = p[2 * i] * i12 + p[2 * i + 1] * i22;
    }
    double q3[3] = {q1[1] * q2[2] - q1[2] * q2[1], q1[2] * q2[0] - q1[0] * q2[2], q1[0] * q2[1] - q1[1] * q2[0]};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r[3 * i + j] = q1[i] * b[j] + q2[i] * b[3 + j] + q3[i] * b[6 + j];
    /* tr(R^T C) = tr(Q^T P). */
    *trace = 0.0;
    for (int i = 0; i < 3; ++i) *trace += q1[i] * p[2 * i] + q2[i] * p[2 * i + 1];
    return 1;
}

/* Eq. 22 for the terms of rotation r: b_i += alpha w R e, b_j -= alpha w R e
 * (interleaved, 3 nv), fused into the local step while the terms are in
 * cache. */
static void accumulate_rhs(const cfi_stretch_bend_model *m, int32_t r, double *rhs)
{
    const double *rot = m->rotations + 9 * r;
    for (int32_t t = m->rot_offsets[r]; t < m->rot_offsets[r + 1]; ++t) {
        int32_t i = m->term_ij[2 * t], j = m->term_ij[2 * t + 1];
        const double *e = m->term_e + 3 * t;
        double w = m->alpha * m->term_w[t];
        for (int d = 0; d < 3; ++d) {
            double re = w * (rot[3 * d] * e[0] + rot[3 * d + 1] * e[1] + rot[3 * d + 2] * e[2]);
            rhs[3 * (size_t)i + d] += re;
            rhs[3 * (size_t)j + d] -= re;
        }
    }
}

/* beta K (|H| u') of Eq. 23, added to rhs (interleaved). */
static void add_bend_rhs(const cfi_stretch_bend_model *m, double *rhs)
{
    for (int32_t v = 0; v < m->nv; ++v) {
        double h = m->hm[v] / m->mass[v];
        for (int d = 0; d < 3; ++d) m->hu[3 * (size_t)v + d] = h * m->u[3 * (size_t)v + d];
    }
    k_apply3_add(m->k, m->beta, m->hu, rhs);
}

void cfi_stretch_bend_assemble_rhs(cfi_stretch_bend_model *m, double *rhs)
{
    memset(rhs, 0, 3 * (size_t)m->nv * sizeof(double));
    for (int32_t r = 0; r < m->rot_count; ++r) accumulate_rhs(m, r, rhs);
    if (m->beta > 0.0) add_bend_rhs(m, rhs);
}

cf_status cfi_stretch_bend_local_step(cfi_stretch_bend_model *m, const double *x, int exact, double *total)
{
    cf_context *ctx = m->ctx;
    int32_t nv = m->nv;
    double term_energy = 0.0;
    double *rhs = m->rhs;
    if (rhs) memset(rhs, 0, 3 * (size_t)nv * sizeof(double));
    /* Eq. 24: C_r = sum w e' e^T (deformed times rest); the rotation
     * maximising tr(R^T C_r) minimises sum w |e' - R e|^2, and then
     * sum w |e' - R e|^2 = sum w |e'|^2 - 2 tr(R^T C_r) + sum w |e|^2. */
    for (int32_t r = 0; r < m->rot_count; ++r) {
        double c[9] = {0};
        double def_sq = 0.0, tr = 0.0;
        double *rot = m->rotations + 9 * r;
        if (m->per_face && !exact) {
            double p[6] = {0};
            for (int32_t t = m->rot_offsets[r]; t < m->rot_offsets[r + 1]; ++t) {
                int32_t i = m->term_ij[2 * t], j = m->term_ij[2 * t + 1];
                double w = m->term_w[t];
                const double *a = m->term_a + 2 * t;
                double q0 = x[3 * i] - x[3 * j], q1 = x[3 * i + 1] - x[3 * j + 1], q2 = x[3 * i + 2] - x[3 * j + 2];
                def_sq += w * (q0 * q0 + q1 * q1 + q2 * q2);
                double wa0 = w * a[0], wa1 = w * a[1];
                p[0] += q0 * wa0; p[1] += q0 * wa1;
                p[2] += q1 * wa0; p[3] += q1 * wa1;
                p[4] += q2 * wa0; p[5] += q2 * wa1;
            }
            const double *b = m->frames + 9 * r;
            if (triangle_rotation(p, b, rot, &tr)) {
                term_energy += def_sq - 2.0 * tr + m->rest_sq[r];
                if (rhs) accumulate_rhs(m, r, rhs);
                continue;
            }
            /* Degenerate deformed triangle: the general path below. */
            def_sq = 0.0;
            ++m->svd_fallbacks;
        }
        for (int32_t t = m->rot_offsets[r]; t < m->rot_offsets[r + 1]; ++t) {
            int32_t i = m->term_ij[2 * t], j = m->term_ij[2 * t + 1];
            double w = m->term_w[t];
            const double *e = m->term_e + 3 * t;
            double q0 = x[3 * i] - x[3 * j], q1 = x[3 * i + 1] - x[3 * j + 1], q2 = x[3 * i + 2] - x[3 * j + 2];
            def_sq += w * (q0 * q0 + q1 * q1 + q2 * q2);
            double wq0 = w * q0, wq1 = w * q1, wq2 = w * q2;
            c[0] += wq0 * e[0]; c[1] += wq0 * e[1]; c[2] += wq0 * e[2];
            c[3] += wq1 * e[0]; c[4] += wq1 * e[1]; c[5] += wq1 * e[2];
            c[6] += wq2 * e[0]; c[7] += wq2 * e[1]; c[8] += wq2 * e[2];
        }
        int done = 0;
        if (!exact && m->quats) {
            double q[4], cand[9];
            memcpy(q, m->quats + 4 * r, sizeof q);
            double old_tr = trace_rt_c(rot, c);
            if (polar_iterate(c, q, cand)) {
                double new_tr = trace_rt_c(cand, c);
                /* Never accept a worse rotation: keeps the local step a
                 * descent step whatever the iteration did. */
                if (new_tr >= old_tr - 1e-12 * fabs(old_tr)) {
                    memcpy(rot, cand, sizeof cand);
                    memcpy(m->quats + 4 * r, q, sizeof q);
                    done = 1;
                }
            }
            if (!done) ++m->svd_fallbacks;
        }
        if (!done) {
            cf_status st = cf_rotation_from_covariance(c, rot);
            if (st != CF_OK)
                return cfi_error(ctx, CF_ERR_NUMERICAL, "%s %d: cross-covariance is not finite",
                                 m->per_face ? "face" : "vertex", r);
            if (m->quats) cf_quat_store(cf_quat_from_rotation_matrix(rot), m->quats + 4 * r);
        }
        tr = trace_rt_c(rot, c);
        term_energy += def_sq - 2.0 * tr + m->rest_sq[r];
        if (rhs) accumulate_rhs(m, r, rhs);
    }
    double bend_energy = 0.0;
    if (m->beta > 0.0) {
        k_apply3(m->k, x, m->kx);
        /* Sec. 4.2: u'_v = (K x')_v / |(K x')_v|; with the optimal u' the
         * term of Eq. 15 is (|K x'|_v - M_v |H_v|)^2 / M_v. A zero vector
         * keeps the previous direction (any unit vector is optimal then). */
        for (int32_t v = 0; v < nv; ++v) {
            double a = m->kx[3 * v], b = m->kx[3 * v + 1], c = m->kx[3 * v + 2];
            double n = sqrt(a * a + b * b + c * c);
            if (n > 0.0) {
                m->u[3 * v] = a / n;
                m->u[3 * v + 1] = b / n;
                m->u[3 * v + 2] = c / n;
            }
            double diff = n - m->hm[v];
            bend_energy += diff * diff / m->mass[v];
        }
        if (rhs) add_bend_rhs(m, rhs);
    }
    m->term_energy = term_energy;
    m->bend_energy = bend_energy;
    if (total) *total = m->alpha * term_energy + m->beta * bend_energy;
    if (!isfinite(term_energy) || !isfinite(bend_energy))
        return cfi_error(ctx, CF_ERR_NUMERICAL, "stretch-bend-edit: energy is not finite");
    return CF_OK;
}

double cfi_stretch_bend_fixed_energy(const cfi_stretch_bend_model *m, const double *x)
{
    int32_t nv = m->nv;
    double e_terms = 0.0;
    for (int32_t r = 0; r < m->rot_count; ++r) {
        const double *rot = m->rotations + 9 * r;
        for (int32_t t = m->rot_offsets[r]; t < m->rot_offsets[r + 1]; ++t) {
            int32_t i = m->term_ij[2 * t], j = m->term_ij[2 * t + 1];
            const double *e = m->term_e + 3 * t;
            double s = 0.0;
            for (int d = 0; d < 3; ++d) {
                double q = x[3 * i + d] - x[3 * j + d] - (rot[3 * d] * e[0] + rot[3 * d + 1] * e[1] + rot[3 * d + 2] * e[2]);
                s += q * q;
            }
            e_terms += m->term_w[t] * s;
        }
    }
    double e_bend = 0.0;
    if (m->beta > 0.0) {
        /* sum_v M_v |(K x)_v / M_v - |H_v| u'_v|^2 (Eq. 15), K applied
         * vertex by vertex so the model's scratch buffers stay untouched. */
        for (int32_t v = 0; v < nv; ++v) {
            double kx[3];
            k_apply3_at(m->k, x, v, kx);
            double s = 0.0;
            for (int d = 0; d < 3; ++d) {
                double q = kx[d] / m->mass[v] - m->hm[v] / m->mass[v] * m->u[3 * (size_t)v + d];
                s += q * q;
            }
            e_bend += m->mass[v] * s;
        }
    }
    return m->alpha * e_terms + m->beta * e_bend;
}
