/*
 * curvflow edit IN --handles H.json -o OUT [--energy hybrid|stretch|bend|arap|arap-rims]
 * [--lambda L] [--iterations N] [--tol T] [--start S] ...: interactive-style
 * mesh editing with the stretching + bending energy of Zhao & Gortler (and
 * the ARAP energies), by local/global iteration (include/curvflow/
 * stretch_bend_edit.h). A front end on `curvflow flow --method
 * stretch-bend-edit`: each option is a spelling of a parameter of the
 * method's table (ranges and messages from the table) and the run goes
 * through cli_flow_execute, the flow command's one run-and-write path.
 */
#define _GNU_SOURCE
#include "common.h"
#include "report.h"
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
            "iteration. One status line per iteration goes to stderr. The same as\n"
            "`curvflow flow IN -o OUT --method stretch-bend-edit -p handles=H.json ...` with the\n"
            "options below spelling its parameters (see --list-params there).\n\n"
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
            "      --arap-weights W  edge weights of arap and arap-rims: cotan (default, the paper's;\n"
            "                        negative on non-Delaunay edges, where ARAP is unbounded below) or\n"
            "                        clamped (negative ones set to 0)\n"
            "  -o, --output OUT      output mesh (required)\n"
            "  -l, --log FILE.jsonl  JSONL log, one object per iteration (energy terms stretch, bend),\n"
            "                        written atomically when the run ends\n"
            "  -q, --quiet           no status lines\n"
            "      --report FILE.html  also write the one-file HTML report of the edit (docs/report.md)\n"
            "  -f, --force           replace read-only output files\n"
            "      --no-weld         keep boundary vertices that share a position apart and vertices no face\n"
            "                        uses (by default a file's seams are welded and its unused vertices\n"
            "                        dropped, and the mesh has the vertices left: docs/io.md)\n"
            "  -h, --help            show this help\n\n"
            "Example:\n"
            "  curvflow generate bar -o bar.obj\n"
            "  curvflow edit bar.obj --handles twist.json --energy hybrid --lambda 0.5 -o bent.obj\n\n"
            "OUT is .obj, .off or .ply and must not be one of the inputs (checked before the run).\n"
            "Exit status: 0 ok, 1 usage error or bad parameter, 2 invalid input (mesh or handle file)\n"
            "or an output that cannot or must not be written, 3 numerical failure (the last good state\n"
            "is still written).\n");
}

/* --lambda weighs the hybrid energy only: stretch and bend are lambda = 1
 * and 0, the ARAP energies have none. */
static int check_lambda(const cli_flow_job *job, const cf_flow_options *options)
{
    const cf_stretch_bend_options *o = cf_flow_options_method_as_const(options, CF_FLOW_STRETCH_BEND_EDIT);
    for (int i = 0; o && i < job->param_count; ++i)
        if (strcmp(job->params[i].name, "lambda") == 0 && o->energy != CF_STRETCH_BEND_HYBRID)
            return cli_usage_error(job->command, "--lambda weighs --energy hybrid; it has no effect with --energy %s",
                                   cf_stretch_bend_energy_name((cf_stretch_bend_energy_kind)o->energy));
    return CLI_EXIT_OK;
}

static void edit_summary(const cli_flow_job *job, const cf_flow *flow)
{
    const cf_flow_info *last = cf_flow_last_info(flow);
    const char *conv = cf_flow_converged(flow) ? " (converged)" : "";
    const char *energy = job->label;
    if (strcmp(energy, "arap") == 0 || strcmp(energy, "arap-rims") == 0)
        fprintf(stderr, "curvflow: edit %s: %lld iterations%s, energy %.9g; wrote %s\n", energy,
                (long long)last->iteration, conv, last->energy, job->output);
    else
        fprintf(stderr, "curvflow: edit %s: %lld iterations%s, energy %.9g (stretch %.6g, bend %.6g); wrote %s\n",
                energy, (long long)last->iteration, conv, last->energy, last->energy_terms[0], last->energy_terms[1],
                job->output);
}

int cli_edit(int argc, char **argv)
{
    enum { OPT_MASS = 256, OPT_NO_SCALE_FREE, OPT_REPORT, OPT_ARAP_WEIGHTS, OPT_NO_WELD };
    static const struct option longopts[] = {
        {"handles", required_argument, NULL, 'H'},    {"energy", required_argument, NULL, 'e'},
        {"lambda", required_argument, NULL, 'L'},     {"iterations", required_argument, NULL, 'n'},
        {"tol", required_argument, NULL, 't'},        {"start", required_argument, NULL, 's'},
        {"mass", required_argument, NULL, OPT_MASS},  {"no-scale-free", no_argument, NULL, OPT_NO_SCALE_FREE},
        {"output", required_argument, NULL, 'o'},     {"log", required_argument, NULL, 'l'},
        {"quiet", no_argument, NULL, 'q'},            {"help", no_argument, NULL, 'h'},
        {"anderson", required_argument, NULL, 'a'},   {"force", no_argument, NULL, 'f'},
        {"report", required_argument, NULL, OPT_REPORT}, {"arap-weights", required_argument, NULL, OPT_ARAP_WEIGHTS},
        {"no-weld", no_argument, NULL, OPT_NO_WELD},  {NULL, 0, NULL, 0}};
    static cli_flow_job job; /* large: not on the stack */
    memset(&job, 0, sizeof job);
    job.command = "edit";
    job.kind = CF_FLOW_STRETCH_BEND_EDIT;
    job.label = "hybrid";
    job.steps = 100;
    job.invalid_options_exit = CLI_EXIT_INPUT; /* the handles do not fit the mesh */
    job.announce_point_sets = true;
    job.check = check_lambda;
    job.summary = edit_summary;
    const char *handles_path = NULL;
    int c;
    optind = 1;
    opterr = 0;
    /* each option is a table parameter; its text is checked by the table */
    while ((c = getopt_long(argc, argv, ":H:e:L:n:t:s:o:l:a:qfh", longopts, NULL)) != -1) {
        bool ok = true;
        switch (c) {
        case 'H': handles_path = optarg; break;
        case 'e':
            job.label = optarg;
            ok = cli_flow_job_param(&job, "--energy", "energy", optarg, true);
            break;
        case 'L': ok = cli_flow_job_param(&job, "--lambda", "lambda", optarg, true); break;
        case 'n':
            if (!cli_parse_int(job.command, "--iterations", optarg, 0, 10000000LL, &job.steps)) return CLI_EXIT_USAGE;
            break;
        case 't': ok = cli_flow_job_param(&job, "--tol", "relative_tolerance", optarg, true); break;
        case 's': job.start_path = optarg; break;
        case 'a': ok = cli_flow_job_param(&job, "--anderson", "anderson", optarg, true); break;
        case OPT_MASS: ok = cli_flow_job_param(&job, "--mass", "mass", optarg, true); break;
        case OPT_ARAP_WEIGHTS: ok = cli_flow_job_param(&job, "--arap-weights", "arap_weights", optarg, true); break;
        case OPT_NO_SCALE_FREE: ok = cli_flow_job_param(&job, "--no-scale-free", "scale_free", "false", true); break;
        case 'o': job.output = optarg; break;
        case 'l': job.log_path = optarg; break;
        case OPT_REPORT: job.report_path = optarg; break;
        case OPT_NO_WELD: cli_set_weld(false); break;
        case 'q': job.quiet = true; break;
        case 'f': job.force = true; break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error(job.command, c, argv);
        }
        if (!ok) return CLI_EXIT_USAGE;
    }
    if (optind + 1 != argc) return cli_usage_error(job.command, "expected one input mesh");
    if (!handles_path) return cli_usage_error(job.command, "missing --handles H.json");
    if (!job.output) return cli_usage_error(job.command, "missing -o OUT");
    job.input = argv[optind];
    if (!cli_flow_job_param(&job, "--handles", "handles", handles_path, false)) return CLI_EXIT_USAGE;
    const char *extra[] = {"handles", handles_path, job.start_path ? "start" : NULL, job.start_path, NULL};
    job.report_extra = extra;
    return cli_flow_execute(&job);
}
