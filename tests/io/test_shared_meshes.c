/* Every mesh of ../shared/meshes: read with the vertex and face counts of
 * MANIFEST.tsv, loaded as a valid mesh with the listed genus, boundary
 * loops and components, and written back to binary PLY and OBJ bit-exactly. */
#define _POSIX_C_SOURCE 200809L
#include "io_test_util.h"

static void check_mesh(const char *name, int nv, int nf, int genus, int loops, int comps)
{
    cf_context *ctx = cft_context();
    char path[4096];
    snprintf(path, sizeof path, "%s", cft_require_shared_mesh(name));
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_file(ctx, path, &d));
    if (!d) {
        cf_context_destroy(&ctx);
        return;
    }
    if (d->vertex_count != nv || d->face_count != nf)
        cft_fail(__FILE__, __LINE__, "%s: read %d vertices %d faces, MANIFEST says %d, %d", name, d->vertex_count,
                 d->face_count, nv, nf);
    cf_mesh_desc desc;
    cf_mesh_data_desc(d, &desc);
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &desc, &m));
    if (m) {
        if (cf_mesh_genus(m) != genus || cf_mesh_boundary_loop_count(m) != loops || cf_mesh_component_count(m) != comps)
            cft_fail(__FILE__, __LINE__, "%s: genus %d loops %d components %d, MANIFEST says %d %d %d", name,
                     cf_mesh_genus(m), cf_mesh_boundary_loop_count(m), cf_mesh_component_count(m), genus, loops, comps);
        static const char *const exts[2] = {".ply", ".obj"};
        for (int e = 0; e < 2; ++e) {
            char out[4096];
            snprintf(out, sizeof out, "%s", cft_temp_path(exts[e]));
            CHECK_OK(ctx, cf_write_mesh_file(ctx, out, m, NULL, NULL, 0));
            cf_mesh_data *back = NULL;
            CHECK_OK(ctx, cf_read_mesh_file(ctx, out, &back));
            if (back) {
                CHECK(back->vertex_count == nv && back->face_count == nf);
                CHECK(memcmp(back->positions, d->positions, sizeof(double) * 3 * (size_t)nv) == 0);
                CHECK(memcmp(back->triangles, d->triangles, sizeof(int32_t) * 3 * (size_t)nf) == 0);
            }
            cf_mesh_data_destroy(&back);
            remove(out);
        }
    }
    cf_mesh_destroy(&m);
    cf_mesh_data_destroy(&d);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_manifest(void)
{
    char path[4096];
    snprintf(path, sizeof path, "%s", cft_require_shared_mesh("MANIFEST.tsv"));
    char *text = iot_read(path, NULL);
    CHECK(text != NULL);
    if (!text) return;
    int meshes = 0;
    char *save = NULL;
    for (char *line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        char name[256];
        int nv, nf, genus, loops, comps;
        /* file vertices faces genus boundary_loops components ... */
        if (sscanf(line, "%255[^\t]\t%d\t%d\t%d\t%d\t%d", name, &nv, &nf, &genus, &loops, &comps) != 6) continue;
        check_mesh(name, nv, nf, genus, loops, comps);
        ++meshes;
    }
    free(text);
    CHECK(meshes >= 13);
}

int main(void)
{
    CFT_RUN(test_manifest);
    return cft_finish();
}
