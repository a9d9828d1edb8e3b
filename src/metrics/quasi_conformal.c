/*
 * Per-face comparisons of two position sets on one connectivity:
 * quasi-conformal error (Sander, Snyder, Gortler & Hoppe 2001, Sec. 3: the
 * ratio of the singular values of the affine map between corresponding
 * triangles), log area distortion and per-vertex corner-angle change.
 *
 * The 2 x 2 map J = [[a, b], [c, d]] between the triangles, each written in
 * its own orthonormal frame, splits into conformal and anti-conformal parts:
 * s_max + s_min = |(a + d, c - b)| = P and s_max - s_min = |(a - d, b + c)| = M
 * (P and M swap for a reflection), so Q = (P + M) / |P - M|. Unlike the
 * closed form with sqrt(E^2 - 4 det^2), this gives Q - 1 at round-off level
 * for a similarity.
 */
#include "metrics/metrics_internal.h"
#include "curvflow/ops.h"

#include <math.h>

/* Edge vectors of face f in the face's own frame: columns (e1, e2) as the
 * upper-triangular [[|e1|, e2.x], [0, e2.y]]. Returns 0 for a degenerate face. */
static int face_frame(const cf_mesh *mesh, const double *x, int32_t f, double m[4])
{
    const int32_t *t = mesh->triangles + 3 * f;
    double e1[3], e2[3], n[3];
    for (int c = 0; c < 3; ++c) {
        e1[c] = x[3 * t[1] + c] - x[3 * t[0] + c];
        e2[c] = x[3 * t[2] + c] - x[3 * t[0] + c];
    }
    double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double a2 = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(l1 > 0.0) || !(a2 > 0.0)) return 0;
    m[0] = l1;
    m[1] = (e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]) / l1;
    m[2] = 0.0;
    m[3] = a2 / l1; /* e2 . (n x e1)/|..| = twice the area / |e1| */
    return 1;
}

cf_status cf_quasi_conformal_error(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                   double *q, cf_stats *stats)
{
    cf_status s = cfi_metrics_check_pair(ctx, mesh, a, b, "quasi_conformal_error");
    if (s != CF_OK) return s;
    double *qq = CFI_ALLOC(ctx, double, mesh->nf);
    double *area = CFI_ALLOC(ctx, double, mesh->nf);
    if (!qq || !area) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double p[4], r[4];
        if (!face_frame(mesh, a, f, p)) {
            s = cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "face %d: zero area in the reference positions", f);
            goto done;
        }
        if (!face_frame(mesh, b, f, r)) {
            s = cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "face %d: zero area in the deformed positions", f);
            goto done;
        }
        area[f] = 0.5 * p[0] * p[3];
        /* J = R P^-1, P^-1 = [[1/p0, -p1/(p0 p3)], [0, 1/p3]] */
        double ja = r[0] / p[0], jb = (r[1] - r[0] * p[1] / p[0]) / p[3];
        double jc = r[2] / p[0], jd = (r[3] - r[2] * p[1] / p[0]) / p[3];
        double pc = hypot(ja + jd, jc - jb), mc = hypot(ja - jd, jb + jc);
        double smin = fabs(pc - mc);
        qq[f] = smin > 0.0 ? (pc + mc) / smin : INFINITY;
        if (!isfinite(qq[f])) {
            s = cfi_error(ctx, CF_ERR_NUMERICAL, "face %d: affine map is singular (Q infinite)", f);
            goto done;
        }
    }
    if (stats) s = cf_stats_compute(ctx, mesh->nf, qq, area, stats);
    if (s == CF_OK && q)
        for (int32_t f = 0; f < mesh->nf; ++f) q[f] = qq[f];
done:
    CFI_FREE(ctx, qq, mesh->nf);
    CFI_FREE(ctx, area, mesh->nf);
    return s;
}

cf_status cf_log_area_distortion(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                 double *out, cf_stats *stats)
{
    cf_status s = cfi_metrics_check_pair(ctx, mesh, a, b, "log_area_distortion");
    if (s != CF_OK) return s;
    double *aa = CFI_ALLOC(ctx, double, mesh->nf);
    double *ab = CFI_ALLOC(ctx, double, mesh->nf);
    if (!aa || !ab) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    if ((s = cf_face_areas(ctx, mesh, a, aa)) != CF_OK) goto done;
    if ((s = cf_face_areas(ctx, mesh, b, ab)) != CF_OK) goto done;
    double ta = 0.0, tb = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        ta += aa[f];
        tb += ab[f];
    }
    double norm = log(ta / tb);
    for (int32_t f = 0; f < mesh->nf; ++f) {
        if (!(aa[f] > 0.0) || !(ab[f] > 0.0)) {
            s = cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "face %d: zero area", f);
            goto done;
        }
        ab[f] = log(ab[f] / aa[f]) + norm;
    }
    if (stats) s = cf_stats_compute(ctx, mesh->nf, ab, aa, stats);
    if (s == CF_OK && out)
        for (int32_t f = 0; f < mesh->nf; ++f) out[f] = ab[f];
done:
    CFI_FREE(ctx, aa, mesh->nf);
    CFI_FREE(ctx, ab, mesh->nf);
    return s;
}

cf_status cf_angle_change(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b, double *out,
                          cf_stats *stats)
{
    cf_status s = cfi_metrics_check_pair(ctx, mesh, a, b, "angle_change");
    if (s != CF_OK) return s;
    int64_t nc = 3 * (int64_t)mesh->nf;
    double *ta = CFI_ALLOC(ctx, double, nc);
    double *tb = CFI_ALLOC(ctx, double, nc);
    double *dv = CFI_ALLOC(ctx, double, mesh->nv);
    double *w = CFI_ALLOC(ctx, double, mesh->nv);
    if (!ta || !tb || !dv || !w) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    if ((s = cf_corner_angles(ctx, mesh, a, ta)) != CF_OK) goto done;
    if ((s = cf_corner_angles(ctx, mesh, b, tb)) != CF_OK) goto done;
    if ((s = cf_vertex_areas(ctx, mesh, a, CF_DUAL_AREA_BARYCENTRIC, w)) != CF_OK) goto done;
    for (int64_t c = 0; c < nc; ++c) {
        int32_t v = mesh->triangles[c];
        dv[v] = fmax(dv[v], fabs(tb[c] - ta[c]));
    }
    if (stats) s = cf_stats_compute(ctx, mesh->nv, dv, w, stats);
    if (s == CF_OK && out)
        for (int32_t v = 0; v < mesh->nv; ++v) out[v] = dv[v];
done:
    CFI_FREE(ctx, ta, nc);
    CFI_FREE(ctx, tb, nc);
    CFI_FREE(ctx, dv, mesh->nv);
    CFI_FREE(ctx, w, mesh->nv);
    return s;
}
