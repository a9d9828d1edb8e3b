/*
 * curvflow edit IN --handles H.json -o OUT [--energy hybrid|stretch|bend|arap|arap-rims]
 * [--lambda L] [--iterations N] [--tol T] [--start S] ...: interactive-style
 * mesh editing with the stretching + bending energy of Zhao & Gortler (and
 * the ARAP energies), by local/global iteration from the public API
 * (include/curvflow/stretch_bend_edit.h).
 */
#define _GNU_SOURCE
#include "common.h"
#include "report.h"
#include "curvflow/io.h"
#include "curvflow/stretch_bend_edit.h"

#include <getopt.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow edit IN --handles H.json -o OUT [OPTIONS]\n"
            "Deforms the mesh IN (the rest pose) so that the handle vertices of H.json reach their\n"
            "targets, minimising a stretching + bending energy (Zhao & Gortler) or ARAP by local/global\n"
            "iteration. One status line per iteration goes to stderr.\n\n"
            "  -H, --handles FILE    JSON handle file (format in docs/edit.md; required)\n"
            "  -e, --energy NAME     hybrid (default), stretch, bend, arap, arap-rims\n"
            "  -L, --lambda L        hybrid weight lambda E_s + (1 - lambda) E_db [0.5]\n"
            "  -n, --iterations N    maximum local/global iterations [100]\n"
            "  -t, --tol T           stop when the relative energy decrease of an iteration is below T [1e-6]\n"
            "  -s, --start MESH      continue from this deformed state (same connectivity as IN); the\n"
            "                        handle file is evaluated on it. Default: start from the rest pose\n"
            "      --mass KIND       dual area of the bending term: voronoi (default) or barycentric\n"
            "      --no-scale-free   do not divide the stretching energy by the rest area\n"
            "  -a, --anderson M      Anderson acceleration with M past iterates (0..10, 0 = off; default\n"
            "                        -1 = 5 for hybrid/stretch/bend, off for ARAP); a mixed step is\n"
            "                        kept only if it lowers the energy\n"
            "  -o, --output OUT      output mesh (required)\n"
            "  -l, --log FILE.jsonl  JSONL log, one object per iteration (energy terms stretch, bend),\n"
            "                        written atomically when the run ends\n"
            "  -q, --quiet           no status lines\n"
            "      --report FILE.html  also write the one-file HTML report of the edit (docs/report.md)\n"
            "  -f, --force           replace read-only output files\n"
            "  -h, --help            show this help\n\n"
            "Example:\n"
            "  curvflow generate bar -o bar.obj\n"
            "  curvflow edit bar.obj --handles twist.json --energy hybrid --lambda 0.5 -o bent.obj\n\n"
            "OUT is .obj, .off or .ply and must not be one of the inputs (checked before the run).\n"
            "Exit status: 0 ok, 1 usage error or bad parameter, 2 invalid input (mesh or handle file)\n"
            "or an output that cannot or must not be written, 3 numerical failure (the last good state\n"
            "is still written).\n");
}

int cli_edit(int argc, char **argv)
{
    enum { OPT_MASS = 256, OPT_NO_SCALE_FREE, OPT_REPORT };
    long long anderson = -1;
    static const struct option longopts[] = {
        {"handles", required_argument, NULL, 'H'},    {"energy", required_argument, NULL, 'e'},
        {"lambda", required_argument, NULL, 'L'},     {"iterations", required_argument, NULL, 'n'},
        {"tol", required_argument, NULL, 't'},        {"start", required_argument, NULL, 's'},
        {"mass", required_argument, NULL, OPT_MASS},  {"no-scale-free", no_argument, NULL, OPT_NO_SCALE_FREE},
        {"output", required_argument, NULL, 'o'},     {"log", required_argument, NULL, 'l'},
        {"quiet", no_argument, NULL, 'q'},            {"help", no_argument, NULL, 'h'},
        {"anderson", required_argument, NULL, 'a'},   {"force", no_argument, NULL, 'f'},
        {"report", required_argument, NULL, OPT_REPORT},
        {NULL, 0, NULL, 0}};
    const char *cmd = "edit";
    const char *handles_path = NULL, *energy = "hybrid", *output = NULL, *log_path = NULL, *start_path = NULL;
    const char *mass = "voronoi", *report_path = NULL;
    double lambda = 0.5, tol = 1e-6;
    long long iterations = 100;
    bool quiet = false, scale_free = true, force = false, lambda_given = false;
    int c;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":H:e:L:n:t:s:o:l:a:qfh", longopts, NULL)) != -1) {
        switch (c) {
        case 'H': handles_path = optarg; break;
        case 'e': energy = optarg; break;
        case 'L':
            if (!cli_parse_double_in(cmd, "--lambda", optarg, 0.0, 1.0, &lambda)) return CLI_EXIT_USAGE;
            lambda_given = true;
            break;
        case 'n':
            if (!cli_parse_int(cmd, "--iterations", optarg, 0, 10000000LL, &iterations)) return CLI_EXIT_USAGE;
            break;
        case 't':
            if (!cli_parse_double(cmd, "--tol", optarg, &tol)) return CLI_EXIT_USAGE;
            if (tol < 0.0) return cli_usage_error(cmd, "--tol must be >= 0, got '%s'", optarg);
            break;
        case 's': start_path = optarg; break;
        case 'a':
            if (!cli_parse_int(cmd, "--anderson", optarg, -1, 10, &anderson)) return CLI_EXIT_USAGE;
            break;
        case OPT_MASS: mass = optarg; break;
        case OPT_NO_SCALE_FREE: scale_free = false; break;
        case 'o': output = optarg; break;
        case 'l': log_path = optarg; break;
        case OPT_REPORT: report_path = optarg; break;
        case 'q': quiet = true; break;
        case 'f': force = true; break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error(cmd, c, argv);
        }
    }
    if (optind + 1 != argc) return cli_usage_error(cmd, "expected one input mesh");
    if (!handles_path) return cli_usage_error(cmd, "missing --handles H.json");
    if (!output) return cli_usage_error(cmd, "missing -o OUT");
    if (strcmp(mass, "voronoi") != 0 && strcmp(mass, "barycentric") != 0)
        return cli_usage_error(cmd, "--mass must be voronoi or barycentric, got '%s'", mass);
    const char *input = argv[optind];
    cli_files files = {.force = force};
    cli_files_input(&files, "IN", input);
    cli_files_input(&files, "--handles", handles_path);
    cli_files_input(&files, "--start", start_path);
    cli_files_output(&files, "-o", output, CLI_FILE_MESH);
    if (log_path) cli_files_output(&files, "--log", log_path, CLI_FILE_LOG);
    if (report_path) cli_files_output(&files, "--report", report_path, CLI_FILE_HTML);
    if (report_path && !cli_report_available()) return CLI_EXIT_INPUT;

    cf_context *ctx = cli_context(false);
    if (!ctx) return CLI_EXIT_NUMERICAL;
    int out_code = cli_files_check(ctx, &files);
    if (out_code != CLI_EXIT_OK) {
        cf_context_destroy(&ctx);
        return out_code;
    }
    cf_flow_options options;
    cf_flow_options_default(CF_FLOW_STRETCH_BEND_EDIT, &options);
    cf_stretch_bend_options *o = cf_flow_options_method(&options);
    cf_stretch_bend_energy_kind kind;
    cf_status st = cf_stretch_bend_energy_from_name(ctx, energy, &kind);
    if (st != CF_OK) {
        int code = cli_usage_error(cmd, "%s", cf_context_message(ctx));
        cf_context_destroy(&ctx);
        return code;
    }
    if (lambda_given && kind != CF_STRETCH_BEND_HYBRID) {
        cf_context_destroy(&ctx);
        /* stretch and bend are lambda = 1 and 0; the ARAP energies have none */
        return cli_usage_error(cmd, "--lambda weighs --energy hybrid; it has no effect with --energy %s", energy);
    }
    o->energy = kind;
    o->lambda = lambda;
    o->max_iterations = (int32_t)iterations;
    o->relative_tolerance = tol;
    o->mass = strcmp(mass, "barycentric") == 0 ? CF_STRETCH_BEND_MASS_BARYCENTRIC : CF_STRETCH_BEND_MASS_VORONOI;
    o->scale_free = scale_free;
    o->anderson = (int32_t)anderson;

    int code = CLI_EXIT_OK;
    cf_mesh *mesh = NULL, *start_mesh = NULL;
    cf_handle_set *handles = NULL;
    cf_flow *flow = NULL;
    const double *start = NULL;
    cli_progress progress;
    cli_progress_init(&progress, energy, iterations, quiet);
    cli_report_log report_log = {0};
    code = cli_load_mesh(ctx, input, &mesh);
    if (code != CLI_EXIT_OK) goto done;
    if (start_path) {
        code = cli_load_mesh(ctx, start_path, &start_mesh);
        if (code != CLI_EXIT_OK) goto done;
        if (cf_mesh_vertex_count(start_mesh) != cf_mesh_vertex_count(mesh) ||
            cf_mesh_face_count(start_mesh) != cf_mesh_face_count(mesh) ||
            memcmp(cf_mesh_triangles(start_mesh), cf_mesh_triangles(mesh),
                   3 * (size_t)cf_mesh_face_count(mesh) * sizeof(int32_t)) != 0) {
            fprintf(stderr, "curvflow: %s: connectivity differs from %s (%d vertices, %d faces vs %d, %d)\n",
                    start_path, input, cf_mesh_vertex_count(start_mesh), cf_mesh_face_count(start_mesh),
                    cf_mesh_vertex_count(mesh), cf_mesh_face_count(mesh));
            code = CLI_EXIT_INPUT;
            goto done;
        }
        start = cf_mesh_positions(start_mesh);
    }
    st = cf_handle_set_read_json(ctx, mesh, start, handles_path, &handles);
    if (st != CF_OK) {
        code = cli_fail(ctx, handles_path, st);
        if (code == CLI_EXIT_USAGE) code = CLI_EXIT_INPUT;
        goto done;
    }
    o->handles = handles;
    if (!quiet)
        fprintf(stderr, "curvflow: %s: %d handle vertices (%d moved), %d free\n", handles_path, handles->count,
                handles->moved_count, cf_mesh_vertex_count(mesh) - handles->count);
    st = cf_flow_create(ctx, mesh, start, &options, &flow);
    if (st != CF_OK) {
        code = cli_fail(ctx, input, st);
        if (st == CF_ERR_INVALID_ARG) code = CLI_EXIT_INPUT;
        goto done;
    }
    bool completed = false;
    double started = cli_now();
    if (report_path && (code = cli_report_log_capture(&report_log, &progress, log_path)) != CLI_EXIT_OK) goto done;
    code = cli_run_flow_and_write(ctx, flow, &progress, log_path, iterations, input, mesh, output, &completed);
    if (report_path) {
        const char *extra[] = {"handles", handles_path, start_path ? "start" : NULL, start_path, NULL};
        cli_report_run run;
        cli_report_run_init(&run);
        run.command = "edit", run.method = energy, run.input_path = input, run.output_path = output;
        run.log_path = log_path, run.options = &options, run.extra = extra, run.steps_requested = iterations;
        run.quiet = quiet, run.seconds_run = cli_now() - started;
        code = cli_report_after_run(ctx, report_path, &run, mesh, flow, &report_log, code);
    }
    if (completed && !quiet) {
        const cf_flow_info *last = cf_flow_last_info(flow);
        if (kind == CF_STRETCH_BEND_ARAP || kind == CF_STRETCH_BEND_ARAP_RIMS)
            fprintf(stderr, "curvflow: edit %s: %lld iterations%s, energy %.9g; wrote %s\n", energy,
                    (long long)last->iteration, cf_flow_converged(flow) ? " (converged)" : "", last->energy, output);
        else
            fprintf(stderr, "curvflow: edit %s: %lld iterations%s, energy %.9g (stretch %.6g, bend %.6g); wrote %s\n",
                    energy, (long long)last->iteration, cf_flow_converged(flow) ? " (converged)" : "", last->energy,
                    last->energy_terms[0], last->energy_terms[1], output);
    }
done:
    cli_progress_finish(&progress);
    cli_report_log_free(&report_log);
    cf_flow_destroy(&flow);
    cf_handle_set_destroy(&handles);
    cf_mesh_destroy(&start_mesh);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
    return code;
}
