/*
 * curvflow info IN [--json]: counts, components, boundary loops, genus,
 * Euler characteristic, the validation report (every defect counted),
 * corner-angle and face-area statistics, and W/4pi for closed meshes.
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

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow info IN [--json]\n"
            "Prints counts, connected components, boundary loops, genus, Euler characteristic,\n"
            "the validation report, corner angle statistics (min / median / fraction below 10 deg,\n"
            "and per face: median smallest angle, fraction of faces whose smallest angle is below 10 deg),\n"
            "face area statistics and, for closed meshes, the Willmore energy W/4pi; of a file whose\n"
            "boundary vertices lie on others (seams), what the other commands weld (docs/io.md).\n\n"
            "  --json       print one JSON object instead of text (for an unreadable file:\n"
            "               {\"file\", \"readable\": false, \"status\", \"error\"})\n"
            "  -h, --help   show this help\n\n"
            "Exit status: 0 valid mesh, 2 unreadable file or invalid mesh (the report is still printed).\n");
}

static json_t *num(double v) { return isfinite(v) ? json_real(v) : json_null(); }

/* The validation report as a JSON object. */
static json_t *validation_json(const cf_mesh_report *report)
{
    json_t *val = json_object();
    json_object_set_new(val, "valid", json_boolean(report->first_status == CF_OK));
    json_object_set_new(val, "index_out_of_range", json_integer(report->index_out_of_range));
    json_object_set_new(val, "repeated_index", json_integer(report->repeated_index));
    json_object_set_new(val, "nonfinite_coordinates", json_integer(report->nonfinite_coordinates));
    json_object_set_new(val, "degenerate_faces", json_integer(report->degenerate_faces));
    json_object_set_new(val, "nonmanifold_edges", json_integer(report->nonmanifold_edges));
    json_object_set_new(val, "nonmanifold_vertices", json_integer(report->nonmanifold_vertices));
    json_object_set_new(val, "inconsistent_orientation_edges", json_integer(report->inconsistent_orientation_edges));
    json_object_set_new(val, "unreferenced_vertices", json_integer(report->unreferenced_vertices));
    json_object_set_new(val, "first_error",
                        report->first_status == CF_OK ? json_null() : json_string(report->first_message));
    return val;
}

/* Topology and the library's quality figures (cf_mesh_quality_compute, the
 * same the Python package reports) of a valid mesh, into root. */
static cf_status add_mesh_figures(cf_context *ctx, const cf_mesh *mesh, json_t *root)
{
    json_object_set_new(root, "edges", json_integer(cf_mesh_edge_count(mesh)));
    json_object_set_new(root, "components", json_integer(cf_mesh_component_count(mesh)));
    json_object_set_new(root, "boundary_loops", json_integer(cf_mesh_boundary_loop_count(mesh)));
    json_object_set_new(root, "euler_characteristic", json_integer(cf_mesh_euler_characteristic(mesh)));
    json_object_set_new(root, "genus", json_integer(cf_mesh_genus(mesh)));
    cf_mesh_quality q;
    cf_status st = cf_mesh_quality_compute(ctx, mesh, NULL, &q);
    if (st != CF_OK) return st;
    const double deg = 180.0 / acos(-1.0);
    json_t *ang = json_object();
    json_object_set_new(ang, "min_degrees", num(q.min_angle * deg));
    json_object_set_new(ang, "median_degrees", num(q.median_angle * deg));
    json_object_set_new(ang, "max_degrees", num(q.max_angle * deg));
    json_object_set_new(ang, "fraction_below_10_degrees", num(q.fraction_angles_below_10_degrees));
    json_object_set_new(ang, "median_face_min_degrees", num(q.median_face_min_angle * deg));
    json_object_set_new(ang, "fraction_faces_min_below_10_degrees", num(q.fraction_faces_min_below_10_degrees));
    json_object_set_new(root, "angles", ang);
    json_t *ar = json_object();
    json_object_set_new(ar, "total", num(q.total_area));
    json_object_set_new(ar, "min", num(q.min_face_area));
    json_object_set_new(ar, "median", num(q.median_face_area));
    json_object_set_new(ar, "max", num(q.max_face_area));
    json_object_set_new(ar, "max_over_min", num(q.max_face_area / q.min_face_area));
    json_object_set_new(root, "face_areas", ar);
    /* NaN (null) with boundary loops */
    json_object_set_new(root, "willmore_over_4pi", num(q.willmore_over_4pi));
    json_object_set_new(root, "volume", num(q.volume));
    return CF_OK;
}

static json_t *string_array(char *const *strings, int32_t count)
{
    json_t *a = json_array();
    for (int32_t i = 0; i < count; ++i) json_array_append_new(a, json_string(strings[i]));
    return a;
}

/* What the file carries besides the mesh, which flow and edit write back:
 * property names (PLY properties, OBJ / OFF colours) and OBJ materials. */
static void add_file_contents(const cf_mesh_data *data, json_t *root)
{
    json_t *vp = json_array(), *fp = json_array();
    for (int32_t i = 0; i < data->vertex_property_count; ++i)
        json_array_append_new(vp, json_string(data->vertex_properties[i].name));
    for (int32_t i = 0; i < data->face_property_count; ++i)
        json_array_append_new(fp, json_string(data->face_properties[i].name));
    json_object_set_new(root, "vertex_properties", vp);
    json_object_set_new(root, "face_properties", fp);
    json_object_set_new(root, "material_libraries",
                        string_array(data->material_libraries, data->material_library_count));
    json_object_set_new(root, "material_names", string_array(data->material_names, data->material_count));
}

/* "name name ..." of a JSON array of strings, on one line. */
static void print_names(const char *label, const json_t *names)
{
    if (json_array_size(names) == 0) return;
    printf("%s", label);
    size_t i;
    const json_t *name;
    json_array_foreach(names, i, name) printf(" %s", json_string_value(name));
    putchar('\n');
}

/* The text form of root (mesh NULL: the mesh is invalid, report says why). */
/* What the other commands make of the file's vertices (docs/io.md,
 * "Unused vertices" and "Seams"): the file read again, its unused vertices
 * dropped (cf_mesh_data_drop_unreferenced) and its seams welded
 * (cf_mesh_data_weld), its topology. */
static cf_status seams_json(cf_context *ctx, const char *path, json_t *root)
{
    cf_mesh_data *data = NULL;
    cf_mesh *mesh = NULL;
    cf_weld_report r;
    int32_t dropped = 0;
    cf_status st = cf_read_mesh_file(ctx, path, &data);
    if (st == CF_OK) st = cli_tidy_vertices(ctx, data, &dropped, &r);
    if (st == CF_OK && r.welded) {
        cf_mesh_desc desc;
        cf_mesh_data_desc(data, &desc);
        st = cf_mesh_create(ctx, &desc, &mesh);
    }
    if (st == CF_OK) {
        json_t *o = json_object();
        json_object_set_new(o, "unused_vertices", json_integer(dropped));
        json_object_set_new(o, "coincident_boundary_vertices", json_integer(r.candidates));
        json_object_set_new(o, "positions", json_integer(r.groups));
        json_object_set_new(o, "welded_vertices", mesh ? json_integer(r.vertices) : json_null());
        json_object_set_new(o, "welded_boundary_loops", mesh ? json_integer(cf_mesh_boundary_loop_count(mesh)) : json_null());
        json_object_set_new(o, "welded_genus", mesh ? json_integer(cf_mesh_genus(mesh)) : json_null());
        json_object_set_new(o, "refused", r.refused[0] ? json_string(r.refused) : json_null());
        json_object_set_new(root, "seams", o);
    }
    cf_mesh_destroy(&mesh);
    cf_mesh_data_destroy(&data);
    return st;
}

static void print_seams(json_t *root)
{
    json_t *o = json_object_get(root, "seams");
    json_int_t unused = json_integer_value(json_object_get(o, "unused_vertices"));
    if (unused > 0)
        printf("unused:        %lld vertices that no face uses; flow, spin, edit, compare and report drop them "
               "(--no-weld keeps them, and the mesh is refused)\n",
               (long long)unused);
    json_int_t n = json_integer_value(json_object_get(o, "coincident_boundary_vertices"));
    if (n == 0) return;
    printf("seams:         %lld boundary vertices lie on others (%lld positions); ", (long long)n,
           (long long)json_integer_value(json_object_get(o, "positions")));
    if (json_is_integer(json_object_get(o, "welded_vertices")))
        printf("flow, spin, edit, compare and report weld them: %lld vertices, %lld boundary loops, genus %lld "
               "(--no-weld keeps them apart)\n",
               (long long)json_integer_value(json_object_get(o, "welded_vertices")),
               (long long)json_integer_value(json_object_get(o, "welded_boundary_loops")),
               (long long)json_integer_value(json_object_get(o, "welded_genus")));
    else
        printf("not welded: %s\n", json_string_value(json_object_get(o, "refused")));
}

static void print_text(const char *path, const cf_mesh_data *data, const cf_mesh *mesh, const cf_mesh_report *report,
                       json_t *root)
{
    printf("file:          %s\n", path);
    printf("vertices:      %d\nfaces:         %d\n", (int)data->vertex_count, (int)data->face_count);
    if (data->polygon_count) printf("polygons:      %d (fan-triangulated)\n", (int)data->polygon_count);
    printf("uv:            %s\n", json_string_value(json_object_get(root, "texture_coordinates")));
    print_names("vertex props: ", json_object_get(root, "vertex_properties"));
    print_names("face props:   ", json_object_get(root, "face_properties"));
    print_names("mtllib:       ", json_object_get(root, "material_libraries"));
    print_names("materials:    ", json_object_get(root, "material_names"));
    if (!mesh) {
        printf("validation:    INVALID: %s\n", report->first_message);
        printf("  index out of range %d, repeated index %d, non-finite %d, degenerate faces %d,\n"
               "  non-manifold edges %d, non-manifold vertices %d, inconsistent orientation %d, unreferenced %d\n",
               (int)report->index_out_of_range, (int)report->repeated_index, (int)report->nonfinite_coordinates,
               (int)report->degenerate_faces, (int)report->nonmanifold_edges, (int)report->nonmanifold_vertices,
               (int)report->inconsistent_orientation_edges, (int)report->unreferenced_vertices);
        return;
    }
    printf("edges:         %d\n", (int)cf_mesh_edge_count(mesh));
    printf("components:    %d\nboundary loops: %d\n", (int)cf_mesh_component_count(mesh),
           (int)cf_mesh_boundary_loop_count(mesh));
    printf("euler char.:   %d\ngenus:         %d\n", (int)cf_mesh_euler_characteristic(mesh), (int)cf_mesh_genus(mesh));
    json_t *ang = json_object_get(root, "angles"), *ar = json_object_get(root, "face_areas");
    printf("angles (deg):  min %.4g  median %.4g  max %.4g  below 10 deg: %.2f %%\n",
           json_real_value(json_object_get(ang, "min_degrees")), json_real_value(json_object_get(ang, "median_degrees")),
           json_real_value(json_object_get(ang, "max_degrees")),
           100.0 * json_real_value(json_object_get(ang, "fraction_below_10_degrees")));
    printf("face min angle: median %.4g deg, faces with min angle below 10 deg: %.2f %%\n",
           json_real_value(json_object_get(ang, "median_face_min_degrees")),
           100.0 * json_real_value(json_object_get(ang, "fraction_faces_min_below_10_degrees")));
    printf("face areas:    total %.6g  min %.4g  median %.4g  max %.4g  (max/min %.3g)\n",
           json_real_value(json_object_get(ar, "total")), json_real_value(json_object_get(ar, "min")),
           json_real_value(json_object_get(ar, "median")), json_real_value(json_object_get(ar, "max")),
           json_real_value(json_object_get(ar, "max_over_min")));
    json_t *w = json_object_get(root, "willmore_over_4pi");
    if (json_is_real(w))
        printf("W/4pi:         %.6g\nvolume:        %.6g\n", json_real_value(w),
               json_real_value(json_object_get(root, "volume")));
    printf("validation:    ok\n");
}

int cli_info(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"json", no_argument, NULL, 'j'}, {"help", no_argument, NULL, 'h'}, {NULL, 0, NULL, 0}};
    int as_json = 0, c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":h", longopts, NULL)) != -1) {
        switch (c) {
        case 'j': as_json = 1; break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error("info", c, argv);
        }
    }
    if (optind + 1 != argc) return cli_usage_error("info", "expected one input mesh, got %d", argc - optind);
    const char *path = argv[optind];

    cf_context *ctx = cli_context(false);
    if (!ctx) return CLI_EXIT_NUMERICAL;
    int code = CLI_EXIT_OK;
    cf_mesh_data *data = NULL;
    cf_mesh *mesh = NULL;
    json_t *root = json_object();

    cf_status st = cf_read_mesh_file(ctx, path, &data);
    if (st != CF_OK) {
        if (as_json) {
            /* stdout stays one JSON object also for an unreadable file */
            json_object_set_new(root, "file", json_string(path));
            json_object_set_new(root, "readable", json_false());
            json_object_set_new(root, "status", json_string(cf_status_name(st)));
            json_object_set_new(root, "error", json_string(cf_context_message(ctx)));
            char *text = json_dumps(root, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
            if (text) puts(text);
            free(text);
        }
        code = cli_fail(ctx, path, st);
        if (code == CLI_EXIT_USAGE) code = CLI_EXIT_INPUT;
        goto done;
    }
    cf_mesh_desc desc;
    cf_mesh_data_desc(data, &desc);
    cf_mesh_report report;
    st = cf_mesh_validate(ctx, &desc, &report);
    if (st != CF_OK) {
        code = cli_fail(ctx, path, st);
        goto done;
    }
    json_object_set_new(root, "file", json_string(path));
    json_object_set_new(root, "vertices", json_integer(data->vertex_count));
    json_object_set_new(root, "faces", json_integer(data->face_count));
    json_object_set_new(root, "polygons_triangulated", json_integer(data->polygon_count));
    json_object_set_new(root, "texture_coordinates",
                        json_string(data->uv_count == 0 ? "none" : data->uv_triangles ? "per-corner" : "per-vertex"));
    add_file_contents(data, root);
    json_object_set_new(root, "validation", validation_json(&report));

    if (report.first_status == CF_OK) {
        st = cf_mesh_create(ctx, &desc, &mesh);
        if (st != CF_OK) {
            code = cli_fail(ctx, path, st);
            goto done;
        }
        if ((st = add_mesh_figures(ctx, mesh, root)) != CF_OK) {
            code = cli_fail(ctx, path, st);
            goto done;
        }
    } else {
        code = CLI_EXIT_INPUT;
    }
    if ((st = seams_json(ctx, path, root)) != CF_OK) {
        code = cli_fail(ctx, path, st);
        goto done;
    }

    if (as_json) {
        char *text = json_dumps(root, JSON_INDENT(2) | JSON_REAL_PRECISION(10) | JSON_PRESERVE_ORDER);
        if (text) puts(text);
        free(text);
    } else {
        print_text(path, data, mesh, &report, root);
        print_seams(root);
    }
    if (!mesh) fprintf(stderr, "curvflow: %s: %s\n", path, report.first_message);

done:
    json_decref(root);
    cf_mesh_destroy(&mesh);
    cf_mesh_data_destroy(&data);
    cf_context_destroy(&ctx);
    return code;
}
