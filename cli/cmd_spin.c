/* curvflow spin — placeholder until the method lands. */
#include "cli.h"

#include <stdio.h>

int cli_spin(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "curvflow spin: not implemented yet\n");
    return CLI_EXIT_USAGE;
}
