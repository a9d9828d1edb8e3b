/*
 * curvflow command-line tool: dispatches to the subcommands (cli.h).
 * Exit codes: 0 ok, 1 usage, 2 invalid mesh or file, 3 numerical failure.
 */
#include "cli.h"
#include "common.h"
#include "curvflow/curvflow.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct command {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
} command;

static const command commands[] = {
    {"info", cli_info, "counts, topology, validation report, angle/area statistics of a mesh"},
    {"generate", cli_generate, "write a built-in mesh (icosphere, torus, bumpy-sphere, grid, ...)"},
    {"flow", cli_flow, "run any flow method on a mesh (--list-methods)"},
    {"compare", cli_compare, "quasi-conformal error and area distortion between two meshes"},
    {"demo", cli_demo, "the main job on a built-in eight-armed star, with its HTML report"},
    {"render", cli_render, "render a mesh to PNG (uv checkerboard, per-face field colours)"},
    {"spin", cli_spin, "spin transformation from a curvature change (Crane 2013)"},
    {"curve", cli_curve, "isometric flow of planar curves (Crane 2013)"},
    {"edit", cli_edit, "stretching + bending mesh editing (Zhao & Gortler)"},
    {"report", cli_report, "one-file HTML report of a run: 3D view, Q map, energy curves"},
};
#define COMMAND_COUNT (sizeof commands / sizeof commands[0])

static void print_help(FILE *out)
{
    fprintf(out,
            "Usage: curvflow COMMAND [ARGS]...\n"
            "Deforms triangle meshes by controlling curvature.\n\n"
            "Commands:\n");
    for (size_t i = 0; i < COMMAND_COUNT; ++i) fprintf(out, "  %-10s %s\n", commands[i].name, commands[i].summary);
    fprintf(out,
            "\nOptions:\n"
            "  -h, --help     show this help (curvflow COMMAND --help for a command)\n"
            "  -V, --version  show the version\n\n"
            "Meshes are read and written as OBJ, OFF or PLY (format from the extension). Every\n"
            "output is written atomically and checked before the run: its extension must name a\n"
            "format of that output, it must not be an input, and a read-only file is replaced only\n"
            "with --force; a symbolic link is written through to its target.\n"
            "Exit status: 0 ok, 1 usage error, 2 invalid mesh or file (or an output that cannot or\n"
            "must not be written), 3 numerical failure.\n\n"
            "Environment:\n"
            "  CURVFLOW_THREADS  solver threads: 1 (default) factorises on one thread, which is as\n"
            "                    fast up to ~26k vertices and keeps its speed when other work keeps\n"
            "                    the cores busy; 0 leaves OpenMP and OpenBLAS as their own variables\n"
            "                    (OPENBLAS_NUM_THREADS, ...) set them; n > 1 lets both run in parallel\n"
            "  OPENBLAS_CORETYPE OpenBLAS's kernels (--version shows them). Unset, and OpenBLAS\n"
            "                    took this CPU for an old one (generic SSE3 'Prescott' kernels on\n"
            "                    a CPU with AVX2 or AVX-512), the tool sets it to Haswell or\n"
            "                    SkylakeX and runs again: about 1.8x faster factorisations\n");
}

static int dispatch(int argc, char **argv)
{
    /* before any command writes: an interrupted run leaves no temporary file */
    cli_install_signal_cleanup();
    if (argc < 2) {
        print_help(stderr);
        return CLI_EXIT_USAGE;
    }
    const char *name = argv[1];
    if (strcmp(name, "-h") == 0 || strcmp(name, "--help") == 0 || strcmp(name, "help") == 0) {
        print_help(stdout);
        return CLI_EXIT_OK;
    }
    if (strcmp(name, "-V") == 0 || strcmp(name, "--version") == 0) {
        printf("curvflow %s\n", cf_version_string());
        const char *blas_core = cf_blas_core(), *chosen = getenv("OPENBLAS_CORETYPE");
        if (blas_core)
            printf("OpenBLAS kernels: %s%s\n", blas_core,
                   chosen && chosen[0] ? " (OPENBLAS_CORETYPE)" : " (OpenBLAS's choice)");
        return CLI_EXIT_OK;
    }
    int32_t threads = 1;
    if (!cli_threads_from_environment(&threads)) {
        fprintf(stderr, "curvflow: CURVFLOW_THREADS must be an integer from 0 to 1024, got '%s'\n",
                getenv("CURVFLOW_THREADS"));
        return CLI_EXIT_USAGE;
    }
    for (size_t i = 0; i < COMMAND_COUNT; ++i)
        if (strcmp(name, commands[i].name) == 0) return commands[i].run(argc - 1, argv + 1);
    fprintf(stderr, "curvflow: unknown command '%s'\nTry 'curvflow --help' for more information.\n", name);
    return CLI_EXIT_USAGE;
}

/* OpenBLAS joins its worker threads at exit; a worker stuck retrying the
 * allocation of its buffer under a too low address-space limit would hang
 * exit() forever (cf_blas_threads_stuck, docs/memory.md). Then leave with
 * _Exit after flushing: every output is already renamed into place. */
int main(int argc, char **argv)
{
    int code = dispatch(argc, argv);
    if (cf_blas_threads_stuck()) {
        fflush(NULL);
        _Exit(code);
    }
    return code;
}
