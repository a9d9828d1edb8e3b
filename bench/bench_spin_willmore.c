/*
 * Benchmark of the conformal Willmore flow (Crane, Pinkall, Schroeder 2013):
 * per-step time split into assembly / factorisation / solves, against one
 * implicit mean-curvature-flow step (Desbrun et al. 1999) on the same mesh in
 * the same run (the median of up to 11 steps; the paper reports 3.3-6.4x),
 * for the mean step and for the median one (on genus > 0 the first steps'
 * factorisations of X(0) and period corrections make most of the mean).
 * TSV on stdout, nothing asserted.
 *
 *   bench_spin_willmore [--real] [--no-reuse] [--no-fairing] [--resolve-periods] [MESH_DIR_OR_FILE ...]
 * Without arguments the meshes come from $CURVFLOW_SHARED_DIR/meshes (or
 * ../shared/meshes); missing files are skipped with a note on stderr.
 * --real factorises the real 4 nv x 4 nv form instead of the complex one
 * (complex_factorization = 0), for the before/after comparison.
 * --no-reuse factorises X(0) on genus > 0 surfaces every step
 * (exactness_refresh = 0), the step before its reuse (docs/spin.md,
 * "Reusing X(0)"); the column x0 says which.
 * --no-fairing runs the paper's step without the vertex-scale fairing
 * (fairing = 0; docs/spin.md, "Vertex-scale fairing"); the column fairing
 * says which.
 * --resolve-periods factorises X again after every period correction
 * (period_first_order = 0; docs/spin.md, "Periods"); the column periods says
 * which (first-order or re-solved).
 */
#include "curvflow/flow.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/spin_willmore.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

static const char *const default_meshes[] = {"spot_3k.obj", "bunny_2k.obj", "bob_5k.obj", "elephant_g3_3k.obj",
                                             "armadillo_26k.obj"};

/* implicit-MCF steps timed for the ratio's denominator */
#define MCF_STEPS 11

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* median of n values (sorted in place); 0 for none */
static double median(double *v, int n)
{
    if (n <= 0) return 0.0;
    qsort(v, (size_t)n, sizeof *v, compare_doubles);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* the variants the flags select */
typedef struct bench_setup {
    int complex_form, reuse, fairing, period_first_order;
} bench_setup;

static void bench_file(const char *path, int steps, const bench_setup *b)
{
    cf_context *ctx = NULL;
    if (cf_context_create(&ctx) != CF_OK) return;
    cf_mesh *mesh = NULL;
    if (cf_load_mesh(ctx, path, &mesh) != CF_OK) {
        fprintf(stderr, "skip %s: %s\n", path, cf_context_message(ctx));
        cf_context_destroy(&ctx);
        return;
    }
    const char *name = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    cf_flow_options o;
    cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o);
    ((cf_spin_willmore_options *)cf_flow_options_method(&o))->tolerance = 0.0;
    ((cf_spin_willmore_options *)cf_flow_options_method(&o))->complex_factorization = b->complex_form;
    if (!b->reuse) ((cf_spin_willmore_options *)cf_flow_options_method(&o))->exactness_refresh = 0.0;
    if (!b->fairing) ((cf_spin_willmore_options *)cf_flow_options_method(&o))->fairing = 0.0;
    ((cf_spin_willmore_options *)cf_flow_options_method(&o))->period_first_order = b->period_first_order;
    /* timing of ten steps: elephant_g3_3k diverges at the default tau (W
     * rises from step 2), which the default check would stop */
    cf_flow_options_policy(&o)->divergence_factor = 0.0;
    cf_flow *flow = NULL;
    double t0 = 0.0;
    double asm_s = 0, fac_s = 0, sol_s = 0, tot_s = 0, w0 = 0, w = 0;
    int done = 0;
    double *step_times = malloc((size_t)(steps > 0 ? steps : 1) * sizeof *step_times);
    cf_status st = step_times ? cf_flow_create(ctx, mesh, NULL, &o, &flow) : CF_ERR_NOMEM;
    if (st == CF_OK) {
        w0 = w = cf_flow_energy(flow);
        for (int s = 0; s < steps; ++s) {
            cf_flow_info info;
            if (cf_flow_step(flow, &info) != CF_OK) {
                fprintf(stderr, "%s: step %d failed: %s\n", name, s + 1, cf_context_message(ctx));
                break;
            }
            asm_s += info.assemble_seconds;
            fac_s += info.factorize_seconds;
            sol_s += info.solve_seconds;
            tot_s += info.total_seconds;
            step_times[done] = info.total_seconds;
            w = info.energy;
            ++done;
        }
    } else {
        fprintf(stderr, "%s: create failed: %s\n", name, cf_context_message(ctx));
    }
    double qmean = 0.0, qmax = 0.0;
    if (flow && done > 0) {
        cf_stats q;
        if (cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, &q) == CF_OK) {
            qmean = q.weighted_mean;
            qmax = q.max;
        }
    }
    cf_flow_destroy(&flow);
    (void)t0;
    /* implicit MCF: the median of up to MCF_STEPS steps (its own create cost
     * excluded). One step is a few ms on the smaller meshes, where a mean of
     * three moved the ratio by 2x from run to run on a shared 2-core machine */
    cf_flow_options mo;
    cf_flow_options_default(CF_FLOW_IMPLICIT_MCF, &mo);
    double mcf_times[MCF_STEPS];
    int mcf_steps = 0;
    if (cf_flow_create(ctx, mesh, NULL, &mo, &flow) == CF_OK) {
        for (int s = 0; s < MCF_STEPS; ++s) {
            cf_flow_info info;
            if (cf_flow_step(flow, &info) != CF_OK) break;
            mcf_times[mcf_steps++] = info.total_seconds;
        }
        cf_flow_destroy(&flow);
    }
    double mcf = median(mcf_times, mcf_steps);
    if (done) {
        /* the median step: a genus > 0 flow's plain steps, without the first
         * steps' factorisations of X(0) and period corrections that make
         * most of its mean (docs/spin.md, "What is missing") */
        double step_median = median(step_times, done);
        printf("spin-willmore\t%s\t%s\t%s\t%s\t%s\t%d\t%d\t%d\t%.2f\t%.2f\t%.2f\t%.2f\t%.2f\t%.2f\t%.4f\t%.4f\t%.4f\t%.3f"
               "\t%.2f\t%.2f\n",
               name, b->complex_form ? "complex" : "real", b->reuse ? "reused" : "every-step", b->fairing ? "on" : "off",
               b->period_first_order ? "first-order" : "re-solved",
               cf_mesh_vertex_count(mesh), cf_mesh_face_count(mesh), done,
               1e3 * asm_s / done, 1e3 * fac_s / done, 1e3 * sol_s / done, 1e3 * tot_s / done, 1e3 * mcf, mcf > 0 ? (tot_s / done) / mcf : 0.0,
               w0 / (4 * PI), w / (4 * PI), qmean, qmax, 1e3 * step_median, mcf > 0 ? step_median / mcf : 0.0);
        fflush(stdout);
    }
    free(step_times);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
}

int main(int argc, char **argv)
{
    int steps = 10;
    bench_setup b = {1, 1, 1, 1};
    while (argc > 1 && (strcmp(argv[1], "--real") == 0 || strcmp(argv[1], "--no-reuse") == 0 ||
                        strcmp(argv[1], "--no-fairing") == 0 || strcmp(argv[1], "--resolve-periods") == 0)) {
        if (strcmp(argv[1], "--real") == 0)
            b.complex_form = 0;
        else if (strcmp(argv[1], "--no-reuse") == 0)
            b.reuse = 0;
        else if (strcmp(argv[1], "--no-fairing") == 0)
            b.fairing = 0;
        else
            b.period_first_order = 0;
        --argc;
        ++argv;
    }
    printf("method\tmesh\tfactorization\tx0\tfairing\tperiods\tV\tF\tsteps\tassemble_ms\tfactorize_ms\tsolve_ms\tstep_ms\timplicit_mcf_ms\tratio\tW0/4pi\tW/4pi\tQ_mean\tQ_max\tmedian_step_ms\tmedian_ratio\n");
    if (argc > 1) {
        for (int i = 1; i < argc; ++i) bench_file(argv[i], steps, &b);
        return 0;
    }
    const char *dir = getenv("CURVFLOW_SHARED_DIR");
    char base[1024];
    snprintf(base, sizeof base, "%s/meshes", dir ? dir : "../shared");
    for (size_t i = 0; i < sizeof default_meshes / sizeof default_meshes[0]; ++i) {
        char path[1200];
        snprintf(path, sizeof path, "%s/%s", base, default_meshes[i]);
        FILE *fp = fopen(path, "r");
        if (!fp) {
            fprintf(stderr, "skip %s: not found\n", path);
            continue;
        }
        fclose(fp);
        bench_file(path, steps, &b);
    }
    return 0;
}
