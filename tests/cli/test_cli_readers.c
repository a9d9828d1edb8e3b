/*
 * The input readers under the hostile cases of issue 15, through the built
 * tool: exit codes (2 = invalid input file) and the messages, for header
 * counts that disagree with the data (S1, M8), spin --rho and flow
 * --boundary-targets files with long lines and bad values (S2, E4), a
 * byte-order mark, NUL bytes and huge integers (M6, M7), duplicated faces
 * (M10) and the warning for ignored vertex values.
 */
#define _POSIX_C_SOURCE 200809L
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/mesh.h"
#include "cli_test.h"

#include <dirent.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static void put(const char *name, const void *bytes, size_t n)
{
    FILE *f = fopen(cft_in_dir(name), "wb");
    if (!f || fwrite(bytes, 1, n, f) != n) {
        fprintf(stderr, "cannot write %s\n", name);
        exit(1);
    }
    fclose(f);
}

static void put_text(const char *name, const char *text) { put(name, text, strlen(text)); }

#define TET_V "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
#define TET_F "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"

static void test_header_counts(void)
{
    /* S1: these read as an open two-face mesh, "validation: ok", flow exit 0 */
    put_text("face2.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                          "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n" TET_V
                          TET_F);
    put_text("face2.off", "OFF\n4 2 0\n" TET_V TET_F);
    EXPECT("info face2.ply", 2, "curvflow: face2.ply: line 16: header declares 2 faces, file holds 4");
    EXPECT("info face2.off", 2, "curvflow: face2.off: line 9: header declares 2 faces, file holds 4");
    EXPECT("flow face2.off -o out.obj --method implicit-mcf -n 1 -q", 2, "header declares 2 faces, file holds 4");
    /* binary PLY with trailing bytes, and with a face count too small */
    EXPECT("generate icosphere --subdivisions 1 -o ico.ply", 0, NULL);
    FILE *f = fopen(cft_in_dir("ico.ply"), "ab");
    CHECK(f && fwrite("junk", 1, 4, f) == 4);
    if (f) fclose(f);
    EXPECT("info ico.ply", 2, "curvflow: ico.ply: 4 bytes after the last element");
    /* M8: the mirror case named the wrong thing ("face 0 has 0 vertices") */
    put_text("v3.off", "OFF\n3 4 0\n" TET_V TET_F);
    EXPECT("info v3.off", 2, "curvflow: v3.off: line 6: header declares 3 vertices, file holds 4");
    put_text("f6.off", "OFF\n4 6 0\n" TET_V TET_F);
    EXPECT("info f6.off", 2, "curvflow: f6.off: header declares 6 faces, file holds 4");
}

static void test_bom_nul_huge(void)
{
    /* M6: "unknown keyword '\ufeffv' ignored", then an index error */
    put_text("bom.obj", "\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    EXPECT("info bom.obj", 0, NULL);
    CHECK(strstr(cft_err, "unknown keyword") == NULL);
    put_text("bom.off", "\xEF\xBB\xBFOFF\n4 4 0\n" TET_V TET_F);
    EXPECT("info bom.off", 0, NULL);
    static const char nul[] = "v 0 0 0\nv 1 0\0 0\n";
    put("nul.obj", nul, sizeof nul - 1);
    EXPECT("info nul.obj", 2, "curvflow: nul.obj: line 2: NUL byte at offset 13");
    /* M7: the index as written, not 4611686018427387904 */
    put_text("huge.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999999\n");
    EXPECT("info huge.obj", 2, "line 4: vertex index 99999999999999999999999999 out of range");
    /* ignored input gets a warning */
    put_text("vextra.obj", "v 0 0 0 1 2\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    EXPECT("info vextra.obj", 0, "vextra.obj: line 1: vertex 0 has 5 values");
    /* M10: a duplicated face is named as such */
    put_text("dup.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nf 4 1 2\n");
    EXPECT("info dup.obj", 2, "faces 1 and 4 are the same triangle (vertices 0, 1, 3; same orientation)");
    EXPECT("flow dup.obj -o out.obj --method implicit-mcf -q", 2, "faces 1 and 4 are the same triangle");
}

static void test_rho_file(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(ctx, cf_context_create(&ctx));
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 4, 0.2, 2u, &mesh)); /* 2562 vertices */
    CHECK_OK(ctx, cf_write_mesh_file(ctx, cft_in_dir("bumpy.obj"), mesh, NULL, NULL, 0));
    int32_t nv = cf_mesh_vertex_count(mesh);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
    /* S2: a comment of 4095 characters, then " 5 5 5", then nv - 3 values:
     * the old 4096-byte line buffer read " 5 5 5" as a line of its own and
     * applied it as three rho values (exit 0) */
    size_t cap = 6000 + 3 * (size_t)nv;
    char *text = malloc(cap);
    size_t n = 0;
    text[n++] = '#';
    while (n < 4095) text[n++] = 'c';
    n += (size_t)snprintf(text + n, cap - n, " 5 5 5\n");
    for (int32_t i = 0; i < nv - 3; ++i) n += (size_t)snprintf(text + n, cap - n, "0\n");
    put("rho_short.txt", text, n);
    char msg[128];
    snprintf(msg, sizeof msg, "curvflow: rho_short.txt: holds %d values, expected one per vertex (%d)", nv - 3, nv);
    EXPECT("spin bumpy.obj --rho rho_short.txt -o spun.obj", 2, msg);
    /* with all nv values it is a valid file (was refused: "more than nv values") */
    for (int i = 0; i < 3; ++i) n += (size_t)snprintf(text + n, cap - n, "0\n");
    put("rho_long_comment.txt", text, n);
    EXPECT("spin bumpy.obj --rho rho_long_comment.txt -o spun.obj", 0, NULL);
    free(text);
    /* S2: one comma-separated line of more than 35 KB (was refused) */
    cap = 20 * (size_t)nv + 2;
    text = malloc(cap);
    n = 0;
    for (int32_t i = 0; i < nv; ++i) n += (size_t)snprintf(text + n, cap - n, "%s%.12f", i ? "," : "", 1e-3 * (i % 7));
    text[n++] = '\n';
    CHECK(n > 35000);
    put("rho_one_line.txt", text, n);
    free(text);
    EXPECT("spin bumpy.obj --rho rho_one_line.txt -o spun.obj", 0, NULL);
    put_text("rho_bad.txt", "0\n0 nan\n");
    EXPECT("spin bumpy.obj --rho rho_bad.txt -o spun.obj", 2, "curvflow: rho_bad.txt: line 2: value 2 ('nan') is not finite");
    put_text("rho_word.txt", "0\n0 zero\n");
    EXPECT("spin bumpy.obj --rho rho_word.txt -o spun.obj", 2, "curvflow: rho_word.txt: line 2: bad number 'zero'");
}

static void test_boundary_targets_file(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(ctx, cf_context_create(&ctx));
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 16, 6, 1.0, 2.0, &mesh));
    CHECK_OK(ctx, cf_write_mesh_file(ctx, cft_in_dir("cyl.obj"), mesh, NULL, NULL, 0));
    const int32_t *off = cf_mesh_boundary_loop_offsets(mesh), *lv = cf_mesh_boundary_loop_vertices(mesh);
    const double *x = cf_mesh_positions(mesh);
    int32_t nb = off[cf_mesh_boundary_loop_count(mesh)];
    /* E4: nan, a zero vector and 1e308 exited 1 (usage) */
    static const char *const bad[4] = {NULL, "nan 0 0", "0 0 0", "1e308 0 0"};
    static const char *const expect[4] = {NULL, "is not finite", "is zero", "is beyond the coordinate range"};
    for (int b = 0; b < 4; ++b) {
        size_t cap = 8000 + 64 * (size_t)nb, n = 0;
        char *text = malloc(cap);
        /* the valid file starts with a comment longer than the old 4096-byte
         * line buffer, ending in a target (was "targets.txt:2: expected
         * 'VERTEX X Y Z'"); the bad ones with a short comment */
        text[n++] = '#';
        while (n < (b ? 10 : 5000)) text[n++] = 'c';
        n += (size_t)snprintf(text + n, cap - n, " %d 1 0 0\n", lv[0]);
        for (int32_t k = 0; k < nb; ++k) {
            const double *p = x + 3 * lv[k];
            if (bad[b] && k == 2) n += (size_t)snprintf(text + n, cap - n, "%d %s\n", lv[k], bad[b]);
            else n += (size_t)snprintf(text + n, cap - n, "%d %.17g %.17g 0\n", lv[k], p[0], p[1]);
        }
        put("targets.txt", text, n);
        free(text);
        char msg[160];
        snprintf(msg, sizeof msg, "curvflow: targets.txt: line 4: vertex %d: direction", lv[2]);
        EXPECT("flow cyl.obj -o out.obj --method spin-willmore -n 1 -q --boundary-targets targets.txt", b ? 2 : 0,
               b ? msg : NULL);
        if (b) CHECK(strstr(cft_err, expect[b]) != NULL);
    }
    put_text("targets.txt", "99999999999999999999999999 1 0 0\n");
    EXPECT("flow cyl.obj -o out.obj --method spin-willmore -q --boundary-targets targets.txt", 2,
           "targets.txt: line 1: vertex 99999999999999999999999999 out of range");
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
}

int main(void)
{
    cft_cli_env = "OMP_THREAD_LIMIT=1";
    if (cft_cli_setup("cli_readers")) return 1;
    CFT_RUN(test_header_counts);
    CFT_RUN(test_bom_nul_huge);
    CFT_RUN(test_rho_file);
    CFT_RUN(test_boundary_targets_file);
    return cft_cli_finish();
}
