/*
 * curvflow demo [--output-dir DIR]: the main job on a built-in shape with
 * real curvature to remove: an eight-armed star (cf_generate_limb_sphere,
 * W/4pi 5.78, per-corner texture coordinates) flowed to a round sphere by
 * the conformal Willmore flow of Crane, Pinkall, Schroeder 2013 at its
 * defaults (the implicit mean curvature flow baseline, Desbrun 1999, with
 * area rescaling when this build lacks it). Writes the meshes, per-face Q,
 * the step log, before/after pictures, run.json and the one-file HTML
 * report, and prints the figures and where everything is.
 */
#define _GNU_SOURCE
#include "common.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/render.h"
#include "report.h"

#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The demo's shape (docs: README, docs/report.md): 10242 vertices. */
enum { DEMO_SUBDIVISIONS = 5, DEMO_LIMBS = 8 };
static const double DEMO_LIMB_LENGTH = 1.4, DEMO_LIMB_WIDTH = 0.22;

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow demo [--output-dir DIR] [--steps N] [--quiet]\n"
            "Flows a built-in eight-armed star (curvflow generate limb-sphere: 10242 vertices,\n"
            "per-corner uv, W/4pi 5.78) to a round sphere with the conformal Willmore flow\n"
            "(spin-willmore at its defaults; implicit mean curvature flow with area rescaling if this\n"
            "build lacks it), and writes to DIR:\n"
            "  report.html             the one-file HTML report: 3D view of input and result coloured\n"
            "                          by Q, energy and residual curves, parameters, timings\n"
            "  input.obj, output.obj   the meshes with their texture coordinates\n"
            "  output.ply              the result with per-face Q (quasi-conformal error) and\n"
            "                          log_area_distortion fields\n"
            "  log.jsonl, run.json     one JSON object per step; the run's method, parameters, timings\n"
            "  before.png, after.png   pictures with a uv checkerboard (texture preservation)\n"
            "  q.png                   the result coloured by Q (blue 1 .. red 1.5, as in the report)\n"
            "and prints W/4pi before and after, the Q statistics and the time taken.\n\n"
            "  -d, --output-dir DIR  output folder [demo-output] (created if missing)\n"
            "  -n, --steps N         at most N steps [20]; the flow stops when it has converged\n"
            "  -q, --quiet           no per-step status lines\n"
            "  -f, --force           replace read-only files of an earlier demo in DIR\n"
            "  -h, --help            show this help\n");
}

static char *join(const char *dir, const char *name)
{
    size_t n = strlen(dir) + strlen(name) + 2;
    char *s = malloc(n);
    if (s) snprintf(s, n, "%s/%s", dir, name);
    return s;
}

enum { P_IN, P_OUT, P_PLY, P_LOG, P_BEFORE, P_AFTER, P_Q, P_RUN, P_REPORT, P_COUNT };

/* Options of the demo; returns -1 to go on, else the exit code. */
static int parse_args(int argc, char **argv, const char **dir, long long *steps, bool *quiet, bool *force)
{
    static const struct option longopts[] = {{"output-dir", required_argument, NULL, 'd'},
                                             {"steps", required_argument, NULL, 'n'},
                                             {"quiet", no_argument, NULL, 'q'},
                                             {"help", no_argument, NULL, 'h'},
                                             {"force", no_argument, NULL, 'f'},
                                             {NULL, 0, NULL, 0}};
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":d:n:qfh", longopts, NULL)) != -1) {
        switch (c) {
        case 'd': *dir = optarg; break;
        case 'n':
            if (!cli_parse_int("demo", "--steps", optarg, 1, 100000, steps)) return CLI_EXIT_USAGE;
            break;
        case 'q': *quiet = true; break;
        case 'f': *force = true; break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error("demo", c, argv);
        }
    }
    if (optind != argc) return cli_usage_error("demo", "unexpected argument '%s'", argv[optind]);
    return -1;
}

/* input.obj, output.obj, output.ply (Q and log area distortion per face)
 * and the three pictures; returns the exit code. */
static int write_meshes_and_pictures(cf_context *ctx, char *const *p, const char *dir, const cf_mesh *mesh,
                                     const double *x0, const double *x1, cli_report_figures *fig)
{
    cf_status st;
    int code;
    cf_field fields[2] = {{"Q", CF_FIELD_FACE, fig->q}, {"log_area_distortion", CF_FIELD_FACE, fig->log_area}};
    if ((st = cf_write_mesh_file(ctx, p[P_IN], mesh, NULL, NULL, 0)) != CF_OK ||
        (st = cf_write_mesh_file(ctx, p[P_OUT], mesh, x1, NULL, 0)) != CF_OK ||
        (st = cf_write_mesh_file(ctx, p[P_PLY], mesh, x1, fields, 2)) != CF_OK) {
        code = cli_fail(ctx, dir, st);
        if (code == CLI_EXIT_USAGE) code = CLI_EXIT_INPUT;
        return code;
    }
    cf_render_options ro;
    cf_render_options_default(&ro);
    ro.width = ro.height = 600;
    ro.uv_checker = 1;
    if ((st = cf_render_png(ctx, p[P_BEFORE], mesh, x0, &ro)) != CF_OK ||
        (st = cf_render_png(ctx, p[P_AFTER], mesh, x1, &ro)) != CF_OK) {
        code = cli_fail(ctx, dir, st);
        return code;
    }
    ro.uv_checker = 0;
    ro.face_field = fig->q;
    ro.field_min = 1.0; /* the report's colour bar: Q 1 (blue) .. 1.5 (red) */
    ro.field_max = 1.5;
    if ((st = cf_render_png(ctx, p[P_Q], mesh, x1, &ro)) != CF_OK) {
        code = cli_fail(ctx, dir, st);
        return code;
    }
    return CLI_EXIT_OK;
}

static void print_summary(const char *method, const cf_mesh *mesh, const cf_flow *flow, const cli_report_figures *fig,
                          double flow_seconds, char *const *p, bool report_written, double started)
{
    const cf_flow_info *last = cf_flow_last_info(flow);
    int32_t nf = cf_mesh_face_count(mesh);
    const double four_pi = 4.0 * acos(-1.0);
    printf("shape:               eight-armed star (limb-sphere, %d vertices, %d faces, per-corner uv)\n",
           (int)cf_mesh_vertex_count(mesh), (int)nf);
    printf("method:              %s at its defaults, %lld steps%s in %.2f s\n", method, (long long)last->iteration,
           cf_flow_converged(flow) ? " (converged)" : "", flow_seconds);
    printf("W/4pi:               %.6f -> %.6f  (1 for a round sphere)\n", fig->willmore_before / four_pi,
           fig->willmore_after / four_pi);
    printf("quasi-conformal Q:   mean %.6f  p95 %.6f  max %.6f  (1 = conformal)\n", fig->q_stats.weighted_mean,
           fig->q_stats.p95, fig->q_stats.max);
    printf("log area distortion: mean %+.3e  std %.3e\n", fig->log_area_stats.weighted_mean,
           fig->log_area_stats.weighted_std);
    printf("outputs:             %s  %s  %s  %s  %s\n", p[P_IN], p[P_OUT], p[P_PLY], p[P_LOG], p[P_RUN]);
    printf("pictures:            %s  %s  %s\n", p[P_BEFORE], p[P_AFTER], p[P_Q]);
    if (report_written)
        printf("report:              %s  (one file; open it in a browser, no network needed)\n", p[P_REPORT]);
    else
        printf("report:              not written (see the message above)\n");
    printf("total time:          %.2f s\n", cli_now() - started);
}

int cli_demo(int argc, char **argv)
{
    const char *dir = "demo-output";
    long long steps = -1;
    bool quiet = false, force = false;
    int code = parse_args(argc, argv, &dir, &steps, &quiet, &force);
    if (code >= 0) return code;
    code = cli_make_dir(dir);
    if (code != CLI_EXIT_OK) return code;

    static const char *const names[P_COUNT] = {"input.obj", "output.obj", "output.ply", "log.jsonl", "before.png",
                                               "after.png", "q.png",      "run.json",   "report.html"};
    char *p[P_COUNT] = {NULL};
    bool paths_ok = true;
    for (int i = 0; i < P_COUNT; ++i) paths_ok &= (p[i] = join(dir, names[i])) != NULL;
    cf_context *ctx = cli_context(false);
    if (!ctx || !paths_ok) {
        for (int i = 0; i < P_COUNT; ++i) free(p[i]);
        cf_context_destroy(&ctx);
        fprintf(stderr, "curvflow: out of memory\n");
        return CLI_EXIT_NUMERICAL;
    }
    /* the outputs pass the same check as every command's (cli_files_check) */
    static const cli_file_kind kinds[P_COUNT] = {CLI_FILE_MESH,  CLI_FILE_MESH,  CLI_FILE_FIELD_MESH,
                                                 CLI_FILE_LOG,   CLI_FILE_IMAGE, CLI_FILE_IMAGE,
                                                 CLI_FILE_IMAGE, CLI_FILE_JSON,  CLI_FILE_HTML};
    cli_files files = {.force = force};
    for (int i = 0; i < P_COUNT; ++i) cli_files_output(&files, names[i], p[i], kinds[i]);
    if ((code = cli_files_check(ctx, &files)) != CLI_EXIT_OK) {
        for (int i = 0; i < P_COUNT; ++i) free(p[i]);
        cf_context_destroy(&ctx);
        return code;
    }
    const double started = cli_now();
    cf_mesh *mesh = NULL;
    cf_flow *flow = NULL;
    cli_report_figures fig;
    memset(&fig, 0, sizeof fig);
    char *run_text = NULL;
    cli_progress progress;
    cli_progress_init(&progress, "demo", 0, quiet);
    cf_status st = cf_generate_limb_sphere(ctx, DEMO_SUBDIVISIONS, DEMO_LIMBS, DEMO_LIMB_LENGTH, DEMO_LIMB_WIDTH,
                                           &mesh);
    if (st != CF_OK) {
        code = cli_fail(ctx, "limb-sphere", st);
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
    }
    if (steps < 0) steps = 20;
    if (st != CF_OK) {
        code = cli_fail(ctx, "demo", st);
        goto done;
    }
    const char *method = cf_flow_kind_name(options.kind);
    progress.method = method;
    progress.total_steps = steps;
    const double *x0 = cf_mesh_positions(mesh);
    if ((code = cli_progress_open_log(&progress, ctx, p[P_LOG])) != CLI_EXIT_OK) goto done;
    cli_progress_log(&progress, cf_flow_last_info(flow));
    cf_flow_set_progress(flow, cli_progress_callback, &progress);
    const double flow_started = cli_now();
    cf_status run = cf_flow_run(flow, steps, NULL);
    const double flow_seconds = cli_now() - flow_started;
    code = cli_progress_finish(&progress);
    char run_message[512] = "";
    if (run != CF_OK) {
        snprintf(run_message, sizeof run_message, "%s", cf_context_message(ctx));
        code = cli_fail(ctx, method, run);
        fprintf(stderr, "curvflow: keeping the last good state (iteration %lld)\n",
                (long long)cf_flow_last_info(flow)->iteration);
    }
    const double *x1 = cf_flow_positions(flow);
    int fcode = cli_report_figures_compute(ctx, mesh, x0, x1, &fig);
    if (fcode != CLI_EXIT_OK || !fig.ok) {
        if (code == CLI_EXIT_OK) code = fcode != CLI_EXIT_OK ? fcode : CLI_EXIT_NUMERICAL;
        goto done;
    }
    if ((code = write_meshes_and_pictures(ctx, p, dir, mesh, x0, x1, &fig)) != CLI_EXIT_OK) goto done;
    const cf_flow_info *last = cf_flow_last_info(flow);
    cli_report_run rr;
    cli_report_run_init(&rr);
    rr.command = "demo", rr.method = method, rr.title = "curvflow demo: eight-armed star to round sphere";
    rr.input_path = names[P_IN], rr.output_path = names[P_OUT], rr.log_path = names[P_LOG];
    rr.options = &options, rr.steps_requested = steps, rr.steps_done = last->iteration;
    rr.converged = cf_flow_converged(flow) ? 1 : 0, rr.exit_status = code;
    rr.message = run_message[0] ? run_message : NULL;
    rr.seconds_run = flow_seconds;
    const char *extra[] = {"shape", "limb-sphere --subdivisions 5 --limbs 8 --length 1.4 --width 0.22", NULL};
    rr.extra = extra;
    if (!(run_text = cli_report_run_json(&rr)) ||
        (st = cf_write_text_file_atomic(ctx, p[P_RUN], run_text, strlen(run_text))) != CF_OK) {
        code = run_text ? cli_fail(ctx, p[P_RUN], st) : CLI_EXIT_NUMERICAL;
        goto done;
    }
    /* the report reads the log back from its file, as `curvflow report DIR` does */
    bool report_written = false;
    if (cli_report_available()) {
        cli_report_log log = {0};
        const char *log_text = cli_report_log_text(&log, p[P_LOG]);
        int rcode = cli_report_write(ctx, p[P_REPORT], &rr, mesh, x0, x1, log_text, p[P_LOG], &fig);
        cli_report_log_free(&log);
        if (rcode != CLI_EXIT_OK) {
            if (code == CLI_EXIT_OK) code = rcode;
        } else {
            report_written = true;
        }
    }
    print_summary(method, mesh, flow, &fig, flow_seconds, p, report_written, started);
done:
    cli_progress_finish(&progress);
    cli_report_figures_free(&fig);
    free(run_text);
    for (int i = 0; i < P_COUNT; ++i) free(p[i]);
    cf_flow_destroy(&flow);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
    return code;
}
