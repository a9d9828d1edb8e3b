/*
 * Atomic file output: temporary file in the same directory as the target,
 * fflush + fsync, rename over the target (POSIX guarantees rename within one
 * file system is atomic). Also the public cf_write_text_file_atomic, the
 * streaming cf_atomic_writer and the clean-up of temporary files after a
 * signal (cf_atomic_remove_pending) or a killed run (cf_atomic_remove_stale).
 */
#define _POSIX_C_SOURCE 200809L

#include "io/atomic_file.h"
#include "curvflow/io.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

/* ---- registry of live temporary files ----------------------------------
 * A signal handler has no context to look in, and a temporary file belongs
 * to the process, not to a context: this fixed table is the library's one
 * piece of process-wide mutable state. A slot is claimed with a
 * compare-and-swap (writers may run in several threads), filled, then
 * published; the handler only reads published slots and calls unlink, so
 * it stays async-signal-safe (lock-free atomics, no allocation, no stdio).
 * With every slot busy a write still works, it is only not removed on a
 * signal (16 simultaneous atomic writes in one process are not expected). */
_Static_assert(ATOMIC_INT_LOCK_FREE == 2, "the signal handler needs lock-free atomic int");
enum { TEMP_SLOTS = 16, TEMP_PATH_MAX = 4096 };
enum { SLOT_FREE = 0, SLOT_FILLING = 1, SLOT_LIVE = 2 };
static struct {
    atomic_int state;
    pid_t owner; /* a forked child inherits the table but not the files' ownership */
    char path[TEMP_PATH_MAX];
} temp_slots[TEMP_SLOTS];

static int registry_add(const char *tmp_path)
{
    size_t n = strlen(tmp_path);
    if (n >= TEMP_PATH_MAX) return -1;
    for (int i = 0; i < TEMP_SLOTS; ++i) {
        int expected = SLOT_FREE;
        if (atomic_compare_exchange_strong(&temp_slots[i].state, &expected, SLOT_FILLING)) {
            memcpy(temp_slots[i].path, tmp_path, n + 1);
            temp_slots[i].owner = getpid();
            atomic_store(&temp_slots[i].state, SLOT_LIVE);
            return i;
        }
    }
    return -1;
}

static void registry_remove(int slot)
{
    if (slot >= 0 && slot < TEMP_SLOTS) atomic_store(&temp_slots[slot].state, SLOT_FREE);
}

void cf_atomic_remove_pending(void)
{
    pid_t self = getpid(); /* async-signal-safe, as are unlink and lock-free atomics */
    for (int i = 0; i < TEMP_SLOTS; ++i)
        if (atomic_load(&temp_slots[i].state) == SLOT_LIVE && temp_slots[i].owner == self)
            (void)unlink(temp_slots[i].path);
}

/* ---- paths ----------------------------------------------------------------- */

/* Length of the directory part of `path` including its last '/' (0 when
 * the path has no '/'). */
static size_t dir_length(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? (size_t)(slash - path) + 1 : 0;
}

/* The file that writing `path` should replace: `path` with symbolic links
 * followed (a relative link target is taken from the link's directory), so
 * that the rename writes through a link instead of replacing it by a
 * regular file. A dangling link gives the missing file it points to (the
 * write creates it). Allocated through the context (*bytes for cfi_free).
 * CF_ERR_IO for a cycle of links or an over-long result, CF_ERR_NOMEM. */
static cf_status resolve_target(cf_context *ctx, const char *path, char **out, size_t *bytes)
{
    char cur[PATH_MAX], link[PATH_MAX];
    size_t n = strlen(path);
    *out = NULL;
    if (n >= sizeof cur) return cfi_error(ctx, CF_ERR_IO, "%s: cannot write: %s", path, strerror(ENAMETOOLONG));
    memcpy(cur, path, n + 1);
    for (int hops = 0;; ++hops) {
        struct stat sb;
        if (lstat(cur, &sb) != 0 || !S_ISLNK(sb.st_mode)) break;
        if (hops == 40) return cfi_error(ctx, CF_ERR_IO, "%s: cannot write: %s", path, strerror(ELOOP));
        ssize_t len = readlink(cur, link, sizeof link - 1);
        if (len < 0) break; /* vanished meanwhile: write to cur */
        link[len] = '\0';
        size_t d = link[0] == '/' ? 0 : dir_length(cur);
        if (d + (size_t)len >= sizeof cur)
            return cfi_error(ctx, CF_ERR_IO, "%s: cannot write: %s", path, strerror(ENAMETOOLONG));
        memcpy(cur + d, link, (size_t)len + 1);
    }
    n = strlen(cur);
    *bytes = n + 1;
    *out = cfi_malloc(ctx, *bytes);
    if (!*out) return cfi_error(ctx, CF_ERR_NOMEM, "%s: out of memory", path);
    memcpy(*out, cur, n + 1);
    return CF_OK;
}

/* ---- one atomic file ---------------------------------------------------- */

static void release(cf_context *ctx, cfi_atomic_file *f)
{
    registry_remove(f->slot);
    f->slot = -1;
    cfi_free(ctx, f->path, f->path_bytes);
    cfi_free(ctx, f->target, f->target_bytes);
    cfi_free(ctx, f->tmp_path, f->tmp_bytes);
    f->path = NULL;
    f->target = NULL;
    f->tmp_path = NULL;
    f->fp = NULL;
}

cf_status cfi_atomic_open(cf_context *ctx, const char *path, cfi_atomic_file *f)
{
    if (!f) return cfi_error(ctx, CF_ERR_INVALID_ARG, "atomic file is NULL");
    memset(f, 0, sizeof *f);
    f->slot = -1;
    if (!path || !*path) return cfi_error(ctx, CF_ERR_INVALID_ARG, "output path is empty");
    size_t len = strlen(path);
    if (path[len - 1] == '/') return cfi_error(ctx, CF_ERR_IO, "%s: cannot write: path names a directory", path);
    f->path_bytes = len + 1;
    f->path = cfi_malloc(ctx, f->path_bytes);
    if (!f->path) {
        release(ctx, f);
        return cfi_error(ctx, CF_ERR_NOMEM, "%s: out of memory", path);
    }
    memcpy(f->path, path, len + 1);
    cf_status st = resolve_target(ctx, path, &f->target, &f->target_bytes);
    if (st != CF_OK) {
        release(ctx, f);
        return st;
    }
    /* ".<base>.tmp-<pid>-<n>" next to the target: same directory, so the
     * rename never crosses file systems; hidden, so a listing stays clean;
     * the pid lets cf_atomic_remove_stale tell whose file it is. */
    const char *target = f->target;
    size_t dir_len = dir_length(target);
    f->tmp_bytes = strlen(target) + 64;
    f->tmp_path = cfi_malloc(ctx, f->tmp_bytes);
    if (!f->tmp_path) {
        release(ctx, f);
        return cfi_error(ctx, CF_ERR_NOMEM, "%s: out of memory", path);
    }
    mode_t mode = 0666;
    struct stat sb;
    bool keep_mode = stat(target, &sb) == 0 && S_ISREG(sb.st_mode);
    if (keep_mode) mode = sb.st_mode & 07777;
    /* A few names in case an old temporary file of the same pid exists. The
     * name is registered before the file is created, so a signal at any
     * point finds it (unlinking a name not created yet is harmless). */
    unsigned long salt = (unsigned long)(cfi_now_seconds() * 1e6);
    int fd = -1, err = 0;
    for (int attempt = 0; attempt < 16 && fd < 0; ++attempt) {
        snprintf(f->tmp_path, f->tmp_bytes, "%.*s.%s.tmp-%ld-%lu", (int)dir_len, target, target + dir_len,
                 (long)getpid(), (salt + (unsigned long)attempt) % 1000000000ul);
        f->slot = registry_add(f->tmp_path);
        fd = open(f->tmp_path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
        err = errno;
        if (fd < 0) {
            registry_remove(f->slot);
            f->slot = -1;
            if (err != EEXIST) break;
        }
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
    if (!err && rename(f->tmp_path, f->target) != 0) err = errno;
    if (err) {
        unlink(f->tmp_path);
        cf_status st = cfi_error(ctx, CF_ERR_IO, "%s: cannot write: %s", f->path, strerror(err));
        release(ctx, f);
        return st;
    }
    /* The temporary name is gone: a signal from here on must not look for it. */
    registry_remove(f->slot);
    f->slot = -1;
    /* Make the rename itself durable (best effort: some file systems refuse
     * fsync on directories). */
    char *slash = strrchr(f->target, '/');
    if (slash) slash[slash == f->target] = '\0';
    int dfd = open(slash ? f->target : ".", O_RDONLY | O_CLOEXEC);
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

/* ---- streaming writer (public) ------------------------------------------ */

struct cf_atomic_writer {
    cf_context *ctx;
    cfi_atomic_file file;
};

cf_status cf_atomic_writer_open(cf_context *ctx, const char *path, cf_atomic_writer **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_atomic_writer_open: out is NULL");
    *out = NULL;
    cf_atomic_writer *w = cfi_malloc(ctx, sizeof *w);
    if (!w) return cfi_error(ctx, CF_ERR_NOMEM, "%s: out of memory", path ? path : "(null)");
    w->ctx = ctx;
    cf_status st = cfi_atomic_open(ctx, path, &w->file);
    if (st != CF_OK) {
        cfi_free(ctx, w, sizeof *w);
        return st;
    }
    *out = w;
    return CF_OK;
}

FILE *cf_atomic_writer_stream(cf_atomic_writer *writer) { return writer ? writer->file.fp : NULL; }

cf_status cf_atomic_writer_commit(cf_atomic_writer **writer)
{
    if (!writer || !*writer) return CF_ERR_INVALID_ARG;
    cf_atomic_writer *w = *writer;
    cf_context *ctx = w->ctx;
    cf_status st = cfi_atomic_commit(ctx, &w->file);
    cfi_free(ctx, w, sizeof *w);
    *writer = NULL;
    return st;
}

void cf_atomic_writer_abort(cf_atomic_writer **writer)
{
    if (!writer || !*writer) return;
    cf_atomic_writer *w = *writer;
    cf_context *ctx = w->ctx;
    cfi_atomic_abort(ctx, &w->file);
    cfi_free(ctx, w, sizeof *w);
    *writer = NULL;
}

/* ---- stale temporary files ---------------------------------------------- */

/* The pid of `name` if it is ".<base>.tmp-<pid>-<digits>", else 0. */
static long temp_owner(const char *name, const char *base)
{
    size_t nb = strlen(base);
    if (name[0] != '.' || strncmp(name + 1, base, nb) != 0 || strncmp(name + 1 + nb, ".tmp-", 5) != 0) return 0;
    const char *p = name + 1 + nb + 5;
    long pid = 0;
    const char *digits = p;
    while (*p >= '0' && *p <= '9') {
        if (pid > (long)INT_MAX / 10) return 0;
        pid = 10 * pid + (*p++ - '0');
    }
    if (p == digits || *p++ != '-' || !(*p >= '0' && *p <= '9')) return 0;
    while (*p >= '0' && *p <= '9') ++p;
    return *p == '\0' ? pid : 0;
}

cf_status cf_atomic_remove_stale(cf_context *ctx, const char *path, int32_t *removed)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (removed) *removed = 0;
    if (!path || !*path) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_atomic_remove_stale: path is empty");
    char *target = NULL;
    size_t target_bytes = 0;
    cf_status st = resolve_target(ctx, path, &target, &target_bytes);
    if (st != CF_OK) return st;
    size_t dir_len = dir_length(target);
    const char *base = target + dir_len;
    char dir[PATH_MAX];
    if (dir_len == 0) {
        strcpy(dir, ".");
    } else {
        memcpy(dir, target, dir_len);
        dir[dir_len] = '\0';
    }
    /* best effort: a folder that cannot be listed has nothing we may remove */
    DIR *d = *base ? opendir(dir) : NULL;
    int32_t count = 0;
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL) {
        long pid = temp_owner(e->d_name, base);
        if (pid <= 0 || pid == (long)getpid()) continue;
        /* kill(pid, 0): ESRCH = no such process; EPERM = alive (someone
         * else's): keep it. A recycled pid keeps a stale file for now. */
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue;
        char file[PATH_MAX];
        if (snprintf(file, sizeof file, "%.*s%s", (int)dir_len, target, e->d_name) >= (int)sizeof file) continue;
        if (unlink(file) == 0) ++count;
    }
    if (d) closedir(d);
    cfi_free(ctx, target, target_bytes);
    if (removed) *removed = count;
    return CF_OK;
}
