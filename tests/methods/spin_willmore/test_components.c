/*
 * spin-willmore and SpinXForm on a mesh of several connected components
 * (docs/spin.md, "Several connected components"): a file with two objects,
 * as users export scenes.
 *
 * X(rho) is block diagonal over the components. Before they were treated
 * apart, the eigenvector of the whole matrix put its weight on one
 * component and the recovery shrank the other to a point, with exit 0: the
 * eight-armed star next to a round sphere ended with one of them at area 0.
 * Now each component has its own lambda scale, its own total-curvature and
 * inversion constraints and its own placement (centroid, and area with
 * `normalize`). Checked: each component keeps its area and centroid, W falls
 * at every step, the star still reaches the round sphere beside the other
 * component (its W/4pi close to the star's own run), a torus beside it
 * (genus 1, exactness on) keeps its area too, SpinXForm with rho = 0 leaves
 * both components in place, and Moebius balancing, written for one surface,
 * is refused with the count of components.
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/mesh.h"
#include "curvflow/ops.h"
#include "curvflow/spin_willmore.h"
#include "spin_test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FOUR_PI (4.0 * 3.14159265358979323846)

/* a and b in one mesh, b moved by shift along x */
static cf_mesh *merged(cf_context *ctx, const cf_mesh *a, const cf_mesh *b, double shift)
{
    int32_t na = cf_mesh_vertex_count(a), nb = cf_mesh_vertex_count(b);
    int32_t fa = cf_mesh_face_count(a), fb = cf_mesh_face_count(b);
    double *x = malloc(3 * (size_t)(na + nb) * sizeof(double));
    int32_t *t = malloc(3 * (size_t)(fa + fb) * sizeof(int32_t));
    cf_mesh *out = NULL;
    CHECK(x && t);
    if (x && t) {
        memcpy(x, cf_mesh_positions(a), 3 * (size_t)na * sizeof(double));
        memcpy(x + 3 * (size_t)na, cf_mesh_positions(b), 3 * (size_t)nb * sizeof(double));
        for (int32_t i = 0; i < nb; ++i) x[3 * (na + i)] += shift;
        memcpy(t, cf_mesh_triangles(a), 3 * (size_t)fa * sizeof(int32_t));
        for (int32_t k = 0; k < 3 * fb; ++k) t[3 * fa + k] = cf_mesh_triangles(b)[k] + na;
        cf_mesh_desc d = {.vertex_count = na + nb, .positions = x, .face_count = fa + fb, .triangles = t};
        CHECK_OK(ctx, cf_mesh_create(ctx, &d, &out));
    }
    free(x);
    free(t);
    return out;
}

/* Area, area-weighted centroid and W/4pi of the part [first, first + part's
 * vertex count) of x, measured on the part's own mesh. */
typedef struct part_figures {
    double area, centroid[3], w;
} part_figures;

static part_figures measure_part(cf_context *ctx, const cf_mesh *part, const double *x_whole, int32_t first)
{
    part_figures p = {0};
    int32_t nv = cf_mesh_vertex_count(part), nf = cf_mesh_face_count(part);
    const double *x = x_whole + 3 * (size_t)first;
    double *fa = malloc((size_t)nf * sizeof(double));
    CHECK(fa != NULL);
    if (!fa) return p;
    CHECK_OK(ctx, cf_face_areas(ctx, part, x, fa));
    const int32_t *t = cf_mesh_triangles(part);
    for (int32_t f = 0; f < nf; ++f) {
        p.area += fa[f];
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) p.centroid[c] += fa[f] / 3.0 * x[3 * t[3 * f + k] + c];
    }
    for (int c = 0; c < 3; ++c) p.centroid[c] /= p.area;
    double w = NAN;
    CHECK_OK(ctx, cf_willmore_energy(ctx, part, x, &w));
    p.w = w / FOUR_PI;
    (void)nv;
    free(fa);
    return p;
}

/* 10 default steps on a next to b; per part: the figures before and after;
 * the whole run's figures in *run. */
static void run_pair(cf_context *ctx, const cf_mesh *a, const cf_mesh *b, spin_run *run, part_figures before[2],
                     part_figures after[2])
{
    cf_mesh *both = merged(ctx, a, b, 4.0);
    if (!both) return;
    CHECK(cf_mesh_component_count(both) == 2);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, both, NULL, &o, &flow));
    if (!flow) {
        cf_mesh_destroy(&both);
        return;
    }
    int32_t na = cf_mesh_vertex_count(a);
    before[0] = measure_part(ctx, a, cf_mesh_positions(both), 0);
    before[1] = measure_part(ctx, b, cf_mesh_positions(both), na);
    memset(run, 0, sizeof *run);
    run->w0 = run->w = cf_flow_energy(flow) / FOUR_PI;
    run->worst_rise = -INFINITY;
    while (run->steps < 10 && !cf_flow_converged(flow)) {
        cf_flow_info info;
        CHECK_OK(ctx, cf_flow_step(flow, &info));
        double w = cf_flow_energy(flow) / FOUR_PI;
        run->worst_rise = fmax(run->worst_rise, w - run->w);
        run->w = w;
        ++run->steps;
    }
    after[0] = measure_part(ctx, a, cf_flow_positions(flow), 0);
    after[1] = measure_part(ctx, b, cf_flow_positions(flow), na);
    cf_mesh_report report;
    CHECK_OK(ctx, cf_mesh_check_positions(ctx, both, cf_flow_positions(flow), &report));
    run->defects = report.nonfinite_coordinates + report.degenerate_faces;
    cf_flow_destroy(&flow);
    cf_mesh_destroy(&both);
}

/* each part kept its area (normalize) and its centroid */
static void check_parts_kept(const part_figures before[2], const part_figures after[2])
{
    for (int k = 0; k < 2; ++k) {
        CHECK_NEAR(after[k].area / before[k].area, 1.0, 0.0, 1e-9);
        for (int c = 0; c < 3; ++c) CHECK_NEAR(after[k].centroid[c], before[k].centroid[c], 0.0, 1e-6);
    }
}

static void test_star_beside_sphere(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(NULL, cf_context_create(&ctx));
    cf_mesh *star = NULL, *sphere = NULL;
    CHECK_OK(ctx, cf_generate_limb_sphere(ctx, 3, 8, 1.4, 0.22, &star));
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 3, 1.0, &sphere));
    if (!star || !sphere) goto done;
    spin_run pair, alone;
    part_figures before[2], after[2];
    run_pair(ctx, star, sphere, &pair, before, after);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    spin_run_steps(ctx, star, &o, 10, &alone, NULL);
    fprintf(stderr,
            "   star + sphere: W/4pi %.4f -> %.4f in %d steps (star %.4f -> %.4f, alone %.4f -> %.4f; sphere %.4f -> "
            "%.4f); areas %.6g -> %.6g and %.6g -> %.6g\n",
            pair.w0, pair.w, pair.steps, before[0].w, after[0].w, alone.w0, alone.w, before[1].w, after[1].w,
            before[0].area, after[0].area, before[1].area, after[1].area);
    CHECK(pair.steps >= 5);
    CHECK_LE(pair.worst_rise, 0.0);
    CHECK(pair.defects == 0);
    check_parts_kept(before, after);
    /* the star reaches the round sphere beside the other component, as on
     * its own; the sphere stays round */
    CHECK_LE(after[0].w, 1.05);
    CHECK_LE(after[0].w, alone.w + 0.02);
    CHECK_LE(after[1].w, before[1].w + 1e-6);
done:
    cf_mesh_destroy(&star);
    cf_mesh_destroy(&sphere);
    cf_context_destroy(&ctx);
}

static void test_star_beside_torus(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(NULL, cf_context_create(&ctx));
    cf_mesh *star = NULL, *torus = NULL;
    CHECK_OK(ctx, cf_generate_limb_sphere(ctx, 3, 8, 1.4, 0.22, &star));
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.3, 36, 12, &torus));
    if (!star || !torus) goto done;
    spin_run pair;
    part_figures before[2], after[2];
    run_pair(ctx, star, torus, &pair, before, after);
    fprintf(stderr, "   star + torus: W/4pi %.4f -> %.4f in %d steps (star %.4f -> %.4f, torus %.4f -> %.4f)\n", pair.w0,
            pair.w, pair.steps, before[0].w, after[0].w, before[1].w, after[1].w);
    CHECK(pair.steps >= 5);
    CHECK_LE(pair.worst_rise, 0.0);
    CHECK(pair.defects == 0);
    check_parts_kept(before, after);
    CHECK_LE(after[0].w, 1.05);
    /* a torus of revolution is critical in its conformal class: W stays */
    CHECK_LE(after[1].w, before[1].w + 1e-6);
    CHECK(after[1].w > 0.9 * before[1].w);
done:
    cf_mesh_destroy(&star);
    cf_mesh_destroy(&torus);
    cf_context_destroy(&ctx);
}

/* SpinXForm with rho = 0 is a similarity on each component: both stay in
 * place (before, the smaller eigenvalue's component took all of lambda) */
static void test_spin_transform_identity(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(NULL, cf_context_create(&ctx));
    cf_mesh *a = NULL, *b = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.2, 1u, &a));
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 0.5, &b));
    cf_mesh *both = a && b ? merged(ctx, a, b, 3.0) : NULL;
    if (!both) goto done;
    int32_t nv = cf_mesh_vertex_count(both);
    double *rho = calloc((size_t)nv, sizeof(double)), *out = malloc(3 * (size_t)nv * sizeof(double));
    CHECK(rho && out);
    if (rho && out) {
        CHECK_OK(ctx, cf_spin_transform(ctx, both, NULL, rho, out));
        const double *x = cf_mesh_positions(both);
        double worst = 0.0;
        for (int32_t k = 0; k < 3 * nv; ++k) worst = fmax(worst, fabs(out[k] - x[k]));
        fprintf(stderr, "   spin transform, rho = 0, two components: largest move %.3g\n", worst);
        CHECK_LE(worst, 1e-6);
    }
    free(rho);
    free(out);
done:
    cf_mesh_destroy(&both);
    cf_mesh_destroy(&a);
    cf_mesh_destroy(&b);
    cf_context_destroy(&ctx);
}

static void test_mobius_refused(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(NULL, cf_context_create(&ctx));
    cf_mesh *a = NULL, *b = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &a));
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &b));
    cf_mesh *both = a && b ? merged(ctx, a, b, 3.0) : NULL;
    if (both) {
        cf_flow_options o;
        CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
        CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "mobius", "true"));
        cf_flow *flow = NULL;
        CHECK(cf_flow_create(ctx, both, NULL, &o, &flow) == CF_ERR_BAD_MESH);
        CHECK(flow == NULL);
        CHECK(strstr(cf_context_message(ctx), "2 components") != NULL);
    }
    cf_mesh_destroy(&both);
    cf_mesh_destroy(&a);
    cf_mesh_destroy(&b);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_star_beside_sphere);
    CFT_RUN(test_star_beside_torus);
    CFT_RUN(test_spin_transform_identity);
    CFT_RUN(test_mobius_refused);
    return cft_finish();
}
