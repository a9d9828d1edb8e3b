/*
 * The curvflow tool end to end: runs the built binary (CF_TEST_CLI) on
 * generated meshes and checks exit codes (0 ok, 1 usage, 2 invalid input,
 * 3 numerical failure), messages, that outputs exist and parse, and that no
 * temporary files are left behind (atomic writes).
 */
#define _XOPEN_SOURCE 700 /* POSIX 2008 with XSI: realpath */
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/mesh.h"
#include "cli_test.h"
#include "png_read.h"

#include <dirent.h>
#include <fcntl.h>
#include <jansson.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static int count_lines(const char *text);

static void test_help_and_usage(void)
{
    CHECK_RUN("--help", 0);
    CHECK(strstr(cft_out, "Usage: curvflow COMMAND") != NULL);
    CHECK_RUN("--version", 0);
    CHECK(strncmp(cft_out, "curvflow ", 9) == 0);
    CHECK(strstr(cft_out, cf_version_string()) != NULL);
    CHECK_RUN("", 1);
    CHECK_RUN("frobnicate", 1);
    CHECK(strstr(cft_err, "unknown command 'frobnicate'") != NULL);
    /* every command refuses an unknown option the same way (spin and curve
     * too, which once had parsers of their own) */
    const char *cmds[] = {"info", "generate", "flow", "compare", "demo", "render", "spin", "curve", "edit"};
    for (int i = 0; i < 9; ++i) {
        char args[64];
        snprintf(args, sizeof args, "%s --help", cmds[i]);
        CHECK_RUN(args, 0);
        CHECK(strstr(cft_out, "Usage: curvflow") != NULL);
        snprintf(args, sizeof args, "%s --no-such-option", cmds[i]);
        CHECK_RUN(args, 1);
        CHECK(strstr(cft_err, "--help") != NULL);
        /* one message line in the tool's format naming the option, then the
         * hint; getopt's own "<cmd>: unrecognized option" line is silenced */
        const char *expected = "curvflow: unrecognized option '--no-such-option'\n";
        CHECK(strncmp(cft_err, expected, strlen(expected)) == 0);
        CHECK(count_lines(cft_err) == 2);
    }
    CHECK_RUN("flow --method implicit-mcf ico.obj -o", 1);
    CHECK(strstr(cft_err, "option '-o' requires an argument") != NULL);
    CHECK_RUN("flow ico.obj --output", 1);
    CHECK(strstr(cft_err, "option '--output' requires an argument") != NULL);
    CHECK_RUN("info --json=yes ico.obj", 1);
    CHECK(strstr(cft_err, "option '--json' does not take an argument") != NULL);
    CHECK_RUN("render -z ico.obj", 1);
    CHECK(strstr(cft_err, "invalid option '-z'") != NULL);
}

static void test_generate(void)
{
    CHECK_RUN("generate icosphere --subdivisions 3 -o ico.obj", 0);
    CHECK_RUN("generate bumpy-sphere --subdivisions 2 --seed 4 -o bumpy.obj", 0);
    CHECK_RUN("generate torus --n-major 24 --n-minor 12 -o torus.ply", 0);
    CHECK_RUN("generate grid --nx 4 --ny 3 -o grid.off", 0);
    const char *kinds[] = {"cylinder", "bar", "sheet", "bumpy-plane", "double-torus"};
    for (int i = 0; i < 5; ++i) {
        char args[128];
        snprintf(args, sizeof args, "generate %s -o kind%d.ply", kinds[i], i);
        CHECK_RUN(args, 0);
        CHECK(cft_exists(args + strlen(args) - 9));
    }
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("ico.obj"), &mesh));
    if (mesh) CHECK(cf_mesh_vertex_count(mesh) == 642 && cf_mesh_face_count(mesh) == 1280);
    cf_mesh_destroy(&mesh);
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("torus.ply"), &mesh));
    if (mesh) CHECK(cf_mesh_vertex_count(mesh) == 24 * 12 && cf_mesh_genus(mesh) == 1);
    cf_mesh_destroy(&mesh);
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("grid.off"), &mesh));
    if (mesh) CHECK(cf_mesh_vertex_count(mesh) == 5 * 4 && cf_mesh_boundary_loop_count(mesh) == 1);
    cf_mesh_destroy(&mesh);
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("bumpy.obj"), &mesh));
    if (mesh) CHECK(cf_mesh_uv_count(mesh) > 0); /* the bumpy sphere carries its uv through the file */
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);

    CHECK_RUN("generate teapot -o x.obj", 1);
    CHECK(strstr(cft_err, "teapot") != NULL);
    CHECK_RUN("generate icosphere --radius 1e300 -o x.obj", 1); /* beyond the accepted range: usage */
    CHECK(strstr(cft_err, "--radius: 1e+300 is beyond the range") != NULL);
    CHECK_RUN("generate icosphere", 1);
    CHECK_RUN("generate icosphere --subdivisions 12 -o x.obj", 1);
    CHECK(strstr(cft_err, "--subdivisions") != NULL);
    CHECK_RUN("generate icosphere --radius abc -o x.obj", 1);
    /* an explicit negative value is passed on (and rejected), not replaced by the default */
    CHECK_RUN("generate grid --width -2 -o x.obj", 1);
    CHECK(strstr(cft_err, "-2") != NULL);
    CHECK_RUN("generate bumpy-sphere --subdivisions 1 --amplitude -0.2 -o neg.obj", 0);
    CHECK_RUN("generate bumpy-sphere --subdivisions 1 -o pos.obj", 0);
    {
        cf_context *c2 = cft_context();
        cf_mesh *neg = NULL, *pos = NULL;
        CHECK_OK(c2, cf_load_mesh(c2, cft_in_dir("neg.obj"), &neg));
        CHECK_OK(c2, cf_load_mesh(c2, cft_in_dir("pos.obj"), &pos));
        if (neg && pos) {
            CHECK(cf_mesh_vertex_count(neg) == cf_mesh_vertex_count(pos));
            CHECK(memcmp(cf_mesh_positions(neg), cf_mesh_positions(pos),
                         3 * (size_t)cf_mesh_vertex_count(neg) * sizeof(double)) != 0);
        }
        cf_mesh_destroy(&neg);
        cf_mesh_destroy(&pos);
        cf_context_destroy(&c2);
    }
    CHECK_RUN("generate icosphere -o x.xyz", 2);
    CHECK_RUN("generate icosphere -o no_such_dir/x.obj", 2);
    CHECK(!cft_exists("x.obj"));
}

static void test_info(void)
{
    CHECK_RUN("info ico.obj", 0);
    CHECK(strstr(cft_out, "genus:         0") != NULL);
    CHECK(strstr(cft_out, "validation:    ok") != NULL);
    CHECK_RUN("info ico.obj --json", 0);
    json_error_t jerr;
    json_t *root = json_loads(cft_out, 0, &jerr);
    CHECK(root != NULL);
    if (root) {
        CHECK(json_integer_value(json_object_get(root, "vertices")) == 642);
        CHECK(json_integer_value(json_object_get(root, "euler_characteristic")) == 2);
        CHECK(json_integer_value(json_object_get(root, "genus")) == 0);
        CHECK(json_integer_value(json_object_get(root, "boundary_loops")) == 0);
        CHECK(json_is_true(json_object_get(json_object_get(root, "validation"), "valid")));
        /* W/4pi of a fine icosphere is close to 1 (the round sphere's value) */
        CHECK_NEAR(json_real_value(json_object_get(root, "willmore_over_4pi")), 1.0, 0.05, 0.0);
        /* icosphere faces: area 4 pi R^2 (slightly less), angles near 60 degrees */
        json_t *areas = json_object_get(root, "face_areas");
        CHECK_NEAR(json_real_value(json_object_get(areas, "total")), 4.0 * acos(-1.0), 0.02, 0.0);
        json_t *ang = json_object_get(root, "angles");
        CHECK_NEAR(json_real_value(json_object_get(ang, "median_degrees")), 60.0, 0.1, 0.0);
        CHECK(json_real_value(json_object_get(ang, "fraction_below_10_degrees")) == 0.0);
    }
    json_decref(root);
    CHECK_RUN("info grid.off --json", 0);
    root = json_loads(cft_out, 0, &jerr);
    CHECK(root != NULL);
    if (root) {
        CHECK(json_integer_value(json_object_get(root, "boundary_loops")) == 1);
        CHECK(json_is_null(json_object_get(root, "willmore_over_4pi")));
    }
    /* what the file carries besides the mesh (session 30): property names, materials */
    CHECK(json_array_size(json_object_get(root, "vertex_properties")) == 0 &&
          json_array_size(json_object_get(root, "material_names")) == 0);
    json_decref(root);
    FILE *f0 = fopen(cft_in_dir("carry.obj"), "w");
    if (!f0) return;
    fprintf(f0, "mtllib skin.mtl\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nv 0 0 1 1 1 1\n"
                "usemtl a\nf 1 3 2\nf 1 2 4\nusemtl b\nf 1 4 3\nf 2 3 4\n");
    fclose(f0);
    CHECK_RUN("info carry.obj", 0);
    CHECK(strstr(cft_out, "\nvertex props:  red green blue\nmtllib:        skin.mtl\nmaterials:     a b\n") != NULL);
    CHECK(!strstr(cft_out, "face props:"));
    CHECK_RUN("info carry.obj --json", 0);
    root = json_loads(cft_out, 0, &jerr);
    CHECK(root && json_array_size(json_object_get(root, "vertex_properties")) == 3);
    CHECK(root && strcmp(json_string_value(json_array_get(json_object_get(root, "material_names"), 1)), "b") == 0);
    json_decref(root);
    remove(cft_in_dir("carry.obj"));

    /* a broken file: exit 2, the message names the file */
    FILE *f = fopen(cft_in_dir("broken.obj"), "w");
    if (f) {
        fputs("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", f);
        fclose(f);
    }
    CHECK_RUN("info broken.obj", 2);
    CHECK(strstr(cft_err, "curvflow: broken.obj:") != NULL);
    CHECK_RUN("info missing.obj", 2);
    CHECK(strstr(cft_err, "missing.obj") != NULL);
    /* --json keeps stdout one JSON object also when the file cannot be read */
    CHECK_RUN("info --json broken.obj", 2);
    root = json_loads(cft_out, 0, &jerr);
    CHECK(root != NULL);
    if (root) {
        CHECK(json_is_false(json_object_get(root, "readable")));
        CHECK(strcmp(json_string_value(json_object_get(root, "file")), "broken.obj") == 0);
        const char *status = json_string_value(json_object_get(root, "status"));
        CHECK(status && strncmp(status, "CF_ERR_", 7) == 0);
        const char *error = json_string_value(json_object_get(root, "error"));
        CHECK(error && strstr(cft_err, error) != NULL); /* the same message as on stderr */
    }
    json_decref(root);
    /* a non-manifold edge: the file reads, validation reports it, exit 2 */
    f = fopen(cft_in_dir("fin.obj"), "w");
    if (f) {
        fputs("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n", f);
        fclose(f);
    }
    CHECK_RUN("info fin.obj --json", 2);
    root = json_loads(cft_out, 0, &jerr);
    CHECK(root != NULL);
    if (root) {
        json_t *val = json_object_get(root, "validation");
        CHECK(json_is_false(json_object_get(val, "valid")));
        CHECK(json_integer_value(json_object_get(val, "nonmanifold_edges")) >= 1);
    }
    json_decref(root);
    CHECK(strstr(cft_err, "fin.obj") != NULL);
    CHECK_RUN("info", 1);
    CHECK_RUN("info a.obj b.obj", 1);

    /* every file of ../shared/meshes/bad is rejected with exit 2 and its own message */
    const char *bad[] = {"bad/flipped_face_spot.obj", "bad/nan_coordinate_bunny.obj",
                         "bad/nonmanifold_edges_beetle.obj", "bad/truncated_spot.obj"};
    for (int i = 0; i < 4; ++i) {
        const char *path = cft_shared_mesh_path(bad[i]);
        if (!path) {
            fprintf(stderr, "SKIP: ../shared/meshes absent, bad-file checks skipped\n");
            break;
        }
        char args[4200];
        snprintf(args, sizeof args, "info '%s'", path);
        CHECK_RUN(args, 2);
        CHECK(strstr(cft_err, bad[i] + 4) != NULL);
    }

    /* info against ../shared/meshes/CHECKS.tsv (independently computed):
     * counts and topology exactly; min angle, median per-face min angle and
     * fraction of faces below 10 deg to the 4-5 digits the table prints. */
    const struct { const char *name; int v, genus, loops; double min_deg, median_min_deg, frac; } rows[] = {
        {"spot_3k.obj", 2930, 0, 0, 10.2103, 38.969, 0.0},
        {"double_torus_315.obj", 315, 2, 0, 5.029, 28.382, 0.0252},
        {"blade_slivers_8k.obj", 8231, 0, 2, 0.4737, 5.72, 1.0},
        {"hand_1k.obj", 1197, 0, 0, 0.691, 33.411, 0.0209},
    };
    for (int i = 0; i < 4; ++i) {
        const char *path = cft_shared_mesh_path(rows[i].name);
        if (!path) break;
        char args[4200];
        snprintf(args, sizeof args, "info '%s' --json", path);
        CHECK_RUN(args, 0);
        root = json_loads(cft_out, 0, &jerr);
        CHECK(root != NULL);
        if (!root) continue;
        CHECK(json_integer_value(json_object_get(root, "vertices")) == rows[i].v);
        CHECK(json_integer_value(json_object_get(root, "genus")) == rows[i].genus);
        CHECK(json_integer_value(json_object_get(root, "boundary_loops")) == rows[i].loops);
        json_t *ang = json_object_get(root, "angles");
        CHECK_NEAR(json_real_value(json_object_get(ang, "min_degrees")), rows[i].min_deg, 0.0, 1e-4);
        CHECK_NEAR(json_real_value(json_object_get(ang, "median_face_min_degrees")), rows[i].median_min_deg, 0.0, 1e-3);
        CHECK_NEAR(json_real_value(json_object_get(ang, "fraction_faces_min_below_10_degrees")), rows[i].frac, 0.0, 1e-4);
        json_decref(root);
    }
}

static int count_lines(const char *text)
{
    int n = 0;
    for (const char *c = text; *c; ++c) n += *c == '\n';
    return n;
}

static void test_flow(void)
{
    CHECK_RUN("flow --list-methods", 0);
    CHECK(strstr(cft_out, "implicit-mcf") != NULL && strstr(cft_out, "spin-willmore") != NULL);
    CHECK(count_lines(cft_out) == 7);
    CHECK_RUN("flow --method implicit-mcf --list-params", 0);
    CHECK(strstr(cft_out, "time_step") != NULL && strstr(cft_out, "[0.001]") != NULL);

    CHECK_RUN("flow bumpy.obj -o smooth.obj --method implicit-mcf --steps 3 --log run.jsonl", 0);
    CHECK(count_lines(cft_err) >= 3); /* one status line per step */
    CHECK(strstr(cft_err, "step 3/3") != NULL);
    cf_context *ctx = cft_context();
    cf_mesh *in = NULL, *out = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("bumpy.obj"), &in));
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("smooth.obj"), &out));
    if (in && out) {
        CHECK(cf_mesh_vertex_count(in) == cf_mesh_vertex_count(out));
        CHECK(cf_mesh_uv_count(in) == cf_mesh_uv_count(out)); /* texture coordinates pass through */
        CHECK(memcmp(cf_mesh_uv(in), cf_mesh_uv(out), 2 * (size_t)cf_mesh_uv_count(in) * sizeof(double)) == 0);
    }
    cf_mesh_destroy(&in);
    cf_mesh_destroy(&out);
    cf_context_destroy(&ctx);

    /* the log: one object per step plus the start, energies decreasing */
    static char log[1 << 16];
    cft_read_small(cft_in_dir("run.jsonl"), log, sizeof log);
    CHECK(count_lines(log) == 4);
    char *save = NULL;
    double prev = INFINITY;
    int64_t expect = 0;
    for (char *line = strtok_r(log, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        json_error_t jerr;
        json_t *o = json_loads(line, 0, &jerr);
        CHECK(o != NULL);
        if (!o) break;
        CHECK(json_integer_value(json_object_get(o, "iteration")) == expect++);
        double e = json_real_value(json_object_get(o, "energy"));
        CHECK(e < prev);
        prev = e;
        CHECK(json_is_object(json_object_get(o, "terms")) && json_object_get(json_object_get(o, "terms"), "area"));
        CHECK(json_is_real(json_object_get(o, "area_drift")) && json_is_real(json_object_get(o, "volume")));
        CHECK(json_is_object(json_object_get(o, "seconds")));
        if (expect > 1) CHECK(json_real_value(json_object_get(json_object_get(o, "residuals"), "solve")) < 1e-10);
        json_decref(o);
    }

    /* a run that ends before its steps says so in its summary (a flat
     * grid: W is 0, no step lowers it), one that runs them all does not */
    CHECK_RUN("flow grid.off -o g.off --method spin-willmore --steps 50", 0);
    CHECK(strstr(cft_err, "curvflow: spin-willmore: ") != NULL && strstr(cft_err, " steps (converged), energy ") != NULL);
    CHECK_RUN("flow bumpy.obj -o b2.obj --method spin-willmore --steps 2", 0);
    CHECK(strstr(cft_err, "curvflow: spin-willmore: 2 steps, energy ") != NULL);
    remove(cft_in_dir("g.off"));
    remove(cft_in_dir("b2.obj"));
    CHECK_RUN("flow bumpy.obj -o p.ply -m conformal-mcf -n 2 -p rescale=true -p mass=voronoi -q", 0);
    CHECK(cft_err[0] == '\0');
    CHECK(cft_exists("p.ply"));
    CHECK_RUN("flow bumpy.obj -o x.obj --method no-such", 1);
    CHECK_RUN("flow bumpy.obj -o x.obj", 1);
    CHECK_RUN("flow bumpy.obj --method implicit-mcf", 1);
    CHECK_RUN("flow bumpy.obj -o x.obj --method implicit-mcf --param colour=red", 1);
    CHECK(strstr(cft_err, "colour") != NULL);
    CHECK_RUN("flow bumpy.obj -o x.obj --method implicit-mcf --time-step -2", 1);
    CHECK(strstr(cft_err, "time_step") != NULL);
    CHECK_RUN("flow bumpy.obj -o x.obj --method implicit-mcf --param rescale", 1);
    CHECK_RUN("flow missing.obj -o x.obj --method implicit-mcf", 2);
    CHECK_RUN("flow broken.obj -o x.obj --method implicit-mcf", 2);
    CHECK_RUN("flow bumpy.obj -o no_such_dir/x.obj --method implicit-mcf -n 1 -q", 2);
    CHECK(strstr(cft_err, "no_such_dir/x.obj") != NULL);
    /* an output that could not be written is refused before the run: no
     * step is taken (the log is never opened) */
    CHECK_RUN("flow bumpy.obj -o no_such_dir/x.obj --method implicit-mcf -n 1000 --log early.jsonl", 2);
    CHECK(strstr(cft_err, "no_such_dir/x.obj: cannot write: directory no_such_dir does not exist") != NULL);
    CHECK(!cft_exists("early.jsonl"));
    CHECK_RUN("flow bumpy.obj -o x.xyz --method implicit-mcf -n 1000 --log early.jsonl", 2);
    CHECK(strstr(cft_err, "unknown mesh format") != NULL);
    CHECK(!cft_exists("early.jsonl"));
    CHECK_RUN("flow bumpy.obj -o . --method implicit-mcf -n 1 -q", 2);
    CHECK_RUN("spin bumpy.obj --rho no_rho.txt -o no_such_dir/x.obj", 2);
    CHECK(strstr(cft_err, "does not exist") != NULL);
    CHECK_RUN("render bumpy.obj -o no_such_dir/x.png", 2);
    CHECK(strstr(cft_err, "does not exist") != NULL);
    CHECK_RUN("flow bumpy.obj -o x.obj --method implicit-mcf -n 1 --log no_such_dir/l.jsonl", 2);
    CHECK_RUN("flow bumpy.obj -o x.obj --method implicit-mcf --steps -3", 1);
    CHECK(!cft_exists("x.obj"));

    /* numerical failure: exit 3, message names the iteration, last good state written */
    CHECK_RUN("flow bumpy.obj -o blown.obj --method explicit-mcf --time-step 10 --steps 20", 3);
    CHECK(strstr(cft_err, "iteration") != NULL);
    CHECK(strstr(cft_err, "stability limit") != NULL);
    CHECK(cft_exists("blown.obj"));
}

/* The input's vertex and face properties are written with the result of
 * `flow` (and `edit`: same path): colours as uchar, other properties as
 * double, in PLY; an OBJ output gets them in its side CSV files; an OFF
 * output cannot hold them and says so; a name that cannot be written is
 * named in a warning (session 29: every property was dropped without a
 * word). */
static void test_flow_keeps_properties(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.2, 4u, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    double *red = malloc((size_t)nv * sizeof *red), *quality = malloc((size_t)nv * sizeof *quality);
    double *label = malloc((size_t)nf * sizeof *label);
    for (int32_t i = 0; i < nv; ++i) {
        red[i] = (double)((7 * i) % 256);
        quality[i] = 0.25 + 1.0 / (i + 3.0);
    }
    for (int32_t f = 0; f < nf; ++f) label[f] = f % 5;
    cf_field fields[3] = {{"red", CF_FIELD_VERTEX, red}, {"quality", CF_FIELD_VERTEX, quality},
                          {"label", CF_FIELD_FACE, label}};
    CHECK_OK(ctx, cf_write_mesh_file(ctx, cft_in_dir("props.ply"), m, NULL, fields, 3));
    CHECK_RUN("flow props.ply -o props_out.ply --method spin-willmore --steps 2 -q", 0);
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_file(ctx, cft_in_dir("props_out.ply"), &d));
    if (d) {
        const cf_mesh_property *p = cf_mesh_data_vertex_property(d, "red");
        CHECK(p && memcmp(p->values, red, (size_t)nv * sizeof *red) == 0);
        p = cf_mesh_data_vertex_property(d, "quality");
        CHECK(p && memcmp(p->values, quality, (size_t)nv * sizeof *quality) == 0);
        p = cf_mesh_data_face_property(d, "label");
        CHECK(p && memcmp(p->values, label, (size_t)nf * sizeof *label) == 0);
        /* and the positions did move */
        CHECK(memcmp(d->positions, cf_mesh_positions(m), 3 * (size_t)nv * sizeof(double)) != 0);
        cf_mesh_data_destroy(&d);
    }
    char text[4096];
    cft_read_small(cft_in_dir("props_out.ply"), text, sizeof text);
    CHECK(strstr(text, "property uchar red\nproperty double quality\n") != NULL);
    CHECK_RUN("flow props.ply -o props_out.obj --method implicit-mcf --steps 1 -q", 0);
    cft_read_small(cft_in_dir("props_out.vertex.csv"), text, sizeof text);
    CHECK(strncmp(text, "index,red,quality\n0,0,", 22) == 0);
    EXPECT("flow props.ply -o props_out.off --method implicit-mcf --steps 1 -q", 0,
           "props_out.off: OFF holds only colours: 3 of the 3 properties of props.ply are not written (write PLY)");
    /* a property name the writer cannot use: named, the others kept */
    FILE *f = fopen(cft_in_dir("odd.ply"), "w");
    fprintf(f, "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
               "property float conf(1)\nproperty float k\nproperty float nx\nelement face 4\n"
               "property list uchar int vertex_indices\nend_header\n0 0 0 1 2 -1\n1 0 0 1 2 1\n0 1 0 1 2 0\n"
               "0 0 1 1 2 0\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    fclose(f);
    EXPECT("flow odd.ply -o odd_out.ply --method implicit-mcf --steps 1 -q", 0,
           "odd.ply: properties 'conf(1)' cannot be written back");
    CHECK_OK(ctx, cf_read_mesh_file(ctx, cft_in_dir("odd_out.ply"), &d));
    CHECK(d && cf_mesh_data_vertex_property(d, "k") && !cf_mesh_data_vertex_property(d, "conf(1)"));
    /* a normal describes the input's shape: not written */
    CHECK(d && !cf_mesh_data_vertex_property(d, "nx"));
    cf_mesh_data_destroy(&d);
    CHECK(cft_exists("props_out.off") && cft_exists("props_out.face.csv"));
    /* an OBJ's vertex colours (v x y z r g b) and a COFF's (session 30; they were dropped): back on the v
     * lines of an OBJ output, uchar in a PLY */
    f = fopen(cft_in_dir("scan.obj"), "w");
    fprintf(f, "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nv 0 0 1 0.5 0.5 0.5\n"
               "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    fclose(f);
    CHECK_RUN("flow scan.obj -o scan_out.obj --method implicit-mcf --steps 1 -q", 0);
    cft_read_small(cft_in_dir("scan_out.obj"), text, sizeof text);
    CHECK(strstr(text, " 1 0 0\nv ") && strstr(text, " 0.50196078431372548 0.50196078431372548 0.50196078431372548\nf"));
    CHECK(!cft_exists("scan_out.vertex.csv"));
    CHECK_RUN("flow scan.obj -o scan_out.ply --method implicit-mcf --steps 1 -q --force", 0);
    cft_read_small(cft_in_dir("scan_out.ply"), text, sizeof text);
    CHECK(strstr(text, "property uchar red\nproperty uchar green\nproperty uchar blue\n") != NULL);
    f = fopen(cft_in_dir("scan.off"), "w");
    fprintf(f, "COFF\n4 4 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n0 0 1 9 9 9 255\n"
               "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    fclose(f);
    CHECK_RUN("flow scan.off -o scan_off_out.ply --method implicit-mcf --steps 1 -q", 0);
    CHECK_OK(ctx, cf_read_mesh_file(ctx, cft_in_dir("scan_off_out.ply"), &d));
    const cf_mesh_property *blue = d ? cf_mesh_data_vertex_property(d, "blue") : NULL;
    CHECK(blue && blue->values[2] == 255 && blue->values[3] == 9 && cf_mesh_data_vertex_property(d, "alpha"));
    cf_mesh_data_destroy(&d);
    /* COFF to OFF: the colours stay, without a warning */
    EXPECT("flow scan.off -o scan_off_out.off --method implicit-mcf --steps 1", 0, "wrote scan_off_out.off");
    cft_read_small(cft_in_dir("scan_off_out.off"), text, sizeof text);
    CHECK(strncmp(text, "COFF\n4 4 0\n", 11) == 0 && strstr(text, " 9 9 9 255\n3 0 2 1\n"));
    CHECK(!cft_err_has("warning"));
    /* test_no_temp_files lists what the other tests leave */
    static const char *const made[] = {"props.ply", "props_out.ply", "props_out.obj", "props_out.vertex.csv",
                                       "props_out.face.csv", "props_out.off", "odd.ply", "odd_out.ply",
                                       "scan.obj", "scan_out.obj", "scan_out.ply", "scan.off", "scan_off_out.ply",
                                       "scan_off_out.off"};
    for (size_t i = 0; i < sizeof made / sizeof made[0]; ++i) remove(cft_in_dir(made[i]));
    free(red);
    free(quality);
    free(label);
    cf_mesh_destroy(&m);
    cf_context_destroy(&ctx);
}

/* An OBJ's materials reach the output OBJ: its mtllib (made absolute when
 * the output goes to another directory, so it still names the library
 * beside the input) and a usemtl before each run of faces; a PLY output
 * says it drops them (session 29: a textured OBJ lost its material). */
static void test_flow_keeps_materials(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.2, 5u, &m));
    if (!m) return;
    int32_t nf = cf_mesh_face_count(m);
    int32_t *mat = malloc((size_t)nf * sizeof *mat);
    for (int32_t f = 0; f < nf; ++f) mat[f] = f < nf / 2 ? 0 : 1;
    const char *libs[1] = {"skin.mtl"}, *names[2] = {"skin", "spots"};
    cf_write_options o;
    cf_write_options_default(&o);
    o.material_library_count = 1, o.material_libraries = libs;
    o.material_count = 2, o.material_names = names, o.face_materials = mat;
    CHECK_OK(ctx, cf_write_mesh_file_ex(ctx, cft_in_dir("textured.obj"), m, NULL, NULL, 0, &o));
    CHECK_RUN("flow textured.obj -o textured_out.obj --method spin-willmore --steps 2 -q", 0);
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_file(ctx, cft_in_dir("textured_out.obj"), &d));
    CHECK(d && d->material_library_count == 1 && strcmp(d->material_libraries[0], "skin.mtl") == 0);
    CHECK(d && d->material_count == 2 && d->face_materials && memcmp(d->face_materials, mat, (size_t)nf * 4) == 0);
    CHECK(d && d->uv_count > 0); /* and the texture coordinates, as before */
    cf_mesh_data_destroy(&d);
    CHECK(cft_shell("mkdir -p other") == 0);
    CHECK_RUN("flow textured.obj -o other/textured_out.obj --method spin-willmore --steps 2 -q", 0);
    CHECK_OK(ctx, cf_read_mesh_file(ctx, cft_in_dir("other/textured_out.obj"), &d));
    char expected[1200];
    char *dir = realpath(cft_dir, NULL);
    snprintf(expected, sizeof expected, "%s/skin.mtl", dir ? dir : cft_dir);
    free(dir);
    CHECK(d && d->material_library_count == 1 && strcmp(d->material_libraries[0], expected) == 0);
    cf_mesh_data_destroy(&d);
    EXPECT("flow textured.obj -o textured_out.ply --method spin-willmore --steps 1 -q", 0,
           "textured_out.ply: the materials of textured.obj (mtllib / usemtl) are not written: only OBJ holds them");
    static const char *const made[] = {"textured.obj", "textured_out.obj", "textured_out.ply",
                                       "other/textured_out.obj"};
    for (size_t i = 0; i < sizeof made / sizeof made[0]; ++i) remove(cft_in_dir(made[i]));
    rmdir(cft_in_dir("other"));
    free(mat);
    cf_mesh_destroy(&m);
    cf_context_destroy(&ctx);
}

static void test_compare(void)
{
    CHECK_RUN("compare bumpy.obj smooth.obj", 0);
    CHECK(strstr(cft_out, "quasi-conformal Q") != NULL);
    CHECK(strstr(cft_out, "vertex-scale model Q") != NULL);
    CHECK_RUN("compare bumpy.obj bumpy.obj --json --ply same.ply", 0);
    json_error_t jerr;
    json_t *root = json_loads(cft_out, 0, &jerr);
    CHECK(root != NULL);
    if (root) {
        /* a mesh against itself: Q = 1 and no area distortion, to rounding */
        json_t *q = json_object_get(root, "quasi_conformal_error");
        CHECK_NEAR(json_real_value(json_object_get(q, "max")), 1.0, 0.0, 1e-9);
        CHECK_NEAR(json_real_value(json_object_get(json_object_get(root, "log_area_distortion"), "max")), 0.0, 0.0, 1e-9);
        /* and the vertex-scale model: every log scale 0, model Q 1, nothing left over */
        json_t *model = json_object_get(root, "vertex_scale_model_q");
        CHECK_NEAR(json_real_value(json_object_get(model, "max")), 1.0, 0.0, 1e-9);
        CHECK(json_integer_value(json_object_get(model, "invalid_faces")) == 0);
        CHECK_NEAR(json_real_value(json_object_get(model, "rms_log_length_residual")), 0.0, 0.0, 1e-12);
    }
    json_decref(root);
    /* the PLY carries the per-face fields */
    cf_context *ctx = cft_context();
    cf_mesh_data *data = NULL;
    CHECK_OK(ctx, cf_read_mesh_file(ctx, cft_in_dir("same.ply"), &data));
    if (data) {
        const cf_mesh_property *q = cf_mesh_data_face_property(data, "Q");
        CHECK(q != NULL && cf_mesh_data_face_property(data, "log_area_distortion") != NULL);
        if (q) CHECK_NEAR(q->values[0], 1.0, 0.0, 1e-9);
        const cf_mesh_property *u = cf_mesh_data_vertex_property(data, "log_scale");
        CHECK(u != NULL);
        if (u) CHECK_NEAR(u->values[0], 0.0, 0.0, 1e-12);
    }
    cf_mesh_data_destroy(&data);
    cf_context_destroy(&ctx);
    /* a genus-0 surface has one conformal class: nothing said */
    CHECK_RUN("compare bumpy.obj smooth.obj", 0);
    CHECK(strstr(cft_out, "conformal class") == NULL);
    /* tori of radii (1, 0.4) and (1, 0.3): moduli near sqrt(0.84) / 0.4 = 2.291 i and
     * sqrt(0.91) / 0.3 = 3.180 i, their hyperbolic distance near log(3.180 / 2.291) = 0.328 */
    CHECK_RUN("generate torus --n-major 48 --n-minor 24 -o torus_a.obj", 0);
    CHECK_RUN("generate torus --n-major 48 --n-minor 24 --minor-radius 0.3 -o torus_b.obj", 0);
    CHECK_RUN("compare torus_a.obj torus_b.obj --json", 0);
    root = json_loads(cft_out, 0, &jerr);
    CHECK(root != NULL);
    if (root) {
        json_t *cls = json_object_get(root, "conformal_class");
        CHECK(json_integer_value(json_object_get(cls, "genus")) == 1);
        CHECK_NEAR(json_real_value(json_object_get(cls, "distance")), 0.328, 0.0, 0.005);
        CHECK_NEAR(json_real_value(json_array_get(json_object_get(cls, "modulus_a"), 1)), 2.291, 0.0, 0.01);
        CHECK_NEAR(json_real_value(json_array_get(json_object_get(cls, "modulus_b"), 1)), 3.180, 0.0, 0.01);
    }
    json_decref(root);
    /* a face of B collapsed onto a line up to 1e-13 (the file loads): one face changes the class
     * by no more than its share (measured 1.3e-5) */
    ctx = cft_context();
    cf_mesh *torus = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("torus_a.obj"), &torus));
    if (torus) {
        int32_t nv = cf_mesh_vertex_count(torus);
        const int32_t *t = cf_mesh_triangles(torus);
        double *x = malloc(3 * (size_t)nv * sizeof *x);
        memcpy(x, cf_mesh_positions(torus), 3 * (size_t)nv * sizeof *x);
        for (int c = 0; c < 3; ++c) x[3 * t[0] + c] = 0.5 * (x[3 * t[1] + c] + x[3 * t[2] + c]) + 1e-13 * (c == 2);
        CHECK_OK(ctx, cf_write_mesh_file(ctx, cft_in_dir("torus_flat_face.obj"), torus, x, NULL, 0));
        free(x);
    }
    cf_mesh_destroy(&torus);
    cf_context_destroy(&ctx);
    CHECK_RUN("compare torus_a.obj torus_flat_face.obj --json", 0);
    root = json_loads(cft_out, 0, &jerr);
    CHECK(root != NULL);
    if (root) {
        double d = json_real_value(json_object_get(json_object_get(root, "conformal_class"), "distance"));
        CHECK(d > 0.0 && d < 1e-3);
    }
    json_decref(root);
    remove(cft_in_dir("torus_a.obj"));
    remove(cft_in_dir("torus_b.obj"));
    remove(cft_in_dir("torus_flat_face.obj"));
    CHECK_RUN("compare bumpy.obj ico.obj", 2);
    CHECK(strstr(cft_err, "connectivity") != NULL);
    CHECK_RUN("compare bumpy.obj missing.obj", 2);
    CHECK_RUN("compare bumpy.obj", 1);
}

static void test_demo(void)
{
    CHECK_RUN("demo --output-dir demo --steps 3 --quiet", 0);
    CHECK(strstr(cft_out, "W/4pi") != NULL && strstr(cft_out, "quasi-conformal Q") != NULL);
    CHECK(strstr(cft_out, "demo/output.obj") != NULL);
    const char *files[] = {"demo/input.obj", "demo/output.obj", "demo/output.ply", "demo/log.jsonl",
                           "demo/before.png", "demo/after.png", "demo/q.png"};
    for (int i = 0; i < 7; ++i) CHECK(cft_exists(files[i]));
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("demo/output.obj"), &mesh));
    if (mesh) CHECK(cf_mesh_uv_count(mesh) > 0 && cf_mesh_uv_triangles(mesh) != NULL);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
    static char log[1 << 16];
    cft_read_small(cft_in_dir("demo/log.jsonl"), log, sizeof log);
    CHECK(count_lines(log) == 4);
    CHECK_RUN("demo --output-dir ico.obj", 2); /* a file, not a folder */
    /* the demo's outputs pass the common output check before any work: a
     * read-only file of an earlier demo is kept unless --force */
    CHECK(chmod(cft_in_dir("demo/q.png"), 0444) == 0);
    CHECK_RUN("demo --output-dir demo --steps 1 --quiet", 2);
    CHECK(strstr(cft_err, "curvflow: demo/q.png: the existing file is read-only; --force replaces it") != NULL);
    cft_read_small(cft_in_dir("demo/log.jsonl"), log, sizeof log);
    CHECK(count_lines(log) == 4); /* not rerun: still the log of the first run */
    CHECK(chmod(cft_in_dir("demo/q.png"), 0644) == 0);
    CHECK_RUN("demo extra", 1);
}

static int png_size(const char *name, int *w, int *h)
{
    unsigned char b[24];
    FILE *f = fopen(cft_in_dir(name), "rb");
    if (!f) return 0;
    size_t n = fread(b, 1, sizeof b, f);
    fclose(f);
    if (n != sizeof b || memcmp(b, "\x89PNG\r\n\x1a\n", 8) != 0) return 0;
    *w = (b[16] << 24) | (b[17] << 16) | (b[18] << 8) | b[19];
    *h = (b[20] << 24) | (b[21] << 16) | (b[22] << 8) | b[23];
    return 1;
}

static void test_render(void)
{
    int w = 0, h = 0;
    CHECK_RUN("render bumpy.obj -o b.png --uv-checker --size 120x80 --view 1,0,0 --perspective", 0);
    CHECK(png_size("b.png", &w, &h) && w == 120 && h == 80);
    CHECK_RUN("render same.ply -o q.png --field face:Q --range 1,2", 0);
    CHECK(png_size("q.png", &w, &h) && w == 800 && h == 800);
    CHECK_RUN("render same.ply -o x.png --field face:nothing", 2);
    CHECK(strstr(cft_err, "nothing") != NULL);
    CHECK_RUN("render ico.obj -o x.png --uv-checker", 2); /* no uv */
    CHECK_RUN("render ico.obj -o x.png --view 1,2", 1);
    CHECK_RUN("render ico.obj -o x.png --size 0x10", 1);
    CHECK_RUN("render ico.obj", 1);
    /* --colours (session 30): the file's own colours; a file without them, or with --field, is refused */
    FILE *f = fopen(cft_in_dir("rgb.obj"), "w");
    if (f) {
        fprintf(f, "v 0 0 0 1 0 0\nv 1 0 0 1 0 0\nv 1 1 0 1 0 0\nv 0 1 0 1 0 0\nf 1 2 3\nf 1 3 4\n");
        fclose(f);
    }
    CHECK_RUN("render rgb.obj -o c.png --colours --size 40x40 --view 0,0,1", 0);
    unsigned char *img = cft_png_load_rgb(cft_in_dir("c.png"), &w, &h);
    CHECK(img && w == 40 && h == 40); /* the square faces the headlight: its full red */
    CHECK(img && img[3 * (20 * 40 + 20)] == 255 && img[3 * (20 * 40 + 20) + 1] == 0 && img[3 * (20 * 40 + 20) + 2] == 0);
    cft_png_free(img);
    CHECK_RUN("render ico.obj -o x.png --colours", 2);
    CHECK(strstr(cft_err, "ico.obj: --colours: the file has no colours (vertex or face properties red, green, blue)"));
    CHECK_RUN("render rgb.obj -o x.png --colours --field face:Q", 1);
    CHECK(!cft_exists("x.png"));
    remove(cft_in_dir("rgb.obj"));
    remove(cft_in_dir("c.png"));
}

/* Atomic writes: only the files the commands named exist in the folder. */
static void test_no_temp_files(void)
{
    DIR *d = opendir(cft_dir);
    CHECK(d != NULL);
    if (!d) return;
    const char *expected[] = {".", "..", "stdout.txt", "stderr.txt", "ico.obj", "bumpy.obj", "torus.ply", "grid.off",
                              "kind0.ply", "kind1.ply", "kind2.ply", "kind3.ply", "kind4.ply", "broken.obj", "fin.obj",
                              "smooth.obj", "run.jsonl", "p.ply", "blown.obj", "same.ply", "demo", "b.png", "q.png", "neg.obj", "pos.obj",
                              "wobbly.csv", "round.csv", "blown.csv", "g"};
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        int known = 0;
        for (size_t i = 0; i < sizeof expected / sizeof expected[0]; ++i) known |= strcmp(e->d_name, expected[i]) == 0;
        if (!known) cft_fail(__FILE__, __LINE__, "unexpected file left in %s: %s", cft_dir, e->d_name);
        ++cft_checks;
    }
    closedir(d);
}

/* curve: a run, a diverging run (exit 3, last good state written), and an
 * output that cannot be written (exit 2, nothing run). */
static void test_curve(void)
{
    FILE *f = fopen(cft_in_dir("wobbly.csv"), "w");
    CHECK(f != NULL);
    if (!f) return;
    for (int i = 0; i < 48; ++i) {
        double t = 2.0 * 3.14159265358979323846 * i / 48;
        double r = 1.0 + 0.2 * sin(5.0 * t);
        fprintf(f, "%.17g,%.17g\n", r * cos(t), r * sin(t));
    }
    fclose(f);
    CHECK_RUN("curve wobbly.csv -o round.csv --steps 5 --quiet", 0);
    CHECK(cft_exists("round.csv"));
    CHECK_RUN("curve wobbly.csv -o blown.csv --steps 5 --time-step 1.5", 3);
    CHECK(strstr(cft_err, "iteration 1: ") != NULL);
    CHECK(strstr(cft_err, "writing the last good state (iteration 0)") != NULL);
    CHECK(cft_exists("blown.csv"));
    CHECK_RUN("curve wobbly.csv -o no_such_dir/c.csv", 2);
    CHECK(strstr(cft_err, "does not exist") != NULL);
}

/* ---- issue 15: hostile use of the command line --------------------------- */

#define CHECK_ERR(part)                                                                                   \
    do {                                                                                                  \
        ++cft_checks;                                                                                     \
        if (!strstr(cft_err, (part)))                                                                    \
            cft_fail(__FILE__, __LINE__, "stderr lacks \"%s\":\n%s", (part), cft_err);                   \
    } while (0)

static void write_text(const char *name, const char *text)
{
    FILE *f = fopen(cft_in_dir(name), "w");
    CHECK(f != NULL);
    if (!f) return;
    fputs(text, f);
    fclose(f);
}

static void read_named(const char *name, char *buf, size_t size) { cft_read_small(cft_in_dir(name), buf, size); }

/* The misuse reproducers of issue 15, each with its exit code and message. */
static void test_misuse_reproducers(void)
{
    static char before[1 << 16], after[1 << 16];
    CHECK(mkdir(cft_in_dir("g"), 0777) == 0);
    CHECK_RUN("generate icosphere --subdivisions 1 -o g/in.obj", 0);

    /* S4: an overflowing size is a usage error naming the option (sscanf
     * wrapped it to 100x100); so are a size past the renderer's limit and junk */
    const char *sizes[] = {"4294967396x4294967396", "16385x10", "0x10", "-5x10", "10x", "10x10x", " 10x10", "+10x10"};
    for (int i = 0; i < 8; ++i) {
        char args[256];
        snprintf(args, sizeof args, "render g/in.obj -o g/s.png --size '%s'", sizes[i]);
        CHECK_RUN(args, 1);
        CHECK_ERR("--size: expected WxH with W and H integers in [1, 16384], got '");
    }
    CHECK(!cft_exists("g/s.png"));
    CHECK_RUN("render g/in.obj -o g/s.png --size 16x8", 0);
    int w = 0, h = 0;
    CHECK(png_size("g/s.png", &w, &h) && w == 16 && h == 8);

    /* S4: an output extension that does not name the format the command
     * writes is refused before the run, nothing is written */
    write_text("g/c.csv", "0,0\n1,0\n1,1\n0,1\n0.5,0.6\n");
    CHECK_RUN("curve g/c.csv -o g/x.obj", 2);
    CHECK_ERR("curvflow: g/x.obj: unknown curve format '.obj' for -o (use .csv, .txt or .svg)");
    CHECK(!cft_exists("g/x.obj"));
    CHECK_RUN("render g/in.obj -o g/r.jpg", 2);
    CHECK_ERR("curvflow: g/r.jpg: unknown image format '.jpg' for -o (use .png)");
    CHECK(!cft_exists("g/r.jpg"));
    CHECK_RUN("generate icosphere -o g/x.png", 2);
    CHECK_ERR("unknown mesh format '.png' for -o (use .obj, .off or .ply)");
    CHECK_RUN("generate icosphere -o g/noext", 2);
    CHECK_ERR("g/noext: no extension to tell the mesh format for -o (use .obj, .off or .ply)");
    CHECK_RUN("spin g/in.obj --rho x -o g/x.csv", 2);
    CHECK_ERR("unknown mesh format '.csv' for -o");
    CHECK_RUN("compare g/in.obj g/in.obj --ply g/q.off", 2);
    CHECK_ERR("g/q.off: unknown mesh format '.off' for --ply (use .ply, or .obj with the fields in <stem>.face.csv");
    CHECK_RUN("flow g/in.obj -o g/o.obj -m implicit-mcf -n 1 --log g/l.txt", 2);
    CHECK_ERR("curvflow: g/l.txt: unknown log format '.txt' for --log (use .jsonl)");
    CHECK(!cft_exists("g/o.obj"));
    CHECK_RUN("edit g/in.obj --handles h.json -o g/o.obj --log g/o.log", 2);
    CHECK_ERR("unknown log format '.log' for --log");
    /* extensions are case-insensitive, as the writers read them */
    CHECK_RUN("curve g/c.csv -o g/C.SVG --steps 1 -q", 0);
    CHECK(cft_exists("g/C.SVG"));

    /* --log IN.obj never overwrites the input; neither does -o through a
     * symbolic or hard link to it */
    read_named("g/in.obj", before, sizeof before);
    CHECK_RUN("flow g/in.obj -o g/o.obj -m implicit-mcf -n 1 --log g/in.obj", 2);
    CHECK_ERR("g/in.obj: unknown log format '.obj' for --log");
    CHECK_RUN("flow g/in.obj -o g/in.obj -m implicit-mcf -n 1", 2);
    CHECK_ERR("curvflow: g/in.obj: -o names the same file as the input g/in.obj (IN); refusing to overwrite an input");
    CHECK(symlink("in.obj", cft_in_dir("g/sym.obj")) == 0);
    CHECK_RUN("flow g/in.obj -o g/sym.obj -m implicit-mcf -n 1", 2);
    CHECK_ERR("g/sym.obj: -o names the same file as the input g/in.obj (IN)");
    char in_path[2048];
    snprintf(in_path, sizeof in_path, "%s", cft_in_dir("g/in.obj")); /* in_dir's buffer is static */
    CHECK(link(in_path, cft_in_dir("g/hard.obj")) == 0);
    CHECK_RUN("spin g/in.obj --rho g/r.txt -o g/hard.obj", 2);
    CHECK_ERR("g/hard.obj: -o names the same file as the input g/in.obj (IN)");
    CHECK_RUN("compare g/in.obj g/hard.obj --ply g/./in.obj", 2);
    CHECK_ERR("--ply names the same file as the input g/in.obj (A)");
    write_text("g/t.jsonl", "0 0 0 1\n");
    CHECK_RUN("flow g/in.obj -o g/o.obj -m spin-willmore --boundary-targets g/t.jsonl --log g/t.jsonl", 2);
    CHECK_ERR("--log names the same file as the input g/t.jsonl (--boundary-targets)");
    CHECK_RUN("edit g/in.obj --handles h.json --start g/o2.obj -o g/o2.obj", 2);
    read_named("g/in.obj", after, sizeof after);
    CHECK(strcmp(before, after) == 0);
    CHECK(!cft_exists("g/o.obj"));

    /* M2: stretch-bend-edit through `flow` says what it needs */
    CHECK_RUN("flow g/in.obj -o g/o.obj --method stretch-bend-edit", 1);
    CHECK_ERR("curvflow: --method stretch-bend-edit needs handles: use --handles FILE or `curvflow edit`");
    CHECK(strstr(cft_err, "options.handles") == NULL);
    CHECK_RUN("flow g/in.obj -o g/o.obj --method implicit-mcf --handles h.json", 1);
    CHECK_ERR("--handles is an option of --method stretch-bend-edit");
    CHECK_RUN("generate bar --nx 6 --ny 2 --nz 2 --width 3 -o g/bar.obj", 0);
    write_text("g/h.json", "{\"sets\": [{\"name\": \"left\", \"relative_box\": {\"min\": [0, 0, 0], \"max\": [0, 1, 1]},"
                           " \"fixed\": true}, {\"name\": \"right\", \"relative_box\": {\"min\": [1, 0, 0], \"max\": [1, 1, 1]},"
                           " \"transform\": {\"translate\": [0, 0, 0.5]}}]}\n");
    CHECK_RUN("flow g/bar.obj -o g/bent.obj --method stretch-bend-edit --handles g/h.json -n 5 -q", 0);
    CHECK(cft_exists("g/bent.obj"));

    /* M3: generate names the real limits of its counts */
    CHECK_RUN("generate cylinder --n-around 1048576 -o g/cyl.obj", 1);
    CHECK_ERR("curvflow: generate cylinder: --n-around: '1048576' is not an integer in [3, 100000]");
    CHECK_RUN("generate cylinder --n-around 100001 -o g/cyl.obj", 1);
    CHECK_ERR("--n-around: '100001' is not an integer in [3, 100000]");
    CHECK_RUN("generate grid --nx 46001 -o g/cyl.obj", 1);
    CHECK_ERR("--nx: '46001' is not an integer in [1, 46000]");
    CHECK_RUN("generate bar --nx 2001 -o g/cyl.obj", 1);
    CHECK_ERR("--nx: '2001' is not an integer in [1, 2000]");
    CHECK(!cft_exists("g/cyl.obj"));
    {
        /* the generator's own limits are those: one above is refused by it too */
        cf_context *ctx = cft_context();
        cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
        cf_mesh *m = NULL;
        CHECK_STATUS(cf_generate_cylinder(ctx, 100001, 1, 1.0, 1.0, &m), CF_ERR_INVALID_ARG);
        CHECK(strstr(cf_context_message(ctx), "need [3, 100000] x [1, 100000]") != NULL); /* was "need >= 3 x >= 1" */
        CHECK_STATUS(cf_generate_cylinder(ctx, 3, 100001, 1.0, 1.0, &m), CF_ERR_INVALID_ARG);
        CHECK_STATUS(cf_generate_grid(ctx, 46001, 1, 1.0, 1.0, &m), CF_ERR_INVALID_ARG);
        CHECK_STATUS(cf_generate_bar(ctx, 2001, 1, 1, 1.0, 1.0, 1.0, 0, &m), CF_ERR_INVALID_ARG);
        CHECK_STATUS(cf_generate_torus(ctx, 1.0, 0.4, 100001, 3, &m), CF_ERR_INVALID_ARG);
        CHECK_STATUS(cf_generate_double_torus(ctx, 201, &m), CF_ERR_INVALID_ARG);
        CHECK_OK(ctx, cf_generate_cylinder(ctx, 100000, 1, 1.0, 1.0, &m)); /* and the limit itself is accepted */
        cf_mesh_destroy(&m);
        cf_context_destroy(&ctx);
    }

    /* M4: range messages print limits that read back as themselves */
    CHECK_RUN("flow g/in.obj -o g/o.obj -m spin-willmore -p boundary_tangent_angle=1.5708", 1);
    CHECK_ERR("parameter 'boundary_tangent_angle': 1.5708 is outside [-1.5707963267948966, 1.5707963267948966] "
              "(above the largest accepted value)");
    CHECK_RUN("flow g/in.obj -o g/o.obj -m spin-willmore -n 0 -q -p boundary_tangent_angle=1.5707963267948966", 0);
    CHECK_RUN("flow --method spin-willmore --list-params", 0);
    CHECK(strstr(cft_out, "boundary_tangent_angle [0] in [-1.5707963267948966, 1.5707963267948966]") != NULL);
    CHECK_RUN("edit g/bar.obj --handles g/h.json -o g/o.obj --lambda 1.0000001", 1);
    CHECK_ERR("--lambda: '1.0000001' is outside [0, 1]");

    /* M5: a subnormal time step is a number below the smallest accepted one */
    CHECK_RUN("flow g/in.obj -o g/o.obj -m spin-willmore --time-step 1e-320", 1);
    CHECK_ERR("parameter 'time_step': 1e-320 is outside [1e-09, 10] (below the smallest accepted value)");
    CHECK_RUN("flow g/in.obj -o g/o.obj -m implicit-mcf -p time_step=1e400", 1);
    CHECK_ERR("parameter 'time_step': '1e400' is not a finite number");
    CHECK_RUN("flow g/in.obj -o g/o.obj -m implicit-mcf -p time_step=fast", 1);
    CHECK_ERR("parameter 'time_step': 'fast' is not a number");
    CHECK_RUN("curve g/c.csv -o g/c2.csv --time-step 1e-320 --steps 1 -q", 0); /* the tool's own parser agrees */
    CHECK_RUN("render g/in.obj -o g/s.png --view 1e999,0,1", 1);
    CHECK_ERR("--view: expected X,Y,Z (3 finite numbers), got '1e999,0,1'");
    CHECK_RUN("render g/in.obj -o g/s.png --view nan,0,1", 1);

    /* unknown or ineffective options are usage errors, never ignored */
    CHECK_RUN("generate cylinder --nx 5 -o g/cyl.obj", 1);
    CHECK_ERR("curvflow: generate cylinder: --nx is not an option of cylinder (its options: --n-around, --n-along, "
              "--radius, --height)");
    CHECK_RUN("generate icosphere --seed 3 -o g/cyl.obj", 1);
    CHECK_ERR("--seed is not an option of icosphere");
    CHECK(!cft_exists("g/cyl.obj"));
    CHECK_RUN("render g/in.obj -o g/s.png --range 0,1", 1);
    CHECK_ERR("--range is the colour range of --field; give --field too");
    CHECK_RUN("render g/in.obj -o g/s.png --checker-count 4", 1);
    CHECK_ERR("--checker-count sets the squares of --uv-checker; give --uv-checker too");
    CHECK_RUN("edit g/bar.obj --handles g/h.json -o g/o.obj --energy arap --lambda 0.3", 1);
    CHECK_ERR("--lambda weighs --energy hybrid; it has no effect with --energy arap");
    CHECK_RUN("spin g/in.obj --rho x --bogus -o g/o.obj", 1);
    CHECK_ERR("curvflow: unrecognized option '--bogus'");
    CHECK_RUN("curve g/c.csv -o g/c2.csv --steps", 1);
    CHECK_ERR("curvflow: option '--steps' requires an argument");

    /* the log is written atomically: complete logs only; after a numerical
     * failure it holds the steps up to the last good one */
    CHECK_RUN("flow g/in.obj -o g/blown.obj -m explicit-mcf --time-step 10 --steps 20 --log g/blown.jsonl -q", 3);
    CHECK(cft_exists("g/blown.jsonl"));
    static char log[1 << 16];
    read_named("g/blown.jsonl", log, sizeof log);
    CHECK(count_lines(log) >= 1 && strncmp(log, "{\"iteration\":0,", 14) == 0);
}

/* Read-only and non-regular targets, and symbolic links as targets. */
static void test_existing_targets(void)
{
    static char before[1 << 16], after[1 << 16];
    CHECK_RUN("generate icosphere --subdivisions 1 -o g/ro.obj", 0);
    CHECK(chmod(cft_in_dir("g/ro.obj"), 0444) == 0);
    read_named("g/ro.obj", before, sizeof before);
    CHECK_RUN("flow g/in.obj -o g/ro.obj -m implicit-mcf -n 1 -q", 2);
    CHECK_ERR("curvflow: g/ro.obj: the existing file is read-only; --force replaces it");
    CHECK_RUN("generate icosphere --subdivisions 2 -o g/ro.obj", 2);
    CHECK_ERR("g/ro.obj: the existing file is read-only");
    read_named("g/ro.obj", after, sizeof after);
    CHECK(strcmp(before, after) == 0);
    CHECK_RUN("generate icosphere --subdivisions 2 -o g/ro.obj --force", 0);
    read_named("g/ro.obj", after, sizeof after);
    CHECK(strcmp(before, after) != 0);
    struct stat sb;
    CHECK(stat(cft_in_dir("g/ro.obj"), &sb) == 0 && (sb.st_mode & 0777) == 0444); /* it stays read-only */

    /* a FIFO (or a device) is never replaced by a regular file */
    CHECK(mkfifo(cft_in_dir("g/fifo.obj"), 0666) == 0);
    CHECK_RUN("generate icosphere -o g/fifo.obj --force", 2);
    CHECK_ERR("g/fifo.obj: exists and is not a regular file; refusing to replace it");
    CHECK(lstat(cft_in_dir("g/fifo.obj"), &sb) == 0 && S_ISFIFO(sb.st_mode));
    CHECK_RUN("render g/in.obj -o g", 2);
    CHECK_ERR("curvflow: g: is a directory");

    /* a symbolic link is written through: the link stays, its target changes */
    CHECK(mkdir(cft_in_dir("g/real"), 0777) == 0);
    CHECK_RUN("generate icosphere --subdivisions 1 -o g/real/t.obj", 0);
    CHECK(symlink("real/t.obj", cft_in_dir("g/link.obj")) == 0);
    CHECK_RUN("flow g/in.obj -o g/link.obj -m implicit-mcf -n 2 -q", 0);
    CHECK(lstat(cft_in_dir("g/link.obj"), &sb) == 0 && S_ISLNK(sb.st_mode));
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("g/real/t.obj"), &m));
    cf_mesh *in = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("g/in.obj"), &in));
    if (m && in) /* the flow's result, not the icosphere written before */
        CHECK(memcmp(cf_mesh_positions(m), cf_mesh_positions(in), 3 * sizeof(double)) != 0);
    cf_mesh_destroy(&m);
    cf_mesh_destroy(&in);
    cf_context_destroy(&ctx);
    CHECK(symlink("real/new.png", cft_in_dir("g/dangling.png")) == 0); /* creates what the link names */
    CHECK_RUN("render g/in.obj -o g/dangling.png --size 8x8", 0);
    CHECK(lstat(cft_in_dir("g/dangling.png"), &sb) == 0 && S_ISLNK(sb.st_mode));
    CHECK(cft_exists("g/real/new.png"));
}

/* Temporary files of a run killed without a chance to clean up (SIGKILL)
 * are removed by the next run that writes the same output, if their pid
 * no longer runs. */
static void test_stale_temp_files(void)
{
    pid_t dead = fork();
    if (dead == 0) _exit(0);
    CHECK(dead > 0 && waitpid(dead, NULL, 0) == dead);
    char stale[256], live[256];
    snprintf(stale, sizeof stale, "g/.st.obj.tmp-%ld-42", (long)dead);
    snprintf(live, sizeof live, "g/.st.obj.tmp-%ld-43", (long)getpid()); /* this test runs: kept */
    write_text(stale, "partial");
    write_text(live, "partial");
    CHECK_RUN("generate icosphere --subdivisions 1 -o g/st.obj", 0);
    CHECK_ERR("curvflow: removed 1 temporary file of an ended run next to g/st.obj");
    CHECK(!cft_exists(stale) && cft_exists(live));
    unlink(cft_in_dir(live));
}

/* Files whose names start with ".<name>.tmp" in folder `sub` of the test folder. */
static int temp_files_in(const char *sub)
{
    DIR *d = opendir(cft_in_dir(sub));
    if (!d) return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) n += e->d_name[0] == '.' && strstr(e->d_name, ".tmp-") != NULL;
    closedir(d);
    return n;
}

/* SIGINT, SIGTERM and SIGHUP sent to a long flow: it dies of the signal,
 * its temporary log is removed, and the previous log stays as it was. */
static void test_signals_remove_temp_files(void)
{
    CHECK_RUN("generate icosphere --subdivisions 3 -o g/sig_in.obj", 0);
    const int sigs[] = {SIGINT, SIGTERM, SIGHUP};
    for (int k = 0; k < 3; ++k) {
        write_text("g/sig.jsonl", "old log\n");
        fflush(NULL);
        pid_t pid = fork();
        CHECK(pid >= 0);
        if (pid < 0) return;
        if (pid == 0) {
            /* the default dispositions a shell would give a foreground job */
            sigset_t none;
            sigemptyset(&none);
            sigprocmask(SIG_SETMASK, &none, NULL);
            for (int i = 0; i < 3; ++i) signal(sigs[i], SIG_DFL);
            int null = open("/dev/null", O_WRONLY);
            if (chdir(cft_dir) != 0 || null < 0) _exit(127);
            dup2(null, 1);
            dup2(null, 2);
            execl(CF_TEST_CLI, CF_TEST_CLI, "flow", "g/sig_in.obj", "-o", "g/sig.obj", "-m", "explicit-mcf", "-t",
                  "0.01", "-p", "rescale=true", "-n", "1000000000", "--log", "g/sig.jsonl", "-q", (char *)NULL);
            _exit(127);
        }
        /* wait (up to a minute, polling) until the run writes its temporary log */
        int seen = 0;
        for (int t = 0; t < 6000 && !seen; ++t) {
            seen = temp_files_in("g") > 0;
            if (!seen) nanosleep(&(struct timespec){0, 10000000}, NULL);
        }
        CHECK(seen);
        kill(pid, sigs[k]);
        int status = 0;
        CHECK(waitpid(pid, &status, 0) == pid);
        ++cft_checks;
        if (!(WIFSIGNALED(status) && WTERMSIG(status) == sigs[k]))
            cft_fail(__FILE__, __LINE__, "signal %d: status %#x (exited %d with %d)", sigs[k], status,
                     WIFEXITED(status), WIFEXITED(status) ? WEXITSTATUS(status) : -1);
        CHECK(temp_files_in("g") == 0);
        static char log[64];
        read_named("g/sig.jsonl", log, sizeof log);
        CHECK(strcmp(log, "old log\n") == 0);
        CHECK(!cft_exists("g/sig.obj"));
    }
}

/* CURVFLOW_THREADS: the solver threads (cf_context_set_threads). A value
 * other than an integer 0..1024 is a usage error before any command runs;
 * 0 and 2 give the default's result up to rounding (OpenBLAS's reductions). */
static void test_threads_variable(void)
{
    CHECK_RUN("generate bumpy-sphere --subdivisions 3 -o threads_in.obj", 0);
    const char *bad[] = {"CURVFLOW_THREADS=abc", "CURVFLOW_THREADS=-1", "CURVFLOW_THREADS=' 2'", "CURVFLOW_THREADS=1025",
                         "CURVFLOW_THREADS="};
    for (int i = 0; i < 5; ++i) {
        cft_cli_env = bad[i];
        CHECK_RUN("info threads_in.obj", 1);
        CHECK(strstr(cft_err, "CURVFLOW_THREADS must be an integer from 0 to 1024, got '") != NULL);
        CHECK(count_lines(cft_err) == 1);
    }
    const char *good[] = {"", "CURVFLOW_THREADS=0", "CURVFLOW_THREADS=2"};
    const char *out[] = {"threads_default.obj", "threads_0.obj", "threads_2.obj"};
    for (int i = 0; i < 3; ++i) {
        cft_cli_env = good[i];
        char args[160];
        snprintf(args, sizeof args, "flow threads_in.obj -o %s --method spin-willmore -n 3 -q", out[i]);
        CHECK_RUN(args, 0);
    }
    /* With the default the result does not depend on OpenBLAS's own count
     * (OPENBLAS_NUM_THREADS, one per core when unset): the same bytes on
     * machines with any number of cores. (With CURVFLOW_THREADS=0 this
     * mesh's result differs in the last bits between 1 and 2.) */
    const char *blas[] = {"OPENBLAS_NUM_THREADS=1", "OPENBLAS_NUM_THREADS=2"};
    for (int i = 0; i < 2; ++i) {
        cft_cli_env = blas[i];
        char args[160];
        snprintf(args, sizeof args, "flow threads_in.obj -o threads_blas%d.obj --method spin-willmore -n 3 -q", i + 1);
        CHECK_RUN(args, 0);
    }
    cft_cli_env = "";
    CHECK(cft_shell("cmp threads_blas1.obj threads_blas2.obj") == 0);
    CHECK(cft_shell("cmp threads_blas1.obj threads_default.obj") == 0);
    cf_context *ctx = cft_context();
    cf_mesh *m[3] = {NULL, NULL, NULL};
    for (int i = 0; i < 3; ++i) CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir(out[i]), &m[i]));
    if (m[0] && m[1] && m[2]) {
        const double *x0 = cf_mesh_positions(m[0]);
        double d = 0.0;
        for (int i = 1; i < 3; ++i) {
            const double *x = cf_mesh_positions(m[i]);
            for (int32_t k = 0; k < 3 * cf_mesh_vertex_count(m[0]); ++k) d = fmax(d, fabs(x[k] - x0[k]));
        }
        CHECK_LE(d, 1e-9);
    }
    for (int i = 0; i < 3; ++i) cf_mesh_destroy(&m[i]);
    cf_context_destroy(&ctx);
}

int main(void)
{
    if (cft_cli_setup("cli")) return 1;
    CFT_RUN(test_help_and_usage);
    CFT_RUN(test_generate);
    CFT_RUN(test_info);
    CFT_RUN(test_flow);
    CFT_RUN(test_flow_keeps_properties);
    CFT_RUN(test_flow_keeps_materials);
    CFT_RUN(test_compare);
    CFT_RUN(test_demo);
    CFT_RUN(test_render);
    CFT_RUN(test_curve);
    CFT_RUN(test_misuse_reproducers);
    CFT_RUN(test_existing_targets);
    CFT_RUN(test_stale_temp_files);
    CFT_RUN(test_signals_remove_temp_files);
    CFT_RUN(test_no_temp_files);
    CFT_RUN(test_threads_variable);
    return cft_cli_finish();
}
