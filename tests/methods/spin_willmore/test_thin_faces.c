/*
 * spin-willmore on a mesh with a near-duplicate vertex (docs/spin.md,
 * "Near-duplicate vertices"): one vertex moved to 1e-12 of an edge's length
 * from its neighbour. The mesh check accepts it (its faces keep a nonzero
 * area), but the thin faces' cotangent weights of about 1e12 cost every solve
 * its accuracy, and the flow stops far from round (spot_3k: W/4pi 4.39 after
 * 10 steps instead of 1.002). Not fixed (a floor on the weights would change
 * the baseline flows' degenerate runs); the flow says so at creation, through
 * the log, naming the thinnest face. Checked: the warning and its face, none
 * on the unperturbed mesh, and that the run still keeps W non-increasing
 * and its faces valid.
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/mesh.h"
#include "spin_test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct warnings {
    int count;
    char first[512];
} warnings;

static void record(void *user, cf_log_level level, const char *line)
{
    warnings *w = user;
    if (level != CF_LOG_WARNING || !strstr(line, "nearly flat")) return;
    if (w->count++ == 0) snprintf(w->first, sizeof w->first, "%s", line);
}

/* The eight-armed star (642 vertices); with `near`, face 100's first corner
 * moved to 1e-12 of the way from its second. */
static cf_mesh *star(cf_context *ctx, int near)
{
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_limb_sphere(ctx, 3, 8, 1.4, 0.22, &m));
    if (!m || !near) return m;
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    double *x = malloc(3 * (size_t)nv * sizeof(double));
    cf_mesh *moved = NULL;
    CHECK(x != NULL);
    if (x) {
        memcpy(x, cf_mesh_positions(m), 3 * (size_t)nv * sizeof(double));
        const int32_t *t = cf_mesh_triangles(m) + 3 * 100;
        for (int c = 0; c < 3; ++c) x[3 * t[0] + c] = x[3 * t[1] + c] + 1e-12 * (x[3 * t[0] + c] - x[3 * t[1] + c]);
        cf_mesh_desc d = {.vertex_count = nv, .positions = x, .face_count = nf, .triangles = cf_mesh_triangles(m)};
        CHECK_OK(ctx, cf_mesh_create(ctx, &d, &moved));
    }
    free(x);
    cf_mesh_destroy(&m);
    return moved;
}

static void test_near_duplicate_warns(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(NULL, cf_context_create(&ctx));
    warnings w;
    memset(&w, 0, sizeof w);
    cf_context_set_log(ctx, record, &w, CF_LOG_WARNING);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    for (int near = 0; near < 2; ++near) {
        cf_mesh *m = star(ctx, near);
        if (!m) continue;
        memset(&w, 0, sizeof w);
        spin_run r;
        memset(&r, 0, sizeof r);
        spin_run_steps(ctx, m, &o, 10, &r, NULL);
        fprintf(stderr, "   %s: W/4pi %.4f -> %.5f, %d warning(s)%s%s\n", near ? "near-duplicate vertex" : "clean",
                r.w0, r.w, w.count, w.count ? ": " : "", w.first);
        CHECK(r.steps == 10);
        CHECK_LE(r.worst_rise, 0.0);
        CHECK(r.defects == 0);
        if (near) {
            CHECK(w.count == 1); /* once, at creation */
            /* the thinnest face named: one of the two at the moved vertex */
            int face = -1;
            CHECK(sscanf(w.first, "spin-willmore: face %d is nearly flat", &face) == 1);
            const int32_t *t = cf_mesh_triangles(m), moved = t[3 * 100];
            CHECK(face >= 0 && face < cf_mesh_face_count(m) &&
                  (t[3 * face] == moved || t[3 * face + 1] == moved || t[3 * face + 2] == moved));
            CHECK(strstr(w.first, "2 faces below 1e-10") != NULL);
            CHECK(strstr(w.first, "near-duplicate vertex") != NULL);
        } else {
            CHECK(w.count == 0);
            CHECK_LE(r.w, 1.01); /* measured 1.0043 */
        }
        cf_mesh_destroy(&m);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_near_duplicate_warns);
    return cft_finish();
}
