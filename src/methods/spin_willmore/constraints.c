/*
 * Constraints of the spin-willmore flow (Crane, Pinkall, Schroeder 2013,
 * Sec. 6.2): rhodot is made M-orthogonal to the inversion directions
 * N^x,y,z (App. D), the constants (total curvature, App. B) and the
 * exactness columns (exactness.c), with Moebius balancing (mobius.c)
 * between the first and the rest (App. E.1).
 */
#include "methods/spin_willmore/spin_flow.h"

#include <math.h>

/* Orthonormalises columns [0, ncols) of the basis under M and projects them
 * out of rhodot; returns the rank. */
static int32_t project(cfi_spin_state *s, int32_t ncols)
{
    if (ncols == 0) return 0;
    int32_t rank = 0;
    cf_orthonormalize(s->nv, ncols, s->basis, s->area, 1e-10, &rank);
    cf_project_out(s->nv, rank, s->basis, s->area, s->rhodot);
    double rn = sqrt(cf_dot(s->nv, s->rhodot, s->rhodot, s->area));
    for (int32_t j = 0; j < rank; ++j) {
        double r = rn > 0.0 ? fabs(cf_dot(s->nv, s->rhodot, s->basis + (int64_t)j * s->nv, s->area)) / rn : 0.0;
        if (r > s->diag.constraint_residual) s->diag.constraint_residual = r;
    }
    return rank;
}

cf_status cfi_spin_apply_constraints(cf_flow *flow, cfi_spin_state *s, const double *x, double *factor_seconds,
                                     double *solve_seconds)
{
    int32_t nv = s->nv;
    cf_status st = CF_OK;
    /* III. constraints (Sec. 6.2). Without Moebius balancing the whole basis
     * {N, 1, Z} is orthonormalised at once, so every residual vanishes. With
     * it, N is projected out first, the balancing term is added, and then
     * only {1, Z} (App. E.1: "after the inversion constraint ... prior to
     * any remaining constraints"). */
    int32_t ncols = 0, count = 0, rank = 0;
    if (s->opt.inversion) {
        for (int c = 0; c < 3; ++c) {
            double *b = s->basis + (int64_t)ncols * nv;
            for (int32_t i = 0; i < nv; ++i) b[i] = s->normal[3 * i + c];
            ++ncols;
        }
    }
    if (s->opt.mobius) {
        count += ncols;
        rank += project(s, ncols);
        s->diag.mobius_norm = cfi_spin_mobius_term(flow, s, x);
        ncols = 0;
    }
    if (s->opt.total_curvature) {
        double *b = s->basis + (int64_t)ncols * nv;
        for (int32_t i = 0; i < nv; ++i) b[i] = 1.0;
        ++ncols;
    }
    int32_t pre = 0;
    if (s->harmonic_dim > 0) {
        if (s->period_newton) {
            /* the columns before the exactness ones orthonormal on their own
             * first, so that the exactness directions are the last columns of
             * the final basis, from s->zfirst (periods.c corrects rho along
             * them; Gram-Schmidt keeps the order) */
            cf_orthonormalize(nv, ncols, s->basis, s->area, 1e-10, &pre);
            count += ncols - pre;
            ncols = pre;
        }
        st = cfi_spin_exactness_columns(flow, s, x, &ncols, factor_seconds, solve_seconds);
        if (st != CF_OK) return st;
    }
    count += ncols;
    int32_t last = project(s, ncols);
    rank += last;
    s->zfirst = pre;
    s->zcount = s->period_newton ? last - pre : 0;
    s->diag.constraint_count = count;
    s->diag.constraint_rank = rank;
    s->diag.harmonic_dimension = s->harmonic_dim;
    {
        double one = 0.0, rn = 0.0, atot = 0.0;
        for (int32_t i = 0; i < nv; ++i) {
            one += s->area[i] * s->rhodot[i];
            rn += s->area[i] * s->rhodot[i] * s->rhodot[i];
            atot += s->area[i];
        }
        s->diag.total_curvature_change = rn > 0.0 ? fabs(one) / sqrt(rn * atot) : 0.0;
    }
    return CF_OK;
}
