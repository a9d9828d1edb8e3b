#include "test.h"

#include "curvflow/io.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int cft_failures = 0;
int cft_checks = 0;
const char *cft_current_test = "";

void cft_fail(const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    ++cft_failures;
    fprintf(stderr, "%s:%d: [%s] ", file, line, cft_current_test);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

int cft_finish(void)
{
    fprintf(stderr, "%d checks, %d failed\n", cft_checks, cft_failures);
    if (cft_checks == 0) {
        fprintf(stderr, "no check ran: a test that checks nothing cannot fail\n");
        return 1;
    }
    return cft_failures == 0 ? 0 : 1;
}

void cft_skip(const char *why)
{
    fprintf(stdout, "SKIP: %s\n", why);
    fprintf(stderr, "SKIP: %s\n", why);
    exit(77);
}

static const char *shared_dir(void)
{
    const char *env = getenv("CURVFLOW_SHARED_DIR");
    return env && *env ? env : CF_TEST_SHARED_DIR;
}

const char *cft_shared_mesh_path(const char *name)
{
    static char path[4096];
    struct stat st;
    snprintf(path, sizeof path, "%s/meshes/%s", shared_dir(), name);
    if (stat(path, &st) != 0) return NULL;
    return path;
}

const char *cft_optional_shared_mesh(const char *name)
{
    const char *p = cft_shared_mesh_path(name);
    if (!p) fprintf(stderr, "SKIP: %s (../shared/meshes absent)\n", name);
    return p;
}

const char *cft_require_shared_mesh(const char *name)
{
    const char *p = cft_shared_mesh_path(name);
    if (!p) {
        static char why[4200];
        snprintf(why, sizeof why, "%s/meshes/%s not found (the shared test data is absent)", shared_dir(), name);
        cft_skip(why);
    }
    return p;
}

const char *cft_temp_path(const char *suffix)
{
    static char path[4096];
    static int counter = 0;
    snprintf(path, sizeof path, "%s/tmp_%ld_%d%s", CF_TEST_BINARY_DIR, (long)getpid(), counter++, suffix);
    return path;
}

static void log_to_stderr(void *user, cf_log_level level, const char *line)
{
    (void)user;
    static const char *names[] = {"debug", "info", "warning", "error"};
    fprintf(stderr, "  [curvflow %s] %s\n", names[level], line);
}

static void log_to_warnings(void *user, cf_log_level level, const char *line)
{
    cft_warnings *w = user;
    if (level != CF_LOG_WARNING) return;
    ++w->count;
    size_t n = strlen(w->text);
    snprintf(w->text + n, sizeof w->text - n, "%s\n", line);
}

void cft_capture_warnings(cf_context *ctx, cft_warnings *w)
{
    w->count = 0;
    w->text[0] = '\0';
    cf_context_set_log(ctx, log_to_warnings, w, CF_LOG_WARNING);
}

const char *const cft_turn_top_handles =
    "{ \"sets\": [ { \"name\": \"base\", \"relative_box\": { \"min\": [0, 0, 0], \"max\": [1, 0.1, 1] }, "
    "\"fixed\": true }, { \"name\": \"top\", \"relative_box\": { \"min\": [0, 0.9, 0], \"max\": [1, 1, 1] }, "
    "\"transform\": { \"rotate\": { \"axis\": [1, 0, 0], \"angle_degrees\": 30 } } } ] }";

void cft_capture_end(cf_context *ctx) { cf_context_set_log(ctx, log_to_stderr, NULL, CF_LOG_WARNING); }

cf_context *cft_context(void)
{
    cf_context *ctx = NULL;
    if (cf_context_create(&ctx) != CF_OK) {
        fprintf(stderr, "cannot create context\n");
        exit(1);
    }
    cf_context_set_log(ctx, log_to_stderr, NULL, CF_LOG_WARNING);
    return ctx;
}

int cft_shared_case_open(cft_shared_case *c, const char *name, int required)
{
    c->ctx = NULL;
    c->mesh = NULL;
    const char *path = required ? cft_require_shared_mesh(name) : cft_optional_shared_mesh(name);
    if (!path) return 0;
    c->ctx = cft_context();
    CHECK_OK(c->ctx, cf_load_mesh(c->ctx, path, &c->mesh));
    if (c->mesh) return 1;
    cft_shared_case_close(c);
    return 0;
}

void cft_shared_case_close(cft_shared_case *c)
{
    cf_mesh_destroy(&c->mesh);
    if (!c->ctx) return;
    CHECK(cf_context_bytes_in_use(c->ctx) == 0);
    cf_context_destroy(&c->ctx);
}

int64_t cft_allocation_sweep(cf_context *ctx, const char *name, cft_alloc_call call, void *user, int may_recover)
{
    size_t base = cf_context_bytes_in_use(ctx);
    int64_t before = cf_context_allocation_count(ctx);
    cf_status s = call(ctx, user);
    ++cft_checks;
    if (s != CF_OK) {
        cft_fail(__FILE__, __LINE__, "%s: unhindered run returned %s: %s", name, cf_status_name(s),
                 cf_context_message(ctx));
        return 0;
    }
    int64_t count = cf_context_allocation_count(ctx) - before;
    ++cft_checks;
    if (cf_context_bytes_in_use(ctx) != base)
        cft_fail(__FILE__, __LINE__, "%s: unhindered run leaked %zu bytes", name, cf_context_bytes_in_use(ctx) - base);
    for (int64_t k = 1; k <= count; ++k) {
        cf_context_fail_allocation(ctx, k, 0);
        s = call(ctx, user);
        cf_context_fail_allocation(ctx, 0, 0);
        ++cft_checks;
        if (s != CF_ERR_NOMEM && !(may_recover && s == CF_OK))
            cft_fail(__FILE__, __LINE__, "%s: failing allocation %lld of %lld gave %s, expected CF_ERR_NOMEM", name,
                     (long long)k, (long long)count, cf_status_name(s));
        ++cft_checks;
        if (cf_context_bytes_in_use(ctx) != base) {
            cft_fail(__FILE__, __LINE__, "%s: failing allocation %lld of %lld leaked %zu bytes", name, (long long)k,
                     (long long)count, cf_context_bytes_in_use(ctx) - base);
            base = cf_context_bytes_in_use(ctx); /* report each leak once */
        }
    }
    fprintf(stderr, "  %-12s %lld allocations, each failure handled\n", name, (long long)count);
    return count;
}

int cft_near(double a, double b, double rtol, double atol)
{
    if (isnan(a) || isnan(b)) return 0;
    double scale = fabs(a) > fabs(b) ? fabs(a) : fabs(b);
    return fabs(a - b) <= atol + rtol * scale;
}

double cft_flow_residual(const cf_flow_info *info, const char *name)
{
    for (int r = 0; r < CF_FLOW_MAX_RESIDUALS; ++r)
        if (info->residual_names[r] && strcmp(info->residual_names[r], name) == 0) return info->residuals[r];
    return NAN;
}
