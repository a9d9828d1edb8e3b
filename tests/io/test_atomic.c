/* Atomic output: success replaces the target, every failure (missing
 * directory, directory as target, failed allocation at any point, bad
 * arguments) leaves an existing target byte-for-byte untouched and no
 * temporary file behind; a symbolic link is written through; a signal
 * removes the temporary files; stale ones of ended processes are found. */
#define _POSIX_C_SOURCE 200809L
#include "io/atomic_file.h"
#include "io_test_util.h"

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
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

/* A symbolic link target is written through: the link stays a link and
 * the file it names (relative to the link's folder, through a chain, or
 * not there yet) gets the content. */
static void test_symlink_written_through(void)
{
    cf_context *ctx = cft_context();
    char real[4096], link1[4096], link2[4096], dangling[4096], missing[4096];
    snprintf(real, sizeof real, "%s", cft_temp_path(".txt"));
    snprintf(link1, sizeof link1, "%s", cft_temp_path(".txt"));
    snprintf(link2, sizeof link2, "%s", cft_temp_path(".txt"));
    snprintf(dangling, sizeof dangling, "%s", cft_temp_path(".txt"));
    snprintf(missing, sizeof missing, "%s", cft_temp_path(".txt"));
    iot_write_text(real, "old");
    const char *base = strrchr(real, '/') + 1; /* relative link: resolved from the link's folder */
    CHECK(symlink(base, link1) == 0);
    CHECK(symlink(link1, link2) == 0); /* a chain */
    CHECK_OK(ctx, cf_write_text_file_atomic(ctx, link2, "new", 3));
    struct stat sb;
    CHECK(lstat(link1, &sb) == 0 && S_ISLNK(sb.st_mode));
    CHECK(lstat(link2, &sb) == 0 && S_ISLNK(sb.st_mode));
    char *text = iot_read(real, NULL);
    CHECK(text && strcmp(text, "new") == 0);
    free(text);
    CHECK(iot_temp_files(real) == 0);
    CHECK(symlink(missing, dangling) == 0);
    CHECK_OK(ctx, cf_write_text_file_atomic(ctx, dangling, "made", 4));
    CHECK(lstat(dangling, &sb) == 0 && S_ISLNK(sb.st_mode));
    text = iot_read(missing, NULL);
    CHECK(text && strcmp(text, "made") == 0);
    free(text);
    /* a cycle of links is an I/O error naming the path, not a hang */
    char a[4096], b[4096];
    snprintf(a, sizeof a, "%s", cft_temp_path(".txt"));
    snprintf(b, sizeof b, "%s", cft_temp_path(".txt"));
    CHECK(symlink(b, a) == 0 && symlink(a, b) == 0);
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    CHECK_STATUS(cf_write_text_file_atomic(ctx, a, "x", 1), CF_ERR_IO);
    CHECK(strstr(cf_context_message(ctx), "Too many levels of symbolic links") != NULL);
    const char *all[] = {real, link1, link2, dangling, missing, a, b};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; ++i) unlink(all[i]);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The streaming writer: nothing at the target until commit; abort leaves
 * an existing target as it was. */
static void test_streaming_writer(void)
{
    cf_context *ctx = cft_context();
    char path[4096];
    snprintf(path, sizeof path, "%s", cft_temp_path(".jsonl"));
    cf_atomic_writer *w = NULL;
    CHECK_OK(ctx, cf_atomic_writer_open(ctx, path, &w));
    CHECK(w && cf_atomic_writer_stream(w));
    fputs("{\"a\": 1}\n", cf_atomic_writer_stream(w));
    fflush(cf_atomic_writer_stream(w));
    CHECK(access(path, F_OK) != 0 && iot_temp_files(path) == 1);
    CHECK_OK(ctx, cf_atomic_writer_commit(&w));
    CHECK(w == NULL && iot_temp_files(path) == 0);
    char *text = iot_read(path, NULL);
    CHECK(text && strcmp(text, "{\"a\": 1}\n") == 0);
    free(text);
    CHECK_OK(ctx, cf_atomic_writer_open(ctx, path, &w));
    fputs("half", cf_atomic_writer_stream(w));
    cf_atomic_writer_abort(&w);
    cf_atomic_writer_abort(&w); /* NULL: no-op */
    CHECK(w == NULL && iot_temp_files(path) == 0);
    text = iot_read(path, NULL);
    CHECK(text && strcmp(text, "{\"a\": 1}\n") == 0);
    free(text);
    remove(path);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void on_signal(int sig)
{
    cf_atomic_remove_pending();
    signal(sig, SIG_DFL);
    raise(sig);
}

/* A process killed by SIGINT / SIGTERM / SIGHUP while two atomic writes are
 * open leaves neither temporary file, and the old targets as they were
 * (a real signal, delivered to a child process). */
static void test_signal_removes_pending(void)
{
    const int sigs[] = {SIGINT, SIGTERM, SIGHUP};
    for (int k = 0; k < 3; ++k) {
        char p1[4096], p2[4096];
        snprintf(p1, sizeof p1, "%s", cft_temp_path(".obj"));
        snprintf(p2, sizeof p2, "%s", cft_temp_path(".jsonl"));
        iot_write_text(p1, "old");
        fflush(NULL);
        pid_t pid = fork();
        CHECK(pid >= 0);
        if (pid == 0) {
            cf_context *ctx = NULL;
            if (cf_context_create(&ctx) != CF_OK) _exit(10);
            cfi_atomic_file f1, f2;
            if (cfi_atomic_open(ctx, p1, &f1) != CF_OK || cfi_atomic_open(ctx, p2, &f2) != CF_OK) _exit(11);
            fputs("partial", f1.fp);
            fflush(f1.fp);
            if (iot_temp_files(p1) != 1 || iot_temp_files(p2) != 1) _exit(12);
            signal(sigs[k], on_signal);
            kill(getpid(), sigs[k]);
            _exit(13); /* not reached: the signal ends the process */
        }
        int status = 0;
        CHECK(waitpid(pid, &status, 0) == pid);
        CHECK(WIFSIGNALED(status) && WTERMSIG(status) == sigs[k]);
        if (WIFEXITED(status)) fprintf(stderr, "child exited with %d\n", WEXITSTATUS(status));
        CHECK(iot_temp_files(p1) == 0 && iot_temp_files(p2) == 0);
        char *text = iot_read(p1, NULL);
        CHECK(text && strcmp(text, "old") == 0);
        free(text);
        CHECK(access(p2, F_OK) != 0);
        remove(p1);
    }
}

/* A forked child inherits the registry but not the files: its clean-up
 * (e.g. in its own signal handler) leaves the parent's write alone. */
static void test_fork_keeps_parent_files(void)
{
    cf_context *ctx = cft_context();
    char path[4096];
    snprintf(path, sizeof path, "%s", cft_temp_path(".ply"));
    cfi_atomic_file f;
    CHECK_OK(ctx, cfi_atomic_open(ctx, path, &f));
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        cf_atomic_remove_pending();
        _exit(iot_temp_files(path) == 1 ? 0 : 1);
    }
    int status = 0;
    CHECK(pid > 0 && waitpid(pid, &status, 0) == pid && WIFEXITED(status) && WEXITSTATUS(status) == 0);
    CHECK(iot_temp_files(path) == 1);
    CHECK_OK(ctx, cfi_atomic_commit(ctx, &f));
    CHECK(access(path, F_OK) == 0 && iot_temp_files(path) == 0);
    remove(path);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Temporary files of ended processes next to a target are removed; those
 * of running processes (this one, its parent) and of other targets stay. */
static void test_remove_stale(void)
{
    cf_context *ctx = cft_context();
    char path[4096];
    snprintf(path, sizeof path, "%s", cft_temp_path(".ply"));
    const char *slash = strrchr(path, '/');
    int dir_len = (int)(slash - path) + 1;
    const char *base = slash + 1;
    pid_t dead = fork();
    if (dead == 0) _exit(0);
    CHECK(dead > 0 && waitpid(dead, NULL, 0) == dead); /* reaped: no such process any more */
    char stale[4200], mine[4200], parent[4200], other[4200], odd[4200];
    snprintf(stale, sizeof stale, "%.*s.%s.tmp-%ld-123", dir_len, path, base, (long)dead);
    snprintf(mine, sizeof mine, "%.*s.%s.tmp-%ld-5", dir_len, path, base, (long)getpid());
    snprintf(parent, sizeof parent, "%.*s.%s.tmp-%ld-5", dir_len, path, base, (long)getppid());
    snprintf(other, sizeof other, "%.*s.other%s.tmp-%ld-7", dir_len, path, base, (long)dead);
    snprintf(odd, sizeof odd, "%.*s.%s.tmp-%ldx-7", dir_len, path, base, (long)dead); /* not our name pattern */
    const char *all[] = {stale, mine, parent, other, odd};
    for (int i = 0; i < 5; ++i) iot_write_text(all[i], "t");
    int32_t removed = -1;
    CHECK_OK(ctx, cf_atomic_remove_stale(ctx, path, &removed));
    CHECK(removed == 1);
    CHECK(access(stale, F_OK) != 0);
    for (int i = 1; i < 5; ++i) CHECK(access(all[i], F_OK) == 0);
    CHECK_OK(ctx, cf_atomic_remove_stale(ctx, path, NULL)); /* nothing left to remove */
    for (int i = 1; i < 5; ++i) remove(all[i]);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_text_file);
    CFT_RUN(test_failures_leave_target_untouched);
    CFT_RUN(test_abort);
    CFT_RUN(test_symlink_written_through);
    CFT_RUN(test_streaming_writer);
    CFT_RUN(test_signal_removes_pending);
    CFT_RUN(test_fork_keeps_parent_files);
    CFT_RUN(test_remove_stale);
    return cft_finish();
}
