/*
 * curvflow flow IN -o OUT --method NAME [--steps N] [--time-step T]
 * [--param k=v]... [--log FILE.jsonl]: runs any method of the flow
 * interface (include/curvflow/flow.h) with a status line per step and an
 * optional JSONL log. --boundary-targets FILE gives spin-willmore's
 * per-vertex boundary directions (boundary=prescribed).
 */
#define _GNU_SOURCE
#include "common.h"
#include "report.h"
#include "curvflow/io.h"
#include "curvflow/spin_willmore.h"
#include "curvflow/stretch_bend_edit.h"

#include <errno.h>
#include <getopt.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow flow IN -o OUT --method NAME [OPTIONS]\n"
            "       curvflow flow --list-methods\n"
            "       curvflow flow --method NAME --list-params\n"
            "Runs a flow method on the mesh IN and writes the result to OUT (format from the\n"
            "extension; texture coordinates are kept). One status line per step goes to stderr\n"
            "(a progress bar when stderr is a terminal).\n\n"
            "  -m, --method NAME     flow method (see --list-methods)\n"
            "  -n, --steps N         number of steps [10]; the run stops earlier if the method converges\n"
            "  -t, --time-step T     shorthand for --param time_step=T (scale-free, see --list-params)\n"
            "  -p, --param KEY=VAL   set a method parameter (repeatable)\n"
            "  -o, --output OUT      output mesh (required)\n"
            "  -l, --log FILE.jsonl  JSONL log: one object per step (iteration 0 = start) with iteration,\n"
            "                        time, time_step, energy, terms, residuals, area, volume, drifts, seconds;\n"
            "                        written atomically when the run ends (also after a numerical failure)\n"
            "  -q, --quiet           no status lines\n"
            "  -f, --force           replace read-only output files\n"
            "      --report FILE.html  also write the one-file HTML report of the run (docs/report.md):\n"
            "                        3D view of IN and OUT with per-face Q, energy and residual curves\n"
            "      --handles FILE    handle file of --method stretch-bend-edit (format in docs/edit.md;\n"
            "                        `curvflow edit` has the editing options)\n"
            "      --boundary-targets FILE\n"
            "                        spin-willmore with boundary=prescribed (Sec. 6.3.1): target direction of\n"
            "                        the boundary vector V at each boundary vertex, one line 'VERTEX X Y Z'\n"
            "                        per boundary vertex (0-based index, every boundary vertex once; '#'\n"
            "                        starts a comment). Implies --param boundary=prescribed\n"
            "      --list-methods    list the methods and exit\n"
            "      --list-params     list the parameters of --method with their defaults and exit\n"
            "  -h, --help            show this help\n\n"
            "OUT is .obj, .off or .ply; it must not be IN (nor the log), and is checked before the run.\n"
            "On a numerical failure (a step that produces NaN, blows up or fails to factorise) the last\n"
            "good state is still written to OUT, the message names the iteration, and the exit status is 3.\n"
            "Exit status: 0 ok, 1 usage error or bad parameter, 2 invalid input or an output that cannot\n"
            "or must not be written, 3 numerical failure.\n");
}

static void list_methods(void)
{
    for (int k = 0; k < CF_FLOW_KIND_COUNT; ++k)
        printf("%-22s %s\n", cf_flow_kind_name((cf_flow_kind)k), cf_flow_kind_description((cf_flow_kind)k));
}

static int list_params(cf_flow_kind kind)
{
    cf_flow_options o;
    const cf_param_desc *params = NULL;
    int32_t count = 0;
    if (cf_flow_options_default(kind, &o) != CF_OK || cf_flow_params(kind, &params, &count) != CF_OK)
        return CLI_EXIT_USAGE;
    printf("Parameters of %s (--param NAME=VALUE):\n", cf_flow_kind_name(kind));
    if (count == 0) printf("  (none)\n");
    for (int32_t i = 0; i < count; ++i) {
        char def[64];
        if (cf_flow_options_format(&o, &params[i], def, sizeof def) != CF_OK) strcpy(def, "?");
        /* the limits as the range messages print them (they read back exactly) */
        char range[256];
        if (cf_flow_param_range_format(&params[i], range, sizeof range) != CF_OK) strcpy(range, "?");
        bool numeric = params[i].type == CF_PARAM_DOUBLE || params[i].type == CF_PARAM_INT;
        printf("  %-20s [%s] %s%s\n      %s\n", params[i].name, def, numeric ? "in " : "", range,
               params[i].help ? params[i].help : "");
    }
    return CLI_EXIT_OK;
}

/* Reads --boundary-targets: lines "VERTEX X Y Z", each boundary vertex of
 * mesh exactly once, a nonzero finite direction; fills targets (3 nv, zero
 * elsewhere). The library's reader (any line length, '#' comments, BOM)
 * names the file and line; every bad file is an input error (2). */
static int read_boundary_targets(cf_context *ctx, const char *path, const cf_mesh *mesh, double *targets)
{
    cf_status st = cf_read_vertex_directions_file(ctx, path, cf_mesh_vertex_count(mesh),
                                                  cf_mesh_vertex_on_boundary(mesh), "boundary vertex", targets);
    return st == CF_OK ? CLI_EXIT_OK : cli_fail(ctx, path, st);
}

int cli_flow(int argc, char **argv)
{
    enum { OPT_LIST_METHODS = 256, OPT_LIST_PARAMS, OPT_BOUNDARY_TARGETS, OPT_HANDLES, OPT_REPORT };
    static const struct option longopts[] = {
        {"method", required_argument, NULL, 'm'}, {"steps", required_argument, NULL, 'n'},
        {"time-step", required_argument, NULL, 't'}, {"param", required_argument, NULL, 'p'},
        {"output", required_argument, NULL, 'o'}, {"log", required_argument, NULL, 'l'},
        {"quiet", no_argument, NULL, 'q'}, {"list-methods", no_argument, NULL, OPT_LIST_METHODS},
        {"list-params", no_argument, NULL, OPT_LIST_PARAMS}, {"help", no_argument, NULL, 'h'},
        {"boundary-targets", required_argument, NULL, OPT_BOUNDARY_TARGETS},
        {"handles", required_argument, NULL, OPT_HANDLES}, {"force", no_argument, NULL, 'f'},
        {"report", required_argument, NULL, OPT_REPORT},
        {NULL, 0, NULL, 0}};
    const char *cmd = "flow";
    const char *method = NULL, *output = NULL, *log_path = NULL, *time_step = NULL, *targets_path = NULL;
    const char *handles_path = NULL, *report_path = NULL;
    long long steps = 10;
    bool quiet = false, want_methods = false, want_params = false, force = false;
    /* --param values are applied after the method is known */
    char **param_args = calloc((size_t)argc + 1, sizeof *param_args);
    int param_count = 0;
    if (!param_args) return CLI_EXIT_NUMERICAL;
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":m:n:t:p:o:l:qfh", longopts, NULL)) != -1) {
        switch (c) {
        case 'm': method = optarg; break;
        case 'n':
            if (!cli_parse_int(cmd, "--steps", optarg, 0, 1000000000LL, &steps)) { free(param_args); return CLI_EXIT_USAGE; }
            break;
        case 't': time_step = optarg; break;
        case 'p': param_args[param_count++] = optarg; break;
        case 'o': output = optarg; break;
        case 'l': log_path = optarg; break;
        case 'q': quiet = true; break;
        case OPT_LIST_METHODS: want_methods = true; break;
        case OPT_LIST_PARAMS: want_params = true; break;
        case OPT_BOUNDARY_TARGETS: targets_path = optarg; break;
        case OPT_HANDLES: handles_path = optarg; break;
        case OPT_REPORT: report_path = optarg; break;
        case 'f': force = true; break;
        case 'h': usage(stdout); free(param_args); return CLI_EXIT_OK;
        default: free(param_args); return cli_option_error(cmd, c, argv);
        }
    }
    if (want_methods) {
        list_methods();
        free(param_args);
        return CLI_EXIT_OK;
    }
    cf_flow_kind kind = CF_FLOW_KIND_COUNT;
    if (!method) { free(param_args); return cli_usage_error(cmd, "missing --method NAME (see --list-methods)"); }
    if (cf_flow_kind_from_name(method, &kind) != CF_OK) {
        free(param_args);
        return cli_usage_error(cmd, "unknown method '%s' (see --list-methods)", method);
    }
    if (want_params) {
        free(param_args);
        return list_params(kind);
    }
    if (optind + 1 != argc) { free(param_args); return cli_usage_error(cmd, "expected one input mesh"); }
    if (!output) { free(param_args); return cli_usage_error(cmd, "missing -o OUT"); }
    if (targets_path && kind != CF_FLOW_SPIN_WILLMORE) {
        free(param_args);
        return cli_usage_error(cmd, "--boundary-targets is an option of --method spin-willmore");
    }
    if (kind == CF_FLOW_STRETCH_BEND_EDIT && !handles_path) {
        free(param_args);
        return cli_usage_error(cmd, "--method stretch-bend-edit needs handles: use --handles FILE or `curvflow edit`");
    }
    if (handles_path && kind != CF_FLOW_STRETCH_BEND_EDIT) {
        free(param_args);
        return cli_usage_error(cmd, "--handles is an option of --method stretch-bend-edit");
    }
    const char *input = argv[optind];
    cli_files files = {.force = force};
    cli_files_input(&files, "IN", input);
    cli_files_input(&files, "--boundary-targets", targets_path);
    cli_files_input(&files, "--handles", handles_path);
    cli_files_output(&files, "-o", output, CLI_FILE_MESH);
    if (log_path) cli_files_output(&files, "--log", log_path, CLI_FILE_LOG);
    if (report_path) cli_files_output(&files, "--report", report_path, CLI_FILE_HTML);
    if (report_path && !cli_report_available()) { free(param_args); return CLI_EXIT_INPUT; }

    cf_context *ctx = cli_context(false);
    if (!ctx) { free(param_args); return CLI_EXIT_NUMERICAL; }
    cf_flow_options options;
    cf_flow_options_default(kind, &options);
    int code = CLI_EXIT_OK;
    cf_status st;
    double *targets = NULL;
    cf_handle_set *handles = NULL;
    if ((code = cli_files_check(ctx, &files)) != CLI_EXIT_OK) goto early;
    if (targets_path && (st = cf_flow_options_set(ctx, &options, "boundary", "prescribed")) != CF_OK) {
        code = cli_fail(ctx, "--boundary-targets", st);
        goto early;
    }
    if (time_step && (st = cf_flow_options_set(ctx, &options, "time_step", time_step)) != CF_OK) {
        code = cli_fail(ctx, "--time-step", st);
        goto early;
    }
    for (int i = 0; i < param_count; ++i) {
        char *eq = strchr(param_args[i], '=');
        if (!eq || eq == param_args[i]) {
            code = cli_usage_error(cmd, "--param: expected KEY=VALUE, got '%s'", param_args[i]);
            goto early;
        }
        *eq = '\0';
        st = cf_flow_options_set(ctx, &options, param_args[i], eq + 1);
        *eq = '=';
        if (st != CF_OK) {
            code = cli_fail(ctx, "--param", st);
            goto early;
        }
    }
    if (targets_path &&
        ((const cf_spin_willmore_options *)cf_flow_options_method(&options))->boundary_mode != CF_SPIN_BOUNDARY_PRESCRIBED) {
        code = cli_usage_error(cmd, "--boundary-targets needs boundary=prescribed");
        goto early;
    }

    cf_mesh *mesh = NULL;
    cf_flow *flow = NULL;
    cli_progress progress;
    cli_progress_init(&progress, method, steps, quiet);
    cli_report_log report_log = {0};
    code = cli_load_mesh(ctx, input, &mesh);
    if (code != CLI_EXIT_OK) goto done;
    if (targets_path) {
        targets = calloc(3 * (size_t)cf_mesh_vertex_count(mesh), sizeof(double));
        if (!targets) {
            fprintf(stderr, "curvflow: out of memory\n");
            code = CLI_EXIT_NUMERICAL;
            goto done;
        }
        code = read_boundary_targets(ctx, targets_path, mesh, targets);
        if (code != CLI_EXIT_OK) goto done;
        ((cf_spin_willmore_options *)cf_flow_options_method(&options))->boundary_targets = targets;
    }
    if (handles_path) {
        st = cf_handle_set_read_json(ctx, mesh, NULL, handles_path, &handles);
        if (st != CF_OK) {
            code = cli_fail(ctx, handles_path, st);
            if (code == CLI_EXIT_USAGE) code = CLI_EXIT_INPUT;
            goto done;
        }
        ((cf_stretch_bend_options *)cf_flow_options_method(&options))->handles = handles;
    }
    st = cf_flow_create(ctx, mesh, NULL, &options, &flow);
    if (st != CF_OK) {
        code = cli_fail(ctx, input, st);
        if (st == CF_ERR_INVALID_ARG) code = CLI_EXIT_USAGE;
        goto done;
    }
    bool completed = false;
    double started = cli_now();
    if (report_path && (code = cli_report_log_capture(&report_log, &progress, log_path)) != CLI_EXIT_OK) goto done;
    code = cli_run_flow_and_write(ctx, flow, &progress, log_path, steps, input, mesh, output, &completed);
    if (report_path) {
        cli_report_run run;
        cli_report_run_init(&run);
        run.command = "flow", run.method = method, run.input_path = input, run.output_path = output;
        run.log_path = log_path, run.options = &options, run.steps_requested = steps, run.quiet = quiet;
        run.seconds_run = cli_now() - started;
        code = cli_report_after_run(ctx, report_path, &run, mesh, flow, &report_log, code);
    }
    if (completed && !quiet) {
        const cf_flow_info *last = cf_flow_last_info(flow);
        fprintf(stderr, "curvflow: %s: %lld steps, energy %.9g, area drift %+.3e, volume drift %+.3e; wrote %s\n",
                method, (long long)last->iteration, last->energy, last->area_drift, last->volume_drift, output);
    }
done:
    cli_progress_finish(&progress);
    cli_report_log_free(&report_log);
    cf_flow_destroy(&flow);
    cf_handle_set_destroy(&handles);
    cf_mesh_destroy(&mesh);
early:
    cf_context_destroy(&ctx);
    free(targets);
    free(param_args);
    return code;
}
