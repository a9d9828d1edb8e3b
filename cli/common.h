/*
 * Helpers shared by the subcommands: error reporting in the tool's format
 * ("curvflow: <file>: <message>"), exit codes from statuses, number and
 * --param key=value parsing, mesh loading, the per-step progress line / bar
 * and the JSONL step log.
 */
#ifndef CF_CLI_COMMON_H
#define CF_CLI_COMMON_H

#include "cli.h"
#include "curvflow/curvflow.h"
#include "curvflow/flow.h"
#include "curvflow/mesh.h"

#include <stdbool.h>
#include <stdio.h>

/* Exit code for a library status: 0 ok, 1 invalid argument (usage), 3
 * numerical failure / cancelled / out of memory, 2 anything about the input
 * (file, format, mesh validity, unsupported request). */
int cli_exit_code(cf_status status);

/* Prints "curvflow: <what>: <message>" to stderr; `what` may be NULL, and is
 * left out when the message already starts with it (I/O messages name the
 * file themselves). Returns cli_exit_code(status). */
int cli_fail(cf_context *ctx, const char *what, cf_status status);

/* Prints "curvflow: <fmt...>" and a hint to --help to stderr; returns 1. */
int cli_usage_error(const char *command, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Reports a failed getopt_long() in the tool's one-line format instead of
 * getopt's own "<cmd>: unrecognized option" line. Use with `opterr = 0` and
 * an optstring starting with ':' so that a missing argument returns ':'.
 * `c` is getopt_long's return value ('?' or ':'). Returns 1 (usage). */
int cli_option_error(const char *command, int c, char **argv);

/* Strict number parsing (whole string, finite, in range); print a usage
 * error naming the option on failure and return false. */
bool cli_parse_int(const char *command, const char *option, const char *text, long long min_value,
                   long long max_value, long long *out);
bool cli_parse_double(const char *command, const char *option, const char *text, double *out);

/* A context with warnings from the library forwarded to stderr. */
cf_context *cli_context(bool verbose);

/* Loads a validated mesh; on failure prints the message and returns the
 * exit code (2), else 0. */
int cli_load_mesh(cf_context *ctx, const char *path, cf_mesh **out);

/* Checks before a long run that OUT can be written: its directory exists and
 * is writable, OUT is not a directory, and (mesh = true) its extension names a
 * mesh format. Prints "curvflow: OUT: ..." and returns 2 if not, else 0. The
 * write itself stays atomic; this only saves a run whose result could not be
 * kept. */
int cli_check_output(cf_context *ctx, const char *path, bool mesh);

/* After writing a flow's result: if those positions would not pass the mesh
 * check (a triangle degenerated to zero area), says so on stderr, so that
 * the failure does not first show when the file is loaded again. */
void cli_warn_if_unreadable(cf_context *ctx, const cf_mesh *mesh, const double *positions, const char *output);

/* Creates the directory (one level) if it does not exist. Returns 0 or 2
 * (with a message). */
int cli_make_dir(const char *path);

/* Progress reporting for a flow run: one line per step on stderr (or a bar
 * redrawn in place when stderr is a terminal) and one JSON object per step
 * in the log file. Use as the flow's progress callback. */
typedef struct cli_progress {
    const char *method;     /* method name for the status line */
    int64_t total_steps;
    bool quiet;             /* no status lines */
    bool tty;               /* draw a bar instead of lines */
    FILE *log;              /* JSONL log or NULL */
    const char *log_path;
    bool log_failed;
    double start_seconds;
    bool bar_drawn;
} cli_progress;

void cli_progress_init(cli_progress *p, const char *method, int64_t total_steps, bool quiet);
/* Opens the log file (truncates); returns 0 or 2 with a message. */
int cli_progress_open_log(cli_progress *p, const char *path);
/* Writes the JSON object of one step (also for the initial state, iteration 0). */
void cli_progress_log(cli_progress *p, const cf_flow_info *info);
/* cf_progress_fn: prints and logs the step; never cancels. */
int cli_progress_callback(void *user, const cf_flow_info *info);
/* Ends the bar line; closes the log. Returns 0 or 2 if the log could not be written. */
int cli_progress_finish(cli_progress *p);

/* Runs `steps` steps of a created flow with the progress reporter (the
 * JSONL log opened at log_path when it is not NULL) and writes the reached
 * positions to `output`, also after a numerical failure (the last good
 * state, with a message naming the iteration). Returns the exit code: 0,
 * 2 (log or output unwritable), 3 (numerical failure). *completed is set
 * when the run succeeded and the output was written, so the caller can
 * print its summary line. Shared by `flow` and `edit`. */
int cli_run_flow_and_write(cf_context *ctx, cf_flow *flow, cli_progress *progress, const char *log_path,
                           int64_t steps, const char *input, const cf_mesh *mesh, const char *output,
                           bool *completed);

/* Wall-clock seconds (monotonic). */
double cli_now(void);

#endif /* CF_CLI_COMMON_H */
