/*
 * A mesh far from the origin (a georeferenced scan: coordinates near 1e6
 * with detail at 1e-3 of that) flows and edits as the same mesh at the
 * origin, moved. Every method is translation-invariant; in double precision
 * the coordinates then keep only ~1e-10 of absolute resolution, and an
 * operator applied through its diagonal, or a system solved for the new
 * positions rather than for the step, loses the detail to cancellation.
 * Measured on spot_3k moved by 1e6 before the fixes: 10 implicit
 * bi-Laplacian steps ended 0.19 of spot's size off (stopped at step 10 on
 * energy "rises" that were rounding); implicit MCF 2.8e-8; the hybrid edit
 * 2.5 % off with an energy 23 % higher. Now the baseline flows take L x and
 * the right-hand side of their implicit step from coordinate differences
 * (cf_sparse_multiply_zero_row_sums) and solve for the displacement, and
 * the edit iterates in coordinates relative to its rest pose's centre.
 *
 * The bumpy sphere here (radius ~1, 642 vertices) moved by (1e6, -2e6, 5e5):
 * every baseline flow (10 default steps) ends at the same positions,
 * moved, to the bound given with each, and after the same number of steps;
 * spin-willmore (5 steps) too, at eight offsets (its difference is the
 * rounding of the moved state amplified: test_spin_offsets); the edit
 * (ARAP, hybrid with its Anderson acceleration, bend; 20 iterations) too.
 * The bounds are a few times what the fixed code measures (printed) and
 * far below what the unfixed code gave (also printed in the comments of
 * each row).
 */
#include "test.h"

#include "curvflow/baseline_flows.h"
#include "curvflow/constraints.h"
#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/mesh.h"
#include "curvflow/stretch_bend_edit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double offset[3] = {1e6, -2e6, 5e5};

/* The same mesh moved by `by`. */
static cf_mesh *moved_copy_by(cf_context *ctx, const cf_mesh *mesh, const double by[3])
{
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    double *p = malloc(sizeof(double) * 3 * (size_t)nv);
    const double *q = cf_mesh_positions(mesh);
    for (int32_t i = 0; i < 3 * nv; ++i) p[i] = q[i] + by[i % 3];
    cf_mesh_desc d = {.vertex_count = nv, .positions = p, .face_count = nf, .triangles = cf_mesh_triangles(mesh)};
    cf_mesh *out = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &out));
    free(p);
    return out;
}

static cf_mesh *moved_copy(cf_context *ctx, const cf_mesh *mesh) { return moved_copy_by(ctx, mesh, offset); }

/* Runs `steps` steps; the positions (malloc'd) and the steps taken. */
static double *run(cf_context *ctx, const cf_mesh *mesh, const cf_flow_options *o, int64_t steps, int64_t *taken)
{
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, o, &flow));
    if (!flow) return NULL;
    cf_flow_info info;
    memset(&info, 0, sizeof info);
    CHECK_OK(ctx, cf_flow_run(flow, steps, &info));
    *taken = info.iteration;
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *x = malloc(sizeof(double) * 3 * (size_t)nv);
    memcpy(x, cf_flow_positions(flow), sizeof(double) * 3 * (size_t)nv);
    cf_flow_destroy(&flow);
    return x;
}

/* Largest |x_far - by - x_near| over the near mesh's size (radius ~1). */
static double moved_difference_by(const double *near, const double *far, int32_t nv, const double by[3])
{
    double d = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) d = fmax(d, fabs(far[i] - by[i % 3] - near[i]));
    return d;
}

static double moved_difference(const double *near, const double *far, int32_t nv)
{
    return moved_difference_by(near, far, nv, offset);
}

static void compare(cf_context *ctx, const cf_mesh *near, const cf_mesh *far, const cf_flow_options *o_near,
                    const cf_flow_options *o_far, int64_t steps, const char *what, double bound)
{
    int64_t taken_near = -1, taken_far = -2;
    double *a = run(ctx, near, o_near, steps, &taken_near);
    double *b = run(ctx, far, o_far, steps, &taken_far);
    if (!a || !b) {
        free(a);
        free(b);
        return;
    }
    double d = moved_difference(a, b, cf_mesh_vertex_count(near));
    fprintf(stderr, "   %-34s %lld / %lld steps, moved difference %.3g (bound %.2g)\n", what, (long long)taken_near,
            (long long)taken_far, d, bound);
    CHECK(taken_near == taken_far);
    CHECK_LE(d, bound);
    free(a);
    free(b);
}

static void test_flows(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *near = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.3, 1, &near));
    cf_mesh *far = moved_copy(ctx, near);
    /* Positions near 2e6 are rounded to 2.3e-10. Measured, fixed / before:
     * explicit MCF 6.2e-10 / 1.8e-9, implicit MCF 5.4e-10 / 1.1e-8, cMCF
     * 2.2e-10 / 5.5e-9, explicit bi-Laplacian 7.2e-10 / 8.8e-10, implicit
     * bi-Laplacian 6.6e-10 / 5.9e-8 (spin-willmore: test_spin_offsets). */
    static const struct {
        cf_flow_kind kind;
        int64_t steps;
        double bound;
    } rows[] = {
        {CF_FLOW_EXPLICIT_MCF, 10, 1.5e-9},        {CF_FLOW_IMPLICIT_MCF, 10, 3e-9},
        {CF_FLOW_CONFORMAL_MCF, 10, 2e-9},         {CF_FLOW_EXPLICIT_BILAPLACIAN, 10, 3e-9},
        {CF_FLOW_IMPLICIT_BILAPLACIAN, 10, 5e-9},
    };
    for (size_t r = 0; r < sizeof rows / sizeof rows[0]; ++r) {
        cf_flow_options o;
        CHECK_OK(ctx, cf_flow_options_default(rows[r].kind, &o));
        char what[64];
        snprintf(what, sizeof what, "%s", cf_flow_kind_name(rows[r].kind));
        compare(ctx, near, far, &o, &o, rows[r].steps, what, rows[r].bound);
    }
    cf_mesh_destroy(&far);
    cf_mesh_destroy(&near);
    cf_context_destroy(&ctx);
}

/* spin-willmore, 5 steps, at eight offsets near that of test_flows. Its
 * curvature is a second difference of the positions, which are rounded to
 * 2.3e-10 at every step (the state is stored moved): the moved difference
 * is that rounding amplified, and varies with how each offset rounds. Its
 * row in test_flows measured 3.3e-9 against a bound of 1e-8, at the first
 * offset only; over these eight offsets it spans 1.8e-9 .. 1.1e-8 with the
 * AMD ordering of X that the flow takes here, and 4.2e-9 .. 1.05e-8 with
 * METIS's (measured in session 41, when X's ordering became a choice: the
 * first offset gives 1.05e-8 there), so a single offset's 1e-8 was within
 * the noise.
 * Asserted: the largest of the eight below 3e-8, and every run takes its 5
 * steps. A cancellation in a solve for positions (what test_flows' fixes
 * removed) leaves 1e-6 and more. */
static void test_spin_offsets(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *near = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.3, 1, &near));
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    int64_t taken_near = -1;
    double *a = near ? run(ctx, near, &o, 5, &taken_near) : NULL;
    double smallest = INFINITY, largest = 0.0;
    for (int k = 0; a && k < 8; ++k) {
        const double by[3] = {offset[0] + k * 12345.678, offset[1] + k * 777.7, offset[2]};
        cf_mesh *far = moved_copy_by(ctx, near, by);
        int64_t taken_far = -2;
        double *b = far ? run(ctx, far, &o, 5, &taken_far) : NULL;
        if (b) {
            double d = moved_difference_by(a, b, cf_mesh_vertex_count(near), by);
            smallest = fmin(smallest, d);
            largest = fmax(largest, d);
            CHECK(taken_far == taken_near && taken_near == 5);
        }
        free(b);
        cf_mesh_destroy(&far);
    }
    fprintf(stderr, "   spin-willmore, 5 steps, 8 offsets: moved difference %.3g .. %.3g (bound 3e-08)\n", smallest,
            largest);
    CHECK(a != NULL);
    CHECK_LE(largest, 3e-8);
    free(a);
    cf_mesh_destroy(&near);
    cf_context_destroy(&ctx);
}

static void test_edit(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *near = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.3, 1, &near));
    cf_mesh *far = moved_copy(ctx, near);
    cf_handle_set *h_near = NULL, *h_far = NULL;
    CHECK_OK(ctx, cf_handle_set_parse_json(ctx, near, cf_mesh_positions(near), cft_turn_top_handles, "near", &h_near));
    CHECK_OK(ctx, cf_handle_set_parse_json(ctx, far, cf_mesh_positions(far), cft_turn_top_handles, "far", &h_far));
    if (!h_near || !h_far) return;
    static const struct {
        cf_stretch_bend_energy_kind energy;
        double bound;
    } rows[] = {/* measured, fixed / before: 4.1e-10 / 1.7e-8, 2.1e-9 / 2.3e-6, 1.9e-9 / 2.3e-6 */
                {CF_STRETCH_BEND_ARAP, 3e-9},
                {CF_STRETCH_BEND_HYBRID, 2e-8},
                {CF_STRETCH_BEND_BEND, 2e-8}};
    for (size_t r = 0; r < sizeof rows / sizeof rows[0]; ++r) {
        cf_flow_options o_near, o_far;
        CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_STRETCH_BEND_EDIT, &o_near));
        cf_stretch_bend_options *s = cf_flow_options_method(&o_near);
        s->energy = rows[r].energy;
        s->handles = h_near;
        o_far = o_near;
        ((cf_stretch_bend_options *)cf_flow_options_method(&o_far))->handles = h_far;
        char what[64];
        snprintf(what, sizeof what, "stretch-bend-edit %s", cf_stretch_bend_energy_name(rows[r].energy));
        compare(ctx, near, far, &o_near, &o_far, 20, what, rows[r].bound);
    }
    cf_handle_set_destroy(&h_near);
    cf_handle_set_destroy(&h_far);
    cf_mesh_destroy(&far);
    cf_mesh_destroy(&near);
    cf_context_destroy(&ctx);
}

/* The case that was seen: spot_3k (diagonal 2.59) 1e6 away, 10 implicit
 * bi-Laplacian steps. Before: stopped at step 10 ("the energy rises at
 * every time step" on rounding: its energy came out 120.401368 against
 * 120.401446 at the origin after one step) and ended 0.19 off; now 2-3e-6, as spot scaled by 1e-6 differs from spot (that flow's
 * own sensitivity to rounding). */
static void test_spot_implicit_bilaplacian(void)
{
    const char *path = cft_optional_shared_mesh("spot_3k.obj");
    if (!path) return;
    cf_context *ctx = cft_context();
    cf_mesh *near = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, path, &near));
    if (!near) return;
    cf_mesh *far = moved_copy(ctx, near);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_IMPLICIT_BILAPLACIAN, &o));
    compare(ctx, near, far, &o, &o, 10, "spot_3k implicit-bilaplacian", 1e-5);
    cf_mesh_destroy(&far);
    cf_mesh_destroy(&near);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_flows);
    CFT_RUN(test_spin_offsets);
    CFT_RUN(test_edit);
    CFT_RUN(test_spot_implicit_bilaplacian);
    return cft_finish();
}
