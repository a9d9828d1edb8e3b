/*
 * curvflow demo [--output-dir DIR]: the main job on a built-in bumpy sphere
 * with per-corner texture coordinates. Runs the conformal Willmore flow of
 * Crane, Pinkall, Schroeder 2013 when this build implements it, else the
 * implicit mean curvature flow baseline (Desbrun 1999) with area
 * rescaling, and writes input/output meshes, per-face Q and a JSONL log.
 */
#define _GNU_SOURCE
#include "common.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/ops.h"
#include "curvflow/render.h"

#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow demo [--output-dir DIR] [--steps N] [--quiet]\n"
            "Smooths a built-in bumpy sphere (2562 vertices, per-corner uv, seed 1) with the\n"
            "conformal Willmore flow (spin-willmore) if this build implements it, else with\n"
            "implicit mean curvature flow (rescaled to keep the area), and writes to DIR:\n"
            "  input.obj, output.obj   the meshes with their texture coordinates\n"
            "  output.ply              the result with per-face Q (quasi-conformal error) and\n"
            "                          log_area_distortion fields\n"
            "  log.jsonl               one JSON object per step\n"
            "  before.png, after.png   pictures with a uv checkerboard (texture preservation)\n"
            "  q.png                   the result coloured by Q (blue 1 .. red max)\n"
            "and prints W/4pi before and after and the Q statistics.\n\n"
            "  -d, --output-dir DIR  output folder [demo-output] (created if missing)\n"
            "  -n, --steps N         number of steps [20 for spin-willmore, 10 for the fallback]\n"
            "  -q, --quiet           no per-step status lines\n"
            "  -h, --help            show this help\n");
}

static char *join(const char *dir, const char *name)
{
    size_t n = strlen(dir) + strlen(name) + 2;
    char *s = malloc(n);
    if (s) snprintf(s, n, "%s/%s", dir, name);
    return s;
}

int cli_demo(int argc, char **argv)
{
    static const struct option longopts[] = {{"output-dir", required_argument, NULL, 'd'},
                                             {"steps", required_argument, NULL, 'n'},
                                             {"quiet", no_argument, NULL, 'q'},
                                             {"help", no_argument, NULL, 'h'},
                                             {NULL, 0, NULL, 0}};
    const char *dir = "demo-output";
    long long steps = -1;
    bool quiet = false;
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":d:n:qh", longopts, NULL)) != -1) {
        switch (c) {
        case 'd': dir = optarg; break;
        case 'n':
            if (!cli_parse_int("demo", "--steps", optarg, 1, 100000, &steps)) return CLI_EXIT_USAGE;
            break;
        case 'q': quiet = true; break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error("demo", c, argv);
        }
    }
    if (optind != argc) return cli_usage_error("demo", "unexpected argument '%s'", argv[optind]);
    int code = cli_make_dir(dir);
    if (code != CLI_EXIT_OK) return code;

    cf_context *ctx = cli_context(false);
    if (!ctx) return CLI_EXIT_NUMERICAL;
    char *p_in = join(dir, "input.obj"), *p_out = join(dir, "output.obj"), *p_ply = join(dir, "output.ply"),
         *p_log = join(dir, "log.jsonl"), *p_before = join(dir, "before.png"), *p_after = join(dir, "after.png"),
         *p_q = join(dir, "q.png");
    cf_mesh *mesh = NULL;
    cf_flow *flow = NULL;
    double *q = NULL, *lad = NULL;
    cli_progress progress;
    cli_progress_init(&progress, "demo", 0, quiet);
    cf_status st = cf_generate_bumpy_sphere(ctx, 4, 0.25, 1u, &mesh);
    if (st != CF_OK || !p_in || !p_out || !p_ply || !p_log || !p_before || !p_after || !p_q) {
        code = cli_fail(ctx, "bumpy-sphere", st != CF_OK ? st : CF_ERR_NOMEM);
        goto done;
    }
    /* The paper's method when it is there; the baseline otherwise. */
    cf_flow_options options;
    cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &options);
    st = cf_flow_create(ctx, mesh, NULL, &options, &flow);
    if (st == CF_ERR_UNSUPPORTED) {
        cf_flow_options_default(CF_FLOW_IMPLICIT_MCF, &options);
        cf_flow_options_set(ctx, &options, "rescale", "true");
        st = cf_flow_create(ctx, mesh, NULL, &options, &flow);
        if (steps < 0) steps = 10;
    }
    if (steps < 0) steps = 20;
    if (st != CF_OK) {
        code = cli_fail(ctx, "demo", st);
        goto done;
    }
    const char *method = cf_flow_kind_name(options.kind);
    progress.method = method;
    progress.total_steps = steps;
    int32_t nf = cf_mesh_face_count(mesh);
    const double *x0 = cf_mesh_positions(mesh);
    double w0 = 0.0, w1 = 0.0;
    if ((st = cf_willmore_energy(ctx, mesh, x0, &w0)) != CF_OK) {
        code = cli_fail(ctx, "demo", st);
        goto done;
    }
    if ((code = cli_progress_open_log(&progress, ctx, p_log)) != CLI_EXIT_OK) goto done;
    cli_progress_log(&progress, cf_flow_last_info(flow));
    cf_flow_set_progress(flow, cli_progress_callback, &progress);
    cf_status run = cf_flow_run(flow, steps, NULL);
    code = cli_progress_finish(&progress);
    if (run != CF_OK) {
        code = cli_fail(ctx, method, run);
        fprintf(stderr, "curvflow: keeping the last good state (iteration %lld)\n",
                (long long)cf_flow_last_info(flow)->iteration);
    }
    const double *x1 = cf_flow_positions(flow);
    q = malloc((size_t)nf * sizeof *q);
    lad = malloc((size_t)nf * sizeof *lad);
    cf_stats sq, sl;
    if (!q || !lad) {
        st = CF_ERR_NOMEM;
    } else if ((st = cf_willmore_energy(ctx, mesh, x1, &w1)) == CF_OK &&
               (st = cf_quasi_conformal_error(ctx, mesh, x0, x1, q, &sq)) == CF_OK) {
        st = cf_log_area_distortion(ctx, mesh, x0, x1, lad, &sl);
    }
    if (st != CF_OK) {
        code = cli_fail(ctx, "demo", st);
        goto done;
    }
    cf_field fields[2] = {{"Q", CF_FIELD_FACE, q}, {"log_area_distortion", CF_FIELD_FACE, lad}};
    if ((st = cf_write_mesh_file(ctx, p_in, mesh, NULL, NULL, 0)) != CF_OK ||
        (st = cf_write_mesh_file(ctx, p_out, mesh, x1, NULL, 0)) != CF_OK ||
        (st = cf_write_mesh_file(ctx, p_ply, mesh, x1, fields, 2)) != CF_OK) {
        code = cli_fail(ctx, dir, st);
        if (code == CLI_EXIT_USAGE) code = CLI_EXIT_INPUT;
        goto done;
    }
    cf_render_options ro;
    cf_render_options_default(&ro);
    ro.width = ro.height = 600;
    ro.uv_checker = 1;
    if ((st = cf_render_png(ctx, p_before, mesh, x0, &ro)) != CF_OK ||
        (st = cf_render_png(ctx, p_after, mesh, x1, &ro)) != CF_OK) {
        code = cli_fail(ctx, dir, st);
        goto done;
    }
    ro.uv_checker = 0;
    ro.face_field = q;
    ro.field_min = 1.0;  /* Q >= 1; white at the middle of [1, max] */
    ro.field_max = sq.max > 1.0 + 1e-9 ? sq.max : 1.0 + 1e-9;
    if ((st = cf_render_png(ctx, p_q, mesh, x1, &ro)) != CF_OK) {
        code = cli_fail(ctx, dir, st);
        goto done;
    }
    const double four_pi = 4.0 * acos(-1.0);
    printf("method:              %s, %lld steps on a bumpy sphere (%d vertices, %d faces, per-corner uv)\n", method,
           (long long)cf_flow_last_info(flow)->iteration, (int)cf_mesh_vertex_count(mesh), (int)nf);
    printf("W/4pi:               %.6f -> %.6f  (1 for a round sphere)\n", w0 / four_pi, w1 / four_pi);
    printf("quasi-conformal Q:   mean %.6f  p95 %.6f  max %.6f  (1 = conformal)\n", sq.weighted_mean, sq.p95, sq.max);
    printf("log area distortion: mean %+.3e  std %.3e\n", sl.weighted_mean, sl.weighted_std);
    printf("outputs:             %s  %s  %s  %s\n", p_in, p_out, p_ply, p_log);
    printf("pictures:            %s  %s  %s\n", p_before, p_after, p_q);
done:
    cli_progress_finish(&progress);
    free(q);
    free(lad);
    free(p_in);
    free(p_out);
    free(p_ply);
    free(p_log);
    free(p_before);
    free(p_after);
    free(p_q);
    cf_flow_destroy(&flow);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
    return code;
}
