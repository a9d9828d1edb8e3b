/*
 * Newton corrections of the periods of the transformed edges (closed
 * surfaces of genus > 0; docs/spin.md, "Periods").
 *
 * The linearised exactness constraint (exactness.c) makes rhodot orthogonal
 * to the first-order change of the periods <e~, h_g>_*1, so the periods of a
 * step are second order in tau. Measured on elk_g1_2k (genus 1), the first
 * default step (tau 0.5, log scale change 1.14 across an edge) leaves a
 * harmonic part of 8.9 % of |e~|, two thirds of the step's non-integrability
 * (13.4 %); halving tau divides it by 3-3.6. The least-squares position
 * recovery then spreads those periods over the whole surface, and the flow
 * stopped at W/4pi 13.08 with mean Q 2.65.
 *
 * Each correction moves rho within the span of the exactness directions
 * (the last zcount columns of the orthonormal constraint basis) to cancel
 * the periods P(lambda(rho)) at first order around the current rho:
 *  - X(rho) is quadratic in rho (App. G); its derivative along q applied
 *    to lambda is assembled face by face (cfi_dirac_rho_derivative, checked
 *    against central differences of the filled matrix in test `dirac_forms`);
 *  - one inverse iteration lambda ~ X(rho)^-1 M 1 changes by
 *    dlambda = -X(rho)^-1 dX lambda (the normalisation only rescales lambda
 *    and P, which vanishes at the solution);
 *  - e~ is quadratic in lambda (dirac.c), so the periods' derivative along
 *    dl, summed from the edges' (cfi_spin_transform_edges_derivative),
 *    equals (P(lambda + dl) - P(lambda - dl)) / 2 exactly: the two edge
 *    transforms per direction that the Jacobian took until session 33.
 * The Jacobian (3 dim x zcount) costs one pass over the faces and one over
 * the edges for all directions together and one solve with the step's factor
 * for all of them. The corrected rho's lambda is first taken at first order
 * from those solves (cfi_spin_period_linear_lambda, option
 * period_first_order); only where that leaves the periods above the
 * tolerance does the update cost one more factorisation (flow_method.c,
 * correct_periods).
 */
#include "methods/spin_willmore/spin_flow.h"

#include <math.h>
#include <string.h>

double cfi_spin_periods(const cf_mesh *mesh, const cfi_spin_state *s, const double *x, const double *lambda,
                        double *edges, double *periods)
{
    int32_t dim = s->harmonic_dim, ne = s->ne;
    cfi_spin_transform_edges(mesh, x, lambda, edges);
    double norm2 = 0.0;
    for (int32_t e = 0; e < ne; ++e) {
        const double *t = edges + 3 * (int64_t)e;
        norm2 += s->hweights[e] * (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    }
    /* form by form, along its row of s->harmonic (edge by edge over all
     * forms strided by ne: a cache miss per form and edge, 26 % of a run at
     * genus 25); each sum keeps its order, so the values are the same */
    for (int32_t g = 0; g < dim; ++g) {
        const double *h = s->harmonic + (int64_t)g * ne;
        double p[3] = {0.0, 0.0, 0.0};
        for (int32_t e = 0; e < ne; ++e) {
            double wh = s->hweights[e] * h[e];
            const double *t = edges + 3 * (int64_t)e;
            for (int c = 0; c < 3; ++c) p[c] += wh * t[c];
        }
        for (int c = 0; c < 3; ++c) periods[3 * g + c] = p[c];
    }
    double p2 = 0.0;
    for (int32_t k = 0; k < 3 * dim; ++k) p2 += periods[k] * periods[k];
    /* the h_g are *1-orthonormal: |P| is the *1 norm of e~'s harmonic part */
    norm2 = fabs(norm2);
    return norm2 > 0.0 ? sqrt(p2 / norm2) : 0.0;
}

cf_status cfi_spin_period_correction(cf_flow *flow, cfi_spin_state *s, cfi_spin_timers *t)
{
    const cf_mesh *mesh = flow->mesh;
    const double *x = flow->positions;
    int32_t nv = s->nv, nz = 3 * s->harmonic_dim, nc = s->zcount;
    const double *rho0 = s->period_rho;
    /* the periods in period_values become the right-hand side, then the
     * solution */
    double *jac = s->period_matrix, *rhs = s->period_values;
    /* dX along each direction, applied to lambda; then all solved at once */
    double ta = cfi_now_seconds();
    cfi_dirac_rho_derivative(mesh, x, rho0, nc, s->basis + (int64_t)s->zfirst * nv, s->lambda, s->period_dx);
    double tb = cfi_now_seconds();
    t->assemble += tb - ta;
    cf_status st = cf_cholesky_solve(s->chol, nc, s->period_dx, s->period_sol); /* -dlambda per direction */
    double tc = cfi_now_seconds();
    t->solve += tc - tb;
    if (st != CF_OK) return st;
    /* The Jacobian: dP_gc along dlambda_l = sum_e w_e h_g[e] de~_e,c, from
     * the edges' derivative (exact: e~ is quadratic in lambda) in blocks
     * of CFI_SPIN_PERIOD_BLOCK edges, summed per form g into acc[g][l][c]
     * (contiguous in l, c). */
    int32_t dim = s->harmonic_dim, ne = s->ne, width = 3 * nc;
    double *acc = s->period_acc, *block = s->period_block;
    memset(acc, 0, (size_t)dim * (size_t)width * sizeof *acc);
    for (int32_t first = 0; first < ne; first += CFI_SPIN_PERIOD_BLOCK) {
        int32_t n = ne - first < CFI_SPIN_PERIOD_BLOCK ? ne - first : CFI_SPIN_PERIOD_BLOCK;
        cfi_spin_transform_edges_derivative(mesh, x, s->lambda, nc, s->period_sol, first, n, block);
        for (int32_t g = 0; g < dim; ++g) {
            const double *h = s->harmonic + (int64_t)g * ne + first;
            double *a = acc + (int64_t)g * width;
            for (int32_t e = 0; e < n; ++e) {
                double wh = s->hweights[first + e] * h[e];
                const double *d = block + (int64_t)e * width;
                for (int32_t k = 0; k < width; ++k) a[k] += wh * d[k];
            }
        }
    }
    /* column l of the Jacobian: the derivative along dlambda = -sol_l */
    for (int32_t l = 0; l < nc; ++l)
        for (int32_t g = 0; g < dim; ++g)
            for (int c = 0; c < 3; ++c) jac[(int64_t)l * nz + 3 * g + c] = -acc[(int64_t)g * width + 3 * l + c];
    t->assemble += cfi_now_seconds() - tc;
    for (int32_t k = 0; k < nz; ++k) rhs[k] = -rhs[k];
    int32_t rank = 0;
    st = cf_dense_least_squares(nz, nc, jac, rhs, 1e-10, s->period_work,
                                cf_dense_least_squares_work_size(nz, nz), &rank);
    if (st != CF_OK) return cfi_error(flow->ctx, CF_ERR_NUMERICAL, "spin-willmore: the periods' Jacobian is not finite");
    memcpy(s->rho, rho0, (size_t)nv * sizeof(double));
    for (int32_t l = 0; l < nc; ++l) {
        const double *q = s->basis + (int64_t)(s->zfirst + l) * nv;
        for (int32_t i = 0; i < nv; ++i) s->rho[i] += rhs[l] * q[i];
    }
    return CF_OK;
}

int cfi_spin_period_linear_lambda(const cfi_spin_state *s, double *lambda)
{
    int64_t n4 = 4 * (int64_t)s->nv;
    memcpy(lambda, s->period_lambda, (size_t)n4 * sizeof(double));
    /* period_sol holds -dlambda per direction, period_values the step along each */
    for (int32_t l = 0; l < s->zcount; ++l) {
        const double *sol = s->period_sol + l * n4;
        double c = s->period_values[l];
        for (int64_t k = 0; k < n4; ++k) lambda[k] -= c * sol[k];
    }
    /* as the inverse iteration normalises (solve_lambda) */
    double n2 = cf_normalize_blocks(s->nv, s->area, 4, cfi_spin_lambda_norm2(s), lambda);
    return n2 > 0.0 && isfinite(n2);
}
