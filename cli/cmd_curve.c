/*
 * curvflow curve IN.csv|IN.svg -o OUT.csv|OUT.svg [--steps N] [--time-step T]
 * Isometric flow of a closed planar polyline (Crane, Pinkall, Schroeder 2013,
 * Sec. 5). File formats: curvflow/curve_flow.h.
 */
#define _GNU_SOURCE
#include "cli.h"
#include "common.h"
#include "curvflow/curve_flow.h"

#include <getopt.h>
#include <string.h>

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow curve IN -o OUT [--steps N] [--time-step T] [--quiet]\n"
            "Isometric curvature flow of a closed planar polyline (Crane et al. 2013, Sec. 5):\n"
            "edge lengths are kept while the curve flows toward the smoothest curve of equal\n"
            "turning number (a circle for a simple curve).\n"
            "  IN, OUT          .csv or .txt (x,y per line) or .svg (the first drawn polygon, polyline,\n"
            "                   path, rect, circle or ellipse, with its transforms; curves flattened to\n"
            "                   within 1e-3 of their size; further shapes are ignored with a warning);\n"
            "                   OUT's extension picks the format written, and any other extension is refused\n"
            "  -n, --steps N    number of steps (default 10)\n"
            "  -t, --time-step T  tau (default 0.5; stable for tau < 1)\n"
            "  -q, --quiet      no per-step lines\n"
            "  -f, --force      replace a read-only OUT\n"
            "A step that raises the energy above its starting value or changes the turning number\n"
            "(tau above the stability limit) fails.\n"
            "Exit status: 0 ok, 1 usage error, 2 invalid input or an output that cannot or must not\n"
            "be written, 3 numerical failure (the last good state is still written).\n");
}

int cli_curve(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"output", required_argument, NULL, 'o'}, {"steps", required_argument, NULL, 'n'},
        {"time-step", required_argument, NULL, 't'}, {"quiet", no_argument, NULL, 'q'},
        {"force", no_argument, NULL, 'f'},        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0}};
    const char *cmd = "curve", *out = NULL;
    long long steps = 10;
    bool quiet = false, force = false;
    cf_curve_flow_options opt;
    cf_curve_flow_options_default(&opt);
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":o:n:t:qfh", longopts, NULL)) != -1) {
        switch (c) {
        case 'o': out = optarg; break;
        case 'n':
            if (!cli_parse_int(cmd, "--steps", optarg, 0, 100000000, &steps)) return CLI_EXIT_USAGE;
            break;
        case 't':
            if (!cli_parse_double(cmd, "--time-step", optarg, &opt.time_step)) return CLI_EXIT_USAGE;
            if (!(opt.time_step > 0.0)) return cli_usage_error(cmd, "--time-step must be > 0, got '%s'", optarg);
            break;
        case 'q': quiet = true; break;
        case 'f': force = true; break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error(cmd, c, argv);
        }
    }
    if (optind + 1 != argc) return cli_usage_error(cmd, "expected one input curve");
    if (!out) return cli_usage_error(cmd, "missing -o OUT");
    const char *in = argv[optind];
    cli_files files = {.force = force};
    cli_files_input(&files, "IN", in);
    cli_files_output(&files, "-o", out, CLI_FILE_CURVE);
    cf_context *ctx = cli_context(false);
    if (!ctx) return CLI_EXIT_NUMERICAL;
    int code = CLI_EXIT_OK;
    cf_curve *curve = NULL;
    cf_curve_flow *flow = NULL;
    cf_status st = CF_OK;
    if ((code = cli_files_check(ctx, &files)) != CLI_EXIT_OK) goto done;
    st = cf_curve_read(ctx, in, &curve);
    if (st != CF_OK) {
        code = cli_fail(ctx, in, st);
        goto done;
    }
    st = cf_curve_flow_create(ctx, curve->count, curve->points, &opt, &flow);
    if (st != CF_OK) {
        code = cli_fail(ctx, in, st);
        goto done;
    }
    if (!quiet) fprintf(stderr, "curve: %d points, energy %.6g\n", curve->count, cf_curve_flow_energy(flow));
    for (long long k = 0; k < steps; ++k) {
        cf_curve_flow_info info;
        st = cf_curve_flow_step(flow, &info);
        if (st != CF_OK) {
            /* a failed step leaves the curve as it was: write that, as flow does */
            code = cli_fail(ctx, in, st);
            if (code == CLI_EXIT_USAGE) code = CLI_EXIT_NUMERICAL;
            fprintf(stderr, "curvflow: writing the last good state (iteration %lld) to %s\n", k, out);
            break;
        }
        if (!quiet)
            fprintf(stderr, "step %lld: energy %.6g, closure gap %.3g, max length error %.3g, turning number %d\n",
                    (long long)info.iteration, info.energy, info.closure_gap, info.max_length_error,
                    info.turning_number);
    }
    st = cf_curve_write(ctx, out, cf_curve_flow_size(flow), cf_curve_flow_points(flow));
    if (st != CF_OK) {
        int wcode = cli_fail(ctx, out, st);
        if (code == CLI_EXIT_OK) code = wcode;
    }
done:
    cf_curve_flow_destroy(&flow);
    cf_curve_destroy(&curve);
    cf_context_destroy(&ctx);
    return code;
}
