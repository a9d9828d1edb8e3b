/*
 * Running the built `curvflow` tool from a test: one folder per test run
 * under the build tree, the command's exit status, stdout and stderr.
 *
 *   int main(void) {
 *       if (cft_cli_setup("cli")) return 1;
 *       CFT_RUN(test_flow);              // CHECK_RUN("flow a.obj -o b.obj ...", 0);
 *       return cft_cli_finish();         // removes the folder if every check passed
 *   }
 */
#ifndef CF_TESTS_CLI_TEST_H
#define CF_TESTS_CLI_TEST_H

#include "test.h"

#include <stddef.h>
#include <stdint.h>

extern char cft_dir[1024];       /* this run's folder (cft_cli_setup) */
extern char cft_out[1 << 16];    /* stdout of the last command, NUL-terminated (truncated) */
extern char cft_err[1 << 16];    /* stderr of the last command */
/* Environment assignments put before every command ("" by default), e.g.
 * "OMP_THREAD_LIMIT=1". */
extern const char *cft_cli_env;

/* Creates CF_TEST_BINARY_DIR/<name>_<pid>; 0, or 1 after printing why not. */
int cft_cli_setup(const char *name);
/* cft_finish(), and the folder's files removed (not subfolders) when every
 * check passed. */
int cft_cli_finish(void);
/* "<cft_dir>/<name>" in a static buffer (valid until the next call). */
const char *cft_in_dir(const char *name);
/* Reads at most size - 1 bytes of a file, NUL-terminated ("" if unreadable). */
void cft_read_small(const char *path, char *buf, size_t size);
/* Runs a shell command in cft_dir with stdout / stderr captured into
 * cft_out / cft_err; the exit status, or -1 if it did not exit. */
int cft_shell(const char *command);
/* cft_shell of "curvflow ARGS" (the tool of this build). */
int cft_run(const char *args);
/* 1 if <cft_dir>/<name> exists. */
int cft_exists(const char *name);
/* 1 if the last command's stderr contains `part` (always for NULL). */
int cft_err_has(const char *part);
/* Removes the files of a folder and the folder (one level). */
void cft_remove_dir(const char *path);
/* Positions of the mesh file <cft_dir>/<name> (malloc'd, 3 nv; *nv set),
 * NULL if it does not load. */
double *cft_load_positions(const char *name, int32_t *nv);

/* Runs "curvflow ARGS" and checks its exit status (stdout and stderr in the
 * failure message). */
#define CHECK_RUN(args, expected)                                                                          \
    do {                                                                                                   \
        int rc_ = cft_run(args);                                                                           \
        ++cft_checks;                                                                                      \
        if (rc_ != (expected))                                                                             \
            cft_fail(__FILE__, __LINE__, "curvflow %s: exit %d, expected %d\nstdout: %s\nstderr: %s", args, \
                     rc_, (expected), cft_out, cft_err);                                                   \
    } while (0)

/* Runs "curvflow ARGS" and checks the exit status and a part of stderr
 * (NULL: any). */
#define EXPECT(args, code, part)                                                                                  \
    do {                                                                                                          \
        int rc_ = cft_run(args);                                                                                  \
        const char *part_ = (part);                                                                               \
        ++cft_checks;                                                                                             \
        if (rc_ != (code) || !cft_err_has(part_))                                                                 \
            cft_fail(__FILE__, __LINE__, "curvflow %s: exit %d (expected %d), stderr '%s' (expected '%s')", args, \
                     rc_, (code), cft_err, part_ ? part_ : "");                                                  \
    } while (0)

#endif /* CF_TESTS_CLI_TEST_H */
