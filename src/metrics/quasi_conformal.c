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
    /* sqrt rather than hypot: the entries are ratios of lengths of one
     * triangle, far from overflow, and this runs at every step of a flow
     * (cf_conformal_excess) */
    double pc = sqrt((ja + jd) * (ja + jd) + (jc - jb) * (jc - jb));
    double mc = sqrt((ja - jd) * (ja - jd) + (jb + jc) * (jb + jc));
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

static double squared_edge_length(const double *x, int32_t i, int32_t j)
{
    double dx = x[3 * i] - x[3 * j], dy = x[3 * i + 1] - x[3 * j + 1], dz = x[3 * i + 2] - x[3 * j + 2];
    return dx * dx + dy * dy + dz * dz;
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
 * degrees) as preconditioner (cf_pcg_solve) solve it in a few dozen
 * iterations, with four vectors and no factor (a Cholesky factor took 0.25 s and 35 % of its time
 * in BLAS threads' spinning at 41k vertices). Returns the edges' RMS
 * residual in *rms (if not NULL); work: fit_work_size doubles. */
#define CFI_SCALE_FIT_TOLERANCE 1e-13
#define CFI_SCALE_FIT_MAX_ITERATIONS 2000
/* cf_conformal_excess needs the mean model Q to a few digits: 21 iterations
 * instead of 25 on spot_3k; at 1e-6 armadillo's mean model Q moved in the
 * second decimal, at 1e-8 and 1e-10 not in the fifth */
#define CFI_EXCESS_FIT_TOLERANCE 1e-10
/* Workspace of fit_log_scales: the edges' targets (ne) and the conjugate
 * gradients' preconditioner and vectors (4 nv). */
static int64_t fit_work_size(const cf_mesh *mesh) { return (int64_t)mesh->ne + 4 * (int64_t)mesh->nv; }

static cf_status fit_log_scales(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b, double *u,
                                double *rms, double *work, double tolerance)
{
    int32_t nv = mesh->nv, ne = mesh->ne;
    const int32_t *ev = mesh->edge_vertices;
    double *target = work, *inverse_degree = target + ne, *r = inverse_degree + nv, *p = r + nv, *q = p + nv;
    for (int32_t i = 0; i < nv; ++i) inverse_degree[i] = r[i] = u[i] = 0.0;
    for (int32_t e = 0; e < ne; ++e) {
        int32_t i = ev[2 * e], j = ev[2 * e + 1];
        double la2 = squared_edge_length(a, i, j), lb2 = squared_edge_length(b, i, j);
        if (!(la2 > 0.0) || !(lb2 > 0.0))
            return cfi_error(ctx, CF_ERR_DEGENERATE_FACE,
                             "vertex_scale_fit: edge %d (vertices %d, %d): zero length in the %s positions", e, i, j,
                             la2 > 0.0 ? "deformed" : "reference");
        target[e] = log(lb2 / la2); /* 2 log(|e|_b / |e|_a) */
        r[i] += target[e];
        r[j] += target[e];
        inverse_degree[i] += 1.0;
        inverse_degree[j] += 1.0;
    }
    /* preconditioned conjugate gradients from u = 0 (r = A^T t) */
    for (int32_t i = 0; i < nv; ++i) inverse_degree[i] = 1.0 / inverse_degree[i]; /* it held the degree */
    cf_pcg_result pcg;
    cf_status s = cf_pcg_solve(ctx, nv, 1, signless_multiply, (void *)(uintptr_t)mesh, inverse_degree, u, r, p, q,
                               tolerance, CFI_SCALE_FIT_MAX_ITERATIONS, &pcg);
    if (s == CF_ERR_NOT_CONVERGED) cfi_error_prefix(ctx, "vertex_scale_fit");
    if (s != CF_OK) return s;
    if (rms) {
        double sum = 0.0;
        for (int32_t e = 0; e < ne; ++e) {
            double res = 0.5 * (target[e] - u[ev[2 * e]] - u[ev[2 * e + 1]]);
            sum += res * res;
        }
        *rms = ne > 0 ? sqrt(sum / ne) : 0.0;
    }
    return CF_OK;
}

/* The model Q of face f: its triangle in a against the triangle of its
 * lengths in a rescaled by e^((u_i + u_j) / 2) = scale_i scale_j, with
 * scale = e^(u / 2) per vertex (NaN when they form none). */
static double model_face_q(const cf_mesh *mesh, const double *a, const double *scale, int32_t f, const double p[4])
{
    const int32_t *t = mesh->triangles + 3 * f;
    double l01 = sqrt(squared_edge_length(a, t[0], t[1])) * scale[t[0]] * scale[t[1]];
    double l02 = sqrt(squared_edge_length(a, t[0], t[2])) * scale[t[0]] * scale[t[2]];
    double l12 = sqrt(squared_edge_length(a, t[1], t[2])) * scale[t[1]] * scale[t[2]];
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
    int64_t nwork = fit_work_size(mesh);
    double *uu = CFI_ALLOC(ctx, double, nv), *qq = CFI_ALLOC(ctx, double, nf);
    double *qv = CFI_ALLOC(ctx, double, nf), *area = CFI_ALLOC(ctx, double, nf);
    double *work = CFI_ALLOC(ctx, double, nwork);
    cf_vertex_scale_fit out;
    memset(&out, 0, sizeof out);
    if (!uu || !qq || !qv || !area || !work) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    if ((s = fit_log_scales(ctx, mesh, a, b, uu, &out.rms_residual, work, CFI_SCALE_FIT_TOLERANCE)) != CF_OK) goto done;
    double *scale = work; /* the fit's workspace is free again (ne + 4 nv >= nv entries) */
    for (int32_t i = 0; i < nv; ++i) scale[i] = exp(0.5 * uu[i]);
    for (int32_t f = 0; f < nf; ++f) {
        double p[4];
        if (!face_frame(mesh, a, f, p)) {
            s = cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "vertex_scale_fit: face %d: zero area in the reference positions",
                          f);
            goto done;
        }
        qq[f] = model_face_q(mesh, a, scale, f, p);
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
    CFI_FREE(ctx, work, nwork);
    return s;
}

int64_t cf_conformal_excess_work_size(const cf_mesh *mesh)
{
    return mesh ? (int64_t)mesh->nv + fit_work_size(mesh) : 0;
}

cf_status cf_conformal_excess(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b, double *work,
                              double *mean_q, double *mean_model_q)
{
    cf_status s = cfi_metrics_check_pair(ctx, mesh, a, b, "conformal_excess");
    if (s != CF_OK) return s;
    if (!work || !mean_q || !mean_model_q)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "conformal_excess: work, mean_q or mean_model_q is NULL");
    double *u = work, *scale = work + mesh->nv;
    if ((s = fit_log_scales(ctx, mesh, a, b, u, NULL, work + mesh->nv, CFI_EXCESS_FIT_TOLERANCE)) != CF_OK) return s;
    for (int32_t i = 0; i < mesh->nv; ++i) scale[i] = exp(0.5 * u[i]); /* over the fit's spent workspace */
    /* the weighted means of cf_quasi_conformal_error and cf_vertex_scale_fit_compute, without their
     * per-face arrays and percentiles */
    double sum_q = 0.0, sum_area = 0.0, sum_model = 0.0, sum_model_area = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double p[4], r[4];
        if (!face_frame(mesh, a, f, p))
            return cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "conformal_excess: face %d: zero area in the reference "
                             "positions", f);
        double area = 0.5 * p[0] * p[3];
        /* a face of zero area in b has no finite Q: the mean is infinite */
        sum_q += area * (face_frame(mesh, b, f, r) ? frames_q(p, r) : INFINITY);
        sum_area += area;
        double model = model_face_q(mesh, a, scale, f, p);
        if (isfinite(model)) {
            sum_model += area * model;
            sum_model_area += area;
        }
    }
    *mean_q = sum_q / sum_area;
    *mean_model_q = sum_model_area > 0.0 ? sum_model / sum_model_area : NAN;
    return CF_OK;
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
