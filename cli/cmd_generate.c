/*
 * curvflow generate KIND [params] -o OUT: writes a built-in mesh
 * (include/curvflow/generate.h), seeded and deterministic.
 */
#define _GNU_SOURCE
#include "common.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"

#include <getopt.h>
#include <math.h>
#include <string.h>

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow generate KIND [OPTIONS] -o OUT\n"
            "Writes a built-in mesh (OBJ, OFF or PLY from OUT's extension).\n\n"
            "Kinds and the options they use (defaults in brackets):\n"
            "  icosphere     --subdivisions [3] --radius [1]\n"
            "  bumpy-sphere  --subdivisions [4] --amplitude [0.25] --seed [1]   (per-corner uv)\n"
            "  torus         --major-radius [1] --minor-radius [0.4] --n-major [48] --n-minor [24]\n"
            "  grid          --nx [16] --ny [16] --width [1] --height [1]\n"
            "  cylinder      --n-around [32] --n-along [16] --radius [1] --height [2]\n"
            "  bar           --nx [20] --ny [2] --nz [2] --width [10] --height [1] --depth [1] --pattern [0]\n"
            "  sheet         --n [16] --size [1] --pattern [0]\n"
            "  bumpy-plane   --n [32] --size [1] --amplitude [0.1] --seed [1]\n"
            "  double-torus  --resolution [2]\n\n"
            "  -o, --output OUT   output mesh (required)\n"
            "  -h, --help         show this help\n");
}

enum {
    OPT_SUBDIV = 256, OPT_RADIUS, OPT_SEED, OPT_AMPLITUDE, OPT_MAJOR, OPT_MINOR, OPT_NMAJOR, OPT_NMINOR, OPT_NX,
    OPT_NY, OPT_NZ, OPT_WIDTH, OPT_HEIGHT, OPT_DEPTH, OPT_NAROUND, OPT_NALONG, OPT_SIZE, OPT_N, OPT_PATTERN,
    OPT_RESOLUTION
};

static double or_default(double given, double fallback) { return isnan(given) ? fallback : given; }

int cli_generate(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"subdivisions", required_argument, NULL, OPT_SUBDIV}, {"radius", required_argument, NULL, OPT_RADIUS},
        {"seed", required_argument, NULL, OPT_SEED}, {"amplitude", required_argument, NULL, OPT_AMPLITUDE},
        {"major-radius", required_argument, NULL, OPT_MAJOR}, {"minor-radius", required_argument, NULL, OPT_MINOR},
        {"n-major", required_argument, NULL, OPT_NMAJOR}, {"n-minor", required_argument, NULL, OPT_NMINOR},
        {"nx", required_argument, NULL, OPT_NX}, {"ny", required_argument, NULL, OPT_NY},
        {"nz", required_argument, NULL, OPT_NZ}, {"width", required_argument, NULL, OPT_WIDTH},
        {"height", required_argument, NULL, OPT_HEIGHT}, {"depth", required_argument, NULL, OPT_DEPTH},
        {"n-around", required_argument, NULL, OPT_NAROUND}, {"n-along", required_argument, NULL, OPT_NALONG},
        {"size", required_argument, NULL, OPT_SIZE}, {"n", required_argument, NULL, OPT_N},
        {"pattern", required_argument, NULL, OPT_PATTERN}, {"resolution", required_argument, NULL, OPT_RESOLUTION},
        {"output", required_argument, NULL, 'o'}, {"help", no_argument, NULL, 'h'}, {NULL, 0, NULL, 0}};
    const char *output = NULL;
    long long subdiv = -1, seed = 1, n_major = 48, n_minor = 24, nx = -1, ny = -1, nz = 2, n_around = 32,
              n_along = 16, n = -1, pattern = 0, resolution = 2;
    /* NAN = not given (kind-specific default); cli_parse_double never yields NaN,
     * so an explicit negative value reaches the generator and is rejected
     * there instead of silently becoming the default */
    double radius = 1.0, amplitude = NAN, major = 1.0, minor = 0.4, width = NAN, height = NAN, depth = 1.0,
           size = 1.0;
    const char *cmd = "generate";
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":o:h", longopts, NULL)) != -1) {
        bool ok = true;
        switch (c) {
        case 'o': output = optarg; break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        case OPT_SUBDIV: ok = cli_parse_int(cmd, "--subdivisions", optarg, 0, 9, &subdiv); break;
        case OPT_SEED: ok = cli_parse_int(cmd, "--seed", optarg, 0, 4294967295LL, &seed); break;
        case OPT_NMAJOR: ok = cli_parse_int(cmd, "--n-major", optarg, 3, 1 << 20, &n_major); break;
        case OPT_NMINOR: ok = cli_parse_int(cmd, "--n-minor", optarg, 3, 1 << 20, &n_minor); break;
        case OPT_NX: ok = cli_parse_int(cmd, "--nx", optarg, 1, 1 << 15, &nx); break;
        case OPT_NY: ok = cli_parse_int(cmd, "--ny", optarg, 1, 1 << 15, &ny); break;
        case OPT_NZ: ok = cli_parse_int(cmd, "--nz", optarg, 1, 1 << 15, &nz); break;
        case OPT_NAROUND: ok = cli_parse_int(cmd, "--n-around", optarg, 3, 1 << 20, &n_around); break;
        case OPT_NALONG: ok = cli_parse_int(cmd, "--n-along", optarg, 1, 1 << 20, &n_along); break;
        case OPT_N: ok = cli_parse_int(cmd, "--n", optarg, 1, 1 << 15, &n); break;
        case OPT_PATTERN: ok = cli_parse_int(cmd, "--pattern", optarg, 0, 1, &pattern); break;
        case OPT_RESOLUTION: ok = cli_parse_int(cmd, "--resolution", optarg, 1, 256, &resolution); break;
        case OPT_RADIUS: ok = cli_parse_double(cmd, "--radius", optarg, &radius); break;
        case OPT_AMPLITUDE: ok = cli_parse_double(cmd, "--amplitude", optarg, &amplitude); break;
        case OPT_MAJOR: ok = cli_parse_double(cmd, "--major-radius", optarg, &major); break;
        case OPT_MINOR: ok = cli_parse_double(cmd, "--minor-radius", optarg, &minor); break;
        case OPT_WIDTH: ok = cli_parse_double(cmd, "--width", optarg, &width); break;
        case OPT_HEIGHT: ok = cli_parse_double(cmd, "--height", optarg, &height); break;
        case OPT_DEPTH: ok = cli_parse_double(cmd, "--depth", optarg, &depth); break;
        case OPT_SIZE: ok = cli_parse_double(cmd, "--size", optarg, &size); break;
        default: return cli_option_error(cmd, c, argv);
        }
        if (!ok) return CLI_EXIT_USAGE;
    }
    /* lengths must stay inside the range the mesh check accepts */
    const struct { const char *name; double value; } lengths[] = {
        {"--radius", radius}, {"--amplitude", amplitude}, {"--major-radius", major}, {"--minor-radius", minor},
        {"--width", width},   {"--height", height},       {"--depth", depth},        {"--size", size}};
    for (size_t i = 0; i < sizeof lengths / sizeof lengths[0]; ++i)
        if (fabs(lengths[i].value) > CF_MAX_COORDINATE) /* NaN (not given) compares false */
            return cli_usage_error(cmd, "%s: %g is beyond the range of lengths (|x| <= %.0e)", lengths[i].name,
                                   lengths[i].value, CF_MAX_COORDINATE);
    if (optind + 1 != argc) return cli_usage_error(cmd, "expected one mesh kind");
    if (!output) return cli_usage_error(cmd, "missing -o OUT");
    const char *kind = argv[optind];

    cf_context *ctx = cli_context(false);
    if (!ctx) return CLI_EXIT_NUMERICAL;
    cf_mesh *mesh = NULL;
    cf_status st;
    if (strcmp(kind, "icosphere") == 0) {
        st = cf_generate_icosphere(ctx, (int32_t)(subdiv < 0 ? 3 : subdiv), radius, &mesh);
    } else if (strcmp(kind, "bumpy-sphere") == 0) {
        st = cf_generate_bumpy_sphere(ctx, (int32_t)(subdiv < 0 ? 4 : subdiv), or_default(amplitude, 0.25),
                                      (uint32_t)seed, &mesh);
    } else if (strcmp(kind, "torus") == 0) {
        st = cf_generate_torus(ctx, major, minor, (int32_t)n_major, (int32_t)n_minor, &mesh);
    } else if (strcmp(kind, "grid") == 0) {
        st = cf_generate_grid(ctx, (int32_t)(nx < 0 ? 16 : nx), (int32_t)(ny < 0 ? 16 : ny), or_default(width, 1.0),
                              or_default(height, 1.0), &mesh);
    } else if (strcmp(kind, "cylinder") == 0) {
        st = cf_generate_cylinder(ctx, (int32_t)n_around, (int32_t)n_along, radius, or_default(height, 2.0), &mesh);
    } else if (strcmp(kind, "bar") == 0) {
        st = cf_generate_bar(ctx, (int32_t)(nx < 0 ? 20 : nx), (int32_t)(ny < 0 ? 2 : ny), (int32_t)nz,
                             or_default(width, 10.0), or_default(height, 1.0), depth, (int32_t)pattern, &mesh);
    } else if (strcmp(kind, "sheet") == 0) {
        st = cf_generate_sheet(ctx, (int32_t)(n < 0 ? 16 : n), size, (int32_t)pattern, &mesh);
    } else if (strcmp(kind, "bumpy-plane") == 0) {
        st = cf_generate_bumpy_plane(ctx, (int32_t)(n < 0 ? 32 : n), size, or_default(amplitude, 0.1),
                                     (uint32_t)seed, &mesh);
    } else if (strcmp(kind, "double-torus") == 0) {
        st = cf_generate_double_torus(ctx, (int32_t)resolution, &mesh);
    } else {
        cf_context_destroy(&ctx);
        return cli_usage_error(cmd, "unknown mesh kind '%s'", kind);
    }
    int code = CLI_EXIT_OK;
    if (st != CF_OK) {
        code = cli_fail(ctx, kind, st);
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
