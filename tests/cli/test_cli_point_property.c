/*
 * Point sets from an integer PLY vertex property (`-p handles=@PROP`, the
 * one CLI loader of array parameters): 0 = in no set, k > 0 = in set k,
 * every member fixed at its position in the start state. On a 6 x 6 grid
 * written by the test (ascii PLY with an int property `sel`: sets 1 and 2
 * on two opposite edges), an edit from a perturbed start keeps the members
 * exactly where the start has them and moves the others; the same sets as
 * a JSON file of vertex lists give the same result bit for bit. Refused
 * with exit 2 and a message naming property and vertex: a fractional or
 * negative number, no vertex in a set, every vertex in a set, a missing
 * property.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli_test.h"

#include "curvflow/io.h"
#include "curvflow/mesh.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define G 6 /* grid side */

/* Set number of grid vertex (x, y): 1 on the column x = 0, 2 on x = G - 1. */
static int set_of(int x) { return x == 0 ? 1 : x == G - 1 ? 2 : 0; }

/* Ascii PLY of the G x G grid in the plane z = 0 (z = bump * (x, y) bump
 * when bumped), with vertex property `sel` of type `type` whose value is
 * set_of(x) unless `override` >= 0 names a vertex whose value is `value`
 * (written as text). all_value >= 0: every vertex gets that value. */
static void write_grid(const char *name, const char *type, double bump, int override, const char *value, int all_value)
{
    FILE *f = fopen(cft_in_dir(name), "w");
    fprintf(f, "ply\nformat ascii 1.0\nelement vertex %d\nproperty double x\nproperty double y\nproperty double z\n"
               "property %s sel\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n",
            G * G, type, 2 * (G - 1) * (G - 1));
    for (int y = 0; y < G; ++y)
        for (int x = 0; x < G; ++x) {
            int i = y * G + x;
            double z = bump * (double)(x * (G - 1 - x) * y * (G - 1 - y)) / 36.0;
            char sel[64];
            if (i == override) snprintf(sel, sizeof sel, "%s", value);
            else snprintf(sel, sizeof sel, "%d", all_value >= 0 ? all_value : set_of(x));
            fprintf(f, "%g %g %.17g %s\n", (double)x, (double)y, z, sel);
        }
    for (int y = 0; y + 1 < G; ++y)
        for (int x = 0; x + 1 < G; ++x) {
            int a = y * G + x, b = a + 1, c = a + G, d = c + 1;
            fprintf(f, "3 %d %d %d\n3 %d %d %d\n", a, b, d, a, d, c);
        }
    fclose(f);
}

static void test_fixed_sets_from_property(void)
{
    write_grid("grid.ply", "int", 0.0, -1, NULL, -1);
    write_grid("bumped.ply", "int", 1.5, -1, NULL, -1); /* the start: same faces, interior lifted */
    CHECK_RUN("flow grid.ply --method stretch-bend-edit -p handles=@sel --start bumped.ply -n 20 -o out.ply -q", 0);
    int32_t nv = 0, ns = 0;
    double *out = cft_load_positions("out.ply", &nv), *start = cft_load_positions("bumped.ply", &ns);
    CHECK(out && start && nv == G * G && ns == nv);
    if (!out || !start || nv != ns) return;
    double moved = 0.0;
    for (int32_t i = 0; i < nv; ++i) {
        double d = fabs(out[3 * i] - start[3 * i]) + fabs(out[3 * i + 1] - start[3 * i + 1]) +
                   fabs(out[3 * i + 2] - start[3 * i + 2]);
        if (set_of(i % G)) CHECK(d == 0.0); /* members stay exactly where they start */
        else moved = fmax(moved, d);
    }
    fprintf(stderr, "  largest move of a free vertex %.3g\n", moved);
    CHECK(moved > 0.05); /* the lifted interior relaxes toward the flat rest pose */
    /* the same sets as a JSON constraint file of vertex lists: identical */
    FILE *f = fopen(cft_in_dir("sets.json"), "w");
    fputs("{\"sets\": [", f);
    for (int s = 1; s <= 2; ++s) {
        fprintf(f, "%s{\"name\": \"%d\", \"vertices\": [", s == 1 ? "" : ", ", s);
        int first = 1;
        for (int i = 0; i < G * G; ++i)
            if (set_of(i % G) == s) {
                fprintf(f, "%s%d", first ? "" : ", ", i);
                first = 0;
            }
        fputs("], \"fixed\": true}", f);
    }
    fputs("]}\n", f);
    fclose(f);
    CHECK_RUN("flow grid.ply --method stretch-bend-edit -p handles=sets.json --start bumped.ply -n 20 -o json.ply -q",
              0);
    int32_t nj = 0;
    double *viajson = cft_load_positions("json.ply", &nj);
    CHECK(viajson && nj == nv);
    if (viajson && nj == nv) CHECK(memcmp(viajson, out, 3 * (size_t)nv * sizeof *out) == 0);
    free(viajson);
    free(out);
    free(start);
    /* a float property with integral values is the same; --handles and
     * `curvflow edit` take the same spelling */
    write_grid("gridf.ply", "float", 0.0, -1, NULL, -1);
    CHECK_RUN("flow gridf.ply --method stretch-bend-edit --handles @sel -n 2 -o f.ply -q", 0);
    EXPECT("edit gridf.ply --handles @sel --iterations 2 -o e.ply", 0, "@sel: 12 handle vertices (0 moved), 24 free");
}

static void test_refusals(void)
{
    write_grid("frac.ply", "float", 0.0, 14, "1.5", -1);
    EXPECT("flow frac.ply --method stretch-bend-edit -p handles=@sel -n 1 -o x.ply", 2,
           "property 'sel' of vertex 14 is 1.5, not a set number");
    write_grid("neg.ply", "int", 0.0, 7, "-2", -1);
    EXPECT("flow neg.ply --method stretch-bend-edit -p handles=@sel -n 1 -o x.ply", 2,
           "property 'sel' of vertex 7 is -2, not a set number");
    write_grid("none.ply", "int", 0.0, -1, NULL, 0);
    EXPECT("flow none.ply --method stretch-bend-edit -p handles=@sel -n 1 -o x.ply", 2,
           "property 'sel' puts no vertex in a set");
    write_grid("all.ply", "int", 0.0, -1, NULL, 3);
    EXPECT("flow all.ply --method stretch-bend-edit -p handles=@sel -n 1 -o x.ply", 2,
           "puts all 36 vertices in sets; nothing is left to deform");
    EXPECT("flow frac.ply --method stretch-bend-edit -p handles=@nosuch -n 1 -o x.ply", 2, "no vertex property 'nosuch'");
    EXPECT("flow frac.ply --method stretch-bend-edit -p handles=@ -n 1 -o x.ply", 1, "expected @PROPERTY");
    CHECK(!cft_exists("x.ply"));
}

int main(void)
{
    if (cft_cli_setup("cli_point_property")) return 1;
    CFT_RUN(test_fixed_sets_from_property);
    CFT_RUN(test_refusals);
    return cft_cli_finish();
}
