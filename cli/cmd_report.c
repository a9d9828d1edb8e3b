/*
 * curvflow report: the one-file HTML report (report.h, docs/report.md).
 *
 *   curvflow report IN OUT [--log LOG.jsonl] [--run RUN.json] -o report.html
 *   curvflow report RUN_DIR [-o report.html]
 *
 * The page is one HTML file with no outside references: the viewer script
 * (report/src, three.js; embedded at build time as cli_report_bundle) and
 * the data (meshes and per-face fields as base64 little-endian float32 /
 * uint32, the step log as parsed JSON, the run's parameters) are inline, and
 * a Content-Security-Policy of default-src 'none' keeps the browser from
 * fetching anything.
 */
#define _GNU_SOURCE
#include "report.h"

#include "curvflow/io.h"
#include "curvflow/ops.h"

#include <errno.h>
#include <getopt.h>
#include <jansson.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* generated at build time (report/build.mjs, or cmake/report_stub.cmake) */
extern const unsigned char cli_report_bundle[];
extern const size_t cli_report_bundle_size;
extern const char *const cli_report_three_version;
extern const char *const cli_report_bundle_missing;

void cli_report_run_init(cli_report_run *run)
{
    memset(run, 0, sizeof *run);
    run->steps_requested = -1;
    run->steps_done = -1;
    run->converged = -1;
    run->exit_status = -1;
    run->seconds_run = NAN;
    run->seconds_load = NAN;
}

bool cli_report_available(void)
{
    if (cli_report_bundle_size > 0) return true;
    fprintf(stderr, "curvflow: cannot write a report: the report viewer is not built into this curvflow (%s)\n",
            cli_report_bundle_missing ? cli_report_bundle_missing : "unknown reason");
    return false;
}

/* ---- figures ------------------------------------------------------------ */

int cli_report_figures_compute(cf_context *ctx, const cf_mesh *mesh, const double *x0, const double *x1,
                               cli_report_figures *fig)
{
    memset(fig, 0, sizeof *fig);
    int32_t nf = cf_mesh_face_count(mesh);
    fig->q = malloc((size_t)nf * sizeof *fig->q);
    fig->log_area = malloc((size_t)nf * sizeof *fig->log_area);
    if (!fig->q || !fig->log_area) {
        cli_report_figures_free(fig);
        fprintf(stderr, "curvflow: out of memory\n");
        return CLI_EXIT_NUMERICAL;
    }
    cf_status st;
    if ((st = cf_willmore_energy(ctx, mesh, x0, &fig->willmore_before)) != CF_OK ||
        (st = cf_willmore_energy(ctx, mesh, x1, &fig->willmore_after)) != CF_OK ||
        (st = cf_quasi_conformal_error(ctx, mesh, x0, x1, fig->q, &fig->q_stats)) != CF_OK ||
        (st = cf_log_area_distortion(ctx, mesh, x0, x1, fig->log_area, &fig->log_area_stats)) != CF_OK) {
        /* e.g. a result whose triangles degenerated: the report still shows
         * the shapes and the log, without the per-face maps */
        fprintf(stderr, "curvflow: warning: the report has no per-face comparison: %s\n", cf_context_message(ctx));
        cf_context_clear_error(ctx);
        return CLI_EXIT_OK;
    }
    fig->ok = 1;
    return CLI_EXIT_OK;
}

void cli_report_figures_free(cli_report_figures *fig)
{
    free(fig->q);
    free(fig->log_area);
    fig->q = fig->log_area = NULL;
    fig->ok = 0;
}

/* ---- JSON pieces ---------------------------------------------------------- */

/* base64 (RFC 4648) of n 32-bit values written little-endian, as a JSON
 * string; values are float32 (from doubles) or uint32 (from int32). */
static json_t *base64_array(const double *d, const int32_t *i, size_t n)
{
    static const char alphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t bytes = 4 * n, out_len = 4 * ((bytes + 2) / 3);
    char *out = malloc(out_len + 1);
    if (!out) return NULL;
    unsigned char chunk[3];
    size_t filled = 0, o = 0;
    for (size_t k = 0; k < n; ++k) {
        uint32_t bits;
        if (d) {
            float f = (float)d[k];
            memcpy(&bits, &f, 4);
        } else {
            bits = (uint32_t)i[k];
        }
        for (int b = 0; b < 4; ++b) {
            chunk[filled++] = (unsigned char)(bits >> (8 * b));
            if (filled == 3) {
                out[o++] = alphabet[chunk[0] >> 2];
                out[o++] = alphabet[((chunk[0] & 3) << 4) | (chunk[1] >> 4)];
                out[o++] = alphabet[((chunk[1] & 15) << 2) | (chunk[2] >> 6)];
                out[o++] = alphabet[chunk[2] & 63];
                filled = 0;
            }
        }
    }
    if (filled > 0) {
        if (filled == 1) chunk[1] = 0;
        out[o++] = alphabet[chunk[0] >> 2];
        out[o++] = alphabet[((chunk[0] & 3) << 4) | (chunk[1] >> 4)];
        out[o++] = filled == 2 ? alphabet[(chunk[1] & 15) << 2] : '=';
        out[o++] = '=';
    }
    out[o] = '\0';
    json_t *s = json_stringn(out, o);
    free(out);
    return s;
}

/* Positions as float32 relative to the centre of their bounding box, with
 * that centre beside them (`<name>_offset`, doubles): float32 keeps ~7
 * digits, so raw coordinates of a mesh 1e6 from the origin would be
 * rounded to steps of 0.0625 (float32's spacing there; spot_3k is 2.6
 * across); relative to the centre they keep 1e-7 of the mesh's size. The viewer
 * centres each shape on its box anyway; a reader adds the offset back. */
static void set_positions(json_t *m, const char *name, const double *x, int32_t nv)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, centre[3];
    for (int32_t v = 0; v < nv; ++v)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], x[3 * (size_t)v + k]);
            hi[k] = fmax(hi[k], x[3 * (size_t)v + k]);
        }
    for (int k = 0; k < 3; ++k) centre[k] = nv > 0 ? 0.5 * (lo[k] + hi[k]) : 0.0;
    double *rel = malloc(sizeof(double) * 3 * (size_t)(nv > 0 ? nv : 1));
    if (rel)
        for (int32_t v = 0; v < nv; ++v)
            for (int k = 0; k < 3; ++k) rel[3 * (size_t)v + k] = x[3 * (size_t)v + k] - centre[k];
    /* (a failed allocation leaves the key out: the page says the data are incomplete) */
    if (rel) json_object_set_new(m, name, base64_array(rel, NULL, 3 * (size_t)nv));
    free(rel);
    char key[64];
    snprintf(key, sizeof key, "%s_offset", name);
    json_object_set_new(m, key, json_pack("[fff]", centre[0], centre[1], centre[2]));
}

static json_t *num(double v) { return isfinite(v) ? json_real(v) : json_null(); }

static json_t *stats_json(const cf_stats *s)
{
    json_t *o = json_object();
    json_object_set_new(o, "mean", num(s->weighted_mean));
    json_object_set_new(o, "std", num(s->weighted_std));
    json_object_set_new(o, "min", num(s->min));
    json_object_set_new(o, "p50", num(s->p50));
    json_object_set_new(o, "p95", num(s->p95));
    json_object_set_new(o, "max", num(s->max));
    return o;
}

static json_t *string_or_null(const char *s) { return s ? json_string(s) : json_null(); }

static json_t *run_json(const cli_report_run *run)
{
    json_t *o = json_object();
    json_object_set_new(o, "command", string_or_null(run->command));
    if (run->title) json_object_set_new(o, "title", json_string(run->title));
    json_object_set_new(o, "method", string_or_null(run->method));
    json_object_set_new(o, "input", string_or_null(run->input_path));
    json_object_set_new(o, "output", string_or_null(run->output_path));
    json_object_set_new(o, "log", string_or_null(run->log_path));
    if (run->steps_requested >= 0) json_object_set_new(o, "steps_requested", json_integer(run->steps_requested));
    if (run->steps_done >= 0) json_object_set_new(o, "steps_done", json_integer(run->steps_done));
    if (run->converged >= 0) json_object_set_new(o, "converged", json_boolean(run->converged));
    if (run->exit_status >= 0) json_object_set_new(o, "exit_status", json_integer(run->exit_status));
    if (run->message) json_object_set_new(o, "message", json_string(run->message));
    json_t *params = json_array();
    if (run->options) {
        const cf_param_desc *descs = NULL;
        int32_t count = 0;
        if (cf_flow_params(run->options->kind, &descs, &count) == CF_OK)
            for (int32_t i = 0; i < count; ++i) {
                char value[128];
                if (cf_flow_options_format(run->options, &descs[i], value, sizeof value) != CF_OK) continue;
                json_array_append_new(params, json_pack("[ss]", descs[i].name, value));
            }
    }
    for (const char *const *e = run->extra; e && e[0] && e[1]; e += 2)
        json_array_append_new(params, json_pack("[ss]", e[0], e[1]));
    json_object_set_new(o, "parameters", params);
    json_t *sec = json_object();
    if (isfinite(run->seconds_run)) json_object_set_new(sec, "run", json_real(run->seconds_run));
    if (isfinite(run->seconds_load)) json_object_set_new(sec, "load", json_real(run->seconds_load));
    json_object_set_new(o, "seconds", sec);
    return o;
}

char *cli_report_run_json(const cli_report_run *run)
{
    json_t *o = run_json(run);
    char *text = o ? json_dumps(o, JSON_INDENT(2) | JSON_REAL_PRECISION(17) | JSON_PRESERVE_ORDER) : NULL;
    json_decref(o);
    return text;
}

/* The JSONL step log as an array of its objects; messages name the line. */
static int parse_log(const char *text, const char *name, json_t **out)
{
    *out = json_array();
    if (!*out) return CLI_EXIT_NUMERICAL;
    const char *p = text;
    long line = 0;
    while (*p) {
        ++line;
        const char *end = strchr(p, '\n');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        size_t k = 0;
        while (k < len && (p[k] == ' ' || p[k] == '\t' || p[k] == '\r')) ++k;
        if (k < len) {
            json_error_t err;
            json_t *o = json_loadb(p, len, 0, &err);
            if (!o || !json_is_object(o) || !json_is_integer(json_object_get(o, "iteration"))) {
                fprintf(stderr, "curvflow: %s:%ld: not a step of a curvflow log (%s)\n", name, line,
                        o ? "expected an object with an integer \"iteration\"" : err.text);
                json_decref(o);
                json_decref(*out);
                *out = NULL;
                return CLI_EXIT_INPUT;
            }
            json_array_append_new(*out, o);
        }
        p += len;
        if (*p == '\n') ++p;
    }
    return CLI_EXIT_OK;
}

/* ---- HTML ------------------------------------------------------------------ */

typedef struct buffer {
    char *data;
    size_t size, capacity;
    bool failed;
} buffer;

static void put(buffer *b, const char *s, size_t n)
{
    if (b->failed) return;
    if (b->size + n + 1 > b->capacity) {
        size_t cap = b->capacity ? b->capacity : 1 << 16;
        while (cap < b->size + n + 1) cap *= 2;
        char *d = realloc(b->data, cap);
        if (!d) {
            b->failed = true;
            return;
        }
        b->data = d;
        b->capacity = cap;
    }
    memcpy(b->data + b->size, s, n);
    b->size += n;
    b->data[b->size] = '\0';
}

static void puts_(buffer *b, const char *s) { put(b, s, strlen(s)); }

static void put_html_text(buffer *b, const char *s)
{
    for (; *s; ++s) {
        switch (*s) {
        case '<': puts_(b, "&lt;"); break;
        case '>': puts_(b, "&gt;"); break;
        case '&': puts_(b, "&amp;"); break;
        case '"': puts_(b, "&quot;"); break;
        default: put(b, s, 1);
        }
    }
}

/* JSON inside <script>: '<' only occurs in strings, where \u003c is the same
 * character, so "</script>" or "<!--" can never end or confuse the element. */
static void put_json_for_script(buffer *b, const char *json)
{
    for (const char *s = json; *s;) {
        const char *lt = strchr(s, '<');
        size_t n = lt ? (size_t)(lt - s) : strlen(s);
        put(b, s, n);
        if (!lt) break;
        puts_(b, "\\u003c");
        s = lt + 1;
    }
}

/* Collects errors before and while the viewer runs, for the reader and for
 * the browser test: uncaught exceptions, rejected promises, console.error
 * and anything the page policy blocked (which would be a network access). */
static const char error_capture_script[] =
    "(function(){var E=window.__curvflowErrors=[];function n(m){E.push(String(m));"
    "document.documentElement.setAttribute('data-curvflow-errors',String(E.length));}"
    "window.addEventListener('error',function(e){n(e.message||'error');});"
    "window.addEventListener('unhandledrejection',function(e){n('unhandled rejection: '+"
    "(e.reason&&e.reason.message||e.reason));});"
    "document.addEventListener('securitypolicyviolation',function(e){n('blocked by the page policy: '+"
    "e.blockedURI);});"
    "var c=console.error;console.error=function(){n(Array.prototype.join.call(arguments,' '));"
    "return c.apply(console,arguments);};})();";

static const char *base_name(const char *path)
{
    const char *s = path ? strrchr(path, '/') : NULL;
    return s ? s + 1 : (path ? path : "");
}

int cli_report_write(cf_context *ctx, const char *html_path, const cli_report_run *run, const cf_mesh *mesh,
                     const double *x0, const double *x1, const char *log_jsonl, const char *log_name,
                     const cli_report_figures *fig)
{
    if (!cli_report_available()) return CLI_EXIT_INPUT;
    int code = CLI_EXIT_OK;
    cli_report_figures own;
    memset(&own, 0, sizeof own);
    if (!fig) {
        if ((code = cli_report_figures_compute(ctx, mesh, x0, x1, &own)) != CLI_EXIT_OK) return code;
        fig = &own;
    }
    json_t *log = NULL;
    if (log_jsonl && (code = parse_log(log_jsonl, log_name ? log_name : "log", &log)) != CLI_EXIT_OK) {
        cli_report_figures_free(&own);
        return code;
    }
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    char title[512];
    if (run->title)
        snprintf(title, sizeof title, "%s", run->title);
    else
        snprintf(title, sizeof title, "curvflow %s: %s", run->method ? run->method : "report",
                 base_name(run->input_path));

    json_t *root = json_object();
    json_object_set_new(root, "format", json_string("curvflow-report-1"));
    json_object_set_new(root, "curvflow", json_string(cf_version_string()));
    json_object_set_new(root, "title", json_string(title));
    json_object_set_new(root, "run", run_json(run));
    json_t *m = json_object();
    json_object_set_new(m, "vertices", json_integer(nv));
    json_object_set_new(m, "faces", json_integer(nf));
    json_object_set_new(m, "genus", json_integer(cf_mesh_genus(mesh)));
    json_object_set_new(m, "boundary_loops", json_integer(cf_mesh_boundary_loop_count(mesh)));
    json_object_set_new(m, "triangles", base64_array(NULL, cf_mesh_triangles(mesh), 3 * (size_t)nf));
    set_positions(m, "input", x0, nv);
    set_positions(m, "result", x1, nv);
    if (cf_mesh_uv(mesh) && cf_mesh_uv_triangles(mesh)) {
        json_object_set_new(m, "uv", base64_array(cf_mesh_uv(mesh), NULL, 2 * (size_t)cf_mesh_uv_count(mesh)));
        json_object_set_new(m, "uv_triangles", base64_array(NULL, cf_mesh_uv_triangles(mesh), 3 * (size_t)nf));
    }
    json_object_set_new(root, "mesh", m);
    json_t *fields = json_object(), *figures = json_object();
    const double four_pi = 4.0 * acos(-1.0);
    if (fig->ok) {
        json_object_set_new(fields, "Q", base64_array(fig->q, NULL, (size_t)nf));
        json_object_set_new(fields, "log_area_distortion", base64_array(fig->log_area, NULL, (size_t)nf));
        json_object_set_new(figures, "willmore_over_4pi",
                            json_pack("[oo]", num(fig->willmore_before / four_pi), num(fig->willmore_after / four_pi)));
        json_object_set_new(figures, "Q", stats_json(&fig->q_stats));
        json_object_set_new(figures, "log_area_distortion", stats_json(&fig->log_area_stats));
    }
    json_object_set_new(root, "fields", fields);
    json_object_set_new(root, "figures", figures);
    json_object_set_new(root, "log", log ? log : json_array());
    /* a base64 string that failed to allocate leaves a NULL member: json_dumps
     * of the whole then still works, so check the pieces that can be NULL */
    bool complete = json_object_get(m, "triangles") && json_object_get(m, "input") && json_object_get(m, "result");
    char *json = complete ? json_dumps(root, JSON_COMPACT | JSON_REAL_PRECISION(17) | JSON_PRESERVE_ORDER) : NULL;
    json_decref(root);
    cli_report_figures_free(&own);
    if (!json) {
        fprintf(stderr, "curvflow: %s: out of memory while writing the report\n", html_path);
        return CLI_EXIT_NUMERICAL;
    }

    buffer b = {0};
    puts_(&b, "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
              "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
              "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; script-src 'unsafe-inline'; "
              "style-src 'unsafe-inline'; img-src data: blob:\">\n"
              "<meta name=\"generator\" content=\"curvflow ");
    put_html_text(&b, cf_version_string());
    puts_(&b, "\">\n<title>");
    put_html_text(&b, title);
    puts_(&b, "</title>\n<script>");
    puts_(&b, error_capture_script);
    puts_(&b, "</script>\n</head>\n<body>\n<noscript>This report is drawn by JavaScript, which is off.</noscript>\n"
              "<script type=\"application/json\" id=\"curvflow-data\">");
    put_json_for_script(&b, json);
    puts_(&b, "</script>\n<script>");
    put(&b, (const char *)cli_report_bundle, cli_report_bundle_size);
    puts_(&b, "</script>\n</body>\n</html>\n");
    free(json);
    if (b.failed) {
        free(b.data);
        fprintf(stderr, "curvflow: %s: out of memory while writing the report\n", html_path);
        return CLI_EXIT_NUMERICAL;
    }
    cf_status st = cf_write_text_file_atomic(ctx, html_path, b.data, b.size);
    free(b.data);
    if (st != CF_OK) {
        code = cli_fail(ctx, html_path, st);
        return code == CLI_EXIT_USAGE ? CLI_EXIT_INPUT : code;
    }
    return CLI_EXIT_OK;
}

/* ---- the step log of flow / edit --report --------------------------------- */

static int read_text(const char *path, char **out)
{
    *out = NULL;
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        fprintf(stderr, "curvflow: %s: cannot open: %s\n", path, strerror(errno));
        return CLI_EXIT_INPUT;
    }
    char *text = NULL;
    size_t size = 0;
    FILE *mem = open_memstream(&text, &size);
    char chunk[1 << 16];
    size_t n;
    bool ok = mem != NULL;
    while (ok && (n = fread(chunk, 1, sizeof chunk, fp)) > 0) ok = fwrite(chunk, 1, n, mem) == n;
    if (ferror(fp)) {
        fprintf(stderr, "curvflow: %s: cannot read: %s\n", path, strerror(errno));
        ok = false;
    }
    fclose(fp);
    if (mem && fclose(mem) != 0) ok = false;
    if (!ok) {
        free(text);
        return CLI_EXIT_INPUT;
    }
    if (strlen(text) != size) {
        fprintf(stderr, "curvflow: %s: contains a NUL byte (not a text file)\n", path);
        free(text);
        return CLI_EXIT_INPUT;
    }
    *out = text;
    return CLI_EXIT_OK;
}

int cli_report_log_capture(cli_report_log *cap, cli_progress *progress, const char *log_path)
{
    memset(cap, 0, sizeof cap[0]);
    if (log_path || progress->log) return CLI_EXIT_OK; /* --log: the report reads the file */
    cap->stream = open_memstream(&cap->text, &cap->size);
    if (!cap->stream) {
        fprintf(stderr, "curvflow: out of memory\n");
        return CLI_EXIT_NUMERICAL;
    }
    cap->progress = progress;
    progress->log = cap->stream;
    progress->log_path = "(the report's step log)";
    return CLI_EXIT_OK;
}

/* Detaches and closes the in-memory log; its text is then complete. */
static void capture_end(cli_report_log *cap)
{
    if (!cap->stream) return;
    if (cap->progress && cap->progress->log == cap->stream) cap->progress->log = NULL;
    fclose(cap->stream);
    cap->stream = NULL;
}

const char *cli_report_log_text(cli_report_log *cap, const char *log_path)
{
    capture_end(cap);
    if (cap->text) return cap->text;
    if (log_path && read_text(log_path, &cap->text) == CLI_EXIT_OK) return cap->text;
    return NULL;
}

void cli_report_log_free(cli_report_log *cap)
{
    capture_end(cap);
    free(cap->text);
    cap->text = NULL;
    cap->size = 0;
}

int cli_report_after_run(cf_context *ctx, const char *report_path, cli_report_run *run, const cf_mesh *mesh,
                         const cf_flow *flow, cli_report_log *cap, int code)
{
    const cf_flow_info *last = cf_flow_last_info(flow);
    run->steps_done = last ? last->iteration : -1;
    run->converged = cf_flow_converged(flow) ? 1 : 0;
    run->exit_status = code;
    const char *msg = cf_context_message(ctx);
    if (code != CLI_EXIT_OK && msg && *msg) run->message = msg;
    const char *log_text = cli_report_log_text(cap, run->log_path);
    int rcode = cli_report_write(ctx, report_path, run, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow),
                                 log_text, run->log_path ? run->log_path : "the step log", NULL);
    if (rcode == CLI_EXIT_OK && !run->quiet) fprintf(stderr, "curvflow: wrote the report %s\n", report_path);
    return code != CLI_EXIT_OK ? code : rcode;
}

/* ---- curvflow report --------------------------------------------------------- */

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: curvflow report IN OUT [--log LOG.jsonl] [--run RUN.json] -o REPORT.html\n"
            "       curvflow report RUN_DIR [-o REPORT.html]\n"
            "Writes one self-contained HTML file (no network access when opened): input IN and\n"
            "result OUT (same connectivity) side by side in an interactive 3D view coloured by the\n"
            "per-face quasi-conformal error Q (1..1.5, blue to red) or log area distortion, W/4pi\n"
            "before and after, the energy and residual curves of the step log (flow --log), and the\n"
            "run's parameters and timings (from RUN.json, as `curvflow demo` writes it).\n"
            "RUN_DIR holds input.obj|ply|off, output.obj|ply|off and optionally log.jsonl and run.json\n"
            "(the demo's output folder); the report goes to RUN_DIR/report.html unless -o is given.\n"
            "flow and edit write the same report with --report FILE.\n\n"
            "  -l, --log FILE     JSONL step log of the run\n"
            "  -r, --run FILE     run description (JSON: method, parameters, timings)\n"
            "  -t, --title TEXT   page title\n"
            "  -o, --output FILE  the HTML file to write\n"
            "  --no-weld          keep boundary vertices that share a position apart and vertices no face\n"
            "                     uses (by default each file's are welded and dropped, as flow does: docs/io.md)\n"
            "  -h, --help         show this help\n\n"
            "Exit status: 0 ok, 1 usage, 2 unreadable / invalid input or unwritable output (also when\n"
            "this curvflow was built without the report viewer: docs/report.md).\n");
}

/* First of DIR/STEM.obj, .ply, .off that exists (malloc'd), or NULL. */
static char *find_in_dir(const char *dir, const char *stem)
{
    static const char *const exts[] = {"obj", "ply", "off"};
    for (size_t i = 0; i < 3; ++i) {
        char *p = NULL;
        if (asprintf(&p, "%s/%s.%s", dir, stem, exts[i]) < 0) return NULL;
        struct stat sb;
        if (stat(p, &sb) == 0 && S_ISREG(sb.st_mode)) return p;
        free(p);
    }
    return NULL;
}

static bool is_dir(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISDIR(sb.st_mode);
}

static bool is_file(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISREG(sb.st_mode);
}

/* Fills run from a run.json text (keys as cli_report_run_json writes them);
 * strings point into *holder, which the caller frees with json_decref. */
static int read_run_json(const char *path, cli_report_run *run, json_t **holder, const char ***extra)
{
    char *text = NULL;
    int code = read_text(path, &text);
    if (code != CLI_EXIT_OK) return code;
    json_error_t err;
    json_t *o = json_loads(text, 0, &err);
    free(text);
    if (!o || !json_is_object(o)) {
        fprintf(stderr, "curvflow: %s:%d: not a run description (%s)\n", path, o ? 1 : err.line,
                o ? "expected a JSON object" : err.text);
        json_decref(o);
        return CLI_EXIT_INPUT;
    }
    *holder = o;
    const char *s;
    if ((s = json_string_value(json_object_get(o, "command")))) run->command = s;
    if ((s = json_string_value(json_object_get(o, "title")))) run->title = s;
    if ((s = json_string_value(json_object_get(o, "method")))) run->method = s;
    json_t *v;
    if (json_is_integer(v = json_object_get(o, "steps_requested"))) run->steps_requested = json_integer_value(v);
    if (json_is_integer(v = json_object_get(o, "steps_done"))) run->steps_done = json_integer_value(v);
    if (json_is_boolean(v = json_object_get(o, "converged"))) run->converged = json_is_true(v);
    if (json_is_integer(v = json_object_get(o, "exit_status"))) run->exit_status = (int)json_integer_value(v);
    if ((s = json_string_value(json_object_get(o, "message")))) run->message = s;
    json_t *sec = json_object_get(o, "seconds");
    if (json_is_number(v = json_object_get(sec, "run"))) run->seconds_run = json_number_value(v);
    if (json_is_number(v = json_object_get(sec, "load"))) run->seconds_load = json_number_value(v);
    json_t *params = json_object_get(o, "parameters");
    size_t n = json_is_array(params) ? json_array_size(params) : 0;
    *extra = calloc(2 * n + 2, sizeof **extra);
    if (!*extra) return CLI_EXIT_NUMERICAL;
    size_t k = 0;
    for (size_t i = 0; i < n; ++i) {
        json_t *pair = json_array_get(params, i);
        const char *name = json_string_value(json_array_get(pair, 0));
        const char *value = json_string_value(json_array_get(pair, 1));
        if (!name || !value) {
            fprintf(stderr, "curvflow: %s: parameter %zu is not a [\"name\", \"value\"] pair\n", path, i + 1);
            return CLI_EXIT_INPUT;
        }
        (*extra)[k++] = name;
        (*extra)[k++] = value;
    }
    run->extra = *extra;
    return CLI_EXIT_OK;
}

int cli_report(int argc, char **argv)
{
    static const struct option longopts[] = {{"log", required_argument, NULL, 'l'},
                                             {"run", required_argument, NULL, 'r'},
                                             {"title", required_argument, NULL, 't'},
                                             {"output", required_argument, NULL, 'o'},
                                             {"help", no_argument, NULL, 'h'},
                                             {"no-weld", no_argument, NULL, 'w'},
                                             {NULL, 0, NULL, 0}};
    const char *cmd = "report";
    const char *log_path = NULL, *run_path = NULL, *title = NULL, *output = NULL;
    int c;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":l:r:t:o:h", longopts, NULL)) != -1) {
        switch (c) {
        case 'l': log_path = optarg; break;
        case 'r': run_path = optarg; break;
        case 't': title = optarg; break;
        case 'o': output = optarg; break;
        case 'w': cli_set_weld(false); break;
        case 'h': usage(stdout); return CLI_EXIT_OK;
        default: return cli_option_error(cmd, c, argv);
        }
    }
    int nargs = argc - optind;
    char *in_path = NULL, *out_path = NULL, *dir_log = NULL, *dir_run = NULL, *dir_html = NULL;
    if (nargs == 1) {
        const char *dir = argv[optind];
        if (!is_dir(dir))
            return cli_usage_error(cmd, "%s is not a directory: give a run directory, or the two meshes IN OUT", dir);
        in_path = find_in_dir(dir, "input");
        out_path = find_in_dir(dir, "output");
        if (!in_path || !out_path) {
            fprintf(stderr, "curvflow: %s: a run directory needs input.obj|ply|off and output.obj|ply|off\n", dir);
            free(in_path);
            free(out_path);
            return CLI_EXIT_INPUT;
        }
        if (asprintf(&dir_log, "%s/log.jsonl", dir) < 0 || asprintf(&dir_run, "%s/run.json", dir) < 0 ||
            asprintf(&dir_html, "%s/report.html", dir) < 0) {
            fprintf(stderr, "curvflow: out of memory\n");
            free(in_path);
            free(out_path);
            free(dir_log);
            free(dir_run);
            return CLI_EXIT_NUMERICAL;
        }
        if (!log_path && is_file(dir_log)) log_path = dir_log;
        if (!run_path && is_file(dir_run)) run_path = dir_run;
        if (!output) output = dir_html;
    } else if (nargs == 2) {
        if (!output) return cli_usage_error(cmd, "missing -o REPORT.html");
    } else {
        return cli_usage_error(cmd, "expected IN OUT (two meshes) or a run directory, got %d arguments", nargs);
    }
    const char *input = in_path ? in_path : argv[optind];
    const char *result = out_path ? out_path : argv[optind + 1];

    int code = CLI_EXIT_OK;
    cf_context *ctx = NULL;
    cf_mesh *a = NULL, *b = NULL;
    char *log_text = NULL;
    json_t *run_holder = NULL;
    const char **extra = NULL;
    if (!cli_report_available()) {
        code = CLI_EXIT_INPUT;
        goto done;
    }
    ctx = cli_context(false);
    if (!ctx) {
        code = CLI_EXIT_NUMERICAL;
        goto done;
    }
    cli_files files = {0};
    cli_files_input(&files, "IN", input);
    cli_files_input(&files, "OUT", result);
    cli_files_input(&files, "--log", log_path);
    cli_files_input(&files, "--run", run_path);
    cli_files_output(&files, "-o", output, CLI_FILE_HTML);
    if ((code = cli_files_check(ctx, &files)) != CLI_EXIT_OK) goto done;
    cli_report_run run;
    cli_report_run_init(&run);
    run.command = "report";
    if (run_path && (code = read_run_json(run_path, &run, &run_holder, &extra)) != CLI_EXIT_OK) goto done;
    if (title) run.title = title;
    run.input_path = input;
    run.output_path = result;
    run.log_path = log_path;
    if ((code = cli_load_mesh(ctx, input, &a)) != CLI_EXIT_OK) goto done;
    if ((code = cli_load_mesh(ctx, result, &b)) != CLI_EXIT_OK) goto done;
    int32_t nv = cf_mesh_vertex_count(a), nf = cf_mesh_face_count(a);
    if (cf_mesh_vertex_count(b) != nv || cf_mesh_face_count(b) != nf ||
        memcmp(cf_mesh_triangles(a), cf_mesh_triangles(b), 3 * (size_t)nf * sizeof(int32_t)) != 0) {
        fprintf(stderr, "curvflow: %s: connectivity differs from %s (%d/%d vertices, %d/%d faces)\n", result, input,
                (int)cf_mesh_vertex_count(b), (int)nv, (int)cf_mesh_face_count(b), (int)nf);
        code = CLI_EXIT_INPUT;
        goto done;
    }
    if (log_path && (code = read_text(log_path, &log_text)) != CLI_EXIT_OK) goto done;
    code = cli_report_write(ctx, output, &run, a, cf_mesh_positions(a), cf_mesh_positions(b), log_text, log_path,
                            NULL);
    if (code == CLI_EXIT_OK) printf("wrote %s\n", output);
done:
    free(log_text);
    free(extra);
    json_decref(run_holder);
    cf_mesh_destroy(&a);
    cf_mesh_destroy(&b);
    cf_context_destroy(&ctx);
    free(in_path);
    free(out_path);
    free(dir_log);
    free(dir_run);
    free(dir_html);
    return code;
}
