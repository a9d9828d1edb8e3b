/* Discrete Gauss-Bonnet: sum K_i = 2 pi chi (interior 2 pi - angles,
 * boundary pi - angles) on every shared mesh and on generated ones, to
 * 1e-10 absolute (round-off of ~1e5 atan2 values is ~1e-12). */
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/ops.h"
#include "test.h"

#include <stdlib.h>

#define PI 3.14159265358979323846

static void check_gauss_bonnet(cf_context *ctx, const cf_mesh *m, const char *name)
{
    int32_t nv = cf_mesh_vertex_count(m);
    double *k = malloc(sizeof(double) * nv);
    CHECK_OK(ctx, cf_angle_defect(ctx, m, cf_mesh_positions(m), k));
    long double s = 0;
    for (int32_t v = 0; v < nv; ++v) s += k[v];
    double target = 2 * PI * cf_mesh_euler_characteristic(m);
    fprintf(stderr, "  %-28s chi %3d  sum K - 2 pi chi = %.2e\n", name, cf_mesh_euler_characteristic(m),
            (double)(s - target));
    CHECK_NEAR((double)s, target, 0, 1e-10);
    free(k);
}

static void test_generated(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 3, 1.0, &m));
    if (m) check_gauss_bonnet(ctx, m, "icosphere(3)");
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.4, 20, 9, &m));
    if (m) check_gauss_bonnet(ctx, m, "torus");
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_double_torus(ctx, 2, &m));
    if (m) check_gauss_bonnet(ctx, m, "double torus");
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 11, 4, 1.0, 3.0, &m));
    if (m) check_gauss_bonnet(ctx, m, "cylinder");
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_bumpy_plane(ctx, 10, 1.0, 0.3, 9u, &m));
    if (m) check_gauss_bonnet(ctx, m, "bumpy plane");
    cf_mesh_destroy(&m);
    /* a flat grid: zero at interior vertices, pi/2 at the 4 corners */
    CHECK_OK(ctx, cf_generate_grid(ctx, 5, 3, 1.0, 1.0, &m));
    if (m) {
        double k[24];
        CHECK(cf_mesh_vertex_count(m) == 24);
        CHECK_OK(ctx, cf_angle_defect(ctx, m, cf_mesh_positions(m), k));
        int corners = 0;
        for (int v = 0; v < 24; ++v) {
            if (fabs(k[v] - PI / 2) < 1e-14) ++corners;
            else CHECK_NEAR(k[v], 0.0, 0, 1e-14);
        }
        CHECK(corners == 4);
    }
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_shared_meshes(void)
{
    static const char *names[] = {"spot_3k.obj", "bunny_2k.obj", "bob_5k.obj", "double_torus_315.obj",
                                  "elephant_g3_3k.obj", "armadillo_26k.obj", "cactus_620.obj", "hand_1k.obj",
                                  "chinese_lion_statue_10k.obj", "plane_841.obj", "blade_slivers_8k.obj",
                                  "mushroom_cap_2k.obj", "bunny_scan_35k.obj"};
    /* chi from ../shared/meshes/CHECKS.tsv */
    static const int chi[] = {2, 2, 0, -2, -4, 2, 2, 2, 0, 1, 0, 1, -3};
    if (!cft_shared_mesh_path(names[0])) cft_skip("../shared/meshes is absent");
    cf_context *ctx = cft_context();
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
        cf_mesh *m = NULL;
        CHECK_OK(ctx, cf_load_mesh(ctx, cft_shared_mesh_path(names[i]), &m));
        if (!m) continue;
        CHECK(cf_mesh_euler_characteristic(m) == chi[i]);
        check_gauss_bonnet(ctx, m, names[i]);
        cf_mesh_destroy(&m);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_generated);
    CFT_RUN(test_shared_meshes);
    return cft_finish();
}
