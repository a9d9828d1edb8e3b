/*
 * The zoo (issue 13): every flow method with its defaults on every mesh of
 * ../shared/meshes (MANIFEST.tsv), 10 steps, one table row per mesh x method
 * on stderr: status, energy (W/4pi for spin-willmore) before and after,
 * whether it never rose, area-weighted mean and max quasi-conformal error Q
 * against the input, smallest angle, ms per step.
 *
 * The edit (stretch-bend-edit) joins with one handle file that fits every
 * mesh and each of its five energies (run_edits); asserted for it too: its
 * energy never rises.
 * Asserted for every method: no crash; the state the flow ends in (the last
 * good one when a step failed) has finite positions and passes the mesh
 * check, i.e. the written result loads again; a failure is a numerical one
 * (CF_ERR_NUMERICAL), not a mis-reported bad input.
 * Asserted for spin-willmore (the paper's claim: its defaults work on real
 * meshes): every mesh runs its 10 steps (or converges) without failure and
 * W never rises (relative slack 1e-12 for rounding).
 * Printed per mesh: issue 13's further targets (W after 10 steps <= W0 / 2
 * where W0/4pi >= 2, mean Q <= 1.5), which the defaults meet on part of the
 * meshes only (docs/spin.md, "Robustness"; the column `targets`); asserted
 * as counts that may not fall (17 and 18 with all 20 meshes).
 * Printed too: the mean Q of the vertex-scale model (cf_vertex_scale_fit_compute:
 * the Q that the variation of the conformal scale across the faces causes
 * by itself). Asserted for spin-willmore where mean Q > 1.5: the model's Q
 * is within 5 % of the flow's, i.e. the miss is the crowding of the
 * conformal scale that the flow's shape needs, not a non-conformal error of
 * the step (docs/spin.md, "The mean-Q misses are the conformal scale's").
 * On closed surfaces of genus >= 1 the column `class` is the distance of
 * the result's conformal class from the input's (cf_conformal_class_distance;
 * 0 for a conformal map). Asserted: spin-willmore's is below conformal-mcf's,
 * which does not keep the class.
 * Meshes above 3 000 vertices are left out of sanitizer builds (CTest time limit).
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/stretch_bend_edit.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define ZOO_STEPS 10
#define ZOO_PI 3.14159265358979323846

#define ZOO_MAX_VERTICES (CFT_UNDER_ASAN ? 3000 : 300000)

/* 1 when positions x on the mesh's connectivity pass the mesh check */
static int passes_mesh_check(cf_context *ctx, const cf_mesh *mesh, const double *x)
{
    cf_mesh_desc d = {0};
    d.vertex_count = cf_mesh_vertex_count(mesh);
    d.positions = x;
    d.face_count = cf_mesh_face_count(mesh);
    d.triangles = cf_mesh_triangles(mesh);
    cf_mesh *check = NULL;
    cf_status st = cf_mesh_create(ctx, &d, &check);
    cf_mesh_destroy(&check);
    return st == CF_OK;
}

typedef struct zoo_totals {
    int runs, spin_runs, spin_w_target, spin_w_target_met, spin_q_met;
    /* on the current mesh when closed of genus >= 1: the distance of the
     * result's conformal class from the input's, spin-willmore and
     * conformal-mcf (NaN until measured) */
    double class_spin, class_cmcf;
} zoo_totals;

/* the distance of x's conformal class from the input's (closed connected
 * surfaces of genus >= 1; NaN elsewhere or when it cannot be measured, as
 * on a degenerate result) */
static double class_distance(cf_context *ctx, const cf_mesh *mesh, const double *x)
{
    if (cf_mesh_component_count(mesh) != 1 || cf_mesh_boundary_loop_count(mesh) != 0 || cf_mesh_genus(mesh) < 1)
        return NAN;
    double d = NAN;
    if (cf_conformal_class_distance(ctx, mesh, cf_mesh_positions(mesh), x, NULL, NULL, &d) != CF_OK) {
        cf_context_clear_error(ctx);
        return NAN;
    }
    return d;
}

/* One row: the flow of options o (kind from o) on mesh, labelled method. */
static void run_one(cf_context *ctx, const char *name, const cf_mesh *mesh, const char *method,
                    const cf_flow_options *o, zoo_totals *totals)
{
    cf_flow *flow = NULL;
    cf_status st = cf_flow_create(ctx, mesh, NULL, o, &flow);
    if (st != CF_OK) {
        /* the edit's handles may miss a component of the mesh: a usage
         * error, named */
        fprintf(stderr, "   %-24s %-22s create: %s: %s\n", name, method, cf_status_name(st), cf_context_message(ctx));
        CHECK(st == CF_ERR_INVALID_ARG || st == CF_ERR_UNSUPPORTED);
        return;
    }
    int spin = o->kind == CF_FLOW_SPIN_WILLMORE, edit = o->kind == CF_FLOW_STRETCH_BEND_EDIT;
    double scale = spin ? 1.0 / (4.0 * ZOO_PI) : 1.0;
    double e0 = cf_flow_energy(flow) * scale, e_prev = e0;
    int monotone = 1, steps = 0;
    double seconds = 0.0;
    for (int i = 0; i < ZOO_STEPS && !cf_flow_converged(flow); ++i) {
        cf_flow_info info;
        st = cf_flow_step(flow, &info);
        if (st != CF_OK) break;
        ++steps;
        seconds += info.total_seconds;
        double e = info.energy * scale;
        /* 1e-20: rounding of an energy that is 0 in exact arithmetic (a
         * flat sheet's interior bi-Laplacian energy is 1.8e-26 and moves
         * by 1e-28 from step to step); W and the other energies are O(1) */
        if (e > e_prev + 1e-12 * fabs(e_prev) + 1e-20) monotone = 0;
        e_prev = e;
    }
    char message[256] = "";
    if (st != CF_OK) snprintf(message, sizeof message, "%s", cf_context_message(ctx));
    const double *x = cf_flow_positions(flow);
    int finite = 1;
    for (int32_t i = 0; i < 3 * cf_mesh_vertex_count(mesh); ++i)
        if (!isfinite(x[i])) finite = 0;
    int loads = finite && passes_mesh_check(ctx, mesh, x);
    cf_stats q = {0};
    cf_status qs = finite ? cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), x, NULL, &q) : CF_ERR_NONFINITE;
    cf_vertex_scale_fit fit = {0};
    cf_status fs = qs == CF_OK ? cf_vertex_scale_fit_compute(ctx, mesh, cf_mesh_positions(mesh), x, NULL, NULL, &fit)
                               : qs;
    cf_mesh_quality quality;
    double min_angle = finite && cf_mesh_quality_compute(ctx, mesh, x, &quality) == CF_OK
                           ? quality.min_angle * 180.0 / ZOO_PI
                           : NAN;
    double e1 = cf_flow_energy(flow) * scale;
    char targets[32] = "";
    if (spin) {
        int w_target = e0 >= 2.0;
        int w_met = !w_target || e1 <= 0.5 * e0;
        int q_met = qs == CF_OK && q.weighted_mean <= 1.5;
        snprintf(targets, sizeof targets, "W%s Q%s", w_target ? (w_met ? "+" : "-") : ".", q_met ? "+" : "-");
        totals->spin_runs++;
        totals->spin_w_target += w_target;
        totals->spin_w_target_met += w_target && w_met;
        totals->spin_q_met += q_met;
    }
    double model_q = fs == CF_OK ? fit.q.weighted_mean : NAN;
    double drift = finite ? class_distance(ctx, mesh, x) : NAN;
    if (spin) totals->class_spin = drift;
    if (o->kind == CF_FLOW_CONFORMAL_MCF) totals->class_cmcf = drift;
    fprintf(stderr, "   %-24s %-22s %-16s %11.4g %11.4g %-4s %7.3f %7.3f %10.3g %7.2f %8.1f %8.3g %-6s %s\n", name,
            method, cf_status_name(st), e0, e1, monotone ? "yes" : "no", qs == CF_OK ? q.weighted_mean : NAN, model_q,
            qs == CF_OK ? q.max : NAN, min_angle, steps ? 1000.0 * seconds / steps : 0.0, drift, targets, message);
    totals->runs++;

    CHECK(finite);
    CHECK(loads);
    /* a failed step is a numerical failure (the CLI's exit 3), never 'bad input' */
    if (st != CF_OK && st != CF_ERR_NUMERICAL && st != CF_ERR_NOT_POSDEF)
        cft_fail(__FILE__, __LINE__, "%s on %s: %s (%s)", method, name, message, cf_status_name(st));
    /* the edit's local/global iteration never raises its energy (Sec. 4) */
    if (edit && !monotone) cft_fail(__FILE__, __LINE__, "%s on %s: the energy rose", method, name);
    if (spin) {
        if (st != CF_OK) cft_fail(__FILE__, __LINE__, "spin-willmore on %s failed: %s", name, message);
        if (!monotone) cft_fail(__FILE__, __LINE__, "spin-willmore on %s: W rose during the flow", name);
        CHECK_OK(ctx, fs);
        if (qs == CF_OK && q.weighted_mean > 1.5 && !(fabs(model_q - q.weighted_mean) <= 0.05 * q.weighted_mean))
            cft_fail(__FILE__, __LINE__, "spin-willmore on %s: mean Q %.4f, vertex-scale model %.4f", name,
                     q.weighted_mean, model_q);
    }
    cf_flow_destroy(&flow);
}

/* The same along x, bending the far end about z: for a mesh flat in y
 * (plane_841), where both boxes in y hold every vertex. */
static const char *const turn_end_handles =
    "{ \"sets\": [ { \"name\": \"base\", \"relative_box\": { \"min\": [0, 0, 0], \"max\": [0.1, 1, 1] }, "
    "\"fixed\": true }, { \"name\": \"end\", \"relative_box\": { \"min\": [0.9, 0, 0], \"max\": [1, 1, 1] }, "
    "\"transform\": { \"rotate\": { \"axis\": [0, 0, 1], \"angle_degrees\": 30 } } } ] }";

/* The edit needs handles: one file that fits every mesh (relative boxes:
 * the lowest tenth in y fixed, the highest turned 30 degrees about x; on a
 * mesh flat in y the same along x), and each of its energies with the
 * other defaults (docs/edit.md; its ARAP weights are the paper's, "ARAP
 * edge weights"). */
static void run_edits(cf_context *ctx, const char *name, const cf_mesh *mesh, zoo_totals *totals)
{
    cf_handle_set *h = NULL;
    cf_status st =
        cf_handle_set_parse_json(ctx, mesh, cf_mesh_positions(mesh), cft_turn_top_handles, "zoo handles", &h);
    if (st == CF_ERR_PARSE && strstr(cf_context_message(ctx), "overlap")) {
        fprintf(stderr, "   %-24s %-22s handles along y overlap (%s): along x\n", name, "stretch-bend-edit",
                cf_context_message(ctx));
        st = cf_handle_set_parse_json(ctx, mesh, cf_mesh_positions(mesh), turn_end_handles, "zoo handles", &h);
    }
    if (st != CF_OK) {
        fprintf(stderr, "   %-24s %-22s handles: %s: %s\n", name, "stretch-bend-edit", cf_status_name(st),
                cf_context_message(ctx));
        CHECK(st == CF_ERR_PARSE);
        return;
    }
    for (int e = 0; e < CF_STRETCH_BEND_ENERGY_COUNT; ++e) {
        cf_flow_options o;
        cf_flow_options_default(CF_FLOW_STRETCH_BEND_EDIT, &o);
        cf_stretch_bend_options *so = cf_flow_options_method(&o);
        so->energy = e;
        so->handles = h;
        char method[64];
        snprintf(method, sizeof method, "edit %s", cf_stretch_bend_energy_name((cf_stretch_bend_energy_kind)e));
        run_one(ctx, name, mesh, method, &o, totals);
    }
    cf_handle_set_destroy(&h);
}

static void test_zoo(void)
{
    const char *manifest = cft_require_shared_mesh("MANIFEST.tsv");
    FILE *fp = fopen(manifest, "r");
    CHECK(fp != NULL);
    if (!fp) return;
    cf_context *ctx = NULL;
    CHECK_OK(ctx, cf_context_create(&ctx));
    zoo_totals totals = {0};
    fprintf(stderr, "   %-24s %-22s %-16s %11s %11s %-4s %7s %7s %10s %7s %8s %8s %-6s %s\n", "mesh", "method", "status",
            "E0", "E10", "mono", "meanQ", "scaleQ", "maxQ", "minang", "ms/step", "class", "target", "message");
    char line[4096];
    int header = 1;
    while (fgets(line, sizeof line, fp)) {
        if (header) {
            header = 0;
            continue;
        }
        char *tab = strchr(line, '\t');
        if (!tab) continue;
        *tab = '\0';
        const char *path = cft_shared_mesh_path(line);
        cf_mesh *mesh = NULL;
        CHECK_OK(ctx, cf_load_mesh(ctx, path, &mesh));
        if (!mesh) continue;
        if (cf_mesh_vertex_count(mesh) > ZOO_MAX_VERTICES) {
            fprintf(stderr, "SKIP: %s (%d vertices) in a sanitizer build\n", line, cf_mesh_vertex_count(mesh));
        } else {
            totals.class_spin = totals.class_cmcf = NAN;
            for (int k = 0; k < CF_FLOW_KIND_COUNT; ++k) {
                if (k == CF_FLOW_STRETCH_BEND_EDIT) {
                    run_edits(ctx, line, mesh, &totals);
                    continue;
                }
                cf_flow_options o;
                cf_flow_options_default((cf_flow_kind)k, &o);
                run_one(ctx, line, mesh, cf_flow_kind_name((cf_flow_kind)k), &o, &totals);
            }
            /* the conformal Willmore flow keeps the conformal class, the
             * conformalized MCF does not try (docs/spin.md, "The conformal
             * class the flow keeps": bob 0.0062 against 0.94, elephant 0.78
             * against 3.5) */
            if (!isnan(totals.class_spin) && !isnan(totals.class_cmcf) && !(totals.class_spin < totals.class_cmcf))
                cft_fail(__FILE__, __LINE__, "%s: spin-willmore moved the conformal class by %.3g, conformal-mcf by %.3g",
                         line, totals.class_spin, totals.class_cmcf);
        }
        cf_mesh_destroy(&mesh);
    }
    fclose(fp);
    fprintf(stderr,
            "   %d runs; spin-willmore issue-13 targets: W10 <= W0/2 on %d of %d meshes with W0/4pi >= 2, mean Q <= 1.5 "
            "on %d of %d\n",
            totals.runs, totals.spin_w_target_met, totals.spin_w_target, totals.spin_q_met, totals.spin_runs);
    CHECK(totals.spin_runs > 0);
    /* no regression on the issue-13 targets met so far (all 20 shared
     * meshes, i.e. not in sanitizer builds): W on 17 of 19 and mean Q on 17
     * of 20 since the vertex-scale fairing (15 and 15 before; the W misses
     * are bob and the double torus, bounded by their conformal classes),
     * mean Q on 18 since the tangential relaxation became a default on closed
     * genus-0 surfaces (session 36: cactus 1.580 -> 1.496; 1.4959-1.4982 with
     * its coordinates perturbed by up to 1e-4 of themselves; the misses elk
     * and the double torus, of genus 1 and 2; docs/spin.md) */
    if (totals.spin_runs == 20) {
        CHECK(totals.spin_w_target_met >= 17);
        CHECK(totals.spin_q_met >= 18);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_zoo);
    return cft_finish();
}
