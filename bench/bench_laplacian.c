/*
 * Benchmark of the sparse layer on the cotan Laplacian: assembly (full
 * one-pass build, and refill of values into the fixed pattern), CHOLMOD
 * symbolic analysis, numeric factorisation of L + eps I (L is singular) and
 * one solve, on generated icospheres and Loop-subdivided tori of 10k-650k
 * vertices. Also the analysis of L lifted to 3x3 blocks (L kron I3) with the
 * ordering computed on the vertex graph (block 3) versus on the whole
 * matrix (block 1). Prints TSV; asserts nothing. Times are the minimum over
 * repetitions, in milliseconds.
 *
 * With --saddle S it instead times the saddle-point solver on icosphere S:
 * A = L kron I3 + eps I (3 nv unknowns), B = Jacobian of the nf face areas
 * with respect to the positions (9 entries per row), C = c I, through the
 * Schur complement and through UMFPACK LU (C = 0).
 *
 * usage: bench_laplacian [--max-vertices N] [--no-thread-fix] [--repeat R] [--ordering auto|amd|metis]
 *                        [--saddle SUBDIVISIONS]
 */
#include "curvflow/generate.h"
#include "curvflow/linalg.h"
#include "curvflow/mesh.h"
#include "curvflow/ops.h"
#include "ops/cotan_laplacian.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now_ms(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return 1e3 * (double)ts.tv_sec + 1e-6 * (double)ts.tv_nsec;
}

static int fail(cf_context *ctx, const char *what, cf_status st)
{
    fprintf(stderr, "bench_laplacian: %s failed: %s: %s\n", what, cf_status_name(st), cf_context_message(ctx));
    return 1;
}

static cf_ordering bench_ordering = CF_ORDERING_AUTO;

static int run(cf_context *ctx, const char *name, const cf_mesh *mesh, int repeat)
{
    const double *pos = cf_mesh_positions(mesh);
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    cf_status st;
    double assemble = INFINITY, refill = INFINITY, analyze = INFINITY, factorize = INFINITY, solve = INFINITY;
    double analyze3_block = INFINITY, analyze3_plain = INFINITY, factorize3 = INFINITY;
    cf_sparse *l = NULL;
    for (int r = 0; r < repeat; ++r) {
        cf_sparse_destroy(&l);
        double t0 = now_ms();
        if ((st = cf_cotan_laplacian(ctx, mesh, pos, &l)) != CF_OK) return fail(ctx, "cotan laplacian", st);
        assemble = fmin(assemble, now_ms() - t0);
    }
    /* refill path used by flows that move the vertices every step */
    int64_t ntrip = cfi_cotan_laplacian_triplet_count(mesh);
    int64_t *slots = malloc((size_t)ntrip * sizeof *slots);
    cf_sparse *lr = NULL;
    if ((st = cfi_cotan_laplacian_pattern(ctx, mesh, pos, 0.0, &lr, slots)) != CF_OK) return fail(ctx, "pattern", st);
    for (int r = 0; r < repeat; ++r) {
        double t0 = now_ms();
        if ((st = cfi_cotan_laplacian_refill(lr, mesh, pos, 0.0, slots)) != CF_OK) return fail(ctx, "refill", st);
        refill = fmin(refill, now_ms() - t0);
    }
    double mean_diag = 0.0;
    for (int32_t j = 0; j < nv; ++j) {
        int64_t p = cf_sparse_find(l, j, j);
        if (p >= 0) mean_diag += l->values[p] / nv;
    }
    const double eps = 1e-8 * mean_diag;
    double *b = malloc((size_t)nv * 3 * sizeof *b), *x = malloc((size_t)nv * 3 * sizeof *x);
    for (int32_t i = 0; i < 3 * nv; ++i) b[i] = sin(0.1 * i);
    cf_cholesky *chol = NULL;
    cf_solver_timings tm;
    for (int r = 0; r < repeat; ++r) {
        cf_cholesky_destroy(&chol);
        cf_cholesky_options o1;
        cf_cholesky_options_default(&o1);
        o1.ordering = bench_ordering;
        if ((st = cf_cholesky_create(ctx, l, &o1, &chol)) != CF_OK) return fail(ctx, "analyse", st);
        cf_cholesky_timings(chol, &tm);
        analyze = fmin(analyze, 1e3 * tm.analyze_seconds);
    }
    for (int r = 0; r < repeat; ++r) {
        if ((st = cf_cholesky_factorize_shifted(chol, l, eps)) != CF_OK) return fail(ctx, "factorise", st);
        cf_cholesky_timings(chol, &tm);
        factorize = fmin(factorize, 1e3 * tm.factorize_seconds);
        if ((st = cf_cholesky_solve(chol, 1, b, x)) != CF_OK) return fail(ctx, "solve", st);
        cf_cholesky_timings(chol, &tm);
        solve = fmin(solve, 1e3 * tm.solve_seconds);
    }
    /* residual of the last solve, relative */
    double *ax = malloc((size_t)nv * sizeof *ax), rn = 0.0, bn = 0.0;
    cf_sparse_multiply(l, x, ax);
    for (int32_t i = 0; i < nv; ++i) {
        double ri = ax[i] + eps * x[i] - b[i];
        rn += ri * ri;
        bn += b[i] * b[i];
    }
    cf_cholesky_destroy(&chol);
    /* L kron I3: ordering on the vertex graph vs on the 3nv matrix */
    cf_sparse *l3 = NULL;
    if ((st = cf_sparse_kron_identity(ctx, l, 3, &l3)) != CF_OK) return fail(ctx, "kron", st);
    for (int blocks = 3; blocks >= 1; blocks -= 2) {
        cf_cholesky_options o;
        cf_cholesky_options_default(&o);
        o.block_size = blocks;
        o.ordering = bench_ordering;
        int reps = nv > 200000 ? 1 : repeat;
        for (int r = 0; r < reps; ++r) {
            if ((st = cf_cholesky_create(ctx, l3, &o, &chol)) != CF_OK) return fail(ctx, "analyse kron", st);
            cf_cholesky_timings(chol, &tm);
            if (blocks == 3) analyze3_block = fmin(analyze3_block, 1e3 * tm.analyze_seconds);
            else analyze3_plain = fmin(analyze3_plain, 1e3 * tm.analyze_seconds);
            if (blocks == 3 && r == 0) {
                if ((st = cf_cholesky_factorize_shifted(chol, l3, eps)) != CF_OK) return fail(ctx, "factorise kron", st);
                cf_cholesky_timings(chol, &tm);
                factorize3 = 1e3 * tm.factorize_seconds;
            }
            cf_cholesky_destroy(&chol);
        }
    }
    printf("%s\t%d\t%d\t%.2f\t%.2f\t%.2f\t%.2f\t%.2f\t%.2f\t%.2e\t%.2f\t%.2f\t%.2f\n", name, nv, nf, assemble, refill,
           analyze, factorize, solve, assemble + factorize, sqrt(rn / bn), analyze3_block, analyze3_plain, factorize3);
    fflush(stdout);
    cf_sparse_destroy(&l3);
    cf_sparse_destroy(&l);
    cf_sparse_destroy(&lr);
    free(slots); free(b); free(x); free(ax);
    return 0;
}

/* Jacobian of face areas: d area_f / d p_v = 0.5 n_f x (p_next - p_prev) for corner v. */
static int run_saddle(cf_context *ctx, int32_t subdivisions)
{
    cf_mesh *mesh = NULL;
    cf_status st = cf_generate_icosphere(ctx, subdivisions, 1.0, &mesh);
    if (st != CF_OK) return fail(ctx, "icosphere", st);
    const double *pos = cf_mesh_positions(mesh);
    const int32_t *tri = cf_mesh_triangles(mesh);
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh), n = 3 * nv;
    cf_sparse *l = NULL, *l3 = NULL, *a = NULL, *eye = NULL, *b = NULL;
    if ((st = cf_cotan_laplacian(ctx, mesh, pos, &l)) != CF_OK) return fail(ctx, "laplacian", st);
    if ((st = cf_sparse_kron_identity(ctx, l, 3, &l3)) != CF_OK) return fail(ctx, "kron", st);
    int32_t *ri = malloc((size_t)9 * nf * sizeof *ri), *ci = malloc((size_t)9 * nf * sizeof *ci);
    double *vi = malloc((size_t)9 * nf * sizeof *vi);
    for (int32_t i = 0; i < n; ++i) { ri[i] = i; vi[i] = 1e-3; }
    if ((st = cf_sparse_from_triplets(ctx, n, n, n, ri, ri, vi, 1, &eye, NULL)) != CF_OK) return fail(ctx, "eye", st);
    if ((st = cf_sparse_add(ctx, 1.0, l3, 1.0, eye, &a)) != CF_OK) return fail(ctx, "add", st);
    int64_t k = 0;
    for (int32_t f = 0; f < nf; ++f) {
        const double *p0 = pos + 3 * tri[3 * f], *p1 = pos + 3 * tri[3 * f + 1], *p2 = pos + 3 * tri[3 * f + 2];
        double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        double nrm[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        for (int c = 0; c < 3; ++c) nrm[c] /= len;
        for (int corner = 0; corner < 3; ++corner) {
            const double *pn = pos + 3 * tri[3 * f + (corner + 1) % 3], *pp = pos + 3 * tri[3 * f + (corner + 2) % 3];
            double e[3] = {pn[0] - pp[0], pn[1] - pp[1], pn[2] - pp[2]};
            double g[3] = {0.5 * (nrm[1] * e[2] - nrm[2] * e[1]), 0.5 * (nrm[2] * e[0] - nrm[0] * e[2]),
                           0.5 * (nrm[0] * e[1] - nrm[1] * e[0])};
            for (int c = 0; c < 3; ++c) { ri[k] = f; ci[k] = 3 * tri[3 * f + corner] + c; vi[k++] = g[c]; }
        }
    }
    if ((st = cf_sparse_from_triplets(ctx, nf, n, k, ri, ci, vi, 0, &b, NULL)) != CF_OK) return fail(ctx, "B", st);
    double *cdiag = malloc((size_t)nf * sizeof *cdiag), *f = malloc((size_t)n * sizeof *f), *g = malloc((size_t)nf * sizeof *g);
    double *x = malloc((size_t)n * sizeof *x), *y = malloc((size_t)nf * sizeof *y);
    for (int32_t r = 0; r < nf; ++r) { cdiag[r] = 1e-6; g[r] = cos(0.7 * r); }
    for (int32_t i = 0; i < n; ++i) f[i] = sin(0.1 * i);
    printf("mesh\tV\tF\tn\tm\tpath\tcreate_ms\tfactorize_ms\tsolve_ms\tresidual\n");
    for (int mode = 0; mode < 3; ++mode) {
        int lu = mode == 2; /* 0: Schur + refinement, 1: Schur without refinement, 2: LU with C = 0 */
        if (lu && nv > 50000) break; /* UMFPACK takes seconds beyond this */
        cf_saddle_options o;
        cf_saddle_options_default(&o);
        o.block_size = 3;
        if (mode == 1) o.refinement_steps = 0;
        cf_saddle *s = NULL;
        double t0 = now_ms();
        if ((st = cf_saddle_create(ctx, a, b, &o, &s)) != CF_OK) return fail(ctx, "saddle create", st);
        double t1 = now_ms();
        if ((st = cf_saddle_factorize(s, a, b, lu ? NULL : cdiag)) != CF_OK) return fail(ctx, "saddle factorise", st);
        double t2 = now_ms();
        if ((st = cf_saddle_solve(s, f, g, x, y)) != CF_OK) return fail(ctx, "saddle solve", st);
        double t3 = now_ms();
        printf("icosphere%d\t%d\t%d\t%d\t%d\t%s\t%.1f\t%.1f\t%.1f\t%.2e\n", subdivisions, nv, nf, n, nf,
               cf_saddle_used_schur(s) ? (mode == 1 ? "schur_no_refinement" : "schur") : "lu_C=0", t1 - t0, t2 - t1, t3 - t2, cf_saddle_residual(s));
        fflush(stdout);
        cf_saddle_destroy(&s);
    }
    cf_sparse_destroy(&l); cf_sparse_destroy(&l3); cf_sparse_destroy(&a); cf_sparse_destroy(&eye); cf_sparse_destroy(&b);
    free(ri); free(ci); free(vi); free(cdiag); free(f); free(g); free(x); free(y);
    cf_mesh_destroy(&mesh);
    return 0;
}

int main(int argc, char **argv)
{
    int32_t saddle = -1;
    int32_t max_vertices = 700000;
    int repeat = 3;
    int32_t threads = 1; /* --no-thread-fix: 0 */
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--max-vertices") && i + 1 < argc) max_vertices = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--no-thread-fix")) threads = 0; /* the OpenMP runtime as the process set it */
        else if (!strcmp(argv[i], "--saddle") && i + 1 < argc) saddle = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--ordering") && i + 1 < argc) {
            ++i;
            bench_ordering = !strcmp(argv[i], "amd") ? CF_ORDERING_AMD : !strcmp(argv[i], "metis") ? CF_ORDERING_METIS
                           : CF_ORDERING_AUTO;
        }
        else {
            fprintf(stderr, "usage: %s [--max-vertices N] [--no-thread-fix] [--repeat R] [--ordering auto|amd|metis] [--saddle S]\n", argv[0]);
            return 1;
        }
    }
    if (repeat < 1) repeat = 1;
    cf_context *ctx = NULL;
    if (cf_context_create(&ctx) != CF_OK) return 1;
    cf_context_set_threads(ctx, threads);
    if (saddle >= 0) {
        int r = run_saddle(ctx, saddle);
        cf_context_destroy(&ctx);
        return r;
    }
    printf("mesh\tV\tF\tassemble_ms\trefill_ms\tanalyze_ms\tfactorize_ms\tsolve_ms\tassemble+factorize_ms\t"
           "residual\tanalyze_kron3_block3_ms\tanalyze_kron3_block1_ms\tfactorize_kron3_ms\n");
    int rc = 0;
    for (int32_t s = 5; s <= 8 && rc == 0; ++s) {
        if (10 * (1 << (2 * s)) + 2 > max_vertices) break;
        cf_mesh *m = NULL;
        cf_status st = cf_generate_icosphere(ctx, s, 1.0, &m);
        if (st != CF_OK) { rc = fail(ctx, "icosphere", st); break; }
        char name[64];
        snprintf(name, sizeof name, "icosphere%d", s);
        rc = run(ctx, name, m, repeat);
        cf_mesh_destroy(&m);
    }
    /* torus 64 x 32 (2048 vertices) refined by Loop subdivision */
    cf_mesh *base = NULL;
    if (rc == 0 && cf_generate_torus(ctx, 1.0, 0.4, 64, 32, &base) != CF_OK) rc = fail(ctx, "torus", cf_context_status(ctx));
    for (int32_t levels = 2; levels <= 4 && rc == 0; ++levels) {
        if (2048 * (1 << (2 * levels)) > max_vertices) break;
        cf_mesh *m = NULL;
        cf_status st = cf_loop_subdivide(ctx, base, cf_mesh_positions(base), levels, &m);
        if (st != CF_OK) { rc = fail(ctx, "loop subdivide", st); break; }
        char name[64];
        snprintf(name, sizeof name, "torus64x32_loop%d", levels);
        rc = run(ctx, name, m, repeat);
        cf_mesh_destroy(&m);
    }
    cf_mesh_destroy(&base);
    cf_context_destroy(&ctx);
    return rc;
}
