/*
 * The command-line front ends of this method: `curvflow spin` (SpinXForm
 * from a rho file or a PLY vertex property), `curvflow curve` (CSV / SVG
 * polylines) and `curvflow flow --method spin-willmore` (with per-vertex
 * boundary targets from a file). Exit codes as in
 * cli/cli.h: 0 ok, 1 usage, 2 input.
 */
#include "test.h"
#include "spin_test_util.h"

#include "curvflow/curve_flow.h"
#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/spin_willmore.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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
        /* a file of the property's name beside it: which one is meant is
         * not guessed (the property won silently); ./rho is the file */
        char dir[512], rho_file[600], cmd[4096];
        snprintf(dir, sizeof dir, "%s", ply);
        char *slash = strrchr(dir, '/');
        if (slash) *slash = '\0';
        snprintf(rho_file, sizeof rho_file, "%s/rho", dir);
        FILE *rf = fopen(rho_file, "w");
        for (int32_t i = 0; rf && i < nv; ++i) fprintf(rf, "0\n");
        if (rf) fclose(rf);
        for (int k = 0; k < 2; ++k) {
            snprintf(cmd, sizeof cmd, "cd '%s' && OMP_THREAD_LIMIT=1 '%s' spin '%s' --rho %s -o '%s' > /dev/null 2>&1", dir,
                     CF_TEST_CLI, ply, k == 0 ? "rho" : "./rho", out);
            int st = system(cmd);
            CHECK(WIFEXITED(st) && WEXITSTATUS(st) == (k == 0 ? 1 : 0));
        }
        CHECK_OK(ctx, cf_load_mesh(ctx, out, &res));
        if (res) { /* the file's rho = 0: the input up to a similarity */
            double r[9], s3, t[3], rms = 1.0;
            CHECK_OK(ctx, cf_similarity_align(ctx, nv, cf_mesh_positions(mesh), cf_mesh_positions(res), NULL, 1, r, &s3, t, &rms));
            CHECK_LE(rms, 1e-7);
            cf_mesh_destroy(&res);
        }
        remove(rho_file);
        /* what the input carries is written with the result, as flow's (session 30; spin wrote the
         * positions and rho only): its properties, with the new rho in place of an old one */
        double *red = malloc((size_t)nv * sizeof *red);
        for (int32_t i = 0; i < nv; ++i) red[i] = (double)((3 * i) % 256);
        cf_field two[2] = {{"rho", CF_FIELD_VERTEX, field}, {"red", CF_FIELD_VERTEX, red}};
        CHECK_OK(ctx, cf_write_mesh_file(ctx, ply, mesh, NULL, two, 2));
        snprintf(args, sizeof args, "spin '%s' --rho rho --scale 2 -o '%s'", ply, out);
        CHECK(run_cli(args) == 0);
        cf_mesh_data *d = NULL;
        CHECK_OK(ctx, cf_read_mesh_file(ctx, out, &d));
        const cf_mesh_property *pr = d ? cf_mesh_data_vertex_property(d, "red") : NULL;
        const cf_mesh_property *prho = d ? cf_mesh_data_vertex_property(d, "rho") : NULL;
        CHECK(pr && memcmp(pr->values, red, (size_t)nv * sizeof *red) == 0);
        CHECK(d && d->vertex_property_count == 2);
        for (int32_t i = 0; prho && i < nv; ++i) CHECK(prho->values[i] == 2.0 * field[i]); /* the rho applied */
        cf_mesh_data_destroy(&d);
        free(red);
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

/* `curvflow flow --boundary-targets FILE` (Sec. 6.3.1): targets that rotate
 * the binormals of the cylinder's rim 1 by 0.4 rad about x give the same
 * surface as the library's boundary_angle rule; bad files are input errors
 * that name the line or vertex. */
static void test_boundary_targets_cli(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 24, 12, 1.0, 2.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    const int32_t *off = cf_mesh_boundary_loop_offsets(mesh), *lv = cf_mesh_boundary_loop_vertices(mesh);
    const double xaxis[3] = {1.0, 0.0, 0.0};
    double *targets = boundary_vectors(ctx, mesh, cf_mesh_positions(mesh), 0.0);
    CHECK(targets != NULL);
    if (!targets) return;
    for (int32_t k = off[1]; k < off[2]; ++k) rotate(targets + 3 * lv[k], xaxis, 0.4);
    char in[512], tf[512], out[512], args[2048];
    snprintf(in, sizeof in, "%s", cft_temp_path(".obj"));
    snprintf(tf, sizeof tf, "%s", cft_temp_path(".txt"));
    snprintf(out, sizeof out, "%s", cft_temp_path(".obj"));
    CHECK_OK(ctx, cf_write_mesh_file(ctx, in, mesh, NULL, NULL, 0));
    FILE *fp = fopen(tf, "w");
    fprintf(fp, "# vertex x y z: rim 1 rotated by 0.4 rad about x\n");
    for (int32_t k = 0; k < off[2]; ++k) {
        const double *t = targets + 3 * lv[k];
        fprintf(fp, "%d %.17g %.17g %.17g\n", lv[k], t[0], t[1], t[2]);
    }
    fclose(fp);
    snprintf(args, sizeof args, "flow '%s' -o '%s' --method spin-willmore --steps 3 --boundary-targets '%s' -q", in, out, tf);
    CHECK(run_cli(args) == 0);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    cf_spin_willmore_options *so = cf_flow_options_method(&o);
    so->boundary_mode = CF_SPIN_BOUNDARY_PRESCRIBED;
    so->boundary_angle = 0.4;
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (flow) CHECK_OK(ctx, cf_flow_run(flow, 3, NULL));
    cf_mesh *res = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, out, &res));
    if (res && flow) {
        double diff = 0.0, moved = 0.0;
        for (int32_t i = 0; i < 3 * nv; ++i) {
            diff = fmax(diff, fabs(cf_mesh_positions(res)[i] - cf_flow_positions(flow)[i]));
            moved = fmax(moved, fabs(cf_mesh_positions(res)[i] - cf_mesh_positions(mesh)[i]));
        }
        fprintf(stderr, "   --boundary-targets vs boundary_angle 0.4: max |dx| %.2g (moved %.3f)\n", diff, moved);
        CHECK_LE(diff, 1e-9);
        CHECK(moved > 0.05);
    }
    cf_mesh_destroy(&res);
    cf_flow_destroy(&flow);
    /* a boundary vertex left out, an interior vertex, a malformed line: input errors */
    static const char *const bad[] = {"missing", "interior", "malformed", "twice"};
    for (int b = 0; b < 4; ++b) {
        fp = fopen(tf, "w");
        for (int32_t k = b == 0 ? 1 : 0; k < off[2]; ++k) {
            const double *t = targets + 3 * lv[k];
            fprintf(fp, "%d %.17g %.17g %.17g\n", lv[k], t[0], t[1], t[2]);
        }
        if (b == 1) fprintf(fp, "%d 1 0 0\n", lv[off[0]] + 24); /* the next ring up is interior */
        if (b == 2) fprintf(fp, "%d 1 0\n", lv[0]);
        if (b == 3) fprintf(fp, "%d 1 0 0\n", lv[0]);
        fclose(fp);
        snprintf(args, sizeof args, "flow '%s' -o '%s' --method spin-willmore --boundary-targets '%s' -q", in, out, tf);
        int code = run_cli(args);
        if (code != 2) fprintf(stderr, "   %s targets: exit %d, expected 2\n", bad[b], code);
        CHECK(code == 2);
    }
    /* targets with another method or another boundary mode: usage errors */
    snprintf(args, sizeof args, "flow '%s' -o '%s' --method implicit-mcf --boundary-targets '%s' -q", in, out, tf);
    CHECK(run_cli(args) == 1);
    snprintf(args, sizeof args, "flow '%s' -o '%s' --method spin-willmore -p boundary=fixed --boundary-targets '%s' -q", in, out, tf);
    CHECK(run_cli(args) == 1);
    free(targets);
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
    CFT_RUN(test_boundary_targets_cli);
    CFT_RUN(test_curve_cli);
    return cft_finish();
}
