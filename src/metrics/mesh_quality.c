/*
 * Mesh quality summary (cf_mesh_quality_compute, curvflow/metrics.h): the
 * corner-angle and face-area statistics that `curvflow info` prints and the
 * Python package's curvflow.info returns, computed once here so that both
 * report the same numbers. Medians are the element n / 2 of the sorted
 * values (the upper median, as ../shared/meshes/CHECKS.tsv computes it);
 * the total area is summed in face order.
 */
#include "metrics/metrics_internal.h"
#include "curvflow/ops.h"

#include <math.h>
#include <stdlib.h>

static int compare_doubles(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return (a > b) - (a < b);
}

cf_status cf_mesh_quality_compute(cf_context *ctx, const cf_mesh *mesh, const double *positions, cf_mesh_quality *out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!mesh || !out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "mesh_quality: mesh or out is NULL");
    const double *x = positions ? positions : mesh->positions;
    int32_t nv = mesh->nv, nf = mesh->nf;
    int64_t bad = cfi_first_unusable_point(x, nv, 3);
    if (bad >= 0)
        return cfi_error(ctx, CF_ERR_NONFINITE, "mesh_quality: vertex %lld: coordinate is not finite or beyond %g",
                         (long long)bad, CF_MAX_COORDINATE);
    size_t na = 3 * (size_t)nf;
    double *angles = CFI_ALLOC(ctx, double, na);
    double *faces = CFI_ALLOC(ctx, double, nf);
    if (!angles || !faces) {
        CFI_FREE(ctx, angles, na);
        CFI_FREE(ctx, faces, nf);
        return CF_ERR_NOMEM;
    }
    cf_mesh_quality q;
    const double deg = 180.0 / acos(-1.0);
    cf_status st = cf_corner_angles(ctx, mesh, x, angles);
    if (st != CF_OK) goto done;
    size_t below = 0, faces_below = 0;
    for (size_t i = 0; i < na; ++i) below += angles[i] * deg < 10.0;
    for (int32_t f = 0; f < nf; ++f) {
        double m = fmin(angles[3 * f], fmin(angles[3 * f + 1], angles[3 * f + 2]));
        faces[f] = m;
        faces_below += m * deg < 10.0;
    }
    qsort(angles, na, sizeof *angles, compare_doubles);
    qsort(faces, (size_t)nf, sizeof *faces, compare_doubles);
    q.min_angle = angles[0];
    q.median_angle = angles[na / 2];
    q.max_angle = angles[na - 1];
    q.fraction_angles_below_10_degrees = (double)below / (double)na;
    q.median_face_min_angle = faces[nf / 2];
    q.fraction_faces_min_below_10_degrees = (double)faces_below / (double)nf;
    if ((st = cf_face_areas(ctx, mesh, x, faces)) != CF_OK) goto done;
    q.total_area = 0.0;
    for (int32_t f = 0; f < nf; ++f) q.total_area += faces[f];
    qsort(faces, (size_t)nf, sizeof *faces, compare_doubles);
    q.min_face_area = faces[0];
    q.median_face_area = faces[nf / 2];
    q.max_face_area = faces[nf - 1];
    q.willmore_over_4pi = NAN;
    q.volume = NAN;
    if (mesh->boundary_loop_count == 0) {
        double w = 0.0;
        if ((st = cf_willmore_energy(ctx, mesh, x, &w)) != CF_OK ||
            (st = cf_enclosed_volume(ctx, mesh, x, &q.volume)) != CF_OK)
            goto done;
        q.willmore_over_4pi = w / (4.0 * acos(-1.0));
    }
    *out = q;
done:
    CFI_FREE(ctx, angles, na);
    CFI_FREE(ctx, faces, nf);
    return st;
}
