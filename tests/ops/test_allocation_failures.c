/* Failure injection (as CHOLMOD's t_memory): every allocation of each
 * operator is made to fail in turn; the call must return CF_ERR_NOMEM,
 * leave no output object and leak nothing. */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "test.h"

#include <stdlib.h>

typedef cf_status (*op_fn)(cf_context *ctx, const cf_mesh *m, const double *x, void *scratch);

/* One operator call on the test mesh, for cft_allocation_sweep. */
typedef struct op_call {
    const cf_mesh *m;
    op_fn fn;
    void *scratch;
} op_call;

static cf_status call_op(cf_context *ctx, void *user)
{
    const op_call *c = user;
    return c->fn(ctx, c->m, cf_mesh_positions(c->m), c->scratch);
}

/* may_recover: the call goes through CHOLMOD's analysis, which tries
 * several orderings and keeps the best that succeeded, so a failed
 * allocation inside one of them can legitimately end in CF_OK. */
static void run(cf_context *ctx, const cf_mesh *m, op_fn fn, void *scratch, const char *name, int may_recover)
{
    op_call c = {m, fn, scratch};
    CHECK(cft_allocation_sweep(ctx, name, call_op, &c, may_recover) > 0);
}

static cf_status op_laplacian(cf_context *ctx, const cf_mesh *m, const double *x, void *scratch)
{
    cf_sparse *l = NULL;
    cf_status s = cf_cotan_laplacian(ctx, m, x, &l);
    if (s != CF_OK && l) s = CF_ERR_INVALID_ARG; /* output must stay NULL on failure */
    cf_sparse_destroy(&l);
    (void)scratch;
    return s;
}

static cf_status op_mass(cf_context *ctx, const cf_mesh *m, const double *x, void *scratch)
{
    cf_status s = CF_OK;
    for (int k = 0; k <= 2 && s == CF_OK; ++k) {
        cf_sparse *mm = NULL;
        s = cf_mass_matrix(ctx, m, x, (cf_mass_kind)k, &mm);
        if (s != CF_OK && mm) s = CF_ERR_INVALID_ARG;
        cf_sparse_destroy(&mm);
    }
    (void)scratch;
    return s;
}

static cf_status op_dec(cf_context *ctx, const cf_mesh *m, const double *x, void *scratch)
{
    cf_sparse *a = NULL, *b = NULL;
    cf_status s = cf_dec_d0(ctx, m, &a);
    if (s == CF_OK) s = cf_dec_d1(ctx, m, &b);
    if (s != CF_OK && b) s = CF_ERR_INVALID_ARG;
    cf_sparse_destroy(&a);
    cf_sparse_destroy(&b);
    (void)x;
    (void)scratch;
    return s;
}

static cf_status op_curvature(cf_context *ctx, const cf_mesh *m, const double *x, void *scratch)
{
    double w;
    cf_status s = cf_mean_curvature(ctx, m, x, scratch);
    if (s == CF_OK) s = cf_willmore_energy(ctx, m, x, &w);
    return s;
}

static cf_status op_harmonic(cf_context *ctx, const cf_mesh *m, const double *x, void *scratch)
{
    int32_t dim;
    return cf_harmonic_basis(ctx, m, x, &dim, scratch);
}

static cf_status op_fairing(cf_context *ctx, const cf_mesh *m, const double *x, void *scratch)
{
    cf_vertex_fairing *f = NULL;
    cf_status s = cf_vertex_fairing_create(ctx, m, x, 1, &f);
    if (s != CF_OK && f) s = CF_ERR_INVALID_ARG; /* output must stay NULL on failure */
    if (s == CF_OK) s = cf_vertex_fairing_apply(f, 0.5, x, scratch, NULL);
    cf_vertex_fairing_destroy(&f);
    return s;
}

static void quiet(void *user, cf_log_level level, const char *line)
{
    (void)user;
    (void)level;
    (void)line;
}

static void test_injection(void)
{
    cf_context *ctx = NULL;
    CHECK_STATUS(cf_context_create(&ctx), CF_OK);
    cf_context_set_log(ctx, quiet, NULL, CF_LOG_ERROR);
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.4, 16, 8, &m));
    if (!m) return;
    double *scratch = malloc(sizeof(double) * 2 * (size_t)cf_mesh_edge_count(m));
    run(ctx, m, op_laplacian, NULL, "laplacian", 0);
    run(ctx, m, op_mass, NULL, "mass", 0);
    run(ctx, m, op_dec, NULL, "dec", 0);
    run(ctx, m, op_curvature, scratch, "curvature", 0);
    run(ctx, m, op_harmonic, scratch, "harmonic", 1);
    run(ctx, m, op_fairing, scratch, "vertex fairing", 1);
    free(scratch);
    cf_mesh_destroy(&m);
    /* the held-boundary path (cf_min_quad) */
    CHECK_OK(ctx, cf_generate_grid(ctx, 6, 5, 1.0, 1.0, &m));
    if (!m) return;
    scratch = malloc(sizeof(double) * 3 * (size_t)cf_mesh_vertex_count(m));
    run(ctx, m, op_fairing, scratch, "vertex fairing, held boundary", 1);
    free(scratch);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_injection);
    return cft_finish();
}
