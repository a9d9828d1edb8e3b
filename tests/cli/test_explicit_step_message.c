/*
 * The explicit baselines' message when a step raises the energy (issue 15,
 * brief memlimit item 3): `flow plane_841 --method explicit-bilaplacian`
 * said the time step was above the stability limit although the default
 * time_step 0 means the automatic step, which is below forward Euler's
 * limit for the mesh before the step. The message now gives the step used
 * and says that with time_step 0 it was the automatic one (0.5 of the
 * limit for the bi-Laplacian, 0.9 for MCF) and that the rise then comes
 * from the mesh moving; with a step given it keeps the advice to lower it.
 * A generated flat sheet (`generate sheet`) rises like plane_841 (energy
 * 64.5 -> 67.44 at the first automatic step; at first order in the step,
 * so no smaller step helps). That was with the free boundary, since
 * session 20 the bi-Laplacian flows' option boundary=free: their default,
 * boundary=fixed, holds the border and leaves a flat sheet flat.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli_test.h"

#include <stdlib.h>
#include <string.h>

static void test_automatic_step(void)
{
    CHECK_RUN("generate sheet -o sheet.obj", 0);
    /* the default, boundary=fixed: nothing to fair, 10 clean steps */
    CHECK_RUN("flow sheet.obj -o fixed.obj --method explicit-bilaplacian -q", 0);
    CHECK_RUN("flow sheet.obj -o auto.obj --method explicit-bilaplacian -p boundary=free -q", 3);
    CHECK(cft_err_has("iteration 1: explicit-bilaplacian: energy rose from 64.5 to 67.4"));
    /* the step used, and that it was the automatic one */
    CHECK(cft_err_has("(time step 1.0596"));
    CHECK(cft_err_has("with time_step 0 (the default) this was the automatic step, 0.5 of forward Euler's "
                      "stability limit"));
    CHECK(cft_err_has("energy_check=false accepts rising steps"));
    CHECK(!cft_err_has("time_step 0 is above"));
    CHECK(!cft_err_has("the time step is above the stability limit of this mesh"));
    CHECK(cft_exists("auto.obj")); /* the last good state */

    /* a smaller given step does not cure it (the rise is first order in
     * the step): the message says so for the automatic step only */
    CHECK_RUN("flow sheet.obj -o small.obj --method explicit-bilaplacian -p boundary=free --time-step 1e-4 -q", 3);
    CHECK(cft_err_has("energy rose from 64.5 to"));
    CHECK(cft_err_has("with a time_step given (units of h^4), a smaller one helps if it was above the stability "
                      "limit"));

    /* the check can be turned off: the run then goes on */
    CHECK_RUN("flow sheet.obj -o off.obj --method explicit-bilaplacian -p boundary=free -p energy_check=false -n 3 -q", 0);
}

static void test_given_step_mcf(void)
{
    /* explicit MCF far above its limit: the advice for a given step, in h^2 */
    CHECK_RUN("generate icosphere --subdivisions 2 -o ico.obj", 0);
    CHECK_RUN("flow ico.obj -o blown.obj --method explicit-mcf --time-step 10 --steps 20 -q", 3);
    CHECK(cft_err_has("explicit-mcf: energy rose from"));
    CHECK(cft_err_has("0.9 of forward Euler's stability limit"));
    CHECK(cft_err_has("with a time_step given (units of h^2), a smaller one helps"));
    /* the automatic step on the same sphere lowers the area step after step */
    CHECK_RUN("flow ico.obj -o auto.obj --method explicit-mcf --steps 20 -q", 0);
}

static void test_help_names_both_factors(void)
{
    CHECK_RUN("flow --method explicit-bilaplacian --list-params", 0);
    CHECK(strstr(cft_out, "0 = auto: 0.9 (MCF) or 0.5 (bi-Laplacian) of forward Euler's stability limit") != NULL);
}

int main(void)
{
    if (cft_cli_setup("explicit_step_message")) return 1;
    CFT_RUN(test_automatic_step);
    CFT_RUN(test_given_step_mcf);
    CFT_RUN(test_help_names_both_factors);
    return cft_cli_finish();
}
