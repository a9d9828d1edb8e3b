/*
 * Tiny test harness. A test file defines static void functions and a main
 * that runs them with CFT_RUN; checks print file:line and both values and
 * count failures; main returns cft_finish().
 *
 *   static void test_sum(void) { CHECK_NEAR(1.0 + 1e-12, 1.0, 1e-9, 0.0); }
 *   int main(void) { CFT_RUN(test_sum); return cft_finish(); }
 *
 * Tests needing ../shared/meshes call cft_shared_mesh_path(), which returns
 * NULL when the folder is absent, and then cft_skip("why") which prints a
 * visible SKIP line and exits with 77 (CTest's skip code here).
 */
#ifndef CF_TESTS_SUPPORT_TEST_H
#define CF_TESTS_SUPPORT_TEST_H

#include "curvflow/curvflow.h"
#include "curvflow/flow.h"
#include "curvflow/mesh.h"

#include <math.h>
#include <stdio.h>

extern int cft_failures;
extern int cft_checks;
extern const char *cft_current_test;

void cft_fail(const char *file, int line, const char *fmt, ...);
int cft_finish(void);
/* Prints "SKIP: <why>" and exits with 77. */
_Noreturn void cft_skip(const char *why);
/* Full path of ../shared/meshes/<name> (static buffer), or NULL if the
 * shared folder is absent. */
const char *cft_shared_mesh_path(const char *name);
/* Like cft_shared_mesh_path, but when the mesh is absent prints the visible
 * line "SKIP: <name> (../shared/meshes absent)" so that the calling test can
 * return while the rest of the program runs. */
const char *cft_optional_shared_mesh(const char *name);
/* Like cft_shared_mesh_path but skips the whole test program when absent. */
const char *cft_require_shared_mesh(const char *name);
/* Temporary file path in the build tree (static buffer, unique per call). */
const char *cft_temp_path(const char *suffix);
/* The residual a step reported under this name (cf_flow_info.residual_names),
 * NaN when the step has none of that name. */
double cft_flow_residual(const cf_flow_info *info, const char *name);

/* 1 in an AddressSanitizer build (the tests that leave out large meshes or
 * address-space limits there), else 0. */
#if defined(__SANITIZE_ADDRESS__)
#define CFT_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CFT_UNDER_ASAN 1
#endif
#endif
#ifndef CFT_UNDER_ASAN
#define CFT_UNDER_ASAN 0
#endif
/* A context that prints library log lines to stderr. */
cf_context *cft_context(void);
/* The library's warnings collected as lines of text: cft_capture_warnings
 * empties w and sends ctx's warnings to it, cft_capture_end sends them to
 * stderr again (as cft_context does). */
typedef struct cft_warnings {
    int count;
    char text[4096];
} cft_warnings;
void cft_capture_warnings(cf_context *ctx, cft_warnings *w);
void cft_capture_end(cf_context *ctx);
/* An edit's handle file (docs/edit.md) that fits every mesh: relative
 * boxes, the lowest tenth in y fixed, the highest turned 30 degrees about
 * x (the zoo's edit rows, the ARAP weight test). */
extern const char *const cft_turn_top_handles;
/* A test case on one mesh of ../shared/meshes: a new context (cft_context)
 * with the mesh loaded. cft_shared_case_open returns 0, with nothing left to
 * close, when the mesh is absent (with `required` the whole program skips,
 * else a SKIP line is printed) or did not load (a failed check);
 * cft_shared_case_close destroys the mesh, checks that the context holds no
 * bytes any more and destroys it. */
typedef struct cft_shared_case {
    cf_context *ctx;
    cf_mesh *mesh;
} cft_shared_case;
int cft_shared_case_open(cft_shared_case *c, const char *name, int required);
void cft_shared_case_close(cft_shared_case *c);
/* Failure-injection sweep (STYLE.md sec. 4, as CHOLMOD's Tcov/t_memory.c).
 * `call` must free everything it creates and return the library's status
 * (and turn "failed but left an output object" into an error of its own).
 * The sweep runs it once unhindered (must return CF_OK), then once for each
 * allocation k of that run with the k-th allocation failing: every run must
 * return CF_ERR_NOMEM (or CF_OK when may_recover, for calls into a library
 * that retries, e.g. CHOLMOD trying several orderings) and leave
 * cf_context_bytes_in_use unchanged. Each failure is a test failure naming
 * `name` and k. Returns the number of allocations of the unhindered run. */
typedef cf_status (*cft_alloc_call)(cf_context *ctx, void *user);
int64_t cft_allocation_sweep(cf_context *ctx, const char *name, cft_alloc_call call, void *user, int may_recover);

/* true if |a - b| <= atol + rtol * max(|a|, |b|) */
int cft_near(double a, double b, double rtol, double atol);

#define CFT_RUN(fn) \
    do { cft_current_test = #fn; fprintf(stderr, "-- %s\n", #fn); fn(); } while (0)

#define CHECK(cond) \
    do { ++cft_checks; if (!(cond)) cft_fail(__FILE__, __LINE__, "CHECK(%s) failed", #cond); } while (0)

#define CHECK_NEAR(a, b, rtol, atol) \
    do { \
        ++cft_checks; \
        double cft_a_ = (double)(a), cft_b_ = (double)(b); \
        if (!cft_near(cft_a_, cft_b_, (rtol), (atol))) \
            cft_fail(__FILE__, __LINE__, "CHECK_NEAR(%s, %s): %.17g vs %.17g (diff %.3g, rtol %g, atol %g)", \
                     #a, #b, cft_a_, cft_b_, fabs(cft_a_ - cft_b_), (double)(rtol), (double)(atol)); \
    } while (0)

#define CHECK_LE(a, b) \
    do { \
        ++cft_checks; \
        double cft_a_ = (double)(a), cft_b_ = (double)(b); \
        if (!(cft_a_ <= cft_b_)) cft_fail(__FILE__, __LINE__, "CHECK_LE(%s, %s): %.17g > %.17g", #a, #b, cft_a_, cft_b_); \
    } while (0)

#define CHECK_STATUS(expr, expected) \
    do { \
        ++cft_checks; \
        cf_status cft_s_ = (expr); \
        if (cft_s_ != (expected)) \
            cft_fail(__FILE__, __LINE__, "%s returned %s, expected %s", #expr, cf_status_name(cft_s_), \
                     cf_status_name(expected)); \
    } while (0)

/* For calls that must succeed; prints the context message on failure. */
#define CHECK_OK(ctx, expr) \
    do { \
        ++cft_checks; \
        cf_status cft_s_ = (expr); \
        if (cft_s_ != CF_OK) \
            cft_fail(__FILE__, __LINE__, "%s returned %s: %s", #expr, cf_status_name(cft_s_), \
                     cf_context_message(ctx)); \
    } while (0)

#endif /* CF_TESTS_SUPPORT_TEST_H */
