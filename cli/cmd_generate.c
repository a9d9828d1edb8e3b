/*
 * curvflow generate KIND [params] -o OUT: writes a built-in mesh
 * (include/curvflow/generate.h), seeded and deterministic.
 *
 * One table says which options each kind takes, with their defaults and,
 * for counts, the generator's own limits: an option the kind does not use
 * is a usage error (it used to be ignored), and a count outside the limits
 * is refused naming the option and the range the generator accepts.
 */
#define _GNU_SOURCE
#include "common.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"

#include <getopt.h>
#include <math.h>
#include <string.h>

typedef enum gen_option {
    O_SUBDIV, O_RADIUS, O_SEED, O_AMPLITUDE, O_MAJOR, O_MINOR, O_NMAJOR, O_NMINOR, O_NX, O_NY, O_NZ, O_WIDTH,
    O_HEIGHT, O_DEPTH, O_NAROUND, O_NALONG, O_SIZE, O_N, O_PATTERN, O_RESOLUTION, O_LIMBS, O_LENGTH, O_COUNT
} gen_option;

static const char *const option_names[O_COUNT] = {
    "subdivisions", "radius", "seed", "amplitude", "major-radius", "minor-radius", "n-major", "n-minor",
    "nx", "ny", "nz", "width", "height", "depth", "n-around", "n-along", "size", "n", "pattern", "resolution",
    "limbs", "length"};

/* One option of a kind: its default and, for an integer, the range the
 * generator accepts (generate.h / src/mesh/generate.c; tests/cli checks
 * that one past each limit is refused by the generator too). Lengths are
 * checked by the generator (positive, etc.) after the tool's range check. */
typedef struct gen_param {
    gen_option option;
    double fallback;
    bool integer;
    long long min, max;
} gen_param;

enum { KIND_MAX_PARAMS = 8 };
typedef struct gen_kind {
    const char *name;
    const char *note;
    gen_param params[KIND_MAX_PARAMS];
    int count; /* entries of params in use */
} gen_kind;

#define INT(o, d, lo, hi) {o, d, true, lo, hi}
#define LEN(o, d) {o, d, false, 0, 0}
static const gen_kind kinds[] = {
    {"icosphere", NULL, {INT(O_SUBDIV, 3, 0, 9), LEN(O_RADIUS, 1)}, 2},
    {"bumpy-sphere", "per-corner uv", {INT(O_SUBDIV, 4, 0, 9), LEN(O_AMPLITUDE, 0.25), INT(O_SEED, 1, 0, 4294967295LL)}, 3},
    {"limb-sphere", "per-corner uv; the demo's eight-armed star, W/4pi 5.78",
     {INT(O_SUBDIV, 5, 0, 9), INT(O_LIMBS, 8, 1, CF_LIMB_SPHERE_MAX_LIMBS), LEN(O_LENGTH, 1.4), LEN(O_WIDTH, 0.22)}, 4},
    {"torus", NULL,
     {LEN(O_MAJOR, 1), LEN(O_MINOR, 0.4), INT(O_NMAJOR, 48, 3, 100000), INT(O_NMINOR, 24, 3, 100000)}, 4},
    {"grid", NULL, {INT(O_NX, 16, 1, 46000), INT(O_NY, 16, 1, 46000), LEN(O_WIDTH, 1), LEN(O_HEIGHT, 1)}, 4},
    {"cylinder", "per-corner uv",
     {INT(O_NAROUND, 32, 3, 100000), INT(O_NALONG, 16, 1, 100000), LEN(O_RADIUS, 1), LEN(O_HEIGHT, 2)}, 4},
    {"bar", NULL,
     {INT(O_NX, 20, 1, 2000), INT(O_NY, 2, 1, 2000), INT(O_NZ, 2, 1, 2000), LEN(O_WIDTH, 10), LEN(O_HEIGHT, 1),
      LEN(O_DEPTH, 1), INT(O_PATTERN, 0, 0, 1)},
     7},
    {"sheet", NULL, {INT(O_N, 16, 1, 46000), LEN(O_SIZE, 1), INT(O_PATTERN, 0, 0, 1)}, 3},
    {"bumpy-plane", NULL, {INT(O_N, 32, 1, 46000), LEN(O_SIZE, 1), LEN(O_AMPLITUDE, 0.1), INT(O_SEED, 1, 0, 4294967295LL)}, 4},
    {"double-torus", "genus 2", {INT(O_RESOLUTION, 2, 1, 200)}, 1},
};
#undef INT
#undef LEN
#define KIND_COUNT (sizeof kinds / sizeof kinds[0])

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow generate KIND [OPTIONS] -o OUT\n"
            "Writes a built-in mesh (OBJ, OFF or PLY from OUT's extension).\n\n"
            "Kinds and the options they take (defaults in brackets, counts with their range);\n"
            "an option a kind does not take is an error:\n");
    for (size_t k = 0; k < KIND_COUNT; ++k) {
        fprintf(out, "  %-13s", kinds[k].name);
        for (int i = 0; i < kinds[k].count; ++i) {
            const gen_param *p = &kinds[k].params[i];
            if (p->integer)
                fprintf(out, " --%s [%.0f] (%lld..%lld)", option_names[p->option], p->fallback, p->min, p->max);
            else
                fprintf(out, " --%s [%g]", option_names[p->option], p->fallback);
        }
        if (kinds[k].note) fprintf(out, "\n  %-13s (%s)", "", kinds[k].note);
        fputc('\n', out);
    }
    fprintf(out,
            "\n  -o, --output OUT   output mesh: .obj, .off or .ply (required)\n"
            "  -f, --force        replace a read-only OUT\n"
            "  -h, --help         show this help\n");
}

static const gen_param *find_param(const gen_kind *kind, gen_option o)
{
    for (int i = 0; i < kind->count; ++i)
        if (kind->params[i].option == o) return &kind->params[i];
    return NULL;
}

/* "--n-around, --n-along, --radius, --height" */
static void list_options(const gen_kind *kind, char *buf, size_t size)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; i < kind->count && used < size; ++i) {
        int n = snprintf(buf + used, size - used, "%s--%s", i ? ", " : "", option_names[kind->params[i].option]);
        if (n < 0) break;
        used += (size_t)n;
    }
}

int cli_generate(int argc, char **argv)
{
    enum { OPT_FIRST = 256 };
    struct option longopts[O_COUNT + 4];
    for (int i = 0; i < O_COUNT; ++i) longopts[i] = (struct option){option_names[i], required_argument, NULL, OPT_FIRST + i};
    longopts[O_COUNT] = (struct option){"output", required_argument, NULL, 'o'};
    longopts[O_COUNT + 1] = (struct option){"force", no_argument, NULL, 'f'};
    longopts[O_COUNT + 2] = (struct option){"help", no_argument, NULL, 'h'};
    longopts[O_COUNT + 3] = (struct option){NULL, 0, NULL, 0};
    const char *output = NULL, *given[O_COUNT] = {NULL};
    const char *cmd = "generate";
    bool force = false;
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":o:fh", longopts, NULL)) != -1) {
        if (c >= OPT_FIRST && c < OPT_FIRST + O_COUNT) {
            given[c - OPT_FIRST] = optarg;
            continue;
        }
        switch (c) {
        case 'o': output = optarg; break;
        case 'f': force = true; break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error(cmd, c, argv);
        }
    }
    if (optind + 1 != argc) return cli_usage_error(cmd, "expected one mesh kind");
    const char *kind_name = argv[optind];
    const gen_kind *kind = NULL;
    for (size_t k = 0; k < KIND_COUNT && !kind; ++k)
        if (strcmp(kinds[k].name, kind_name) == 0) kind = &kinds[k];
    if (!kind) return cli_usage_error(cmd, "unknown mesh kind '%s'", kind_name);

    /* every option given must be one the kind takes; then its value, in
     * the kind's range (counts) or the range of lengths (the rest) */
    double v[O_COUNT] = {0};
    for (int o = 0; o < O_COUNT; ++o) {
        const gen_param *p = find_param(kind, (gen_option)o);
        if (!p) {
            if (!given[o]) continue;
            char known[256];
            list_options(kind, known, sizeof known);
            return cli_usage_error(cmd, "generate %s: --%s is not an option of %s (its options: %s)", kind->name,
                                   option_names[o], kind->name, known);
        }
        v[o] = p->fallback;
        if (!given[o]) continue;
        char label[96];
        snprintf(label, sizeof label, "generate %s: --%s", kind->name, option_names[o]);
        if (p->integer) {
            long long n = 0;
            if (!cli_parse_int(cmd, label, given[o], p->min, p->max, &n)) return CLI_EXIT_USAGE;
            v[o] = (double)n;
        } else {
            if (!cli_parse_double(cmd, label, given[o], &v[o])) return CLI_EXIT_USAGE;
            /* lengths must stay inside the range the mesh check accepts */
            if (fabs(v[o]) > CF_MAX_COORDINATE)
                return cli_usage_error(cmd, "%s: %g is beyond the range of lengths (|x| <= %.0e)", label, v[o],
                                       CF_MAX_COORDINATE);
        }
    }
    if (!output) return cli_usage_error(cmd, "missing -o OUT");
    cli_files files = {.force = force};
    cli_files_output(&files, "-o", output, CLI_FILE_MESH);

    cf_context *ctx = cli_context(false);
    if (!ctx) return CLI_EXIT_NUMERICAL;
    int code = cli_files_check(ctx, &files);
    if (code != CLI_EXIT_OK) {
        cf_context_destroy(&ctx);
        return code;
    }
    cf_mesh *mesh = NULL;
    cf_status st;
    const char *k = kind->name;
#define I(o) ((int32_t)v[o])
    if (strcmp(k, "icosphere") == 0)
        st = cf_generate_icosphere(ctx, I(O_SUBDIV), v[O_RADIUS], &mesh);
    else if (strcmp(k, "bumpy-sphere") == 0)
        st = cf_generate_bumpy_sphere(ctx, I(O_SUBDIV), v[O_AMPLITUDE], (uint32_t)v[O_SEED], &mesh);
    else if (strcmp(k, "limb-sphere") == 0)
        st = cf_generate_limb_sphere(ctx, I(O_SUBDIV), I(O_LIMBS), v[O_LENGTH], v[O_WIDTH], &mesh);
    else if (strcmp(k, "torus") == 0)
        st = cf_generate_torus(ctx, v[O_MAJOR], v[O_MINOR], I(O_NMAJOR), I(O_NMINOR), &mesh);
    else if (strcmp(k, "grid") == 0)
        st = cf_generate_grid(ctx, I(O_NX), I(O_NY), v[O_WIDTH], v[O_HEIGHT], &mesh);
    else if (strcmp(k, "cylinder") == 0)
        st = cf_generate_cylinder(ctx, I(O_NAROUND), I(O_NALONG), v[O_RADIUS], v[O_HEIGHT], &mesh);
    else if (strcmp(k, "bar") == 0)
        st = cf_generate_bar(ctx, I(O_NX), I(O_NY), I(O_NZ), v[O_WIDTH], v[O_HEIGHT], v[O_DEPTH], I(O_PATTERN), &mesh);
    else if (strcmp(k, "sheet") == 0)
        st = cf_generate_sheet(ctx, I(O_N), v[O_SIZE], I(O_PATTERN), &mesh);
    else if (strcmp(k, "bumpy-plane") == 0)
        st = cf_generate_bumpy_plane(ctx, I(O_N), v[O_SIZE], v[O_AMPLITUDE], (uint32_t)v[O_SEED], &mesh);
    else
        st = cf_generate_double_torus(ctx, I(O_RESOLUTION), &mesh);
#undef I
    if (st != CF_OK) {
        code = cli_fail(ctx, kind->name, st);
    } else if ((st = cf_write_mesh_file(ctx, output, mesh, NULL, NULL, 0)) != CF_OK) {
        code = cli_fail(ctx, output, st);
        if (code == CLI_EXIT_USAGE) code = CLI_EXIT_INPUT;
    } else {
        fprintf(stderr, "curvflow: wrote %s (%d vertices, %d faces)\n", output, (int)cf_mesh_vertex_count(mesh),
                (int)cf_mesh_face_count(mesh));
    }
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
    return code;
}
