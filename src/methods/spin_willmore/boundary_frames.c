/*
 * Boundary conditions of the spin-willmore flow that prescribe the boundary
 * vectors (Crane, Pinkall, Schroeder 2013, Sec. 6.3.1): the current
 * boundary vectors V in the N-B plane, the targets V~ (per-vertex from the
 * caller, or the input's binormals rotated loop by loop), and the frames
 * Q_i = L(r) [1 | V~ | u1 | u2] that restrict lambda on the boundary to
 * r (a - b V~).
 */
#include "methods/spin_willmore/spin_flow.h"
#include "curvflow/quaternion.h"

#include <math.h>
#include <string.h>


/* Boundary vectors V = cos(phi) B + sin(phi) N of the N-B plane at boundary
 * vertices (3 nv; other entries untouched), B = T x N, T the mean of the
 * incident boundary edges, N the vertex normal made orthogonal to T, phi =
 * boundary_vector_angle (0: the binormal). Uses s->normal, so x must be the surface of the last
 * update_geometry. */
cf_status cfi_spin_boundary_binormals(const cf_flow *flow, const cfi_spin_state *s, const double *x, double *out)
{
    const cf_mesh *mesh = flow->mesh;
    const int32_t *off = mesh->boundary_loop_offsets, *lv = mesh->boundary_loop_vertices;
    double cp = cos(s->opt.boundary_vector_angle), sp = sin(s->opt.boundary_vector_angle);
    double ct = cos(s->opt.boundary_tangent_angle), stn = sin(s->opt.boundary_tangent_angle);
    for (int32_t b = 0; b < mesh->boundary_loop_count; ++b) {
        int32_t n = off[b + 1] - off[b];
        for (int32_t k = 0; k < n; ++k) {
            int32_t v = lv[off[b] + k], prev = lv[off[b] + (k + n - 1) % n], next = lv[off[b] + (k + 1) % n];
            double t[3], nn[3], bb[3];
            for (int c = 0; c < 3; ++c) t[c] = x[3 * next + c] - x[3 * prev + c];
            double tl = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            if (!(tl > 0.0))
                return cfi_error(flow->ctx, CF_ERR_NUMERICAL,
                                 "vertex %d: no boundary tangent (its boundary neighbours %d and %d coincide)", v, prev,
                                 next);
            for (int c = 0; c < 3; ++c) t[c] /= tl;
            const double *nv = s->normal + 3 * v;
            double d = nv[0] * t[0] + nv[1] * t[1] + nv[2] * t[2];
            for (int c = 0; c < 3; ++c) nn[c] = nv[c] - d * t[c];
            double nl = sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
            if (!(nl > 0.0)) return cfi_error(flow->ctx, CF_ERR_NUMERICAL, "vertex %d: normal parallel to the boundary", v);
            bb[0] = (t[1] * nn[2] - t[2] * nn[1]) / nl;
            bb[1] = (t[2] * nn[0] - t[0] * nn[2]) / nl;
            bb[2] = (t[0] * nn[1] - t[1] * nn[0]) / nl;
            /* V = cos(psi) (cos(phi) B + sin(phi) N) + sin(psi) T: the N-B plane
             * for psi = 0, the tangent for psi = pi / 2 */
            for (int c = 0; c < 3; ++c) out[3 * v + c] = ct * (cp * bb[c] + sp * nn[c] / nl) + stn * t[c];
        }
    }
    return CF_OK;
}

/* Q_i for every boundary vertex: columns r, r V~, r u1, r u2 with r the
 * rotation taking V = current binormal to V~ under v -> conj(r) v r
 * (r = cos(theta/2) - sin(theta/2) w, w = V x V~ / |V x V~|, Sec. 6.3.1), and
 * u1, u2 unit imaginary quaternions orthogonal to V~. */
void cfi_spin_boundary_frames(const cf_flow *flow, cfi_spin_state *s)
{
    const cf_mesh *mesh = flow->mesh;
    int cmc = s->opt.boundary_mode == CF_SPIN_BOUNDARY_CMC;
    for (int32_t i = 0; i < s->nv; ++i) {
        if (!mesh->vertex_on_boundary[i]) continue;
        const double *v = s->binormal + 3 * i;
        const double *vt = cmc ? v : s->target + 3 * i;
        double w[3] = {v[1] * vt[2] - v[2] * vt[1], v[2] * vt[0] - v[0] * vt[2], v[0] * vt[1] - v[1] * vt[0]};
        double sn = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        double cs = v[0] * vt[0] + v[1] * vt[1] + v[2] * vt[2];
        double theta = atan2(sn, cs);
        double r[4] = {cos(0.5 * theta), 0.0, 0.0, 0.0};
        if (!(sn > 1e-12 * fabs(cs)) && cs < 0.0) {
            /* V~ = -V (a user's target): the half turn about the boundary
             * tangent, which keeps V in the N-B plane (V x N is parallel to
             * T for V = cos(phi) B + sin(phi) N, |phi| < pi / 2) */
            const double *n = s->normal + 3 * i;
            w[0] = v[1] * n[2] - v[2] * n[1], w[1] = v[2] * n[0] - v[0] * n[2], w[2] = v[0] * n[1] - v[1] * n[0];
            sn = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        }
        if (sn > 0.0)
            for (int c = 0; c < 3; ++c) r[1 + c] = -sin(0.5 * theta) * w[c] / sn;
        /* u1, u2 orthogonal to V~ */
        double a[3] = {1.0, 0.0, 0.0};
        if (fabs(vt[0]) > 0.8) a[0] = 0.0, a[1] = 1.0;
        double u1[3] = {a[1] * vt[2] - a[2] * vt[1], a[2] * vt[0] - a[0] * vt[2], a[0] * vt[1] - a[1] * vt[0]};
        double l1 = sqrt(u1[0] * u1[0] + u1[1] * u1[1] + u1[2] * u1[2]);
        for (int c = 0; c < 3; ++c) u1[c] /= l1;
        double u2[3] = {vt[1] * u1[2] - vt[2] * u1[1], vt[2] * u1[0] - vt[0] * u1[2], vt[0] * u1[1] - vt[1] * u1[0]};
        double cols[4][4];
        double e1[4] = {0.0, vt[0], vt[1], vt[2]}, e2[4] = {0.0, u1[0], u1[1], u1[2]}, e3[4] = {0.0, u2[0], u2[1], u2[2]};
        cf_quat rq = cf_quat_load(r);
        memcpy(cols[0], r, sizeof r);
        cf_quat_store(cf_quat_mul(rq, cf_quat_load(e1)), cols[1]);
        cf_quat_store(cf_quat_mul(rq, cf_quat_load(e2)), cols[2]);
        cf_quat_store(cf_quat_mul(rq, cf_quat_load(e3)), cols[3]);
        double *q = s->frames + 16 * (int64_t)i;
        for (int row = 0; row < 4; ++row)
            for (int c = 0; c < 4; ++c) q[4 * row + c] = cols[c][row];
    }
}

cf_status cfi_spin_boundary_targets(cf_flow *flow, cfi_spin_state *s, const cf_spin_willmore_options *o)
{
    const cf_mesh *mesh = flow->mesh;
    cf_status st = CF_OK;
    double axis_len = sqrt(o->boundary_axis[0] * o->boundary_axis[0] + o->boundary_axis[1] * o->boundary_axis[1] +
                           o->boundary_axis[2] * o->boundary_axis[2]);
    if (o->boundary_mode == CF_SPIN_BOUNDARY_PRESCRIBED && o->boundary_targets.values) {
        for (int32_t i = 0; i < mesh->nv; ++i) {
            if (!mesh->vertex_on_boundary[i]) continue;
            const double *t = o->boundary_targets.values + 3 * (int64_t)i;
            double len = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            for (int c = 0; c < 3; ++c) s->target[3 * i + c] = t[c] / len;
        }
    } else if (o->boundary_mode == CF_SPIN_BOUNDARY_PRESCRIBED) {
        st = cfi_spin_boundary_binormals(flow, s, flow->positions, s->target);
        if (st != CF_OK) return st;
        /* loops 1, 2, ... : rotate the binormals by the angle about the axis */
        double ax[3] = {o->boundary_axis[0] / axis_len, o->boundary_axis[1] / axis_len, o->boundary_axis[2] / axis_len};
        cf_quat q = cf_quat_from_axis_angle(ax, o->boundary_angle);
        const int32_t *off = mesh->boundary_loop_offsets, *lv = mesh->boundary_loop_vertices;
        for (int32_t b = 1; b < mesh->boundary_loop_count; ++b)
            for (int32_t k = off[b]; k < off[b + 1]; ++k) {
                double *t = s->target + 3 * lv[k], w[3];
                /* q v conj(q) rotates by +angle: conj_sandwich with conj(q) */
                cf_quat_conj_sandwich(cf_quat_conj(q), t, w);
                memcpy(t, w, sizeof w);
            }
    }
    return st;
}
