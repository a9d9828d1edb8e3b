/*
 * cf_mesh: validation of a flat triangle list and the connectivity tables
 * built once from it (edges, halfedge twins, edge faces, vertex rings,
 * vertex-face incidence, boundary loops, components, Euler characteristic,
 * genus).
 *
 * Everything is O(V + F) for bounded valence: halfedges are grouped by
 * their undirected vertex pair with a counting sort by the smaller vertex
 * and an insertion sort by the larger one inside each (small) bucket, so
 * edges come out in lexicographic (i, j) order and no per-edge allocation
 * is needed. The same pass serves cf_mesh_create (stop at the
 * first defect) and cf_mesh_validate (count all defects).
 */
#include "mesh/mesh_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Defect recording: strict mode stops at the first defect, report mode
 * counts them all and keeps the first message. */

typedef struct checker {
    cf_context *ctx;
    cf_mesh_report *report; /* NULL in strict mode */
    cf_status first;
    char message[256];
} checker;

CF_PRINTF(4, 5)
static bool defect(checker *c, int32_t *counter, cf_status status, const char *fmt, ...)
{
    if (c->first == CF_OK) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(c->message, sizeof c->message, fmt, ap);
        va_end(ap);
        c->first = status;
    }
    if (counter && *counter < INT32_MAX) ++*counter;
    return c->report == NULL; /* stop in strict mode */
}

static const char *nonfinite_word(double x) { return isnan(x) ? "NaN" : "infinite"; }

/* ------------------------------------------------------------------------ */
/* Halfedge grouping */

/* Scratch shared by the checks and the build. */
typedef struct scratch {
    int32_t nv, nf;
    uint8_t *face_ok;     /* nf: face passed index checks (report mode skips bad ones) */
    int32_t *order;       /* nh_ok: halfedges sorted by (min, max) vertex, then index */
    int32_t nh_ok;        /* halfedges taking part */
    int32_t *tmp;         /* 3 nf */
    int32_t *count;       /* nv + 1 */
    int32_t *uf;          /* 3 nf: union-find over corners */
    int32_t *gnext;       /* 3 nf: end of the key group starting at a position */
} scratch;

static void scratch_free(cf_context *ctx, scratch *s)
{
    size_t nh = (size_t)s->nf * 3;
    CFI_FREE(ctx, s->face_ok, s->nf);
    CFI_FREE(ctx, s->order, nh);
    CFI_FREE(ctx, s->tmp, nh);
    CFI_FREE(ctx, s->count, (size_t)s->nv + 1);
    CFI_FREE(ctx, s->uf, nh);
    CFI_FREE(ctx, s->gnext, nh);
}

static cf_status scratch_alloc(cf_context *ctx, scratch *s, int32_t nv, int32_t nf)
{
    memset(s, 0, sizeof *s);
    s->nv = nv;
    s->nf = nf;
    size_t nh = (size_t)nf * 3;
    s->face_ok = CFI_ALLOC(ctx, uint8_t, nf);
    s->order = CFI_ALLOC(ctx, int32_t, nh);
    s->tmp = CFI_ALLOC(ctx, int32_t, nh);
    s->count = CFI_ALLOC(ctx, int32_t, (size_t)nv + 1);
    s->uf = CFI_ALLOC(ctx, int32_t, nh);
    s->gnext = CFI_ALLOC(ctx, int32_t, nh);
    if (!s->face_ok || !s->order || !s->tmp || !s->count || !s->uf || !s->gnext) {
        scratch_free(ctx, s);
        return CF_ERR_NOMEM;
    }
    return CF_OK;
}

static inline int32_t he_lo(const int32_t *tri, int32_t h)
{
    int32_t a = tri[h], b = tri[cfi_he_next(h)];
    return a < b ? a : b;
}
static inline int32_t he_hi(const int32_t *tri, int32_t h)
{
    int32_t a = tri[h], b = tri[cfi_he_next(h)];
    return a < b ? b : a;
}

static inline bool pair_less(const int32_t *key, const int32_t *val, int32_t a, int32_t b)
{
    return key[a] < key[b] || (key[a] == key[b] && val[a] < val[b]);
}

static void sift_down(int32_t *key, int32_t *val, int32_t root, int32_t n)
{
    for (;;) {
        int32_t child = 2 * root + 1;
        if (child >= n) return;
        if (child + 1 < n && pair_less(key, val, child, child + 1)) ++child;
        if (!pair_less(key, val, root, child)) return;
        int32_t tk = key[root], tv = val[root];
        key[root] = key[child], val[root] = val[child];
        key[child] = tk, val[child] = tv;
        root = child;
    }
}

/* Heap sort of n (key, val) pairs by key then val: O(n log n) for the rare
 * vertex with a very large valence, where insertion sort would be O(n^2). */
static void heap_sort_pairs(int32_t *key, int32_t *val, int32_t n)
{
    for (int32_t i = n / 2 - 1; i >= 0; --i) sift_down(key, val, i, n);
    for (int32_t end = n - 1; end > 0; --end) {
        int32_t tk = key[0], tv = val[0];
        key[0] = key[end], val[0] = val[end];
        key[end] = tk, val[end] = tv;
        sift_down(key, val, 0, end);
    }
}

/* Sorts the halfedges of the faces taking part by (smaller vertex, larger
 * vertex, halfedge index): one counting sort by the smaller vertex (reads
 * tri sequentially), then an insertion sort by the larger vertex inside each
 * bucket (buckets hold ~3 halfedges on average). Then records, for each
 * group of equal keys starting at position i, its end in gnext[i]. */
static void sort_halfedges(const int32_t *tri, scratch *s)
{
    const int32_t nv = s->nv;
    int32_t *count = s->count, *hi = s->tmp;
    memset(count, 0, ((size_t)nv + 1) * sizeof *count);
    int32_t n = 0;
    for (int32_t f = 0; f < s->nf; ++f)
        if (s->face_ok[f])
            for (int32_t k = 0; k < 3; ++k) {
                ++count[he_lo(tri, 3 * f + k) + 1];
                ++n;
            }
    s->nh_ok = n;
    for (int32_t v = 0; v < nv; ++v) count[v + 1] += count[v];
    for (int32_t f = 0; f < s->nf; ++f)
        if (s->face_ok[f])
            for (int32_t k = 0; k < 3; ++k) {
                int32_t h = 3 * f + k, pos = count[he_lo(tri, h)]++;
                s->order[pos] = h;
                hi[pos] = he_hi(tri, h);
            }
    /* count[v] is now the end of bucket v (= start of bucket v + 1) */
    int32_t start = 0;
    for (int32_t v = 0; v < nv; ++v) {
        const int32_t end = count[v];
        if (end - start > 32) heap_sort_pairs(hi + start, s->order + start, end - start); /* high valence */
        for (int32_t i = start + 1; i < end; ++i) { /* stable insertion sort by hi */
            int32_t h = s->order[i], key = hi[i], j = i - 1;
            while (j >= start && hi[j] > key) {
                s->order[j + 1] = s->order[j];
                hi[j + 1] = hi[j];
                --j;
            }
            s->order[j + 1] = h;
            hi[j + 1] = key;
        }
        for (int32_t i = start; i < end;) {
            int32_t j = i + 1;
            while (j < end && hi[j] == hi[i]) ++j;
            s->gnext[i] = j;
            i = j;
        }
        start = end;
    }
}

/* End of the group of equal keys starting at position i of order. */
static inline int32_t group_end(const int32_t *tri, const scratch *s, int32_t i)
{
    (void)tri;
    return s->gnext[i];
}

static int32_t uf_find(int32_t *uf, int32_t x)
{
    while (uf[x] != x) {
        uf[x] = uf[uf[x]];
        x = uf[x];
    }
    return x;
}

static void uf_union(int32_t *uf, int32_t a, int32_t b)
{
    a = uf_find(uf, a);
    b = uf_find(uf, b);
    if (a == b) return;
    /* the smaller index becomes the root: keeps results deterministic */
    if (a < b) uf[b] = a;
    else uf[a] = b;
}

/* ------------------------------------------------------------------------ */
/* Validation in the documented order. Returns CF_OK when the caller may go
 * on; in strict mode the first defect is returned as an error status. */

static cf_status check_arguments(cf_context *ctx, const cf_mesh_desc *d)
{
    if (!d) return cfi_error(ctx, CF_ERR_INVALID_ARG, "mesh description is NULL");
    if (d->vertex_count < 0 || d->face_count < 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "negative counts (%d vertices, %d faces)", d->vertex_count,
                         d->face_count);
    if (d->face_count > INT32_MAX / 12 || d->vertex_count > INT32_MAX / 4)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "mesh too large (%d vertices, %d faces)", d->vertex_count,
                         d->face_count);
    if (d->vertex_count > 0 && !d->positions) return cfi_error(ctx, CF_ERR_INVALID_ARG, "positions are NULL");
    if (d->face_count > 0 && !d->triangles) return cfi_error(ctx, CF_ERR_INVALID_ARG, "triangles are NULL");
    if (d->uv) {
        if (d->uv_count <= 0) return cfi_error(ctx, CF_ERR_INVALID_ARG, "uv given with uv_count %d", d->uv_count);
        if (!d->uv_triangles && d->uv_count != d->vertex_count)
            return cfi_error(ctx, CF_ERR_INVALID_ARG,
                             "per-vertex uv needs uv_count == vertex_count (%d != %d)", d->uv_count,
                             d->vertex_count);
    } else if (d->uv_triangles || d->uv_count != 0) {
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "uv_count or uv_triangles given without uv");
    }
    return CF_OK;
}

/* Largest |component| of the face's edge vectors (no squares: no underflow). */
static double face_longest_component(const double *p, const int32_t *t)
{
    double m = 0.0;
    for (int e = 0; e < 3; ++e) {
        const double *a = p + 3 * (size_t)t[e], *b = p + 3 * (size_t)t[(e + 1) % 3];
        for (int k = 0; k < 3; ++k) m = fmax(m, fabs(b[k] - a[k]));
    }
    return m;
}

/* Steps 1-2: vertex indices in range, no index repeated in a face (sets s->face_ok). Returns 1 when checking must stop (first defect, no report). */
static int check_indices(checker *c, const cf_mesh_desc *d, scratch *s, cf_mesh_report *r)
{
    const int32_t nv = d->vertex_count;
    const int32_t nf = d->face_count;
    const int32_t *tri = d->triangles;
    /* 1. indices in range */
    for (int32_t f = 0; f < nf; ++f) {
        s->face_ok[f] = 1;
        for (int k = 0; k < 3; ++k) {
            int32_t v = tri[3 * (size_t)f + k];
            if (v < 0 || v >= nv) {
                s->face_ok[f] = 0;
                if (defect(c, &r->index_out_of_range, CF_ERR_INDEX_RANGE,
                           "face %d: vertex index %d out of range [0, %d)", f, v, nv))
                    return 1;
                break;
            }
        }
    }
    /* 2. repeated index */
    for (int32_t f = 0; f < nf; ++f) {
        if (!s->face_ok[f]) continue;
        const int32_t *t = tri + 3 * (size_t)f;
        int32_t rep = t[0] == t[1] || t[0] == t[2] ? t[0] : (t[1] == t[2] ? t[1] : -1);
        if (rep >= 0) {
            s->face_ok[f] = 0;
            if (defect(c, &r->repeated_index, CF_ERR_REPEATED_INDEX, "face %d: vertex %d repeated", f, rep))
                return 1;
        }
    }
    return 0;
}

/* Step 3: finite coordinates within CF_MAX_COORDINATE. Returns 1 when checking must stop (first defect, no report). */
static int check_coordinates(checker *c, const cf_mesh_desc *d, scratch *s, cf_mesh_report *r)
{
    const int32_t nv = d->vertex_count;
    const double *p = d->positions;
    /* 3. non-finite coordinates */
    static const char axis[3] = {'x', 'y', 'z'};
    for (int32_t v = 0; v < nv; ++v)
        for (int k = 0; k < 3; ++k) {
            double x = p[3 * (size_t)v + k];
            if (!isfinite(x)) {
                if (defect(c, &r->nonfinite_coordinates, CF_ERR_NONFINITE, "vertex %d: coordinate %c is %s", v,
                           axis[k], nonfinite_word(x)))
                    return 1;
                break;
            }
            if (fabs(x) > CF_MAX_COORDINATE) {
                /* finite, but cubes of lengths (volumes) and squares of areas
                 * would overflow: every later result would be Inf or NaN */
                if (defect(c, &r->nonfinite_coordinates, CF_ERR_NONFINITE,
                           "vertex %d: coordinate %c = %.3g is out of range (|x| > %.0e, volumes would overflow); "
                           "rescale the mesh",
                           v, axis[k], x, CF_MAX_COORDINATE))
                    return 1;
                break;
            }
        }
    return 0;
}

/* Step 3b: texture coordinate indices and values. Returns 1 when checking must stop (first defect, no report). */
static int check_uv(checker *c, const cf_mesh_desc *d, scratch *s, cf_mesh_report *r)
{
    const int32_t nf = d->face_count;
    /* 3b. texture coordinates */
    if (d->uv) {
        if (d->uv_triangles)
            for (int32_t f = 0; f < nf; ++f)
                for (int k = 0; k < 3; ++k) {
                    int32_t t = d->uv_triangles[3 * (size_t)f + k];
                    if (t < 0 || t >= d->uv_count) {
                        if (defect(c, &r->index_out_of_range, CF_ERR_INDEX_RANGE,
                                   "face %d: uv index %d out of range [0, %d)", f, t, d->uv_count))
                            return 1;
                        break;
                    }
                }
        for (int32_t i = 0; i < d->uv_count; ++i)
            for (int k = 0; k < 2; ++k) {
                double x = d->uv[2 * (size_t)i + k];
                if (!isfinite(x)) {
                    if (defect(c, &r->nonfinite_coordinates, CF_ERR_NONFINITE, "uv %d: coordinate %c is %s", i,
                               k ? 'v' : 'u', nonfinite_word(x)))
                        return 1;
                    break;
                }
            }
    }
    return 0;
}

/* Step 4: no zero-area face (scale-free test), edges measurable. Returns 1 when checking must stop (first defect, no report). */
static int check_areas(checker *c, const cf_mesh_desc *d, scratch *s, cf_mesh_report *r)
{
    const int32_t nf = d->face_count;
    const int32_t *tri = d->triangles;
    const double *p = d->positions;
    /* 4. zero-area faces: area <= CFI_ZERO_AREA_RATIO * (longest edge)^2 (scale-free) */
    for (int32_t f = 0; f < nf; ++f) {
        if (s->face_ok && !s->face_ok[f]) continue;
        double l2;
        const int32_t *t = tri + 3 * (size_t)f;
        double area = cfi_triangle_area(p + 3 * (size_t)t[0], p + 3 * (size_t)t[1], p + 3 * (size_t)t[2], &l2);
        if (!isfinite(area) || !isfinite(l2)) continue; /* already reported as non-finite or out of range */
        double longest = face_longest_component(p, tri + 3 * (size_t)f);
        if (longest > 0.0 && longest < CF_MIN_EDGE_LENGTH) {
            /* squared lengths underflow: the face is not degenerate, only too small to measure */
            if (defect(c, &r->degenerate_faces, CF_ERR_DEGENERATE_FACE,
                       "face %d: its edges are shorter than %.0e (longest component %.3g), below the range of "
                       "lengths this library computes with; rescale the mesh",
                       f, CF_MIN_EDGE_LENGTH, longest))
                return 1;
            continue;
        }
        if (area <= CFI_ZERO_AREA_RATIO * l2) {
            if (defect(c, &r->degenerate_faces, CF_ERR_DEGENERATE_FACE, "face %d: zero area", f)) return 1;
        }
    }
    return 0;
}

/* Step 4b (halfedges sorted): no two faces on the same three vertices. Returns 1 when checking must stop (first defect, no report). */
static int check_duplicate_faces(checker *c, const cf_mesh_desc *d, scratch *s, cf_mesh_report *r)
{
    const int32_t *tri = d->triangles;
    /* 4b. duplicated faces: two faces on the same three vertices (any
     * rotation, either orientation). Checked before the edges because a
     * duplicate otherwise shows as a non-manifold edge or an orientation
     * conflict (or, two opposite faces alone, as a valid closed surface),
     * none of which names the actual mistake. Two such faces share the edge
     * of their two smallest vertices: within that edge's halfedge group,
     * sort the faces by their third vertex. Reports the pair with the lowest
     * face indices. */
    {
        int32_t bf1 = -1, bf2 = -1;
        int32_t *key = s->tmp, *val = s->uf; /* free until step 6 */
        for (int32_t i = 0; i < s->nh_ok;) {
            int32_t j = group_end(tri, s, i), m = 0;
            for (int32_t k = i; j - i > 1 && k < j; ++k) {
                int32_t h = s->order[k], third = tri[cfi_he_prev(h)];
                if (third < he_hi(tri, h)) continue; /* (lo, hi) is not this face's smallest pair */
                key[m] = third;
                val[m++] = cfi_he_face(h);
            }
            if (m > 1) heap_sort_pairs(key, val, m);
            for (int32_t k = 1; k < m; ++k) {
                if (key[k] != key[k - 1]) continue;
                int32_t first = k - 1;
                while (first > 0 && key[first - 1] == key[k]) --first;
                if (bf1 < 0 || val[first] < bf1 || (val[first] == bf1 && val[k] < bf2)) {
                    bf1 = val[first];
                    bf2 = val[k];
                }
            }
            i = j;
        }
        if (bf1 >= 0) {
            const int32_t *a = tri + 3 * (size_t)bf1, *b = tri + 3 * (size_t)bf2;
            bool same = false;
            for (int q = 0; q < 3; ++q) same |= a[0] == b[q] && a[1] == b[(q + 1) % 3];
            int32_t lo = a[0] < a[1] ? (a[0] < a[2] ? a[0] : a[2]) : (a[1] < a[2] ? a[1] : a[2]);
            int32_t hi = a[0] > a[1] ? (a[0] > a[2] ? a[0] : a[2]) : (a[1] > a[2] ? a[1] : a[2]);
            int32_t mid = a[0] + a[1] + a[2] - lo - hi;
            int32_t count = 0;
            defect(c, &count, CF_ERR_BAD_MESH, "faces %d and %d are the same triangle (vertices %d, %d, %d; %s orientation)",
                   bf1, bf2, lo, mid, hi, same ? "same" : "opposite");
            if (!c->report) return 1;
        }
    }
    return 0;
}

/* Step 5: no edge with more than two faces. Returns 1 when checking must stop (first defect, no report). */
static int check_nonmanifold_edges(checker *c, const cf_mesh_desc *d, scratch *s, cf_mesh_report *r)
{
    const int32_t *tri = d->triangles;
    /* 5. edges with more than two faces; report the face that first makes
     * an edge exceed two (the third-lowest face index of its group). */
    {
        int32_t best_face = -1, best_i = 0, best_n = 0;
        for (int32_t i = 0; i < s->nh_ok;) {
            int32_t j = group_end(tri, s, i);
            if (j - i > 2) {
                if (r) ++r->nonmanifold_edges;
                int32_t f3 = cfi_he_face(s->order[i + 2]);
                if (best_face < 0 || f3 < best_face) {
                    best_face = f3;
                    best_i = i;
                    best_n = j - i;
                }
            }
            i = j;
        }
        if (best_face >= 0) {
            int32_t h = s->order[best_i];
            int32_t count = 0;
            defect(c, &count, CF_ERR_NONMANIFOLD_EDGE, "face %d: edge (%d, %d) is shared by %d faces", best_face,
                   he_lo(tri, h), he_hi(tri, h), best_n);
            if (!c->report) return 1;
        }
    }
    return 0;
}

/* Step 6: the faces around each vertex form one fan. Returns 1 when checking must stop (first defect, no report). */
static int check_nonmanifold_vertices(checker *c, const cf_mesh_desc *d, scratch *s, cf_mesh_report *r)
{
    const int32_t nv = d->vertex_count;
    const int32_t nf = d->face_count;
    const int32_t *tri = d->triangles;
    /* 6. non-manifold vertices: corners around a vertex joined across
     * two-face edges (ignoring direction) must form a single fan. */
    for (int32_t h = 0; h < 3 * nf; ++h) s->uf[h] = h;
    for (int32_t i = 0; i < s->nh_ok;) {
        int32_t j = group_end(tri, s, i);
        if (j - i == 2) {
            int32_t h1 = s->order[i], h2 = s->order[i + 1];
            if (tri[h1] == tri[h2]) { /* same direction */
                uf_union(s->uf, h1, h2);
                uf_union(s->uf, cfi_he_next(h1), cfi_he_next(h2));
            } else {
                uf_union(s->uf, h1, cfi_he_next(h2));
                uf_union(s->uf, cfi_he_next(h1), h2);
            }
        }
        i = j;
    }
    {
        /* fans per vertex = number of root corners at that vertex */
        int32_t *fans = s->count; /* nv + 1, free now */
        memset(fans, 0, ((size_t)nv + 1) * sizeof *fans);
        for (int32_t h = 0; h < 3 * nf; ++h)
            if (s->face_ok[cfi_he_face(h)] && uf_find(s->uf, h) == h) ++fans[tri[h]];
        for (int32_t v = 0; v < nv; ++v)
            if (fans[v] > 1) {
                if (defect(c, &r->nonmanifold_vertices, CF_ERR_NONMANIFOLD_VERTEX,
                           "vertex %d: its faces form %d separate fans", v, fans[v]))
                    return 1;
            }
    }
    return 0;
}

/* Step 7: consistent orientation across every two-face edge. Returns 1 when checking must stop (first defect, no report). */
static int check_orientation(checker *c, const cf_mesh_desc *d, scratch *s, cf_mesh_report *r)
{
    const int32_t *tri = d->triangles;
    /* 7. orientation: the two faces of an edge traverse it in opposite
     * directions. Report the pair with the lowest face index. */
    {
        int32_t bf1 = -1, bf2 = -1, bh = -1;
        for (int32_t i = 0; i < s->nh_ok;) {
            int32_t j = group_end(tri, s, i);
            if (j - i == 2 && tri[s->order[i]] == tri[s->order[i + 1]]) {
                int32_t f1 = cfi_he_face(s->order[i]), f2 = cfi_he_face(s->order[i + 1]);
                if (r) ++r->inconsistent_orientation_edges;
                if (bf1 < 0 || f1 < bf1 || (f1 == bf1 && f2 < bf2)) {
                    bf1 = f1;
                    bf2 = f2;
                    bh = s->order[i];
                }
            }
            i = j;
        }
        if (bf1 >= 0) {
            int32_t count = 0;
            defect(c, &count, CF_ERR_ORIENTATION,
                   "faces %d and %d: edge (%d, %d) is traversed in the same direction by both", bf1, bf2,
                   tri[bh], tri[cfi_he_next(bh)]);
            if (!c->report) return 1;
        }
    }
    return 0;
}

/* Step 8: every vertex is used by a face. Returns 1 when checking must stop (first defect, no report). */
static int check_unreferenced(checker *c, const cf_mesh_desc *d, scratch *s, cf_mesh_report *r)
{
    const int32_t nv = d->vertex_count;
    const int32_t nf = d->face_count;
    const int32_t *tri = d->triangles;
    /* 8. unreferenced vertices */
    {
        int32_t *used = s->count;
        memset(used, 0, ((size_t)nv + 1) * sizeof *used);
        for (int32_t f = 0; f < nf; ++f)
            if (s->face_ok[f])
                for (int k = 0; k < 3; ++k) used[tri[3 * (size_t)f + k]] = 1;
        for (int32_t v = 0; v < nv; ++v)
            if (!used[v]) {
                if (defect(c, &r->unreferenced_vertices, CF_ERR_BAD_MESH, "vertex %d is not used by any face", v))
                    return 1;
            }
    }
    return 0;
}

/* Runs every check; fills s (sorted halfedges, face_ok). */
static cf_status run_checks(checker *c, const cf_mesh_desc *d, scratch *s)
{
    cf_mesh_report dummy;
    cf_mesh_report *r = c->report ? c->report : &dummy;
    memset(&dummy, 0, sizeof dummy);
    const int32_t nv = d->vertex_count, nf = d->face_count;

    if (nv == 0 || nf == 0) {
        defect(c, NULL, CF_ERR_BAD_MESH, "empty mesh (%d vertices, %d faces)", nv, nf);
        return c->first;
    }
    if (check_indices(c, d, s, r) || check_coordinates(c, d, s, r) || (d->uv && check_uv(c, d, s, r)) ||
        check_areas(c, d, s, r))
        return c->first;
    sort_halfedges(d->triangles, s);
    if (check_duplicate_faces(c, d, s, r) || check_nonmanifold_edges(c, d, s, r) ||
        check_nonmanifold_vertices(c, d, s, r) || check_orientation(c, d, s, r) || check_unreferenced(c, d, s, r))
        return c->first;
    return c->report ? CF_OK : c->first;
}

/* ------------------------------------------------------------------------ */
/* Building the tables of a valid mesh */

void cf_mesh_destroy(cf_mesh **mesh)
{
    if (!mesh || !*mesh) return;
    cf_mesh *m = *mesh;
    cf_context *ctx = m->ctx;
    size_t nv = (size_t)m->nv, nf = (size_t)m->nf, ne = (size_t)m->ne;
    CFI_FREE(ctx, m->positions, 3 * nv);
    CFI_FREE(ctx, m->triangles, 3 * nf);
    CFI_FREE(ctx, m->edge_vertices, 2 * ne);
    CFI_FREE(ctx, m->halfedge_edge, 3 * nf);
    CFI_FREE(ctx, m->halfedge_twin, 3 * nf);
    CFI_FREE(ctx, m->edge_faces, 2 * ne);
    CFI_FREE(ctx, m->edge_halfedge, ne);
    CFI_FREE(ctx, m->vertex_on_boundary, nv);
    CFI_FREE(ctx, m->vertex_component, nv);
    CFI_FREE(ctx, m->face_component, nf);
    CFI_FREE(ctx, m->ring_offsets, nv + 1);
    CFI_FREE(ctx, m->ring_neighbors, 2 * ne);
    CFI_FREE(ctx, m->ring_edges, 2 * ne);
    CFI_FREE(ctx, m->vface_offsets, nv + 1);
    CFI_FREE(ctx, m->vface_faces, 3 * nf);
    CFI_FREE(ctx, m->boundary_loop_offsets, (size_t)m->boundary_loop_count + 1);
    CFI_FREE(ctx, m->boundary_loop_vertices, (size_t)m->boundary_vertex_count);
    CFI_FREE(ctx, m->uv, 2 * (size_t)m->uv_count);
    if (m->uv_triangles) CFI_FREE(ctx, m->uv_triangles, 3 * nf);
    cfi_free(ctx, m, sizeof *m);
    *mesh = NULL;
}

static cf_status build_edges(cf_mesh *m, const scratch *s)
{
    cf_context *ctx = m->ctx;
    const int32_t *tri = m->triangles;
    int32_t ne = 0;
    for (int32_t i = 0; i < s->nh_ok; i = group_end(tri, s, i)) ++ne;
    m->ne = ne;
    m->edge_vertices = CFI_ALLOC(ctx, int32_t, 2 * (size_t)ne);
    m->halfedge_edge = CFI_ALLOC(ctx, int32_t, 3 * (size_t)m->nf);
    m->halfedge_twin = CFI_ALLOC(ctx, int32_t, 3 * (size_t)m->nf);
    m->edge_faces = CFI_ALLOC(ctx, int32_t, 2 * (size_t)ne);
    m->edge_halfedge = CFI_ALLOC(ctx, int32_t, ne);
    m->vertex_on_boundary = CFI_ALLOC(ctx, uint8_t, m->nv);
    if (!m->edge_vertices || !m->halfedge_edge || !m->halfedge_twin || !m->edge_faces || !m->edge_halfedge ||
        !m->vertex_on_boundary)
        return CF_ERR_NOMEM;
    int32_t e = 0;
    for (int32_t i = 0; i < s->nh_ok; ++e) {
        int32_t j = group_end(tri, s, i);
        int32_t h1 = s->order[i], h2 = j - i == 2 ? s->order[i + 1] : -1;
        int32_t lo = he_lo(tri, h1), hi = he_hi(tri, h1);
        m->edge_vertices[2 * e] = lo;
        m->edge_vertices[2 * e + 1] = hi;
        m->edge_faces[2 * e] = -1;
        m->edge_faces[2 * e + 1] = -1;
        m->edge_halfedge[e] = h1;
        m->halfedge_edge[h1] = e;
        m->halfedge_twin[h1] = h2;
        m->edge_faces[2 * e + (tri[h1] == lo ? 0 : 1)] = cfi_he_face(h1);
        if (h2 >= 0) {
            m->halfedge_edge[h2] = e;
            m->halfedge_twin[h2] = h1;
            m->edge_faces[2 * e + (tri[h2] == lo ? 0 : 1)] = cfi_he_face(h2);
        } else {
            m->vertex_on_boundary[lo] = 1;
            m->vertex_on_boundary[hi] = 1;
        }
        i = j;
    }
    return CF_OK;
}

static cf_status build_incidence(cf_mesh *m)
{
    cf_context *ctx = m->ctx;
    const int32_t nv = m->nv, nf = m->nf, ne = m->ne;
    m->ring_offsets = CFI_ALLOC(ctx, int32_t, (size_t)nv + 1);
    m->ring_neighbors = CFI_ALLOC(ctx, int32_t, 2 * (size_t)ne);
    m->ring_edges = CFI_ALLOC(ctx, int32_t, 2 * (size_t)ne);
    m->vface_offsets = CFI_ALLOC(ctx, int32_t, (size_t)nv + 1);
    m->vface_faces = CFI_ALLOC(ctx, int32_t, 3 * (size_t)nf);
    if (!m->ring_offsets || !m->ring_neighbors || !m->ring_edges || !m->vface_offsets || !m->vface_faces)
        return CF_ERR_NOMEM;
    /* Rings: edges are sorted by (i, j), so filling in edge order lists each
     * vertex's neighbours in increasing order. */
    for (int32_t e = 0; e < ne; ++e) {
        ++m->ring_offsets[m->edge_vertices[2 * e] + 1];
        ++m->ring_offsets[m->edge_vertices[2 * e + 1] + 1];
    }
    for (int32_t v = 0; v < nv; ++v) m->ring_offsets[v + 1] += m->ring_offsets[v];
    int32_t *fill = m->vface_offsets; /* borrowed as a cursor, rebuilt below */
    memcpy(fill, m->ring_offsets, ((size_t)nv + 1) * sizeof *fill);
    for (int32_t e = 0; e < ne; ++e) {
        int32_t a = m->edge_vertices[2 * e], b = m->edge_vertices[2 * e + 1];
        m->ring_neighbors[fill[a]] = b;
        m->ring_edges[fill[a]++] = e;
        m->ring_neighbors[fill[b]] = a;
        m->ring_edges[fill[b]++] = e;
    }
    memset(m->vface_offsets, 0, ((size_t)nv + 1) * sizeof *m->vface_offsets);
    for (int32_t h = 0; h < 3 * nf; ++h) ++m->vface_offsets[m->triangles[h] + 1];
    for (int32_t v = 0; v < nv; ++v) m->vface_offsets[v + 1] += m->vface_offsets[v];
    /* faces in increasing order; use vface_faces positions via a cursor
     * reconstructed from the offsets (vertex v's cursor is offsets[v]). */
    for (int32_t h = 0; h < 3 * nf; ++h) m->vface_faces[m->vface_offsets[m->triangles[h]]++] = cfi_he_face(h);
    for (int32_t v = nv; v > 0; --v) m->vface_offsets[v] = m->vface_offsets[v - 1];
    m->vface_offsets[0] = 0;
    return CF_OK;
}

/* Boundary loops and components; tmp holds at least 3 nf + nv + 1 ints. */
static cf_status build_loops_components(cf_mesh *m, scratch *s)
{
    cf_context *ctx = m->ctx;
    const int32_t nv = m->nv, nf = m->nf, ne = m->ne;
    const int32_t *tri = m->triangles;
    /* Outgoing boundary halfedge per vertex: unique on a manifold mesh. */
    int32_t *out_he = s->count; /* nv + 1 */
    int32_t nb = 0;
    for (int32_t v = 0; v < nv; ++v) out_he[v] = -1;
    for (int32_t h = 0; h < 3 * nf; ++h)
        if (m->halfedge_twin[h] < 0) {
            out_he[tri[h]] = h;
            ++nb;
        }
    m->boundary_vertex_count = nb;
    if (nb > 0) { /* NULL for closed meshes */
        m->boundary_loop_vertices = CFI_ALLOC(ctx, int32_t, nb);
        if (!m->boundary_loop_vertices) return CF_ERR_NOMEM;
    }
    int32_t *starts = s->tmp; /* up to nb + 1 */
    int32_t loops = 0, n = 0;
    for (int32_t v = 0; v < nv; ++v) {
        if (out_he[v] < 0) continue;
        starts[loops++] = n;
        int32_t w = v;
        while (out_he[w] >= 0) {
            int32_t h = out_he[w];
            out_he[w] = -1; /* visited */
            m->boundary_loop_vertices[n++] = w;
            w = tri[cfi_he_next(h)];
        }
        if (CF_NEVER(w != v)) return cfi_error(ctx, CF_ERR_BAD_MESH, "vertex %d: boundary loop does not close", v);
    }
    starts[loops] = n;
    m->boundary_loop_count = loops;
    m->boundary_loop_offsets = CFI_ALLOC(ctx, int32_t, (size_t)loops + 1);
    if (!m->boundary_loop_offsets) return CF_ERR_NOMEM;
    memcpy(m->boundary_loop_offsets, starts, ((size_t)loops + 1) * sizeof *starts);

    /* Components over vertices (union-find along edges), numbered in order
     * of their lowest vertex. */
    m->vertex_component = CFI_ALLOC(ctx, int32_t, nv);
    m->face_component = CFI_ALLOC(ctx, int32_t, nf);
    if (!m->vertex_component || !m->face_component) return CF_ERR_NOMEM;
    int32_t *uf = s->uf; /* 3 nf >= nv since every vertex is used */
    for (int32_t v = 0; v < nv; ++v) uf[v] = v;
    for (int32_t e = 0; e < ne; ++e) uf_union(uf, m->edge_vertices[2 * e], m->edge_vertices[2 * e + 1]);
    int32_t nc = 0;
    for (int32_t v = 0; v < nv; ++v) {
        int32_t r = uf_find(uf, v);
        m->vertex_component[v] = r == v ? nc++ : m->vertex_component[r];
    }
    m->component_count = nc;
    for (int32_t f = 0; f < nf; ++f) m->face_component[f] = m->vertex_component[tri[3 * (size_t)f]];

    /* Genus: sum over components of (2 - chi_c - b_c) / 2. */
    int64_t *chi = (int64_t *)cfi_alloc_array(ctx, (size_t)nc * 2, sizeof(int64_t));
    if (!chi) return CF_ERR_NOMEM;
    int64_t *bc = chi + nc;
    for (int32_t v = 0; v < nv; ++v) ++chi[m->vertex_component[v]];
    for (int32_t e = 0; e < ne; ++e) --chi[m->vertex_component[m->edge_vertices[2 * e]]];
    for (int32_t f = 0; f < nf; ++f) ++chi[m->face_component[f]];
    for (int32_t b = 0; b < loops; ++b) ++bc[m->vertex_component[m->boundary_loop_vertices[starts[b]]]];
    int64_t genus = 0;
    for (int32_t c = 0; c < nc; ++c) genus += (2 - chi[c] - bc[c]) / 2;
    cfi_free(ctx, chi, (size_t)nc * 2 * sizeof(int64_t));
    m->genus = (int32_t)genus;
    m->euler_characteristic = nv - ne + nf;
    return CF_OK;
}

static cf_status copy_input(cf_mesh *m, const cf_mesh_desc *d)
{
    cf_context *ctx = m->ctx;
    m->positions = CFI_ALLOC(ctx, double, 3 * (size_t)m->nv);
    m->triangles = CFI_ALLOC(ctx, int32_t, 3 * (size_t)m->nf);
    if (!m->positions || !m->triangles) return CF_ERR_NOMEM;
    memcpy(m->positions, d->positions, 3 * (size_t)m->nv * sizeof(double));
    memcpy(m->triangles, d->triangles, 3 * (size_t)m->nf * sizeof(int32_t));
    if (d->uv) {
        m->uv = CFI_ALLOC(ctx, double, 2 * (size_t)d->uv_count);
        if (!m->uv) return CF_ERR_NOMEM;
        m->uv_count = d->uv_count;
        memcpy(m->uv, d->uv, 2 * (size_t)d->uv_count * sizeof(double));
        m->uv_triangles = CFI_ALLOC(ctx, int32_t, 3 * (size_t)m->nf);
        if (!m->uv_triangles) return CF_ERR_NOMEM;
        memcpy(m->uv_triangles, d->uv_triangles ? d->uv_triangles : d->triangles,
               3 * (size_t)m->nf * sizeof(int32_t));
    }
    return CF_OK;
}

cf_status cf_mesh_create(cf_context *ctx, const cf_mesh_desc *desc, cf_mesh **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "output pointer is NULL");
    *out = NULL;
    cf_status st = check_arguments(ctx, desc);
    if (st != CF_OK) return st;

    scratch s;
    memset(&s, 0, sizeof s);
    checker c = {ctx, NULL, CF_OK, ""};
    if (desc->vertex_count == 0 || desc->face_count == 0)
        return cfi_error(ctx, CF_ERR_BAD_MESH, "empty mesh (%d vertices, %d faces)", desc->vertex_count,
                         desc->face_count);
    if (scratch_alloc(ctx, &s, desc->vertex_count, desc->face_count) != CF_OK) return CF_ERR_NOMEM;
    st = run_checks(&c, desc, &s);
    if (st != CF_OK) {
        scratch_free(ctx, &s);
        return cfi_error(ctx, st, "%s", c.message);
    }

    cf_mesh *m = (cf_mesh *)cfi_calloc(ctx, 1, sizeof *m);
    if (!m) {
        scratch_free(ctx, &s);
        return CF_ERR_NOMEM;
    }
    m->ctx = ctx;
    m->nv = desc->vertex_count;
    m->nf = desc->face_count;
    st = copy_input(m, desc);
    if (st == CF_OK) st = build_edges(m, &s);
    if (st == CF_OK) st = build_incidence(m);
    if (st == CF_OK) st = build_loops_components(m, &s);
    scratch_free(ctx, &s);
    if (st != CF_OK) {
        cf_mesh_destroy(&m);
        return st;
    }
    *out = m;
    return CF_OK;
}

cf_status cf_mesh_validate(cf_context *ctx, const cf_mesh_desc *desc, cf_mesh_report *report)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!report) return cfi_error(ctx, CF_ERR_INVALID_ARG, "report is NULL");
    memset(report, 0, sizeof *report);
    cf_status st = check_arguments(ctx, desc);
    if (st != CF_OK) return st;
    checker c = {ctx, report, CF_OK, ""};
    if (desc->vertex_count == 0 || desc->face_count == 0) {
        report->first_status = CF_ERR_BAD_MESH;
        snprintf(report->first_message, sizeof report->first_message, "empty mesh (%d vertices, %d faces)",
                 desc->vertex_count, desc->face_count);
        return CF_OK;
    }
    scratch s;
    if (scratch_alloc(ctx, &s, desc->vertex_count, desc->face_count) != CF_OK) return CF_ERR_NOMEM;
    run_checks(&c, desc, &s);
    scratch_free(ctx, &s);
    report->first_status = c.first;
    snprintf(report->first_message, sizeof report->first_message, "%s", c.message);
    return CF_OK;
}

/* ------------------------------------------------------------------------ */

cf_status cf_mesh_check_positions(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                  cf_mesh_report *report)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!report) return cfi_error(ctx, CF_ERR_INVALID_ARG, "report is NULL");
    if (!mesh || !positions) return cfi_error(ctx, CF_ERR_INVALID_ARG, "mesh or positions is NULL");
    memset(report, 0, sizeof *report);
    /* the connectivity passed every check when the mesh was built, so only
     * the geometric steps (3 and 4) can fail; every face takes part, which
     * needs none of the full check's per-halfedge scratch */
    cf_mesh_desc d = {mesh->nv, positions, mesh->nf, mesh->triangles, 0, NULL, NULL};
    scratch s;
    memset(&s, 0, sizeof s);
    s.nv = mesh->nv, s.nf = mesh->nf;
    checker c = {ctx, report, CF_OK, ""};
    if (!check_coordinates(&c, &d, &s, report)) (void)check_areas(&c, &d, &s, report);
    report->first_status = c.first;
    snprintf(report->first_message, sizeof report->first_message, "%s", c.message);
    return CF_OK;
}

/* ------------------------------------------------------------------------ */

void cfi_mesh_split4_triangles(const cf_mesh *mesh, int32_t *out)
{
    const int32_t nv = mesh->nv;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * (size_t)f;
        const int32_t *he = mesh->halfedge_edge + 3 * (size_t)f;
        int32_t a = t[0], b = t[1], c = t[2];
        int32_t mab = nv + he[0], mbc = nv + he[1], mca = nv + he[2];
        int32_t *o = out + 12 * (size_t)f;
        o[0] = a, o[1] = mab, o[2] = mca;
        o[3] = mab, o[4] = b, o[5] = mbc;
        o[6] = mca, o[7] = mbc, o[8] = c;
        o[9] = mab, o[10] = mbc, o[11] = mca;
    }
}

/* Accessors */
int32_t cf_mesh_vertex_count(const cf_mesh *mesh) { return mesh ? mesh->nv : 0; }
int32_t cf_mesh_face_count(const cf_mesh *mesh) { return mesh ? mesh->nf : 0; }
int32_t cf_mesh_edge_count(const cf_mesh *mesh) { return mesh ? mesh->ne : 0; }
int32_t cf_mesh_boundary_loop_count(const cf_mesh *mesh) { return mesh ? mesh->boundary_loop_count : 0; }
int32_t cf_mesh_component_count(const cf_mesh *mesh) { return mesh ? mesh->component_count : 0; }
int32_t cf_mesh_euler_characteristic(const cf_mesh *mesh) { return mesh ? mesh->euler_characteristic : 0; }
int32_t cf_mesh_genus(const cf_mesh *mesh) { return mesh ? mesh->genus : 0; }
const double *cf_mesh_positions(const cf_mesh *mesh) { return mesh ? mesh->positions : NULL; }
const int32_t *cf_mesh_triangles(const cf_mesh *mesh) { return mesh ? mesh->triangles : NULL; }
const int32_t *cf_mesh_edge_vertices(const cf_mesh *mesh) { return mesh ? mesh->edge_vertices : NULL; }
const int32_t *cf_mesh_halfedge_edge(const cf_mesh *mesh) { return mesh ? mesh->halfedge_edge : NULL; }
const int32_t *cf_mesh_halfedge_twin(const cf_mesh *mesh) { return mesh ? mesh->halfedge_twin : NULL; }
const int32_t *cf_mesh_edge_faces(const cf_mesh *mesh) { return mesh ? mesh->edge_faces : NULL; }
const uint8_t *cf_mesh_vertex_on_boundary(const cf_mesh *mesh) { return mesh ? mesh->vertex_on_boundary : NULL; }
const int32_t *cf_mesh_vertex_component(const cf_mesh *mesh) { return mesh ? mesh->vertex_component : NULL; }
const int32_t *cf_mesh_boundary_loop_offsets(const cf_mesh *mesh)
{
    return mesh ? mesh->boundary_loop_offsets : NULL;
}
const int32_t *cf_mesh_boundary_loop_vertices(const cf_mesh *mesh)
{
    return mesh ? mesh->boundary_loop_vertices : NULL;
}
const int32_t *cf_mesh_vertex_ring_offsets(const cf_mesh *mesh) { return mesh ? mesh->ring_offsets : NULL; }
const int32_t *cf_mesh_vertex_neighbors(const cf_mesh *mesh) { return mesh ? mesh->ring_neighbors : NULL; }
const int32_t *cf_mesh_vertex_edges(const cf_mesh *mesh) { return mesh ? mesh->ring_edges : NULL; }
const int32_t *cf_mesh_vertex_face_offsets(const cf_mesh *mesh) { return mesh ? mesh->vface_offsets : NULL; }
const int32_t *cf_mesh_vertex_faces(const cf_mesh *mesh) { return mesh ? mesh->vface_faces : NULL; }
int32_t cf_mesh_uv_count(const cf_mesh *mesh) { return mesh ? mesh->uv_count : 0; }
const double *cf_mesh_uv(const cf_mesh *mesh) { return mesh ? mesh->uv : NULL; }
const int32_t *cf_mesh_uv_triangles(const cf_mesh *mesh) { return mesh ? mesh->uv_triangles : NULL; }
cf_context *cf_mesh_context(const cf_mesh *mesh) { return mesh ? mesh->ctx : NULL; }
