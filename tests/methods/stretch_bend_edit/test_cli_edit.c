/*
 * `curvflow edit` end to end: generate a bar, edit it with a JSON handle
 * file, check the handle vertices of the written mesh sit on their targets,
 * continue from the result with --start, and the exit status 2 with a
 * message naming the problem for bad handle files (1 for usage errors);
 * warnings (exit 0) for an unknown top-level key and a set without a name.
 */
#define _POSIX_C_SOURCE 200809L
#include "test.h"

#include "curvflow/io.h"
#include "curvflow/mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

static char err_text[1 << 14];

static int run(const char *args)
{
    const char *errpath = cft_temp_path(".stderr");
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "'%s' %s 2> '%s' > /dev/null", CF_TEST_CLI, args, errpath);
    int st = system(cmd);
    err_text[0] = '\0';
    FILE *f = fopen(errpath, "rb");
    if (f) {
        size_t n = fread(err_text, 1, sizeof err_text - 1, f);
        err_text[n] = '\0';
        fclose(f);
        remove(errpath);
    }
    if (st == -1 || !WIFEXITED(st)) return -1;
    return WEXITSTATUS(st);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    CHECK(f != NULL);
    if (!f) return;
    fputs(text, f);
    fclose(f);
}

static void test_edit_command(void)
{
    cf_context *ctx = cft_context();
    char bar[1024], out[1024], out2[1024], hj[1024], bad[1024], args[8192];
    snprintf(bar, sizeof bar, "%s", cft_temp_path("_bar.obj"));
    snprintf(out, sizeof out, "%s", cft_temp_path("_out.obj"));
    snprintf(out2, sizeof out2, "%s", cft_temp_path("_out2.obj"));
    snprintf(hj, sizeof hj, "%s", cft_temp_path("_h.json"));
    snprintf(bad, sizeof bad, "%s", cft_temp_path("_bad.json"));
    snprintf(args, sizeof args, "generate bar --nx 8 --ny 2 --nz 2 --width 4 -o '%s'", bar);
    CHECK(run(args) == 0);
    write_text(hj, "{\"sets\": [\n"
                   "  {\"name\": \"left\", \"relative_box\": {\"min\": [0,0,0], \"max\": [0,1,1]}, \"fixed\": true},\n"
                   "  {\"name\": \"right\", \"relative_box\": {\"min\": [1,0,0], \"max\": [1,1,1]},\n"
                   "   \"transform\": {\"translate\": [0, 0, 1]}}]}\n");
    for (int e = 0; e < 5; ++e) {
        static const char *const names[] = {"hybrid", "stretch", "bend", "arap", "arap-rims"};
        snprintf(args, sizeof args, "edit '%s' --handles '%s' --energy %s --iterations 20 -q -o '%s'", bar, hj,
                 names[e], out);
        int rc = run(args);
        CHECK(rc == 0);
        if (rc != 0) fprintf(stderr, "%s\n", err_text);
    }
    /* The right end (x = 4) moved up by 1, the left end kept. */
    cf_mesh *m0 = NULL, *m1 = NULL;
    int32_t right = -1;
    CHECK_OK(ctx, cf_load_mesh(ctx, bar, &m0));
    CHECK_OK(ctx, cf_load_mesh(ctx, out, &m1));
    if (m0 && m1) {
        const double *x0 = cf_mesh_positions(m0), *x1 = cf_mesh_positions(m1);
        int ends = 0;
        for (int32_t v = 0; v < cf_mesh_vertex_count(m0); ++v) {
            if (x0[3 * v] > 4.0 - 1e-9) {
                CHECK_NEAR(x1[3 * v + 2], x0[3 * v + 2] + 1.0, 0.0, 1e-5); /* OBJ keeps ~9 digits */
                right = v;
                ++ends;
            } else if (x0[3 * v] < 1e-9) {
                CHECK_NEAR(x1[3 * v + 2], x0[3 * v + 2], 0.0, 1e-5);
                ++ends;
            }
        }
        CHECK(ends == 2 * 9);
    }
    cf_mesh_destroy(&m0);
    cf_mesh_destroy(&m1);
    /* Continue from the result: the handle file is applied to it. */
    snprintf(args, sizeof args, "edit '%s' --start '%s' --handles '%s' --energy arap -n 10 -q -o '%s'", bar, out, hj,
             out2);
    CHECK(run(args) == 0);
    CHECK_OK(ctx, cf_load_mesh(ctx, out2, &m1));
    CHECK(right >= 0);
    if (m1 && right >= 0) {
        const double *x1 = cf_mesh_positions(m1);
        CHECK(x1[3 * right + 2] > 1.9); /* the right end moved up twice (z in [0, 1] at rest) */
    }
    cf_mesh_destroy(&m1);

    write_text(bad, "{\"sets\": [{\"name\": \"tip\", \"vertices\": [1, 100000], \"fixed\": true}]}");
    snprintf(args, sizeof args, "edit '%s' --handles '%s' -o '%s'", bar, bad, out);
    CHECK(run(args) == 2);
    CHECK(strstr(err_text, "unknown vertex 100000") != NULL);
    write_text(bad, "{\"sets\": [}");
    CHECK(run(args) == 2);
    CHECK(strstr(err_text, "malformed JSON") != NULL);
    /* issue 15: what the reader ignores is said (a warning, exit 0) */
    write_text(bad, "{\"version\": 1, \"sets\": [{\"relative_box\": {\"min\": [0,0,0], \"max\": [0,1,1]}, "
                    "\"fixed\": true}, {\"name\": \"r\", \"relative_box\": {\"min\": [1,0,0], \"max\": [1,1,1]}, "
                    "\"transform\": {\"translate\": [0, 0, 1]}}]}");
    snprintf(args, sizeof args, "edit '%s' --handles '%s' -n 2 -q -o '%s'", bar, bad, out);
    CHECK(run(args) == 0);
    CHECK(strstr(err_text, "warning: ") != NULL);
    CHECK(strstr(err_text, "unknown top-level key 'version' ignored") != NULL);
    CHECK(strstr(err_text, "set #0 has no \"name\"") != NULL);
    snprintf(args, sizeof args, "edit '%s' --handles '%s' --energy twist -o '%s'", bar, hj, out);
    CHECK(run(args) == 1);
    CHECK(strstr(err_text, "unknown energy 'twist'") != NULL);
    snprintf(args, sizeof args, "edit '%s' -o '%s'", bar, out);
    CHECK(run(args) == 1);
    remove(bar);
    remove(out);
    remove(out2);
    remove(hj);
    remove(bad);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_edit_command);
    return cft_finish();
}
