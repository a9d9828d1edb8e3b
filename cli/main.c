/* curvflow command-line tool (placeholder until the CLI lands). */
#include "curvflow/curvflow.h"

#include <stdio.h>

int main(int argc, char **argv)
{
    (void)argc; (void)argv;
    printf("curvflow %s\n", cf_version_string());
    return 0;
}
