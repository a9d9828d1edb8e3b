/*
 * curvflow flow IN -o OUT --method NAME [--steps N] [--time-step T]
 * [--param k=v]... [--start S] [--log FILE.jsonl]: runs any method of the flow
 * interface (include/curvflow/flow.h) with a status line per step and an
 * optional JSONL log. Every method parameter goes through the method's
 * table (-p NAME=VALUE; array parameters NAME=FILE or NAME=@PROPERTY, see
 * cli/common.h); --handles and --boundary-targets are spellings of
 * -p handles=FILE and -p boundary_targets=FILE. cli_flow_execute is the one
 * run-and-write path, also of `curvflow edit` (cli/cmd_edit.c).
 */
#define _GNU_SOURCE
#include "common.h"
#include "report.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/spin_willmore.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
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
            "  -s, --start MESH      start from these positions (same vertices and faces as IN, e.g. the\n"
            "                        output of an earlier run, to resume it); IN stays the reference: the\n"
            "                        input metric, targets, rest areas and the drifts are IN's\n"
            "      --report FILE.html  also write the one-file HTML report of the run (docs/report.md):\n"
            "                        3D view of IN and OUT with per-face Q, energy and residual curves\n"
"      --no-weld         keep boundary vertices that share a position apart and vertices no face\n"
            "                        uses (by default a file's seams are welded and its unused vertices\n"
            "                        dropped, and the mesh has the vertices left: docs/io.md)\n"
            "  -p NAME=FILE, -p NAME=@PROP\n"
            "                        an array parameter (type vertex-scalars, vertex-vectors, face-scalars or\n"
            "                        point-set in --list-params): a file (numbers in vertex/face order; lines\n"
            "                        'VERTEX X Y Z'; a JSON constraint file for point sets, docs/edit.md) or a\n"
            "                        property of IN (PLY; @X,Y,Z for vectors; for point sets an integer vertex\n"
            "                        property: 0 = no set, k > 0 = set k, fixed where they start)\n"
            "      --handles FILE    -p handles=FILE: handle file of --method stretch-bend-edit (format in\n"
            "                        docs/edit.md; `curvflow edit` is the editing front end)\n"
            "      --boundary-targets FILE\n"
            "                        -p boundary=prescribed -p boundary_targets=FILE of spin-willmore\n"
            "                        (Sec. 6.3.1): target direction of the boundary vector V at each boundary\n"
            "                        vertex, one line 'VERTEX X Y Z' per boundary vertex (0-based index, every\n"
            "                        boundary vertex once; '#' starts a comment)\n"
            "      --list-methods    list the methods and exit\n"
            "      --list-params     list the parameters of --method with their defaults and exit\n"
            "  -h, --help            show this help\n\n"
            "OUT is .obj, .off or .ply; it must not be IN (nor the log), and is checked before the run.\n"
            "On a numerical failure (a step that produces NaN, blows up or fails to factorise) the last\n"
            "good state is still written to OUT, the message names the iteration, and the exit status is 3.\n"
            "A flow that fails in its set-up, before any step (e.g. a filter matrix that does not\n"
            "factorise), exits 3 and writes nothing. A run that stops early because no time step lowers\n"
            "the energy any more (step policy, --list-params) keeps the last state that did and exits 0.\n"
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
        if (cf_param_type_is_array(params[i].type))
            printf("  %-20s [%s] %s, %s (NAME=FILE or NAME=@PROPERTY)\n      %s\n", params[i].name, def,
                   cf_param_type_name(params[i].type), range, params[i].help ? params[i].help : "");
        else
            printf("  %-20s [%s] %s%s\n      %s\n", params[i].name, def, numeric ? "in " : "", range,
                   params[i].help ? params[i].help : "");
    }
    /* the step policy common to every method (scalars only; docs/flowcli.md) */
    if (cf_flow_common_params(&params, &count) != CF_OK) return CLI_EXIT_USAGE;
    printf("Step policy, common to every method (--param NAME=VALUE; docs/flowcli.md):\n");
    for (int32_t i = 0; i < count; ++i) {
        char def[64], range[256];
        if (cf_flow_options_format(&o, &params[i], def, sizeof def) != CF_OK) strcpy(def, "?");
        if (cf_flow_param_range_format(&params[i], range, sizeof range) != CF_OK) strcpy(range, "?");
        bool numeric = params[i].type == CF_PARAM_DOUBLE || params[i].type == CF_PARAM_INT;
        printf("  %-20s [%s] %s%s\n      %s\n", params[i].name, def, numeric ? "in " : "", range,
               params[i].help ? params[i].help : "");
    }
    return CLI_EXIT_OK;
}

/* Options that spell an array parameter of one method. */
static const struct {
    const char *option, *param, *also, *implies_name, *implies_value;
} flow_aliases[] = {
    {"--handles", "handles", "`curvflow edit`", NULL, NULL},
    {"--boundary-targets", "boundary_targets", NULL, "boundary", "prescribed"},
};
enum { FLOW_ALIAS_COUNT = (int)(sizeof flow_aliases / sizeof flow_aliases[0]) };

/* The kind whose table has parameter `name`, or CF_FLOW_KIND_COUNT. */
static cf_flow_kind kind_with_param(const char *name)
{
    for (int k = 0; k < CF_FLOW_KIND_COUNT; ++k) {
        const cf_param_desc *params = NULL;
        int32_t count = 0;
        if (cf_flow_params((cf_flow_kind)k, &params, &count) != CF_OK) continue;
        for (int32_t i = 0; i < count; ++i)
            if (strcmp(params[i].name, name) == 0) return (cf_flow_kind)k;
    }
    return CF_FLOW_KIND_COUNT;
}

bool cli_flow_job_param(cli_flow_job *job, const char *option, const char *name, const char *value,
                        bool alias_message)
{
    if (job->param_count == CLI_MAX_PARAM_ARGS) {
        cli_usage_error(job->command, "too many parameters (at most %d)", CLI_MAX_PARAM_ARGS);
        return false;
    }
    job->params[job->param_count].option = option;
    job->params[job->param_count].name = name;
    job->params[job->param_count].value = value;
    job->params[job->param_count].alias_message = alias_message;
    ++job->param_count;
    return true;
}

/* A required array parameter that was not given: a usage error naming the
 * ways to give it (M2 of issue 15: never an internal field). */
static int check_required(const cli_flow_job *job)
{
    const cf_param_desc *params = NULL;
    int32_t count = 0;
    if (cf_flow_params(job->kind, &params, &count) != CF_OK) return CLI_EXIT_USAGE;
    for (int32_t i = 0; i < count; ++i) {
        const cf_param_desc *p = &params[i];
        if (!cf_param_type_is_array(p->type) || p->min_value < 1.0) continue;
        bool given = false;
        for (int j = 0; j < job->param_count; ++j) given = given || strcmp(job->params[j].name, p->name) == 0;
        if (given) continue;
        const char *kind_name = cf_flow_kind_name(job->kind);
        for (int a = 0; a < FLOW_ALIAS_COUNT; ++a)
            if (strcmp(flow_aliases[a].param, p->name) == 0)
                return cli_usage_error(job->command, "--method %s needs %s: use %s FILE%s%s (or -p %s=FILE)", kind_name,
                                       p->name, flow_aliases[a].option, flow_aliases[a].also ? " or " : "",
                                       flow_aliases[a].also ? flow_aliases[a].also : "", p->name);
        return cli_usage_error(job->command, "--method %s needs %s: use -p %s=FILE", kind_name, p->name, p->name);
    }
    return CLI_EXIT_OK;
}

/* An alias's implied value overridden by a later -p (--boundary-targets
 * with -p boundary=fixed) is a usage error, found before any file is read. */
static int check_implied(const cli_flow_job *job, const cf_flow_options *options)
{
    for (int a = 0; a < FLOW_ALIAS_COUNT; ++a) {
        if (!flow_aliases[a].implies_name) continue;
        bool given = false;
        for (int j = 0; j < job->param_count; ++j) given = given || strcmp(job->params[j].option, flow_aliases[a].option) == 0;
        const cf_param_desc *params = NULL;
        int32_t count = 0;
        if (!given || cf_flow_params(job->kind, &params, &count) != CF_OK) continue;
        for (int32_t i = 0; i < count; ++i) {
            char value[128];
            if (strcmp(params[i].name, flow_aliases[a].implies_name) != 0 ||
                cf_flow_options_format(options, &params[i], value, sizeof value) != CF_OK)
                continue;
            if (strcmp(value, flow_aliases[a].implies_value) != 0)
                return cli_usage_error(job->command, "%s needs %s=%s", flow_aliases[a].option,
                                       flow_aliases[a].implies_name, flow_aliases[a].implies_value);
        }
    }
    return CLI_EXIT_OK;
}

/* Loads the start state: the same vertex and face counts as IN and the same
 * faces, vertex for vertex and in the same order (a start written by a
 * previous run of curvflow from IN qualifies; a re-triangulated or
 * re-indexed mesh does not). Else exit 2 naming the first difference. */
static int load_start(cf_context *ctx, const cli_flow_job *job, const cf_mesh *mesh, cf_mesh **start_mesh)
{
    int code = cli_load_mesh(ctx, job->start_path, start_mesh);
    if (code != CLI_EXIT_OK) return code;
    const cf_mesh *s = *start_mesh;
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    if (cf_mesh_vertex_count(s) != nv || cf_mesh_face_count(s) != nf) {
        fprintf(stderr,
                "curvflow: --start %s: %d vertices and %d faces, but %s has %d and %d (the start must have the "
                "connectivity of IN)\n",
                job->start_path, cf_mesh_vertex_count(s), cf_mesh_face_count(s), job->input, nv, nf);
        return CLI_EXIT_INPUT;
    }
    const int32_t *a = cf_mesh_triangles(s), *b = cf_mesh_triangles(mesh);
    for (int32_t f = 0; f < nf; ++f)
        if (a[3 * f] != b[3 * f] || a[3 * f + 1] != b[3 * f + 1] || a[3 * f + 2] != b[3 * f + 2]) {
            fprintf(stderr,
                    "curvflow: --start %s: face %d is (%d %d %d), in %s it is (%d %d %d) (the start must have the "
                    "faces of IN, in the same order)\n",
                    job->start_path, f, a[3 * f], a[3 * f + 1], a[3 * f + 2], job->input, b[3 * f], b[3 * f + 1],
                    b[3 * f + 2]);
            return CLI_EXIT_INPUT;
        }
    return CLI_EXIT_OK;
}

static void announce_point_sets(const cli_flow_job *job, const cli_flow_arrays *arrays, const cf_mesh *mesh)
{
    for (int i = 0; i < arrays->count; ++i) {
        const cf_handle_set *h = arrays->items[i].set;
        if (h)
            fprintf(stderr, "curvflow: %s: %d handle vertices (%d moved), %d free\n", arrays->items[i].value, h->count,
                    h->moved_count, cf_mesh_vertex_count(mesh) - h->count);
    }
    (void)job;
}

/* Sets every parameter of the job in order; exit code. */
static int apply_params(cf_context *ctx, const cli_flow_job *job, cf_flow_options *options, cli_flow_arrays *arrays,
                        cli_files *files)
{
    for (int i = 0; i < job->param_count; ++i) {
        int code = cli_flow_param_apply(ctx, options, arrays, files, job->params[i].option, job->params[i].name,
                                        job->params[i].value, job->params[i].alias_message);
        if (code != CLI_EXIT_OK) return code;
    }
    return CLI_EXIT_OK;
}

/* Above this mean Q of the map from the input, a spin-willmore run says why
 * and what helps (issue 13's bound on mean Q) */
#define CLI_RELAXATION_HINT_MEAN_Q 1.5

/* spin-willmore: when the result's area-weighted mean Q against the input
 * exceeds the bound, a note (docs/spin.md, "Tangential relaxation"): the
 * crowding of thin parts is what a user of a coarse model with limbs sees.
 * Where the tangential relaxation did not run (set to 0, or its default on a
 * surface with a boundary or of genus > 0) the note names it; where it ran
 * (the flow's last step reports its `relaxation_sweeps`, which the method
 * names whenever the relaxation is on) it says what is left. On a closed
 * connected surface of genus > 0 it names keep_class's modes instead
 * (docs/spin.md, "The conformal class the flow keeps"): without keep_class
 * with the class distance, and the relaxation where it did not run (not the
 * default there: it helps elk, 1.555 -> 1.482, and lets a coarse double
 * torus crowd further, 1.531 -> 1.969); with 1 the second mode. */
static void relaxation_hint(cf_context *ctx, const cf_flow_options *options, const cf_mesh *mesh,
                            const cf_flow *flow)
{
    const cf_spin_willmore_options *spin = cf_flow_options_method_as_const(options, CF_FLOW_SPIN_WILLMORE);
    if (!spin) return;
    cf_stats q;
    if (cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, &q) != CF_OK) {
        cf_context_clear_error(ctx);
        return;
    }
    if (!(q.weighted_mean > CLI_RELAXATION_HINT_MEAN_Q)) return;
    if (cf_mesh_component_count(mesh) == 1 && cf_mesh_boundary_loop_count(mesh) == 0 && cf_mesh_genus(mesh) >= 1) {
        /* genus > 0: holding the class, and with keep_class 2 the
         * triangulation's part of G too, keeps the triangles; the relaxation
         * helps on some meshes */
        double drift = NAN;
        if (cf_conformal_class_distance(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, NULL,
                                        &drift) != CF_OK)
            cf_context_clear_error(ctx);
        if (spin->keep_class == 0)
            fprintf(stderr,
                    "curvflow: note: the result's mean Q against the input is %.3f and its conformal class moved by "
                    "%.3g: %s-p keep_class=1 holds the input's class, -p keep_class=2 also the triangulation's part of "
                    "its Gram matrix, which keeps the triangles at some cost in W and time; a finer input helps too "
                    "(docs/spin.md, \"The conformal class the flow keeps\")\n",
                    q.weighted_mean, drift,
                    spin->relaxation > 0 ? ""
                                         : "-p relaxation=10 moves the vertices within the surface toward a more "
                                           "conformal map (not the default on genus > 0: on some coarse meshes W then "
                                           "falls further at more crowding), ");
        else if (spin->keep_class == 1)
            fprintf(stderr,
                    "curvflow: note: the result's mean Q against the input is %.3f with its conformal class held: "
                    "-p keep_class=2 also holds the triangulation's part of the class's Gram matrix, which keeps the "
                    "triangles at some cost in W and time; a finer input helps too (docs/spin.md, \"The conformal "
                    "class the flow keeps\")\n",
                    q.weighted_mean);
        else
            fprintf(stderr,
                    "curvflow: note: the result's mean Q against the input is %.3f with its conformal class and Gram "
                    "matrix held: thin parts crowded by the conformal map; a finer input helps (docs/spin.md, \"The "
                    "conformal class the flow keeps\")\n",
                    q.weighted_mean);
        return;
    }
    const cf_flow_info *last = cf_flow_last_info(flow);
    int relaxed = 0;
    for (int k = 0; last && k < CF_FLOW_MAX_RESIDUALS; ++k)
        relaxed |= last->residual_names[k] && strcmp(last->residual_names[k], "relaxation_sweeps") == 0;
    if (relaxed)
        fprintf(stderr,
                "curvflow: note: the result's mean Q against the input is %.3f: thin parts crowded by the conformal map, "
                "more than the tangential relaxation undoes; a finer input helps (docs/spin.md, \"Tangential "
                "relaxation\")\n",
                q.weighted_mean);
    else
        fprintf(stderr,
                "curvflow: note: the result's mean Q against the input is %.3f: thin parts crowded by the conformal map; "
                "-p relaxation=10 moves the vertices within the surface toward a more conformal map (the default on "
                "closed surfaces of genus 0 only: on genus > 0 it can let a coarse mesh crowd further, with a "
                "boundary it can slow the flow), a finer input helps too (docs/spin.md, \"Tangential relaxation\")\n",
                q.weighted_mean);
}

static int run_loaded(cf_context *ctx, const cli_flow_job *job, cf_flow_options *options, cli_flow_arrays *arrays)
{
    cf_mesh *mesh = NULL, *start_mesh = NULL;
    cf_flow *flow = NULL;
    cli_progress progress;
    cli_progress_init(&progress, job->label, job->steps, job->quiet);
    cli_report_log report_log = {0};
    const double *start = NULL;
    cli_properties props;
    int code = cli_load_mesh_properties(ctx, job->input, &mesh, &props);
    if (code == CLI_EXIT_OK && job->start_path && (code = load_start(ctx, job, mesh, &start_mesh)) == CLI_EXIT_OK)
        start = cf_mesh_positions(start_mesh);
    if (code == CLI_EXIT_OK) code = cli_flow_arrays_load(ctx, arrays, options, job->input, mesh, start);
    if (code != CLI_EXIT_OK) goto done;
    if (job->announce_point_sets && !job->quiet) announce_point_sets(job, arrays, mesh);
    /* IN is the reference (input metric, targets, drifts), the start only
     * the initial state (cf_flow_create_at) */
    cf_status st = cf_flow_create_at(ctx, mesh, start, options, &flow);
    if (st != CF_OK) {
        code = cli_fail(ctx, job->input, st);
        if (st == CF_ERR_INVALID_ARG) code = job->invalid_options_exit;
        goto done;
    }
    bool completed = false;
    double started = cli_now();
    if (job->report_path && (code = cli_report_log_capture(&report_log, &progress, job->log_path)) != CLI_EXIT_OK)
        goto done;
    code = cli_run_flow_and_write(ctx, flow, &progress, job->log_path, job->steps, job->input, mesh, &props,
                                  job->output, &completed);
    if (job->report_path) {
        cli_report_run run;
        cli_report_run_init(&run);
        run.command = job->command, run.method = job->label, run.input_path = job->input;
        run.output_path = job->output, run.log_path = job->log_path, run.options = options;
        run.extra = job->report_extra, run.steps_requested = job->steps, run.quiet = job->quiet;
        run.seconds_run = cli_now() - started;
        code = cli_report_after_run(ctx, job->report_path, &run, mesh, flow, &report_log, code);
    }
    if (completed && !job->quiet) {
        if (job->summary) {
            job->summary(job, flow);
        } else {
            /* a run that ends before its steps says so: converged, by the
             * method's tolerance or where no time step lowers the energy
             * any more (the step policy's stop; as edit and demo say it) */
            const cf_flow_info *last = cf_flow_last_info(flow);
            fprintf(stderr,
                    "curvflow: %s: %lld steps%s, energy %.9g, area drift %+.3e, volume drift %+.3e; wrote %s\n",
                    job->label, (long long)last->iteration, cf_flow_converged(flow) ? " (converged)" : "",
                    last->energy, last->area_drift, last->volume_drift, job->output);
        }
        relaxation_hint(ctx, options, mesh, flow);
    }
done:
    cli_progress_finish(&progress);
    cli_report_log_free(&report_log);
    cf_flow_destroy(&flow);
    cf_mesh_destroy(&start_mesh);
    cf_mesh_destroy(&mesh);
    cli_properties_free(&props);
    return code;
}

int cli_flow_execute(const cli_flow_job *job)
{
    if (!job->output) return cli_usage_error(job->command, "missing -o OUT");
    int code = check_required(job);
    if (code != CLI_EXIT_OK) return code;
    cli_files files = {.force = job->force};
    cli_files_input(&files, "IN", job->input);
    cli_files_input(&files, "--start", job->start_path);
    cf_context *ctx = cli_context(false);
    if (!ctx) return CLI_EXIT_NUMERICAL;
    cf_flow_options options;
    cf_flow_options_default(job->kind, &options);
    cli_flow_arrays arrays = {0};
    /* parameters first: their files join the inputs the outputs are checked against */
    code = apply_params(ctx, job, &options, &arrays, &files);
    if (code == CLI_EXIT_OK && job->check) code = job->check(job, &options);
    if (code == CLI_EXIT_OK) {
        cli_files_output(&files, "-o", job->output, CLI_FILE_MESH);
        if (job->log_path) cli_files_output(&files, "--log", job->log_path, CLI_FILE_LOG);
        if (job->report_path) cli_files_output(&files, "--report", job->report_path, CLI_FILE_HTML);
        if (job->report_path && !cli_report_available()) code = CLI_EXIT_INPUT;
    }
    if (code == CLI_EXIT_OK) code = cli_files_check(ctx, &files);
    if (code == CLI_EXIT_OK) code = run_loaded(ctx, job, &options, &arrays);
    cli_flow_arrays_free(&arrays);
    cf_context_destroy(&ctx);
    return code;
}

int cli_flow(int argc, char **argv)
{
    enum { OPT_LIST_METHODS = 256, OPT_LIST_PARAMS, OPT_BOUNDARY_TARGETS, OPT_HANDLES, OPT_REPORT, OPT_NO_WELD };
    static const struct option longopts[] = {
        {"method", required_argument, NULL, 'm'}, {"steps", required_argument, NULL, 'n'},
        {"time-step", required_argument, NULL, 't'}, {"param", required_argument, NULL, 'p'},
        {"output", required_argument, NULL, 'o'}, {"log", required_argument, NULL, 'l'},
        {"quiet", no_argument, NULL, 'q'}, {"list-methods", no_argument, NULL, OPT_LIST_METHODS},
        {"list-params", no_argument, NULL, OPT_LIST_PARAMS}, {"help", no_argument, NULL, 'h'},
        {"boundary-targets", required_argument, NULL, OPT_BOUNDARY_TARGETS},
        {"handles", required_argument, NULL, OPT_HANDLES}, {"force", no_argument, NULL, 'f'},
        {"report", required_argument, NULL, OPT_REPORT}, {"start", required_argument, NULL, 's'},
        {"no-weld", no_argument, NULL, OPT_NO_WELD}, {NULL, 0, NULL, 0}};
    static cli_flow_job job; /* large: not on the stack */
    memset(&job, 0, sizeof job);
    job.command = "flow";
    job.steps = 10;
    job.invalid_options_exit = CLI_EXIT_USAGE;
    const char *method = NULL, *time_step = NULL, *alias_value[FLOW_ALIAS_COUNT] = {NULL};
    const char *param_args[CLI_MAX_PARAM_ARGS];
    int param_count = 0;
    bool want_methods = false, want_params = false;
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":m:n:t:p:o:l:s:qfh", longopts, NULL)) != -1) {
        switch (c) {
        case 'm': method = optarg; break;
        case 'n':
            if (!cli_parse_int(job.command, "--steps", optarg, 0, 1000000000LL, &job.steps)) return CLI_EXIT_USAGE;
            break;
        case 't': time_step = optarg; break;
        case 'p':
            if (param_count == CLI_MAX_PARAM_ARGS)
                return cli_usage_error(job.command, "too many --param (at most %d)", CLI_MAX_PARAM_ARGS);
            param_args[param_count++] = optarg;
            break;
        case 'o': job.output = optarg; break;
        case 'l': job.log_path = optarg; break;
        case 's': job.start_path = optarg; break;
        case 'q': job.quiet = true; break;
        case OPT_LIST_METHODS: want_methods = true; break;
        case OPT_LIST_PARAMS: want_params = true; break;
        case OPT_HANDLES: alias_value[0] = optarg; break;
        case OPT_BOUNDARY_TARGETS: alias_value[1] = optarg; break;
        case OPT_REPORT: job.report_path = optarg; break;
        case OPT_NO_WELD: cli_set_weld(false); break;
        case 'f': job.force = true; break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error(job.command, c, argv);
        }
    }
    if (want_methods) {
        list_methods();
        return CLI_EXIT_OK;
    }
    if (!method) return cli_usage_error(job.command, "missing --method NAME (see --list-methods)");
    if (cf_flow_kind_from_name(method, &job.kind) != CF_OK)
        return cli_usage_error(job.command, "unknown method '%s' (see --list-methods)", method);
    if (want_params) return list_params(job.kind);
    if (optind + 1 != argc) return cli_usage_error(job.command, "expected one input mesh");
    if (!job.output) return cli_usage_error(job.command, "missing -o OUT");
    job.input = argv[optind];
    job.label = method;
    job.check = check_implied;
    static const char *start_extra[3];
    if (job.start_path) {
        start_extra[0] = "start", start_extra[1] = job.start_path, start_extra[2] = NULL;
        job.report_extra = start_extra;
    }
    /* the order of the options' effects: an alias's implied value, then
     * --time-step, then -p in the order given (a later -p wins) */
    for (int a = 0; a < FLOW_ALIAS_COUNT; ++a) {
        if (!alias_value[a]) continue;
        cf_flow_kind owner = kind_with_param(flow_aliases[a].param);
        if (owner != job.kind)
            return cli_usage_error(job.command, "%s is an option of --method %s", flow_aliases[a].option,
                                   cf_flow_kind_name(owner));
        if (flow_aliases[a].implies_name &&
            !cli_flow_job_param(&job, flow_aliases[a].option, flow_aliases[a].implies_name,
                                flow_aliases[a].implies_value, false))
            return CLI_EXIT_USAGE;
        if (!cli_flow_job_param(&job, flow_aliases[a].option, flow_aliases[a].param, alias_value[a], false))
            return CLI_EXIT_USAGE;
    }
    if (time_step && !cli_flow_job_param(&job, "--time-step", "time_step", time_step, false)) return CLI_EXIT_USAGE;
    static char names[CLI_MAX_PARAM_ARGS][128];
    for (int i = 0; i < param_count; ++i) {
        const char *eq = strchr(param_args[i], '=');
        if (!eq || eq == param_args[i]) return cli_usage_error(job.command, "--param: expected KEY=VALUE, got '%s'", param_args[i]);
        size_t n = (size_t)(eq - param_args[i]);
        if (n >= sizeof names[0]) n = sizeof names[0] - 1;
        memcpy(names[i], param_args[i], n);
        names[i][n] = '\0';
        if (!cli_flow_job_param(&job, "--param", names[i], eq + 1, false)) return CLI_EXIT_USAGE;
    }
    return cli_flow_execute(&job);
}
