/*
 * curvflow render IN -o OUT.png [--uv-checker] [--field face:NAME] [--colours] [--view x,y,z]:
 * a picture of a mesh with the software renderer (include/curvflow/render.h).
 */
#define _GNU_SOURCE
#include "common.h"
#include "curvflow/io.h"
#include "curvflow/render.h"

#include <getopt.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow render IN -o OUT.png [OPTIONS]\n"
            "Renders the mesh IN to a PNG image (z-buffer, Lambert shading with a headlight).\n\n"
            "  -o, --output OUT.png     output image (required)\n"
            "      --uv-checker         checkerboard from the texture coordinates (shows texture\n"
            "                           preservation; the mesh must have uv)\n"
            "      --checker-count N    squares per unit of uv [16]\n"
            "      --field face:NAME    colour faces by a per-face property of IN (e.g. face:Q from\n"
            "                           'curvflow compare --ply'), blue (low) - white - red (high)\n"
            "      --range MIN,MAX      colour range of the field [data range]\n"
            "      --colours            IN's own colours: its vertex (else face) properties red,\n"
            "                           green, blue in 0..255 (a scan's colours, kept by flow)\n"
            "      --view X,Y,Z         direction from the object towards the camera [0.4,0.5,1]\n"
            "      --up X,Y,Z           screen up direction [0,1,0]\n"
            "      --size WxH           image size in pixels [800x800]\n"
            "      --perspective        perspective instead of orthographic projection\n"
            "  -f, --force              replace a read-only OUT.png\n"
            "  -h, --help               show this help\n\n"
            "OUT must end in .png (the only format written). Exit status: 0 ok, 1 usage error,\n"
            "2 invalid input or an output that cannot or must not be written.\n");
}

/* The file's colours (vertex, else face, properties red green blue in
 * 0..255, as every reader stores them) as the renderer's RGB in [0, 1];
 * *rgb is malloc'd. */
static int file_colours(const char *input, const cf_mesh_data *data, cf_render_options *ro, double **rgb)
{
    static const char *const names[3] = {"red", "green", "blue"};
    for (int face = 0; face < 2; ++face) {
        const cf_mesh_property *p[3];
        for (int c = 0; c < 3; ++c)
            p[c] = face ? cf_mesh_data_face_property(data, names[c]) : cf_mesh_data_vertex_property(data, names[c]);
        if (!p[0] || !p[1] || !p[2]) continue;
        int32_t n = face ? data->face_count : data->vertex_count;
        *rgb = malloc(3 * (size_t)(n > 0 ? n : 1) * sizeof **rgb);
        if (!*rgb) {
            fprintf(stderr, "curvflow: out of memory\n");
            return CLI_EXIT_NUMERICAL;
        }
        for (int32_t i = 0; i < n; ++i)
            for (int c = 0; c < 3; ++c) (*rgb)[3 * (size_t)i + (size_t)c] = p[c]->values[i] / 255.0;
        if (face) ro->face_colors = *rgb;
        else ro->vertex_colors = *rgb;
        return CLI_EXIT_OK;
    }
    fprintf(stderr, "curvflow: %s: --colours: the file has no colours (vertex or face properties red, green, blue)\n",
            input);
    return CLI_EXIT_INPUT;
}

int cli_render(int argc, char **argv)
{
    enum { OPT_CHECKER = 256, OPT_COUNT, OPT_FIELD, OPT_RANGE, OPT_VIEW, OPT_UP, OPT_SIZE, OPT_PERSP, OPT_COLOURS };
    static const struct option longopts[] = {
        {"output", required_argument, NULL, 'o'},     {"uv-checker", no_argument, NULL, OPT_CHECKER},
        {"checker-count", required_argument, NULL, OPT_COUNT}, {"field", required_argument, NULL, OPT_FIELD},
        {"range", required_argument, NULL, OPT_RANGE}, {"view", required_argument, NULL, OPT_VIEW},
        {"up", required_argument, NULL, OPT_UP},       {"size", required_argument, NULL, OPT_SIZE},
        {"perspective", no_argument, NULL, OPT_PERSP}, {"help", no_argument, NULL, 'h'},
        {"force", no_argument, NULL, 'f'},             {"colours", no_argument, NULL, OPT_COLOURS},
        {"colors", no_argument, NULL, OPT_COLOURS},    {NULL, 0, NULL, 0}};
    const char *cmd = "render", *output = NULL, *field = NULL;
    cf_render_options ro;
    cf_render_options_default(&ro);
    bool force = false, range_given = false, count_given = false, colours = false;
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":o:fh", longopts, NULL)) != -1) {
        switch (c) {
        case 'o': output = optarg; break;
        case OPT_CHECKER: ro.uv_checker = 1; break;
        case OPT_COUNT:
            if (!cli_parse_double(cmd, "--checker-count", optarg, &ro.checker_count)) return CLI_EXIT_USAGE;
            if (!(ro.checker_count > 0.0))
                return cli_usage_error(cmd, "--checker-count must be > 0, got '%s'", optarg);
            count_given = true;
            break;
        case OPT_FIELD: field = optarg; break;
        case OPT_RANGE: {
            double r[2];
            if (!cli_parse_doubles(cmd, "--range", optarg, ',', 2, "MIN,MAX", r)) return CLI_EXIT_USAGE;
            if (!(r[0] < r[1])) return cli_usage_error(cmd, "--range: expected MIN < MAX, got '%s'", optarg);
            ro.field_min = r[0];
            ro.field_max = r[1];
            range_given = true;
            break;
        }
        case OPT_VIEW:
            if (!cli_parse_doubles(cmd, "--view", optarg, ',', 3, "X,Y,Z", ro.view)) return CLI_EXIT_USAGE;
            break;
        case OPT_UP:
            if (!cli_parse_doubles(cmd, "--up", optarg, ',', 3, "X,Y,Z", ro.up)) return CLI_EXIT_USAGE;
            break;
        case OPT_SIZE:
            /* the renderer's limit per side (render.h) */
            if (!cli_parse_size(cmd, "--size", optarg, 16384, &ro.width, &ro.height)) return CLI_EXIT_USAGE;
            break;
        case 'f': force = true; break;
        case OPT_PERSP: ro.perspective = 1; break;
        case OPT_COLOURS: colours = true; break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error(cmd, c, argv);
        }
    }
    if (optind + 1 != argc) return cli_usage_error(cmd, "expected one input mesh");
    if (!output) return cli_usage_error(cmd, "missing -o OUT.png");
    if (field && strncmp(field, "face:", 5) != 0)
        return cli_usage_error(cmd, "--field: expected face:NAME, got '%s'", field);
    if (colours && field)
        return cli_usage_error(cmd, "--colours and --field both colour the surface; give one of them");
    if (range_given && !field) return cli_usage_error(cmd, "--range is the colour range of --field; give --field too");
    if (count_given && !ro.uv_checker)
        return cli_usage_error(cmd, "--checker-count sets the squares of --uv-checker; give --uv-checker too");
    const char *input = argv[optind];
    cli_files files = {.force = force};
    cli_files_input(&files, "IN", input);
    cli_files_output(&files, "-o", output, CLI_FILE_IMAGE);

    cf_context *ctx = cli_context(false);
    if (!ctx) return CLI_EXIT_NUMERICAL;
    int code = CLI_EXIT_OK;
    cf_mesh_data *data = NULL;
    cf_mesh *mesh = NULL;
    cf_mesh_desc desc;
    double *rgb = NULL;
    cf_status st = CF_OK;
    if ((code = cli_files_check(ctx, &files)) != CLI_EXIT_OK) goto done;
    st = cf_read_mesh_file(ctx, input, &data);
    if (st == CF_OK) st = cf_mesh_data_desc(data, &desc);
    if (st == CF_OK) st = cf_mesh_create(ctx, &desc, &mesh);
    if (st != CF_OK) {
        code = cli_fail(ctx, input, st);
        if (code == CLI_EXIT_USAGE) code = CLI_EXIT_INPUT;
        goto done;
    }
    if (ro.uv_checker && cf_mesh_uv_count(mesh) == 0) {
        fprintf(stderr, "curvflow: %s: --uv-checker needs texture coordinates, the mesh has none\n", input);
        code = CLI_EXIT_INPUT;
        goto done;
    }
    if (field) {
        const cf_mesh_property *p = cf_mesh_data_face_property(data, field + 5);
        if (!p) {
            fprintf(stderr, "curvflow: %s: no per-face property '%s'\n", input, field + 5);
            code = CLI_EXIT_INPUT;
            goto done;
        }
        ro.face_field = p->values;
    }
    if (colours && (code = file_colours(input, data, &ro, &rgb)) != CLI_EXIT_OK) goto done;
    st = cf_render_png(ctx, output, mesh, NULL, &ro);
    if (st != CF_OK) {
        code = cli_fail(ctx, output, st);
        if (st == CF_ERR_IO || st == CF_ERR_NONFINITE) code = CLI_EXIT_INPUT;
    }
done:
    free(rgb);
    cf_mesh_destroy(&mesh);
    cf_mesh_data_destroy(&data);
    cf_context_destroy(&ctx);
    return code;
}
