/*
 * The demo (cli/cmd_demo.c) shows what curvflow does: the built-in
 * eight-armed star (W/4pi 5.78) goes to a round sphere under the conformal
 * Willmore flow at its defaults, cleanly: exit 0, at least ten steps, W
 * decreasing at every step, a conformal result (small Q), and it ends with
 * the pictures, run.json and (when the viewer is built in) the report
 * written, and the figures printed.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli_test.h"

#include <jansson.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

/* The number after `label` in the demo's output, or NaN. */
static double figure(const char *label)
{
    const char *p = strstr(cft_out, label);
    return p ? strtod(p + strlen(label), NULL) : NAN;
}

static void test_demo_flows_the_star_to_a_sphere(void)
{
    int rc = cft_run("demo --output-dir d --quiet");
    ++cft_checks;
    if (rc != 0) cft_fail(__FILE__, __LINE__, "demo: exit %d\n%s%s", rc, cft_out, cft_err);
    fprintf(stderr, "%s", cft_out);
    CHECK(strstr(cft_out, "eight-armed star (limb-sphere, 10242 vertices, 20480 faces") != NULL);
    CHECK(strstr(cft_out, "spin-willmore at its defaults") != NULL);

    /* the step log: W at every step, from 5.78 x 4 pi down to a sphere's */
    static char log[1 << 20];
    cft_read_small(cft_in_dir("d/log.jsonl"), log, sizeof log);
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
    for (int i = 0; i < 8; ++i) CHECK(cft_exists(outputs[i]));
    /* the report, or the reason there is none */
    if (strstr(cft_out, "report:              d/report.html") != NULL)
        CHECK(cft_exists("d/report.html"));
    else
        CHECK(strstr(cft_err, "the report viewer is not built into this curvflow") != NULL);
}

int main(void)
{
    if (cft_cli_setup("report_demo")) return 1;
    CFT_RUN(test_demo_flows_the_star_to_a_sphere);
    int rc = cft_finish();
    if (rc == 0) {
        char cmd[1200];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", cft_dir);
        if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", cft_dir);
    }
    return rc;
}
