/* curvflow curve — placeholder until the method lands. */
#include "cli.h"

#include <stdio.h>

int cli_curve(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "curvflow curve: not implemented yet\n");
    return CLI_EXIT_USAGE;
}
