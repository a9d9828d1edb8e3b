/*
 * Zhao & Gortler, Figs. 3 and 4: tessellation (in)sensitivity.
 *  - Fig. 3: twisting a flat sheet at two resolutions gives nearly the same
 *    hybrid result, while ARAP's results differ clearly more (its bending
 *    resistance comes from the cell size, App. B).
 *  - Fig. 4's bar at two resolutions (the test): pulled sideways,
 *    every energy is resolution-insensitive (membrane-dominated); with the
 *    top face turned by 90 degrees the walls must fold and ARAP's results
 *    differ clearly more than the hybrid's.
 *  - Fig. 4: pulling the top of a bar under two triangulations of the same
 *    vertices changes ARAP's result, not hybrid's or spokes-and-rims'.
 * Distances are measured at shared vertices relative to the bounding-box
 * diagonal of the rest shape.
 */
#include "stretch_bend_test_util.h"
#include "test.h"

#include "curvflow/generate.h"
#include "curvflow/stretch_bend_edit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double *solve(cf_context *ctx, const cf_mesh *mesh, const cf_handle_set *h, cf_stretch_bend_energy_kind e, int iterations)
{
    cf_stretch_bend_options o;
    cf_stretch_bend_options_default(&o);
    o.energy = e;
    o.handles = h;
    o.max_iterations = iterations;
    o.relative_tolerance = 1e-8;
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *out = malloc(sizeof(double) * 3 * (size_t)nv);
    cf_flow_info info;
    CHECK_OK(ctx, cf_stretch_bend_edit(ctx, mesh, NULL, &o, out, &info));
    fprintf(stderr, "    [%s nv %d: %lld iterations, E %.6g, relative decrease %.3g]\n", cf_stretch_bend_energy_name(e), nv,
            (long long)info.iteration, info.energy, info.residuals[0]);
    return out;
}

/* Sheet [0,1]^2 at resolution n: left edge fixed, right edge twisted by
 * `angle` about the line y = 1/2, z = 0 and pulled in by `pull` along x. */
typedef struct { double angle, pull; } sheet_edit;

static int twist_rule(int32_t v, const double *p, double *t, const void *user)
{
    (void)v;
    const sheet_edit *se = user;
    if (p[0] < 1e-9) {
        memcpy(t, p, 3 * sizeof(double));
        return 1;
    }
    if (p[0] > 1.0 - 1e-9) {
        double qy = p[1] - 0.5;
        t[0] = p[0] - se->pull;
        t[1] = 0.5 + cos(se->angle) * qy;
        t[2] = sin(se->angle) * qy;
        return 1;
    }
    return 0;
}

static cf_handle_set *twist_handles(cf_context *ctx, const cf_mesh *mesh, double angle, double pull)
{
    sheet_edit se = {angle, pull};
    return stretch_bend_handles_where(ctx, mesh, twist_rule, &se);
}

static void test_sheet_twist_resolution(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *coarse = NULL, *fine = NULL;
    CHECK_OK(ctx, cf_generate_sheet(ctx, 8, 1.0, 0, &coarse));
    int nfine = 16, rr = nfine / 8;
    CHECK_OK(ctx, cf_generate_sheet(ctx, nfine, 1.0, 0, &fine));
    if (!coarse || !fine) return;
    /* A quarter turn with the twisted edge pulled in by 0.2: the sheet
     * has to bend, which is where ARAP's resistance depends on the cell
     * size. The hybrid iteration converges slowly (first-order local/global
     * on a bi-Laplacian system), hence the high iteration cap. */
    double ang = 0.5 * 3.14159265358979323846, pull = 0.2;
    int iters = 4000;
    cf_handle_set *hc = twist_handles(ctx, coarse, ang, pull), *hf = twist_handles(ctx, fine, ang, pull);
    double dist[CF_STRETCH_BEND_ENERGY_COUNT] = {0};
    for (int e = 0; e < CF_STRETCH_BEND_ENERGY_COUNT; ++e) {
        if (e == CF_STRETCH_BEND_STRETCH || e == CF_STRETCH_BEND_BEND) continue;
        double *yc = solve(ctx, coarse, hc, (cf_stretch_bend_energy_kind)e, iters);
        double *yf = solve(ctx, fine, hf, (cf_stretch_bend_energy_kind)e, iters);
        /* Coarse vertex (i, j) is fine vertex (4 i, 4 j). */
        double worst = 0.0;
        for (int j = 0; j <= 8; ++j)
            for (int i = 0; i <= 8; ++i) {
                const double *a = yc + 3 * (j * 9 + i), *b = yf + 3 * (rr * j * (nfine + 1) + rr * i);
                worst = fmax(worst, sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                                         (a[2] - b[2]) * (a[2] - b[2])));
            }
        dist[e] = worst / sqrt(2.0);
        fprintf(stderr, "  twist %-9s max distance n=8 vs n=16: %.4f of the diagonal\n",
                cf_stretch_bend_energy_name((cf_stretch_bend_energy_kind)e), dist[e]);
        free(yc);
        free(yf);
    }
    /* Fig. 3: the hybrid result barely depends on the resolution (1.5%
     * of the diagonal measured; bound 3%), both ARAP variants move by
     * several times more (8.9% and 10.5% measured; asked: 3 times the
     * hybrid's). ARAP runs without Anderson acceleration (the default):
     * with it, at n = 16 the run stops at E = 0.070 on a saddle plateau
     * before the sheet buckles to the minimum E = 0.041 (docs/edit.md). */
    CHECK_LE(dist[CF_STRETCH_BEND_HYBRID], 0.03);
    CHECK(dist[CF_STRETCH_BEND_ARAP] > 3.0 * dist[CF_STRETCH_BEND_HYBRID]);
    CHECK(dist[CF_STRETCH_BEND_ARAP_RIMS] > 3.0 * dist[CF_STRETCH_BEND_HYBRID]);
    cf_handle_set_destroy(&hc);
    cf_handle_set_destroy(&hf);
    cf_mesh_destroy(&coarse);
    cf_mesh_destroy(&fine);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Handles of the 1 x 1 x 4 bar: bottom face (z = 0) fixed; top face (z = 4)
 * either translated by `pull` along x (Fig. 4's edit) or, for bend != 0,
 * rotated by `bend` radians about the y-parallel line through its centre. */
typedef struct { double pull, bend; } bar_edit;

static int bar_rule(int32_t v, const double *p, double *t, const void *user)
{
    (void)v;
    const bar_edit *b = user;
    if (!(p[2] < 1e-9 || p[2] > 4.0 - 1e-9)) return 0;
    memcpy(t, p, 3 * sizeof(double));
    if (p[2] > 1.0) {
        double dx = p[0] - 0.5;
        t[0] = 0.5 + cos(b->bend) * dx + b->pull;
        t[2] = 4.0 - sin(b->bend) * dx;
    }
    return 1;
}

static cf_handle_set *bar_handles(cf_context *ctx, const cf_mesh *mesh, double pull, double bend)
{
    bar_edit b = {pull, bend};
    return stretch_bend_handles_where(ctx, mesh, bar_rule, &b);
}

/* Fig. 4's bar, 1 x 1 x 4, at 3 x 3 x 12 and 6 x 6 x 24 cells. The fine
 * lattice refines the coarse one, so every coarse vertex is a fine vertex;
 * cf_generate_bar numbers vertices in emission order, so they are matched
 * by position. Returns the max distance at the shared vertices relative to
 * the diagonal sqrt(18), for the pull (bend = 0) or the bend. */
static double bar_resolution_distance(cf_context *ctx, const cf_mesh *mc, const cf_mesh *mf, const int32_t *map,
                                      cf_stretch_bend_energy_kind e, double pull, double bend)
{
    cf_handle_set *hc = bar_handles(ctx, mc, pull, bend), *hf = bar_handles(ctx, mf, pull, bend);
    double *yc = solve(ctx, mc, hc, e, 3000);
    double *yf = solve(ctx, mf, hf, e, 3000);
    double worst = 0.0;
    for (int32_t v = 0; v < cf_mesh_vertex_count(mc); ++v) {
        const double *a = yc + 3 * v, *b = yf + 3 * map[v];
        worst = fmax(worst, sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                                 (a[2] - b[2]) * (a[2] - b[2])));
    }
    double d = worst / sqrt(18.0);
    fprintf(stderr, "  bar %s %-9s 3x3x12 vs 6x6x24: max distance %.5f of the diagonal\n", bend != 0.0 ? "bend" : "pull",
            cf_stretch_bend_energy_name(e), d);
    free(yc);
    free(yf);
    cf_handle_set_destroy(&hc);
    cf_handle_set_destroy(&hf);
    return d;
}

/* The "pulling the bar at two resolutions" (Fig. 4's bar and edit;
 * the figure itself compares triangulations, tested below).
 * Pull (top face moved sideways by 1.5, not rotated), measured with the
 * default options (hybrid with Anderson acceleration): hybrid 1.64% of the
 * diagonal (1.25% with the plain iteration, 3000 steps), ARAP 0.32%,
 * spokes-and-rims 0.28%. Here the claim "ARAP differs clearly more" does NOT hold, and
 * cannot be expected to: the bar bends as a beam whose cross-sections stay
 * square, so the cost is membrane strain of the side walls, which every
 * energy resolves consistently; ARAP's cell-size-dependent bending
 * resistance (App. B: a fold costs half as much per refinement) only
 * decides the shape when the walls must fold. (No lambda changes this:
 * the hybrid distance is 2.9% / 0.9% / 1.1% at lambda = 0.1 / 0.9 / 0.99,
 * ARAP's does not depend on lambda. Hybrid and ARAP differ from each other
 * by 6% of the diagonal on the fine bar, so they do not agree trivially.)
 * The hybrid's 1.5% comes from its own discretisation of the bar's sharp
 * edges (rest |H_v| ~ 1/h there) and from its slow convergence on the fine
 * bar (3000 steps do not reach the 1e-8 tolerance; 1.7% after 20000).
 * Bend (top face turned by 90 degrees about a horizontal axis through its
 * centre): the walls must fold near the top, and the claim holds: hybrid
 * 1.3% (1.3-1.4% for 1000-6000 plain steps, 2.1% after 20000), ARAP 14.4%,
 * spokes-and-rims 13.5% — on the fine bar ARAP folds at the top (largest
 * displacement 0.18 of the diagonal against the hybrid's 0.32).
 * Bounds: the measured values with a margin (hybrid pull 3%, bend 3.5%,
 * covering the drift with iteration count); ARAP pull 0.6% (twice the
 * measured); bend: ARAP and rims above 10% and 4 times the hybrid. */
static void test_bar_resolution(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mc = NULL, *mf = NULL;
    CHECK_OK(ctx, cf_generate_bar(ctx, 3, 3, 12, 1.0, 1.0, 4.0, 0, &mc));
    CHECK_OK(ctx, cf_generate_bar(ctx, 6, 6, 24, 1.0, 1.0, 4.0, 0, &mf));
    if (!mc || !mf) return;
    int32_t nc = cf_mesh_vertex_count(mc), nf = cf_mesh_vertex_count(mf);
    CHECK(nc == 164 && nf == 650);
    const double *xc = cf_mesh_positions(mc), *xf = cf_mesh_positions(mf);
    int32_t *map = malloc(sizeof(int32_t) * (size_t)nc);
    int32_t matched = 0;
    for (int32_t v = 0; v < nc; ++v) {
        map[v] = -1;
        for (int32_t w = 0; w < nf && map[v] < 0; ++w)
            if (fabs(xc[3 * v] - xf[3 * w]) + fabs(xc[3 * v + 1] - xf[3 * w + 1]) + fabs(xc[3 * v + 2] - xf[3 * w + 2]) <
                1e-9)
                map[v] = w;
        matched += map[v] >= 0;
    }
    CHECK(matched == nc);
    if (matched == nc) {
        double pi = 3.14159265358979323846;
        double ph = bar_resolution_distance(ctx, mc, mf, map, CF_STRETCH_BEND_HYBRID, 1.5, 0.0);
        double pa = bar_resolution_distance(ctx, mc, mf, map, CF_STRETCH_BEND_ARAP, 1.5, 0.0);
        double pr = bar_resolution_distance(ctx, mc, mf, map, CF_STRETCH_BEND_ARAP_RIMS, 1.5, 0.0);
        CHECK_LE(ph, 0.03);
        CHECK_LE(pa, 0.006);
        CHECK_LE(pr, 0.006);
        double bh = bar_resolution_distance(ctx, mc, mf, map, CF_STRETCH_BEND_HYBRID, 0.0, 0.5 * pi);
        double ba = bar_resolution_distance(ctx, mc, mf, map, CF_STRETCH_BEND_ARAP, 0.0, 0.5 * pi);
        double br = bar_resolution_distance(ctx, mc, mf, map, CF_STRETCH_BEND_ARAP_RIMS, 0.0, 0.5 * pi);
        CHECK_LE(bh, 0.035);
        CHECK(ba > 0.10 && ba > 4.0 * bh);
        CHECK(br > 0.10 && br > 4.0 * bh);
    }
    free(map);
    cf_mesh_destroy(&mc);
    cf_mesh_destroy(&mf);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Bottom face of the 1 x 1 x 4 bar fixed, top face moved by `user` (a
 * double) along x. */
static int pull_rule(int32_t v, const double *p, double *t, const void *user)
{
    (void)v;
    if (!(p[2] < 1e-9 || p[2] > 4.0 - 1e-9)) return 0;
    memcpy(t, p, 3 * sizeof(double));
    if (p[2] > 1.0) t[0] += *(const double *)user;
    return 1;
}

static cf_handle_set *pull_handles(cf_context *ctx, const cf_mesh *mesh, double pull)
{
    return stretch_bend_handles_where(ctx, mesh, pull_rule, &pull);
}

/* The same bar re-triangulated: every square cell of cf_generate_bar
 * (pattern 0, two right triangles) is split into four triangles by its
 * centre. The original vertices keep their indices and positions, so the
 * results can be compared there. (Flipping diagonals instead would not do:
 * the diagonal of a rectangle has cotan weight cot 90 + cot 90 = 0, so any
 * diagonal choice gives the same cotan Laplacian and the same ARAP.) */
static cf_mesh *split_cells(cf_context *ctx, const cf_mesh *mesh)
{
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    const double *x = cf_mesh_positions(mesh);
    const int32_t *tri = cf_mesh_triangles(mesh), *twin = cf_mesh_halfedge_twin(mesh);
    double *px = malloc(sizeof(double) * 3 * (size_t)(nv + nf));
    int32_t *nt = malloc(sizeof(int32_t) * 6 * (size_t)nf);
    int32_t *mid = malloc(sizeof(int32_t) * (size_t)nf);
    memcpy(px, x, sizeof(double) * 3 * (size_t)nv);
    int32_t n = nv;
    for (int32_t f = 0; f < nf; ++f) mid[f] = -1;
    for (int32_t f = 0; f < nf; ++f) {
        /* Right-angle corner c; the diagonal runs a -> b opposite it. */
        int c = 0;
        for (int k = 0; k < 3; ++k) {
            const double *p = x + 3 * tri[3 * f + k], *q = x + 3 * tri[3 * f + (k + 1) % 3],
                         *r = x + 3 * tri[3 * f + (k + 2) % 3];
            double d = (q[0] - p[0]) * (r[0] - p[0]) + (q[1] - p[1]) * (r[1] - p[1]) + (q[2] - p[2]) * (r[2] - p[2]);
            if (fabs(d) < 1e-12) c = k;
        }
        int32_t h = 3 * f + (c + 1) % 3, g = twin[h];
        int32_t a = tri[h], b = tri[3 * f + (c + 2) % 3], cv = tri[3 * f + c];
        int32_t m;
        if (g >= 0 && mid[g / 3] >= 0) {
            m = mid[g / 3];
        } else {
            m = n++;
            for (int d = 0; d < 3; ++d) px[3 * m + d] = 0.5 * (x[3 * a + d] + x[3 * b + d]);
        }
        mid[f] = m;
        int32_t *o = nt + 6 * f;
        o[0] = a; o[1] = m; o[2] = cv;
        o[3] = m; o[4] = b; o[5] = cv;
    }
    cf_mesh_desc desc = {0};
    desc.vertex_count = n;
    desc.positions = px;
    desc.face_count = 2 * nf;
    desc.triangles = nt;
    cf_mesh *out = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &desc, &out));
    free(px);
    free(nt);
    free(mid);
    return out;
}

/* Max distance between two results at the first nv vertices, relative to
 * the bar's diagonal. */
static double bar_distance(cf_context *ctx, const cf_mesh *m0, const cf_mesh *m1, cf_stretch_bend_energy_kind e, const char *what)
{
    cf_handle_set *h0 = pull_handles(ctx, m0, 1.5), *h1 = pull_handles(ctx, m1, 1.5);
    int32_t nv = cf_mesh_vertex_count(m0);
    double *y0 = solve(ctx, m0, h0, e, 3000);
    double *y1 = solve(ctx, m1, h1, e, 3000);
    double worst = 0.0;
    for (int32_t v = 0; v < nv; ++v) {
        const double *a = y0 + 3 * v, *b = y1 + 3 * v;
        worst = fmax(worst, sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                                 (a[2] - b[2]) * (a[2] - b[2])));
    }
    double d = worst / sqrt(1.0 + 1.0 + 16.0);
    fprintf(stderr, "  bar %-9s %s: max distance %.5f of the diagonal\n", cf_stretch_bend_energy_name(e), what, d);
    free(y0);
    free(y1);
    cf_handle_set_destroy(&h0);
    cf_handle_set_destroy(&h1);
    return d;
}

/* The bar with every face-interior vertex moved within its face by up to
 * `amp` cells (a deterministic hash of the index), so the surface is the
 * same box but the triangles are irregular (some obtuse, with negative
 * cotan weights); `pattern` picks the diagonals as in cf_generate_bar. */
static cf_mesh *jittered_bar(cf_context *ctx, int32_t pattern, double amp)
{
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bar(ctx, 3, 3, 12, 1.0, 1.0, 4.0, pattern, &m));
    if (!m) return NULL;
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    double *p = malloc(sizeof(double) * 3 * (size_t)nv);
    memcpy(p, cf_mesh_positions(m), sizeof(double) * 3 * (size_t)nv);
    const double cell[3] = {1.0 / 3, 1.0 / 3, 4.0 / 12}, len[3] = {1.0, 1.0, 4.0};
    for (int32_t v = 0; v < nv; ++v) {
        int on_side[3], sides = 0;
        for (int d = 0; d < 3; ++d) {
            on_side[d] = fabs(p[3 * v + d]) < 1e-9 || fabs(p[3 * v + d] - len[d]) < 1e-9;
            sides += on_side[d];
        }
        if (sides != 1) continue; /* edges and corners stay */
        uint32_t hsh = (uint32_t)v * 2654435761u + 12345u;
        for (int d = 0; d < 3; ++d) {
            hsh = hsh * 1664525u + 1013904223u;
            double r = 2.0 * (double)(hsh >> 8) / (double)(1u << 24) - 1.0;
            if (!on_side[d]) p[3 * v + d] += amp * cell[d] * r;
        }
    }
    cf_mesh_desc desc = {0};
    desc.vertex_count = nv;
    desc.positions = p;
    desc.face_count = nf;
    desc.triangles = cf_mesh_triangles(m);
    cf_mesh *out = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &desc, &out));
    free(p);
    cf_mesh_destroy(&m);
    return out;
}

/* Fig. 4: the top of a 1 x 1 x 4 bar pulled sideways by 1.5, bottom fixed,
 * under (a) the other diagonal in every other cell (cf_generate_bar
 * pattern 1) and (b) every cell split in four by its centre.
 * Measured (see docs/edit.md): (a) ARAP is unchanged to round-off — the
 * rectangle diagonals carry zero cotan weight, so the Laplacian does not
 * see the flip — hybrid moves by 0.2% of the diagonal and spokes-and-rims
 * by 0.4% (its rim sets change); (b) hybrid 1.5%, ARAP 0.3%, rims 0.4%.
 * On these regular grids ARAP is the least sensitive of the three. The
 * paper's claim shows on an irregular triangulation: (c) the bar's face
 * vertices moved within their faces by up to 0.35 cells (same surface,
 * some obtuse triangles), the two diagonal patterns of it compared: ARAP
 * moves by 4.9% of the diagonal, hybrid by 0.9%, spokes-and-rims by 2.9%
 * (Eq. 7's full edge weights go negative on non-Delaunay edges, so it is
 * less robust here than the paper's figure suggests). Below 0.3 cells of
 * jitter (no obtuse triangles) ARAP moves by less than 0.2%. The test
 * bounds the measured behaviour so a regression in any energy shows. */
static void test_bar_retriangulation(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m0 = NULL, *m1 = NULL, *m2 = NULL;
    CHECK_OK(ctx, cf_generate_bar(ctx, 3, 3, 12, 1.0, 1.0, 4.0, 0, &m0));
    CHECK_OK(ctx, cf_generate_bar(ctx, 3, 3, 12, 1.0, 1.0, 4.0, 1, &m1));
    if (!m0 || !m1) return;
    m2 = split_cells(ctx, m0);
    if (!m2) return;
    int32_t nv = cf_mesh_vertex_count(m0);
    CHECK(cf_mesh_vertex_count(m1) == nv);
    CHECK(cf_mesh_vertex_count(m2) == nv + cf_mesh_face_count(m0) / 2);
    const double *x0 = cf_mesh_positions(m0), *x1 = cf_mesh_positions(m1);
    double same = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) same = fmax(same, fabs(x0[i] - x1[i]));
    CHECK(same == 0.0);
    CHECK_LE(bar_distance(ctx, m0, m1, CF_STRETCH_BEND_ARAP, "diagonal flip"), 1e-9);
    CHECK_LE(bar_distance(ctx, m0, m1, CF_STRETCH_BEND_HYBRID, "diagonal flip"), 4e-3);
    CHECK_LE(bar_distance(ctx, m0, m1, CF_STRETCH_BEND_ARAP_RIMS, "diagonal flip"), 1e-2);
    CHECK_LE(bar_distance(ctx, m0, m2, CF_STRETCH_BEND_HYBRID, "cells split in 4"), 0.03);
    CHECK_LE(bar_distance(ctx, m0, m2, CF_STRETCH_BEND_ARAP, "cells split in 4"), 0.01);
    CHECK_LE(bar_distance(ctx, m0, m2, CF_STRETCH_BEND_ARAP_RIMS, "cells split in 4"), 0.01);
    cf_mesh *j0 = jittered_bar(ctx, 0, 0.35), *j1 = jittered_bar(ctx, 1, 0.35);
    if (j0 && j1) {
        double dh = bar_distance(ctx, j0, j1, CF_STRETCH_BEND_HYBRID, "irregular, diagonal flip");
        double da = bar_distance(ctx, j0, j1, CF_STRETCH_BEND_ARAP, "irregular, diagonal flip");
        double dr = bar_distance(ctx, j0, j1, CF_STRETCH_BEND_ARAP_RIMS, "irregular, diagonal flip");
        CHECK_LE(dh, 0.015);
        CHECK(da > 0.03);
        CHECK(da > 3.0 * dh);
        CHECK(dr < da);
    }
    cf_mesh_destroy(&j0);
    cf_mesh_destroy(&j1);
    cf_mesh_destroy(&m0);
    cf_mesh_destroy(&m1);
    cf_mesh_destroy(&m2);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_sheet_twist_resolution);
    CFT_RUN(test_bar_resolution);
    CFT_RUN(test_bar_retriangulation);
    return cft_finish();
}
