/* Shared helpers of the curvflow subcommands (see common.h). */
#define _POSIX_C_SOURCE 200809L
#include "common.h"

#include "curvflow/io.h"

#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

int cli_exit_code(cf_status status)
{
    switch (status) {
    case CF_OK: return CLI_EXIT_OK;
    case CF_ERR_INVALID_ARG: return CLI_EXIT_USAGE;
    case CF_ERR_NUMERICAL:
    case CF_ERR_NOT_POSDEF:
    case CF_ERR_NOT_CONVERGED:
    case CF_ERR_CANCELLED:
    case CF_ERR_NOMEM: return CLI_EXIT_NUMERICAL;
    default: return CLI_EXIT_INPUT;
    }
}

int cli_fail(cf_context *ctx, const char *what, cf_status status)
{
    const char *msg = cf_context_message(ctx);
    if (!msg || !*msg) msg = cf_status_name(status);
    size_t n = what ? strlen(what) : 0;
    if (what && !(strncmp(msg, what, n) == 0 && msg[n] == ':'))
        fprintf(stderr, "curvflow: %s: %s\n", what, msg);
    else
        fprintf(stderr, "curvflow: %s\n", msg);
    return cli_exit_code(status);
}

int cli_usage_error(const char *command, const char *fmt, ...)
{
    va_list ap;
    fputs("curvflow: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\nTry 'curvflow %s%s--help' for more information.\n", command ? command : "", command ? " " : "");
    return CLI_EXIT_USAGE;
}

int cli_option_error(const char *command, int c, char **argv)
{
    const char *arg = optind > 0 ? argv[optind - 1] : "";
    bool is_long = strncmp(arg, "--", 2) == 0;
    int name_len = (int)strcspn(arg, "=");
    if (c == ':') {
        if (is_long) return cli_usage_error(command, "option '%.*s' requires an argument", name_len, arg);
        return cli_usage_error(command, "option '-%c' requires an argument", optopt);
    }
    if (is_long) {
        /* glibc leaves optopt 0 for an unknown long option and sets it to
         * the option's value when a flag was given an argument */
        if (optopt != 0 && arg[name_len] == '=')
            return cli_usage_error(command, "option '%.*s' does not take an argument", name_len, arg);
        return cli_usage_error(command, "unrecognized option '%.*s'", name_len, arg);
    }
    if (optopt > 0 && optopt < 128) return cli_usage_error(command, "invalid option '-%c'", optopt);
    return cli_usage_error(command, "invalid option '%s'", arg);
}

bool cli_parse_int(const char *command, const char *option, const char *text, long long min_value,
                   long long max_value, long long *out)
{
    char *end = NULL;
    errno = 0;
    long long v = strtoll(text, &end, 10);
    if (end == text || *end != '\0' || errno == ERANGE || v < min_value || v > max_value) {
        cli_usage_error(command, "%s: '%s' is not an integer in [%lld, %lld]", option, text, min_value, max_value);
        return false;
    }
    *out = v;
    return true;
}

bool cli_parse_double(const char *command, const char *option, const char *text, double *out)
{
    char *end = NULL;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end != '\0' || errno == ERANGE || !isfinite(v)) {
        cli_usage_error(command, "%s: '%s' is not a finite number", option, text);
        return false;
    }
    *out = v;
    return true;
}

static void log_to_stderr(void *user, cf_log_level level, const char *line)
{
    (void)user;
    if (level >= CF_LOG_WARNING && level < CF_LOG_ERROR) fprintf(stderr, "curvflow: warning: %s\n", line);
    else if (level < CF_LOG_WARNING) fprintf(stderr, "curvflow: %s\n", line);
}

cf_context *cli_context(bool verbose)
{
    cf_context *ctx = NULL;
    if (cf_context_create(&ctx) != CF_OK) {
        fprintf(stderr, "curvflow: out of memory\n");
        return NULL;
    }
    /* Errors are reported by the tool from the context message; warnings
     * (e.g. polygons fan-triangulated) go to stderr as they happen. */
    cf_context_set_log(ctx, log_to_stderr, NULL, verbose ? CF_LOG_INFO : CF_LOG_WARNING);
    return ctx;
}

int cli_load_mesh(cf_context *ctx, const char *path, cf_mesh **out)
{
    cf_status st = cf_load_mesh(ctx, path, out);
    if (st != CF_OK) {
        int code = cli_fail(ctx, path, st);
        return code == CLI_EXIT_USAGE ? CLI_EXIT_INPUT : code;
    }
    return CLI_EXIT_OK;
}

int cli_make_dir(const char *path)
{
    struct stat sb;
    if (stat(path, &sb) == 0) {
        if (S_ISDIR(sb.st_mode)) return CLI_EXIT_OK;
        fprintf(stderr, "curvflow: %s: exists and is not a directory\n", path);
        return CLI_EXIT_INPUT;
    }
    if (mkdir(path, 0777) != 0) {
        fprintf(stderr, "curvflow: %s: cannot create directory: %s\n", path, strerror(errno));
        return CLI_EXIT_INPUT;
    }
    return CLI_EXIT_OK;
}

void cli_warn_if_unreadable(cf_context *ctx, const cf_mesh *mesh, const double *positions, const char *output)
{
    cf_mesh_desc d = {cf_mesh_vertex_count(mesh), positions, cf_mesh_face_count(mesh), cf_mesh_triangles(mesh), 0,
                      NULL, NULL};
    cf_mesh_report r;
    if (cf_mesh_validate(ctx, &d, &r) != CF_OK || r.first_status == CF_OK) return;
    fprintf(stderr,
            "curvflow: warning: %s was written, but its triangles have degenerated (%s; %d such faces), so it "
            "will not load as a valid mesh\n",
            output, r.first_message, (int)r.degenerate_faces);
}

int cli_run_flow_and_write(cf_context *ctx, cf_flow *flow, cli_progress *progress, const char *log_path,
                           int64_t steps, const char *input, const cf_mesh *mesh, const char *output,
                           bool *completed)
{
    *completed = false;
    int code = CLI_EXIT_OK;
    if (log_path && (code = cli_progress_open_log(progress, log_path)) != CLI_EXIT_OK) return code;
    cli_progress_log(progress, cf_flow_last_info(flow));
    cf_flow_set_progress(flow, cli_progress_callback, progress);
    cf_flow_info info;
    cf_status run = cf_flow_run(flow, steps, &info);
    int log_code = cli_progress_finish(progress);
    if (run != CF_OK) {
        code = cli_fail(ctx, input, run);
        if (code == CLI_EXIT_USAGE) code = CLI_EXIT_NUMERICAL;
        fprintf(stderr, "curvflow: writing the last good state (iteration %lld) to %s\n",
                (long long)cf_flow_last_info(flow)->iteration, output);
    }
    cf_status st = cf_write_mesh_file(ctx, output, mesh, cf_flow_positions(flow), NULL, 0);
    if (st != CF_OK) {
        int wcode = cli_fail(ctx, output, st);
        if (code == CLI_EXIT_OK) code = wcode == CLI_EXIT_USAGE ? CLI_EXIT_INPUT : wcode;
    } else {
        if (run == CF_OK) *completed = true;
        cli_warn_if_unreadable(ctx, mesh, cf_flow_positions(flow), output);
    }
    if (code == CLI_EXIT_OK) code = log_code;
    return code;
}

int cli_check_output(cf_context *ctx, const char *path, bool mesh)
{
    if (!path || !*path) {
        fprintf(stderr, "curvflow: the output path is empty\n");
        return CLI_EXIT_INPUT;
    }
    if (mesh) {
        cf_mesh_format format;
        cf_status st = cf_mesh_format_from_path(ctx, path, &format);
        if (st != CF_OK) {
            int code = cli_fail(ctx, path, st);
            return code == CLI_EXIT_USAGE ? CLI_EXIT_INPUT : code;
        }
    }
    struct stat sb;
    if (stat(path, &sb) == 0 && S_ISDIR(sb.st_mode)) {
        fprintf(stderr, "curvflow: %s: is a directory\n", path);
        return CLI_EXIT_INPUT;
    }
    /* the directory part ("." when there is none) must exist and be writable */
    const char *slash = strrchr(path, '/');
    char dir[4096];
    if (!slash) {
        strcpy(dir, ".");
    } else {
        size_t n = (size_t)(slash - path);
        if (n == 0) n = 1; /* "/name" */
        if (n >= sizeof dir) {
            fprintf(stderr, "curvflow: %s: path too long\n", path);
            return CLI_EXIT_INPUT;
        }
        memcpy(dir, path, n);
        dir[n] = '\0';
    }
    if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode)) {
        fprintf(stderr, "curvflow: %s: cannot write: directory %s does not exist\n", path, dir);
        return CLI_EXIT_INPUT;
    }
    if (access(dir, W_OK) != 0) {
        fprintf(stderr, "curvflow: %s: cannot write: %s\n", path, strerror(errno));
        return CLI_EXIT_INPUT;
    }
    return CLI_EXIT_OK;
}

double cli_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void cli_progress_init(cli_progress *p, const char *method, int64_t total_steps, bool quiet)
{
    memset(p, 0, sizeof *p);
    p->method = method;
    p->total_steps = total_steps;
    p->quiet = quiet;
    p->tty = isatty(fileno(stderr)) != 0;
    p->start_seconds = cli_now();
}

int cli_progress_open_log(cli_progress *p, const char *path)
{
    p->log = fopen(path, "w");
    if (!p->log) {
        fprintf(stderr, "curvflow: %s: cannot open log: %s\n", path, strerror(errno));
        return CLI_EXIT_INPUT;
    }
    p->log_path = path;
    return CLI_EXIT_OK;
}

/* JSON numbers cannot be NaN/Inf: those become null. */
static json_t *json_num(double v) { return isfinite(v) ? json_real(v) : json_null(); }

void cli_progress_log(cli_progress *p, const cf_flow_info *info)
{
    if (!p->log) return;
    json_t *o = json_object();
    json_object_set_new(o, "iteration", json_integer((json_int_t)info->iteration));
    json_object_set_new(o, "time", json_num(info->time));
    json_object_set_new(o, "time_step", json_num(info->time_step));
    json_object_set_new(o, "energy", json_num(info->energy));
    json_t *terms = json_object();
    for (int i = 0; i < CF_FLOW_MAX_TERMS; ++i)
        if (info->term_names[i]) json_object_set_new(terms, info->term_names[i], json_num(info->energy_terms[i]));
    json_object_set_new(o, "terms", terms);
    json_t *res = json_object();
    for (int i = 0; i < CF_FLOW_MAX_RESIDUALS; ++i)
        if (info->residual_names[i]) json_object_set_new(res, info->residual_names[i], json_num(info->residuals[i]));
    json_object_set_new(o, "residuals", res);
    json_object_set_new(o, "area", json_num(info->area));
    json_object_set_new(o, "volume", json_num(info->volume));
    json_object_set_new(o, "area_drift", json_num(info->area_drift));
    json_object_set_new(o, "volume_drift", json_num(info->volume_drift));
    json_t *sec = json_object();
    json_object_set_new(sec, "assemble", json_num(info->assemble_seconds));
    json_object_set_new(sec, "factorize", json_num(info->factorize_seconds));
    json_object_set_new(sec, "solve", json_num(info->solve_seconds));
    json_object_set_new(sec, "total", json_num(info->total_seconds));
    json_object_set_new(o, "seconds", sec);
    char *text = json_dumps(o, JSON_COMPACT | JSON_REAL_PRECISION(17) | JSON_PRESERVE_ORDER);
    json_decref(o);
    if (!text || fprintf(p->log, "%s\n", text) < 0 || fflush(p->log) != 0) p->log_failed = true;
    free(text);
}

int cli_progress_callback(void *user, const cf_flow_info *info)
{
    cli_progress *p = user;
    cli_progress_log(p, info);
    if (p->quiet) return 0;
    if (p->tty) {
        int width = 30;
        int filled = p->total_steps > 0 ? (int)(width * info->iteration / p->total_steps) : width;
        if (filled > width) filled = width;
        char bar[64];
        for (int i = 0; i < width; ++i) bar[i] = i < filled ? '#' : '.';
        bar[width] = '\0';
        fprintf(stderr, "\r%s [%s] %lld/%lld  energy %.6g  area drift %+.2e  %.1f s\x1b[K", p->method, bar,
                (long long)info->iteration, (long long)p->total_steps, info->energy, info->area_drift,
                cli_now() - p->start_seconds);
        p->bar_drawn = true;
    } else {
        fprintf(stderr, "%s: step %lld/%lld  t %.6g  energy %.9g  area drift %+.3e  volume drift %+.3e  %.1f ms\n",
                p->method, (long long)info->iteration, (long long)p->total_steps, info->time, info->energy,
                info->area_drift, info->volume_drift, 1e3 * info->total_seconds);
    }
    fflush(stderr);
    return 0;
}

int cli_progress_finish(cli_progress *p)
{
    if (p->bar_drawn) fputc('\n', stderr);
    p->bar_drawn = false;
    int code = CLI_EXIT_OK;
    if (p->log) {
        if (fclose(p->log) != 0) p->log_failed = true;
        p->log = NULL;
        if (p->log_failed) {
            fprintf(stderr, "curvflow: %s: could not write the log\n", p->log_path);
            code = CLI_EXIT_INPUT;
        }
    }
    return code;
}
