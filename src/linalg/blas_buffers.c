/*
 * OpenBLAS's work buffers under an address-space limit (RLIMIT_AS,
 * `ulimit -v`): taken before the first BLAS call of a thread, or refused
 * with CF_ERR_NOMEM, so that a limit ends a run with a message instead of a
 * hang (docs/memory.md, "Under a memory limit").
 *
 * Why: OpenBLAS (0.3.21, Debian 12) gives every thread that runs a level-3
 * routine or a LAPACK factorisation one work buffer of BUFFER_SIZE bytes
 * (32 << 22 = 128 MiB in the x86_64 build: one 134 217 728-byte mmap, the
 * malloc fallback asks a page more), kept in a process-wide pool: the
 * buffer is mapped on the first call that finds no free one and stays
 * mapped until exit, so later calls never allocate. When that first
 * allocation fails, blas_memory_alloc retries mmap and malloc in an endless
 * loop: the process hangs. Two places were seen hanging (gdb backtraces):
 *   - the calling thread's own buffer, at the first supernodal
 *     factorisation (zpotrf_ / dpotrf_ from cholmod_super_numeric), when
 *     less than 128 MiB of address space is left by then (10k-vertex
 *     sphere: spin-willmore at 288-384 MB, implicit-mcf at 224-320 MB);
 *   - each worker thread's buffer, taken when the thread starts, i.e. when
 *     the library is loaded (OpenBLAS's constructor), before main: under a
 *     limit below ~195 MB the worker spins forever, every threaded BLAS
 *     call waits for it, and exit() hangs joining it (gotoblas_quit ->
 *     blas_thread_shutdown_), even for commands that never use BLAS.
 * The library cannot change OpenBLAS; it can make sure the calling thread's
 * buffer exists before CHOLMOD or UMFPACK call BLAS: check that the address
 * space is there (an untouched mapping of the buffer's size, mapped and
 * unmapped at once) and, if so, make OpenBLAS take its buffer right away
 * with a 2 x 2 dpotrf_. For the worker threads it can only tell that they
 * are stuck (cf_blas_threads_stuck) and refuse to call BLAS.
 *
 * Per thread: the pool is process-wide in this OpenBLAS, per thread in
 * builds with USE_TLS; warming each calling thread up once covers both.
 * (Between the check and the warm-up another thread of the application
 * could take the memory: the window is two system calls.)
 */
#define _GNU_SOURCE 1
#include "linalg/linalg_internal.h"

#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

/* OpenBLAS's BUFFER_SIZE in the x86_64 builds (measured above). Another
 * build's smaller buffer only makes the check conservative. */
#define CFI_BLAS_BUFFER_BYTES ((size_t)128 << 20)
/* What the check asks beyond the buffer: the malloc fallback's extra page
 * and chunk header, and a margin for the warm-up call itself. */
#define CFI_BLAS_PROBE_SLACK ((size_t)1 << 20)

/* Weak references: resolved when the process has OpenBLAS (and its
 * LAPACK), NULL with another BLAS, which needs no warm-up that we know of. */
extern int openblas_get_num_threads(void) __attribute__((weak));
extern void openblas_set_num_threads(int threads) __attribute__((weak));
extern void dpotrf_(const char *uplo, const int *n, double *a, const int *lda, int *info) __attribute__((weak));

/* The calling thread has its OpenBLAS buffer (or the BLAS is not OpenBLAS). */
static _Thread_local int thread_ready;
/* Buffers that OpenBLAS mapped for a warm-up of cfi_blas_reserve:
 * process-wide, like its pool, whose buffers cf_blas_threads_stuck counts. */
static atomic_int warmed_threads;

/* Bytes of address space the process maps now (/proc/self/statm, first
 * field, in pages); 0 if unknown. */
static size_t address_space_in_use(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    if (!f) return 0;
    unsigned long pages = 0;
    int got = fscanf(f, "%lu", &pages);
    fclose(f);
    long page = sysconf(_SC_PAGESIZE);
    return got == 1 && page > 0 ? (size_t)pages * (size_t)page : 0;
}

static double megabytes(size_t bytes) { return (double)bytes / (1024.0 * 1024.0); }

void cfi_address_space_note(char *buf, size_t size)
{
    if (!buf || size == 0) return;
    struct rlimit rl;
    size_t used = address_space_in_use();
    if (getrlimit(RLIMIT_AS, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY)
        snprintf(buf, size, "no address-space limit, %.0f MB mapped", megabytes(used));
    else
        snprintf(buf, size, "address-space limit (RLIMIT_AS) %.0f MB, %.0f MB in use", megabytes((size_t)rl.rlim_cur),
                 megabytes(used));
}

/* How many OpenBLAS buffers the process maps: the sum, over anonymous
 * private writable mappings (/proc/self/maps lines without a path), of
 * their size in whole buffers (adjacent buffers merge into one mapping).
 * A large array of the application counts too: the count errs high only.
 * -1 if unknown. */
static long buffers_mapped(void)
{
    FILE *f = fopen("/proc/self/maps", "r");
    if (!f) return -1;
    char line[1024];
    long count = 0;
    while (fgets(line, sizeof line, f)) {
        unsigned long lo = 0, hi = 0, offset = 0, inode = 0;
        char perms[8], dev[16];
        int end = 0;
        if (sscanf(line, "%lx-%lx %7s %lx %15s %lu %n", &lo, &hi, perms, &offset, dev, &inode, &end) < 6 || end <= 0)
            continue;
        if (inode != 0 || strcmp(perms, "rw-p") != 0 || line[end] != '\0' || hi <= lo) continue;
        count += (long)((hi - lo) / CFI_BLAS_BUFFER_BYTES);
    }
    fclose(f);
    return count;
}

/* A worker stuck in its allocation loop needs three things at once: a
 * finite RLIMIT_AS, less room under it than a buffer (else its next retry
 * succeeds, within microseconds), and fewer buffers mapped than the
 * workers plus the threads warmed up here hold. Each test only errs
 * towards "not stuck" (the case before this check existed). */
int cf_blas_threads_stuck(void)
{
    if (!openblas_get_num_threads) return 0;
    int workers = openblas_get_num_threads() - 1;
    if (workers < 1) return 0;
    struct rlimit rl;
    if (getrlimit(RLIMIT_AS, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY) return 0;
    size_t used = address_space_in_use();
    if (used == 0 || (size_t)rl.rlim_cur > used + CFI_BLAS_BUFFER_BYTES + CFI_BLAS_PROBE_SLACK) return 0;
    long mapped = buffers_mapped();
    return mapped >= 0 && mapped < (long)workers + (long)atomic_load(&warmed_threads);
}

cf_status cfi_blas_reserve(cf_context *ctx, const char *what)
{
    if (thread_ready) return CF_OK;
    if (!openblas_get_num_threads || !dpotrf_) {
        thread_ready = 1;
        return CF_OK;
    }
    char note[128];
    if (cf_blas_threads_stuck()) {
        cfi_address_space_note(note, sizeof note);
        return cfi_error(ctx, CF_ERR_NOMEM,
                         "%s: out of memory: %d OpenBLAS worker thread(s) could not map their %.0f MB work buffer "
                         "when the process started (%s) and retry forever, so BLAS cannot run in this process "
                         "(raise the limit, or set OPENBLAS_NUM_THREADS=1)",
                         what, openblas_get_num_threads() - 1, megabytes(CFI_BLAS_BUFFER_BYTES), note);
    }
    /* the same kind of mapping OpenBLAS makes (private, anonymous,
     * writable; never touched, so it costs no memory) */
    size_t probe = CFI_BLAS_BUFFER_BYTES + CFI_BLAS_PROBE_SLACK;
    void *p = mmap(NULL, probe, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) {
        cfi_address_space_note(note, sizeof note);
        return cfi_error(ctx, CF_ERR_NOMEM,
                         "%s: out of memory: OpenBLAS needs a %.0f MB work buffer for this thread before it can "
                         "factorise (%s)",
                         what, megabytes(CFI_BLAS_BUFFER_BYTES), note);
    }
    munmap(p, probe);
    /* any LAPACK factorisation makes OpenBLAS map the thread's buffer (or
     * reuse a free one of its pool); the pool keeps it for every later call */
    size_t before = address_space_in_use();
    double a[4] = {4.0, 1.0, 1.0, 3.0};
    int n = 2, info = 0;
    dpotrf_("L", &n, a, &n, &info);
    thread_ready = 1;
    if (before > 0 && address_space_in_use() >= before + CFI_BLAS_BUFFER_BYTES) atomic_fetch_add(&warmed_threads, 1);
    return CF_OK;
}

static _Thread_local int last_entered;

int cfi_blas_threads_enter(const cf_context *ctx)
{
    if (!openblas_get_num_threads || !openblas_set_num_threads) return 0;
    int current = openblas_get_num_threads();
    if (!ctx || ctx->threads != 1 || current <= 1) {
        last_entered = current;
        return 0;
    }
    openblas_set_num_threads(1);
    last_entered = openblas_get_num_threads();
    return current;
}

void cfi_blas_threads_leave(int saved)
{
    if (saved > 1 && openblas_set_num_threads) openblas_set_num_threads(saved);
}

int cfi_blas_threads_last_entered(void) { return last_entered; }
