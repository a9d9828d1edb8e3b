/*
 * Which OpenBLAS kernels the process runs, and a better choice when
 * OpenBLAS did not recognise the CPU (docs/linalg.md, "OpenBLAS's kernels").
 *
 * Why: OpenBLAS picks its kernels once, in its constructor, from the CPU's
 * family and model (DYNAMIC_ARCH builds, as Debian's). A model newer than
 * the release falls through its table to the generic "Prescott" kernels
 * (SSE3, 2004): OpenBLAS 0.3.21 (Debian 12) on the Xeons that report family
 * 6, model 207 (0xCF) does so although they have AVX-512. Measured there:
 * CHOLMOD's supernodal factorisations spend their time in zgemm / ztrsm,
 * and spin-willmore's factorisation of X on armadillo_26k takes 219 ms a
 * step with the Prescott kernels, 122 ms with the SkylakeX ones; ten
 * default steps on blade_slivers_8k take 0.53 x the time (whole process).
 * OpenBLAS reads OPENBLAS_CORETYPE in that constructor, so the choice must
 * be in the environment before OpenBLAS is loaded: a program re-executes
 * itself with it (the command-line tool, the tests and the benchmarks do),
 * the Python package sets it before it loads numpy and the library. The
 * library only answers the question; it never changes the environment.
 *
 * A real Prescott has no AVX, so "Prescott" on a CPU with AVX2 can only be
 * the fallback. Kernels are chosen by what the CPU can run (GCC's
 * __builtin_cpu_supports, which also checks that the OS saves the AVX and
 * AVX-512 registers): SkylakeX needs AVX-512 F, CD, BW, DQ and VL, Haswell
 * AVX2 and FMA. A CPU that OpenBLAS recognised keeps its choice.
 */
#include "linalg/linalg_internal.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* Weak: NULL with another BLAS. Both are OpenBLAS's public API (cblas.h). */
extern char *openblas_get_corename(void) __attribute__((weak));
extern char *openblas_get_config(void) __attribute__((weak));

const char *cf_blas_core(void)
{
    return openblas_get_corename ? openblas_get_corename() : NULL;
}

/* The kernels this CPU can run, best first; NULL if none better than SSE3. */
static const char *best_core_for_cpu(void)
{
#if defined(__x86_64__) && defined(__GNUC__)
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
        __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
        __builtin_cpu_supports("avx512vl"))
        return "SkylakeX";
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return "Haswell";
#endif
    return NULL;
}

const char *cf_blas_core_advice(void)
{
    const char *chosen = getenv("OPENBLAS_CORETYPE");
    if (chosen && chosen[0]) return NULL; /* the user's (or an earlier run's) choice stands */
    if (!openblas_get_corename || !openblas_get_config) return NULL;
    const char *config = openblas_get_config();
    /* only a DYNAMIC_ARCH build reads OPENBLAS_CORETYPE */
    if (!config || !strstr(config, "DYNAMIC_ARCH")) return NULL;
    const char *core = openblas_get_corename();
    if (!core || strcasecmp(core, "Prescott") != 0) return NULL;
    return best_core_for_cpu();
}
