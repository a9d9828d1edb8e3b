/*
 * The demo (cli/cmd_demo.c) shows what curvflow does: the built-in
 * eight-armed star (W/4pi 5.78) goes to a round sphere under the conformal
 * Willmore flow at its defaults, cleanly: exit 0, at least ten steps, W
 * decreasing at every step, a conformal result (small Q), and it ends with
 * the pictures, run.json and (when the viewer is built in) the report
 * written, and the figures printed.
 */
#define _POSIX_C_SOURCE 200809L
#include "test.h"

#include <jansson.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static char dir[1024];
static char out_text[1 << 16];
static char err_text[1 << 16];

static void read_small(const char *path, char *buf, size_t size)
{
    buf[0] = '\0';
    FILE *f = fopen(path, "rb");
    if (!f) return;
    size_t n = fread(buf, 1, size - 1, f);
    buf[n] = '\0';
    fclose(f);
}

static const char *in_dir(const char *name)
{
    static char path[2048];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return path;
}

static int run(const char *args)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "cd '%s' && '%s' %s > stdout.txt 2> stderr.txt", dir, CF_TEST_CLI, args);
    int st = system(cmd);
    read_small(in_dir("stdout.txt"), out_text, sizeof out_text);
    read_small(in_dir("stderr.txt"), err_text, sizeof err_text);
    return st == -1 || !WIFEXITED(st) ? -1 : WEXITSTATUS(st);
}

static int exists(const char *name)
{
    struct stat sb;
    return stat(in_dir(name), &sb) == 0;
}

/* The number after `label` in the demo's output, or NaN. */
static double figure(const char *label)
{
    const char *p = strstr(out_text, label);
    return p ? strtod(p + strlen(label), NULL) : NAN;
}

static void test_demo_flows_the_star_to_a_sphere(void)
{
    int rc = run("demo --output-dir d --quiet");
    ++cft_checks;
    if (rc != 0) cft_fail(__FILE__, __LINE__, "demo: exit %d\n%s%s", rc, out_text, err_text);
    fprintf(stderr, "%s", out_text);
    CHECK(strstr(out_text, "eight-armed star (limb-sphere, 10242 vertices, 20480 faces") != NULL);
    CHECK(strstr(out_text, "spin-willmore at its defaults") != NULL);

    /* the step log: W at every step, from 5.78 x 4 pi down to a sphere's */
    static char log[1 << 20];
    read_small(in_dir("d/log.jsonl"), log, sizeof log);
    double prev = INFINITY, first = NAN, last = NAN;
    int steps = -1;
    for (char *line = strtok(log, "\n"); line; line = strtok(NULL, "\n")) {
        json_t *o = json_loads(line, 0, NULL);
        double w = json_number_value(json_object_get(o, "energy"));
        int it = (int)json_integer_value(json_object_get(o, "iteration"));
        json_decref(o);
        ++cft_checks;
        if (it != steps + 1) cft_fail(__FILE__, __LINE__, "log line of iteration %d after %d", it, steps);
        ++cft_checks;
        if (!(w < prev)) cft_fail(__FILE__, __LINE__, "W rose at step %d: %.17g after %.17g", it, w, prev);
        if (steps < 0) first = w;
        prev = last = w;
        steps = it;
    }
    const double four_pi = 4.0 * acos(-1.0);
    CHECK(steps >= 10);
    CHECK_NEAR(first / four_pi, 5.783, 0.0, 0.001);
    CHECK_LE(last / four_pi, 1.001); /* a round sphere has W = 4 pi */
    CHECK(last / four_pi > 0.99);    /* and no less, up to discretisation */

    /* the printed figures agree with the log */
    CHECK_NEAR(figure("W/4pi:               "), first / four_pi, 1e-6, 0.0);
    double q_mean = figure("quasi-conformal Q:   mean "), q_max = figure("max ");
    CHECK(q_mean >= 1.0 && q_mean < 1.15); /* conformal up to the discretisation (1.099 measured) */
    CHECK(q_max >= q_mean && q_max < 1.5);
    CHECK(figure(" steps (converged) in ") > 0.0 || figure(" steps in ") > 0.0); /* seconds */
    const char *outputs[] = {"d/input.obj", "d/output.obj", "d/output.ply", "d/log.jsonl", "d/run.json",
                             "d/before.png", "d/after.png", "d/q.png"};
    for (int i = 0; i < 8; ++i) CHECK(exists(outputs[i]));
    /* the report, or the reason there is none */
    if (strstr(out_text, "report:              d/report.html") != NULL)
        CHECK(exists("d/report.html"));
    else
        CHECK(strstr(err_text, "the report viewer is not built into this curvflow") != NULL);
}

int main(void)
{
    snprintf(dir, sizeof dir, "%s/report_demo_%ld", CF_TEST_BINARY_DIR, (long)getpid());
    if (mkdir(dir, 0777) != 0) {
        fprintf(stderr, "cannot create %s\n", dir);
        return 1;
    }
    CFT_RUN(test_demo_flows_the_star_to_a_sphere);
    int rc = cft_finish();
    if (rc == 0) {
        char cmd[1200];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
        if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
    }
    return rc;
}
