/*
 * Isometric curve flow (Crane, Pinkall, Schroeder 2013, Sec. 5, Fig. 9-11):
 * a noisy closed polyline flows to a circle while keeping its edge lengths
 * and turning number; the closure gap before the Poisson projection is
 * second order in the time step.
 */
#include "test.h"

#include "curvflow/curve_flow.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* n points on a blob r = 1 + 0.25 sin 3t with deterministic radial noise
 * and uneven angular spacing. */
static void noisy_circle(int32_t n, double noise, double *p)
{
    uint32_t s = 12345u;
    for (int32_t i = 0; i < n; ++i) {
        s = s * 1664525u + 1013904223u;
        double t0 = 2.0 * PI * i / n;
        double r = 1.0 + 0.25 * sin(3.0 * t0) + noise * ((double)(s >> 8) / 16777216.0 - 0.5);
        double t = 2.0 * PI * (i + 0.3 * sin(3.0 * i)) / n;
        p[2 * i] = r * cos(t);
        p[2 * i + 1] = r * sin(t);
    }
}

/* Radial deviation from the best centroid circle, relative. */
static double circle_deviation(int32_t n, const double *p)
{
    double c[2] = {0, 0}, rm = 0.0, dev = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        c[0] += p[2 * i] / n;
        c[1] += p[2 * i + 1] / n;
    }
    for (int32_t i = 0; i < n; ++i) rm += hypot(p[2 * i] - c[0], p[2 * i + 1] - c[1]) / n;
    for (int32_t i = 0; i < n; ++i) dev = fmax(dev, fabs(hypot(p[2 * i] - c[0], p[2 * i + 1] - c[1]) - rm) / rm);
    return dev;
}

/* Fig. 9: flows to a round circle, lengths kept to 1e-3 per step at tau = 0.5,
 * turning number kept, constraints <kappadot, {1, x, y}> = 0 to round-off. */
static void test_noisy_polyline_to_circle(void)
{
    cf_context *ctx = cft_context();
    int32_t n = 200;
    double *p = malloc(2 * (size_t)n * sizeof(double));
    noisy_circle(n, 0.005, p);
    double dev0 = circle_deviation(n, p);
    cf_curve_flow_options o;
    cf_curve_flow_options_default(&o);
    CHECK_NEAR(o.time_step, 0.5, 0, 0);
    cf_curve_flow *flow = NULL;
    CHECK_OK(ctx, cf_curve_flow_create(ctx, n, p, &o, &flow));
    double e0 = cf_curve_flow_energy(flow);
    double eprev = e0;
    double prev[400];
    for (int step = 0; step < 10 && flow; ++step) {
        memcpy(prev, cf_curve_flow_points(flow), sizeof prev);
        cf_curve_flow_info info;
        CHECK_OK(ctx, cf_curve_flow_step(flow, &info));
        /* per-step length change relative to the previous step's lengths */
        const double *q = cf_curve_flow_points(flow);
        double worst = 0.0;
        for (int32_t i = 0; i < n; ++i) {
            int32_t j = (i + 1) % n;
            double l0 = hypot(prev[2 * j] - prev[2 * i], prev[2 * j + 1] - prev[2 * i + 1]);
            double l1 = hypot(q[2 * j] - q[2 * i], q[2 * j + 1] - q[2 * i + 1]);
            worst = fmax(worst, fabs(l1 - l0) / l0);
        }
        if (step == 0) fprintf(stderr, "   step 1: max relative edge length change %.3g\n", worst);
        CHECK_LE(worst, 1e-3);
        CHECK(info.turning_number == 1);
        CHECK_LE(info.constraint_residual, 1e-10);
        CHECK_LE(info.energy, eprev * (1.0 + 1e-12));
        eprev = info.energy;
    }
    double dev = circle_deviation(n, cf_curve_flow_points(flow));
    fprintf(stderr, "   energy %.4f -> %.6f, circle deviation %.3g -> %.3g\n", e0, eprev, dev0, dev);
    /* a circle of the same length L has E = (2 pi)^2 / L */
    double length = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        int32_t j = (i + 1) % n;
        length += hypot(p[2 * j] - p[2 * i], p[2 * j + 1] - p[2 * i + 1]);
    }
    CHECK_NEAR(eprev, 4.0 * PI * PI / length, 2e-3, 0.0);
    CHECK_LE(dev, 2e-3);
    cf_curve_flow_destroy(&flow);
    free(p);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Fig. 11: the closure gap of one step converges quadratically in tau
 * (the constraints remove the first-order part, App. A). */
static void test_closure_gap_quadratic(void)
{
    cf_context *ctx = cft_context();
    int32_t n = 200;
    double *p = malloc(2 * (size_t)n * sizeof(double));
    noisy_circle(n, 0.3, p);
    double gaps[4];
    double tau = 0.2;
    for (int k = 0; k < 4; ++k, tau *= 0.5) {
        cf_curve_flow_options o = {tau};
        cf_curve_flow *flow = NULL;
        CHECK_OK(ctx, cf_curve_flow_create(ctx, n, p, &o, &flow));
        cf_curve_flow_info info;
        CHECK_OK(ctx, cf_curve_flow_step(flow, &info));
        gaps[k] = info.closure_gap;
        cf_curve_flow_destroy(&flow);
    }
    for (int k = 0; k < 3; ++k) {
        double rate = log2(gaps[k] / gaps[k + 1]);
        fprintf(stderr, "   gap %.3g -> %.3g: order %.3f\n", gaps[k], gaps[k + 1], rate);
        CHECK(rate > 1.7 && rate < 2.3);
    }
    free(p);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* A figure-eight keeps turning number 0; a doubly wound circle keeps 2. */
static void test_turning_number_kept(void)
{
    cf_context *ctx = cft_context();
    int32_t n = 120;
    double p[240];
    for (int32_t i = 0; i < n; ++i) {
        double t = 2.0 * PI * i / n;
        p[2 * i] = sin(t) * (1.0 + 0.05 * cos(5 * t));
        p[2 * i + 1] = sin(t) * cos(t);
    }
    cf_curve_flow *flow = NULL;
    CHECK_OK(ctx, cf_curve_flow_create(ctx, n, p, NULL, &flow));
    cf_curve_flow_info info = {0};
    for (int s = 0; s < 5; ++s) CHECK_OK(ctx, cf_curve_flow_step(flow, &info));
    CHECK(info.turning_number == 0);
    cf_curve_flow_destroy(&flow);
    for (int32_t i = 0; i < n; ++i) {
        double t = 4.0 * PI * i / n;
        double r = 1.0 + 0.2 * (double)i / n;   /* a spiral closing on itself: two turns */
        p[2 * i] = r * cos(t);
        p[2 * i + 1] = r * sin(t);
    }
    CHECK_OK(ctx, cf_curve_flow_create(ctx, n, p, NULL, &flow));
    for (int s = 0; s < 5; ++s) CHECK_OK(ctx, cf_curve_flow_step(flow, &info));
    CHECK(info.turning_number == 2);
    cf_curve_flow_destroy(&flow);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_invalid_input(void)
{
    cf_context *ctx = cft_context();
    cf_curve_flow *flow = NULL;
    double p[6] = {0, 0, 1, 0, 1, 0};
    CHECK_STATUS(cf_curve_flow_create(ctx, 3, p, NULL, &flow), CF_ERR_DEGENERATE_FACE);
    CHECK(strstr(cf_context_message(ctx), "edge 1") != NULL);
    CHECK_STATUS(cf_curve_flow_create(ctx, 2, p, NULL, &flow), CF_ERR_INVALID_ARG);
    p[0] = NAN;
    CHECK_STATUS(cf_curve_flow_create(ctx, 3, p, NULL, &flow), CF_ERR_NONFINITE);
    CHECK(flow == NULL);
    /* the library's range of lengths, 1e-50 .. 1e50 (CF_MAX_COORDINATE, curvflow.h) */
    double far[6] = {0, 0, 1e60, 0, 0, 1};
    CHECK_STATUS(cf_curve_flow_create(ctx, 3, far, NULL, &flow), CF_ERR_NONFINITE);
    CHECK(strstr(cf_context_message(ctx), "point 1: coordinate 1e+60 is out of range") != NULL);
    double tiny[6] = {0, 0, 1e-60, 0, 0, 1e-60};
    CHECK_STATUS(cf_curve_flow_create(ctx, 3, tiny, NULL, &flow), CF_ERR_DEGENERATE_FACE);
    CHECK(strstr(cf_context_message(ctx), "edge 0 (points 0, 1): length 1e-60 is below 1e-50") != NULL);
    CHECK(flow == NULL);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Above the stability limit (tau ~ 1, Sec. 4) the explicit step on kappa
 * overshoots: at tau 1.5 the energy of a noisy circle went 38 -> 134 -> 522
 * -> ... and the turning number wandered (1, 0, 3, 2) while every step
 * reported success. Now the first such step fails with CF_ERR_NUMERICAL,
 * names the iteration and leaves the curve as it was; tau 0.99 still runs.
 * A 180 degree turn (no signed angle) is refused at creation. */
static void test_divergence_detected(void)
{
    cf_context *ctx = cft_context();
    enum { N = 64 };
    double p[2 * N], before[2 * N];
    noisy_circle(N, 0.05, p);
    cf_curve_flow_options o;
    cf_curve_flow_options_default(&o);
    o.time_step = 1.5;
    cf_curve_flow *flow = NULL;
    CHECK_OK(ctx, cf_curve_flow_create(ctx, N, p, &o, &flow));
    if (!flow) return;
    memcpy(before, cf_curve_flow_points(flow), sizeof before);
    double e0 = cf_curve_flow_energy(flow);
    CHECK_STATUS(cf_curve_flow_step(flow, NULL), CF_ERR_NUMERICAL);
    fprintf(stderr, "   %s\n", cf_context_message(ctx));
    CHECK(strstr(cf_context_message(ctx), "iteration 1: ") == cf_context_message(ctx));
    CHECK(strstr(cf_context_message(ctx), "diverges") != NULL || strstr(cf_context_message(ctx), "turning number") != NULL);
    CHECK(memcmp(before, cf_curve_flow_points(flow), sizeof before) == 0);
    CHECK(cf_curve_flow_energy(flow) == e0);
    cf_curve_flow_destroy(&flow);

    o.time_step = 0.99;
    CHECK_OK(ctx, cf_curve_flow_create(ctx, N, p, &o, &flow));
    if (!flow) return;
    for (int s = 0; s < 20; ++s) CHECK_OK(ctx, cf_curve_flow_step(flow, NULL));
    CHECK(cf_curve_flow_energy(flow) < e0);
    cf_curve_flow_destroy(&flow);

    const double back[8] = {0, 0, 1, 0, 2, 0, 1, 1e-3}; /* sharp turns, none of exactly 180 degrees */
    CHECK_OK(ctx, cf_curve_flow_create(ctx, 4, back, NULL, &flow));
    cf_curve_flow_destroy(&flow);
    const double reverse[6] = {0, 0, 1, 0, 2, 0}; /* out and back along a line */
    CHECK_STATUS(cf_curve_flow_create(ctx, 3, reverse, NULL, &flow), CF_ERR_DEGENERATE_FACE);
    CHECK(strstr(cf_context_message(ctx), "turns back on itself") != NULL);
    CHECK(flow == NULL);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Inside that range the flow is scale-free: a copy scaled by 1e+-45 flows to
 * the unit result, scaled (to 1e-12 of the size). */
static void test_scale_invariance(void)
{
    cf_context *ctx = cft_context();
    enum { N = 64 };
    double p[2 * N], q[2 * N], ref[2 * N];
    noisy_circle(N, 0.05, p);
    const double scales[] = {1.0, 1e45, 1e-45};
    for (int t = 0; t < 3; ++t) {
        for (int i = 0; i < 2 * N; ++i) q[i] = scales[t] * p[i];
        cf_curve_flow *flow = NULL;
        CHECK_OK(ctx, cf_curve_flow_create(ctx, N, q, NULL, &flow));
        if (!flow) continue;
        for (int s = 0; s < 10; ++s) CHECK_OK(ctx, cf_curve_flow_step(flow, NULL));
        const double *x = cf_curve_flow_points(flow);
        if (t == 0) memcpy(ref, x, sizeof ref);
        double worst = 0.0;
        for (int i = 0; i < 2 * N; ++i) worst = fmax(worst, fabs(x[i] / scales[t] - ref[i]));
        CHECK_LE(worst, 1e-12);
        cf_curve_flow_destroy(&flow);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* CSV and SVG round trips, and the SVG path subset (absolute + relative). */
static void test_files(void)
{
    cf_context *ctx = cft_context();
    double p[8] = {0, 0, 2, 0, 2, 1, 0, 1};
    const char *csv = cft_temp_path(".csv");
    CHECK_OK(ctx, cf_curve_write(ctx, csv, 4, p));
    cf_curve *c = NULL;
    CHECK_OK(ctx, cf_curve_read(ctx, csv, &c));
    CHECK(c && c->count == 4);
    for (int i = 0; c && i < 8; ++i) CHECK_NEAR(c->points[i], p[i], 0, 0);
    cf_curve_destroy(&c);
    const char *svg = cft_temp_path(".svg");
    CHECK_OK(ctx, cf_curve_write(ctx, svg, 4, p));
    CHECK_OK(ctx, cf_curve_read(ctx, svg, &c));
    CHECK(c && c->count == 4);
    for (int i = 0; c && i < 8; ++i) CHECK_NEAR(c->points[i], p[i], 0, 0);
    cf_curve_destroy(&c);
    const char *path = cft_temp_path(".svg");
    FILE *fp = fopen(path, "w");
    fprintf(fp, "<svg><path fill=\"none\" d=\"M 0,0 h 2 v 1 L 0 1 z\"/></svg>\n");
    fclose(fp);
    CHECK_OK(ctx, cf_curve_read(ctx, path, &c));
    CHECK(c && c->count == 4);
    for (int i = 0; c && i < 8; ++i) CHECK_NEAR(c->points[i], p[i], 0, 0);
    cf_curve_destroy(&c);
    fp = fopen(path, "w");
    fprintf(fp, "<svg><path d=\"M0 0 R 1 1 2 2 3 3\"/></svg>\n");
    fclose(fp);
    CHECK_STATUS(cf_curve_read(ctx, path, &c), CF_ERR_PARSE);
    CHECK(strstr(cf_context_message(ctx), "unsupported path command 'R'") != NULL);
    CHECK_STATUS(cf_curve_read(ctx, cft_temp_path(".csv"), &c), CF_ERR_IO);
    /* from memory (the fuzz targets' entry): same parse, messages name the
     * given name; a NUL byte is refused rather than silently ending the text */
    const char svg_text[] = "<svg><path fill=\"none\" d=\"M 0,0 h 2 v 1 L 0 1 z\"/></svg>";
    CHECK_OK(ctx, cf_curve_read_memory(ctx, svg_text, sizeof svg_text - 1, 1, "mem.svg", &c));
    CHECK(c && c->count == 4);
    for (int i = 0; c && i < 8; ++i) CHECK_NEAR(c->points[i], p[i], 0, 0);
    cf_curve_destroy(&c);
    const char csv_text[] = "x,y\n0,0\n2,0\n2,1\n0,1\n";
    CHECK_OK(ctx, cf_curve_read_memory(ctx, csv_text, sizeof csv_text - 1, 0, NULL, &c));
    CHECK(c && c->count == 4);
    cf_curve_destroy(&c);
    const char with_nul[] = "0,0\n1,0\0\n1,1\n";
    CHECK_STATUS(cf_curve_read_memory(ctx, with_nul, sizeof with_nul - 1, 0, "nul.csv", &c), CF_ERR_PARSE);
    CHECK(strstr(cf_context_message(ctx), "nul.csv: line 2: NUL byte at offset 7") != NULL);
    CHECK_STATUS(cf_curve_read_memory(ctx, "0,0\n1,x\n", 8, 0, "bad.csv", &c), CF_ERR_PARSE);
    CHECK(strstr(cf_context_message(ctx), "bad.csv:2:") != NULL);
    CHECK(c == NULL);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Reads svg from memory; returns the status, the points in *c. */
static cf_status read_svg(cf_context *ctx, const char *svg, cf_curve **c, cft_warnings *log)
{
    cft_capture_warnings(ctx, log);
    cf_status st = cf_curve_read_memory(ctx, svg, strlen(svg), 1, "t.svg", c);
    cft_capture_end(ctx);
    return st;
}

/* An SVG text the reader refuses, and the part of the message that says why. */
typedef struct svg_refusal {
    const char *svg, *message;
} svg_refusal;

/* Each case refused (parse or range error, no curve) with its message. */
static void expect_refused(cf_context *ctx, const svg_refusal *cases, size_t n)
{
    cft_warnings log;
    for (size_t i = 0; i < n; ++i) {
        cf_curve *c = NULL;
        cf_status st = read_svg(ctx, cases[i].svg, &c, &log);
        CHECK(st == CF_ERR_PARSE || st == CF_ERR_NONFINITE);
        CHECK(c == NULL);
        cf_curve_destroy(&c);
        int named = strstr(cf_context_message(ctx), cases[i].message) != NULL;
        if (!named) fprintf(stderr, "   case %zu: '%s'\n", i, cf_context_message(ctx));
        CHECK(named);
    }
}

static int points_are(const cf_curve *c, int32_t n, const double *xy, double tol)
{
    if (!c || c->count != n) return 0;
    for (int32_t i = 0; i < 2 * n; ++i)
        if (!(fabs(c->points[i] - xy[i]) <= tol)) return 0;
    return 1;
}

/* The SVG subset as drawing programs write it (session 29: a <g transform>
 * was ignored, so scale(2, 1) gave a square instead of a 2 x 1 rectangle;
 * a shape inside a comment was read; a path's second subpath and every
 * shape after the first vanished without a word; a <polygon> anywhere
 * took precedence over an earlier <path>). */
static void test_svg_reader(void)
{
    cf_context *ctx = cft_context();
    cf_curve *c = NULL;
    cft_warnings log;
    /* transforms of the ancestors and the element, composed as SVG does:
     * the unit square under translate(10 20) scale(2, 1) rotate(90) */
    const char *nested = "<?xml version=\"1.0\"?>\n"
                         "<!DOCTYPE svg PUBLIC \"-//W3C//DTD SVG 1.1//EN\" \"x.dtd\" [ <!ENTITY e \"v\"> ]>\n"
                         "<svg xmlns=\"http://www.w3.org/2000/svg\">\n"
                         "<!-- <polygon points=\"9,9 8,8 7,9\"/> -->\n"
                         "<defs><polygon points=\"0,0 5,0 0,5\"/></defs>\n"
                         "<g transform=\"translate(10 20) scale(2, 1)\"><g transform='rotate(90)'>\n"
                         "<polygon points=\"0,0 1,0 1,1 0,1\"/></g></g>\n"
                         "</svg>\n";
    const double rotated[8] = {10, 20, 10, 21, 8, 21, 8, 20};
    CHECK_OK(ctx, read_svg(ctx, nested, &c, &log));
    CHECK(points_are(c, 4, rotated, 1e-14));
    CHECK(log.text[0] == '\0');
    cf_curve_destroy(&c);
    /* every transform function, on the element itself: matrix, rotate about
     * a point, skewX, skewY */
    const char *each = "<svg><path transform=\"matrix(1 0 0 1 5 0) rotate(180 0.5 0.5) skewX(45) skewY(0)\" "
                       "d=\"M0,0 L1,0 L1,1 Z\"/></svg>";
    /* skewX(45): (x + y, y); rotate 180 about (0.5, 0.5): (1 - x, 1 - y); then x + 5 */
    const double each_xy[6] = {6, 1, 5, 1, 4, 0};
    CHECK_OK(ctx, read_svg(ctx, each, &c, &log));
    CHECK(points_are(c, 3, each_xy, 1e-14));
    cf_curve_destroy(&c);
    /* document order, and a warning for what is not read */
    const char *two = "<svg>\n<path d=\"M 0 0 h 1 v 1 z m 5 5 h 1 v 1 z\"/>\n<polygon points=\"0,0 3,0 3,3\"/>\n"
                      "<polyline points=\"0,0 4,0 4,4\"/></svg>";
    const double first[6] = {0, 0, 1, 0, 1, 1};
    CHECK_OK(ctx, read_svg(ctx, two, &c, &log));
    CHECK(points_are(c, 3, first, 0.0));
    fprintf(stderr, "   warnings: %s", log.text);
    CHECK(strstr(log.text, "t.svg: line 2: the <path> holds more than one subpath") != NULL);
    CHECK(strstr(log.text, "t.svg: 3 shapes are drawn; the first, the <path> of line 2, is read and the others are "
                           "ignored") != NULL);
    cf_curve_destroy(&c);
    /* what is refused, and how */
    static const svg_refusal bad[] = {
        {"<svg><!-- <polygon points=\"0,0 1,0 1,1\"/>", "t.svg: line 1: comment not closed (no '-->')"},
        {"<svg>\n<polygon points=\"0,0 1,0 1,1\"", "t.svg: line 2: malformed or unclosed tag <polygon"},
        {"<svg><defs><polygon points=\"0,0 1,0 1,1\"/></defs></svg>",
         "t.svg: no drawn <polygon>, <polyline>, <path>, <rect>, <circle> or <ellipse> (1 inside defs"},
        {"<svg><g transform=\"shear(2)\"><polygon points=\"0,0 1,0 1,1\"/></g></svg>",
         "t.svg: line 1: unsupported transform near \"shear(2)\""},
        {"<svg><polygon transform=\"rotate(1, 2)\" points=\"0,0 1,0 1,1\"/></svg>",
         "t.svg: line 1: rotate() takes 1 or 3 arguments, got 2"},
        {"<svg><polygon transform=\"scale(1e300)\" points=\"0,0 1,0 1,1\"/></svg>", "out of range"},
    };
    expect_refused(ctx, bad, sizeof bad / sizeof bad[0]);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Largest |distance of a point from (cx, cy) - r| */
static double radial_error(const cf_curve *c, double cx, double cy, double r)
{
    double worst = 0.0;
    for (int32_t i = 0; i < c->count; ++i)
        worst = fmax(worst, fabs(hypot(c->points[2 * i] - cx, c->points[2 * i + 1] - cy) - r));
    return worst;
}

/* Twice the signed area (positive: counter-clockwise with y up). */
static double signed_area2(const cf_curve *c)
{
    double a = 0.0;
    for (int32_t i = 0; i < c->count; ++i) {
        int32_t j = (i + 1) % c->count;
        a += c->points[2 * i] * c->points[2 * j + 1] - c->points[2 * j] * c->points[2 * i + 1];
    }
    return a;
}

/* Index of the point (x, y) to within tol, or -1. */
static int32_t find_point(const cf_curve *c, double x, double y, double tol)
{
    for (int32_t i = 0; i < c->count; ++i)
        if (fabs(c->points[2 * i] - x) <= tol && fabs(c->points[2 * i + 1] - y) <= tol) return i;
    return -1;
}

/* Largest distance of a chord's midpoint from the circle (cx, cy, r): the
 * flattening's error for a circle drawn with curves. */
static double chord_sagitta(const cf_curve *c, double cx, double cy, double r)
{
    double worst = 0.0;
    for (int32_t i = 0; i < c->count; ++i) {
        int32_t j = (i + 1) % c->count;
        double mx = 0.5 * (c->points[2 * i] + c->points[2 * j]), my = 0.5 * (c->points[2 * i + 1] + c->points[2 * j + 1]);
        worst = fmax(worst, fabs(hypot(mx - cx, my - cy) - r));
    }
    return worst;
}

/* Curves as drawing programs write them (Inkscape's paths are cubic
 * Beziers; its circles and rectangles are <circle> and <rect>): flattened
 * into points on the curve, within 1e-3 of each segment's size between
 * them (session 31; before, "unsupported path command 'c'"). */
static void test_svg_curves(void)
{
    cf_context *ctx = cft_context();
    cf_curve *c = NULL;
    cft_warnings log;
    /* a circle of radius 2 about (1, 1) as four cubics (kappa 0.5522847498,
     * radial error 2.7e-4 of r), three by S, whose first control point is
     * the previous one reflected: every point on the cubics, so within
     * that of the circle, and the chords within 1e-3 of each cubic's
     * control polygon (3.49) */
    const char *cubics = "<svg><path d=\"M3,1 C3,2.1045695 2.1045695,3 1,3 S-1,2.1045695 -1,1 "
                         "s0.8954305,-2 2,-2 S3,-0.1045695 3,1 Z\"/></svg>";
    CHECK_OK(ctx, read_svg(ctx, cubics, &c, &log));
    CHECK(c && c->count >= 40 && c->count <= 100);
    if (c) {
        CHECK(radial_error(c, 1.0, 1.0, 2.0) < 6e-4);
        CHECK(chord_sagitta(c, 1.0, 1.0, 2.0) < 6e-4 + 3.5e-3);
        CHECK(signed_area2(c) > 0.0); /* (3,1) -> (1,3) -> (-1,1): counter-clockwise with y up */
    }
    cf_curve_destroy(&c);
    /* Q and T: T's control point is the previous one reflected, so the
     * second segment is (2,0) (3,-1) (4,0); its middle, (3, -0.5), is a
     * sample (14 pieces each) */
    CHECK_OK(ctx, read_svg(ctx, "<svg><path d=\"M0,0 Q1,1 2,0 T4,0 L2,-3 Z\"/></svg>", &c, &log));
    CHECK(c && find_point(c, 1.0, 0.5, 1e-12) > 0 && find_point(c, 3.0, -0.5, 1e-12) > 0);
    CHECK(c && find_point(c, 4.0, 0.0, 0.0) > 0 && find_point(c, 2.0, -3.0, 0.0) == c->count - 1);
    cf_curve_destroy(&c);
    /* arcs: two half circles, end points as written and every point on the
     * circle; sweep 1 turns the positive way (y down on the screen:
     * clockwise there, counter-clockwise in these coordinates) */
    CHECK_OK(ctx, read_svg(ctx, "<svg><path d=\"M3,1 A2,2 0 0 1 -1,1 A2,2 0 0 1 3,1 Z\"/></svg>", &c, &log));
    CHECK(c && c->count >= 60 && radial_error(c, 1.0, 1.0, 2.0) < 1e-12 && signed_area2(c) > 0.0);
    CHECK(c && chord_sagitta(c, 1.0, 1.0, 2.0) <= 2e-3 && find_point(c, -1.0, 1.0, 0.0) > 0);
    cf_curve_destroy(&c);
    /* the four arcs from (3,1) to (1,3) on circles of radius 2: large-arc and
     * sweep flags choose the centre and the way, as SVG defines them; the
     * same written compactly (flags without separators, relative) */
    static const struct {
        const char *d;
        double cx, cy, quarter; /* centre, and how many quarter turns */
    } arcs[] = {{"M3,1 A2,2 0 0 1 1,3 L1,1 Z", 1.0, 1.0, 1.0},  {"M3,1 A2,2 0 1 1 1,3 L3,3 Z", 3.0, 3.0, 3.0},
                {"M3,1 A2,2 0 0 0 1,3 L3,3 Z", 3.0, 3.0, 1.0},  {"M3,1 A2,2 0 1 0 1,3 L1,1 Z", 1.0, 1.0, 3.0},
                {"M3,1a2,2,0,01-2,2L1,1z", 1.0, 1.0, 1.0}};
    int32_t quarter_count = 0;
    for (size_t i = 0; i < sizeof arcs / sizeof arcs[0]; ++i) {
        char svg[128];
        snprintf(svg, sizeof svg, "<svg><path d=\"%s\"/></svg>", arcs[i].d);
        CHECK_OK(ctx, read_svg(ctx, svg, &c, &log));
        if (!c) continue;
        /* the arc's points: all but the closing corner */
        int32_t on = 0;
        for (int32_t k = 0; k < c->count; ++k)
            on += fabs(hypot(c->points[2 * k] - arcs[i].cx, c->points[2 * k + 1] - arcs[i].cy) - 2.0) < 1e-12;
        CHECK(on == c->count - 1);
        if (arcs[i].quarter == 1.0 && i == 0) quarter_count = c->count;
        if (arcs[i].quarter == 1.0) CHECK(c->count == quarter_count);
        else CHECK(c->count >= 3 * (quarter_count - 2));
        cf_curve_destroy(&c);
    }
    /* radii too small for the end points grow until they fit (a half
     * circle about the chord's middle); a zero radius is a line; a rotated
     * ellipse's points satisfy its equation */
    CHECK_OK(ctx, read_svg(ctx, "<svg><path d=\"M0,0 A1,1 0 0 1 4,0 A0,2 0 0 1 0,0\"/></svg>", &c, &log));
    CHECK(c && radial_error(c, 2.0, 0.0, 2.0) < 1e-12 && c->count > 30);
    cf_curve_destroy(&c);
    CHECK_OK(ctx, read_svg(ctx, "<svg><path d=\"M0,0 A2,1 30 1 1 0.5,0.2 Z\"/></svg>", &c, &log));
    if (c) {
        /* the centre from the first, a middle and the last point is not
         * needed: every point is at unit "ellipse distance" from the centre
         * the arc's middle points share; measured through the two axes */
        double phi = 30.0 * PI / 180.0, worst = 0.0;
        /* centre by least squares would be circular; use SVG's formulas'
         * invariant instead: all points p satisfy q(p - c) = 1 for one c,
         * so q(p_i - c) - q(p_j - c) = 0; c from three points */
        double ux = cos(phi), uy = sin(phi);
        double px[3], py[3];
        int32_t pick[3] = {1, c->count / 2, c->count - 2};
        for (int k = 0; k < 3; ++k) {
            double x = c->points[2 * pick[k]], y = c->points[2 * pick[k] + 1];
            px[k] = (x * ux + y * uy) / 2.0; /* scaled to the unit circle */
            py[k] = (-x * uy + y * ux) / 1.0;
        }
        /* circumcentre of the three scaled points */
        double d = 2.0 * (px[0] * (py[1] - py[2]) + px[1] * (py[2] - py[0]) + px[2] * (py[0] - py[1]));
        double s0 = px[0] * px[0] + py[0] * py[0], s1 = px[1] * px[1] + py[1] * py[1], s2 = px[2] * px[2] + py[2] * py[2];
        double ccx = (s0 * (py[1] - py[2]) + s1 * (py[2] - py[0]) + s2 * (py[0] - py[1])) / d;
        double ccy = (s0 * (px[2] - px[1]) + s1 * (px[0] - px[2]) + s2 * (px[1] - px[0])) / d;
        for (int32_t k = 0; k < c->count; ++k) {
            double x = c->points[2 * k], y = c->points[2 * k + 1];
            worst = fmax(worst, fabs(hypot((x * ux + y * uy) / 2.0 - ccx, (-x * uy + y * ux) - ccy) - 1.0));
        }
        CHECK(worst < 1e-9);
        CHECK(c->count > 50); /* the large arc */
    }
    cf_curve_destroy(&c);
    /* basic shapes, with their transforms: a circle from (cx + r, cy) on, an
     * ellipse, a rectangle's four corners, rounded corners (one radius given
     * stands for both; clamped to half the side) */
    CHECK_OK(ctx, read_svg(ctx, "<svg><circle cx=\"1\" cy=\"2px\" r=\" 3 \"/></svg>", &c, &log));
    CHECK(c && c->count >= 60 && radial_error(c, 1.0, 2.0, 3.0) < 1e-12 && find_point(c, 4.0, 2.0, 0.0) == 0);
    CHECK(c && chord_sagitta(c, 1.0, 2.0, 3.0) <= 3e-3);
    cf_curve_destroy(&c);
    CHECK_OK(ctx, read_svg(ctx, "<svg><g transform=\"translate(5,0)\"><ellipse rx=\"2\" ry=\"1\"/></g></svg>", &c, &log));
    if (c) {
        double worst = 0.0;
        for (int32_t k = 0; k < c->count; ++k)
            worst = fmax(worst, fabs(hypot((c->points[2 * k] - 5.0) / 2.0, c->points[2 * k + 1]) - 1.0));
        CHECK(worst < 1e-12 && find_point(c, 7.0, 0.0, 0.0) == 0);
    }
    cf_curve_destroy(&c);
    const double corners[8] = {1, 2, 5, 2, 5, 5, 1, 5};
    CHECK_OK(ctx, read_svg(ctx, "<svg><rect x=\"1\" y=\"2\" width=\"4\" height=\"3\"/></svg>", &c, &log));
    CHECK(points_are(c, 4, corners, 0.0));
    cf_curve_destroy(&c);
    CHECK_OK(ctx, read_svg(ctx, "<svg><rect x=\"1\" y=\"2\" width=\"4\" height=\"3\" ry=\"1\"/></svg>", &c, &log));
    if (c) {
        CHECK(find_point(c, 2.0, 2.0, 0.0) == 0 && find_point(c, 4.0, 2.0, 0.0) == 1 && find_point(c, 5.0, 3.0, 0.0) > 1);
        CHECK(radial_error(c, 4.0, 3.0, 1.0) > 0.5); /* not all on one corner, but each arc point on its corner's circle */
        int32_t on_corners = 0;
        for (int32_t k = 0; k < c->count; ++k) {
            double x = c->points[2 * k], y = c->points[2 * k + 1];
            double kx = x < 3.0 ? 2.0 : 4.0, ky = y < 3.5 ? 3.0 : 4.0;
            on_corners += fabs(hypot(x - kx, y - ky) - 1.0) < 1e-12;
        }
        CHECK(on_corners == c->count); /* the sides' ends are the arcs' ends */
        CHECK(signed_area2(c) > 0.0);
    }
    cf_curve_destroy(&c);
    /* rx 10 on a 4 x 2 rect: a stadium (rx 2, ry 1), no repeated point */
    CHECK_OK(ctx, read_svg(ctx, "<svg><rect width=\"4\" height=\"2\" rx=\"10\"/></svg>", &c, &log));
    if (c) {
        int repeated = 0;
        for (int32_t k = 0; k < c->count; ++k) {
            int32_t j = (k + 1) % c->count;
            repeated += c->points[2 * k] == c->points[2 * j] && c->points[2 * k + 1] == c->points[2 * j + 1];
        }
        CHECK(repeated == 0 && c->count > 40);
        double worst = 0.0;
        for (int32_t k = 0; k < c->count; ++k)
            worst = fmax(worst, fabs(hypot((c->points[2 * k] - 2.0) / 2.0, c->points[2 * k + 1] - 1.0) - 1.0));
        CHECK(worst < 1e-12); /* the ellipse inscribed in the rect */
    }
    cf_curve_destroy(&c);
    /* the first drawn shape is read, whatever its kind */
    CHECK_OK(ctx, read_svg(ctx, "<svg>\n<rect width=\"4\" height=\"3\"/>\n<path d=\"M0,0 L1,0 L1,1 Z\"/></svg>", &c, &log));
    CHECK(c && c->count == 4 && strstr(log.text, "the first, the <rect> of line 2, is read") != NULL);
    cf_curve_destroy(&c);
    /* what is refused, and how */
    static const svg_refusal bad[] = {
        {"<svg><circle r=\"0\"/></svg>", "t.svg: line 1: <circle> needs r > 0 (got 0): it draws nothing"},
        {"<svg><ellipse rx=\"1\"/></svg>", "<ellipse> needs ry > 0"},
        {"<svg><rect width=\"5mm\" height=\"1\"/></svg>", "<rect> width=\"5mm\" is not a number in user units"},
        {"<svg><rect width=\"50%\" height=\"1\"/></svg>", "<rect> width=\"50%\" is not a number"},
        {"<svg><rect width=\"1\" height=\"1\" rx=\"-1\"/></svg>", "<rect> rx is negative"},
        {"<svg><circle r=\"1e400\"/></svg>", "is not a number in user units"},
        {"<svg><circle r=\"1e60\"/></svg>", "out of range"},
        {"<svg><path d=\"M0 0 A1 1 0 2 1 1 1\"/></svg>", "t.svg: arc flag must be 0 or 1 near \"2 1 1 1\""},
        {"<svg><path d=\"M0 0 C1 1 2 2\"/></svg>", "t.svg: path command 'C' takes 6 numbers; too few near \"\""},
        {"<svg><path d=\"M0 0 q1\"/></svg>", "path command 'q' takes 4 numbers"},
        {"<svg><path d=\"M0 0 C1 1 2 2 3 nan 4 4\"/></svg>", "not finite"},
    };
    expect_refused(ctx, bad, sizeof bad / sizeof bad[0]);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_noisy_polyline_to_circle);
    CFT_RUN(test_closure_gap_quadratic);
    CFT_RUN(test_turning_number_kept);
    CFT_RUN(test_invalid_input);
    CFT_RUN(test_scale_invariance);
    CFT_RUN(test_divergence_detected);
    CFT_RUN(test_files);
    CFT_RUN(test_svg_reader);
    CFT_RUN(test_svg_curves);
    return cft_finish();
}
