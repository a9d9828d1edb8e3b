/*
 * The one-file HTML report (cli/cmd_report.c, report/, docs/report.md):
 * `flow --report`, `edit --report`, `curvflow report IN OUT` and
 * `curvflow report RUN_DIR` write a self-contained page whose embedded data
 * are the run's (meshes, per-face Q, the step log read back exactly), and
 * the page works in headless Chromium: it loads with no console error, the
 * curves drawn are the log's values at the axis positions they claim, the
 * WebGL canvas is not blank (screenshot pixels), and the page's security
 * policy blocks any network access.
 *
 * Needs the viewer built into the tool (node + npm at build time) and
 * Debian's chromium for the browser part; without them those parts skip
 * with a visible SKIP line, except under CI (CI set), where they fail.
 */
#define _POSIX_C_SOURCE 200809L
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/ops.h"
#include "cli_test.h"

#include <dirent.h>
#include <jansson.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "png_read.h"

/* Whole file (malloc'd, NUL-terminated) or NULL. */
static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t cap = 1 << 16, n = 0, got;
    char *buf = malloc(cap);
    while (buf && (got = fread(buf + n, 1, cap - n - 1, f)) > 0) {
        n += got;
        if (n + 1 == cap) {
            char *bigger = realloc(buf, 2 * cap);
            if (!bigger) {
                free(buf);
                buf = NULL;
            }
            buf = bigger;
            cap *= 2;
        }
    }
    fclose(f);
    if (buf) buf[n] = '\0';
    return buf;
}

static bool under_ci(void)
{
    const char *ci = getenv("CI");
    return ci && *ci && strcmp(ci, "false") != 0 && strcmp(ci, "0") != 0;
}

/* Without the viewer or the browser the rest cannot run: a visible SKIP on
 * a developer's machine, a failure in CI (which installs both). */
static int skip_rest(const char *why)
{
    if (under_ci()) {
        cft_fail(__FILE__, __LINE__, "%s, and CI must run this test (.ci/run installs nodejs, npm, chromium)", why);
        return cft_finish();
    }
    if (cft_failures > 0) return cft_finish();
    fprintf(stderr, "%d checks before the skip, %d failed\n", cft_checks, cft_failures);
    cft_skip(why);
}

/* The JSON embedded in a report (parsed), or NULL. */
static json_t *report_data(const char *html)
{
    const char *open = "<script type=\"application/json\" id=\"curvflow-data\">";
    const char *a = strstr(html, open);
    if (!a) return NULL;
    a += strlen(open);
    const char *b = strstr(a, "</script>");
    if (!b) return NULL;
    json_error_t err;
    json_t *o = json_loadb(a, (size_t)(b - a), 0, &err);
    if (!o) fprintf(stderr, "embedded JSON: %s at %d\n", err.text, err.position);
    return o;
}

/* The log file's lines as parsed objects. */
static json_t *read_log(const char *name)
{
    char *text = slurp(cft_in_dir(name));
    json_t *arr = json_array();
    for (char *line = text ? strtok(text, "\n") : NULL; line; line = strtok(NULL, "\n"))
        json_array_append_new(arr, json_loads(line, 0, NULL));
    free(text);
    return arr;
}

static int count_substr(const char *s, const char *sub)
{
    int n = 0;
    for (const char *p = strstr(s, sub); p; p = strstr(p + 1, sub)) ++n;
    return n;
}

static void test_usage_and_errors(void)
{
    CHECK_RUN("report --help", 0);
    CHECK(strstr(cft_out, "Usage: curvflow report") != NULL);
    CHECK_RUN("report", 1);
    CHECK(strstr(cft_err, "expected IN OUT") != NULL);
    CHECK_RUN("report a.obj b.obj", 1);
    CHECK(strstr(cft_err, "missing -o REPORT.html") != NULL);
    CHECK_RUN("report a.obj b.obj c.obj -o r.html", 1);
    CHECK_RUN("report nosuchdir", 1);
    CHECK(strstr(cft_err, "not a directory") != NULL);
    CHECK_RUN("report --frob a b", 1);
    CHECK(strstr(cft_err, "unrecognized option '--frob'") != NULL);
    CHECK_RUN("--help", 0);
    CHECK(strstr(cft_out, "report") != NULL);
}

/* The viewer is in the tool when `report` gets past its availability check:
 * with it, a missing input is an input error naming the file; without it,
 * the message says why. */
static bool viewer_built(void)
{
    int rc = cft_run("report missing_a.obj missing_b.obj -o r.html");
    if (strstr(cft_err, "the report viewer is not built into this curvflow") != NULL) {
        ++cft_checks;
        if (rc != 2) cft_fail(__FILE__, __LINE__, "no viewer: exit %d, expected 2", rc);
        fprintf(stderr, "%s", cft_err);
        return false;
    }
    ++cft_checks;
    if (rc != 2 || strstr(cft_err, "missing_a.obj") == NULL)
        cft_fail(__FILE__, __LINE__, "missing input: exit %d (expected 2), stderr %s", rc, cft_err);
    return true;
}

static double num_of(json_t *o, const char *key) { return json_number_value(json_object_get(o, key)); }

/* flow --report on the demo's shape (coarser): a self-contained page whose
 * data are the run's. */
static void test_flow_report_data(void)
{
    CHECK_RUN("generate limb-sphere --subdivisions 3 -o star.obj", 0);
    CHECK_RUN("flow star.obj -o star_out.obj --method spin-willmore --steps 6 --log star.jsonl --report star.html -q",
              0);
    CHECK(cft_exists("star.html"));
    char *html = slurp(cft_in_dir("star.html"));
    CHECK(html != NULL);
    if (!html) return;
    CHECK(strncmp(html, "<!DOCTYPE html>", 15) == 0);
    /* self-contained: nothing is loaded from elsewhere, and the policy says so */
    CHECK(strstr(html, "content=\"default-src 'none'; script-src 'unsafe-inline'") != NULL);
    CHECK(count_substr(html, "<script") == 3); /* error capture, data, viewer */
    CHECK(strstr(html, "<script src") == NULL && strstr(html, "<link") == NULL);
    CHECK(count_substr(html, "</script>") == 3);
    json_t *data = report_data(html);
    free(html);
    CHECK(data != NULL);
    if (!data) return;
    CHECK(strcmp(json_string_value(json_object_get(data, "format")), "curvflow-report-1") == 0);
    json_t *run_info = json_object_get(data, "run");
    CHECK(strcmp(json_string_value(json_object_get(run_info, "method")), "spin-willmore") == 0);
    CHECK(json_integer_value(json_object_get(run_info, "steps_requested")) == 6);
    CHECK(json_integer_value(json_object_get(run_info, "exit_status")) == 0);
    /* every parameter of the method, with its value */
    json_t *params = json_object_get(run_info, "parameters");
    bool has_tau = false;
    for (size_t i = 0; i < json_array_size(params); ++i) {
        json_t *pair = json_array_get(params, i);
        if (strcmp(json_string_value(json_array_get(pair, 0)), "time_step") == 0)
            has_tau = strcmp(json_string_value(json_array_get(pair, 1)), "0.5") == 0;
    }
    CHECK(has_tau);
    CHECK(json_array_size(params) > 10);

    /* the log, exactly: every number of every step */
    json_t *log = read_log("star.jsonl"), *embedded = json_object_get(data, "log");
    CHECK(json_array_size(log) == 7);
    CHECK(json_array_size(embedded) == json_array_size(log));
    for (size_t i = 0; i < json_array_size(log); ++i) CHECK(json_equal(json_array_get(log, i), json_array_get(embedded, i)));

    /* the mesh and the figures are those of the files */
    cf_context *ctx = cft_context();
    cf_mesh *a = NULL, *b = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("star.obj"), &a));
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("star_out.obj"), &b));
    if (a && b) {
        json_t *m = json_object_get(data, "mesh");
        CHECK(json_integer_value(json_object_get(m, "vertices")) == cf_mesh_vertex_count(a));
        CHECK(json_integer_value(json_object_get(m, "faces")) == cf_mesh_face_count(a));
        CHECK(json_is_string(json_object_get(m, "uv"))); /* the star carries texture coordinates */
        /* base64 of 4-byte values: 4 characters per 3 bytes */
        size_t tri_len = strlen(json_string_value(json_object_get(m, "triangles")));
        CHECK(tri_len == 4 * ((12 * (size_t)cf_mesh_face_count(a) + 2) / 3));
        double w0 = 0, w1 = 0;
        CHECK_OK(ctx, cf_willmore_energy(ctx, a, cf_mesh_positions(a), &w0));
        CHECK_OK(ctx, cf_willmore_energy(ctx, b, cf_mesh_positions(b), &w1));
        json_t *fig = json_object_get(data, "figures");
        json_t *w = json_object_get(fig, "willmore_over_4pi");
        const double four_pi = 4.0 * acos(-1.0);
        CHECK_NEAR(json_number_value(json_array_get(w, 0)), w0 / four_pi, 1e-9, 0);
        CHECK_NEAR(json_number_value(json_array_get(w, 1)), w1 / four_pi, 1e-6, 0);
        CHECK(w0 / four_pi > 3.0);       /* the star has curvature to remove */
        CHECK(w1 / four_pi < 1.2);       /* and six steps take it near a sphere */
        /* the last logged energy is the result's W */
        CHECK_NEAR(num_of(json_array_get(log, 6), "energy"), w1, 1e-6, 0);
        cf_stats q;
        CHECK_OK(ctx, cf_quasi_conformal_error(ctx, a, cf_mesh_positions(a), cf_mesh_positions(b), NULL, &q));
        CHECK_NEAR(num_of(json_object_get(fig, "Q"), "mean"), q.weighted_mean, 1e-6, 0);
        CHECK_NEAR(num_of(json_object_get(fig, "Q"), "max"), q.max, 1e-6, 0);
    }
    cf_mesh_destroy(&a);
    cf_mesh_destroy(&b);
    cf_context_destroy(&ctx);
    json_decref(log);
    json_decref(data);

    /* no --log: the steps are still in the report */
    CHECK_RUN("flow star.obj -o star_out2.obj --method implicit-mcf --steps 3 --report nolog.html -q", 0);
    html = slurp(cft_in_dir("nolog.html"));
    data = html ? report_data(html) : NULL;
    free(html);
    CHECK(json_array_size(json_object_get(data, "log")) == 4);
    json_decref(data);
    /* report targets are checked before the run like every output */
    CHECK_RUN("flow star.obj -o star_out3.obj --method implicit-mcf --steps 3 --report r.txt -q", 2);
    CHECK(strstr(cft_err, "unknown report format '.txt'") != NULL);
    CHECK(!cft_exists("star_out3.obj"));
}

/* curvflow report IN OUT and RUN_DIR; edit --report; input errors. */
static void test_report_command(void)
{
    CHECK_RUN("report star.obj star_out.obj --log star.jsonl -o again.html", 0);
    CHECK(strstr(cft_out, "wrote again.html") != NULL);
    char *html = slurp(cft_in_dir("again.html"));
    json_t *data = html ? report_data(html) : NULL;
    free(html);
    CHECK(json_array_size(json_object_get(data, "log")) == 7);
    json_decref(data);

    /* a run directory: the demo's, which also writes run.json */
    CHECK_RUN("demo --output-dir demo --steps 2 --quiet", 0);
    CHECK(strstr(cft_out, "report:              demo/report.html") != NULL);
    CHECK(cft_exists("demo/report.html") && cft_exists("demo/run.json"));
    unlink(cft_in_dir("demo/report.html"));
    CHECK_RUN("report demo", 0);
    CHECK(cft_exists("demo/report.html"));
    html = slurp(cft_in_dir("demo/report.html"));
    data = html ? report_data(html) : NULL;
    free(html);
    json_t *run_info = json_object_get(data, "run");
    CHECK(json_string_value(json_object_get(run_info, "method")) &&
          strcmp(json_string_value(json_object_get(run_info, "method")), "spin-willmore") == 0);
    CHECK(json_integer_value(json_object_get(run_info, "steps_done")) == 2);
    CHECK(json_array_size(json_object_get(data, "log")) == 3);
    json_decref(data);

    /* errors name the file and the place */
    CHECK_RUN("report star.obj demo/output.obj -o x.html", 2);
    CHECK(strstr(cft_err, "connectivity differs") != NULL);
    FILE *f = fopen(cft_in_dir("bad.jsonl"), "w");
    if (f) {
        fputs("{\"iteration\": 0, \"energy\": 1}\nnot json\n", f);
        fclose(f);
    }
    CHECK_RUN("report star.obj star_out.obj --log bad.jsonl -o x.html", 2);
    CHECK(strstr(cft_err, "bad.jsonl:2:") != NULL);
    CHECK(!cft_exists("x.html"));
    CHECK_RUN("report star.obj star_out.obj -o star.obj", 2); /* not an HTML name */
    CHECK_RUN("report star.obj star_out.obj -o nodir/x.html", 2);
    CHECK(strstr(cft_err, "does not exist") != NULL);

    /* edit --report: the energy terms come along */
    CHECK_RUN("generate bar --nx 8 -o bar.obj", 0);
    f = fopen(cft_in_dir("bar.json"), "w");
    if (f) {
        fputs("{\"sets\": [{\"relative_box\": {\"min\": [0, 0, 0], \"max\": [0, 1, 1]}, \"fixed\": true},\n"
              "  {\"relative_box\": {\"min\": [1, 0, 0], \"max\": [1, 1, 1]},\n"
              "   \"transform\": {\"translate\": [0, 2, 0]}}]}\n",
              f);
        fclose(f);
    }
    CHECK_RUN("edit bar.obj --handles bar.json --iterations 5 -o bar_out.obj --report bar.html -q", 0);
    html = slurp(cft_in_dir("bar.html"));
    data = html ? report_data(html) : NULL;
    free(html);
    run_info = json_object_get(data, "run");
    CHECK(json_string_value(json_object_get(run_info, "command")) &&
          strcmp(json_string_value(json_object_get(run_info, "command")), "edit") == 0);
    json_t *first = json_array_get(json_object_get(data, "log"), 0);
    CHECK(json_object_get(json_object_get(first, "terms"), "stretch") != NULL);
    json_decref(data);
}

/* ---- the browser ------------------------------------------------------------ */

static bool have_chromium(void) { return system("command -v chromium > /dev/null 2>&1") == 0; }

/* Runs headless Chromium on a page of the test folder with the flags of
 * docs/report.md, in a new empty profile; `what` is "--dump-dom" or
 * "--screenshot=FILE". stdout (the DOM) and stderr (the browser's log with
 * the page's console lines) land in out_name / err_name. */
static int chromium(const char *page, const char *what, const char *out_name, const char *err_name)
{
    static int profile = 0;
    char profile_dir[64], cmd[4096];
    snprintf(profile_dir, sizeof profile_dir, "chromium-profile-%d", profile++);
    mkdir(cft_in_dir(profile_dir), 0700);
    /* --enable-unsafe-swiftshader: WebGL on the CPU (there is no GPU here),
     * opted into explicitly, as Chromium asks for trusted content */
    snprintf(cmd, sizeof cmd,
             "cd '%s' && timeout 180 chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
             "--disable-background-networking --disable-component-update --disable-sync "
             "--user-data-dir='%s/%s' --enable-unsafe-swiftshader --window-size=1280,900 "
             "--force-device-scale-factor=1 --hide-scrollbars --virtual-time-budget=10000 "
             "--enable-logging=stderr --v=0 %s 'file://%s/%s' > %s 2> %s",
             cft_dir, cft_dir, profile_dir, what, cft_dir, page, out_name, err_name);
    int st = system(cmd);
    return st == -1 || !WIFEXITED(st) ? -1 : WEXITSTATUS(st);
}

/* Console lines of the page in Chromium's log, apart from the GPU driver's
 * performance notes (the screenshot's own read-back stalls the software
 * renderer and says so). */
static int console_problems(const char *log, bool print)
{
    int n = 0;
    for (const char *line = log; line && *line;) {
        const char *end = strchr(line, '\n');
        size_t len = end ? (size_t)(end - line) : strlen(line);
        char buf[2048];
        snprintf(buf, sizeof buf, "%.*s", (int)(len < sizeof buf - 1 ? len : sizeof buf - 1), line);
        if (strstr(buf, ":CONSOLE") && !strstr(buf, "GL Driver Message (OpenGL, Performance")) {
            ++n;
            if (print) fprintf(stderr, "console: %s\n", buf);
        }
        line = end ? end + 1 : NULL;
    }
    return n;
}

/* Value of attribute `name` in the tag starting at `tag` (malloc'd). */
static char *attribute(const char *tag, const char *name)
{
    const char *end = strchr(tag, '>');
    char key[128];
    snprintf(key, sizeof key, " %s=\"", name);
    const char *a = strstr(tag, key);
    if (!a || (end && a > end)) return NULL;
    a += strlen(key);
    const char *b = strchr(a, '"');
    if (!b) return NULL;
    char *v = malloc((size_t)(b - a) + 1);
    memcpy(v, a, (size_t)(b - a));
    v[b - a] = '\0';
    return v;
}

static bool parse_numbers(const char *text, double *out, int count)
{
    for (int i = 0; i < count; ++i) {
        char *end;
        out[i] = strtod(text, &end);
        if (end == text) return false;
        text = *end == ',' ? end + 1 : end;
    }
    return true;
}

/* One chart of the dumped DOM against the log: every curve's values are
 * the log's (key "energy", or an object key such as "residuals") and each
 * drawn point sits where the chart's own axis mapping puts that value. */
static void check_chart(const char *dom, const char *id, json_t *log, const char *object_key, int min_curves)
{
    char key[128];
    snprintf(key, sizeof key, "id=\"%s\"", id);
    const char *at = strstr(dom, key);
    CHECK(at != NULL);
    if (!at) return;
    const char *svg = at;
    while (svg > dom && strncmp(svg, "<svg", 4) != 0) --svg;
    const char *svg_end = strstr(at, "</svg>");
    char *plot_s = attribute(svg, "data-plot"), *xd_s = attribute(svg, "data-x-domain"),
         *yd_s = attribute(svg, "data-y-domain"), *scale = attribute(svg, "data-y-scale");
    double plot[4] = {0}, xd[2] = {0}, yd[2] = {0};
    bool ok = plot_s && xd_s && yd_s && scale && parse_numbers(plot_s, plot, 4) && parse_numbers(xd_s, xd, 2) &&
              parse_numbers(yd_s, yd, 2);
    CHECK(ok);
    bool logy = scale && strcmp(scale, "log") == 0;
    free(plot_s);
    free(xd_s);
    free(yd_s);
    free(scale);
    if (!ok) return;
    int curves = 0;
    for (const char *p = strstr(svg, "<path "); p && p < svg_end; p = strstr(p + 1, "<path ")) {
        char *name = attribute(p, "data-series"), *values_s = attribute(p, "data-values"), *d = attribute(p, "d");
        if (!name) {
            free(values_s);
            free(d);
            continue;
        }
        json_t *values = values_s ? json_loads(values_s, 0, NULL) : NULL;
        CHECK(json_array_size(values) == json_array_size(log));
        const char *dp = d;
        int drawn = 0, drawable = 0;
        for (size_t i = 0; i < json_array_size(values) && i < json_array_size(log); ++i) {
            json_t *step = json_array_get(log, i);
            json_t *expected = object_key ? json_object_get(json_object_get(step, object_key), name)
                                          : json_object_get(step, name);
            json_t *got = json_array_get(values, i);
            /* the log's number, to the last bit (JSON round trip of a double) */
            ++cft_checks;
            if (json_is_number(expected) != json_is_number(got) ||
                (json_is_number(got) && json_number_value(got) != json_number_value(expected)))
                cft_fail(__FILE__, __LINE__, "%s %s step %zu: drawn %.17g, log %.17g", id, name, i,
                         json_number_value(got), json_number_value(expected));
            double v = json_number_value(got);
            if (!json_is_number(got) || (logy && !(v > 0))) continue; /* a gap in the curve */
            ++drawable;
            /* the next point of the path */
            while (dp && *dp && *dp != 'M' && *dp != 'L') ++dp;
            double xy[2];
            if (!dp || !*dp || !parse_numbers(dp + 1, xy, 2)) {
                CHECK(false);
                break;
            }
            ++dp;
            ++drawn;
            double it = json_number_value(json_object_get(step, "iteration"));
            double ex = plot[0] + (it - xd[0]) / (xd[1] - xd[0]) * (plot[2] - plot[0]);
            double t = logy ? (log10(v) - log10(yd[0])) / (log10(yd[1]) - log10(yd[0])) : (v - yd[0]) / (yd[1] - yd[0]);
            double ey = plot[3] - t * (plot[3] - plot[1]);
            CHECK_NEAR(xy[0], ex, 0, 0.006); /* the path keeps two decimals */
            CHECK_NEAR(xy[1], ey, 0, 0.006);
            CHECK(xy[1] >= plot[1] - 0.01 && xy[1] <= plot[3] + 0.01); /* inside the plot */
        }
        /* one point per drawable value and no other */
        while (dp && *dp && *dp != 'M' && *dp != 'L') ++dp;
        ++cft_checks;
        if (drawn != drawable || (dp && *dp))
            cft_fail(__FILE__, __LINE__, "%s: curve %s has %d points for %d values%s", id, name, drawn, drawable,
                     dp && *dp ? " and more" : "");
        if (drawable > 0) ++curves;
        json_decref(values);
        free(name);
        free(values_s);
        free(d);
    }
    ++cft_checks;
    if (curves < min_curves) cft_fail(__FILE__, __LINE__, "%s: %d curves drawn, expected >= %d", id, curves, min_curves);
}

static void test_browser_page(void)
{
    int rc = chromium("star.html", "--dump-dom", "dom.html", "dom.log");
    CHECK(rc == 0);
    char *dom = slurp(cft_in_dir("dom.html")), *blog = slurp(cft_in_dir("dom.log"));
    CHECK(dom != NULL && blog != NULL);
    if (!dom || !blog) {
        free(dom);
        free(blog);
        return;
    }
    CHECK(strstr(dom, "data-curvflow-ready=\"1\"") != NULL);
    CHECK(strstr(dom, "data-curvflow-errors=\"0\"") != NULL);
    CHECK(console_problems(blog, true) == 0);
    CHECK(strstr(dom, "<canvas") != NULL);
    CHECK(strstr(dom, "data-curvflow-mode=\"q\"") != NULL); /* Q colours first */
    CHECK(strstr(dom, "≥ 1.5") != NULL);                     /* and its colour bar */
    json_t *log = read_log("star.jsonl");
    check_chart(dom, "cf-chart-energy", log, NULL, 1);
    check_chart(dom, "cf-chart-residuals", log, "residuals", 3);
    json_decref(log);
    free(dom);
    free(blog);
}

/* The canvas rectangle the page reports, in CSS pixels (= screenshot pixels
 * at device scale factor 1). */
static bool canvas_rect(int r[4])
{
    char *dom = slurp(cft_in_dir("dom.html"));
    char *rect = dom ? attribute(strstr(dom, "<html"), "data-curvflow-canvas") : NULL;
    double v[4];
    bool ok = rect && parse_numbers(rect, v, 4);
    for (int i = 0; ok && i < 4; ++i) r[i] = (int)v[i];
    free(rect);
    free(dom);
    return ok && r[2] > 100 && r[3] > 100;
}

static void test_browser_screenshot(void)
{
    int r[4];
    CHECK(canvas_rect(r));
    int rc = chromium("star.html", "--screenshot=shot.png", "shot.out", "shot.log");
    CHECK(rc == 0);
    char *blog = slurp(cft_in_dir("shot.log"));
    CHECK(blog && console_problems(blog, true) == 0);
    free(blog);
    int w = 0, h = 0;
    unsigned char *img = cft_png_load_rgb(cft_in_dir("shot.png"), &w, &h);
    CHECK(img != NULL);
    if (!img || !canvas_rect(r)) {
        cft_png_free(img);
        return;
    }
    CHECK(w == 1280 && h == 900);
    CHECK(r[0] + r[2] <= w && r[1] + r[3] <= h);
    /* each half of the canvas (input, result) shows a shape: not a uniform
     * picture, many colours (shading and the Q map), a fair share of
     * non-background pixels */
    for (int half = 0; half < 2; ++half) {
        int x0 = r[0] + half * r[2] / 2, x1 = r[0] + (half + 1) * r[2] / 2;
        long shape = 0, total = 0;
        int lo = 255, hi = 0;
        static unsigned char seen[1 << 15];
        memset(seen, 0, sizeof seen);
        int colours = 0;
        for (int y = r[1]; y < r[1] + r[3] && y < h; ++y)
            for (int x = x0; x < x1 && x < w; ++x) {
                const unsigned char *p = img + 3 * ((size_t)y * w + x);
                int lum = (p[0] + p[1] + p[2]) / 3;
                lo = lum < lo ? lum : lo;
                hi = lum > hi ? lum : hi;
                shape += lum < 240;
                ++total;
                int key = (p[0] >> 3) << 10 | (p[1] >> 3) << 5 | (p[2] >> 3);
                if (!seen[key]) {
                    seen[key] = 1;
                    ++colours;
                }
            }
        fprintf(stderr, "canvas half %d: %ld of %ld pixels drawn, luminance %d..%d, %d colours\n", half, shape,
                total, lo, hi, colours);
        CHECK(hi - lo > 80);
        CHECK(shape > total / 20);
        CHECK(colours > 50);
    }
    cft_png_free(img);
}

/* The checks above can fail: a page whose data are broken reports its
 * error, and the page policy blocks (and reports) any network access. */
static void test_browser_catches_problems(void)
{
    char *html = slurp(cft_in_dir("star.html"));
    CHECK(html != NULL);
    if (!html) return;
    char *fmt = strstr(html, "curvflow-report-1");
    CHECK(fmt != NULL);
    FILE *f = fopen(cft_in_dir("broken.html"), "w");
    if (f && fmt) {
        fwrite(html, 1, (size_t)(fmt - html), f);
        fputs("curvflow-report-0", f);
        fputs(fmt + strlen("curvflow-report-1"), f);
        fclose(f);
    }
    /* a page that tries to fetch: an image from the loopback address (nothing
     * listens there, and the policy stops the request before it is made) */
    char *body = strstr(html, "<body>");
    f = fopen(cft_in_dir("fetching.html"), "w");
    if (f && body) {
        fwrite(html, 1, (size_t)(body - html) + 6, f);
        fputs("<img src=\"http://127.0.0.1:9/x.png\" alt=\"\">", f);
        fputs(body + 6, f);
        fclose(f);
    }
    free(html);
    chromium("broken.html", "--dump-dom", "broken.dom", "broken.log");
    char *dom = slurp(cft_in_dir("broken.dom")), *blog = slurp(cft_in_dir("broken.log"));
    CHECK(dom && strstr(dom, "data-curvflow-errors=\"0\"") == NULL && strstr(dom, "could not be shown") != NULL);
    CHECK(blog && console_problems(blog, false) >= 1);
    free(dom);
    free(blog);
    chromium("fetching.html", "--dump-dom", "fetching.dom", "fetching.log");
    dom = slurp(cft_in_dir("fetching.dom"));
    CHECK(dom && strstr(dom, "data-curvflow-ready=\"1\"") != NULL && strstr(dom, "data-curvflow-errors=\"0\"") == NULL);
    free(dom);
}

/* The float32 values of a base64 string (malloc'd; *n set), NULL if malformed. */
static float *decode_f32(const char *b64, size_t *n)
{
    static const char alphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t len = strlen(b64), bytes = 0;
    unsigned char *raw = malloc(len);
    if (!raw) return NULL;
    uint32_t acc = 0;
    int bits = 0;
    for (size_t k = 0; k < len && b64[k] != '='; ++k) {
        const char *at = strchr(alphabet, b64[k]);
        if (!at) {
            free(raw);
            return NULL;
        }
        acc = (acc << 6) | (uint32_t)(at - alphabet);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            raw[bytes++] = (unsigned char)(acc >> bits);
        }
    }
    *n = bytes / 4;
    float *out = malloc(sizeof(float) * (*n > 0 ? *n : 1));
    for (size_t i = 0; out && i < *n; ++i) {
        uint32_t u = (uint32_t)raw[4 * i] | (uint32_t)raw[4 * i + 1] << 8 | (uint32_t)raw[4 * i + 2] << 16 |
                     (uint32_t)raw[4 * i + 3] << 24;
        memcpy(&out[i], &u, 4);
    }
    free(raw);
    return out;
}

/* Largest |offset + value - x| over a mesh's positions as the report holds
 * them (mesh.<name> float32 relative to mesh.<name>_offset); -1 if absent. */
static double report_position_error(json_t *m, const char *name, const double *x, int32_t nv)
{
    char key[64];
    snprintf(key, sizeof key, "%s_offset", name);
    json_t *off = json_object_get(m, key);
    const char *b64 = json_string_value(json_object_get(m, name));
    if (!json_is_array(off) || json_array_size(off) != 3 || !b64) return -1.0;
    size_t n = 0;
    float *f = decode_f32(b64, &n);
    if (!f || n != 3 * (size_t)nv) {
        free(f);
        return -1.0;
    }
    double err = 0.0;
    for (size_t i = 0; i < n; ++i)
        err = fmax(err, fabs(json_number_value(json_array_get(off, i % 3)) + (double)f[i] - x[i]));
    free(f);
    return err;
}

/* A mesh far from the origin (a georeferenced scan) keeps its shape in the
 * report: float32 holds ~7 digits, so raw coordinates near 1e6 were
 * rounded to steps of 0.0625 (the star below is 2.5 across);
 * the positions are stored relative to their bounding box's centre, the
 * centre beside them. Read back: within 1e-6 of the star's size, at the
 * origin and 1e6 away alike. */
static void test_report_positions(void)
{
    CHECK_RUN("generate limb-sphere --subdivisions 3 -o near.obj", 0);
    cf_context *ctx = cft_context();
    cf_mesh *near = NULL, *far = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("near.obj"), &near));
    if (!near) return;
    int32_t nv = cf_mesh_vertex_count(near);
    double *x = malloc(sizeof(double) * 3 * (size_t)nv);
    const double *x0 = cf_mesh_positions(near);
    for (int32_t i = 0; i < 3 * nv; ++i) x[i] = x0[i] + (i % 3 == 1 ? -2e6 : 1e6);
    CHECK_OK(ctx, cf_write_mesh_file(ctx, cft_in_dir("far.obj"), near, x, NULL, 0));
    CHECK_RUN("report far.obj far.obj -o far.html", 0);
    CHECK_RUN("report near.obj near.obj -o near.html", 0);
    CHECK_OK(ctx, cf_load_mesh(ctx, cft_in_dir("far.obj"), &far));
    const char *pages[2] = {"near.html", "far.html"};
    const cf_mesh *meshes[2] = {near, far};
    for (int k = 0; k < 2 && far; ++k) {
        char *html = slurp(cft_in_dir(pages[k]));
        json_t *data = html ? report_data(html) : NULL;
        free(html);
        CHECK(data != NULL);
        if (!data) continue;
        json_t *m = json_object_get(data, "mesh");
        const double *xs = cf_mesh_positions(meshes[k]);
        double e_in = report_position_error(m, "input", xs, nv), e_out = report_position_error(m, "result", xs, nv);
        fprintf(stderr, "   %s: largest error of the positions read back %.3g / %.3g\n", pages[k], e_in, e_out);
        CHECK(e_in >= 0.0 && e_out >= 0.0);
        CHECK_LE(e_in, 2.5e-6);
        CHECK_LE(e_out, 2.5e-6);
        json_decref(data);
    }
    free(x);
    cf_mesh_destroy(&far);
    cf_mesh_destroy(&near);
    cf_context_destroy(&ctx);
}

int main(void)
{
    if (cft_cli_setup("report")) return 1;
    CFT_RUN(test_usage_and_errors);
    if (!viewer_built()) return skip_rest("the report viewer is not built into this curvflow (node and npm at build time)");
    CFT_RUN(test_flow_report_data);
    CFT_RUN(test_report_command);
    CFT_RUN(test_report_positions);
    if (!have_chromium()) return skip_rest("chromium is not installed (apt-get install chromium): no browser test");
    CFT_RUN(test_browser_page);
    CFT_RUN(test_browser_screenshot);
    CFT_RUN(test_browser_catches_problems);
    return cft_cli_finish();
}
