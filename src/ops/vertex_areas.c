/*
 * Dual (vertex) areas: barycentric (a third of each incident face) or the
 * mixed Voronoi cells of Meyer, Desbrun, Schroeder & Barr 2003 (Sec. 3.3,
 * Fig. 4): Voronoi region inside non-obtuse triangles, A/2 at an obtuse
 * corner and A/4 at the other two corners of an obtuse triangle. Both sum
 * to the total area.
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

cf_status cf_vertex_areas(cf_context *ctx, const cf_mesh *mesh, const double *positions, cf_dual_area_kind kind,
                          double *areas)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, areas, "vertex_areas");
    if (s != CF_OK) return s;
    if (kind != CF_DUAL_AREA_BARYCENTRIC && kind != CF_DUAL_AREA_MIXED_VORONOI)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "vertex_areas: unknown kind %d", (int)kind);
    for (int32_t v = 0; v < mesh->nv; ++v) areas[v] = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        if (kind == CF_DUAL_AREA_BARYCENTRIC) {
            double a = cfi_face_area(mesh, positions, f) / 3.0;
            for (int k = 0; k < 3; ++k) areas[t[k]] += a;
            continue;
        }
        double cot[3], a2;
        s = cfi_face_cotangents(ctx, mesh, positions, f, 0.0, cot, &a2);
        if (s != CF_OK) return s;
        double area = 0.5 * a2;
        int obtuse = -1;
        for (int k = 0; k < 3; ++k)
            if (cot[k] < 0.0) obtuse = k;
        for (int k = 0; k < 3; ++k) {
            if (obtuse >= 0) {
                areas[t[k]] += obtuse == k ? 0.5 * area : 0.25 * area;
                continue;
            }
            /* Meyer 2003, Eq. (7): (1/8) sum |PQ|^2 cot(angle opposite PQ) */
            double u[3], w[3];
            cfi_v3_sub(positions + 3 * t[(k + 1) % 3], positions + 3 * t[k], u);
            cfi_v3_sub(positions + 3 * t[(k + 2) % 3], positions + 3 * t[k], w);
            areas[t[k]] += (cfi_v3_dot(u, u) * cot[(k + 2) % 3] + cfi_v3_dot(w, w) * cot[(k + 1) % 3]) / 8.0;
        }
    }
    return CF_OK;
}
