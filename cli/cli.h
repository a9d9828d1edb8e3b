/*
 * Subcommands of the curvflow tool. Each takes the arguments after the
 * subcommand name (argv[0] is the subcommand) and returns the process exit
 * code: 0 ok, 1 usage, 2 invalid mesh or file, 3 numerical failure.
 * The CLI uses only the public API (include/curvflow/).
 */
#ifndef CF_CLI_CLI_H
#define CF_CLI_CLI_H

enum {
    CLI_EXIT_OK = 0,
    CLI_EXIT_USAGE = 1,
    CLI_EXIT_INPUT = 2,
    CLI_EXIT_NUMERICAL = 3
};

int cli_info(int argc, char **argv);
int cli_generate(int argc, char **argv);
int cli_flow(int argc, char **argv);
int cli_compare(int argc, char **argv);
int cli_demo(int argc, char **argv);
int cli_render(int argc, char **argv);
int cli_spin(int argc, char **argv);   /* cli/cmd_spin.c  (Crane 2013 SpinXForm) */
int cli_curve(int argc, char **argv);  /* cli/cmd_curve.c (Crane 2013 isometric curve flow) */
int cli_edit(int argc, char **argv);   /* cli/cmd_edit.c  (Zhao & Gortler editing) */
int cli_report(int argc, char **argv); /* cli/cmd_report.c (one-file HTML report) */

#endif
