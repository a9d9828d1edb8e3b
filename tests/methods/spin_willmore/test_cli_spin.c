/*
 * The command-line front ends of this method: `curvflow spin` (SpinXForm
 * from a rho file or a PLY vertex property), `curvflow curve` (CSV / SVG
 * polylines) and `curvflow flow --method spin-willmore`. Exit codes as in
 * cli/cli.h: 0 ok, 1 usage, 2 input.
 */
#include "test.h"

#include "curvflow/curve_flow.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"

#include <stdlib.h>
#include <sys/wait.h>

static int run_cli(const char *args)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "OMP_THREAD_LIMIT=1 '%s' %s > /dev/null 2>&1", CF_TEST_CLI, args);
    int st = system(cmd);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static void test_spin_cli(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.2, 2u, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    char in[512], rho[512], out[512], args[2048];
    snprintf(in, sizeof in, "%s", cft_temp_path(".obj"));
    snprintf(rho, sizeof rho, "%s", cft_temp_path(".txt"));
    snprintf(out, sizeof out, "%s", cft_temp_path(".ply"));
    CHECK_OK(ctx, cf_write_mesh_file(ctx, in, mesh, NULL, NULL, 0));
    FILE *fp = fopen(rho, "w");
    fprintf(fp, "# rho = 0: the output is the input up to a similarity\n");
    for (int32_t i = 0; i < nv; ++i) fprintf(fp, "0\n");
    fclose(fp);
    snprintf(args, sizeof args, "spin '%s' --rho '%s' -o '%s'", in, rho, out);
    CHECK(run_cli(args) == 0);
    cf_mesh *res = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, out, &res));
    if (res) {
        double r[9], s, t[3], rms = 1.0;
        CHECK_OK(ctx, cf_similarity_align(ctx, nv, cf_mesh_positions(mesh), cf_mesh_positions(res), NULL, 1, r, &s, t, &rms));
        CHECK_LE(rms, 1e-7);
        cf_mesh_destroy(&res);
    }
    /* rho as a PLY vertex property: a small bump of curvature change */
    {
        char ply[512];
        snprintf(ply, sizeof ply, "%s", cft_temp_path(".ply"));
        double *field = calloc((size_t)nv, sizeof(double));
        for (int32_t i = 0; i < nv; ++i) field[i] = cf_mesh_positions(mesh)[3 * i + 2] > 0.5 ? 0.5 : 0.0;
        cf_field f = {"rho", CF_FIELD_VERTEX, field};
        CHECK_OK(ctx, cf_write_mesh_file(ctx, ply, mesh, NULL, &f, 1));
        snprintf(args, sizeof args, "spin '%s' --rho rho -o '%s'", ply, out);
        CHECK(run_cli(args) == 0);
        CHECK_OK(ctx, cf_load_mesh(ctx, out, &res));
        if (res) {
            double r[9], s2, t[3], rms = 0.0;
            CHECK_OK(ctx, cf_similarity_align(ctx, nv, cf_mesh_positions(mesh), cf_mesh_positions(res), NULL, 1, r, &s2, t, &rms));
            CHECK(rms > 1e-4);   /* the surface did change */
            cf_mesh_destroy(&res);
        }
        free(field);
    }
    /* wrong count of values -> input error; missing --rho -> usage */
    fp = fopen(rho, "w");
    fprintf(fp, "1 2 3\n");
    fclose(fp);
    snprintf(args, sizeof args, "spin '%s' --rho '%s' -o '%s'", in, rho, out);
    CHECK(run_cli(args) == 2);
    snprintf(args, sizeof args, "spin '%s' -o '%s'", in, out);
    CHECK(run_cli(args) == 1);
    /* the flow through the common interface, with a method parameter */
    snprintf(args, sizeof args, "flow '%s' -o '%s' --method spin-willmore --steps 2 -p sigma=0.05 -q", in, out);
    CHECK(run_cli(args) == 0);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_curve_cli(void)
{
    cf_context *ctx = cft_context();
    char in[512], out[512], args[2048];
    snprintf(in, sizeof in, "%s", cft_temp_path(".csv"));
    snprintf(out, sizeof out, "%s", cft_temp_path(".svg"));
    FILE *fp = fopen(in, "w");
    fprintf(fp, "x,y\n");
    for (int i = 0; i < 60; ++i) {
        double t = 2 * 3.14159265358979323846 * i / 60, r = 1.0 + 0.2 * sin(3 * t);
        fprintf(fp, "%.17g,%.17g\n", r * cos(t), r * sin(t));
    }
    fclose(fp);
    snprintf(args, sizeof args, "curve '%s' -o '%s' --steps 3 --time-step 0.5", in, out);
    CHECK(run_cli(args) == 0);
    cf_curve *c = NULL;
    CHECK_OK(ctx, cf_curve_read(ctx, out, &c));
    CHECK(c && c->count == 60);
    cf_curve_destroy(&c);
    snprintf(args, sizeof args, "curve '%s' -o '%s' --time-step -1", in, out);
    CHECK(run_cli(args) == 1);
    snprintf(args, sizeof args, "curve '%s.missing' -o '%s'", in, out);
    CHECK(run_cli(args) == 2);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_spin_cli);
    CFT_RUN(test_curve_cli);
    return cft_finish();
}
