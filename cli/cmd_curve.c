/*
 * curvflow curve IN.csv|IN.svg -o OUT.csv|OUT.svg [--steps N] [--time-step T]
 * Isometric flow of a closed planar polyline (Crane, Pinkall, Schroeder 2013,
 * Sec. 5). File formats: curvflow/curve_flow.h.
 */
#include "cli.h"
#include "common.h"
#include "curvflow/curve_flow.h"

#include <string.h>

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow curve IN -o OUT [--steps N] [--time-step T] [--quiet]\n"
            "Isometric curvature flow of a closed planar polyline (Crane et al. 2013, Sec. 5):\n"
            "edge lengths are kept while the curve flows toward the smoothest curve of equal\n"
            "turning number (a circle for a simple curve).\n"
            "  IN, OUT        .csv (x,y per line) or .svg (polygon/polyline points, or a path with\n"
            "                 M L H V Z commands, absolute or relative)\n"
            "  --steps N      number of steps (default 10)\n"
            "  --time-step T  tau (default 0.5; stable for tau < 1)\n"
            "  --quiet        no per-step lines\n"
            "A step that raises the energy above its starting value or changes the turning number\n"
            "(tau above the stability limit) fails.\n"
            "Exit status: 0 ok, 1 usage error, 2 invalid input or unwritable output, 3 numerical\n"
            "failure (the last good state is still written).\n");
}

int cli_curve(int argc, char **argv)
{
    const char *in = NULL, *out = NULL;
    long long steps = 10;
    bool quiet = false;
    cf_curve_flow_options opt;
    cf_curve_flow_options_default(&opt);
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout);
            return CLI_EXIT_OK;
        } else if ((strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0) && i + 1 < argc) {
            out = argv[++i];
        } else if (strcmp(a, "--steps") == 0 && i + 1 < argc) {
            if (!cli_parse_int("curve", "--steps", argv[++i], 0, 100000000, &steps)) return CLI_EXIT_USAGE;
        } else if (strcmp(a, "--time-step") == 0 && i + 1 < argc) {
            if (!cli_parse_double("curve", "--time-step", argv[++i], &opt.time_step)) return CLI_EXIT_USAGE;
            if (!(opt.time_step > 0.0)) return cli_usage_error("curve", "--time-step must be > 0");
        } else if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
            quiet = true;
        } else if (a[0] == '-' && a[1] != '\0') {
            return cli_usage_error("curve", "unknown or incomplete option '%s'", a);
        } else if (!in) {
            in = a;
        } else {
            return cli_usage_error("curve", "unexpected argument '%s'", a);
        }
    }
    if (!in || !out) return cli_usage_error("curve", "IN and -o OUT are required");
    cf_context *ctx = cli_context(false);
    if (!ctx) return CLI_EXIT_NUMERICAL;
    int code = CLI_EXIT_OK;
    cf_curve *curve = NULL;
    cf_curve_flow *flow = NULL;
    cf_status st = CF_OK;
    if ((code = cli_check_output(ctx, out, false)) != CLI_EXIT_OK) goto done;
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
