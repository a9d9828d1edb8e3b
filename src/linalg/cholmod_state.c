/*
 * Per-context CHOLMOD state: one cholmod_common per cf_context, started on
 * first use and finished by cf_context_destroy through
 * ctx->linalg_state_destroy. CHOLMOD never prints (print = 0); its error
 * handler records the message, which cfi_cholmod_check puts into the
 * context. Also limits CHOLMOD's OpenMP threads (see docs/linalg.md: on 2
 * cores its loops, hard-wired to 4 threads, fight OpenBLAS's threads).
 */
#define _GNU_SOURCE 1 /* RTLD_DEFAULT */
#include "linalg/linalg_internal.h"

#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* CHOLMOD's int interface is used on our int32_t arrays without copies */
_Static_assert(sizeof(int) == sizeof(int32_t), "CHOLMOD int must be 32-bit");

typedef struct linalg_state {
    cholmod_common common; /* first member: cfi_cholmod_reset_parameters casts back */
    int started;
    struct cholmod_method_struct default_methods[CHOLMOD_MAXMETHODS + 1];
    cfi_ordering_cache orderings;
    void (*set_levels)(int);  /* omp_set_max_active_levels, NULL if absent */
    int set_levels_looked_up;
} linalg_state;

/* CHOLMOD's error handler receives no user pointer, so the text of the last
 * error is kept per thread and read back right after the failing call by
 * cfi_cholmod_check (the status itself is read from Common->status). */
static _Thread_local struct {
    int status;
    int line;
    char text[160];
} last_cholmod_error;

static void record_cholmod_error(int status, const char *file, int line, const char *message)
{
    (void)file;
    last_cholmod_error.status = status;
    last_cholmod_error.line = line;
    snprintf(last_cholmod_error.text, sizeof last_cholmod_error.text, "%s", message ? message : "");
}

void cfi_cholmod_clear_message(void)
{
    last_cholmod_error.status = 0;
    last_cholmod_error.text[0] = '\0';
}

static void clear_orderings(cf_context *ctx, cfi_ordering_cache *o)
{
    for (int m = 0; m < 2; ++m)
        if (o->perm[m]) ctx->allocator.free_fn(ctx->allocator.user, o->perm[m], ((size_t)o->nb + 1) * sizeof(int32_t));
    memset(o, 0, sizeof *o);
}

static void destroy_state(cf_context *ctx, void *state)
{
    linalg_state *s = state;
    clear_orderings(ctx, &s->orderings);
    if (s->started) cholmod_finish(&s->common);
    /* allocated with the context's allocator but outside its byte count:
     * the state lives as long as the context (see cfi_cholmod_common) */
    ctx->allocator.free_fn(ctx->allocator.user, s, sizeof *s);
}

/* The context's thread setting (cf_context_set_threads) for CHOLMOD's
 * OpenMP regions. CHOLMOD 3.0.14 opens its loops with num_threads(4), which
 * omp_set_num_threads cannot lower; the max-active-levels ICV can: 0 makes
 * every region run on the calling thread alone (the in-program equivalent
 * of OMP_THREAD_LIMIT=1), 1 lets them run in parallel. libgomp is already
 * loaded (CHOLMOD needs it), so the symbol is looked up at run time (once
 * per context) instead of linking libgomp ourselves. threads = 0 leaves the
 * runtime alone. OpenBLAS's threads follow the same setting around each
 * factorisation and solve (cfi_blas_threads_enter, blas_buffers.c). */
static void apply_threads(cf_context *ctx, linalg_state *s)
{
    if (ctx->threads == 0) return;
    if (!s->set_levels_looked_up) {
        void *sym = dlsym(RTLD_DEFAULT, "omp_set_max_active_levels");
        if (sym) memcpy(&s->set_levels, &sym, sizeof s->set_levels); /* object -> function pointer, no cast warning */
        s->set_levels_looked_up = 1;
    }
    if (s->set_levels) s->set_levels(ctx->threads == 1 ? 0 : 1);
}

void cfi_cholmod_reset_parameters(cholmod_common *c)
{
    const linalg_state *s = (const linalg_state *)(const void *)c;
    memcpy(c->method, s->default_methods, sizeof c->method);
    c->nmethods = 0;          /* CHOLMOD's own rule: AMD, METIS if AMD fills badly */
    c->postorder = 1;
    c->supernodal = CHOLMOD_AUTO;
    /* simplicial factors are LL' too: an LDL' factorisation would accept
     * negative pivots and never report NOT_POSDEF */
    c->final_asis = 0;
    c->final_ll = 1;
    c->final_super = 1;
    c->final_pack = 1;
    c->final_monotonic = 1;
    c->final_resymbol = 0;
    c->quick_return_if_not_posdef = 0;
    /* CHOLMOD's default supernode amalgamation (the quaternion-block path
     * widens it for its own analysis) */
    c->nrelax[0] = 4;
    c->nrelax[1] = 16;
    c->nrelax[2] = 48;
    c->zrelax[0] = 0.8;
    c->zrelax[1] = 0.1;
    c->zrelax[2] = 0.05;
}

void cfi_cholmod_apply_threads(cf_context *ctx)
{
    if (ctx && ctx->linalg_state) apply_threads(ctx, ctx->linalg_state);
}

cf_status cfi_cholmod_common(cf_context *ctx, cholmod_common **out)
{
    *out = NULL;
    linalg_state *s = ctx->linalg_state;
    if (!s) {
        /* honour failure injection although the state's bytes are not counted */
        int64_t count = ++ctx->allocation_count;
        if (ctx->fail_at > 0 && (count == ctx->fail_at || (ctx->fail_sticky && count > ctx->fail_at)))
            return cfi_error(ctx, CF_ERR_NOMEM, "out of memory starting CHOLMOD");
        s = ctx->allocator.malloc_fn(ctx->allocator.user, sizeof *s);
        if (!s) return cfi_error(ctx, CF_ERR_NOMEM, "out of memory starting CHOLMOD");
        memset(s, 0, sizeof *s);
        ctx->linalg_state = s;
        ctx->linalg_state_destroy = destroy_state;
    }
    if (!s->started) {
        apply_threads(ctx, s);
        cholmod_start(&s->common);
        s->common.print = 0;
        s->common.error_handler = record_cholmod_error;
        if (s->common.status != CHOLMOD_OK) return cfi_error(ctx, CF_ERR_NOMEM, "cholmod_start failed");
        memcpy(s->default_methods, s->common.method, sizeof s->default_methods);
        cfi_cholmod_reset_parameters(&s->common);
        s->started = 1;
    }
    apply_threads(ctx, s); /* every call: the setting may have changed, another context may have run */
    s->common.status = CHOLMOD_OK;
    cfi_cholmod_clear_message();
    *out = &s->common;
    return CF_OK;
}

cfi_ordering_cache *cfi_cholmod_ordering_cache(cf_context *ctx)
{
    return &((linalg_state *)ctx->linalg_state)->orderings;
}

int32_t *cfi_ordering_cache_store(cf_context *ctx, int32_t nb, int64_t nnz, uint64_t hash, int m, double fl, double lnz)
{
    cfi_ordering_cache *o = cfi_cholmod_ordering_cache(ctx);
    if (o->nb != nb || o->nnz != nnz || o->hash != hash) {
        clear_orderings(ctx, o);
        o->nb = nb;
        o->nnz = nnz;
        o->hash = hash;
    }
    if (!o->perm[m]) {
        /* outside the context's byte count and failure injection: a cache
         * entry outlives the objects whose creation filled it */
        o->perm[m] = ctx->allocator.malloc_fn(ctx->allocator.user, ((size_t)nb + 1) * sizeof(int32_t));
        if (!o->perm[m]) return NULL;
    }
    o->fl[m] = fl;
    o->lnz[m] = lnz;
    return o->perm[m];
}

cf_status cfi_cholmod_check(cf_context *ctx, cholmod_common *c, int ok, const char *what)
{
    int st = c->status;
    if (st == CHOLMOD_OK && ok) return CF_OK;
    if (st > 0 && st != CHOLMOD_NOT_POSDEF && ok) return CF_OK; /* harmless warning */
    const char *text = last_cholmod_error.status == st ? last_cholmod_error.text : "";
    /* CHOLMOD reports some failures (out of memory inside a factorisation)
     * without a message: say so instead of printing empty parentheses */
    char said[sizeof last_cholmod_error.text];
    snprintf(said, sizeof said, "%s", text[0] ? text : "no detail from CHOLMOD");
    text = said;
    cfi_cholmod_clear_message();
    switch (st) {
    case CHOLMOD_OUT_OF_MEMORY: {
        char note[128];
        cfi_address_space_note(note, sizeof note);
        return cfi_error(ctx, CF_ERR_NOMEM, "%s: CHOLMOD out of memory (%s; %s)", what, text, note);
    }
    case CHOLMOD_TOO_LARGE:
        return cfi_error(ctx, CF_ERR_NOMEM, "%s: CHOLMOD integer overflow, problem too large (%s)", what, text);
    case CHOLMOD_INVALID:
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: CHOLMOD rejected its input (%s)", what, text);
    case CHOLMOD_NOT_INSTALLED:
        return cfi_error(ctx, CF_ERR_UNSUPPORTED, "%s: CHOLMOD method not installed (%s)", what, text);
    case CHOLMOD_NOT_POSDEF:
        return cfi_error(ctx, CF_ERR_NOT_POSDEF, "%s: matrix not positive definite", what);
    default:
        return cfi_error(ctx, CF_ERR_NUMERICAL, "%s: CHOLMOD status %d (%s)", what, st, text);
    }
}

void cfi_cholmod_view(const cf_sparse *a, int stype, cholmod_sparse *view)
{
    memset(view, 0, sizeof *view);
    view->nrow = (size_t)a->nrows;
    view->ncol = (size_t)a->ncols;
    view->nzmax = (size_t)a->colptr[a->ncols];
    view->p = a->colptr;
    view->i = a->rowind;
    view->nz = NULL;
    view->x = a->values;
    view->z = NULL;
    view->stype = stype;
    view->itype = CHOLMOD_INT;
    view->xtype = CHOLMOD_REAL;
    view->dtype = CHOLMOD_DOUBLE;
    view->sorted = 1;
    view->packed = 1;
}

int64_t cfi_first_nonfinite(const double *x, int64_t n)
{
    for (int64_t k = 0; k < n; ++k)
        if (!isfinite(x[k])) return k;
    return -1;
}
