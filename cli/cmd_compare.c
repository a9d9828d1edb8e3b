/* curvflow compare — waits for the metrics module (include/curvflow/metrics.h). */
#include "cli.h"

#include <stdio.h>

int cli_compare(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "curvflow compare: not available yet\n");
    return CLI_EXIT_USAGE;
}
