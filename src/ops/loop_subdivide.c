/*
 * Loop subdivision (C. Loop, "Smooth subdivision surfaces based on
 * triangles", MSc thesis, Utah 1987) with the smooth-boundary (crease)
 * rules of Hoppe et al. 1994, "Piecewise smooth surface reconstruction".
 *
 * Each level splits every triangle 1-to-4 (topology from
 * cfi_mesh_split4_triangles: old vertices keep their index, the vertex of
 * edge e is nv + e) and places
 *  - interior edge vertices at 3/8 (a + b) + 1/8 (c + d)        (Loop)
 *  - boundary edge vertices at 1/2 (a + b)                        (Hoppe)
 *  - interior old vertices at (1 - n beta) v + beta sum(nbrs),
 *    beta = (5/8 - (3/8 + cos(2 pi / n) / 4)^2) / n               (Loop)
 *  - boundary old vertices at 3/4 v + 1/8 (p + q), p, q its two
 *    boundary neighbours                                          (Hoppe)
 * Corner rules (fixed vertices) are not used: a boundary is one smooth
 * crease. Per-corner texture coordinates are subdivided linearly: an edge's
 * new uv is the midpoint of its two uv's, shared by both faces unless the
 * edge is a texture seam.
 */
#include "curvflow/ops.h"
#include "mesh/mesh_internal.h"

#include <math.h>
#include <string.h>

#define LOOP_PI 3.14159265358979323846

/* New positions of one level (3 (nv + ne) doubles). */
static void loop_positions(const cf_mesh *m, const double *p, double *out)
{
    const int32_t nv = m->nv, ne = m->ne;
    const int32_t *tri = m->triangles;
    for (int32_t v = 0; v < nv; ++v) {
        const int32_t r0 = m->ring_offsets[v], r1 = m->ring_offsets[v + 1];
        double s[3] = {0.0, 0.0, 0.0};
        double *o = out + 3 * (size_t)v;
        const double *pv = p + 3 * (size_t)v;
        if (m->vertex_on_boundary[v]) {
            /* Hoppe 1994 crease rule: only the two boundary neighbours */
            for (int32_t k = r0; k < r1; ++k) {
                int32_t e = m->ring_edges[k];
                if (m->edge_faces[2 * e] >= 0 && m->edge_faces[2 * e + 1] >= 0) continue;
                const double *q = p + 3 * (size_t)m->ring_neighbors[k];
                for (int d = 0; d < 3; ++d) s[d] += q[d];
            }
            for (int d = 0; d < 3; ++d) o[d] = 0.75 * pv[d] + 0.125 * s[d];
        } else {
            const int32_t n = r1 - r0;
            const double c = 0.375 + 0.25 * cos(2.0 * LOOP_PI / n);
            const double beta = (0.625 - c * c) / n; /* Loop 1987 */
            for (int32_t k = r0; k < r1; ++k) {
                const double *q = p + 3 * (size_t)m->ring_neighbors[k];
                for (int d = 0; d < 3; ++d) s[d] += q[d];
            }
            for (int d = 0; d < 3; ++d) o[d] = (1.0 - n * beta) * pv[d] + beta * s[d];
        }
    }
    for (int32_t e = 0; e < ne; ++e) {
        const double *a = p + 3 * (size_t)m->edge_vertices[2 * e];
        const double *b = p + 3 * (size_t)m->edge_vertices[2 * e + 1];
        double *o = out + 3 * ((size_t)nv + e);
        const int32_t h = m->edge_halfedge[e], t = m->halfedge_twin[h];
        if (t < 0) {
            for (int d = 0; d < 3; ++d) o[d] = 0.5 * (a[d] + b[d]);
        } else {
            const double *c = p + 3 * (size_t)tri[cfi_he_prev(h)];
            const double *dd = p + 3 * (size_t)tri[cfi_he_prev(t)];
            for (int d = 0; d < 3; ++d) o[d] = 0.375 * (a[d] + b[d]) + 0.125 * (c[d] + dd[d]);
        }
    }
}

/* Per-corner uv of one level. mid[h] receives the uv index of halfedge h's
 * midpoint; returns the new uv count. Writes uv_out (2 * count) and
 * uv_tri_out (12 nf) when non-NULL. */
static int32_t loop_uv(const cf_mesh *m, int32_t *mid, double *uv_out, int32_t *uv_tri_out)
{
    const int32_t *ut = m->uv_triangles;
    int32_t n = m->uv_count;
    if (uv_out) memcpy(uv_out, m->uv, 2 * (size_t)m->uv_count * sizeof(double));
    for (int32_t h = 0; h < 3 * m->nf; ++h) {
        const int32_t t = m->halfedge_twin[h];
        const int32_t a = ut[h], b = ut[cfi_he_next(h)];
        /* shared across the edge unless it is a texture seam */
        if (t >= 0 && t < h && ut[t] == b && ut[cfi_he_next(t)] == a) {
            mid[h] = mid[t];
            continue;
        }
        mid[h] = n;
        if (uv_out)
            for (int d = 0; d < 2; ++d)
                uv_out[2 * (size_t)n + d] = 0.5 * (m->uv[2 * (size_t)a + d] + m->uv[2 * (size_t)b + d]);
        ++n;
    }
    if (uv_tri_out)
        for (int32_t f = 0; f < m->nf; ++f) {
            /* same child layout as cfi_mesh_split4_triangles */
            const int32_t *c = ut + 3 * (size_t)f;
            int32_t mab = mid[3 * f], mbc = mid[3 * f + 1], mca = mid[3 * f + 2];
            int32_t *o = uv_tri_out + 12 * (size_t)f;
            o[0] = c[0], o[1] = mab, o[2] = mca;
            o[3] = mab, o[4] = c[1], o[5] = mbc;
            o[6] = mca, o[7] = mbc, o[8] = c[2];
            o[9] = mab, o[10] = mbc, o[11] = mca;
        }
    return n;
}

static cf_status loop_level(cf_context *ctx, const cf_mesh *m, const double *positions, cf_mesh **out)
{
    const size_t nv2 = (size_t)m->nv + (size_t)m->ne, nf4 = 4 * (size_t)m->nf, nh = 3 * (size_t)m->nf;
    if (nv2 > (size_t)INT32_MAX / 4 || nf4 > (size_t)INT32_MAX / 12)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "subdivided mesh too large (%zu vertices, %zu faces)", nv2, nf4);
    double *pos = CFI_ALLOC(ctx, double, 3 * nv2);
    int32_t *tri = CFI_ALLOC(ctx, int32_t, 3 * nf4);
    int32_t *mid = NULL, *uv_tri = NULL;
    double *uv = NULL;
    int32_t nuv = 0;
    cf_status st = pos && tri ? CF_OK : CF_ERR_NOMEM;
    if (st == CF_OK && m->uv) {
        mid = CFI_ALLOC(ctx, int32_t, nh);
        uv_tri = CFI_ALLOC(ctx, int32_t, 3 * nf4);
        if (!mid || !uv_tri) st = CF_ERR_NOMEM;
        if (st == CF_OK) {
            nuv = loop_uv(m, mid, NULL, NULL);
            uv = CFI_ALLOC(ctx, double, 2 * (size_t)nuv);
            if (!uv) st = CF_ERR_NOMEM;
        }
        if (st == CF_OK) loop_uv(m, mid, uv, uv_tri);
    }
    if (st == CF_OK) {
        loop_positions(m, positions, pos);
        cfi_mesh_split4_triangles(m, tri);
        cf_mesh_desc d = {(int32_t)nv2, pos, (int32_t)nf4, tri, nuv, uv, uv_tri};
        st = cf_mesh_create(ctx, &d, out);
    }
    CFI_FREE(ctx, pos, 3 * nv2);
    CFI_FREE(ctx, tri, 3 * nf4);
    CFI_FREE(ctx, mid, nh);
    CFI_FREE(ctx, uv_tri, 3 * nf4);
    CFI_FREE(ctx, uv, 2 * (size_t)nuv);
    return st;
}

cf_status cf_loop_subdivide(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t levels,
                            cf_mesh **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "output pointer is NULL");
    *out = NULL;
    if (!mesh || !positions) return cfi_error(ctx, CF_ERR_INVALID_ARG, "mesh or positions is NULL");
    if (levels < 1 || levels > 10) return cfi_error(ctx, CF_ERR_INVALID_ARG, "levels %d outside [1, 10]", levels);
    for (int32_t i = 0; i < 3 * mesh->nv; ++i)
        if (!isfinite(positions[i]))
            return cfi_error(ctx, CF_ERR_NONFINITE, "vertex %d: coordinate %c is not finite", i / 3, "xyz"[i % 3]);
    cf_mesh *cur = NULL;
    cf_status st = loop_level(ctx, mesh, positions, &cur);
    for (int32_t level = 1; st == CF_OK && level < levels; ++level) {
        cf_mesh *next = NULL;
        st = loop_level(ctx, cur, cur->positions, &next);
        cf_mesh_destroy(&cur);
        cur = next;
    }
    if (st != CF_OK) {
        cf_mesh_destroy(&cur);
        return st;
    }
    *out = cur;
    return CF_OK;
}
