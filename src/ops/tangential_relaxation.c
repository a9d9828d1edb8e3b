/*
 * Tangential relaxation: vertices slide within a surface so that the map
 * from reference triangles to theirs becomes more conformal, face by face.
 *
 * A conformal map sampled at the vertices is not conformal per triangle
 * where its scale varies across the triangle: a limb of 6-8 sides that a
 * conformal map shrinks by e^(2 pi / n) per ring has a mean quasi-conformal
 * error Q of 1.8-2.2 by itself (docs/spin.md, "The mean-Q misses are the
 * conformal scale's"). The most conformal piecewise-linear map onto the same
 * surface spreads that crowding; this module descends toward it without
 * moving the surface: each vertex goes to the nearest point of its own star
 * in the surface given, so a call moves no vertex out of its star and the
 * shape is the given one's, resampled.
 *
 * Energy (MIPS, Hormann and Greiner 2000), with reference areas as weights:
 *   E(x) = sum_f A0_f (sigma_1 / sigma_2 + sigma_2 / sigma_1) / 2
 *        = sum_f A0_f |J_f|^2 / (2 det J_f) = sum_f A0_f D_f / (2 A_f),
 * J_f the linear map of face f from its reference triangle, A_f its area now
 * and D_f = (1/2) sum_m cot0_m |e_m|^2 its Dirichlet energy (cot0_m the
 * reference cotangent at corner m, e_m the edge opposite m). E = sum A0 at a
 * similarity; (Q + 1 / Q) / 2 is Q's own measure up to second order.
 * Descent: in each sweep every vertex proposes a move along the tangential
 * part of its star's gradient, scaled by its star's area now over its
 * reference area (the gradient of a scale-free energy grows as 1 / size, so
 * the move is in units of the local size), with its own step: the move
 * must lower its star's energy with the other vertices where they are and
 * turn none of its faces against the surface given; the vertex's step grows
 * 1.5x after such a move and is halved (up to 6 times) until one is found.
 * The moves are then made together (Jacobi: no vertex order, so a symmetric
 * map stays symmetric) and halved together while E does not fall. A single
 * global step was the first version: the most crowded vertex set the step
 * of all, and a sphere crowded by a Moebius map (Q 1.18) stalled after 7
 * steps; sweeps in vertex order (Gauss-Seidel) converged about twice as
 * fast but moved the centroid of a symmetric star of eight limbs by 3e-4 of
 * its size (docs/spin.md, "Tangential relaxation"). The projection first
 * tries the face of the star that held the vertex last (the nearest point
 * of its plane, if inside the face), then the whole star.
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

#include <math.h>
#include <string.h>

/* the first trial step of every vertex, its bounds, and the halvings
 * tried per vertex and sweep */
#define CFI_RELAX_FIRST_STEP 0.05
#define CFI_RELAX_SMALLEST_STEP 1e-6
#define CFI_RELAX_LARGEST_STEP 1.0
#define CFI_RELAX_HALVINGS 6

struct cf_tangential_relaxation {
    cf_context *ctx;
    const cf_mesh *mesh;
    int32_t nv, nf;
    const double *reference; /* 3 nv: the mesh's rest positions, or reference_copy */
    double *reference_copy;  /* 3 nv: a reference given that is not the rest positions (else NULL) */
    double area0_total;   /* sum of the reference areas */
    /* the rest is made by the first apply above the threshold (make_arrays):
     * most of spin-willmore's flows never get there, and it would be held
     * from creation on (47 MB of reference triangles at 655k vertices) */
    double *area0;        /* nf: reference areas */
    double *cot0;         /* 3 nf: reference cotangents at the corners */
    double *star_area0;   /* nv: reference area of each vertex's star */
    uint8_t *held;        /* nv: 1 = kept where it is */
    int32_t *home;        /* nv: the face of its star the vertex was projected onto last (-1: none yet) */
    double *surface;      /* 3 nv: the surface of the current apply */
    double *surface_normal; /* 3 nf: its face normals (length twice the area) */
    double *x;            /* 3 nv: the iterate */
    double *proposal;     /* 3 nv: each vertex's move from it, made with the others where they are */
    uint8_t *proposed;    /* nv: 1 = the vertex has a move in proposal */
    double *vertex_step;  /* nv: each vertex's last kept step, the next sweep's first */
};

/* A0 D / (2 A) of one face with corners q (its MIPS energy times A0), and
 * its gradient with respect to each corner into g (may be NULL); *area (may
 * be NULL) its area. +inf when it has no area, or when `orientation` (may
 * be NULL) is given and the face turns against it. Both mips_energy and
 * the stars' moves take it from here, so the central differences of
 * cf_mips_energy check the gradient they follow. */
static double face_mips(const double *const q[3], double a0, const double *c, const double *orientation, double *area,
                        double g[3][3])
{
    double e[3][3], normal[3];
    for (int m = 0; m < 3; ++m) cfi_v3_sub(q[(m + 2) % 3], q[(m + 1) % 3], e[m]); /* opposite corner m */
    cfi_v3_cross(e[2], e[0], normal); /* (q1 - q0) x (q2 - q1) = 2 A n */
    if (orientation && !(cfi_v3_dot(normal, orientation) > 0.0)) return INFINITY;
    double twice_area = sqrt(cfi_v3_dot(normal, normal));
    if (area) *area = 0.5 * twice_area;
    if (!(twice_area > 0.0)) return INFINITY;
    double dirichlet = 0.5 * (c[0] * cfi_v3_dot(e[0], e[0]) + c[1] * cfi_v3_dot(e[1], e[1]) + c[2] * cfi_v3_dot(e[2], e[2]));
    double a = 0.5 * twice_area, energy = a0 * dirichlet / (2.0 * a);
    if (!g) return energy;
    /* dD/dq: e_m = q_(m+2) - q_(m+1) adds c_m e_m to q_(m+2), -c_m e_m to q_(m+1);
     * dA/dq_m = n x e_m / 2 */
    double n[3] = {normal[0] / twice_area, normal[1] / twice_area, normal[2] / twice_area};
    double gd = a0 / (2.0 * a), ga = -energy / a;
    for (int m = 0; m < 3; ++m) {
        double ne[3];
        cfi_v3_cross(n, e[m], ne);
        for (int j = 0; j < 3; ++j) g[m][j] = ga * 0.5 * ne[j];
    }
    for (int m = 0; m < 3; ++m)
        for (int j = 0; j < 3; ++j) {
            g[(m + 2) % 3][j] += gd * c[m] * e[m][j];
            g[(m + 1) % 3][j] -= gd * c[m] * e[m][j];
        }
    return energy;
}

/* E(x), and its gradient (3 nv, may be NULL) and the face areas (nf, may be
 * NULL). +inf when a face has no area, or when `orientation` (3 nf, may be
 * NULL) is given and a face turns against its normal there. */
static double mips_energy(const cf_mesh *mesh, const double *area0, const double *cot0, const double *x,
                          const double *orientation, double *gradient, double *face_area)
{
    if (gradient) memset(gradient, 0, 3 * (size_t)mesh->nv * sizeof(double));
    double energy = 0.0, g[3][3];
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        const double *const q[3] = {x + 3 * t[0], x + 3 * t[1], x + 3 * t[2]};
        double e = face_mips(q, area0[f], cot0 + 3 * f, orientation ? orientation + 3 * f : NULL,
                             face_area ? face_area + f : NULL, gradient ? g : NULL);
        if (!isfinite(e)) return INFINITY;
        energy += e;
        if (gradient)
            for (int m = 0; m < 3; ++m)
                for (int j = 0; j < 3; ++j) gradient[3 * t[m] + j] += g[m][j];
    }
    return energy;
}

/* The nearest point of the plane of triangle (a, b, c) to p into out, if
 * it lies in the triangle; 0 otherwise. */
static int inside_projection(const double *p, const double *a, const double *b, const double *c, double *out)
{
    double ab[3], ac[3], ap[3];
    cfi_v3_sub(b, a, ab), cfi_v3_sub(c, a, ac), cfi_v3_sub(p, a, ap);
    double d00 = cfi_v3_dot(ab, ab), d01 = cfi_v3_dot(ab, ac), d11 = cfi_v3_dot(ac, ac), d20 = cfi_v3_dot(ap, ab), d21 = cfi_v3_dot(ap, ac);
    double det = d00 * d11 - d01 * d01;
    if (!(det > 0.0)) return 0;
    double v = (d11 * d20 - d01 * d21) / det, w = (d00 * d21 - d01 * d20) / det;
    if (!(v >= 0.0 && w >= 0.0 && v + w <= 1.0)) return 0;
    for (int k = 0; k < 3; ++k) out[k] = a[k] + v * ab[k] + w * ac[k];
    return 1;
}

/* p moved onto the surface given: the nearest point of v's star there
 * (tried first on the face that held v last). */
static void project_to_star(cf_tangential_relaxation *r, int32_t v, double *p)
{
    const cf_mesh *mesh = r->mesh;
    const int32_t *offsets = mesh->vface_offsets, *faces = mesh->vface_faces;
    const double *s = r->surface;
    double q[3];
    int32_t h = r->home[v];
    if (h >= 0) {
        const int32_t *t = mesh->triangles + 3 * h;
        if (inside_projection(p, s + 3 * t[0], s + 3 * t[1], s + 3 * t[2], q)) {
            memcpy(p, q, sizeof q);
            return;
        }
    }
    double best[3] = {0, 0, 0}, best_d2 = INFINITY;
    for (int32_t k = offsets[v]; k < offsets[v + 1]; ++k) {
        const int32_t *t = mesh->triangles + 3 * faces[k];
        double d[3];
        cfi_nearest_point_on_triangle(p, s + 3 * t[0], s + 3 * t[1], s + 3 * t[2], q);
        cfi_v3_sub(q, p, d);
        double d2 = cfi_v3_dot(d, d);
        if (d2 < best_d2) best_d2 = d2, memcpy(best, q, sizeof best), r->home[v] = faces[k];
    }
    memcpy(p, best, sizeof best);
}

/* E of v's star with v at p and the other vertices at r->x, its gradient
 * with respect to p into grad (may be NULL) and the star's area into
 * *star_area (may be NULL); +inf when a face of the star has no area or
 * turns against its normal on the surface given. */
static double star_energy(const cf_tangential_relaxation *r, int32_t v, const double *p, double *grad,
                          double *star_area)
{
    const cf_mesh *mesh = r->mesh;
    const int32_t *offsets = mesh->vface_offsets, *faces = mesh->vface_faces;
    double energy = 0.0, area_sum = 0.0, g[3][3];
    if (grad) grad[0] = grad[1] = grad[2] = 0.0;
    for (int32_t k = offsets[v]; k < offsets[v + 1]; ++k) {
        int32_t f = faces[k];
        const int32_t *t = mesh->triangles + 3 * f;
        int corner = t[0] == v ? 0 : t[1] == v ? 1 : 2;
        const double *const q[3] = {corner == 0 ? p : r->x + 3 * t[0], corner == 1 ? p : r->x + 3 * t[1],
                                    corner == 2 ? p : r->x + 3 * t[2]};
        double area = 0.0;
        double e = face_mips(q, r->area0[f], r->cot0 + 3 * f, r->surface_normal + 3 * f, &area, grad ? g : NULL);
        if (!isfinite(e)) return INFINITY;
        energy += e;
        area_sum += area;
        if (grad)
            for (int j = 0; j < 3; ++j) grad[j] += g[corner][j];
    }
    if (star_area) *star_area = area_sum;
    return energy;
}

/* The move of v that lowers its star's energy with the other vertices
 * where they are, into r->proposal (which holds r->x there otherwise): 1
 * if there is one. */
static int propose_move(cf_tangential_relaxation *r, int32_t v, int32_t *trials)
{
    const cf_mesh *mesh = r->mesh;
    const int32_t *offsets = mesh->vface_offsets, *faces = mesh->vface_faces;
    const double *x = r->x + 3 * v;
    double g[3], star_area = 0.0;
    double energy = star_energy(r, v, x, g, &star_area);
    if (!isfinite(energy)) return 0;
    /* the tangent plane: the star's area-weighted normal on the surface given */
    double n[3] = {0, 0, 0};
    for (int32_t k = offsets[v]; k < offsets[v + 1]; ++k) {
        const double *fn = r->surface_normal + 3 * faces[k];
        n[0] += fn[0], n[1] += fn[1], n[2] += fn[2];
    }
    double nn = cfi_v3_dot(n, n), gn = nn > 0.0 ? cfi_v3_dot(g, n) / nn : 0.0, scale = star_area / r->star_area0[v];
    double d[3] = {-scale * (g[0] - gn * n[0]), -scale * (g[1] - gn * n[1]), -scale * (g[2] - gn * n[2])};
    if (!(cfi_v3_dot(d, d) > 0.0)) return 0;
    double step = r->vertex_step[v];
    for (int h = 0; h <= CFI_RELAX_HALVINGS; ++h, step *= 0.5) {
        double y[3] = {x[0] + step * d[0], x[1] + step * d[1], x[2] + step * d[2]};
        project_to_star(r, v, y);
        ++*trials;
        if (star_energy(r, v, y, NULL, NULL) < energy) {
            memcpy(r->proposal + 3 * v, y, sizeof y);
            r->vertex_step[v] = fmin(1.5 * step, CFI_RELAX_LARGEST_STEP);
            return 1;
        }
    }
    r->vertex_step[v] = fmax(step, CFI_RELAX_SMALLEST_STEP);
    return 0;
}

/* Reference areas and corner cotangents of faces first .. last - 1 into
 * area0 and cot0 (from their starts: last - first and 3 (last - first)),
 * with the operators' own per-face routine: a reference face without area
 * is an error naming it. */
static cf_status reference_triangles(cf_context *ctx, const cf_mesh *mesh, const double *reference, int32_t first,
                                     int32_t last, double *area0, double *cot0)
{
    for (int32_t f = first; f < last; ++f) {
        double twice_area = 0.0;
        cf_status st = cfi_face_cotangents(ctx, mesh, reference, f, 0.0, cot0 + 3 * (f - first), &twice_area);
        if (st != CF_OK) return st;
        if (!isfinite(twice_area))
            return cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "face %d: reference triangle of infinite area", f);
        area0[f - first] = 0.5 * twice_area;
    }
    return CF_OK;
}

/* E(positions) against the triangles of `reference`, each made as
 * reference_triangles makes it, face by face (one pass, no allocation), and
 * the gradient (3 nv, may be NULL). An error names a reference face without
 * area; a face of positions without area gives *energy = +inf. */
static cf_status reference_energy(cf_context *ctx, const cf_mesh *mesh, const double *reference,
                                  const double *positions, double *energy, double *gradient)
{
    if (gradient) memset(gradient, 0, 3 * (size_t)mesh->nv * sizeof(double));
    double sum = 0.0, g[3][3];
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double area0 = 0.0, cot0[3];
        cf_status st = reference_triangles(ctx, mesh, reference, f, f + 1, &area0, cot0);
        if (st != CF_OK) return st;
        const int32_t *t = mesh->triangles + 3 * f;
        const double *const q[3] = {positions + 3 * t[0], positions + 3 * t[1], positions + 3 * t[2]};
        double e = face_mips(q, area0, cot0, NULL, NULL, gradient ? g : NULL);
        if (!isfinite(e)) {
            *energy = INFINITY;
            return CF_OK;
        }
        sum += e;
        if (gradient)
            for (int m = 0; m < 3; ++m)
                for (int j = 0; j < 3; ++j) gradient[3 * t[m] + j] += g[m][j];
    }
    *energy = sum;
    return CF_OK;
}

cf_status cf_mips_energy(cf_context *ctx, const cf_mesh *mesh, const double *reference, const double *positions,
                         double *energy, double *gradient)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!mesh || !positions || !energy) return cfi_error(ctx, CF_ERR_INVALID_ARG, "mips_energy: NULL argument");
    cf_status st = reference_energy(ctx, mesh, reference ? reference : mesh->positions, positions, energy, gradient);
    if (st == CF_OK && !isfinite(*energy))
        return cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "mips_energy: a face of the positions has no area");
    return st;
}

/* The arrays make_arrays makes (each NULL after, so that they can be made
 * again): by destroy, and by make_arrays when one of them failed. */
static void free_arrays(cf_tangential_relaxation *t)
{
    cf_context *ctx = t->ctx;
    size_t nv = (size_t)t->nv, nf = (size_t)t->nf;
    CFI_FREE(ctx, t->area0, nf);
    CFI_FREE(ctx, t->cot0, 3 * nf);
    CFI_FREE(ctx, t->star_area0, nv);
    CFI_FREE(ctx, t->home, nv);
    CFI_FREE(ctx, t->surface, 3 * nv);
    CFI_FREE(ctx, t->surface_normal, 3 * nf);
    CFI_FREE(ctx, t->x, 3 * nv);
    CFI_FREE(ctx, t->proposal, 3 * nv);
    CFI_FREE(ctx, t->proposed, nv);
    CFI_FREE(ctx, t->vertex_step, nv);
}

void cf_tangential_relaxation_destroy(cf_tangential_relaxation **r)
{
    if (!r || !*r) return;
    cf_tangential_relaxation *t = *r;
    cf_context *ctx = t->ctx;
    size_t nv = (size_t)t->nv;
    free_arrays(t);
    CFI_FREE(ctx, t->reference_copy, 3 * nv);
    CFI_FREE(ctx, t->held, nv);
    CFI_FREE(ctx, t, 1);
    *r = NULL;
}

cf_status cf_tangential_relaxation_create(cf_context *ctx, const cf_mesh *mesh, const double *reference,
                                          int32_t hold_boundary, cf_tangential_relaxation **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out || !mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "tangential_relaxation: mesh or out is NULL");
    *out = NULL;
    cf_tangential_relaxation *r = CFI_ALLOC(ctx, cf_tangential_relaxation, 1);
    if (!r) return CF_ERR_NOMEM;
    memset(r, 0, sizeof *r);
    r->ctx = ctx, r->mesh = mesh, r->nv = mesh->nv, r->nf = mesh->nf;
    size_t nv = (size_t)r->nv;
    r->held = CFI_ALLOC(ctx, uint8_t, nv);
    if (reference && reference != mesh->positions) r->reference_copy = CFI_ALLOC(ctx, double, 3 * nv);
    if (!r->held || (reference && reference != mesh->positions && !r->reference_copy)) {
        cf_tangential_relaxation_destroy(&r);
        return cfi_error(ctx, CF_ERR_NOMEM, "tangential_relaxation: out of memory for %d vertices", (int)nv);
    }
    if (r->reference_copy) memcpy(r->reference_copy, reference, 3 * nv * sizeof(double));
    r->reference = r->reference_copy ? r->reference_copy : mesh->positions;
    /* every reference triangle checked now, and their total area */
    for (int32_t f = 0; f < r->nf; ++f) {
        double area0 = 0.0, cot0[3];
        cf_status st = reference_triangles(ctx, mesh, r->reference, f, f + 1, &area0, cot0);
        if (st != CF_OK) {
            cf_tangential_relaxation_destroy(&r);
            return st;
        }
        r->area0_total += area0;
    }
    for (int32_t v = 0; v < r->nv; ++v) r->held[v] = hold_boundary && mesh->vertex_on_boundary[v];
    *out = r;
    return CF_OK;
}

/* The arrays of the descent, at the first apply above the threshold:
 * reference triangles, stars' reference areas, work arrays. */
static cf_status make_arrays(cf_tangential_relaxation *r)
{
    cf_context *ctx = r->ctx;
    const cf_mesh *mesh = r->mesh;
    size_t nv = (size_t)r->nv, nf = (size_t)r->nf;
    r->area0 = CFI_ALLOC(ctx, double, nf);
    r->cot0 = CFI_ALLOC(ctx, double, 3 * nf);
    r->star_area0 = CFI_ALLOC(ctx, double, nv);
    r->home = CFI_ALLOC(ctx, int32_t, nv);
    r->surface = CFI_ALLOC(ctx, double, 3 * nv);
    r->surface_normal = CFI_ALLOC(ctx, double, 3 * nf);
    r->x = CFI_ALLOC(ctx, double, 3 * nv);
    r->proposal = CFI_ALLOC(ctx, double, 3 * nv);
    r->proposed = CFI_ALLOC(ctx, uint8_t, nv);
    r->vertex_step = CFI_ALLOC(ctx, double, nv);
    if (!r->area0 || !r->cot0 || !r->star_area0 || !r->surface || !r->surface_normal || !r->x || !r->vertex_step ||
        !r->home || !r->proposal || !r->proposed) {
        free_arrays(r);
        return cfi_error(ctx, CF_ERR_NOMEM, "tangential_relaxation: out of memory for %d vertices", (int)nv);
    }
    /* checked at create: no error here */
    cf_status st = reference_triangles(ctx, mesh, r->reference, 0, r->nf, r->area0, r->cot0);
    if (st != CF_OK) return st;
    memset(r->star_area0, 0, nv * sizeof(double));
    for (int32_t f = 0; f < r->nf; ++f)
        for (int m = 0; m < 3; ++m) r->star_area0[mesh->triangles[3 * f + m]] += r->area0[f];
    for (size_t v = 0; v < nv; ++v) r->vertex_step[v] = CFI_RELAX_FIRST_STEP;
    return CF_OK;
}

cf_status cf_tangential_relaxation_apply(cf_tangential_relaxation *r, const double *in, int32_t iterations,
                                         double min_mean_q, double *out, cf_tangential_relaxation_report *report)
{
    if (!r) return CF_ERR_INVALID_ARG;
    cf_context *ctx = r->ctx;
    if (!in || !out || iterations < 0 || !(min_mean_q >= 1.0) || !isfinite(min_mean_q))
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "tangential_relaxation: NULL positions, %d iterations or min_mean_q %g (expected >= 1)",
                         iterations, min_mean_q);
    const cf_mesh *mesh = r->mesh;
    size_t n3 = 3 * (size_t)r->nv;
    for (size_t i = 0; i < n3; ++i)
        if (!isfinite(in[i]))
            return cfi_error(ctx, CF_ERR_NUMERICAL, "tangential_relaxation: vertex %d: position is not finite",
                             (int)(i / 3));
    /* below the threshold the map is left as it is: E / sum A0 is the
     * area-weighted mean of (Q + 1 / Q) / 2 (E from the reference itself,
     * the same values as from the arrays, which may not exist yet) */
    double energy = INFINITY;
    cf_status st = reference_energy(ctx, mesh, r->reference, in, &energy, NULL);
    if (st != CF_OK) return st;
    cf_tangential_relaxation_report rep = {0, 0, energy, energy};
    if (out != in) memcpy(out, in, n3 * sizeof(double));
    if (report) *report = rep;
    if (!isfinite(energy))
        return cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "tangential_relaxation: a face of the surface has no area");
    if (iterations == 0 || energy <= 0.5 * (min_mean_q + 1.0 / min_mean_q) * r->area0_total) return CF_OK;
    if (!r->area0 && (st = make_arrays(r)) != CF_OK) return st;
    memcpy(r->surface, in, n3 * sizeof(double));
    for (int32_t f = 0; f < r->nf; ++f) cfi_face_area_vector(mesh, in, f, r->surface_normal + 3 * f);
    for (int32_t v = 0; v < r->nv; ++v) r->home[v] = -1;
    memcpy(r->x, r->surface, n3 * sizeof(double));
    for (int32_t sweep = 0; sweep < iterations; ++sweep) {
        int32_t moved = 0;
        memcpy(r->proposal, r->x, n3 * sizeof(double));
        for (int32_t v = 0; v < r->nv; ++v) moved += r->proposed[v] = !r->held[v] && propose_move(r, v, &rep.trials);
        if (moved == 0) break; /* no vertex lowers its star's energy: at a minimum within the stars */
        /* all moves at once (no vertex order: a symmetric map stays
         * symmetric), halved together while they do not lower E or turn a
         * face; a vertex's move alone lowered its star's energy */
        double next = INFINITY;
        for (int h = 0; h <= CFI_RELAX_HALVINGS; ++h) {
            next = mips_energy(mesh, r->area0, r->cot0, r->proposal, r->surface_normal, NULL, NULL);
            if (next < energy) break;
            for (int32_t v = 0; v < r->nv; ++v) {
                if (!r->proposed[v]) continue;
                double *y = r->proposal + 3 * v;
                const double *x = r->x + 3 * v;
                for (int c = 0; c < 3; ++c) y[c] = 0.5 * (x[c] + y[c]);
                project_to_star(r, v, y);
                r->vertex_step[v] = fmax(0.5 * r->vertex_step[v], CFI_RELAX_SMALLEST_STEP);
            }
        }
        if (!(next < energy)) break;
        double *swap = r->x;
        r->x = r->proposal, r->proposal = swap;
        energy = next;
        rep.iterations = sweep + 1;
    }
    rep.energy_after = energy;
    memcpy(out, r->x, n3 * sizeof(double));
    if (report) *report = rep;
    return CF_OK;
}
