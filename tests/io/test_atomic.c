/* Atomic output: success replaces the target, every failure (missing
 * directory, directory as target, failed allocation at any point, bad
 * arguments) leaves an existing target byte-for-byte untouched and no
 * temporary file behind. */
#define _POSIX_C_SOURCE 200809L
#include "io/atomic_file.h"
#include "io_test_util.h"

#include <sys/stat.h>
#include <unistd.h>

static void test_text_file(void)
{
    cf_context *ctx = cft_context();
    const char *path = cft_temp_path(".json");
    char keep[4096];
    snprintf(keep, sizeof keep, "%s", path);
    CHECK_OK(ctx, cf_write_text_file_atomic(ctx, keep, "{\"a\": 1}\n", 9));
    char *text = iot_read(keep, NULL);
    CHECK(text && strcmp(text, "{\"a\": 1}\n") == 0);
    free(text);
    /* replaced as a whole */
    CHECK_OK(ctx, cf_write_text_file_atomic(ctx, keep, "x", 1));
    text = iot_read(keep, NULL);
    CHECK(text && strcmp(text, "x") == 0);
    free(text);
    /* the mode of an existing target is kept */
    chmod(keep, 0640);
    CHECK_OK(ctx, cf_write_text_file_atomic(ctx, keep, "yz", 2));
    struct stat st;
    CHECK(stat(keep, &st) == 0 && (st.st_mode & 0777) == 0640);
    CHECK(iot_temp_files(keep) == 0);
    remove(keep);
    CHECK_OK(ctx, cf_write_text_file_atomic(ctx, keep, NULL, 0)); /* empty file */
    CHECK(stat(keep, &st) == 0 && st.st_size == 0);
    remove(keep);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_failures_leave_target_untouched(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    CHECK_STATUS(cf_write_text_file_atomic(ctx, "/nonexistent_dir_cf/out.json", "x", 1), CF_ERR_IO);
    CHECK(strcmp(cf_context_message(ctx), "/nonexistent_dir_cf/out.json: cannot write: No such file or directory") == 0);
    /* a directory as target: the rename fails, the directory stays */
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", cft_temp_path(".dir"));
    CHECK(mkdir(dir, 0755) == 0);
    CHECK_STATUS(cf_write_text_file_atomic(ctx, dir, "x", 1), CF_ERR_IO);
    struct stat st;
    CHECK(stat(dir, &st) == 0 && S_ISDIR(st.st_mode));
    CHECK(iot_temp_files(dir) == 0);
    rmdir(dir);

    /* failed allocation at every point of a PLY/OBJ write */
    cf_mesh *m = iot_octahedron_mesh(ctx, 2);
    double vf[IOT_NV] = {1, 2, 3, 4, 5, 6};
    cf_field field = {"f", CF_FIELD_VERTEX, vf};
    static const char *const exts[] = {".ply", ".obj", ".off"};
    for (int e = 0; e < 3; ++e) {
        char path[4096];
        snprintf(path, sizeof path, "%s", cft_temp_path(exts[e]));
        iot_write_text(path, "old content");
        int failures = 0;
        size_t baseline = cf_context_bytes_in_use(ctx); /* the mesh */
        for (int64_t n = 1; n < 100; ++n) {
            cf_context_fail_allocation(ctx, n, 0);
            cf_status s = cf_write_mesh_file(ctx, path, m, NULL, &field, e == 2 ? 0 : 1);
            cf_context_fail_allocation(ctx, 0, 0);
            CHECK(iot_temp_files(path) == 0);
            CHECK(cf_context_bytes_in_use(ctx) == baseline);
            if (s == CF_OK) break;
            ++failures;
            CHECK_STATUS(s, CF_ERR_NOMEM);
            char *text = iot_read(path, NULL);
            CHECK(text && strcmp(text, "old content") == 0);
            free(text);
        }
        CHECK(failures >= 1);
        cf_mesh_data *d = NULL;
        CHECK_OK(ctx, cf_read_mesh_file(ctx, path, &d));
        CHECK(d && d->vertex_count == IOT_NV);
        cf_mesh_data_destroy(&d);
        remove(path);
        if (e == 1) {
            char csv[4200];
            snprintf(csv, sizeof csv, "%.*s.vertex.csv", (int)(strlen(path) - 4), path);
            CHECK(remove(csv) == 0);
        }
    }

    /* argument errors are caught before the target is touched */
    char path[4096];
    snprintf(path, sizeof path, "%s", cft_temp_path(".ply"));
    iot_write_text(path, "old content");
    cf_field bad = {"x", CF_FIELD_VERTEX, vf};
    CHECK_STATUS(cf_write_mesh_file(ctx, path, m, NULL, &bad, 1), CF_ERR_INVALID_ARG);
    bad.name = "has space";
    CHECK_STATUS(cf_write_mesh_file(ctx, path, m, NULL, &bad, 1), CF_ERR_INVALID_ARG);
    cf_field twice[2] = {field, field};
    CHECK_STATUS(cf_write_mesh_file(ctx, path, m, NULL, twice, 2), CF_ERR_INVALID_ARG);
    double nan_pos[3 * IOT_NV];
    memcpy(nan_pos, cf_mesh_positions(m), sizeof nan_pos);
    nan_pos[7] = NAN;
    CHECK_STATUS(cf_write_mesh_file(ctx, path, m, nan_pos, NULL, 0), CF_ERR_NONFINITE);
    CHECK(strstr(cf_context_message(ctx), "vertex 2 has a non-finite coordinate") != NULL);
    CHECK_STATUS(cf_write_mesh_file(ctx, "out.stl", m, NULL, NULL, 0), CF_ERR_UNSUPPORTED);
    char *text = iot_read(path, NULL);
    CHECK(text && strcmp(text, "old content") == 0);
    free(text);
    CHECK(iot_temp_files(path) == 0);
    remove(path);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_abort(void)
{
    cf_context *ctx = cft_context();
    char path[4096];
    snprintf(path, sizeof path, "%s", cft_temp_path(".txt"));
    iot_write_text(path, "old");
    cfi_atomic_file f;
    CHECK_OK(ctx, cfi_atomic_open(ctx, path, &f));
    CHECK(iot_temp_files(path) == 1); /* the temporary file sits next to the target */
    fputs("new", f.fp);
    cfi_atomic_abort(ctx, &f);
    cfi_atomic_abort(ctx, &f); /* second abort is a no-op */
    CHECK(iot_temp_files(path) == 0);
    char *text = iot_read(path, NULL);
    CHECK(text && strcmp(text, "old") == 0);
    free(text);
    remove(path);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_text_file);
    CFT_RUN(test_failures_leave_target_untouched);
    CFT_RUN(test_abort);
    return cft_finish();
}
