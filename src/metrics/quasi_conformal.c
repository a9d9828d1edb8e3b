/*
 * Per-face comparisons of two position sets on one connectivity:
 * quasi-conformal error (Sander, Snyder, Gortler & Hoppe 2001, Sec. 3: the
 * ratio of the singular values of the affine map between corresponding
 * triangles), log area distortion, per-vertex corner-angle change, and the
 * vertex-scale fit (the conformal part of the map: log scales at the
 * vertices fitted to the edge-length change, the rescaling of discrete
 * conformal equivalence, Luo 2004 / Springborn, Schroeder, Pinkall 2008,
 * and the Q that their variation across a face causes by itself).
 *
 * The 2 x 2 map J = [[a, b], [c, d]] between the triangles, each written in
 * its own orthonormal frame, splits into conformal and anti-conformal parts:
 * s_max + s_min = |(a + d, c - b)| = P and s_max - s_min = |(a - d, b + c)| = M
 * (P and M swap for a reflection), so Q = (P + M) / |P - M|. Unlike the
 * closed form with sqrt(E^2 - 4 det^2), this gives Q - 1 at round-off level
 * for a similarity.
 */
#include "metrics/metrics_internal.h"
#include "curvflow/linalg.h"
#include "curvflow/ops.h"

#include <math.h>
#include <string.h>

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

/* Q of the affine map from the triangle with frame p to the one with frame
 * r (face_frame's form); infinite for a singular map. */
static double frames_q(const double p[4], const double r[4])
{
    /* J = R P^-1, P^-1 = [[1/p0, -p1/(p0 p3)], [0, 1/p3]] */
    double ja = r[0] / p[0], jb = (r[1] - r[0] * p[1] / p[0]) / p[3];
    double jc = r[2] / p[0], jd = (r[3] - r[2] * p[1] / p[0]) / p[3];
    double pc = hypot(ja + jd, jc - jb), mc = hypot(ja - jd, jb + jc);
    double smin = fabs(pc - mc);
    return smin > 0.0 ? (pc + mc) / smin : INFINITY;
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
        qq[f] = frames_q(p, r);
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

static double edge_length(const double *x, int32_t i, int32_t j)
{
    return hypot(hypot(x[3 * i] - x[3 * j], x[3 * i + 1] - x[3 * j + 1]), x[3 * i + 2] - x[3 * j + 2]);
}

/* y = N x for the signless Laplacian N = A^T A of the edge-vertex incidence
 * A (+1, +1 per edge): degree on the diagonal, 1 per edge; *xy = x^T y
 * (cf_pcg_multiply_fn, one column; user: the mesh). */
static void signless_multiply(void *user, const double *x, double *y, double *xy)
{
    const cf_mesh *mesh = user;
    const int32_t *ev = mesh->edge_vertices;
    for (int32_t i = 0; i < mesh->nv; ++i) y[i] = 0.0;
    for (int32_t e = 0; e < mesh->ne; ++e) {
        int32_t i = ev[2 * e], j = ev[2 * e + 1];
        y[i] += x[i] + x[j];
        y[j] += x[i] + x[j];
    }
    *xy = 0.0;
    for (int32_t i = 0; i < mesh->nv; ++i) *xy += x[i] * y[i];
}

/* The least-squares log scales: the normal equations N u = A^T t with t_e =
 * 2 log(|e|_b / |e|_a). N is positive definite because every component of a
 * triangle mesh has an odd cycle, and well conditioned: it depends on the
 * graph only (not on the triangles' shapes), and on a regular triangulation
 * its spectrum is [3, 12]. So conjugate gradients with the diagonal (the
 * degrees) as preconditioner (cf_pcg_solve) solve it in a few dozen iterations, with four
 * vectors and no factor (a Cholesky factor took 0.25 s and 35 % of its time
 * in BLAS threads' spinning at 41k vertices). Returns the edges' RMS
 * residual in *rms. */
#define CFI_SCALE_FIT_TOLERANCE 1e-13
#define CFI_SCALE_FIT_MAX_ITERATIONS 2000
static cf_status fit_log_scales(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b, double *u,
                                double *rms)
{
    int32_t nv = mesh->nv, ne = mesh->ne;
    const int32_t *ev = mesh->edge_vertices;
    double *target = CFI_ALLOC(ctx, double, ne), *inverse_degree = CFI_ALLOC(ctx, double, nv);
    double *r = CFI_ALLOC(ctx, double, nv), *p = CFI_ALLOC(ctx, double, nv), *q = CFI_ALLOC(ctx, double, nv);
    cf_status s = CF_OK;
    if (!target || !inverse_degree || !r || !p || !q) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    for (int32_t i = 0; i < nv; ++i) inverse_degree[i] = r[i] = u[i] = 0.0;
    for (int32_t e = 0; e < ne; ++e) {
        int32_t i = ev[2 * e], j = ev[2 * e + 1];
        double la = edge_length(a, i, j), lb = edge_length(b, i, j);
        if (!(la > 0.0) || !(lb > 0.0)) {
            s = cfi_error(ctx, CF_ERR_DEGENERATE_FACE,
                          "vertex_scale_fit: edge %d (vertices %d, %d): zero length in the %s positions", e, i, j,
                          la > 0.0 ? "deformed" : "reference");
            goto done;
        }
        target[e] = 2.0 * log(lb / la);
        r[i] += target[e];
        r[j] += target[e];
        inverse_degree[i] += 1.0;
        inverse_degree[j] += 1.0;
    }
    /* preconditioned conjugate gradients from u = 0 (r = A^T t) */
    for (int32_t i = 0; i < nv; ++i) inverse_degree[i] = 1.0 / inverse_degree[i]; /* the degree until here */
    cf_pcg_result pcg;
    s = cf_pcg_solve(ctx, nv, 1, signless_multiply, (void *)(uintptr_t)mesh, inverse_degree, u, r, p, q,
                     CFI_SCALE_FIT_TOLERANCE, CFI_SCALE_FIT_MAX_ITERATIONS, &pcg);
    if (s == CF_ERR_NOT_CONVERGED) cfi_error_prefix(ctx, "vertex_scale_fit");
    if (s != CF_OK) goto done;
    double sum = 0.0;
    for (int32_t e = 0; e < ne; ++e) {
        double res = 0.5 * (target[e] - u[ev[2 * e]] - u[ev[2 * e + 1]]);
        sum += res * res;
    }
    *rms = ne > 0 ? sqrt(sum / ne) : 0.0;
done:
    CFI_FREE(ctx, target, ne);
    CFI_FREE(ctx, inverse_degree, nv);
    CFI_FREE(ctx, r, nv);
    CFI_FREE(ctx, p, nv);
    CFI_FREE(ctx, q, nv);
    return s;
}

/* The model Q of face f: its triangle in a against the triangle of its
 * lengths in a rescaled by e^((u_i + u_j) / 2) (NaN when they form none). */
static double model_face_q(const cf_mesh *mesh, const double *a, const double *u, int32_t f, const double p[4])
{
    const int32_t *t = mesh->triangles + 3 * f;
    double l01 = edge_length(a, t[0], t[1]) * exp(0.5 * (u[t[0]] + u[t[1]]));
    double l02 = edge_length(a, t[0], t[2]) * exp(0.5 * (u[t[0]] + u[t[2]]));
    double l12 = edge_length(a, t[1], t[2]) * exp(0.5 * (u[t[1]] + u[t[2]]));
    /* Heron: 16 A^2; the model triangle in face_frame's form */
    double h = (l01 + l02 + l12) * (l02 + l12 - l01) * (l01 - l02 + l12) * (l01 + l02 - l12);
    if (!(h > 0.0)) return NAN;
    double r[4] = {l01, (l01 * l01 + l02 * l02 - l12 * l12) / (2.0 * l01), 0.0, sqrt(h) / (2.0 * l01)};
    return frames_q(p, r);
}

cf_status cf_vertex_scale_fit_compute(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                      double *u, double *q, cf_vertex_scale_fit *result)
{
    cf_status s = cfi_metrics_check_pair(ctx, mesh, a, b, "vertex_scale_fit");
    if (s != CF_OK) return s;
    int32_t nv = mesh->nv, nf = mesh->nf, valid = 0;
    double *uu = CFI_ALLOC(ctx, double, nv), *qq = CFI_ALLOC(ctx, double, nf);
    double *qv = CFI_ALLOC(ctx, double, nf), *area = CFI_ALLOC(ctx, double, nf);
    cf_vertex_scale_fit out;
    memset(&out, 0, sizeof out);
    if (!uu || !qq || !qv || !area) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    if ((s = fit_log_scales(ctx, mesh, a, b, uu, &out.rms_residual)) != CF_OK) goto done;
    for (int32_t f = 0; f < nf; ++f) {
        double p[4];
        if (!face_frame(mesh, a, f, p)) {
            s = cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "vertex_scale_fit: face %d: zero area in the reference positions",
                          f);
            goto done;
        }
        qq[f] = model_face_q(mesh, a, uu, f, p);
        if (isfinite(qq[f])) {
            qv[valid] = qq[f];
            area[valid++] = 0.5 * p[0] * p[3];
        }
    }
    out.invalid_faces = nf - valid;
    if (valid == 0) {
        s = cfi_error(ctx, CF_ERR_NUMERICAL, "vertex_scale_fit: no face's rescaled lengths form a triangle");
        goto done;
    }
    if (result && (s = cf_stats_compute(ctx, valid, qv, area, &out.q)) != CF_OK) goto done;
    if (u) memcpy(u, uu, (size_t)nv * sizeof *u);
    if (q) memcpy(q, qq, (size_t)nf * sizeof *q);
    if (result) *result = out;
done:
    CFI_FREE(ctx, uu, nv);
    CFI_FREE(ctx, qq, nf);
    CFI_FREE(ctx, qv, nf);
    CFI_FREE(ctx, area, nf);
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
