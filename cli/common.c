/* Shared helpers of the curvflow subcommands (see common.h). */
#define _XOPEN_SOURCE 700 /* POSIX 2008 with XSI: realpath, SA_RESETHAND */
#include "common.h"

#include "curvflow/io.h"

#include <errno.h>
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
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

/* strtod over [text, *end): 0 ok, 1 not a number, 2 not finite. Underflow
 * (ERANGE with a tiny or zero result) is a number; the caller's range check
 * decides whether it is acceptable. */
static int parse_number(const char *text, char **end, double *out)
{
    errno = 0;
    double v = strtod(text, end);
    if (*end == text) return 1;
    if (!isfinite(v) || (errno == ERANGE && fabs(v) > 1.0)) return 2;
    *out = v;
    return 0;
}

bool cli_parse_double(const char *command, const char *option, const char *text, double *out)
{
    char *end = NULL;
    double v = 0.0;
    int bad = parse_number(text, &end, &v);
    if (!bad && *end != '\0') bad = 1;
    if (bad) {
        cli_usage_error(command, "%s: '%s' is not a %snumber", option, text, bad == 2 ? "finite " : "");
        return false;
    }
    *out = v;
    return true;
}

bool cli_parse_double_in(const char *command, const char *option, const char *text, double lo, double hi,
                         double *out)
{
    double v = 0.0;
    if (!cli_parse_double(command, option, text, &v)) return false;
    if (v < lo || v > hi) {
        /* one formatter for every printed range: the flow layer's */
        cf_param_desc range = {option, CF_PARAM_DOUBLE, 0, lo, hi, NULL, NULL};
        char text_range[160];
        if (cf_flow_param_range_format(&range, text_range, sizeof text_range) != CF_OK) strcpy(text_range, "?");
        cli_usage_error(command, "%s: '%s' is outside %s", option, text, text_range);
        return false;
    }
    *out = v;
    return true;
}

bool cli_parse_doubles(const char *command, const char *option, const char *text, char separator, int count,
                       const char *form, double *out)
{
    const char *s = text;
    for (int k = 0; k < count; ++k) {
        char *end = NULL;
        int bad = parse_number(s, &end, &out[k]);
        if (!bad && *end != (k + 1 < count ? separator : '\0')) bad = 1;
        if (bad) {
            cli_usage_error(command, "%s: expected %s (%d finite numbers), got '%s'", option, form, count, text);
            return false;
        }
        s = end + 1;
    }
    return true;
}

bool cli_parse_size(const char *command, const char *option, const char *text, long long max_side, int32_t *width,
                    int32_t *height)
{
    long long v[2] = {0, 0};
    const char *s = text;
    bool ok = true;
    for (int k = 0; k < 2 && ok; ++k) {
        char *end = NULL;
        errno = 0;
        /* digits only: strtoll would also take a sign or leading blanks */
        ok = *s >= '0' && *s <= '9';
        if (ok) v[k] = strtoll(s, &end, 10);
        ok = ok && errno != ERANGE && v[k] >= 1 && v[k] <= max_side && *end == (k == 0 ? 'x' : '\0');
        if (ok) s = end + 1;
    }
    if (!ok) {
        cli_usage_error(command, "%s: expected WxH with W and H integers in [1, %lld], got '%s'", option, max_side,
                        text);
        return false;
    }
    *width = (int32_t)v[0];
    *height = (int32_t)v[1];
    return true;
}

static void log_to_stderr(void *user, cf_log_level level, const char *line)
{
    (void)user;
    if (level >= CF_LOG_WARNING && level < CF_LOG_ERROR) fprintf(stderr, "curvflow: warning: %s\n", line);
    else if (level < CF_LOG_WARNING) fprintf(stderr, "curvflow: %s\n", line);
}

bool cli_threads_from_environment(int32_t *threads)
{
    *threads = 1;
    const char *text = getenv("CURVFLOW_THREADS");
    if (!text) return true;
    /* digits only (strtol alone would take signs and leading blanks), as the Python package */
    size_t length = strlen(text);
    if (length == 0 || length > 5 || strspn(text, "0123456789") != length) return false;
    long value = strtol(text, NULL, 10);
    if (value > 1024) return false;
    *threads = (int32_t)value;
    return true;
}

cf_context *cli_context(bool verbose)
{
    cf_context *ctx = NULL;
    if (cf_context_create(&ctx) != CF_OK) {
        fprintf(stderr, "curvflow: out of memory\n");
        return NULL;
    }
    /* the solver threads (cf_context_set_threads; main checked the value) */
    int32_t threads = 1;
    if (cli_threads_from_environment(&threads)) cf_context_set_threads(ctx, threads);
    /* Errors are reported by the tool from the context message; warnings
     * (e.g. polygons fan-triangulated) go to stderr as they happen. */
    cf_context_set_log(ctx, log_to_stderr, NULL, verbose ? CF_LOG_INFO : CF_LOG_WARNING);
    return ctx;
}

static bool weld_seams = true;
/* vertices the last announced weld joined and unused vertices it dropped
 * (the command's input) */
static int32_t weld_removed, unused_dropped;

void cli_set_weld(bool weld) { weld_seams = weld; }

int cli_check_vertex_file(const char *option, const char *path, const char *mesh_path)
{
    if (weld_removed == 0 && unused_dropped == 0) return CLI_EXIT_OK;
    char what[96];
    if (weld_removed > 0 && unused_dropped > 0)
        snprintf(what, sizeof what, "seams were welded (%d vertices joined) and %d unused vertices dropped",
                 (int)weld_removed, (int)unused_dropped);
    else if (weld_removed > 0)
        snprintf(what, sizeof what, "seams were welded (%d vertices joined)", (int)weld_removed);
    else
        snprintf(what, sizeof what, "unused vertices were dropped (%d)", (int)unused_dropped);
    fprintf(stderr,
            "curvflow: %s %s: %s's %s, which renumbers its vertices, but a file numbers the file's: pass "
            "--no-weld, or give the values for the mesh read\n",
            option, path, mesh_path, what);
    return CLI_EXIT_INPUT;
}

cf_status cli_tidy_vertices(cf_context *ctx, cf_mesh_data *data, int32_t *dropped, cf_weld_report *weld)
{
    cf_status st = cf_mesh_data_drop_unreferenced(ctx, data, NULL, dropped);
    return st == CF_OK ? cf_mesh_data_weld(ctx, data, NULL, weld) : st;
}

/* Reads a mesh file and, unless --no-weld, drops the vertices no face uses
 * (cf_mesh_data_drop_unreferenced; docs/io.md, "Unused vertices") and joins
 * its seams (cf_mesh_data_weld; "Seams"); `announce`: says on stderr what
 * it did (once per file: a property read again later is silent). The mesh
 * every command then sees, and writes, is that one. */
static cf_status read_mesh_data(cf_context *ctx, const char *path, cf_mesh_data **data, bool announce)
{
    cf_status st = cf_read_mesh_file(ctx, path, data);
    if (st != CF_OK || !weld_seams) return st;
    int32_t in_file = (*data)->vertex_count, dropped = 0;
    cf_weld_report r;
    if ((st = cli_tidy_vertices(ctx, *data, &dropped, &r)) != CF_OK) {
        cf_mesh_data_destroy(data);
        return st;
    }
    if (!announce) return CF_OK;
    int32_t before = in_file - dropped; /* the weld's count before */
    if (dropped > 0) {
        unused_dropped = dropped;
        fprintf(stderr,
                "curvflow: %s: dropped %d vertices that no face uses: %d vertices instead of %d, also in what is "
                "written from it (--no-weld keeps the file's)\n",
                path, (int)dropped, (int)before, (int)in_file);
    }
    if (r.welded) {
        weld_removed = r.removed;
        char differing[96] = "";
        if (r.differing_properties > 0)
            snprintf(differing, sizeof differing, "; %d of the joined copies had other property values, the first "
                     "copy's are kept", (int)r.differing_properties);
        fprintf(stderr,
                "curvflow: %s: welded %d seam vertices onto others at the same position on the boundary (texture "
                "or normal seams, or unshared triangles): %d vertices instead of %d, also in what is written from it%s "
                "(--no-weld keeps the file's)\n",
                path, (int)r.removed, (int)r.vertices, (int)before, differing);
    } else if (r.candidates > 0) {
        fprintf(stderr,
                "curvflow: warning: %s: %d boundary vertices lie on others (seams?) but stay apart, since %s; "
                "the flows move them as free boundaries\n",
                path, (int)r.candidates, r.refused);
    }
    return CF_OK;
}

/* Reads and validates a mesh: the context's message names the file. */
static cf_status load_mesh(cf_context *ctx, const char *path, cf_mesh **out, cf_mesh_data **data)
{
    *out = NULL;
    cf_status st = read_mesh_data(ctx, path, data, true);
    if (st != CF_OK) return st;
    cf_mesh_desc desc;
    cf_mesh_data_desc(*data, &desc);
    if ((st = cf_mesh_create(ctx, &desc, out)) != CF_OK) cf_mesh_data_destroy(data);
    return st;
}

int cli_load_mesh(cf_context *ctx, const char *path, cf_mesh **out)
{
    cf_mesh_data *data = NULL;
    cf_status st = load_mesh(ctx, path, out, &data);
    cf_mesh_data_destroy(&data);
    if (st != CF_OK) {
        int code = cli_fail(ctx, path, st);
        return code == CLI_EXIT_USAGE ? CLI_EXIT_INPUT : code;
    }
    return CLI_EXIT_OK;
}

int cli_load_mesh_properties(cf_context *ctx, const char *path, cf_mesh **out, cli_properties *props)
{
    memset(props, 0, sizeof *props);
    cf_mesh_data *data = NULL;
    cf_status st = load_mesh(ctx, path, out, &data);
    if (st != CF_OK) {
        int code = cli_fail(ctx, path, st);
        return code == CLI_EXIT_USAGE ? CLI_EXIT_INPUT : code;
    }
    int32_t total = data->vertex_property_count + data->face_property_count;
    if (total == 0 && data->material_library_count == 0 && data->material_count == 0) {
        /* nothing to carry: not a second copy of the mesh for the whole run */
        cf_mesh_data_destroy(&data);
        return CLI_EXIT_OK;
    }
    props->data = data;
    props->fields = total > 0 ? calloc((size_t)total, sizeof *props->fields) : NULL;
    if (total > 0 && !props->fields) {
        fprintf(stderr, "curvflow: out of memory\n");
        cli_properties_free(props);
        cf_mesh_destroy(out);
        return CLI_EXIT_NUMERICAL;
    }
    char skipped[256] = "";
    for (int32_t i = 0; i < total; ++i) {
        int vertex = i < data->vertex_property_count;
        const cf_mesh_property *p =
            vertex ? &data->vertex_properties[i] : &data->face_properties[i - data->vertex_property_count];
        /* vertex normals describe the input's shape, not the result's:
         * left out, as before, for viewers to recompute */
        static const char *const normals[] = {"nx", "ny", "nz", "normal_x", "normal_y", "normal_z"};
        bool normal = false;
        for (size_t k = 0; k < sizeof normals / sizeof normals[0]; ++k)
            normal = normal || strcmp(p->name, normals[k]) == 0;
        if (normal) continue;
        if (!cf_field_name_valid(p->name)) {
            size_t n = strlen(skipped);
            snprintf(skipped + n, sizeof skipped - n, "%s'%s'", n ? ", " : "", p->name);
            continue;
        }
        props->fields[props->count++] = (cf_field){p->name, vertex ? CF_FIELD_VERTEX : CF_FIELD_FACE, p->values};
    }
    if (skipped[0])
        fprintf(stderr, "curvflow: warning: %s: properties %s cannot be written back (a written name is 1-128 of "
                        "[A-Za-z0-9_.-]); the others are kept in the output\n",
                path, skipped);
    return CLI_EXIT_OK;
}

void cli_properties_free(cli_properties *props)
{
    if (!props) return;
    free(props->fields);
    cf_mesh_data_destroy(&props->data);
    memset(props, 0, sizeof *props);
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
    cf_mesh_report r;
    if (cf_mesh_check_positions(ctx, mesh, positions, &r) != CF_OK || r.first_status == CF_OK) return;
    fprintf(stderr,
            "curvflow: warning: %s was written, but its triangles have degenerated (%s; %d such faces), so it "
            "will not load as a valid mesh\n",
            output, r.first_message, (int)r.degenerate_faces);
}

/* The directory part of a path as a canonical name (malloc'd), or NULL. */
static char *canonical_dir(const char *path)
{
    const char *slash = strrchr(path, '/');
    char dir[PATH_MAX];
    if (!slash) snprintf(dir, sizeof dir, ".");
    else if (slash == path) snprintf(dir, sizeof dir, "/");
    else snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    return realpath(dir, NULL);
}

/* An OBJ input's materials for an OBJ output: its mtllib lines (a relative
 * library made absolute when the output is written to another directory,
 * so that it still names the file beside the input) and each face's usemtl.
 * Another output format holds none: a warning. Returns the strings made
 * (*made, free with free_made). */
static void material_options(const cli_properties *props, const char *input, const char *output,
                             cf_mesh_format format, cf_write_options *o, char ***made)
{
    *made = NULL;
    const cf_mesh_data *d = props ? props->data : NULL;
    if (!d || (d->material_library_count == 0 && d->material_count == 0)) return;
    if (format != CF_FORMAT_OBJ) {
        fprintf(stderr,
                "curvflow: warning: %s: the materials of %s (mtllib / usemtl) are not written: only OBJ holds them\n",
                output, input);
        return;
    }
    char *in_dir = canonical_dir(input), *out_dir = canonical_dir(output);
    bool same_dir = in_dir && out_dir && strcmp(in_dir, out_dir) == 0;
    char **libs = calloc((size_t)d->material_library_count + 1, sizeof *libs);
    for (int32_t l = 0; libs && l < d->material_library_count; ++l) {
        const char *lib = d->material_libraries[l];
        if (same_dir || lib[0] == '/' || !in_dir) {
            libs[l] = strdup(lib);
        } else {
            size_t n = strlen(in_dir) + strlen(lib) + 2;
            libs[l] = malloc(n);
            if (libs[l]) snprintf(libs[l], n, "%s/%s", in_dir, lib);
        }
        if (!libs[l]) { /* out of memory: no libraries rather than a part of them */
            for (int32_t k = 0; k < l; ++k) free(libs[k]);
            free(libs);
            libs = NULL;
        }
    }
    free(in_dir);
    free(out_dir);
    o->material_library_count = libs ? d->material_library_count : 0;
    o->material_libraries = (const char *const *)libs;
    o->material_count = d->material_count;
    o->material_names = (const char *const *)d->material_names;
    o->face_materials = d->face_materials;
    *made = libs;
}

static void free_made(char **made)
{
    for (int32_t i = 0; made && made[i]; ++i) free(made[i]);
    free(made);
}

/* The result of a command on the input's connectivity, with what the input
 * carries: its properties (props; an OFF output holds the colours only, a
 * warning names how many others it drops), its OBJ materials (to an OBJ
 * output), and `extra` fields the command adds (a property of the same
 * name and location gives way to them). Returns the writer's status. */
cf_status cli_write_result(cf_context *ctx, const char *input, const cf_mesh *mesh, const double *positions,
                           const cli_properties *props, const cf_field *extra, int32_t extra_count, const char *output)
{
    int32_t nprops = props ? props->count : 0, nfields = 0;
    cf_field *fields = calloc((size_t)(nprops + extra_count) + 1, sizeof *fields);
    if (!fields) {
        fprintf(stderr, "curvflow: out of memory\n");
        return CF_ERR_NOMEM;
    }
    for (int32_t i = 0; i < nprops; ++i) {
        bool replaced = false;
        for (int32_t k = 0; k < extra_count; ++k)
            replaced = replaced || (extra[k].location == props->fields[i].location &&
                                    strcmp(extra[k].name, props->fields[i].name) == 0);
        if (!replaced) fields[nfields++] = props->fields[i];
    }
    for (int32_t k = 0; k < extra_count; ++k) fields[nfields++] = extra[k];
    cf_mesh_format format = CF_FORMAT_AUTO; /* the output's name was checked before the run */
    (void)cf_mesh_format_from_path(ctx, output, &format);
    if (nfields > 0 && format == CF_FORMAT_OFF) { /* OFF holds colours only */
        uint8_t *writable = calloc((size_t)nfields, 1);
        int32_t kept = 0;
        if (writable) {
            (void)cf_off_fields_writable(fields, nfields, cf_mesh_vertex_count(mesh), cf_mesh_face_count(mesh),
                                         writable);
            for (int32_t i = 0; i < nfields; ++i)
                if (writable[i]) fields[kept++] = fields[i];
        }
        if (kept < nfields)
            fprintf(stderr,
                    "curvflow: warning: %s: OFF holds only colours: %d of the %d properties of %s are not written "
                    "(write PLY)\n",
                    output, (int)(nfields - kept), (int)nfields, input);
        free(writable);
        nfields = kept;
    }
    cf_write_options wo;
    cf_write_options_default(&wo);
    char **made = NULL;
    material_options(props, input, output, format, &wo, &made);
    cf_status st = cf_write_mesh_file_ex(ctx, output, mesh, positions, fields, nfields, &wo);
    free_made(made);
    free(fields);
    return st;
}

int cli_run_flow_and_write(cf_context *ctx, cf_flow *flow, cli_progress *progress, const char *log_path,
                           int64_t steps, const char *input, const cf_mesh *mesh, const cli_properties *props,
                           const char *output, bool *completed)
{
    *completed = false;
    int code = CLI_EXIT_OK;
    if (log_path && (code = cli_progress_open_log(progress, ctx, log_path)) != CLI_EXIT_OK) return code;
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
    cf_status st = cli_write_result(ctx, input, mesh, cf_flow_positions(flow), props, NULL, 0, output);
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

/* ---- signals ------------------------------------------------------------ */

static void on_fatal_signal(int sig)
{
    /* async-signal-safe only: unlink in the library, then the default
     * action (SA_RESETHAND restored it; the signal is blocked while this
     * handler runs and is delivered again as it returns) */
    cf_atomic_remove_pending();
    raise(sig);
}

void cli_install_signal_cleanup(void)
{
    static const int signals[] = {SIGINT, SIGTERM, SIGHUP};
    for (size_t i = 0; i < sizeof signals / sizeof signals[0]; ++i) {
        struct sigaction old;
        if (sigaction(signals[i], NULL, &old) != 0 || old.sa_handler == SIG_IGN) continue;
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_fatal_signal;
        sigemptyset(&sa.sa_mask);
        sa.sa_flags = SA_RESETHAND;
        (void)sigaction(signals[i], &sa, NULL);
    }
}

/* ---- the output-path check ---------------------------------------------- */

void cli_files_input(cli_files *files, const char *option, const char *path)
{
    if (!path || files->input_count >= CLI_MAX_FILES) return;
    files->inputs[files->input_count].option = option;
    files->inputs[files->input_count].path = path;
    ++files->input_count;
}

void cli_files_output(cli_files *files, const char *option, const char *path, cli_file_kind kind)
{
    if (files->output_count >= CLI_MAX_FILES) return;
    files->outputs[files->output_count].option = option;
    files->outputs[files->output_count].path = path;
    files->outputs[files->output_count].kind = kind;
    ++files->output_count;
}

/* What each kind of output accepts; the writers pick the format from the
 * extension (case-insensitive), so these lists are the formats they write. */
static const struct {
    const char *label;
    const char *extensions[4];
    const char *text;
} file_kinds[] = {
    [CLI_FILE_MESH] = {"mesh", {".obj", ".off", ".ply", NULL}, ".obj, .off or .ply"},
    [CLI_FILE_FIELD_MESH] = {"mesh", {".ply", ".obj", NULL, NULL},
                             ".ply, or .obj with the fields in <stem>.face.csv; OFF cannot hold them"},
    [CLI_FILE_IMAGE] = {"image", {".png", NULL, NULL, NULL}, ".png"},
    [CLI_FILE_CURVE] = {"curve", {".csv", ".txt", ".svg", NULL}, ".csv, .txt or .svg"},
    [CLI_FILE_LOG] = {"log", {".jsonl", NULL, NULL, NULL}, ".jsonl"},
    [CLI_FILE_TABLE] = {"table", {".csv", NULL, NULL, NULL}, ".csv"},
    [CLI_FILE_HTML] = {"report", {".html", ".htm", NULL, NULL}, ".html"},
    [CLI_FILE_JSON] = {"JSON", {".json", NULL, NULL, NULL}, ".json"},
};

/* The extension of the last path component ("" when it has none). */
static const char *extension(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    return dot && dot != base ? dot : "";
}

/* Canonical name of a path that may not exist yet: realpath of the file if
 * it exists (symbolic links followed), else realpath of its directory plus
 * the last component. Falls back to the path as given. */
static void canonical(const char *path, char *out, size_t size)
{
    char resolved[PATH_MAX];
    if (realpath(path, resolved)) {
        snprintf(out, size, "%s", resolved);
        return;
    }
    const char *slash = strrchr(path, '/');
    char dir[PATH_MAX];
    if (!slash) {
        strcpy(dir, ".");
    } else if ((size_t)(slash - path) < sizeof dir) {
        memcpy(dir, path, (size_t)(slash - path));
        dir[slash - path] = '\0';
        if (!dir[0]) strcpy(dir, "/");
    } else {
        snprintf(out, size, "%s", path);
        return;
    }
    int n = -1;
    if (realpath(dir, resolved))
        n = snprintf(out, size, "%s%s%s", resolved, strcmp(resolved, "/") == 0 ? "" : "/", slash ? slash + 1 : path);
    if (n < 0 || (size_t)n >= size) snprintf(out, size, "%s", path);
}

static bool same_file(const struct stat *a, const struct stat *b)
{
    return a->st_dev == b->st_dev && a->st_ino == b->st_ino;
}

/* Checks of one output apart from the other files; 0 or 2 with a message. */
static int check_one_output(const char *option, const char *path, cli_file_kind kind, bool force)
{
    if (!path || !*path) {
        fprintf(stderr, "curvflow: %s: the output path is empty\n", option);
        return CLI_EXIT_INPUT;
    }
    const char *ext = extension(path);
    bool known = false;
    for (int i = 0; i < 4 && file_kinds[kind].extensions[i]; ++i)
        known |= strcasecmp(ext, file_kinds[kind].extensions[i]) == 0;
    struct stat sb;
    bool is_dir = path[strlen(path) - 1] == '/' || (stat(path, &sb) == 0 && S_ISDIR(sb.st_mode));
    if (is_dir) {
        fprintf(stderr, "curvflow: %s: is a directory (%s needs a %s file name)\n", path, option,
                file_kinds[kind].label);
        return CLI_EXIT_INPUT;
    }
    if (!known) {
        if (*ext)
            fprintf(stderr, "curvflow: %s: unknown %s format '%s' for %s (use %s)\n", path, file_kinds[kind].label, ext,
                    option, file_kinds[kind].text);
        else
            fprintf(stderr, "curvflow: %s: no extension to tell the %s format for %s (use %s)\n", path,
                    file_kinds[kind].label, option, file_kinds[kind].text);
        return CLI_EXIT_INPUT;
    }
    /* the directory the rename happens in ("." when there is none): the
     * link's target's for a symbolic link, which the write goes through */
    char target[PATH_MAX], dir[PATH_MAX];
    canonical(path, target, sizeof target);
    const char *slash = strrchr(target, '/');
    if (!slash) {
        strcpy(dir, ".");
    } else {
        size_t n = (size_t)(slash - target);
        if (n == 0) n = 1; /* "/name" */
        memcpy(dir, target, n);
        dir[n] = '\0';
    }
    if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode)) {
        const char *given = strrchr(path, '/');
        fprintf(stderr, "curvflow: %s: cannot write: directory %.*s does not exist\n", path,
                given ? (int)(given - path) + (given == path) : 1, given ? path : ".");
        return CLI_EXIT_INPUT;
    }
    if (access(dir, W_OK) != 0) {
        fprintf(stderr, "curvflow: %s: cannot write: %s\n", path, strerror(errno));
        return CLI_EXIT_INPUT;
    }
    if (stat(path, &sb) == 0) {
        if (!S_ISREG(sb.st_mode)) {
            fprintf(stderr, "curvflow: %s: exists and is not a regular file; refusing to replace it\n", path);
            return CLI_EXIT_INPUT;
        }
        /* the mode bits, not only access(): root may write anything, yet a
         * file without write permission was meant to stay */
        if (!force && ((sb.st_mode & 0222) == 0 || access(path, W_OK) != 0)) {
            fprintf(stderr, "curvflow: %s: the existing file is read-only; --force replaces it\n", path);
            return CLI_EXIT_INPUT;
        }
    }
    return CLI_EXIT_OK;
}

int cli_files_check(cf_context *ctx, const cli_files *files)
{
    for (int i = 0; i < files->output_count; ++i) {
        const char *out = files->outputs[i].path, *opt = files->outputs[i].option;
        int code = check_one_output(opt, out, files->outputs[i].kind, files->force);
        if (code != CLI_EXIT_OK) return code;
        struct stat so, si;
        bool out_exists = stat(out, &so) == 0;
        char co[PATH_MAX], ci[PATH_MAX];
        canonical(out, co, sizeof co);
        for (int k = 0; k < files->input_count; ++k) {
            const char *in = files->inputs[k].path;
            bool same = out_exists && stat(in, &si) == 0 ? same_file(&so, &si) : false;
            if (!same) {
                canonical(in, ci, sizeof ci);
                same = strcmp(co, ci) == 0;
            }
            if (same) {
                fprintf(stderr, "curvflow: %s: %s names the same file as the input %s (%s); refusing to overwrite an input\n",
                        out, opt, in, files->inputs[k].option);
                return CLI_EXIT_INPUT;
            }
        }
        for (int k = 0; k < i; ++k) {
            const char *other = files->outputs[k].path;
            bool same = out_exists && stat(other, &si) == 0 ? same_file(&so, &si) : false;
            if (!same) {
                canonical(other, ci, sizeof ci);
                same = strcmp(co, ci) == 0;
            }
            if (same) {
                fprintf(stderr, "curvflow: %s: %s and %s name the same file\n", out, files->outputs[k].option, opt);
                return CLI_EXIT_INPUT;
            }
        }
    }
    /* a run killed without a chance to clean up (SIGKILL, power loss)
     * leaves its temporary files: remove those of ended processes */
    for (int i = 0; i < files->output_count; ++i) {
        int32_t removed = 0;
        if (cf_atomic_remove_stale(ctx, files->outputs[i].path, &removed) == CF_OK && removed > 0)
            fprintf(stderr, "curvflow: removed %d temporary file%s of an ended run next to %s\n", (int)removed,
                    removed == 1 ? "" : "s", files->outputs[i].path);
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

int cli_progress_open_log(cli_progress *p, cf_context *ctx, const char *path)
{
    cf_status st = cf_atomic_writer_open(ctx, path, &p->log_writer);
    if (st != CF_OK) {
        int code = cli_fail(ctx, path, st);
        return code == CLI_EXIT_USAGE ? CLI_EXIT_INPUT : code;
    }
    p->ctx = ctx;
    p->log = cf_atomic_writer_stream(p->log_writer);
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
    if (p->log_writer) {
        p->log = NULL;
        if (p->log_failed) {
            cf_atomic_writer_abort(&p->log_writer);
            fprintf(stderr, "curvflow: %s: could not write the log\n", p->log_path);
            code = CLI_EXIT_INPUT;
        } else {
            cf_status st = cf_atomic_writer_commit(&p->log_writer);
            if (st != CF_OK) {
                code = cli_fail(p->ctx, p->log_path, st);
                if (code != CLI_EXIT_NUMERICAL) code = CLI_EXIT_INPUT;
            }
        }
    }
    return code;
}

/* ---- flow parameters from the command line ------------------------------ */

static const cf_param_desc *find_flow_param(cf_flow_kind kind, const char *name)
{
    const cf_param_desc *params = NULL;
    int32_t count = 0;
    if (cf_flow_params(kind, &params, &count) != CF_OK) return NULL;
    for (int32_t i = 0; i < count; ++i)
        if (strcmp(params[i].name, name) == 0) return &params[i];
    return NULL;
}

/* The message of a dedicated option (`edit --lambda 2`): the text as given
 * and the accepted values from the table. */
static int alias_error(cf_context *ctx, const cf_param_desc *p, const char *option, const char *value)
{
    char range[256];
    if (cf_flow_param_range_format(p, range, sizeof range) != CF_OK) snprintf(range, sizeof range, "?");
    if (p->type == CF_PARAM_CHOICE)
        fprintf(stderr, "curvflow: %s: unknown %s '%s' (expected %s)\n", option, p->name, value, range);
    else if (p->type == CF_PARAM_DOUBLE || p->type == CF_PARAM_INT) {
        char *end = NULL;
        double v = strtod(value, &end);
        if (end != value && *end == '\0' && isfinite(v))
            fprintf(stderr, "curvflow: %s: '%s' is outside %s\n", option, value, range);
        else
            fprintf(stderr, "curvflow: %s: %s\n", option, cf_context_message(ctx));
    } else {
        fprintf(stderr, "curvflow: %s: %s\n", option, cf_context_message(ctx));
    }
    return CLI_EXIT_USAGE;
}

int cli_flow_param_apply(cf_context *ctx, cf_flow_options *options, cli_flow_arrays *arrays, cli_files *files,
                         const char *option, const char *name, const char *value, bool alias_message)
{
    const cf_param_desc *p = find_flow_param(options->kind, name);
    if (p && cf_param_type_is_array(p->type)) {
        for (int i = 0; i < arrays->count; ++i)
            if (arrays->items[i].param == p) { /* the last one given wins, as for scalars */
                arrays->items[i].option = option;
                arrays->items[i].value = value;
                if (value[0] != '@') cli_files_input(files, option, value);
                return CLI_EXIT_OK;
            }
        if (arrays->count == CLI_MAX_ARRAY_PARAMS) {
            fprintf(stderr, "curvflow: %s: too many array parameters\n", option);
            return CLI_EXIT_USAGE;
        }
        if (value[0] == '\0') {
            fprintf(stderr, "curvflow: %s: parameter '%s' needs a file or @property\n", option, name);
            return CLI_EXIT_USAGE;
        }
        arrays->items[arrays->count].param = p;
        arrays->items[arrays->count].option = option;
        arrays->items[arrays->count].value = value;
        arrays->items[arrays->count].values = NULL;
        arrays->items[arrays->count].set = NULL;
        ++arrays->count;
        if (value[0] != '@') cli_files_input(files, option, value);
        return CLI_EXIT_OK;
    }
    cf_status st = cf_flow_options_set(ctx, options, name, value);
    if (st == CF_OK) return CLI_EXIT_OK;
    if (alias_message && p) return alias_error(ctx, p, option, value);
    return cli_fail(ctx, option, st);
}

bool cli_flow_arrays_has(const cli_flow_arrays *arrays, const char *name)
{
    for (int i = 0; i < arrays->count; ++i)
        if (strcmp(arrays->items[i].param->name, name) == 0) return true;
    return false;
}

/* Copies the property (or the three comma-separated properties of
 * "@x,y,z") of the mesh file into out (count or 3 count doubles). */
static int load_property(cf_context *ctx, const char *mesh_path, const char *option, const cf_param_desc *p,
                         const char *spec, int32_t count, double *out)
{
    cf_mesh_data *data = NULL;
    cf_status st = read_mesh_data(ctx, mesh_path, &data, false); /* welded as the mesh was */
    if (st != CF_OK) return cli_fail(ctx, mesh_path, st) == CLI_EXIT_USAGE ? CLI_EXIT_INPUT : cli_exit_code(st);
    bool face = p->type == CF_PARAM_FACE_SCALARS;
    int components = p->type == CF_PARAM_VERTEX_VECTORS ? 3 : 1;
    int32_t have = face ? data->face_count : data->vertex_count;
    int code = CLI_EXIT_OK;
    char names[256];
    snprintf(names, sizeof names, "%s", spec + 1);
    char *cursor = names;
    for (int c = 0; c < components && code == CLI_EXIT_OK; ++c) {
        char *comma = strchr(cursor, ',');
        if (comma) *comma = '\0';
        if ((comma != NULL) != (c + 1 < components) || cursor[0] == '\0') {
            fprintf(stderr, "curvflow: %s: expected @%s for parameter '%s', got '%s'\n", option,
                    components == 3 ? "X,Y,Z (three property names)" : "PROPERTY", p->name, spec);
            code = CLI_EXIT_USAGE;
            break;
        }
        const cf_mesh_property *prop =
            face ? cf_mesh_data_face_property(data, cursor) : cf_mesh_data_vertex_property(data, cursor);
        if (!prop) {
            fprintf(stderr, "curvflow: %s: %s: no %s property '%s' (%s)\n", option, mesh_path, face ? "face" : "vertex",
                    cursor, (face ? data->face_property_count : data->vertex_property_count) ? "see its header"
                                                                                               : "it has none");
            code = CLI_EXIT_INPUT;
            break;
        }
        if (have != count) { /* polygons fan-triangulated: the file's faces are not the mesh's */
            fprintf(stderr, "curvflow: %s: %s has %d %s, the mesh %d\n", option, mesh_path, (int)have,
                    face ? "faces" : "vertices", (int)count);
            code = CLI_EXIT_INPUT;
            break;
        }
        for (int32_t i = 0; i < count; ++i) {
            double v = prop->values[i];
            if (!isfinite(v)) {
                fprintf(stderr, "curvflow: %s: %s: property '%s' of %s %d is not finite\n", option, mesh_path, cursor,
                        face ? "face" : "vertex", (int)i);
                code = CLI_EXIT_INPUT;
                break;
            }
            out[(size_t)components * i + c] = v;
        }
        cursor = comma ? comma + 1 : cursor;
    }
    cf_mesh_data_destroy(&data);
    return code;
}

/* Point sets from an integer vertex property (`-p handles=@PROP`): 0 = in
 * no set, k > 0 = in set k; every vertex in a set is fixed where it is
 * (target = its position in `positions`, the start). The sets are disjoint
 * by construction; their numbers only name them in messages. To move a
 * set, a JSON constraint file gives it a transform (docs/edit.md). */
static int load_point_sets_property(cf_context *ctx, const char *mesh_path, const char *option, const cf_param_desc *p,
                                    const char *spec, const cf_mesh *mesh, const double *positions,
                                    cf_handle_set **out)
{
    int32_t nv = cf_mesh_vertex_count(mesh);
    cf_param_desc scalar = *p;
    scalar.type = CF_PARAM_VERTEX_SCALARS;
    double *code_of = calloc((size_t)nv + 1, sizeof *code_of);
    int32_t *members = calloc((size_t)nv + 1, sizeof *members);
    if (!code_of || !members) {
        free(code_of);
        free(members);
        fprintf(stderr, "curvflow: out of memory\n");
        return CLI_EXIT_NUMERICAL;
    }
    int code = load_property(ctx, mesh_path, option, &scalar, spec, nv, code_of);
    int32_t count = 0;
    for (int32_t i = 0; i < nv && code == CLI_EXIT_OK; ++i) {
        double k = code_of[i];
        if (k < 0.0 || k != floor(k) || k > INT32_MAX) {
            fprintf(stderr,
                    "curvflow: %s: %s: property '%s' of vertex %d is %.17g, not a set number (0 = in no set, k > 0 = "
                    "in set k)\n",
                    option, mesh_path, spec + 1, (int)i, k);
            code = CLI_EXIT_INPUT;
        } else if (k > 0.0) {
            members[count++] = i;
        }
    }
    if (code == CLI_EXIT_OK && count == 0) {
        fprintf(stderr, "curvflow: %s: %s: property '%s' puts no vertex in a set (every value is 0)\n", option,
                mesh_path, spec + 1);
        code = CLI_EXIT_INPUT;
    }
    if (code == CLI_EXIT_OK && count == nv) {
        fprintf(stderr,
                "curvflow: %s: %s: property '%s' puts all %d vertices in sets; nothing is left to deform\n", option,
                mesh_path, spec + 1, (int)nv);
        code = CLI_EXIT_INPUT;
    }
    cf_point_set *set = NULL;
    if (code == CLI_EXIT_OK) {
        cf_status st = cf_point_set_from_indices(ctx, nv, count, members, &set);
        if (st == CF_OK) st = cf_handle_set_from_points(ctx, set, positions, NULL, out);
        if (st != CF_OK) code = cli_fail(ctx, option, st);
    }
    cf_point_set_destroy(&set);
    free(code_of);
    free(members);
    return code;
}

int cli_flow_arrays_load(cf_context *ctx, cli_flow_arrays *arrays, cf_flow_options *options, const char *mesh_path,
                         const cf_mesh *mesh, const double *start)
{
    unsigned char *base = cf_flow_options_method(options);
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    for (int i = 0; i < arrays->count; ++i) {
        const cf_param_desc *p = arrays->items[i].param;
        const char *option = arrays->items[i].option, *value = arrays->items[i].value;
        cf_status st = CF_OK;
        /* a property of IN was welded with it; faces keep their order */
        if (value[0] != '@' && p->type != CF_PARAM_FACE_SCALARS) {
            int code = cli_check_vertex_file(option, value, mesh_path);
            if (code != CLI_EXIT_OK) return code;
        }
        if (p->type == CF_PARAM_POINT_SETS && value[0] == '@') {
            int code = load_point_sets_property(ctx, mesh_path, option, p, value, mesh,
                                                start ? start : cf_mesh_positions(mesh), &arrays->items[i].set);
            if (code != CLI_EXIT_OK) return code;
            const cf_handle_set *set = arrays->items[i].set;
            memcpy(base + p->offset, &set, sizeof set);
            continue;
        }
        if (p->type == CF_PARAM_POINT_SETS) {
            st = cf_handle_set_read_json(ctx, mesh, start, value, &arrays->items[i].set);
            if (st != CF_OK) {
                int code = cli_fail(ctx, value, st);
                return code == CLI_EXIT_USAGE ? CLI_EXIT_INPUT : code;
            }
            const cf_handle_set *set = arrays->items[i].set;
            memcpy(base + p->offset, &set, sizeof set);
            continue;
        }
        int32_t count = p->type == CF_PARAM_FACE_SCALARS ? nf : nv;
        int components = p->type == CF_PARAM_VERTEX_VECTORS ? 3 : 1;
        double *values = calloc((size_t)components * (size_t)count + 1, sizeof(double));
        if (!values) {
            fprintf(stderr, "curvflow: out of memory\n");
            return CLI_EXIT_NUMERICAL;
        }
        arrays->items[i].values = values;
        if (value[0] == '@') {
            int code = load_property(ctx, mesh_path, option, p, value, count, values);
            if (code != CLI_EXIT_OK) return code;
        } else {
            if (p->type == CF_PARAM_VERTEX_VECTORS) {
                bool boundary_only = p->max_value >= 1.0;
                st = cf_read_vertex_directions_file(ctx, value, nv, boundary_only ? cf_mesh_vertex_on_boundary(mesh) : NULL,
                                                    boundary_only ? "boundary vertex" : NULL, values);
            } else {
                st = cf_read_vertex_scalars_file(ctx, value, count, values);
            }
            if (st != CF_OK) {
                int code = cli_fail(ctx, value, st);
                return code == CLI_EXIT_USAGE ? CLI_EXIT_INPUT : code;
            }
        }
        cf_param_values field = {values, count};
        memcpy(base + p->offset, &field, sizeof field);
    }
    return CLI_EXIT_OK;
}

void cli_flow_arrays_free(cli_flow_arrays *arrays)
{
    for (int i = 0; i < arrays->count; ++i) {
        free(arrays->items[i].values);
        arrays->items[i].values = NULL;
        cf_handle_set_destroy(&arrays->items[i].set);
    }
    arrays->count = 0;
}
