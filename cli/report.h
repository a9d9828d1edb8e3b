/*
 * The one-file HTML report (cli/cmd_report.c, docs/report.md): input and
 * result in an interactive 3D view coloured by per-face quasi-conformal
 * error Q and log area distortion, the energy and residual curves of the
 * step log, the run's parameters and timings. The viewer (report/, three.js
 * bundled by esbuild) is embedded in the tool at build time; when it could
 * not be built, writing a report fails with a message saying why.
 * Used by `curvflow report`, `flow --report`, `edit --report` and `demo`.
 */
#ifndef CF_CLI_REPORT_H
#define CF_CLI_REPORT_H

#include "common.h"
#include "curvflow/metrics.h"

#include <stdint.h>
#include <stdio.h>

/* What the report says about the run; NULL / negative / NaN = not known. */
typedef struct cli_report_run {
    const char *command;     /* "flow", "edit", "demo", "report" */
    const char *method;      /* flow method or edit energy */
    const char *title;       /* page title; NULL: from the input's name */
    const char *input_path;  /* as shown on the page */
    const char *output_path;
    const char *log_path;
    const cf_flow_options *options;   /* every parameter with its value; NULL: not recorded */
    const char *const *extra;         /* more "name", "value" pairs, NULL-terminated (e.g. the handle file) */
    int64_t steps_requested;
    int64_t steps_done;
    int converged;           /* 1 yes, 0 no, -1 unknown */
    int exit_status;         /* the command's exit code; -1 unknown */
    const char *message;     /* failure message or NULL */
    double seconds_run;      /* wall clock of the steps (+ writing) */
    double seconds_load;
    bool quiet;              /* no "wrote the report" line */
} cli_report_run;

/* A run description with nothing known. */
void cli_report_run_init(cli_report_run *run);

/* Per-face comparison of result to input and the figures shown at the top
 * of the report (and printed by the demo). q, log_area: nf each, owned. */
typedef struct cli_report_figures {
    double *q;
    double *log_area;
    cf_stats q_stats, log_area_stats;
    double willmore_before, willmore_after; /* W, not divided by 4 pi */
    int ok;                  /* 0: the comparison failed (message on stderr); no fields */
} cli_report_figures;

/* Computes the figures of positions x1 against x0 (3 nv each). Returns 0,
 * or 3 (out of memory); a failed comparison (e.g. a degenerate result) is
 * not an error: fig->ok is 0 and a warning names the problem. */
int cli_report_figures_compute(cf_context *ctx, const cf_mesh *mesh, const double *x0, const double *x1,
                               cli_report_figures *fig);
void cli_report_figures_free(cli_report_figures *fig);

/* Whether this tool carries the viewer; if not, prints
 * "curvflow: cannot write a report: ..." (the reason) and returns false. */
bool cli_report_available(void);

/* Writes the report to html_path atomically. log_jsonl: the text of a JSONL
 * step log (flow --log format) or NULL; log_name names it in messages. fig:
 * precomputed figures or NULL (computed here). Returns 0, 2 (bad log,
 * unwritable file, no viewer) or 3 (out of memory). */
int cli_report_write(cf_context *ctx, const char *html_path, const cli_report_run *run, const cf_mesh *mesh,
                     const double *x0, const double *x1, const char *log_jsonl, const char *log_name,
                     const cli_report_figures *fig);

/* Run description as JSON text (the demo's run.json, read back by
 * `curvflow report DIR`); malloc'd, NULL on failure. */
char *cli_report_run_json(const cli_report_run *run);

/* --report for flow and edit: when the command writes no --log, the steps
 * are captured in memory through the progress reporter's log stream. */
typedef struct cli_report_log {
    char *text;
    size_t size;
    FILE *stream;           /* the in-memory log while the run lasts */
    cli_progress *progress; /* whose log it is */
} cli_report_log;

/* Attaches an in-memory log to `progress` when the command writes no log
 * file (log_path NULL); call before the run. Returns 0 or 3. */
int cli_report_log_capture(cli_report_log *cap, cli_progress *progress, const char *log_path);
/* The step log to put in the report (after the run): the captured text, or
 * the file at log_path when one was written (read into cap). Returns the
 * text or NULL. */
const char *cli_report_log_text(cli_report_log *cap, const char *log_path);
void cli_report_log_free(cli_report_log *cap);

/* flow/edit --report, after the run (whatever its outcome; `code` is the
 * command's exit code so far): fills in the steps done, convergence and
 * outcome, writes the report of the mesh's rest positions against the
 * flow's current ones with the step log, and returns `code`, or the
 * report's exit code when `code` is 0. */
int cli_report_after_run(cf_context *ctx, const char *report_path, cli_report_run *run, const cf_mesh *mesh,
                         const cf_flow *flow, cli_report_log *cap, int code);

#endif /* CF_CLI_REPORT_H */
