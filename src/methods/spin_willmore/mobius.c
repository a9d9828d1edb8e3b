/*
 * Moebius balancing of the spin-willmore flow (Crane, Pinkall, Schroeder
 * 2013, App. E.1): an inversion direction that moves the vertex areas back
 * toward the input's distribution, added to rhodot after the inversion
 * constraint and before the others (constraints.c).
 */
#include "methods/spin_willmore/spin_flow.h"

#include <math.h>

/* Sign of an inversion's curvature change relative to App. D's
 * rhodot = -2 <a, N> in our orientation of X: with +1 the balancing term
 * takes an inverted icosphere back to uniform areas (log-area std 0.905 ->
 * 0.003 in 10 steps) and lowers the spread on spot (test constraints). */
#define CFI_MOBIUS_SIGN 1.0

/* Moebius balancing (App. E.1): an inversion direction a that moves the
 * vertex areas toward the input's distribution; adds the corresponding
 * curvature change to rhodot and returns its M-norm. The rate alpha makes
 * the induced change of log scale, -2 alpha <a, f>, the best L2 fit of
 * -u0, so the term vanishes once areas are balanced. */
double cfi_spin_mobius_term(const cf_flow *flow, cfi_spin_state *s, const double *x)
{
    int32_t nv = s->nv;
    double atot = 0.0, rtot = 0.0;
    for (int32_t i = 0; i < nv; ++i) {
        atot += s->area[i];
        rtot += s->rest_area[i];
    }
    double *u = s->vtmp;
    double ubar = 0.0, cen[3] = {0, 0, 0};
    for (int32_t i = 0; i < nv; ++i) {
        u[i] = 0.5 * log(s->area[i] / (s->rest_area[i] * atot / rtot));
        ubar += s->rest_area[i] * u[i];
        for (int c = 0; c < 3; ++c) cen[c] += s->rest_area[i] * x[3 * i + c];
    }
    ubar /= rtot;
    for (int c = 0; c < 3; ++c) cen[c] /= rtot;
    double v[3] = {0, 0, 0}, b[9] = {0};
    for (int32_t i = 0; i < nv; ++i) {
        u[i] -= ubar;
        const double *n = s->normal + 3 * i;
        for (int c = 0; c < 3; ++c) {
            v[c] += s->rest_area[i] * (x[3 * i + c] - cen[c]) * u[i];
            for (int d = 0; d < 3; ++d) b[3 * c + d] += 4.0 * s->area[i] * n[c] * n[d];
        }
    }
    /* a = B^-1 v by Cramer's rule */
    double det = b[0] * (b[4] * b[8] - b[5] * b[7]) - b[1] * (b[3] * b[8] - b[5] * b[6]) +
                 b[2] * (b[3] * b[7] - b[4] * b[6]);
    double scale = fabs(b[0]) + fabs(b[4]) + fabs(b[8]);
    if (!(fabs(det) > 1e-12 * scale * scale * scale)) return 0.0;
    double a[3];
    a[0] = (v[0] * (b[4] * b[8] - b[5] * b[7]) - b[1] * (v[1] * b[8] - b[5] * v[2]) + b[2] * (v[1] * b[7] - b[4] * v[2])) / det;
    a[1] = (b[0] * (v[1] * b[8] - b[5] * v[2]) - v[0] * (b[3] * b[8] - b[5] * b[6]) + b[2] * (b[3] * v[2] - v[1] * b[6])) / det;
    a[2] = (b[0] * (b[4] * v[2] - v[1] * b[7]) - b[1] * (b[3] * v[2] - v[1] * b[6]) + v[0] * (b[3] * b[7] - b[4] * b[6])) / det;
    double gu = 0.0, gg = 0.0;
    for (int32_t i = 0; i < nv; ++i) {
        double g = 0.0;
        for (int c = 0; c < 3; ++c) g += a[c] * (x[3 * i + c] - cen[c]);
        gu += s->rest_area[i] * g * u[i];
        gg += s->rest_area[i] * g * g;
    }
    if (!(gg > 0.0)) return 0.0;
    double alpha = gu / (2.0 * gg);
    double norm2 = 0.0;
    for (int32_t i = 0; i < nv; ++i) {
        const double *n = s->normal + 3 * i;
        double t = CFI_MOBIUS_SIGN * s->opt.mobius_weight * (-2.0 * alpha) * (a[0] * n[0] + a[1] * n[1] + a[2] * n[2]);
        s->rhodot[i] += t;
        norm2 += s->area[i] * t * t;
    }
    return sqrt(norm2);
}
