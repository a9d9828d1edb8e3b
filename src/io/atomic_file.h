/*
 * Atomic output for every writer of the library: the content goes to a
 * temporary file in the target's directory; commit flushes, fsyncs and
 * renames it over the target (so readers see either the old or the new
 * file, never a partial one); abort removes it and leaves the target
 * untouched.
 *
 *   cfi_atomic_file f;
 *   if ((st = cfi_atomic_open(ctx, path, &f)) != CF_OK) return st;
 *   fprintf(f.fp, ...);
 *   if (failed) { cfi_atomic_abort(ctx, &f); return st; }
 *   return cfi_atomic_commit(ctx, &f);   // also cleans up on failure
 *
 * A target that is a symbolic link is written through: the temporary file
 * sits next to the link's final target and the rename replaces that file,
 * so the link stays a link. The temporary file is named
 * ".<target name>.tmp-<pid>-<n>"; while it exists its path is in a
 * process-wide registry that cf_atomic_remove_pending() (public, for
 * signal handlers) empties, and cf_atomic_remove_stale() removes such files
 * left by processes that no longer run (curvflow/io.h).
 */
#ifndef CF_IO_ATOMIC_FILE_H
#define CF_IO_ATOMIC_FILE_H

#include "core/core.h"

#include <stdio.h>

typedef struct cfi_atomic_file {
    FILE *fp;             /* write here; NULL once committed or aborted */
    char *path;           /* copy of the path as given (messages) */
    size_t path_bytes;
    char *target;         /* the file the rename replaces: path with symbolic links followed */
    size_t target_bytes;
    char *tmp_path;       /* the temporary file */
    size_t tmp_bytes;
    int slot;             /* registry slot of tmp_path, -1 if not registered */
} cfi_atomic_file;

/* Creates the temporary file (mode 0666 minus umask, or the existing
 * target's mode). CF_ERR_IO naming the path and the reason (also for a
 * cycle of symbolic links), CF_ERR_NOMEM. On failure nothing is left behind
 * and f->fp is NULL. */
cf_status cfi_atomic_open(cf_context *ctx, const char *path, cfi_atomic_file *f);

/* Checks for write errors, flushes, fsyncs, closes and renames over the
 * target. On failure the temporary file is removed and CF_ERR_IO names the
 * path and the reason. Always releases f. */
cf_status cfi_atomic_commit(cf_context *ctx, cfi_atomic_file *f);

/* Closes and removes the temporary file; the target is untouched. Accepts
 * a file already committed or aborted (no-op). */
void cfi_atomic_abort(cf_context *ctx, cfi_atomic_file *f);

#endif /* CF_IO_ATOMIC_FILE_H */
