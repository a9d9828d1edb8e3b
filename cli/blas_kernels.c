/*
 * Before main: when OpenBLAS took this CPU for an old one and runs its
 * generic SSE3 kernels (cf_blas_core_advice, docs/linalg.md "OpenBLAS's
 * kernels"), set OPENBLAS_CORETYPE to the kernels the CPU can run and
 * execute the program again, so that OpenBLAS's constructor reads it:
 * supernodal factorisations about 1.8x faster.
 *
 * Linked into every program of the project: the tool (cli/), the tests and
 * the benchmarks (tests/CMakeLists.txt, bench/CMakeLists.txt), so that all
 * of them run the same kernels and their results agree bit for bit (the
 * Python package sets the same variable before it loads the library).
 *
 * A constructor of the program runs after those of its shared libraries, so
 * OpenBLAS has made its choice by then; glibc passes it main's arguments.
 * The variable is set from then on, so this happens at most once; if the
 * exec fails, the program goes on with OpenBLAS's own choice. A user's
 * OPENBLAS_CORETYPE, whatever its value, is left alone.
 */
#define _POSIX_C_SOURCE 200809L /* setenv, execv */
#include "curvflow/curvflow.h"

#include <stdlib.h>
#include <unistd.h>

__attribute__((constructor)) static void run_with_fast_blas_kernels(int argc, char **argv, char **envp)
{
    const char *core = cf_blas_core_advice();
    if (!core || !argv || argc < 1) return;
    if (setenv("OPENBLAS_CORETYPE", core, 1) != 0) return;
    execv("/proc/self/exe", argv);
    unsetenv("OPENBLAS_CORETYPE"); /* the exec failed: this process keeps OpenBLAS's choice, and says so */
}
