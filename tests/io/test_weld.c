/* cf_mesh_data_weld: a surface cut along seams (as an exporter splits
 * vertices where the texture changes) and a triangle soup weld back into
 * the closed surface; texture coordinates become per corner and keep each
 * corner's own; properties keep the first copy's value; welds that would
 * make an invalid mesh are refused with the reason, leaving the data as it
 * was; interior vertices at one position are no seam; running out of
 * memory at any allocation leaves the data unchanged. */
#define _POSIX_C_SOURCE 200809L
#include "io_test_util.h"
#include "curvflow/generate.h"
#include "curvflow/mesh.h"

#include <stdarg.h>

typedef struct text {
    char *data;
    size_t size, cap;
} text;

static void put(text *t, const char *fmt, ...)
{
    va_list ap;
    for (;;) {
        va_start(ap, fmt);
        int n = vsnprintf(t->data ? t->data + t->size : NULL, t->data ? t->cap - t->size : 0, fmt, ap);
        va_end(ap);
        if (t->data && t->size + (size_t)n < t->cap) {
            t->size += (size_t)n;
            return;
        }
        t->cap = 2 * (t->cap + (size_t)n + 64);
        t->data = realloc(t->data, t->cap);
        if (!t->data) exit(1);
    }
}

/* The icosphere (subdivisions 2: 162 vertices, 320 faces), for reference. */
static cf_mesh *icosphere(cf_context *ctx)
{
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &m));
    return m;
}

/* The icosphere cut along a seam: every vertex used by faces on both sides
 * of x = 0 gets a copy, appended after the originals, used by the faces
 * with x > 0 (as an exporter splits a texture seam). A PLY with u, v per
 * vertex (the copies' u shifted by 1, as across a texture seam) and a
 * property "label" (the copies' equal to the originals' except one).
 * *copies: the count of copies; copy_of[k]: the vertex copy k duplicates. */
static char *seam_ply(const cf_mesh *m, int32_t *copies, int32_t *copy_of, size_t *size)
{
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    const double *x = cf_mesh_positions(m);
    const int32_t *t = cf_mesh_triangles(m);
    uint8_t *side = calloc((size_t)nv, 1); /* bit 1: used by a face x > 0, bit 2: x <= 0 */
    int32_t *copy = malloc((size_t)nv * sizeof *copy);
    for (int32_t f = 0; f < nf; ++f) {
        double cx = (x[3 * t[3 * f]] + x[3 * t[3 * f + 1]] + x[3 * t[3 * f + 2]]) / 3.0;
        for (int k = 0; k < 3; ++k) side[t[3 * f + k]] |= cx > 0.0 ? 1 : 2;
    }
    *copies = 0;
    for (int32_t v = 0; v < nv; ++v) {
        copy[v] = side[v] == 3 ? nv + *copies : v;
        if (side[v] == 3) copy_of[(*copies)++] = v;
    }
    text s = {0};
    put(&s, "ply\nformat ascii 1.0\nelement vertex %d\nproperty double x\nproperty double y\nproperty double z\n"
            "property double u\nproperty double v\nproperty double label\nelement face %d\n"
            "property list uchar int vertex_indices\nend_header\n",
        (int)(nv + *copies), (int)nf);
    for (int32_t v = 0; v < nv + *copies; ++v) {
        int32_t o = v < nv ? v : copy_of[v - nv];
        double label = v == nv ? 1000.0 : (double)o; /* the first copy's label differs */
        put(&s, "%.17g %.17g %.17g %.17g %.17g %.17g\n", x[3 * o], x[3 * o + 1], x[3 * o + 2],
            0.25 * o + (v < nv ? 0.0 : 1.0), 0.5, label);
    }
    for (int32_t f = 0; f < nf; ++f) {
        double cx = (x[3 * t[3 * f]] + x[3 * t[3 * f + 1]] + x[3 * t[3 * f + 2]]) / 3.0;
        int32_t a = t[3 * f], b = t[3 * f + 1], c = t[3 * f + 2];
        if (cx > 0.0) a = copy[a], b = copy[b], c = copy[c];
        put(&s, "3 %d %d %d\n", (int)a, (int)b, (int)c);
    }
    free(side);
    free(copy);
    *size = s.size;
    return s.data;
}

static void test_seam(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = icosphere(ctx);
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    int32_t copies = 0, copy_of[200];
    size_t size = 0;
    char *ply = seam_ply(m, &copies, copy_of, &size);
    CHECK(copies > 10 && copies < 200);
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, ply, size, CF_FORMAT_PLY, "seam.ply", &d));
    CHECK(d && d->vertex_count == nv + copies && d->uv_count == nv + copies && !d->uv_triangles);

    /* as read, the file is an open surface: its cut is two boundary loops */
    cf_mesh_desc desc;
    cf_mesh *cut = NULL;
    cf_mesh_data_desc(d, &desc);
    CHECK_OK(ctx, cf_mesh_create(ctx, &desc, &cut));
    CHECK(cf_mesh_boundary_loop_count(cut) == 2);
    cf_mesh_destroy(&cut);

    int32_t *new_index = malloc((size_t)(nv + copies) * sizeof *new_index);
    cf_weld_report r;
    CHECK_OK(ctx, cf_mesh_data_weld(ctx, d, new_index, &r));
    CHECK(r.welded == 1 && r.candidates == 2 * copies && r.groups == copies && r.removed == copies);
    CHECK(r.vertices == nv && d->vertex_count == nv && r.refused[0] == '\0');
    CHECK(r.differing_properties == 1); /* the first copy's label, and no other */
    /* the copies came last: the weld gives back the icosphere, vertex for vertex */
    CHECK(memcmp(d->triangles, cf_mesh_triangles(m), 3 * (size_t)nf * sizeof(int32_t)) == 0);
    CHECK(memcmp(d->positions, cf_mesh_positions(m), 3 * (size_t)nv * sizeof(double)) == 0);
    for (int32_t k = 0; k < copies; ++k) CHECK(new_index[nv + k] == copy_of[k]);
    for (int32_t v = 0; v < nv; ++v) CHECK(new_index[v] == v);
    /* texture: per corner now, each corner with the coordinates it had */
    CHECK(d->uv_triangles != NULL && d->uv_count == nv + copies);
    const double *x = cf_mesh_positions(m);
    const int32_t *t = cf_mesh_triangles(m);
    int32_t shifted = 0;
    for (int32_t f = 0; f < nf; ++f) {
        double cx = (x[3 * t[3 * f]] + x[3 * t[3 * f + 1]] + x[3 * t[3 * f + 2]]) / 3.0;
        for (int k = 0; k < 3; ++k) {
            int32_t v = t[3 * f + k], u = d->uv_triangles[3 * f + k];
            bool copied = u >= nv;
            CHECK(d->uv[2 * u] == 0.25 * v + (copied ? 1.0 : 0.0));
            CHECK(!copied || cx > 0.0);
            shifted += copied;
        }
    }
    CHECK(shifted > 0);
    const cf_mesh_property *label = cf_mesh_data_vertex_property(d, "label");
    CHECK(label != NULL);
    for (int32_t v = 0; label && v < nv; ++v) CHECK(label->values[v] == (double)v);

    /* the welded data builds the closed sphere */
    cf_mesh *welded = NULL;
    cf_mesh_data_desc(d, &desc);
    CHECK_OK(ctx, cf_mesh_create(ctx, &desc, &welded));
    CHECK(cf_mesh_boundary_loop_count(welded) == 0 && cf_mesh_genus(welded) == 0);
    CHECK(cf_mesh_uv_triangles(welded) != NULL);

    /* welding again finds nothing */
    CHECK_OK(ctx, cf_mesh_data_weld(ctx, d, NULL, &r));
    CHECK(r.welded == 0 && r.candidates == 0 && r.vertices == nv);
    cf_mesh_destroy(&welded);
    cf_mesh_data_destroy(&d);

    /* out of memory at any allocation: the data as read, nothing leaked */
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    int failures = 0;
    for (int64_t n = 1; n < 1000; ++n) {
        CHECK_OK(ctx, cf_read_mesh_memory(ctx, ply, size, CF_FORMAT_PLY, "seam.ply", &d));
        size_t before = cf_context_bytes_in_use(ctx);
        cf_context_fail_allocation(ctx, n, 0);
        cf_status st = cf_mesh_data_weld(ctx, d, NULL, &r);
        cf_context_fail_allocation(ctx, 0, 0);
        if (st == CF_OK) {
            CHECK(r.welded == 1 && d->vertex_count == nv);
            cf_mesh_data_destroy(&d);
            break;
        }
        ++failures;
        CHECK_STATUS(st, CF_ERR_NOMEM);
        CHECK(d->vertex_count == nv + copies && !d->uv_triangles);
        CHECK(cf_context_bytes_in_use(ctx) == before);
        cf_mesh_data_destroy(&d);
    }
    CHECK(failures >= 8); /* every array the weld makes */
    free(new_index);
    free(ply);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* An OBJ of the icosphere's faces as unshared triangles (an STL export),
 * optionally with face `flip` reversed. */
static char *soup_obj(const cf_mesh *m, int32_t flip, size_t *size)
{
    const double *x = cf_mesh_positions(m);
    const int32_t *t = cf_mesh_triangles(m);
    text s = {0};
    for (int32_t f = 0; f < cf_mesh_face_count(m); ++f)
        for (int k = 0; k < 3; ++k) {
            int32_t v = t[3 * f + (f == flip ? 2 - k : k)];
            put(&s, "v %.17g %.17g %.17g\n", x[3 * v], x[3 * v + 1], x[3 * v + 2]);
        }
    for (int32_t f = 0; f < cf_mesh_face_count(m); ++f) put(&s, "f %d %d %d\n", 3 * f + 1, 3 * f + 2, 3 * f + 3);
    *size = s.size;
    return s.data;
}

static void test_soup(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = icosphere(ctx);
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    size_t size = 0;
    char *obj = soup_obj(m, -1, &size);
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, obj, size, CF_FORMAT_OBJ, "soup.obj", &d));
    cf_weld_report r, rm;
    /* the map of the arrays first (the data is not changed by it) */
    int32_t *map = malloc(3 * (size_t)nf * sizeof *map);
    CHECK_OK(ctx, cf_weld_map(ctx, d->vertex_count, d->positions, d->face_count, d->triangles, map, &rm));
    CHECK(rm.welded == 1 && rm.vertices == nv && rm.removed == 3 * nf - nv && d->vertex_count == 3 * nf);
    int32_t kept = 0, *first = malloc((size_t)nv * sizeof *first);
    for (int32_t v = 0; v < 3 * nf; ++v) {
        CHECK(map[v] <= kept && map[v] >= 0 && map[v] < nv);
        if (map[v] == kept && kept < nv) first[kept++] = v;
        /* a joined vertex is at its kept vertex's position, and comes after it */
        else CHECK(memcmp(d->positions + 3 * (size_t)v, d->positions + 3 * (size_t)first[map[v]], 3 * sizeof(double)) ==
                       0 && first[map[v]] < v);
    }
    CHECK(kept == nv);
    free(first);
    CHECK_OK(ctx, cf_mesh_data_weld(ctx, d, NULL, &r));
    CHECK(r.welded == 1 && r.candidates == 3 * nf && r.groups == nv && r.vertices == nv && r.removed == 3 * nf - nv);
    CHECK(rm.candidates == r.candidates && rm.groups == r.groups);
    for (int32_t c = 0; c < 3 * nf; ++c) CHECK(d->triangles[c] == map[c]); /* the soup's corner c is vertex c */
    free(map);
    cf_mesh_desc desc;
    cf_mesh *welded = NULL;
    cf_mesh_data_desc(d, &desc);
    CHECK_OK(ctx, cf_mesh_create(ctx, &desc, &welded));
    CHECK(cf_mesh_boundary_loop_count(welded) == 0 && cf_mesh_genus(welded) == 0 &&
          cf_mesh_edge_count(welded) == cf_mesh_edge_count(m));
    cf_mesh_destroy(&welded);
    cf_mesh_data_destroy(&d);
    free(obj);

    /* one triangle reversed: the welded surface would not be oriented; the
     * weld is refused, the reason given, the data unchanged */
    obj = soup_obj(m, 7, &size);
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, obj, size, CF_FORMAT_OBJ, "soup.obj", &d));
    CHECK_OK(ctx, cf_mesh_data_weld(ctx, d, NULL, &r));
    CHECK(r.welded == 0 && r.removed == 0 && r.candidates == 3 * nf && d->vertex_count == 3 * nf);
    CHECK(strstr(r.refused, "after welding, faces ") == r.refused && strstr(r.refused, " and 7: edge ") != NULL &&
          strstr(r.refused, "traversed in the same direction by both") != NULL);
    cf_mesh_data_destroy(&d);
    free(obj);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_not_seams(void)
{
    cf_context *ctx = cft_context();
    cf_mesh_data *d = NULL;
    cf_weld_report r;
    /* two triangles that touch at one corner (a bow tie): joining the corner
     * would make a vertex of two separate fans */
    const char *bowtie = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 0\nv -1 0 0\nv 0 -1 0\nf 1 2 3\nf 4 5 6\n";
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, bowtie, strlen(bowtie), CF_FORMAT_OBJ, "bowtie.obj", &d));
    CHECK_OK(ctx, cf_mesh_data_weld(ctx, d, NULL, &r));
    CHECK(r.welded == 0 && r.candidates == 2 && r.groups == 1 && d->vertex_count == 6);
    CHECK(strstr(r.refused, "vertex 0: its faces form 2 separate fans") != NULL);
    cf_mesh_data_destroy(&d);
    /* two closed tetrahedra that share a corner's position: no boundary, so
     * no candidate (a surface touching itself is no seam) */
    const char *tetrahedra = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0 0 0\nv -1 0 0\nv 0 -1 0\nv 0 0 -1\n"
                             "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nf 5 6 7\nf 5 8 6\nf 5 7 8\nf 6 8 7\n";
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, tetrahedra, strlen(tetrahedra), CF_FORMAT_OBJ, "t.obj", &d));
    CHECK_OK(ctx, cf_mesh_data_weld(ctx, d, NULL, &r));
    CHECK(r.welded == 0 && r.candidates == 0 && r.refused[0] == '\0' && d->vertex_count == 8);
    cf_mesh_data_destroy(&d);
    /* exact positions only: the vertex at 1e-300 from the origin is no
     * candidate (one group, the corner at (0, 1, 0); joining it alone
     * would again make a bow tie) */
    const char *near = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1e-300 0 0\nv 0 1 0\nv -1 0 0\nf 1 2 3\nf 4 5 6\n";
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, near, strlen(near), CF_FORMAT_OBJ, "near.obj", &d));
    int32_t index[6];
    CHECK_OK(ctx, cf_mesh_data_weld(ctx, d, index, &r));
    CHECK(r.welded == 0 && r.candidates == 2 && r.groups == 1 && index[4] == 4);
    CHECK(strstr(r.refused, "separate fans") != NULL);
    cf_mesh_data_destroy(&d);
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    CHECK_STATUS(cf_mesh_data_weld(ctx, NULL, NULL, &r), CF_ERR_INVALID_ARG);
    /* the arrays' map checks what a reader would have */
    static const double x[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const int32_t bad[6] = {0, 1, 2, 0, 2, 9};
    int32_t map[3];
    CHECK_STATUS(cf_weld_map(ctx, 3, x, 2, bad, map, &r), CF_ERR_INDEX_RANGE);
    CHECK(strcmp(cf_context_message(ctx), "face 1: vertex index 9 out of range [0, 3)") == 0);
    CHECK_STATUS(cf_weld_map(ctx, 3, x, 1, bad, NULL, &r), CF_ERR_INVALID_ARG);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_seam);
    CFT_RUN(test_soup);
    CFT_RUN(test_not_seams);
    return cft_finish();
}
