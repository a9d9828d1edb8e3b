/* Mesh core on every file of ../shared/meshes: V, E, F, Euler
 * characteristic, genus, boundary loops, boundary edges and components
 * equal the independently computed values of CHECKS.tsv; the bad files
 * with topological defects are rejected with their own status, and the
 * full report counts the defects listed in bad/MANIFEST.tsv.
 * Skips (exit 77) when ../shared is absent. */
#include "curvflow/io.h"
#include "curvflow/mesh.h"
#include "test.h"

#include <stdlib.h>
#include <string.h>

enum { MAX_COLS = 64, LINE = 4096 };

/* Splits a tab-separated line in place; returns the number of fields. */
static int split_tabs(char *line, char **fields)
{
    int n = 0;
    fields[n++] = line;
    for (char *c = line; *c && n < MAX_COLS; ++c) {
        if (*c == '\t') {
            *c = '\0';
            fields[n++] = c + 1;
        } else if (*c == '\n' || *c == '\r') {
            *c = '\0';
        }
    }
    return n;
}

static int column(char **header, int n, const char *name)
{
    for (int i = 0; i < n; ++i)
        if (strcmp(header[i], name) == 0) return i;
    cft_fail(__FILE__, __LINE__, "CHECKS.tsv has no column %s", name);
    return 0;
}

static void test_checks_tsv(void)
{
    const char *path = cft_require_shared_mesh("CHECKS.tsv");
    FILE *f = fopen(path, "r");
    CHECK(f != NULL);
    if (!f) return;
    static char head_line[LINE], line[LINE];
    char *head[MAX_COLS], *row[MAX_COLS];
    if (!fgets(head_line, sizeof head_line, f)) {
        fclose(f);
        cft_fail(__FILE__, __LINE__, "CHECKS.tsv is empty");
        return;
    }
    int nh = split_tabs(head_line, head);
    int c_name = column(head, nh, "name"), c_v = column(head, nh, "vertices"), c_f = column(head, nh, "faces");
    int c_e = column(head, nh, "edges"), c_chi = column(head, nh, "euler_characteristic");
    int c_g = column(head, nh, "genus"), c_b = column(head, nh, "boundary_loops");
    int c_be = column(head, nh, "boundary_edges"), c_c = column(head, nh, "components");
    int meshes = 0;
    cf_context *ctx = cft_context();
    while (fgets(line, sizeof line, f)) {
        int n = split_tabs(line, row);
        if (n < nh || row[c_name][0] == '\0') continue;
        char mesh_path[LINE];
        snprintf(mesh_path, sizeof mesh_path, "%s", cft_shared_mesh_path(row[c_name]));
        cf_mesh *m = NULL;
        cf_status st = cf_load_mesh(ctx, mesh_path, &m);
        if (st != CF_OK) {
            cft_fail(__FILE__, __LINE__, "%s: %s", row[c_name], cf_context_message(ctx));
            continue;
        }
        ++meshes;
        fprintf(stderr, "   %s: V %d E %d F %d chi %d genus %d loops %d components %d\n", row[c_name],
                cf_mesh_vertex_count(m), cf_mesh_edge_count(m), cf_mesh_face_count(m),
                cf_mesh_euler_characteristic(m), cf_mesh_genus(m), cf_mesh_boundary_loop_count(m),
                cf_mesh_component_count(m));
        CHECK(cf_mesh_vertex_count(m) == atoi(row[c_v]));
        CHECK(cf_mesh_face_count(m) == atoi(row[c_f]));
        CHECK(cf_mesh_edge_count(m) == atoi(row[c_e]));
        CHECK(cf_mesh_euler_characteristic(m) == atoi(row[c_chi]));
        CHECK(cf_mesh_genus(m) == atoi(row[c_g]));
        CHECK(cf_mesh_boundary_loop_count(m) == atoi(row[c_b]));
        CHECK(cf_mesh_component_count(m) == atoi(row[c_c]));
        /* boundary edges = boundary halfedges = boundary loop vertices */
        int32_t loops = cf_mesh_boundary_loop_count(m);
        CHECK(cf_mesh_boundary_loop_offsets(m)[loops] == atoi(row[c_be]));
        cf_mesh_destroy(&m);
    }
    fclose(f);
    CHECK(meshes >= 13);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void validate_file(cf_context *ctx, const char *path, cf_mesh_report *r)
{
    cf_mesh_data *data = NULL;
    memset(r, 0, sizeof *r);
    CHECK_OK(ctx, cf_read_mesh_file(ctx, path, &data));
    if (!data) return;
    cf_mesh_desc d;
    CHECK_OK(ctx, cf_mesh_data_desc(data, &d));
    CHECK_OK(ctx, cf_mesh_validate(ctx, &d, r));
    cf_mesh_data_destroy(&data);
}

static void test_bad_files(void)
{
    const char *beetle = cft_require_shared_mesh("bad/nonmanifold_edges_beetle.obj");
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_STATUS(cf_load_mesh(ctx, beetle, &m), CF_ERR_NONMANIFOLD_EDGE);
    CHECK(m == NULL);
    CHECK(strstr(cf_context_message(ctx), "is shared by 3 faces") != NULL);
    fprintf(stderr, "   %s\n", cf_context_message(ctx));
    cf_mesh_report r;
    validate_file(ctx, beetle, &r);
    CHECK(r.nonmanifold_edges == 47); /* bad/MANIFEST.tsv: 47 edges shared by 3 triangles */
    CHECK_STATUS(r.first_status, CF_ERR_NONMANIFOLD_EDGE);

    const char *spot = cft_require_shared_mesh("bad/flipped_face_spot.obj");
    CHECK_STATUS(cf_load_mesh(ctx, spot, &m), CF_ERR_ORIENTATION);
    fprintf(stderr, "   %s\n", cf_context_message(ctx));
    /* face #101 (1-based) = face 100 was reversed: it belongs to every
     * inconsistent pair, so to the one reported (the lowest pair) */
    CHECK(strstr(cf_context_message(ctx), "faces 94 and 100: edge (212, 822)") != NULL);
    validate_file(ctx, spot, &r);
    CHECK(r.inconsistent_orientation_edges == 3); /* MANIFEST: 3 edges */
    CHECK(r.nonmanifold_edges == 0 && r.nonmanifold_vertices == 0);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_checks_tsv);
    CFT_RUN(test_bad_files);
    return cft_finish();
}
