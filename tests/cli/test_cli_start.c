/*
 * `curvflow flow --start S`: the flow starts from the positions of S while
 * IN stays the reference. Resuming a run from its own output continues it
 * exactly (conformal MCF, whose stiffness and scale-free step come from the
 * reference: 3 + 3 steps from the 3-step output give the 6-step result and
 * log, which a start taken as the reference would not); the log's
 * iteration 0 is the start, with drifts against IN. A start whose
 * connectivity differs is refused with exit 2 naming the first difference
 * (counts, or the first differing face with both vertex triples); a start
 * with a non-finite coordinate or a missing file exits 2; the edit front
 * end's --start goes through the same path.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli_test.h"

#include "curvflow/io.h"
#include "curvflow/mesh.h"

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Largest |a - b| over the largest |a|. */
static double max_rel_diff(const double *a, const double *b, int32_t n)
{
    double d = 0.0, big = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        d = fmax(d, fabs(a[i] - b[i]));
        big = fmax(big, fabs(a[i]));
    }
    return d / big;
}

/* Field `key` of record `index` of a JSONL log (NaN if absent). */
static double log_field(const char *name, int index, const char *key)
{
    FILE *f = fopen(cft_in_dir(name), "r");
    if (!f) return NAN;
    static char line[1 << 15];
    double v = NAN;
    for (int i = 0; fgets(line, sizeof line, f); ++i) {
        if (i != index) continue;
        json_error_t err;
        json_t *o = json_loads(line, 0, &err);
        if (o) v = json_number_value(json_object_get(o, key));
        json_decref(o);
        break;
    }
    fclose(f);
    return v;
}

static void test_resume_continues_the_run(void)
{
    CHECK_RUN("generate bumpy-sphere --subdivisions 3 -o bumpy.obj", 0);
    CHECK_RUN("flow bumpy.obj --method conformal-mcf -n 6 -o six.ply --log six.jsonl -q", 0);
    CHECK_RUN("flow bumpy.obj --method conformal-mcf -n 3 -o three.ply --log three.jsonl -q", 0);
    CHECK_RUN("flow bumpy.obj --method conformal-mcf -n 3 --start three.ply -o resumed.ply --log resumed.jsonl -q",
              0);
    int32_t n6 = 0, nr = 0;
    double *x6 = cft_load_positions("six.ply", &n6), *xr = cft_load_positions("resumed.ply", &nr);
    CHECK(x6 && xr && n6 == nr && n6 > 0);
    if (x6 && xr && n6 == nr) {
        double d = max_rel_diff(x6, xr, 3 * n6);
        fprintf(stderr, "  6 steps vs 3 + 3 resumed: %.3g\n", d);
        /* the PLY output keeps doubles and the arithmetic is the same, so
         * equal up to the last bits; with the start as the reference the
         * stiffness and the scale-free step would be the start's */
        CHECK_LE(d, 1e-12);
    }
    /* the log: iteration 0 is the start (energy of step 3, drift against
     * IN), the last record the 6-step one */
    CHECK_NEAR(log_field("resumed.jsonl", 0, "energy"), log_field("three.jsonl", 3, "energy"), 1e-12, 0);
    CHECK_NEAR(log_field("resumed.jsonl", 0, "area_drift"), log_field("three.jsonl", 3, "area_drift"), 1e-9, 1e-15);
    CHECK(log_field("resumed.jsonl", 0, "area_drift") < -0.01);
    CHECK_NEAR(log_field("resumed.jsonl", 3, "energy"), log_field("six.jsonl", 6, "energy"), 1e-12, 0);
    CHECK_NEAR(log_field("resumed.jsonl", 3, "area_drift"), log_field("six.jsonl", 6, "area_drift"), 1e-9, 1e-15);
    free(x6);
    free(xr);
    /* spin-willmore from a resumed state runs too (its input metric is IN's) */
    CHECK_RUN("flow bumpy.obj --method spin-willmore -n 2 -o spin2.ply -q", 0);
    CHECK_RUN("flow bumpy.obj --method spin-willmore -n 2 --start spin2.ply -o spin4.ply -q", 0);
    /* the help names the option */
    CHECK_RUN("flow --help", 0);
    CHECK(strstr(cft_out, "--start MESH") != NULL);
}

/* Writes a 4-vertex, 4-face tetrahedron OBJ with the given first face and
 * first vertex's x. */
static void write_tet(const char *name, const char *face0, const char *x0)
{
    FILE *f = fopen(cft_in_dir(name), "w");
    fprintf(f, "v %s 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n%s\nf 1 2 4\nf 2 3 4\nf 3 1 4\n", x0, face0);
    fclose(f);
}

static void test_refusals(void)
{
    write_tet("tet.obj", "f 1 3 2", "0");
    write_tet("moved.obj", "f 1 3 2", "-0.25");
    CHECK_RUN("flow tet.obj --method implicit-mcf -n 1 --start moved.obj -o ok.obj -q", 0);
    /* the same face listed from another corner: a different face to the check */
    write_tet("rotated.obj", "f 3 2 1", "0");
    EXPECT("flow tet.obj --method implicit-mcf -n 1 --start rotated.obj -o x.obj -q", 2,
           "face 0 is (2 1 0), in tet.obj it is (0 2 1)");
    CHECK(!cft_exists("x.obj"));
    CHECK_RUN("generate icosphere --subdivisions 1 -o ico.obj", 0);
    EXPECT("flow tet.obj --method implicit-mcf -n 1 --start ico.obj -o x.obj -q", 2,
           "ico.obj: 42 vertices and 80 faces, but tet.obj has 4 and 4");
    EXPECT("flow tet.obj --method implicit-mcf -n 1 --start absent.obj -o x.obj -q", 2, "absent.obj");
    CHECK(!cft_exists("x.obj"));
    /* the start must be a valid mesh of finite positions */
    write_tet("nan.obj", "f 1 3 2", "nan");
    int rc = cft_run("flow tet.obj --method implicit-mcf -n 1 --start nan.obj -o x.obj -q");
    CHECK(rc == 2);
    CHECK(!cft_exists("x.obj"));
    /* --start is an input: it must not be the output */
    EXPECT("flow tet.obj --method implicit-mcf -n 1 --start moved.obj -o moved.obj -q", 2, "moved.obj");
}

static void test_edit_start_same_path(void)
{
    CHECK_RUN("generate bar -o bar.obj", 0);
    FILE *f = fopen(cft_in_dir("h.json"), "w");
    fputs("{\"sets\": [{\"name\": \"a\", \"relative_box\": {\"min\": [0, 0, 0], \"max\": [0.1, 1, 1]}, \"fixed\": true},"
          " {\"name\": \"b\", \"relative_box\": {\"min\": [0.9, 0, 0], \"max\": [1, 1, 1]},"
          " \"transform\": {\"translate\": [0, 1, 0]}}]}\n",
          f);
    fclose(f);
    CHECK_RUN("edit bar.obj --handles h.json --iterations 3 -o e1.obj -q", 0);
    CHECK_RUN("edit bar.obj --handles h.json --iterations 3 --start e1.obj -o e2.obj -q", 0);
    CHECK_RUN("flow bar.obj --method stretch-bend-edit --handles h.json -n 3 --start e1.obj -o f2.obj -q", 0);
    int32_t a = 0, b = 0;
    double *xe = cft_load_positions("e2.obj", &a), *xf = cft_load_positions("f2.obj", &b);
    CHECK(xe && xf && a == b);
    if (xe && xf && a == b) CHECK(max_rel_diff(xe, xf, 3 * a) == 0.0);
    free(xe);
    free(xf);
}

int main(void)
{
    if (cft_cli_setup("cli_start")) return 1;
    CFT_RUN(test_resume_continues_the_run);
    CFT_RUN(test_refusals);
    CFT_RUN(test_edit_start_same_path);
    return cft_cli_finish();
}
