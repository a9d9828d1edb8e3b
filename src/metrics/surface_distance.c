/*
 * Distance from points to a triangle mesh: a bounding-volume hierarchy
 * (axis-aligned boxes, median split of the face centroids along the
 * longest axis, up to 4 faces per leaf) queried nearest-child-first with
 * box-distance pruning, and the exact closest point on a triangle found by
 * locating the point in the triangle's Voronoi regions (vertex, edge,
 * interior) from barycentric dot products.
 */
#include "metrics/metrics_internal.h"

#include <math.h>

#define BVH_LEAF_SIZE 4
#define BVH_STACK 128

typedef struct bvh_node {
    double lo[3], hi[3];
    int32_t left, right;   /* children, -1 for a leaf */
    int32_t start, count;  /* range in the face order (leaves) */
} bvh_node;

typedef struct bvh {
    bvh_node *nodes;
    int32_t node_count, node_capacity;
    int32_t *order;        /* nf face indices */
    double *centroid;      /* 3 nf */
} bvh;

static void face_box(const cf_mesh *mesh, const double *x, int32_t f, double lo[3], double hi[3])
{
    const int32_t *t = mesh->triangles + 3 * f;
    for (int c = 0; c < 3; ++c) {
        lo[c] = fmin(x[3 * t[0] + c], fmin(x[3 * t[1] + c], x[3 * t[2] + c]));
        hi[c] = fmax(x[3 * t[0] + c], fmax(x[3 * t[1] + c], x[3 * t[2] + c]));
    }
}

/* Quickselect: reorders order[lo..hi] so that position k holds the face
 * whose centroid coordinate `axis` would be there in sorted order. */
static void select_kth(int32_t *order, const double *cen, int axis, int32_t lo, int32_t hi, int32_t k)
{
    while (hi > lo) {
        double pivot = cen[3 * order[(lo + hi) / 2] + axis];
        int32_t i = lo, j = hi;
        while (i <= j) {
            while (cen[3 * order[i] + axis] < pivot) ++i;
            while (cen[3 * order[j] + axis] > pivot) --j;
            if (i <= j) {
                int32_t t = order[i];
                order[i] = order[j];
                order[j] = t;
                ++i;
                --j;
            }
        }
        if (k <= j) hi = j;
        else if (k >= i) lo = i;
        else return;
    }
}

static cf_status bvh_build(cf_context *ctx, const cf_mesh *mesh, const double *x, bvh *b)
{
    int32_t nf = mesh->nf;
    b->node_capacity = 2 * nf;
    b->nodes = CFI_ALLOC(ctx, bvh_node, b->node_capacity);
    b->order = CFI_ALLOC(ctx, int32_t, nf);
    b->centroid = CFI_ALLOC(ctx, double, 3 * (int64_t)nf);
    if (!b->nodes || !b->order || !b->centroid) return CF_ERR_NOMEM;
    for (int32_t f = 0; f < nf; ++f) {
        b->order[f] = f;
        const int32_t *t = mesh->triangles + 3 * f;
        for (int c = 0; c < 3; ++c) b->centroid[3 * f + c] = (x[3 * t[0] + c] + x[3 * t[1] + c] + x[3 * t[2] + c]) / 3.0;
    }
    int32_t stack[BVH_STACK], top = 0;
    b->node_count = 1;
    b->nodes[0].start = 0;
    b->nodes[0].count = nf;
    stack[top++] = 0;
    while (top > 0) {
        int32_t id = stack[--top];
        bvh_node *nd = &b->nodes[id];
        double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int c = 0; c < 3; ++c) {
            nd->lo[c] = INFINITY;
            nd->hi[c] = -INFINITY;
        }
        for (int32_t i = nd->start; i < nd->start + nd->count; ++i) {
            double lo[3], hi[3];
            int32_t f = b->order[i];
            face_box(mesh, x, f, lo, hi);
            for (int c = 0; c < 3; ++c) {
                nd->lo[c] = fmin(nd->lo[c], lo[c]);
                nd->hi[c] = fmax(nd->hi[c], hi[c]);
                clo[c] = fmin(clo[c], b->centroid[3 * f + c]);
                chi[c] = fmax(chi[c], b->centroid[3 * f + c]);
            }
        }
        nd->left = nd->right = -1;
        if (nd->count <= BVH_LEAF_SIZE || top + 2 > BVH_STACK || b->node_count + 2 > b->node_capacity) continue;
        int axis = 0;
        for (int c = 1; c < 3; ++c)
            if (chi[c] - clo[c] > chi[axis] - clo[axis]) axis = c;
        int32_t half = nd->count / 2, start = nd->start, count = nd->count;
        select_kth(b->order, b->centroid, axis, start, start + count - 1, start + half);
        int32_t l = b->node_count++, r = b->node_count++;
        nd = &b->nodes[id];
        nd->left = l;
        nd->right = r;
        b->nodes[l].start = start;
        b->nodes[l].count = half;
        b->nodes[r].start = start + half;
        b->nodes[r].count = count - half;
        stack[top++] = l;
        stack[top++] = r;
    }
    return CF_OK;
}

static void bvh_free(cf_context *ctx, bvh *b, int32_t nf)
{
    CFI_FREE(ctx, b->nodes, b->node_capacity);
    CFI_FREE(ctx, b->order, nf);
    CFI_FREE(ctx, b->centroid, 3 * (int64_t)nf);
}

static double box_dist2(const bvh_node *nd, const double p[3])
{
    double d2 = 0.0;
    for (int c = 0; c < 3; ++c) {
        double d = p[c] < nd->lo[c] ? nd->lo[c] - p[c] : (p[c] > nd->hi[c] ? p[c] - nd->hi[c] : 0.0);
        d2 += d * d;
    }
    return d2;
}

static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Squared distance from p to triangle (a, b, c). */
static double point_triangle_dist2(const double p[3], const double a[3], const double b[3], const double c[3])
{
    double q[3];
    cfi_nearest_point_on_triangle(p, a, b, c, q);
    double d[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
    return dot3(d, d);
}

static double bvh_nearest2(const bvh *b, const cf_mesh *mesh, const double *x, const double p[3])
{
    double best = INFINITY;
    int32_t stack[BVH_STACK], top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const bvh_node *nd = &b->nodes[stack[--top]];
        if (box_dist2(nd, p) >= best) continue;
        if (nd->left < 0) {
            for (int32_t i = nd->start; i < nd->start + nd->count; ++i) {
                const int32_t *t = mesh->triangles + 3 * b->order[i];
                double d2 = point_triangle_dist2(p, x + 3 * t[0], x + 3 * t[1], x + 3 * t[2]);
                if (d2 < best) best = d2;
            }
            continue;
        }
        double dl = box_dist2(&b->nodes[nd->left], p), dr = box_dist2(&b->nodes[nd->right], p);
        /* push the farther child first so the nearer one is searched first */
        if (dl < dr) {
            if (dr < best) stack[top++] = nd->right;
            if (dl < best) stack[top++] = nd->left;
        } else {
            if (dl < best) stack[top++] = nd->left;
            if (dr < best) stack[top++] = nd->right;
        }
    }
    return best;
}

cf_status cf_point_to_surface_distance(cf_context *ctx, int32_t n, const double *points, const cf_mesh *mesh,
                                       const double *positions, double *dist, double *max_dist, double *rms_dist,
                                       int32_t *argmax)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!mesh || !positions || (n > 0 && !points))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "point_to_surface_distance: NULL argument");
    if (n < 0) return cfi_error(ctx, CF_ERR_INVALID_ARG, "point_to_surface_distance: negative count %d", n);
    for (int64_t i = 0; i < 3 * (int64_t)mesh->nv; ++i)
        if (!isfinite(positions[i]))
            return cfi_error(ctx, CF_ERR_NONFINITE, "point_to_surface_distance: vertex %d is not finite", (int)(i / 3));
    for (int64_t i = 0; i < 3 * (int64_t)n; ++i)
        if (!isfinite(points[i]))
            return cfi_error(ctx, CF_ERR_NONFINITE, "point_to_surface_distance: point %d is not finite", (int)(i / 3));
    bvh b = {0};
    cf_status s = bvh_build(ctx, mesh, positions, &b);
    if (s == CF_OK) {
        double dmax = 0.0, sum = 0.0;
        int32_t imax = -1;
        for (int32_t i = 0; i < n; ++i) {
            double d = sqrt(bvh_nearest2(&b, mesh, positions, points + 3 * (size_t)i));
            if (dist) dist[i] = d;
            if (d > dmax || imax < 0) {
                dmax = d;
                imax = i;
            }
            sum += d * d;
        }
        if (max_dist) *max_dist = dmax;
        if (rms_dist) *rms_dist = n > 0 ? sqrt(sum / n) : 0.0;
        if (argmax) *argmax = imax;
    }
    bvh_free(ctx, &b, mesh->nf);
    return s;
}

cf_status cf_aligned_surface_distance(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                      int with_scale, double *max_dist, double *rms_dist, double *scale)
{
    cf_status s = cfi_metrics_check_pair(ctx, mesh, a, b, "aligned_surface_distance");
    if (s != CF_OK) return s;
    double r[9], sc, t[3];
    s = cf_similarity_align(ctx, mesh->nv, a, b, NULL, with_scale, r, &sc, t, NULL);
    if (s != CF_OK) return s;
    double *aligned = CFI_ALLOC(ctx, double, 3 * (int64_t)mesh->nv);
    if (!aligned) return CF_ERR_NOMEM;
    cf_similarity_apply(mesh->nv, r, sc, t, a, aligned);
    s = cf_point_to_surface_distance(ctx, mesh->nv, aligned, mesh, b, NULL, max_dist, rms_dist, NULL);
    CFI_FREE(ctx, aligned, 3 * (int64_t)mesh->nv);
    if (s == CF_OK && scale) *scale = sc;
    return s;
}
