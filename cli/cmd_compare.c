/*
 * curvflow compare A B [--json] [--ply OUT]: quasi-conformal error Q
 * (Sander et al. 2001), log area distortion and angle change between two
 * meshes with the same connectivity (include/curvflow/metrics.h).
 */
#define _GNU_SOURCE
#include "common.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"

#include <getopt.h>
#include <jansson.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow compare A B [--json] [--ply OUT]\n"
            "Compares two meshes with the same connectivity (B a deformation of A): per-face\n"
            "quasi-conformal error Q = sigma_max / sigma_min of the affine map A -> B (1 = conformal),\n"
            "log area distortion log(area_B / area_A) after normalising the total area, and the\n"
            "per-vertex largest corner angle change. Means are area-weighted (areas of A).\n"
            "Also the vertex-scale model: log scale factors fitted at the vertices to the change of\n"
            "edge lengths (least squares; discrete conformal rescaling) and the Q of each face with\n"
            "its lengths so rescaled: the part of Q that the variation of the conformal scale\n"
            "across the faces causes by itself, which a conformal map of that scale cannot avoid\n"
            "on this triangulation (near the measured Q: the map is as conformal as its scale\n"
            "allows). The residual is the RMS log-length change that no vertex scale explains.\n"
            "On a closed connected surface of genus >= 1 also the distance between the conformal\n"
            "classes of A and B (0: conformally equivalent; genus 1: the hyperbolic distance of the\n"
            "moduli, both printed; docs/ops.md, \"Conformal class\").\n\n"
            "  --json       print one JSON object instead of text\n"
            "  --ply OUT    write B with per-face fields Q and log_area_distortion and the per-vertex\n"
            "               field log_scale, the fitted log conformal factor (OUT.ply: PLY properties;\n"
            "               OUT.obj: side CSVs <stem>.face.csv, <stem>.vertex.csv; OFF cannot hold them)\n"
            "  -f, --force  replace read-only output files\n"
            "  --no-weld    keep boundary vertices that share a position apart and vertices no face uses\n"
            "               (by default each file's are welded and dropped, as flow does: docs/io.md)\n"
            "  -h, --help   show this help\n\n"
            "Exit status: 0 ok, 1 usage, 2 unreadable / invalid mesh, different connectivity, or an\n"
            "output that cannot or must not be written (checked before reading).\n");
}

static json_t *num(double v) { return isfinite(v) ? json_real(v) : json_null(); }

static json_t *stats_json(const cf_stats *s)
{
    json_t *o = json_object();
    json_object_set_new(o, "mean", num(s->weighted_mean));
    json_object_set_new(o, "std", num(s->weighted_std));
    json_object_set_new(o, "min", num(s->min));
    json_object_set_new(o, "median", num(s->p50));
    json_object_set_new(o, "p95", num(s->p95));
    json_object_set_new(o, "max", num(s->max));
    return o;
}

int cli_compare(int argc, char **argv)
{
    static const struct option longopts[] = {{"json", no_argument, NULL, 'j'},
                                             {"ply", required_argument, NULL, 'p'},
                                             {"help", no_argument, NULL, 'h'},
                                             {"force", no_argument, NULL, 'f'},
                                             {"no-weld", no_argument, NULL, 'w'},
                                             {NULL, 0, NULL, 0}};
    int as_json = 0, c;
    bool force = false;
    const char *ply = NULL;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":fh", longopts, NULL)) != -1) {
        switch (c) {
        case 'j': as_json = 1; break;
        case 'p': ply = optarg; break;
        case 'f': force = true; break;
        case 'w': cli_set_weld(false); break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error("compare", c, argv);
        }
    }
    if (optind + 2 != argc) return cli_usage_error("compare", "expected two meshes A B, got %d", argc - optind);
    const char *pa = argv[optind], *pb = argv[optind + 1];
    cli_files files = {.force = force};
    cli_files_input(&files, "A", pa);
    cli_files_input(&files, "B", pb);
    /* an OBJ gets its face fields in "<stem>.face.csv" (cf_write_mesh_file):
     * that file is an output too */
    char side[4096] = "";
    if (ply) {
        cli_files_output(&files, "--ply", ply, CLI_FILE_FIELD_MESH);
        size_t n = strlen(ply);
        if (n > 4 && n < sizeof side - 16 && strcasecmp(ply + n - 4, ".obj") == 0) {
            snprintf(side, sizeof side, "%.*s.face.csv", (int)(n - 4), ply);
            cli_files_output(&files, "--ply (its face fields)", side, CLI_FILE_TABLE);
        }
    }
    cf_context *ctx = cli_context(false);
    if (!ctx) return CLI_EXIT_NUMERICAL;
    cf_mesh *a = NULL, *b = NULL;
    double *q = NULL, *lad = NULL, *log_scale = NULL;
    int code = cli_files_check(ctx, &files);
    if (code == CLI_EXIT_OK) code = cli_load_mesh(ctx, pa, &a);
    if (code == CLI_EXIT_OK) code = cli_load_mesh(ctx, pb, &b);
    if (code != CLI_EXIT_OK) goto done;
    int32_t nv = cf_mesh_vertex_count(a), nf = cf_mesh_face_count(a);
    if (cf_mesh_vertex_count(b) != nv || cf_mesh_face_count(b) != nf ||
        memcmp(cf_mesh_triangles(a), cf_mesh_triangles(b), 3 * (size_t)nf * sizeof(int32_t)) != 0) {
        fprintf(stderr, "curvflow: %s: connectivity differs from %s (%d/%d vertices, %d/%d faces)\n", pb, pa,
                (int)cf_mesh_vertex_count(b), (int)nv, (int)cf_mesh_face_count(b), (int)nf);
        code = CLI_EXIT_INPUT;
        goto done;
    }
    q = malloc((size_t)nf * sizeof *q);
    lad = malloc((size_t)nf * sizeof *lad);
    log_scale = malloc((size_t)nv * sizeof *log_scale);
    if (!q || !lad || !log_scale) {
        fprintf(stderr, "curvflow: out of memory\n");
        code = CLI_EXIT_NUMERICAL;
        goto done;
    }
    const double *xa = cf_mesh_positions(a), *xb = cf_mesh_positions(b);
    cf_stats sq, sl, sa;
    cf_vertex_scale_fit fit;
    cf_status st;
    if ((st = cf_quasi_conformal_error(ctx, a, xa, xb, q, &sq)) != CF_OK ||
        (st = cf_log_area_distortion(ctx, a, xa, xb, lad, &sl)) != CF_OK ||
        (st = cf_angle_change(ctx, a, xa, xb, NULL, &sa)) != CF_OK ||
        (st = cf_vertex_scale_fit_compute(ctx, a, xa, xb, log_scale, NULL, &fit)) != CF_OK) {
        code = cli_fail(ctx, pb, st);
        if (code == CLI_EXIT_USAGE) code = CLI_EXIT_INPUT;
        goto done;
    }
    /* closed surfaces of genus >= 1: how far B's conformal class is from A's */
    int class_measured = 0;
    const char *class_problem = NULL;
    double class_distance = NAN;
    cf_conformal_class ca, cb;
    if (cf_mesh_component_count(a) == 1 && cf_mesh_boundary_loop_count(a) == 0 && cf_mesh_genus(a) >= 1) {
        if (cf_conformal_class_distance(ctx, a, xa, xb, &ca, &cb, &class_distance) == CF_OK)
            class_measured = 1;
        else
            class_problem = cf_context_message(ctx);
    }
    const double deg = 180.0 / acos(-1.0);
    if (as_json) {
        json_t *root = json_object();
        json_object_set_new(root, "a", json_string(pa));
        json_object_set_new(root, "b", json_string(pb));
        json_object_set_new(root, "faces", json_integer(nf));
        json_object_set_new(root, "quasi_conformal_error", stats_json(&sq));
        json_object_set_new(root, "log_area_distortion", stats_json(&sl));
        json_t *ang = stats_json(&sa);
        json_object_set_new(ang, "unit", json_string("radians"));
        json_object_set_new(root, "angle_change", ang);
        json_t *model = stats_json(&fit.q);
        json_object_set_new(model, "invalid_faces", json_integer(fit.invalid_faces));
        json_object_set_new(model, "rms_log_length_residual", num(fit.rms_residual));
        json_object_set_new(root, "vertex_scale_model_q", model);
        json_t *cls = json_null();
        if (class_measured) {
            cls = json_object();
            json_object_set_new(cls, "genus", json_integer(ca.genus));
            json_object_set_new(cls, "distance", num(class_distance));
            if (ca.genus == 1) {
                json_object_set_new(cls, "modulus_a", json_pack("[o, o]", num(ca.modulus[0]), num(ca.modulus[1])));
                json_object_set_new(cls, "modulus_b", json_pack("[o, o]", num(cb.modulus[0]), num(cb.modulus[1])));
            }
        } else if (class_problem) {
            cls = json_object();
            json_object_set_new(cls, "error", json_string(class_problem));
        }
        json_object_set_new(root, "conformal_class", cls);
        char *text = json_dumps(root, JSON_INDENT(2) | JSON_REAL_PRECISION(10) | JSON_PRESERVE_ORDER);
        if (text) puts(text);
        free(text);
        json_decref(root);
    } else {
        printf("faces:                 %d\n", (int)nf);
        printf("quasi-conformal Q:     mean %.6f  median %.6f  p95 %.6f  max %.6f\n", sq.weighted_mean, sq.p50, sq.p95,
               sq.max);
        printf("log area distortion:   mean %+.4e  std %.4e  min %+.4f  max %+.4f\n", sl.weighted_mean, sl.weighted_std,
               sl.min, sl.max);
        printf("angle change (deg):    mean %.4f  p95 %.4f  max %.4f\n", sa.weighted_mean * deg, sa.p95 * deg,
               sa.max * deg);
        printf("vertex-scale model Q:  mean %.6f  median %.6f  p95 %.6f  max %.6f  (%d faces without a model "
               "triangle; log-length residual rms %.4f)\n",
               fit.q.weighted_mean, fit.q.p50, fit.q.p95, fit.q.max, (int)fit.invalid_faces, fit.rms_residual);
        if (class_measured && ca.genus == 1)
            printf("conformal class:       distance %.4e  (genus 1: modulus %.6f%+.6fi -> %.6f%+.6fi)\n", class_distance,
                   ca.modulus[0], ca.modulus[1], cb.modulus[0], cb.modulus[1]);
        else if (class_measured)
            printf("conformal class:       distance %.4e  (genus %d)\n", class_distance, (int)ca.genus);
        else if (class_problem)
            printf("conformal class:       not measured: %s\n", class_problem);
    }
    if (ply) {
        cf_field fields[3] = {{"Q", CF_FIELD_FACE, q},
                              {"log_area_distortion", CF_FIELD_FACE, lad},
                              {"log_scale", CF_FIELD_VERTEX, log_scale}};
        st = cf_write_mesh_file(ctx, ply, b, NULL, fields, 3);
        if (st != CF_OK) {
            code = cli_fail(ctx, ply, st);
            if (code == CLI_EXIT_USAGE) code = CLI_EXIT_INPUT;
        } else if (!as_json) {
            printf("wrote:                 %s (per-face Q, log_area_distortion; per-vertex log_scale)\n", ply);
        }
    }
done:
    free(q);
    free(lad);
    free(log_scale);
    cf_mesh_destroy(&a);
    cf_mesh_destroy(&b);
    cf_context_destroy(&ctx);
    return code;
}
