/*
 * curvflow spin IN --rho FILE|NAME -o OUT
 * SpinXForm (Crane, Pinkall, Schroeder 2011/2013): spin transformation of a
 * mesh from a prescribed change of mean curvature rho per vertex, read from
 * a text file (one value per vertex, separated by whitespace, commas or
 * newlines, '#' comments; read by cf_read_vertex_scalars_file) or from a PLY
 * vertex property of that name.
 */
#define _GNU_SOURCE
#include "cli.h"
#include "common.h"
#include "curvflow/io.h"
#include "curvflow/spin_willmore.h"

#include <getopt.h>
#include <sys/stat.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow spin IN --rho FILE|NAME -o OUT [--scale S]\n"
            "Spin transformation (Crane, Pinkall, Schroeder 2013, App. G): the output has mean\n"
            "curvature H + rho (to first order) and is conformal to the input.\n"
            "  --rho FILE|NAME  text file with one value per vertex (1/length), or the name of a\n"
            "                   PLY vertex property of IN (a name that is both is refused: ./NAME is the file)\n"
            "  --scale S        multiply rho by S (default 1)\n"
            "  -o OUT           output mesh (.obj, .off or .ply; texture coordinates, IN's properties,\n"
            "                   colours and OBJ materials are kept, as by flow; a PLY also gets rho as\n"
            "                   a vertex property); must not be IN or the rho file\n"
            "  -f, --force      replace a read-only OUT\n"
            "  --no-weld        keep boundary vertices that share a position apart and vertices no face uses\n"
            "                   (by default a file's seams are welded and its unused vertices dropped, and OUT\n"
            "                   and a --rho file have the vertices left: docs/io.md)\n"
            "Exit status: 0 ok, 1 usage error, 2 invalid input or an output that cannot or must not\n"
            "be written, 3 numerical failure.\n");
}

int cli_spin(int argc, char **argv)
{
    enum { OPT_RHO = 256, OPT_SCALE, OPT_NO_WELD };
    static const struct option longopts[] = {
        {"rho", required_argument, NULL, OPT_RHO}, {"scale", required_argument, NULL, OPT_SCALE},
        {"output", required_argument, NULL, 'o'}, {"force", no_argument, NULL, 'f'},
        {"help", no_argument, NULL, 'h'},         {"no-weld", no_argument, NULL, OPT_NO_WELD},
        {NULL, 0, NULL, 0}};
    const char *cmd = "spin", *out = NULL, *rho_arg = NULL;
    double scale = 1.0;
    bool force = false;
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":o:fh", longopts, NULL)) != -1) {
        switch (c) {
        case OPT_RHO: rho_arg = optarg; break;
        case 'o': out = optarg; break;
        case OPT_SCALE:
            if (!cli_parse_double(cmd, "--scale", optarg, &scale)) return CLI_EXIT_USAGE;
            break;
        case 'f': force = true; break;
        case OPT_NO_WELD: cli_set_weld(false); break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error(cmd, c, argv);
        }
    }
    if (optind + 1 != argc || !out || !rho_arg) return cli_usage_error(cmd, "IN, --rho and -o are required");
    const char *in = argv[optind];
    cli_files files = {.force = force};
    cli_files_input(&files, "IN", in);
    cli_files_input(&files, "--rho", rho_arg); /* a property name matches no file */
    cli_files_output(&files, "-o", out, CLI_FILE_MESH);

    cf_context *ctx = cli_context(false);
    if (!ctx) return CLI_EXIT_NUMERICAL;
    int code = CLI_EXIT_OK;
    cli_properties props;
    memset(&props, 0, sizeof props);
    cf_mesh *mesh = NULL;
    double *rho = NULL, *x = NULL;
    cf_status st = CF_OK;
    if ((code = cli_files_check(ctx, &files)) != CLI_EXIT_OK) goto done;
    /* the input's properties and materials are written with the result, as flow's */
    if ((code = cli_load_mesh_properties(ctx, in, &mesh, &props)) != CLI_EXIT_OK) goto done;
    int32_t nv = cf_mesh_vertex_count(mesh);
    rho = malloc((size_t)nv * sizeof(double));
    x = malloc(3 * (size_t)nv * sizeof(double));
    if (!rho || !x) {
        fprintf(stderr, "curvflow: out of memory\n");
        code = CLI_EXIT_NUMERICAL;
        goto done;
    }
    const cf_mesh_property *prop = props.data ? cf_mesh_data_vertex_property(props.data, rho_arg) : NULL;
    struct stat sb;
    if (prop && stat(rho_arg, &sb) == 0) {
        /* a property name has no '/', so ./NAME always names the file */
        code = cli_usage_error(cmd,
                               "--rho %s: ambiguous: %s has a vertex property '%s' and there is a file of that name; "
                               "write --rho ./%s to read the file",
                               rho_arg, argv[optind], rho_arg, rho_arg);
        goto done;
    }
    if (prop) {
        memcpy(rho, prop->values, (size_t)nv * sizeof(double));
    } else {
        if ((code = cli_check_vertex_file("--rho", rho_arg, in)) != CLI_EXIT_OK) goto done;
        /* the library's reader: lines of any length, '#' comments, BOM, file:line messages */
        st = cf_read_vertex_scalars_file(ctx, rho_arg, nv, rho);
        if (st != CF_OK) {
            code = cli_fail(ctx, rho_arg, st);
            goto done;
        }
    }
    for (int32_t i = 0; i < nv; ++i) rho[i] *= scale;
    st = cf_spin_transform(ctx, mesh, NULL, rho, x);
    if (st != CF_OK) {
        code = cli_fail(ctx, "spin", st);
        goto done;
    }
    cf_field field = {"rho", CF_FIELD_VERTEX, rho};
    cf_mesh_format fmt;
    int with_field = cf_mesh_format_from_path(ctx, out, &fmt) == CF_OK && fmt == CF_FORMAT_PLY;
    st = cli_write_result(ctx, in, mesh, x, &props, with_field ? &field : NULL, with_field ? 1 : 0, out);
    if (st != CF_OK) {
        code = cli_fail(ctx, out, st);
        if (code == CLI_EXIT_USAGE) code = CLI_EXIT_INPUT;
    } else {
        cli_warn_if_unreadable(ctx, mesh, x, out);
    }
done:
    free(rho);
    free(x);
    cf_mesh_destroy(&mesh);
    cli_properties_free(&props);
    cf_context_destroy(&ctx);
    return code;
}
