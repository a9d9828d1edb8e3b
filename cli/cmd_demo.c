/* curvflow demo — waits for the metrics module (include/curvflow/metrics.h). */
#include "cli.h"

#include <stdio.h>

int cli_demo(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "curvflow demo: not available yet\n");
    return CLI_EXIT_USAGE;
}
