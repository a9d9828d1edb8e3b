/*
 * Elongated shapes under spin-willmore's defaults (docs/spin.md, "Elongated
 * shapes"): a mesh stretched along one axis, as a CAD export with mixed
 * units or a long bone is.
 *
 * Elongation alone is not what stops the flow: an icosphere (4 subdivisions)
 * stretched 6x and 8x has needle triangles of those aspect ratios and
 * reaches a round sphere in 10 steps (measured W/4pi 2.698 -> 1.024 at mean
 * Q 1.259; 3.457 -> 1.087 at 1.498). What does stop it are thin parts that
 * a conformal map has to absorb: spot_3k stretched 5x along y (horns, ears
 * and legs become spikes) ended at W/4pi 13.89 of 25.90 (issue 13's target is
 * half: 12.95) and stayed there (13.86 after 40 steps), with its extremities
 * crowded to e^-12 .. e^-23 of their area. Since the tangential relaxation is
 * a default on closed genus-0 surfaces (session 36) it ends at 10.84, under
 * the target, with mean Q 1.697 (1.666 without: `relaxation=0`, 13.89).
 * Checked there: what the defaults guarantee (every step lowers W, a valid
 * mesh, no failure) and the figures measured, so that a change in either
 * direction is seen.
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/mesh.h"
#include "curvflow/spin_willmore.h"
#include "spin_test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* mesh with its y coordinates multiplied by `factor` (*out; NULL on failure) */
static void stretched(cf_context *ctx, const cf_mesh *mesh, double factor, cf_mesh **out)
{
    *out = NULL;
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *x = malloc(3 * (size_t)nv * sizeof(double));
    CHECK(x != NULL);
    if (!x) return;
    memcpy(x, cf_mesh_positions(mesh), 3 * (size_t)nv * sizeof(double));
    for (int32_t i = 0; i < nv; ++i) x[3 * i + 1] *= factor;
    cf_mesh_desc desc = {0};
    desc.vertex_count = nv;
    desc.positions = x;
    desc.face_count = cf_mesh_face_count(mesh);
    desc.triangles = cf_mesh_triangles(mesh);
    CHECK_OK(ctx, cf_mesh_create(ctx, &desc, out));
    free(x);
}

/* 10 default steps on mesh stretched by factor; 0 when the run could not be made */
static int run_stretched(cf_context *ctx, const cf_mesh *mesh, double factor, spin_run *r)
{
    cf_mesh *long_mesh = NULL;
    stretched(ctx, mesh, factor, &long_mesh);
    if (!long_mesh) return 0;
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    int made = spin_run_steps(ctx, long_mesh, &o, 10, r, NULL);
    cf_mesh_destroy(&long_mesh);
    return made;
}

static void test_stretched_sphere(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *sphere = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 4, 1.0, &sphere));
    if (!sphere) {
        cf_context_destroy(&ctx);
        return;
    }
    const double factors[2] = {6.0, 8.0};
    /* W/4pi after 10 steps (measured 1.024, 1.087); mean Q of the 6x one
     * (measured 1.259; the 8x one's 1.498 is issue 13's bound itself) */
    const double w_bound[2] = {1.05, 1.12}, q_bound[2] = {1.3, INFINITY};
    for (int k = 0; k < 2; ++k) {
        spin_run r;
        if (!run_stretched(ctx, sphere, factors[k], &r)) continue;
        fprintf(stderr, "   icosphere x%.0f: W/4pi %.4f -> %.4f in %d steps, mean Q %.4f\n", factors[k], r.w0, r.w,
                r.steps, r.mean_q);
        CHECK(r.worst_rise <= 0.0);
        CHECK(r.defects == 0);
        CHECK_LE(r.w, w_bound[k]);
        CHECK_LE(r.w, 0.5 * r.w0); /* issue 13's target */
        CHECK_LE(r.mean_q, q_bound[k]);
    }
    cf_mesh_destroy(&sphere);
    cf_context_destroy(&ctx);
}

static void test_stretched_spot(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "spot_3k.obj", 0)) return;
    spin_run r;
    if (run_stretched(shared.ctx, shared.mesh, 5.0, &r)) {
        fprintf(stderr, "   spot_3k x5: W/4pi %.4f -> %.4f in %d steps, mean Q %.4f\n", r.w0, r.w, r.steps, r.mean_q);
        /* what the defaults guarantee on it */
        CHECK(r.worst_rise <= 0.0);
        CHECK(r.defects == 0);
        /* measured: 25.896 -> 10.838 (mean Q 1.697); 13.890 without the
         * relaxation, above half of W0 */
        CHECK_LE(r.w, 0.45 * r.w0); /* issue 13's target, met with a margin */
        CHECK_LE(r.mean_q, 1.75);
        CHECK(r.mean_q > 1.5); /* the open gap: when this fails, update docs/spin.md */
    }
    cft_shared_case_close(&shared);
}

int main(void)
{
    CFT_RUN(test_stretched_sphere);
    CFT_RUN(test_stretched_spot);
    return cft_finish();
}
