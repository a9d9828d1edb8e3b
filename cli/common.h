/*
 * Helpers shared by the subcommands: error reporting in the tool's format
 * ("curvflow: <file>: <message>"), exit codes from statuses, number and
 * --param key=value parsing, mesh loading, the per-step progress line / bar
 * and the JSONL step log.
 */
#ifndef CF_CLI_COMMON_H
#define CF_CLI_COMMON_H

#include "cli.h"
#include "curvflow/constraints.h"
#include "curvflow/curvflow.h"
#include "curvflow/flow.h"
#include "curvflow/io.h"
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
 * error naming the option on failure and return false. A double below the
 * smallest normal one (1e-320) is a number (strtod's underflow flag is not
 * an error); nan, inf and overflow are not finite. */
bool cli_parse_int(const char *command, const char *option, const char *text, long long min_value,
                   long long max_value, long long *out);
bool cli_parse_double(const char *command, const char *option, const char *text, double *out);
/* cli_parse_double, then lo <= value <= hi; the message prints the text as
 * given and the limits as the flow parameters' messages do (they read back
 * exactly): "--lambda: '1.0000001' is outside [0, 1]". */
bool cli_parse_double_in(const char *command, const char *option, const char *text, double lo, double hi,
                         double *out);
/* `count` finite numbers separated by `separator` ("1,2,3" for --view,
 * "MIN,MAX" for --range), with the same rules as cli_parse_double; the
 * usage error names the option and the expected form `form`. */
bool cli_parse_doubles(const char *command, const char *option, const char *text, char separator, int count,
                       const char *form, double *out);
/* "WxH" with 1 <= W, H <= max_side (integers, no overflow): --size. */
bool cli_parse_size(const char *command, const char *option, const char *text, long long max_side, int32_t *width,
                    int32_t *height);

/* The solver threads asked for by the environment variable CURVFLOW_THREADS
 * (cf_context_set_threads: 1 serial, the default when it is unset; 0
 * OpenMP and OpenBLAS as the process set them; n > 1 parallel). false (and
 * 1) when it is set to anything but an integer in 0..1024. */
bool cli_threads_from_environment(int32_t *threads);

/* A context with warnings from the library forwarded to stderr and the
 * solver threads of CURVFLOW_THREADS. */
cf_context *cli_context(bool verbose);

/* Loads a validated mesh, its seams welded (cli_set_weld); on failure
 * prints the message and returns the exit code (2), else 0. */
int cli_load_mesh(cf_context *ctx, const char *path, cf_mesh **out);

/* Whether cli_load_mesh and cli_load_mesh_properties drop a file's unused
 * vertices and weld its seams (cf_mesh_data_drop_unreferenced,
 * cf_mesh_data_weld; true unless a command's --no-weld). */
void cli_set_weld(bool weld);
/* What the commands make of a file's vertices (docs/io.md, "Unused vertices"
 * and "Seams"): the unused ones dropped (cf_mesh_data_drop_unreferenced),
 * then the seams welded (cf_mesh_data_weld); *dropped and *weld say what was
 * done. Shared by the reading of every command and by info's report. */
cf_status cli_tidy_vertices(cf_context *ctx, cf_mesh_data *data, int32_t *dropped, cf_weld_report *weld);
/* A file of per-vertex values or vertex numbers (`option` PATH) for the
 * mesh file mesh_path: exit 2 with a message if the weld renumbered that
 * mesh's vertices, else 0. */
int cli_check_vertex_file(const char *option, const char *path, const char *mesh_path);

/* The scalar vertex and face properties of a mesh file (a PLY's colours,
 * quality, labels), kept to be written with a result of the same
 * connectivity: fields point into `data`. */
typedef struct cli_properties {
    cf_mesh_data *data;
    cf_field *fields;
    int32_t count;
} cli_properties;

/* cli_load_mesh that also keeps the file's properties (every property whose
 * name a written field may have, the others named in one warning; vertex
 * normals nx ny nz / normal_x .. left out: they are the input's shape). */
int cli_load_mesh_properties(cf_context *ctx, const char *path, cf_mesh **out, cli_properties *props);
void cli_properties_free(cli_properties *props);

/* Writes `positions` on the input's connectivity `mesh` to `output` with
 * what the input carries (props, may be NULL: its properties, its OBJ
 * materials; an OFF output holds the colours only and a warning names what
 * it drops) and the command's own `extra` fields (a property of the same
 * name and location gives way to them). Returns the writer's status. */
cf_status cli_write_result(cf_context *ctx, const char *input, const cf_mesh *mesh, const double *positions,
                           const cli_properties *props, const cf_field *extra, int32_t extra_count, const char *output);

/* Removes the temporary files of atomic writes in progress when the tool
 * gets SIGINT, SIGTERM or SIGHUP, then dies of the signal as it would have
 * (a signal the tool was started with ignored, e.g. SIGHUP under nohup,
 * stays ignored). Called once by main. */
void cli_install_signal_cleanup(void);

/* The files a command reads and writes, checked together before any work
 * by cli_files_check: the one output-path check of every command. */
typedef enum cli_file_kind {
    CLI_FILE_MESH,       /* .obj .off .ply */
    CLI_FILE_FIELD_MESH, /* a mesh with per-element fields: .ply, or .obj with side CSV files */
    CLI_FILE_IMAGE,      /* .png */
    CLI_FILE_CURVE,      /* .csv .txt .svg */
    CLI_FILE_LOG,        /* .jsonl (JSON lines) */
    CLI_FILE_TABLE,      /* .csv (the side file of an OBJ with fields) */
    CLI_FILE_HTML,       /* .html .htm (the report) */
    CLI_FILE_JSON        /* .json (a run's description) */
} cli_file_kind;

enum { CLI_MAX_FILES = 12 };
typedef struct cli_files {
    struct { const char *option, *path; } inputs[CLI_MAX_FILES];
    struct { const char *option, *path; cli_file_kind kind; } outputs[CLI_MAX_FILES];
    int input_count, output_count;
    bool force;   /* --force: replace read-only targets */
} cli_files;

/* Records an input (option names it in messages, e.g. "IN", "--handles";
 * NULL path: ignored). */
void cli_files_input(cli_files *files, const char *option, const char *path);
/* Records an output of the given kind (option: "-o", "--log", ...). */
void cli_files_output(cli_files *files, const char *option, const char *path, cli_file_kind kind);
/* Before the run, for every output: the path is not empty, its extension
 * names a format of its kind, it is not a directory, its directory exists
 * and is writable, an existing target is a regular file and not read-only
 * (unless files->force), it is not the same file as an input (after
 * symbolic links, also hard links) nor as another output. Then removes the
 * stale temporary files of ended runs next to each output
 * (cf_atomic_remove_stale). Prints "curvflow: OUT: ..." and returns 2 on
 * the first problem, else 0. The writes stay atomic (a symbolic link is
 * written through); this saves a run whose result could not be kept and
 * keeps the tool from clobbering what it should not. */
int cli_files_check(cf_context *ctx, const cli_files *files);

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
    FILE *log;              /* stream of log_writer, or NULL */
    cf_atomic_writer *log_writer; /* the JSONL log, written atomically */
    cf_context *ctx;        /* for the log's messages */
    const char *log_path;
    bool log_failed;
    double start_seconds;
    bool bar_drawn;
} cli_progress;

void cli_progress_init(cli_progress *p, const char *method, int64_t total_steps, bool quiet);
/* Starts the JSONL log: written to a temporary file next to `path` while
 * the run lasts and renamed into place by cli_progress_finish (also after a
 * numerical failure: the steps up to it are kept); removed on a signal.
 * Returns 0 or 2 with a message. */
int cli_progress_open_log(cli_progress *p, cf_context *ctx, const char *path);
/* Writes the JSON object of one step (also for the initial state, iteration 0). */
void cli_progress_log(cli_progress *p, const cf_flow_info *info);
/* cf_progress_fn: prints and logs the step; never cancels. */
int cli_progress_callback(void *user, const cf_flow_info *info);
/* Ends the bar line; commits the log (or, if a write to it failed, removes
 * it). Returns 0 or 2 if the log could not be written. Idempotent. */
int cli_progress_finish(cli_progress *p);

/* Runs `steps` steps of a created flow with the progress reporter (the
 * JSONL log opened at log_path when it is not NULL) and writes the reached
 * positions to `output`, also after a numerical failure (the last good
 * state, with a message naming the iteration). Returns the exit code: 0,
 * 2 (log or output unwritable), 3 (numerical failure). *completed is set
 * when the run succeeded and the output was written, so the caller can
 * print its summary line. Shared by `flow` and `edit`. The input's
 * properties (props, may be NULL) are written with it: as PLY properties,
 * as OBJ side CSV files; an OFF output holds none and says so. */
int cli_run_flow_and_write(cf_context *ctx, cf_flow *flow, cli_progress *progress, const char *log_path,
                           int64_t steps, const char *input, const cf_mesh *mesh, const cli_properties *props,
                           const char *output, bool *completed);

/* Wall-clock seconds (monotonic). */
double cli_now(void);

/* ---- flow parameters from the command line ------------------------------
 * Every method parameter goes through its kind's table (flow.h): scalar ones
 * as text (cf_flow_options_set, ranges and messages from the table), array
 * ones (CF_PARAM_VERTEX_SCALARS / _VERTEX_VECTORS / _FACE_SCALARS /
 * _POINT_SETS) loaded by cli_flow_arrays_load once the mesh is known, from
 *   NAME=FILE       vertex/face scalars: numbers in element order
 *                   (cf_read_vertex_scalars_file); vertex vectors: lines
 *                   "VERTEX X Y Z" (cf_read_vertex_directions_file; every
 *                   vertex, or every boundary vertex when the table says so);
 *                   point sets: a JSON constraint ("handle") file
 *                   (cf_handle_set_read_json, docs/edit.md)
 *   NAME=@PROP      a property of the input mesh file (PLY): a vertex or face
 *                   property for scalars, three properties "@nx,ny,nz" for
 *                   vertex vectors.
 * The arrays are owned by the cli_flow_arrays and must be freed after the
 * flow (cli_flow_arrays_free). */
enum { CLI_MAX_ARRAY_PARAMS = 8 };
typedef struct cli_flow_arrays {
    int count;
    struct {
        const cf_param_desc *param;
        const char *option;   /* as the user gave it, for messages ("--handles", "-p handles") */
        const char *value;    /* FILE or @PROP */
        double *values;       /* loaded, owned */
        cf_handle_set *set;   /* loaded, owned */
    } items[CLI_MAX_ARRAY_PARAMS];
} cli_flow_arrays;

/* Applies one parameter to options: name and value text, `option` the
 * command-line spelling for messages. Array parameters are recorded in
 * `arrays` (their files are added to `files` as inputs) and loaded later.
 * Scalar failures print "curvflow: OPTION: <library message>" unless
 * alias_message, which prints "OPTION: 'TEXT' is outside RANGE" (numbers)
 * or "OPTION: unknown NAME 'TEXT' (expected a|b)" (choices) as the
 * dedicated options of `curvflow edit` always did. Returns an exit code. */
int cli_flow_param_apply(cf_context *ctx, cf_flow_options *options, cli_flow_arrays *arrays, cli_files *files,
                         const char *option, const char *name, const char *value, bool alias_message);
/* Loads the recorded arrays for `mesh` (read from mesh_path; start: the
 * positions point sets are evaluated on, NULL = the mesh's) into options.
 * Returns 0, 2 (bad file or property, with the message), 3 (no memory). */
int cli_flow_arrays_load(cf_context *ctx, cli_flow_arrays *arrays, cf_flow_options *options, const char *mesh_path,
                         const cf_mesh *mesh, const double *start);
/* 1 if the array parameter `name` was given. */
bool cli_flow_arrays_has(const cli_flow_arrays *arrays, const char *name);
void cli_flow_arrays_free(cli_flow_arrays *arrays);

/* A flow run as `curvflow flow` does it; `curvflow edit` is a front end
 * that fills the same job (cli/cmd_edit.c). */
enum { CLI_MAX_PARAM_ARGS = 64 };
typedef struct cli_flow_job {
    const char *command;     /* "flow", "edit": messages and report */
    cf_flow_kind kind;
    const char *label;       /* status lines and report: method or energy name */
    const char *input, *output, *log_path, *report_path, *start_path;
    long long steps;
    bool quiet, force;
    struct {
        const char *option;  /* "-p", "--lambda", ... */
        const char *name;
        const char *value;
        bool alias_message;
    } params[CLI_MAX_PARAM_ARGS];
    int param_count;
    int invalid_options_exit; /* exit code when cf_flow_create refuses the options (1 flow, 2 edit) */
    bool announce_point_sets; /* "H: N handle vertices (M moved), K free" */
    const char *const *report_extra;
    /* front end's check of the options once set (may be NULL): exit code */
    int (*check)(const struct cli_flow_job *job, const cf_flow_options *options);
    /* the closing line after a completed run (may be NULL: flow's line) */
    void (*summary)(const struct cli_flow_job *job, const cf_flow *flow);
} cli_flow_job;

/* Adds a parameter to job (name=value as given by `option`). Returns false
 * (usage error printed) when there are too many. */
bool cli_flow_job_param(cli_flow_job *job, const char *option, const char *name, const char *value,
                        bool alias_message);
/* Loads, creates, runs, writes (also the log and report). Exit code. */
int cli_flow_execute(const cli_flow_job *job);

#endif /* CF_CLI_COMMON_H */
