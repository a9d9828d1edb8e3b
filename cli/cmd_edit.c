/* curvflow edit — placeholder until the method lands. */
#include "cli.h"

#include <stdio.h>

int cli_edit(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "curvflow edit: not implemented yet\n");
    return CLI_EXIT_USAGE;
}
