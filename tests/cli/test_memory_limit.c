/*
 * Under an address-space limit (RLIMIT_AS, what `ulimit -v` sets) every
 * flow ends: exit 0, or exit 3 saying "out of memory", no temporary file
 * left, and the output written when the run says it wrote the last good
 * state (issue 15, docs/memory.md "Under a memory limit").
 *
 * Before the fix some limits hung the process for ever: OpenBLAS retries a
 * failed allocation of its 128 MB per-thread work buffer in an endless loop,
 * in the main thread at the first supernodal factorisation (10k-vertex
 * sphere: spin-willmore at 288-384 MB, implicit-mcf at 224-320 MB) and in
 * its worker thread at start-up (below ~195 MB, where exit() then waits for
 * the worker). Each run here has a watchdog: a run still going after
 * WATCHDOG_SECONDS is killed and fails the test.
 *
 * The tool runs in a child with the limit set (fork, setrlimit, exec), on
 * meshes generated without a limit: a 10 242-vertex icosphere for the flows
 * and a 5 250-vertex bar with the twist handles of docs/edit.md for
 * stretch-bend-edit. The limits cover the former hangs, the regions where
 * CHOLMOD or our allocations run out, and one generous limit at which every
 * run must succeed (so that the sweep is not vacuous).
 *
 * Environment (to show the old behaviour with another build of the tool):
 * CURVFLOW_MEMLIMIT_CLI=path runs that tool instead of this build's;
 * CURVFLOW_MEMLIMIT_WATCHDOG=seconds changes the watchdog (default 60).
 *
 * Skipped in sanitizer builds: AddressSanitizer reserves terabytes of
 * address space for its shadow memory and cannot start under these limits.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli_test.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define WATCHDOG_SECONDS 60

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static const char *tool(void)
{
    const char *t = getenv("CURVFLOW_MEMLIMIT_CLI");
    return t && t[0] ? t : CF_TEST_CLI;
}

static double watchdog_seconds(void)
{
    const char *w = getenv("CURVFLOW_MEMLIMIT_WATCHDOG");
    double s = w ? atof(w) : 0.0;
    return s > 0.0 ? s : WATCHDOG_SECONDS;
}

/* Runs the tool with argv (argv[0] ignored) in cft_dir under an address-space
 * limit of limit_mb, stderr into cft_err. Returns the exit status, -1 if the
 * watchdog killed it, -2 if it died of a signal, -3 if fork failed. */
static int run_limited(int limit_mb, char *argv[], double *seconds)
{
    const char *err_path = cft_in_dir("stderr.txt");
    char err_copy[2048];
    snprintf(err_copy, sizeof err_copy, "%s", err_path);
    argv[0] = (char *)tool();
    double t0 = now();
    pid_t pid = fork();
    if (pid < 0) return -3;
    if (pid == 0) {
        /* only async-signal-safe calls between fork and exec */
        rlim_t bytes = (rlim_t)limit_mb << 20;
        struct rlimit rl = {bytes, bytes};
        int fd = open(err_copy, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        int nul = open("/dev/null", O_WRONLY);
        if (fd < 0 || nul < 0 || dup2(fd, 2) < 0 || dup2(nul, 1) < 0 || chdir(cft_dir) != 0 ||
            setrlimit(RLIMIT_AS, &rl) != 0)
            _exit(126);
        execv(argv[0], argv);
        _exit(127);
    }
    int status = 0, result = 0;
    const struct timespec pause = {0, 20 * 1000 * 1000};
    for (;;) {
        pid_t r = waitpid(pid, &status, WNOHANG);
        if (r == pid) {
            result = WIFEXITED(status) ? WEXITSTATUS(status) : -2;
            break;
        }
        if (r < 0) {
            result = -2;
            break;
        }
        if (now() - t0 > watchdog_seconds()) {
            kill(pid, SIGKILL);
            (void)waitpid(pid, &status, 0);
            result = -1;
            break;
        }
        nanosleep(&pause, NULL);
    }
    *seconds = now() - t0;
    cft_read_small(err_copy, cft_err, sizeof cft_err);
    return result;
}

/* Files of cft_dir whose name marks an unfinished atomic write. */
static int temp_files_left(void)
{
    DIR *d = opendir(cft_dir);
    if (!d) return 0;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strstr(e->d_name, ".tmp")) ++n;
    closedir(d);
    return n;
}

typedef struct method_case {
    const char *method;
    const char *input;
    const char *extra[4]; /* NULL-terminated */
} method_case;

static const method_case cases[] = {
    {"spin-willmore", "sphere.ply", {NULL}},
    {"implicit-mcf", "sphere.ply", {NULL}},
    {"implicit-bilaplacian", "sphere.ply", {NULL}},
    {"conformal-mcf", "sphere.ply", {NULL}},
    {"stretch-bend-edit", "bar.ply", {"--handles", "handles.json", NULL}},
};
#define CASE_COUNT (sizeof cases / sizeof cases[0])

/* 160: OpenBLAS's worker has no buffer; 256-352: the main thread's buffer
 * does not fit at the first factorisation; 416-512: CHOLMOD's factors or
 * our arrays; 4096: everything fits. */
static const int limits_mb[] = {160, 256, 288, 352, 416, 512, 4096};
#define LIMIT_COUNT (sizeof limits_mb / sizeof limits_mb[0])
#define GENEROUS_MB 4096

static void write_handles(void)
{
    /* docs/edit_bar_twist_handles.json: one end fixed, the other twisted */
    FILE *f = fopen(cft_in_dir("handles.json"), "w");
    if (!f) return;
    fputs("{\"sets\": ["
          "{\"name\": \"left end\", \"relative_box\": {\"min\": [0, 0, 0], \"max\": [0, 1, 1]}, \"fixed\": true},"
          "{\"name\": \"right end\", \"relative_box\": {\"min\": [1, 0, 0], \"max\": [1, 1, 1]},"
          " \"transform\": {\"rotate\": {\"axis\": [1, 0, 0], \"angle_degrees\": 90}, \"translate\": [-1, 0, 2]}}]}\n",
          f);
    fclose(f);
}

static void test_flows_end_under_limits(void)
{
    CHECK_RUN("generate icosphere --subdivisions 5 -o sphere.ply", 0);
    CHECK_RUN("generate bar --nx 160 --ny 8 --nz 8 -o bar.ply", 0);
    write_handles();
    int out_of_memory = 0, succeeded = 0;
    double longest = 0.0;
    for (size_t l = 0; l < LIMIT_COUNT; ++l) {
        for (size_t c = 0; c < CASE_COUNT; ++c) {
            const method_case *mc = &cases[c];
            char *argv[16];
            int k = 0;
            argv[k++] = NULL; /* the tool (run_limited) */
            argv[k++] = (char *)"flow";
            argv[k++] = (char *)mc->input;
            argv[k++] = (char *)"-o";
            argv[k++] = (char *)"out.ply";
            argv[k++] = (char *)"--method";
            argv[k++] = (char *)mc->method;
            argv[k++] = (char *)"--steps";
            argv[k++] = (char *)"2";
            argv[k++] = (char *)"-q";
            for (int e = 0; mc->extra[e]; ++e) argv[k++] = (char *)mc->extra[e];
            argv[k] = NULL;
            remove(cft_in_dir("out.ply"));
            double seconds = 0.0;
            int rc = run_limited(limits_mb[l], argv, &seconds);
            if (seconds > longest) longest = seconds;
            fprintf(stderr, "%5d MB  %-21s exit %2d  %5.2f s  %.160s\n", limits_mb[l], mc->method, rc, seconds,
                    cft_err);
            ++cft_checks;
            if (rc == -1) {
                cft_fail(__FILE__, __LINE__, "%s under %d MB: still running after %.0f s (hang), killed", mc->method,
                         limits_mb[l], watchdog_seconds());
                continue;
            }
            if (rc != 0 && rc != 3) {
                cft_fail(__FILE__, __LINE__, "%s under %d MB: exit %d (expected 0 or 3), stderr: %s", mc->method,
                         limits_mb[l], rc, cft_err);
                continue;
            }
            CHECK(temp_files_left() == 0);
            if (rc == 3) {
                ++out_of_memory;
                if (!strstr(cft_err, "out of memory"))
                    cft_fail(__FILE__, __LINE__, "%s under %d MB: exit 3 without 'out of memory': %s", mc->method,
                             limits_mb[l], cft_err);
                /* a run that reports writing its last good state has written it */
                if (strstr(cft_err, "writing the last good state")) CHECK(cft_exists("out.ply"));
            } else {
                ++succeeded;
                CHECK(cft_exists("out.ply"));
            }
            if (limits_mb[l] == GENEROUS_MB && rc != 0)
                cft_fail(__FILE__, __LINE__, "%s under %d MB: exit %d, expected to succeed: %s", mc->method,
                         limits_mb[l], rc, cft_err);
        }
    }
    fprintf(stderr, "%d runs out of memory, %d succeeded, longest %.2f s\n", out_of_memory, succeeded, longest);
    /* the low limits do bite (else the sweep tests nothing) */
    CHECK(out_of_memory >= (int)CASE_COUNT);
    CHECK(succeeded >= (int)CASE_COUNT);
}

int main(void)
{
#if CFT_UNDER_ASAN
    cft_skip("memory_limit: AddressSanitizer reserves terabytes of address space and cannot run under RLIMIT_AS");
#endif
    if (cft_cli_setup("memory_limit")) return 1;
    CFT_RUN(test_flows_end_under_limits);
    return cft_cli_finish();
}
