/*
 * OpenBLAS's kernels (cf_blas_core, cf_blas_core_advice, cli/blas_kernels.c;
 * docs/linalg.md, "OpenBLAS's kernels"). OpenBLAS falls back to its generic
 * SSE3 "Prescott" kernels on a CPU model it does not know; the advice then
 * names the kernels the CPU can run, and the tool (and every program of the
 * project, this test included) runs again with them. Checked:
 *   - the advice is NULL whenever OPENBLAS_CORETYPE is set, whatever its value;
 *   - on the fallback (forced here with OPENBLAS_CORETYPE=Prescott in a child
 *     run of this program, which then clears the variable and asks), the
 *     advice is SkylakeX on an AVX-512 CPU, Haswell on an AVX2 + FMA one,
 *     NULL on an older one;
 *   - the tool, started without the variable, never runs the Prescott
 *     kernels on a CPU with AVX2, and runs the same kernels as this process
 *     (the condition for the bit-for-bit equalities of the other tests);
 *   - a user's OPENBLAS_CORETYPE stands, Prescott included.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli_test.h"

#include "curvflow/curvflow.h"
#include "curvflow/linalg.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define CHILD_FLAG "--advice-on-the-fallback"

/* CHECK with a message (printf-style arguments after the condition) */
#define CHECK_SAY(cond, ...)                                                \
    do {                                                                    \
        ++cft_checks;                                                       \
        if (!(cond)) cft_fail(__FILE__, __LINE__, __VA_ARGS__);             \
    } while (0)

/* The kernels the CPU can run, best first, as cf_blas_core_advice's
 * contract names them; NULL for none better than SSE3. */
static const char *expected_advice(void)
{
#if defined(__x86_64__) && defined(__GNUC__)
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
        __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
        __builtin_cpu_supports("avx512vl"))
        return "SkylakeX";
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return "Haswell";
#endif
    return NULL;
}

static int cpu_has_avx2(void)
{
#if defined(__x86_64__) && defined(__GNUC__)
    return __builtin_cpu_supports("avx2");
#else
    return 0;
#endif
}

/* The kernels named by `curvflow --version`'s second line, or "" if none. */
static const char *version_kernels(void)
{
    static char name[64];
    name[0] = '\0';
    const char *line = strstr(cft_out, "OpenBLAS kernels: ");
    if (line) sscanf(line + strlen("OpenBLAS kernels: "), "%63s", name);
    return name;
}

static void test_advice_respects_the_variable(void)
{
    const char *saved = getenv("OPENBLAS_CORETYPE");
    char keep[64] = "";
    if (saved) snprintf(keep, sizeof keep, "%s", saved);
    const char *values[] = {"Prescott", "SkylakeX", "no-such-core"};
    for (int i = 0; i < 3; ++i) {
        setenv("OPENBLAS_CORETYPE", values[i], 1);
        CHECK_SAY(cf_blas_core_advice() == NULL, "advice with OPENBLAS_CORETYPE=%s", values[i]);
    }
    if (saved) setenv("OPENBLAS_CORETYPE", keep, 1);
    else unsetenv("OPENBLAS_CORETYPE");
}

static void test_advice_on_the_fallback(void)
{
    char self[1024];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    CHECK_SAY(n > 0, "readlink /proc/self/exe");
    if (n <= 0) return;
    self[n] = '\0';
    char command[1200];
    snprintf(command, sizeof command, "OPENBLAS_CORETYPE=Prescott '%s' " CHILD_FLAG, self);
    CHECK_SAY(cft_shell(command) == 0, "child run: %s", cft_err);
    char core[64] = "", advice[64] = "";
    CHECK_SAY(sscanf(cft_out, "core %63s advice %63s", core, advice) == 2, "child printed '%s'", cft_out);
    const char *want = expected_advice();
    CHECK_SAY(strcmp(core, "Prescott") == 0, "forced kernels: %s", core);
    CHECK_SAY(strcmp(advice, want ? want : "none") == 0, "advice on the fallback: %s, expected %s", advice,
          want ? want : "none");
}

static void test_tool_runs_the_fast_kernels(void)
{
    /* in this test's environment (which may hold a user's choice): the same kernels as this process */
    CHECK_SAY(cft_shell("'" CF_TEST_CLI "' --version") == 0, "%s", cft_err);
    const char *mine = cf_blas_core();
    CHECK_SAY(mine != NULL, "this process runs OpenBLAS");
    CHECK_SAY(version_kernels()[0] != '\0', "--version names the kernels: '%s'", cft_out);
    if (mine) CHECK_SAY(strcmp(version_kernels(), mine) == 0, "tool %s, this test %s", version_kernels(), mine);
    /* without a choice in the environment: never the fallback on an AVX2 CPU */
    CHECK_SAY(cft_shell("env -u OPENBLAS_CORETYPE '" CF_TEST_CLI "' --version") == 0, "%s", cft_err);
    if (cpu_has_avx2())
        CHECK_SAY(strcmp(version_kernels(), "Prescott") != 0, "the tool runs Prescott on an AVX2 CPU");
}

static void test_users_choice_stands(void)
{
    CHECK_SAY(cft_shell("OPENBLAS_CORETYPE=Prescott '" CF_TEST_CLI "' --version") == 0, "%s", cft_err);
    CHECK_SAY(strcmp(version_kernels(), "Prescott") == 0, "kernels '%s'", cft_out);
    CHECK_SAY(strstr(cft_out, "(OPENBLAS_CORETYPE)") != NULL, "said why: '%s'", cft_out);
}

/* A 2 x 2 Cholesky factorisation: it makes this program use CHOLMOD, hence
 * OpenBLAS, as the tool does (a program that uses no BLAS does not load it,
 * and cf_blas_core is then NULL); 1 if it worked. */
static int factorise_something(void)
{
    cf_context *ctx = NULL;
    cf_sparse *a = NULL;
    cf_cholesky *chol = NULL;
    const int32_t rows[] = {0, 0, 1, 1}, cols[] = {0, 1, 0, 1};
    const double vals[] = {4.0, 1.0, 1.0, 3.0}, b[] = {1.0, 2.0};
    double x[2] = {0.0, 0.0};
    int ok = cf_context_create(&ctx) == CF_OK && cf_sparse_from_triplets(ctx, 2, 2, 4, rows, cols, vals, 1, &a, NULL) == CF_OK &&
             cf_cholesky_create(ctx, a, NULL, &chol) == CF_OK && cf_cholesky_factorize(chol, a) == CF_OK &&
             cf_cholesky_solve(chol, 1, b, x) == CF_OK;
    cf_cholesky_destroy(&chol);
    cf_sparse_destroy(&a);
    cf_context_destroy(&ctx);
    return ok && fabs(4.0 * x[0] + x[1] - 1.0) < 1e-12 && fabs(x[0] + 3.0 * x[1] - 2.0) < 1e-12;
}

int main(int argc, char **argv)
{
    if (!factorise_something()) {
        fprintf(stderr, "a 2 x 2 factorisation failed\n");
        return 1;
    }
    if (argc == 2 && strcmp(argv[1], CHILD_FLAG) == 0) {
        /* OpenBLAS loaded with the Prescott kernels; without the variable,
         * what would the advice be? */
        unsetenv("OPENBLAS_CORETYPE");
        const char *core = cf_blas_core(), *advice = cf_blas_core_advice();
        printf("core %s advice %s\n", core ? core : "none", advice ? advice : "none");
        return 0;
    }
    if (cft_cli_setup("blas_kernels")) return 1;
    CFT_RUN(test_advice_respects_the_variable);
    CFT_RUN(test_advice_on_the_fallback);
    CFT_RUN(test_tool_runs_the_fast_kernels);
    CFT_RUN(test_users_choice_stands);
    return cft_cli_finish();
}
