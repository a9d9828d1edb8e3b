/*
 * Atomic file output: temporary file in the same directory, fflush + fsync,
 * rename over the target (POSIX guarantees rename within one file system is
 * atomic). Also the public cf_write_text_file_atomic.
 */
#define _POSIX_C_SOURCE 200809L

#include "io/atomic_file.h"
#include "curvflow/io.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static void release(cf_context *ctx, cfi_atomic_file *f)
{
    cfi_free(ctx, f->path, f->path_bytes);
    cfi_free(ctx, f->tmp_path, f->tmp_bytes);
    f->path = NULL;
    f->tmp_path = NULL;
    f->fp = NULL;
}

cf_status cfi_atomic_open(cf_context *ctx, const char *path, cfi_atomic_file *f)
{
    if (!f) return cfi_error(ctx, CF_ERR_INVALID_ARG, "atomic file is NULL");
    memset(f, 0, sizeof *f);
    if (!path || !*path) return cfi_error(ctx, CF_ERR_INVALID_ARG, "output path is empty");
    size_t len = strlen(path);
    if (path[len - 1] == '/') return cfi_error(ctx, CF_ERR_IO, "%s: cannot write: path names a directory", path);
    f->path_bytes = len + 1;
    f->path = cfi_malloc(ctx, f->path_bytes);
    /* ".<base>.tmp-<pid>-<n>" next to the target: same directory, so the
     * rename never crosses file systems; hidden, so a listing stays clean. */
    f->tmp_bytes = len + 64;
    f->tmp_path = cfi_malloc(ctx, f->tmp_bytes);
    if (!f->path || !f->tmp_path) {
        release(ctx, f);
        return cfi_error(ctx, CF_ERR_NOMEM, "%s: out of memory", path);
    }
    memcpy(f->path, path, len + 1);
    const char *slash = strrchr(path, '/');
    size_t dir_len = slash ? (size_t)(slash - path) + 1 : 0;
    mode_t mode = 0666;
    struct stat st;
    bool keep_mode = stat(path, &st) == 0 && S_ISREG(st.st_mode);
    if (keep_mode) mode = st.st_mode & 07777;
    /* A few names in case an old temporary file of the same pid exists. */
    unsigned long salt = (unsigned long)(cfi_now_seconds() * 1e6);
    int fd = -1, err = 0;
    for (int attempt = 0; attempt < 16 && fd < 0; ++attempt) {
        snprintf(f->tmp_path, f->tmp_bytes, "%.*s.%s.tmp-%ld-%lu", (int)dir_len, path, path + dir_len,
                 (long)getpid(), (salt + (unsigned long)attempt) % 1000000000ul);
        fd = open(f->tmp_path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
        err = errno;
        if (fd < 0 && err != EEXIST) break;
    }
    if (fd < 0) {
        release(ctx, f);
        return cfi_error(ctx, CF_ERR_IO, "%s: cannot write: %s", path, strerror(err));
    }
    /* open() applies the umask; an existing target keeps its own mode. */
    if (keep_mode) (void)fchmod(fd, mode);
    f->fp = fdopen(fd, "wb");
    if (!f->fp) {
        err = errno;
        close(fd);
        unlink(f->tmp_path);
        release(ctx, f);
        return cfi_error(ctx, CF_ERR_IO, "%s: cannot write: %s", path, strerror(err));
    }
    return CF_OK;
}

void cfi_atomic_abort(cf_context *ctx, cfi_atomic_file *f)
{
    if (!f || !f->fp) return;
    fclose(f->fp);
    unlink(f->tmp_path);
    release(ctx, f);
}

cf_status cfi_atomic_commit(cf_context *ctx, cfi_atomic_file *f)
{
    if (!f || !f->fp) return cfi_error(ctx, CF_ERR_INVALID_ARG, "atomic file is not open");
    int err = 0;
    if (ferror(f->fp)) err = errno ? errno : EIO;
    if (!err && fflush(f->fp) != 0) err = errno;
    if (!err && fsync(fileno(f->fp)) != 0) err = errno;
    if (fclose(f->fp) != 0 && !err) err = errno;
    f->fp = NULL;
    if (!err && rename(f->tmp_path, f->path) != 0) err = errno;
    if (err) {
        unlink(f->tmp_path);
        cf_status st = cfi_error(ctx, CF_ERR_IO, "%s: cannot write: %s", f->path, strerror(err));
        release(ctx, f);
        return st;
    }
    /* Make the rename itself durable (best effort: some file systems refuse
     * fsync on directories). */
    const char *slash = strrchr(f->path, '/');
    if (slash) f->path[slash - f->path + (slash == f->path)] = '\0';
    int dfd = open(slash ? f->path : ".", O_RDONLY | O_CLOEXEC);
    if (dfd >= 0) {
        (void)fsync(dfd);
        close(dfd);
    }
    release(ctx, f);
    return CF_OK;
}

cf_status cf_write_text_file_atomic(cf_context *ctx, const char *path, const char *text, size_t size)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!path || (!text && size > 0))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_write_text_file_atomic: path or text is NULL");
    cfi_atomic_file f;
    cf_status st = cfi_atomic_open(ctx, path, &f);
    if (st != CF_OK) return st;
    if (size > 0 && fwrite(text, 1, size, f.fp) != size) {
        int err = errno;
        cfi_atomic_abort(ctx, &f);
        return cfi_error(ctx, CF_ERR_IO, "%s: cannot write: %s", path, strerror(err));
    }
    return cfi_atomic_commit(ctx, &f);
}
