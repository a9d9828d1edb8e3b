/*
 * Conformal Willmore flow in curvature space: Crane, Pinkall, Schroeder
 * 2013, "Robust Fairing via Conformal Curvature Flow", Table 1 and
 * Sections 4, 6.1-6.3, App. B-E.
 *
 * One step on the current surface f:
 *   I.   H from the cotan Laplacian (Sec. 6.1);
 *   II.  rhodot = -2 H, optionally filtered v <- v - (id + sigma Delta^k)^-1 v (Sec. 4);
 *   III. constraints (Sec. 6.2): inversion N^x,y,z, then Moebius balancing
 *        (App. E.1), then total curvature 1 and exactness: by default the
 *        discrete linearisation of "no periods" (exactness_columns_linearized),
 *        or App. C.1's Z_i^x,y,z on closed surfaces (exactness_linearized = 0);
 *   IV.  rho = tau rhodot (so mu~ = (1 - 2 tau) mu, NOTES.md);
 *   V.   lambda = smallest eigenvector of X(rho) by one inverse power
 *        iteration from lambda = 1 (Sec. 6.4.2), with lambda restricted to
 *        r (a - b V~) on the boundary for prescribed binormals / CMC
 *        (Sec. 6.3.1), or the Dirichlet solve of Sec. 6.3.2 for a fixed
 *        boundary;
 *   VI.  transformed edges and the cotan Poisson problem (Eq. (6)), by
 *        default in the metric of the starting surface (input_metric).
 * With `adaptive`, IV-VI are redone with tau halved while W would rise.
 * The symbolic factorisations of X (block size 4, complex form by default)
 * and L are computed once at creation; each step only refills values and
 * refactorises (X; X(0) for exactness; L only with the current metric).
 */
#include "methods/flow_internal.h"
#include "methods/spin_willmore/spin_internal.h"
#include "curvflow/ops.h"
#include "curvflow/quaternion.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#define CFI_PI 3.14159265358979323846

/* Sign of an inversion's curvature change relative to App. D's
 * rhodot = -2 <a, N> in our orientation of X: with +1 the balancing term
 * takes an inverted icosphere back to uniform areas (log-area std 0.905 ->
 * 0.003 in 10 steps) and lowers the spread on spot (test constraints). */
#define CFI_MOBIUS_SIGN 1.0

typedef struct spin_state {
    cf_spin_willmore_options opt;
    int32_t nv, ne, nf;
    cfi_dirac *dirac;
    cf_cholesky *chol;       /* X(rho) + eps M */
    cf_cholesky *chol0;      /* X(0) + eps M, exactness only */
    cfi_poisson *poisson;    /* cotan Laplacian of the current surface (H; fixed-boundary positions) */
    cfi_poisson *poisson_input; /* input_metric: that of the starting surface, factorised once */
    cf_sparse *filter;       /* M + sigma' L (M^-1 L)^(k-1), built from the input */
    cf_cholesky *filter_chol;
    double filter_scale;     /* k = 0: sigma / (1 + sigma) */
    double *filter_mass;     /* nv: M of the filter (input areas) */
    int32_t harmonic_dim;    /* dim H^1 (2g + b - 1 with boundary) if the exactness constraint is active */
    int32_t linearized;      /* exactness by the discrete linearisation instead of App. C's Z_i */
    double *hweights;        /* ne: cotan weights of the input (the *1 of the harmonic basis), linearized only */
    int32_t fixed_boundary;
    int32_t restricted_boundary;   /* PRESCRIBED or CMC */
    int32_t has_boundary;
    double *frames;          /* 16 nv: Q_i of cfi_dirac_restrict_boundary (boundary vertices) */
    double *target;          /* 3 nv: prescribed V~ (PRESCRIBED) */
    double *binormal;        /* 3 nv: current boundary binormals */
    double eps;
    double *harmonic;        /* ne x 2g */
    double *area;            /* nv barycentric areas of the current surface */
    double *normal;          /* 3 nv */
    double *lx;              /* 3 nv: L f */
    double *h;               /* nv */
    double *rest_area;       /* nv: areas of the input, for Moebius balancing */
    double *rhodot, *rho;    /* nv */
    double *lambda, *qrhs, *qwork;   /* 4 nv */
    double *zrhs, *zsol;     /* 4 nv x dim (x 3 dim if linearized) */
    double *basis;           /* nv x max_cols */
    int32_t max_cols;
    double *edges;           /* 3 ne */
    double *newpos;          /* 3 nv */
    double *xsave;           /* 3 nv: positions before the step (adaptive only) */
    double tau;              /* time step of the next step (adaptive: may be below opt.time_step) */
    double *vtmp, *vtmp2;    /* nv */
    double energy;
    double initial_energy;   /* W of the starting surface (divergence check) */
    cfi_spin_diagnostics diag;
} spin_state;

void cf_spin_willmore_options_default(cf_spin_willmore_options *o)
{
    if (!o) return;
    memset(o, 0, sizeof *o);
    o->time_step = 0.5;
    o->total_curvature = 1;
    o->inversion = 1;
    o->exactness = 1;
    o->mobius = 0;
    o->mobius_weight = 1.0;
    o->sigma = 0.0;
    o->filter_k = 2;
    o->boundary_mode = CF_SPIN_BOUNDARY_FREE;
    o->boundary_angle = 0.0;
    o->boundary_axis[0] = 1.0;
    o->power_iterations = 1;
    o->normalize = 1;
    o->tolerance = 1e-6;
    o->blowup_factor = 10.0;
    o->divergence_factor = 1.0;
    o->complex_factorization = 1;
    o->harmonic_update = 1;
    o->exactness_linearized = 1;
    o->adaptive = 1;
    o->max_scale_change = 1.2;
    o->input_metric = 1;
    o->regularization = CFI_SPIN_SHIFT;
}

static void options_default(void *options) { cf_spin_willmore_options_default(options); }

static const char *const boundary_choices[] = {"free", "fixed", "prescribed", "cmc", NULL};

#define OPT(f) offsetof(cf_spin_willmore_options, f)
static const cf_param_desc spin_params[] = {
    {"time_step", CF_PARAM_DOUBLE, OPT(time_step), 1e-9, 10.0, NULL,
     "tau: rho = -2 tau H per step (stable for tau < 1; 0.5 removes curvature to first order)"},
    {"total_curvature", CF_PARAM_BOOL, OPT(total_curvature), 0, 1, NULL, "constraint <rhodot, 1> = 0 (App. B)"},
    {"inversion", CF_PARAM_BOOL, OPT(inversion), 0, 1, NULL, "constraints <rhodot, N> = 0 (App. D)"},
    {"exactness", CF_PARAM_BOOL, OPT(exactness), 0, 1, NULL,
     "constraints <rhodot, Z_i> = 0: genus > 0, or holes with boundary=free (App. C)"},
    {"mobius", CF_PARAM_BOOL, OPT(mobius), 0, 1, NULL, "Moebius balancing toward the input area distribution (App. E)"},
    {"mobius_weight", CF_PARAM_DOUBLE, OPT(mobius_weight), 0.0, 100.0, NULL, "scale of the balancing term"},
    {"sigma", CF_PARAM_DOUBLE, OPT(sigma), 0.0, 1e12, NULL,
     "spectral filter strength in units of R^2k, R = sqrt(area/4pi); 0 = off (Sec. 4)"},
    {"filter_k", CF_PARAM_INT, OPT(filter_k), 0, 3, NULL, "spectral filter power k (Fig. 8)"},
    {"boundary", CF_PARAM_CHOICE, OPT(boundary_mode), 0, 3, boundary_choices,
     "free (natural), fixed positions (Sec. 6.3.2), prescribed binormals or cmc (Sec. 6.3.1)"},
    {"boundary_angle", CF_PARAM_DOUBLE, OPT(boundary_angle), -6.3, 6.3, NULL,
     "prescribed: rotation (radians) of the target binormals of boundary loops 1, 2, ..."},
    {"boundary_vector_angle", CF_PARAM_DOUBLE, OPT(boundary_vector_angle), -1.5, 1.5, NULL,
     "prescribed/cmc: V = cos(phi) B + sin(phi) N in the N-B plane (0: binormal; not +-N)"},
    {"boundary_tangent_angle", CF_PARAM_DOUBLE, OPT(boundary_tangent_angle), -1.5707963267948966, 1.5707963267948966, NULL,
     "prescribed/cmc: tilt psi of V toward the boundary tangent T (pi/2: V = T, Fig. 15 centre)"},
    {"boundary_axis_x", CF_PARAM_DOUBLE, OPT(boundary_axis[0]), -1e9, 1e9, NULL, "prescribed: rotation axis x"},
    {"boundary_axis_y", CF_PARAM_DOUBLE, OPT(boundary_axis[1]), -1e9, 1e9, NULL, "prescribed: rotation axis y"},
    {"boundary_axis_z", CF_PARAM_DOUBLE, OPT(boundary_axis[2]), -1e9, 1e9, NULL, "prescribed: rotation axis z"},
    {"power_iterations", CF_PARAM_INT, OPT(power_iterations), 1, 100, NULL, "inverse power iterations per step"},
    {"normalize", CF_PARAM_BOOL, OPT(normalize), 0, 1, NULL, "keep total area and centroid"},
    {"tolerance", CF_PARAM_DOUBLE, OPT(tolerance), 0.0, 1.0, NULL, "converged below this relative energy decrease"},
    {"blowup_factor", CF_PARAM_DOUBLE, OPT(blowup_factor), 0.0, 1e12, NULL,
     "fail a step whose energy grows more than this factor (0: never)"},
    {"divergence_factor", CF_PARAM_DOUBLE, OPT(divergence_factor), 0.0, 1e12, NULL,
     "fail a step that leaves W above this factor times the starting W (0: never; not for prescribed/cmc)"},
    {"complex_factorization", CF_PARAM_BOOL, OPT(complex_factorization), 0, 1, NULL,
     "factorise X as its complex Hermitian form of half the size (0: real 4n x 4n form)"},
    {"input_metric", CF_PARAM_BOOL, OPT(input_metric), 0, 1, NULL,
     "recover positions in the cotan metric of the starting surface (0: the current surface's, per step)"},
    {"adaptive", CF_PARAM_BOOL, OPT(adaptive), 0, 1, NULL,
     "retry a step with a smaller tau while it would raise W or exceed max_scale_change (up to 10 times; then "
     "stop as converged), grow tau back after; 0: the paper's fixed step"},
    {"max_scale_change", CF_PARAM_DOUBLE, OPT(max_scale_change), 0.0, 100.0, NULL,
     "adaptive: largest change of the log conformal scale across an edge in one step (0: no bound)"},
    {"exactness_linearized", CF_PARAM_BOOL, OPT(exactness_linearized), 0, 1, NULL,
     "exactness as the discrete linearisation of 'no periods' (0: App. C's Z_i on closed surfaces)"},
    {"regularization", CF_PARAM_DOUBLE, OPT(regularization), 1e-9, 1e6, NULL,
     "weight of |lambda - 1|^2 in units of 4pi/area: damps near-kernel modes of thin shapes"},
    {"harmonic_update", CF_PARAM_BOOL, OPT(harmonic_update), 0, 1, NULL,
     "with App. C's Z_i: re-project the harmonic 1-forms onto the current metric each step"},
};
#undef OPT

/* ---- geometry of the current surface ---------------------------------- */

/* Refills L, areas, normals, L f, H and the energy W = sum |L f|_i^2 / (4 A_i)
 * (as cf_willmore_energy; interior vertices only when there is a boundary). */
static cf_status update_geometry(cf_flow *flow, spin_state *s, const double *x)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    cf_status st = cfi_poisson_refill(s->poisson, mesh, x);
    if (st == CF_OK) st = cf_vertex_areas(ctx, mesh, x, CF_DUAL_AREA_BARYCENTRIC, s->area);
    if (st == CF_OK) st = cf_vertex_normals(ctx, mesh, x, s->normal);
    if (st != CF_OK) return st;
    const cf_sparse *l = s->poisson->l;
    memset(s->lx, 0, 3 * (size_t)s->nv * sizeof(double));
    for (int32_t j = 0; j < s->nv; ++j)
        for (int32_t p = l->colptr[j]; p < l->colptr[j + 1]; ++p) {
            int32_t i = l->rowind[p];
            for (int c = 0; c < 3; ++c) s->lx[3 * i + c] += l->values[p] * x[3 * j + c];
        }
    double w = 0.0;
    for (int32_t i = 0; i < s->nv; ++i) {
        const double *v = s->lx + 3 * i, *n = s->normal + 3 * i;
        if (!(s->area[i] > 0.0)) return cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "vertex %d: zero dual area", i);
        if (mesh->vertex_on_boundary[i]) {
            s->h[i] = 0.0;
            continue;
        }
        s->h[i] = (v[0] * n[0] + v[1] * n[1] + v[2] * n[2]) / (2.0 * s->area[i]);
        w += (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / (4.0 * s->area[i]);
    }
    s->energy = w;
    return CF_OK;
}


/* ---- boundary frames (Sec. 6.3.1) -------------------------------------- */

/* Boundary vectors V = cos(phi) B + sin(phi) N of the N-B plane at boundary
 * vertices (3 nv; other entries untouched), B = T x N, T the mean of the
 * incident boundary edges, N the vertex normal made orthogonal to T, phi =
 * boundary_vector_angle (0: the binormal). Uses s->normal, so x must be the surface of the last
 * update_geometry. */
static cf_status boundary_binormals(const cf_flow *flow, const spin_state *s, const double *x, double *out)
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

/* Hamilton product on (w, x, y, z) arrays. */
static void qmul4(const double *a, const double *b, double *o)
{
    o[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    o[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    o[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    o[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

/* Q_i for every boundary vertex: columns r, r V~, r u1, r u2 with r the
 * rotation taking V = current binormal to V~ under v -> conj(r) v r
 * (r = cos(theta/2) - sin(theta/2) w, w = V x V~ / |V x V~|, Sec. 6.3.1), and
 * u1, u2 unit imaginary quaternions orthogonal to V~. */
static void boundary_frames(const cf_flow *flow, spin_state *s)
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
        memcpy(cols[0], r, sizeof r);
        qmul4(r, e1, cols[1]);
        qmul4(r, e2, cols[2]);
        qmul4(r, e3, cols[3]);
        double *q = s->frames + 16 * (int64_t)i;
        for (int row = 0; row < 4; ++row)
            for (int c = 0; c < 4; ++c) q[4 * row + c] = cols[c][row];
    }
}

/* ---- creation ---------------------------------------------------------- */

static void spin_destroy(cf_flow *flow)
{
    spin_state *s = flow->impl;
    if (!s) return;
    cf_context *ctx = flow->ctx;
    cfi_dirac_destroy(ctx, &s->dirac);
    cf_cholesky_destroy(&s->chol);
    cf_cholesky_destroy(&s->chol0);
    cfi_poisson_destroy(ctx, &s->poisson);
    cfi_poisson_destroy(ctx, &s->poisson_input);
    cf_sparse_destroy(&s->filter);
    cf_cholesky_destroy(&s->filter_chol);
    int64_t nv = s->nv, g2 = s->harmonic_dim;
    CFI_FREE(ctx, s->harmonic, (int64_t)s->ne * g2);
    CFI_FREE(ctx, s->area, nv);
    CFI_FREE(ctx, s->normal, 3 * nv);
    CFI_FREE(ctx, s->lx, 3 * nv);
    CFI_FREE(ctx, s->h, nv);
    CFI_FREE(ctx, s->rest_area, nv);
    CFI_FREE(ctx, s->rhodot, nv);
    CFI_FREE(ctx, s->rho, nv);
    CFI_FREE(ctx, s->lambda, 4 * nv);
    CFI_FREE(ctx, s->qrhs, 4 * nv);
    CFI_FREE(ctx, s->qwork, 4 * nv);
    int64_t zc = s->linearized ? 3 * g2 : g2;
    CFI_FREE(ctx, s->zrhs, 4 * nv * zc);
    CFI_FREE(ctx, s->zsol, 4 * nv * zc);
    if (s->hweights) CFI_FREE(ctx, s->hweights, s->ne);
    CFI_FREE(ctx, s->basis, nv * s->max_cols);
    CFI_FREE(ctx, s->edges, 3 * (int64_t)s->ne);
    CFI_FREE(ctx, s->newpos, 3 * nv);
    CFI_FREE(ctx, s->xsave, 3 * nv);
    CFI_FREE(ctx, s->vtmp, nv);
    CFI_FREE(ctx, s->vtmp2, nv);
    CFI_FREE(ctx, s->filter_mass, nv);
    CFI_FREE(ctx, s->frames, 16 * nv);
    CFI_FREE(ctx, s->target, 3 * nv);
    CFI_FREE(ctx, s->binormal, 3 * nv);
    CFI_FREE(ctx, s, 1);
    flow->impl = NULL;
}

/* Copy of a with column j scaled by colscale[j]. */
static cf_status scaled_copy(cf_context *ctx, const cf_sparse *a, const double *colscale, cf_sparse **out)
{
    int64_t nnz = cf_sparse_nnz(a);
    int32_t *r = CFI_ALLOC(ctx, int32_t, nnz), *c = CFI_ALLOC(ctx, int32_t, nnz);
    double *v = CFI_ALLOC(ctx, double, nnz);
    cf_status st = CF_ERR_NOMEM;
    if (r && c && v) {
        for (int32_t j = 0; j < a->ncols; ++j)
            for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
                r[p] = a->rowind[p];
                c[p] = j;
                v[p] = a->values[p] * colscale[j];
            }
        st = cf_sparse_from_triplets(ctx, a->nrows, a->ncols, nnz, r, c, v, 0, out, NULL);
    }
    CFI_FREE(ctx, r, nnz);
    CFI_FREE(ctx, c, nnz);
    CFI_FREE(ctx, v, nnz);
    return st;
}

/* Filter matrix F = M + sigma' L (M^-1 L)^(k-1) of the input surface. The
 * weak cotan Laplacian is invariant under conformal maps, and the flow is
 * conformal, so F is built and factorised once. */
static cf_status build_filter(cf_flow *flow, spin_state *s)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    int32_t k = s->opt.filter_k;
    double sigma = s->opt.sigma;
    if (k == 0) {
        s->filter_scale = sigma / (1.0 + sigma);
        return CF_OK;
    }
    s->filter_mass = CFI_ALLOC(ctx, double, s->nv);
    if (!s->filter_mass) return CF_ERR_NOMEM;
    memcpy(s->filter_mass, s->area, (size_t)s->nv * sizeof(double));
    double radius2 = flow->initial_area / (4.0 * CFI_PI);
    double sig = sigma * pow(radius2, (double)k);
    cf_sparse *l = NULL, *m = NULL, *lminv = NULL, *p = NULL, *p2 = NULL;
    cf_status st = cf_cotan_laplacian(ctx, mesh, flow->positions, &l);
    if (st == CF_OK) st = cf_mass_matrix(ctx, mesh, flow->positions, CF_MASS_LUMPED_BARYCENTRIC, &m);
    if (st != CF_OK) goto done;
    if (k == 1) {
        st = cf_sparse_add(ctx, 1.0, m, sig, l, &s->filter);
    } else {
        for (int32_t i = 0; i < s->nv; ++i) s->vtmp[i] = 1.0 / s->area[i];
        st = scaled_copy(ctx, l, s->vtmp, &lminv);
        if (st == CF_OK) st = cf_sparse_product(ctx, lminv, l, &p);
        if (st == CF_OK && k == 3) {
            st = cf_sparse_product(ctx, lminv, p, &p2);
            cf_sparse_destroy(&p);
            p = p2;
            p2 = NULL;
        }
        if (st == CF_OK) st = cf_sparse_add(ctx, 1.0, m, sig, p, &s->filter);
    }
    if (st != CF_OK) goto done;
    s->filter->symmetric = 1;
    cf_cholesky_options co;
    cf_cholesky_options_default(&co);
    co.block_size = 1;
    st = cf_cholesky_create(ctx, s->filter, &co, &s->filter_chol);
    if (st == CF_OK) st = cf_cholesky_factorize(s->filter_chol, s->filter);
done:
    cf_sparse_destroy(&l);
    cf_sparse_destroy(&m);
    cf_sparse_destroy(&lminv);
    cf_sparse_destroy(&p);
    cf_sparse_destroy(&p2);
    return st;
}

static cf_status spin_create(cf_flow *flow, const void *options)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    const cf_spin_willmore_options *o = options;
    if (!(o->time_step > 0.0) || !isfinite(o->time_step))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: time_step must be > 0, got %g", o->time_step);
    if (o->filter_k < 0 || o->filter_k > 3)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: filter_k must be 0..3, got %d", o->filter_k);
    if (!(o->sigma >= 0.0) || !isfinite(o->sigma))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: sigma must be >= 0, got %g", o->sigma);
    if (!(o->blowup_factor == 0.0 || o->blowup_factor > 1.0) || !isfinite(o->blowup_factor))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: blowup_factor must be 0 (off) or > 1, got %g",
                         o->blowup_factor);
    if (!(o->divergence_factor == 0.0 || o->divergence_factor >= 1.0) || !isfinite(o->divergence_factor))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: divergence_factor must be 0 (off) or >= 1, got %g",
                         o->divergence_factor);
    if (!(o->regularization > 0.0) || !isfinite(o->regularization))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: regularization must be > 0, got %g", o->regularization);
    if (o->power_iterations < 1)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: power_iterations must be >= 1, got %d",
                         o->power_iterations);
    if (o->boundary_mode < CF_SPIN_BOUNDARY_FREE || o->boundary_mode > CF_SPIN_BOUNDARY_CMC)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: unknown boundary mode %d", o->boundary_mode);
    double axis_len = sqrt(o->boundary_axis[0] * o->boundary_axis[0] + o->boundary_axis[1] * o->boundary_axis[1] +
                           o->boundary_axis[2] * o->boundary_axis[2]);
    if (!(fabs(o->boundary_tangent_angle) <= 0.5 * CFI_PI + 1e-12))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: boundary_tangent_angle must be in [-pi/2, pi/2]");
    if (!(fabs(o->boundary_vector_angle) <= 1.5))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: boundary_vector_angle must be in [-1.5, 1.5] (V = +-N is excluded)");
    if (o->boundary_mode == CF_SPIN_BOUNDARY_PRESCRIBED && (!(axis_len > 0.0) || !isfinite(axis_len) || !isfinite(o->boundary_angle)))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: boundary_axis must be a nonzero finite vector");
    if (!(o->mobius_weight >= 0.0) || !isfinite(o->mobius_weight))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: mobius_weight must be >= 0");
    if (o->boundary_targets && o->boundary_mode != CF_SPIN_BOUNDARY_PRESCRIBED)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: boundary targets are given but boundary=%s "
                         "(they need boundary=prescribed)", boundary_choices[o->boundary_mode]);
    if (o->boundary_targets)
        for (int32_t i = 0; i < mesh->nv; ++i) {
            if (!mesh->vertex_on_boundary[i]) continue;
            const double *t = o->boundary_targets + 3 * (int64_t)i;
            double len = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            if (!isfinite(len) || !(len > 0.0))
                return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: vertex %d: boundary target (%g, %g, %g) is %s",
                                 i, t[0], t[1], t[2], isfinite(len) ? "zero" : "not finite");
        }
    int32_t has_boundary = mesh->boundary_loop_count > 0;
    if (o->boundary_mode != CF_SPIN_BOUNDARY_FREE && !has_boundary)
        return cfi_error(ctx, CF_ERR_BAD_MESH, "spin-willmore: boundary=%s needs a mesh with boundary",
                         boundary_choices[o->boundary_mode]);

    spin_state *s = CFI_ALLOC(ctx, spin_state, 1);
    if (!s) return CF_ERR_NOMEM;
    flow->impl = s;
    s->opt = *o;
    s->opt.boundary_targets = NULL; /* the caller's array is read below, not kept */
    s->tau = o->time_step;
    s->nv = mesh->nv;
    s->ne = mesh->ne;
    s->nf = mesh->nf;
    s->has_boundary = has_boundary;
    s->fixed_boundary = o->boundary_mode == CF_SPIN_BOUNDARY_FIXED;
    s->restricted_boundary = o->boundary_mode == CF_SPIN_BOUNDARY_PRESCRIBED || o->boundary_mode == CF_SPIN_BOUNDARY_CMC;
    int64_t nv = s->nv;
    cf_status st = CF_OK;

    /* exactness: harmonic 1-forms of the input (App. C.1, steps I-III), on
     * closed surfaces of genus > 0 and on free-boundary surfaces that are
     * not disks (dim 2g + b - 1 > 0). Harmonic forms depend only on the
     * conformal structure, which the flow preserves, so the basis is
     * computed once. Not with fixed boundaries (the transformed boundary
     * edges are the input's, so the periods around the boundary loops vanish
     * identically) nor with prescribed / cmc ones (lambda is not near 1 on
     * the boundary and App. C's Z_i were measured to increase the periods
     * there), see docs/spin.md. */
    int32_t dim = 0;
    if (o->exactness && (has_boundary ? o->boundary_mode == CF_SPIN_BOUNDARY_FREE : mesh->genus > 0)) {
        st = cf_harmonic_basis(ctx, mesh, flow->positions, &dim, NULL);
        if (st != CF_OK) goto fail;
    }
    s->harmonic_dim = dim;
    /* Closed surfaces too by default: App. C's Z_i remove the periods only
     * approximately (bob 32x, elephant_g3_3k only 2.9x, at first order in
     * tau), the linearised condition to first order (elephant 20x at tau
     * 0.01, 87x at 0.002); docs/spin.md. */
    s->linearized = dim > 0 && (has_boundary || o->exactness_linearized);
    int64_t zcols = s->linearized ? 3 * (int64_t)dim : dim;
    s->hweights = s->linearized ? CFI_ALLOC(ctx, double, s->ne) : NULL;
    s->max_cols = 4 + 3 * dim + 1;
    s->harmonic = dim ? CFI_ALLOC(ctx, double, (int64_t)s->ne * dim) : NULL;
    s->area = CFI_ALLOC(ctx, double, nv);
    s->normal = CFI_ALLOC(ctx, double, 3 * nv);
    s->lx = CFI_ALLOC(ctx, double, 3 * nv);
    s->h = CFI_ALLOC(ctx, double, nv);
    s->rest_area = CFI_ALLOC(ctx, double, nv);
    s->rhodot = CFI_ALLOC(ctx, double, nv);
    s->rho = CFI_ALLOC(ctx, double, nv);
    s->lambda = CFI_ALLOC(ctx, double, 4 * nv);
    s->qrhs = CFI_ALLOC(ctx, double, 4 * nv);
    s->qwork = CFI_ALLOC(ctx, double, 4 * nv);
    s->zrhs = dim ? CFI_ALLOC(ctx, double, 4 * nv * zcols) : NULL;
    s->zsol = dim ? CFI_ALLOC(ctx, double, 4 * nv * zcols) : NULL;
    s->basis = CFI_ALLOC(ctx, double, nv * s->max_cols);
    s->edges = CFI_ALLOC(ctx, double, 3 * (int64_t)s->ne);
    s->newpos = CFI_ALLOC(ctx, double, 3 * nv);
    if (o->adaptive) {
        s->xsave = CFI_ALLOC(ctx, double, 3 * nv);
        if (!s->xsave) {
            st = CF_ERR_NOMEM;
            goto fail;
        }
    }
    s->vtmp = CFI_ALLOC(ctx, double, nv);
    s->vtmp2 = CFI_ALLOC(ctx, double, nv);
    if (s->restricted_boundary) {
        s->frames = CFI_ALLOC(ctx, double, 16 * nv);
        s->target = CFI_ALLOC(ctx, double, 3 * nv);
        s->binormal = CFI_ALLOC(ctx, double, 3 * nv);
        if (!s->frames || !s->target || !s->binormal) {
            st = CF_ERR_NOMEM;
            goto fail;
        }
    }
    if ((dim && (!s->harmonic || !s->zrhs || !s->zsol)) || (s->linearized && !s->hweights) || !s->area ||
        !s->normal || !s->lx || !s->h ||
        !s->rest_area || !s->rhodot || !s->rho || !s->lambda || !s->qrhs || !s->qwork || !s->basis || !s->edges ||
        !s->newpos || !s->vtmp || !s->vtmp2) {
        st = CF_ERR_NOMEM;
        goto fail;
    }
    if (dim) {
        int32_t dim2 = 0;
        st = cf_harmonic_basis(ctx, mesh, flow->positions, &dim2, s->harmonic);
        if (st != CF_OK) goto fail;
        if (CF_NEVER(dim2 != dim)) {
            st = cfi_error(ctx, CF_ERR_NUMERICAL, "spin-willmore: harmonic basis dimension changed");
            goto fail;
        }
        if (s->linearized) {
            st = cf_cotan_weights(ctx, mesh, flow->positions, s->hweights);
            if (st != CF_OK) goto fail;
        }
    }
    st = cfi_poisson_create(ctx, mesh, flow->positions, &s->poisson);
    /* Position recovery in the metric of the starting surface: the Dirichlet
     * energy is conformally invariant, so for a conformal flow the Poisson
     * problem of Eq. (6) is the same in the input's metric (as cMCF keeps the
     * input's Laplacian, Kazhdan et al. 2012), and its factorisation is done
     * once. Measured (docs/spin.md): armadillo mean Q 1.81 -> 1.24, max Q 12.0
     * -> 2.9; bunny max Q 7.1 -> 3.7; spot W/4pi 1.0488 -> 1.0472. A fixed
     * boundary rewrites the matrix every step and keeps the current metric. */
    if (st == CF_OK && o->input_metric && !s->fixed_boundary)
        st = cfi_poisson_create(ctx, mesh, flow->positions, &s->poisson_input); /* filled with these positions */
    if (st == CF_OK) st = update_geometry(flow, s, flow->positions);
    if (st != CF_OK) goto fail;
    /* desired vertex areas of Moebius balancing: the mesh's rest shape */
    st = cf_vertex_areas(ctx, mesh, mesh->positions, CF_DUAL_AREA_BARYCENTRIC, s->rest_area);
    if (st != CF_OK) goto fail;
    s->eps = o->regularization * 4.0 * CFI_PI / flow->initial_area;
    if (o->boundary_mode == CF_SPIN_BOUNDARY_PRESCRIBED && o->boundary_targets) {
        for (int32_t i = 0; i < mesh->nv; ++i) {
            if (!mesh->vertex_on_boundary[i]) continue;
            const double *t = o->boundary_targets + 3 * (int64_t)i;
            double len = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            for (int c = 0; c < 3; ++c) s->target[3 * i + c] = t[c] / len;
        }
    } else if (o->boundary_mode == CF_SPIN_BOUNDARY_PRESCRIBED) {
        st = boundary_binormals(flow, s, flow->positions, s->target);
        if (st != CF_OK) goto fail;
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

    st = cfi_dirac_create(ctx, mesh, &s->dirac);
    if (st == CF_OK) st = cfi_dirac_fill(s->dirac, mesh, flow->positions, NULL, s->eps);
    if (st != CF_OK) goto fail;
    cf_cholesky_options co;
    cf_cholesky_options_default(&co);
    co.block_size = 4;
    /* X(rho) is a Hermitian quaternionic matrix; its complex form halves the
     * factorisation (docs/linalg.md). The boundary frames of prescribed/cmc
     * boundaries mix the quaternion components, so those keep the real form;
     * X(0) of the exactness constraint never has them. */
    co.quaternion_blocks = o->complex_factorization && !s->restricted_boundary;
    st = cf_cholesky_create(ctx, s->dirac->x, &co, &s->chol);
    co.quaternion_blocks = o->complex_factorization != 0;
    if (st == CF_OK && dim) st = cf_cholesky_create(ctx, s->dirac->x, &co, &s->chol0);
    if (st == CF_OK && o->sigma > 0.0) st = build_filter(flow, s);
    if (st != CF_OK) goto fail;

    flow->info.energy = s->energy;
    s->initial_energy = s->energy;
    flow->info.energy_terms[0] = s->energy / (4.0 * CFI_PI);
    flow->info.term_names[0] = "W/4pi";
    return CF_OK;
fail:
    spin_destroy(flow);
    return st;
}

/* ---- constraints ------------------------------------------------------- */

/* The discrete flow keeps the conformal structure only up to the mesh's
 * resolution, so 1-forms harmonic on the input drift away from harmonic on
 * the current surface, and Z_i built from them stop spanning the periods
 * (a bumped torus at tau 0.1 blew up after 62 steps, its integrability
 * error growing from 4e-4 to 4e-2). Each form is re-projected onto the
 * harmonic forms of the current cotan metric within its cohomology class:
 * omega <- omega - d u with L u = -div omega, (div omega)_i = sum_j w_ij
 * omega_ij, so that the result is co-closed and still closed with the same
 * periods. The current L is refilled every step for H; its factorisation is
 * shared with the position solve only when that uses the current metric
 * (input_metric = 0). */
static cf_status update_harmonic_forms(cf_flow *flow, spin_state *s, double *factor_seconds, double *solve_seconds)
{
    const cf_mesh *mesh = flow->mesh;
    int32_t nv = s->nv, ne = s->ne, dim = s->harmonic_dim;
    const cf_sparse *l = s->poisson->l;
    const int64_t *slot = s->poisson->edge_slot;
    double *div = s->zrhs, *u = s->zsol; /* scratch: at least nv x dim each */
    memset(div, 0, (size_t)nv * dim * sizeof(double));
    for (int32_t g = 0; g < dim; ++g) {
        const double *w = s->harmonic + (int64_t)g * ne;
        double *d = div + (int64_t)g * nv;
        for (int32_t e = 0; e < ne; ++e) {
            int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
            double flux = -l->values[slot[e]] * w[e]; /* w_ij omega_ij, the edge runs i -> j */
            d[i] -= flux;                              /* right-hand side -div */
            d[j] += flux;
        }
        /* L's range is orthogonal to the constants; the rounding left in the
         * sum would come back multiplied by 1 / shift as a constant in u,
         * whose cancellation in d u then costs digits */
        double mean = 0.0;
        for (int32_t i = 0; i < nv; ++i) mean += d[i];
        mean /= nv;
        for (int32_t i = 0; i < nv; ++i) d[i] -= mean;
    }
    cf_status st = cfi_poisson_solve_scalar(s->poisson, dim, div, u, factor_seconds, solve_seconds);
    if (st != CF_OK) return st;
    for (int32_t g = 0; g < dim; ++g) {
        double *w = s->harmonic + (int64_t)g * ne;
        const double *ug = u + (int64_t)g * nv;
        for (int32_t e = 0; e < ne; ++e) w[e] -= ug[mesh->edge_vertices[2 * e + 1]] - ug[mesh->edge_vertices[2 * e]];
    }
    return CF_OK;
}

/* Z_i of App. C.1 on the current surface x: face vectors v from the 2 x 2
 * systems, right-hand side D^* A v (vertex i gets sum_k e_i v_k / 2), and
 * solves with X(0). Fills columns of s->basis from `col` with the imaginary
 * parts of each Z_i; returns the new column count. */
static cf_status exactness_columns(cf_flow *flow, spin_state *s, const double *x, int32_t *col,
                                   double *factor_seconds, double *solve_seconds)
{
    const cf_mesh *mesh = flow->mesh;
    int32_t nv = s->nv, dim = s->harmonic_dim;
    if (s->opt.harmonic_update) {
        cf_status sth = update_harmonic_forms(flow, s, factor_seconds, solve_seconds);
        if (sth != CF_OK) return sth;
    }
    double t0 = cfi_now_seconds();
    cf_status st = cfi_dirac_fill(s->dirac, mesh, x, NULL, s->eps);
    if (st != CF_OK) return st;
    st = cf_cholesky_factorize(s->chol0, s->dirac->x);
    double t1 = cfi_now_seconds();
    *factor_seconds += t1 - t0;
    if (st != CF_OK) return st;
    memset(s->zrhs, 0, 4 * (size_t)nv * dim * sizeof(double));
    for (int32_t f = 0; f < s->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        const int32_t *he = mesh->halfedge_edge + 3 * f;
        double e[3][3];
        for (int m = 0; m < 3; ++m)
            for (int c = 0; c < 3; ++c) e[m][c] = x[3 * t[(m + 2) % 3] + c] - x[3 * t[(m + 1) % 3] + c];
        /* halfedge 3f+k runs t[k] -> t[k+1] = edge opposite corner k+2, i.e. e[(k+2)%3] */
        double a11 = 0, a12 = 0, a22 = 0;
        const double *e1 = e[2], *e2 = e[0];   /* halfedges 0 (t0->t1) and 1 (t1->t2) */
        for (int c = 0; c < 3; ++c) {
            a11 += e1[c] * e1[c];
            a12 += e1[c] * e2[c];
            a22 += e2[c] * e2[c];
        }
        double det = a11 * a22 - a12 * a12;
        if (!(det > 0.0)) return cfi_error(flow->ctx, CF_ERR_DEGENERATE_FACE, "face %d: degenerate in exactness", f);
        for (int32_t g = 0; g < dim; ++g) {
            const double *w = s->harmonic + (int64_t)g * s->ne;
            /* 1-form values along the halfedges: the edge runs i < j */
            double om[2];
            for (int h = 0; h < 2; ++h) {
                int32_t ed = he[h];
                double sgn = mesh->edge_vertices[2 * ed] == t[h] ? 1.0 : -1.0;
                om[h] = sgn * w[ed];
            }
            double a1 = (a22 * om[0] - a12 * om[1]) / det, a2 = (a11 * om[1] - a12 * om[0]) / det;
            double v[3];
            for (int c = 0; c < 3; ++c) v[c] = a1 * e1[c] + a2 * e2[c];
            double *r = s->zrhs + (int64_t)g * 4 * nv;
            for (int m = 0; m < 3; ++m) {
                /* e_m v = -<e_m, v> + e_m x v */
                const double *em = e[m];
                double *ri = r + 4 * t[m];
                ri[0] += -0.5 * (em[0] * v[0] + em[1] * v[1] + em[2] * v[2]);
                ri[1] += 0.5 * (em[1] * v[2] - em[2] * v[1]);
                ri[2] += 0.5 * (em[2] * v[0] - em[0] * v[2]);
                ri[3] += 0.5 * (em[0] * v[1] - em[1] * v[0]);
            }
        }
    }
    st = cf_cholesky_solve(s->chol0, dim, s->zrhs, s->zsol);
    *solve_seconds += cfi_now_seconds() - t1;
    if (st != CF_OK) return st;
    for (int32_t g = 0; g < dim; ++g) {
        const double *z = s->zsol + (int64_t)g * 4 * nv;
        for (int c = 1; c < 4; ++c) {
            double *b = s->basis + (int64_t)(*col) * nv;
            for (int32_t i = 0; i < nv; ++i) b[i] = z[4 * i + c];
            ++*col;
        }
    }
    return CF_OK;
}

/* Exactness by linearising "no periods" through the discrete step; the
 * default, and the only way on a surface with free boundary: App. C's step "<D Z a,
 * lambda> = <Z a, D lambda>" needs D to be self-adjoint, which fails with
 * the natural boundary condition (Green's formula leaves a boundary
 * integral); measured on annuli, the Z_i constraint does not reduce the
 * period of the transformed edges at all (docs/spin.md). Instead the
 * condition <e~, h_g>_*1 = 0 (no harmonic part = no period around any
 * hole, as h_g spans the Neumann harmonic fields, ops.md) is linearised
 * through the discrete pipeline of one step:
 *  - lambda = X(tau rhodot)^-1 M 1 with X(0) 1 = eps M 1 (D 1 = 0), so to
 *    first order lambda ~ 1 + tau mu, mu = -X(0)^-1 K rhodot, where
 *    K rhodot = X_1(rhodot) 1 = -(1/6) sum_faces e_m (rho_0 + rho_1 + rho_2)
 *    at corner m (App. G: the rho-linear term (rho_m e_n - rho_n e_m) / 6,
 *    sum_n e_n = 0);
 *  - the edge transform (dirac.c) changes by d e~ = (a_i + a_j) e +
 *    e x (u_i + u_j) for mu = (a, u);
 *  - so <d e~, h_g>^c = G_gc . mu, and the constraint is rhodot orthogonal
 *    (in M) to M^-1 K^T X(0)^-1 G_gc, three columns per harmonic form.
 * Exact to first order in tau for one inverse power iteration (the
 * default); an approximation for more. */
static cf_status exactness_columns_linearized(cf_flow *flow, spin_state *s, const double *x, int32_t *col,
                                              double *factor_seconds, double *solve_seconds)
{
    const cf_mesh *mesh = flow->mesh;
    int32_t nv = s->nv, dim = s->harmonic_dim, ncol = 3 * dim;
    double t0 = cfi_now_seconds();
    cf_status st = cfi_dirac_fill(s->dirac, mesh, x, NULL, s->eps);
    if (st != CF_OK) return st;
    st = cf_cholesky_factorize(s->chol0, s->dirac->x);
    double t1 = cfi_now_seconds();
    *factor_seconds += t1 - t0;
    if (st != CF_OK) return st;
    memset(s->zrhs, 0, 4 * (size_t)nv * ncol * sizeof(double));
    for (int32_t e = 0; e < s->ne; ++e) {
        int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
        double v[3] = {x[3 * j] - x[3 * i], x[3 * j + 1] - x[3 * i + 1], x[3 * j + 2] - x[3 * i + 2]};
        /* coefficient of u_l in (v x u)_c: (v x unit_l)_c */
        const double vx[3][3] = {{0.0, v[2], -v[1]}, {-v[2], 0.0, v[0]}, {v[1], -v[0], 0.0}};
        for (int32_t g = 0; g < dim; ++g) {
            double wh = s->hweights[e] * s->harmonic[(int64_t)g * s->ne + e];
            for (int c = 0; c < 3; ++c) {
                double *r = s->zrhs + (int64_t)(3 * g + c) * 4 * nv;
                double q[4] = {wh * v[c], wh * vx[0][c], wh * vx[1][c], wh * vx[2][c]};
                for (int k = 0; k < 4; ++k) {
                    r[4 * i + k] += q[k];
                    r[4 * j + k] += q[k];
                }
            }
        }
    }
    st = cf_cholesky_solve(s->chol0, ncol, s->zrhs, s->zsol);
    *solve_seconds += cfi_now_seconds() - t1;
    if (st != CF_OK) return st;
    for (int32_t k = 0; k < ncol; ++k) {
        const double *y = s->zsol + (int64_t)k * 4 * nv;
        double *b = s->basis + (int64_t)(*col) * nv;
        memset(b, 0, (size_t)nv * sizeof(double));
        /* K^T y: face f adds -(1/6) sum_m <Im y_tri[m], e_m> to each corner */
        for (int32_t f = 0; f < s->nf; ++f) {
            const int32_t *t = mesh->triangles + 3 * f;
            double sum = 0.0;
            for (int m = 0; m < 3; ++m) {
                const double *a = x + 3 * t[(m + 1) % 3], *bb = x + 3 * t[(m + 2) % 3], *ym = y + 4 * t[m];
                for (int c = 0; c < 3; ++c) sum += ym[1 + c] * (bb[c] - a[c]);
            }
            for (int m = 0; m < 3; ++m) b[t[m]] -= sum / 6.0;
        }
        for (int32_t i = 0; i < nv; ++i) b[i] /= s->area[i];
        ++*col;
    }
    return CF_OK;
}

/* Moebius balancing (App. E.1): an inversion direction a that moves the
 * vertex areas toward the input's distribution; adds the corresponding
 * curvature change to rhodot and returns its M-norm. The rate alpha makes
 * the induced change of log scale, -2 alpha <a, f>, the best L2 fit of
 * -u0, so the term vanishes once areas are balanced. */
static double mobius_term(const cf_flow *flow, spin_state *s, const double *x)
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

/* Orthonormalises columns [0, ncols) of the basis under M and projects them
 * out of rhodot; returns the rank. */
static int32_t project(spin_state *s, int32_t ncols)
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

/* ---- step -------------------------------------------------------------- */

/* Steps IV-VI for the time step tau from the current state (rhodot and its
 * constraints computed): rho, lambda, edges, positions (x in place) and the
 * geometry of the new surface (s->energy). */
/* Largest change of the log conformal scale across an edge, |log(|l_i|^2 / |l_j|^2)|. */
static double max_scale_change(const cf_mesh *mesh, const double *lambda)
{
    double worst = 0.0;
    for (int32_t e = 0; e < mesh->ne; ++e) {
        const double *li = lambda + 4 * (int64_t)mesh->edge_vertices[2 * e];
        const double *lj = lambda + 4 * (int64_t)mesh->edge_vertices[2 * e + 1];
        double ni = li[0] * li[0] + li[1] * li[1] + li[2] * li[2] + li[3] * li[3];
        double nj = lj[0] * lj[0] + lj[1] * lj[1] + lj[2] * lj[2] + lj[3] * lj[3];
        double r = ni > 0.0 && nj > 0.0 ? fabs(log(ni / nj)) : INFINITY;
        if (!(r <= worst)) worst = r;
    }
    return worst;
}

static cf_status realise_step(cf_flow *flow, spin_state *s, double tau, int *too_large, double *t_asm, double *t_fac,
                              double *t_sol)
{
    const cf_mesh *mesh = flow->mesh;
    cf_context *ctx = flow->ctx;
    int32_t nv = s->nv;
    double *x = flow->positions;
    cf_status st = CF_OK;
    /* IV. rho = tau rhodot */
    for (int32_t i = 0; i < nv; ++i) s->rho[i] = tau * s->rhodot[i];

    /* V. lambda from X(rho) */
    double ta = cfi_now_seconds();
    /* The shift eps M is the regularisation alpha |lambda - 1|^2_M (option
     * `regularization`); it also makes the eigenproblem definite (X(0) 1 = 0).
     * With a fixed boundary the problem is the linear least-squares solve
     * (X_II + eps M) lambda_I = -X_IB 1 + eps M 1: without the eps M 1 on the
     * right the shift would bias lambda toward 0 (at tau -> 0 it shrank the
     * mushroom cap by 0.8 % and blade_slivers_8k by 47 % per step). */
    st = cfi_dirac_fill(s->dirac, mesh, x, s->rho, s->eps);
    if (st != CF_OK) return st;
    if (s->fixed_boundary) {
        cfi_dirac_fix_boundary(s->dirac, mesh, s->qrhs);
        for (int32_t i = 0; i < nv; ++i)
            if (!mesh->vertex_on_boundary[i]) s->qrhs[4 * i] += s->eps * s->area[i];
    }
    if (s->restricted_boundary) {
        st = boundary_binormals(flow, s, x, s->binormal);
        if (st != CF_OK) return st;
        boundary_frames(flow, s);
        cfi_dirac_restrict_boundary(s->dirac, mesh, s->frames);
    }
    double tb = cfi_now_seconds();
    *t_asm += tb - ta;
    st = cf_cholesky_factorize(s->chol, s->dirac->x);
    double tc = cfi_now_seconds();
    *t_fac += tc - tb;
    if (st != CF_OK) return st;
    if (s->fixed_boundary) {
        st = cf_cholesky_solve(s->chol, 1, s->qrhs, s->lambda);
    } else {
        for (int32_t i = 0; i < nv; ++i) {
            s->lambda[4 * i] = 1.0;
            s->lambda[4 * i + 1] = s->lambda[4 * i + 2] = s->lambda[4 * i + 3] = 0.0;
            if (s->restricted_boundary && mesh->vertex_on_boundary[i]) {
                /* start from Q_i^T 1 restricted to the admissible components */
                const double *q = s->frames + 16 * (int64_t)i;
                s->lambda[4 * i] = q[0];
                s->lambda[4 * i + 1] = q[1];
                s->lambda[4 * i + 2] = s->lambda[4 * i + 3] = 0.0;
            }
        }
        st = cfi_spin_power_iteration(s->chol, s->area, nv, s->opt.power_iterations, s->lambda, s->qwork);
    }
    *t_sol += cfi_now_seconds() - tc;
    if (st != CF_OK) return cfi_error(ctx, st, "spin-willmore: eigenvector solve failed");
    s->diag.eigenvalue = cfi_spin_rayleigh(s->dirac->x, s->area, nv, s->eps, s->lambda, s->qwork);
    if (s->restricted_boundary) {
        /* back to lambda = Q mu on the boundary */
        for (int32_t i = 0; i < nv; ++i) {
            if (!mesh->vertex_on_boundary[i]) continue;
            const double *q = s->frames + 16 * (int64_t)i;
            double mu[4];
            memcpy(mu, s->lambda + 4 * i, sizeof mu);
            for (int r = 0; r < 4; ++r)
                s->lambda[4 * i + r] = q[4 * r] * mu[0] + q[4 * r + 1] * mu[1] + q[4 * r + 2] * mu[2] + q[4 * r + 3] * mu[3];
        }
    }

    /* A lambda whose scale jumps along an edge gives transformed edges that
     * no similar triangle fits (docs/spin.md, "Robustness"): with adaptive
     * steps such a step is redone with a smaller tau before positions are
     * recovered. */
    s->diag.scale_change = max_scale_change(mesh, s->lambda);
    /* (prescribed and cmc boundaries turn lambda by design: not bounded) */
    *too_large = s->opt.adaptive && !s->restricted_boundary && s->opt.max_scale_change > 0.0 &&
                 !(s->diag.scale_change <= s->opt.max_scale_change);
    if (*too_large) return CF_OK;

    /* VI. edges and positions */
    ta = cfi_now_seconds();
    cfi_spin_transform_edges(mesh, x, s->lambda, s->edges);
    *t_asm += cfi_now_seconds() - ta;
    st = cfi_poisson_solve(s->poisson_input ? s->poisson_input : s->poisson, mesh, s->edges, s->fixed_boundary, x,
                           s->newpos, t_fac, t_sol);
    if (st != CF_OK) return st;
    s->diag.integrability_error = cfi_spin_integrability_error(mesh, s->newpos, s->edges);
    if (!s->fixed_boundary) {
        /* fix translation (and the scale, if asked): Willmore energy is invariant under both */
        double c_old[3] = {0, 0, 0}, c_new[3] = {0, 0, 0}, atot = 0.0;
        for (int32_t i = 0; i < nv; ++i) {
            atot += s->area[i];
            for (int c = 0; c < 3; ++c) {
                c_old[c] += s->area[i] * x[3 * i + c];
                c_new[c] += s->area[i] * s->newpos[3 * i + c];
            }
        }
        double scale = 1.0;
        if (s->opt.normalize) {
            double a_new = 0.0;
            st = cf_total_area(ctx, mesh, s->newpos, &a_new);
            if (st != CF_OK) return st;
            if (!(a_new > 0.0)) return cfi_error(ctx, CF_ERR_NUMERICAL, "spin-willmore: recovered surface has no area");
            scale = sqrt(flow->initial_area / a_new);
        }
        for (int32_t i = 0; i < nv; ++i)
            for (int c = 0; c < 3; ++c)
                x[3 * i + c] = c_old[c] / atot + scale * (s->newpos[3 * i + c] - c_new[c] / atot);
    } else {
        memcpy(x, s->newpos, 3 * (size_t)nv * sizeof(double));
    }
    for (int32_t i = 0; i < 3 * nv; ++i)
        if (!isfinite(x[i])) return cfi_error(ctx, CF_ERR_NUMERICAL, "vertex %d: position is not finite", i / 3);

    ta = cfi_now_seconds();
    st = update_geometry(flow, s, x);
    *t_asm += cfi_now_seconds() - ta;
    return st;
}

static cf_status spin_step(cf_flow *flow, cf_flow_info *info)
{
    spin_state *s = flow->impl;
    cf_context *ctx = flow->ctx;
    int32_t nv = s->nv;
    double *x = flow->positions;
    double t_asm = 0.0, t_fac = 0.0, t_sol = 0.0;
    double t0 = cfi_now_seconds();
    double energy_before = s->energy;
    cf_status st = CF_OK;
    memset(&s->diag, 0, sizeof s->diag);

    /* I-II. rhodot = -2 H (Sec. 6.1), then the spectral filter (Sec. 4) */
    for (int32_t i = 0; i < nv; ++i) s->rhodot[i] = -2.0 * s->h[i];
    if (s->opt.sigma > 0.0) {
        if (s->opt.filter_k == 0) {
            for (int32_t i = 0; i < nv; ++i) s->rhodot[i] *= s->filter_scale;
        } else {
            for (int32_t i = 0; i < nv; ++i) s->vtmp[i] = s->filter_mass[i] * s->rhodot[i];
            double ts = cfi_now_seconds();
            st = cf_cholesky_solve(s->filter_chol, 1, s->vtmp, s->vtmp2);
            t_sol += cfi_now_seconds() - ts;
            if (st != CF_OK) return st;
            for (int32_t i = 0; i < nv; ++i) s->rhodot[i] -= s->vtmp2[i];
        }
    }

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
        s->diag.mobius_norm = mobius_term(flow, s, x);
        ncols = 0;
    }
    if (s->opt.total_curvature) {
        double *b = s->basis + (int64_t)ncols * nv;
        for (int32_t i = 0; i < nv; ++i) b[i] = 1.0;
        ++ncols;
    }
    if (s->harmonic_dim > 0) {
        st = s->linearized ? exactness_columns_linearized(flow, s, x, &ncols, &t_fac, &t_sol)
                           : exactness_columns(flow, s, x, &ncols, &t_fac, &t_sol);
        if (st != CF_OK) return st;
    }
    count += ncols;
    rank += project(s, ncols);
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

    /* IV-VI, and with adaptive time steps the step is redone from the same
     * rhodot with tau halved while W would rise (or the step fails
     * numerically); when no halving helps, the state is kept and the flow
     * reports convergence (W stopped decreasing). */
    double tau = s->tau; /* opt.time_step unless adaptive steps changed it */
    int32_t halvings = 0;
    int stalled = 0;
    /* a failed attempt restores x from xsave, so one copy serves every retry */
    if (s->opt.adaptive) memcpy(s->xsave, x, 3 * (size_t)nv * sizeof(double));
    for (;;) {
        int too_large = 0;
        st = realise_step(flow, s, tau, &too_large, &t_asm, &t_fac, &t_sol);
        if (!s->opt.adaptive) break;
        /* prescribed and cmc boundaries may raise W by design: only the scale bound applies */
        if (st == CF_OK && !too_large && (s->energy <= energy_before || s->restricted_boundary)) break;
        if (st != CF_OK && st != CF_ERR_NUMERICAL && st != CF_ERR_NOT_POSDEF && st != CF_ERR_DEGENERATE_FACE)
            return st;
        memcpy(x, s->xsave, 3 * (size_t)nv * sizeof(double));
        cf_status sg = update_geometry(flow, s, x);
        if (sg != CF_OK) return sg;
        if (halvings == CFI_SPIN_MAX_HALVINGS) {
            stalled = 1;
            st = CF_OK;
            cfi_log(ctx, CF_LOG_INFO,
                    "spin-willmore: W does not decrease for any time step down to %g; stopping at W/4pi = %.6g", tau,
                    s->energy / (4.0 * CFI_PI));
            break;
        }
        ++halvings;
        /* the scale change grows about linearly with tau: cut it in proportion (at least halve) */
        tau *= too_large ? fmin(0.5, 0.9 * s->opt.max_scale_change / s->diag.scale_change) : 0.5;
    }
    if (st != CF_OK) return st;
    if (s->opt.adaptive && !stalled) s->tau = halvings ? tau : fmin(s->opt.time_step, 2.0 * tau);
    /* An explicit step on rho can overshoot where the realised curvature
     * change is far from the prescribed one (thin cone tips, slivers;
     * docs/spin.md): a jump of the energy by more than blowup_factor is
     * reported as a failure so that the flow layer keeps the last good state. */
    if (s->opt.blowup_factor > 0.0 && energy_before > 0.0 && s->energy > s->opt.blowup_factor * energy_before)
        return cfi_error(ctx, CF_ERR_NUMERICAL,
                         "spin-willmore: energy grew from %.6g to %.6g in one step (more than %gx): the step blew "
                         "up; try a smaller time_step",
                         energy_before, s->energy, s->opt.blowup_factor);
    /* A Willmore descent that ends above its start has diverged, even when
     * it creeps up by less than blowup_factor per step (elephant_g3_3k at
     * the default tau: 24.99 -> 12.46 -> 26.9 -> 102 -> ...). Prescribed and
     * cmc boundaries may raise W by design. The slack absorbs rounding at an
     * equilibrium start (a round sphere). */
    if (s->opt.divergence_factor > 0.0 && !s->restricted_boundary &&
        s->energy > s->opt.divergence_factor * s->initial_energy * (1.0 + 1e-9))
        return cfi_error(ctx, CF_ERR_NUMERICAL,
                         "spin-willmore: W/4pi rose to %.6g, above %g times its starting value %.6g: the flow "
                         "diverges (time_step %g is above this mesh's stability limit); try a smaller time_step, "
                         "adaptive=1 or a larger regularization (docs/spin.md)",
                         s->energy / (4.0 * CFI_PI), s->opt.divergence_factor, s->initial_energy / (4.0 * CFI_PI), tau);

    info->time_step = stalled ? 0.0 : tau;
    info->energy = s->energy;
    info->energy_terms[0] = s->energy / (4.0 * CFI_PI);
    info->term_names[0] = "W/4pi";
    info->residuals[0] = s->diag.constraint_residual;
    info->residual_names[0] = "constraint";
    info->residuals[1] = s->diag.integrability_error;
    info->residual_names[1] = "integrability";
    info->residuals[2] = s->diag.eigenvalue;
    info->residual_names[2] = "eigenvalue";
    if (s->opt.adaptive) {
        info->residuals[3] = halvings;
        info->residual_names[3] = "time_step_halvings";
    }
    info->residuals[4] = s->diag.scale_change;
    info->residual_names[4] = "scale_change";
    info->assemble_seconds = t_asm;
    info->factorize_seconds = t_fac;
    info->solve_seconds = t_sol;
    info->total_seconds = cfi_now_seconds() - t0;
    double decrease = energy_before - s->energy;
    flow->converged = stalled || (decrease >= 0.0 && decrease <= s->opt.tolerance * energy_before);
    return CF_OK;
}

static cf_status spin_reset(cf_flow *flow)
{
    spin_state *s = flow->impl;
    if (!s) return CF_OK;
    s->tau = s->opt.time_step;
    flow->converged = 0;
    cf_status st = update_geometry(flow, s, flow->positions);
    s->initial_energy = s->energy; /* new positions: a new start for the divergence check */
    return st;
}

cf_status cfi_spin_willmore_diagnostics(const cf_flow *flow, cfi_spin_diagnostics *out)
{
    if (!flow || !out || flow->method != &cfi_spin_willmore_method || !flow->impl) return CF_ERR_INVALID_ARG;
    *out = ((const spin_state *)flow->impl)->diag;
    return CF_OK;
}

const double *cfi_spin_willmore_harmonic_forms(const cf_flow *flow, int32_t *dimension)
{
    if (dimension) *dimension = 0;
    if (!flow || flow->method != &cfi_spin_willmore_method || !flow->impl) return NULL;
    const spin_state *s = flow->impl;
    if (dimension) *dimension = s->harmonic_dim;
    return s->harmonic;
}

const double *cfi_spin_willmore_last_edges(const cf_flow *flow)
{
    if (!flow || flow->method != &cfi_spin_willmore_method || !flow->impl) return NULL;
    return ((const spin_state *)flow->impl)->edges;
}

const double *cfi_spin_willmore_last_rhodot(const cf_flow *flow)
{
    if (!flow || flow->method != &cfi_spin_willmore_method || !flow->impl) return NULL;
    return ((const spin_state *)flow->impl)->rhodot;
}

const cfi_flow_method cfi_spin_willmore_method = {
    .kind = CF_FLOW_SPIN_WILLMORE,
    .name = "spin-willmore",
    .description = "conformal Willmore flow in curvature space (Crane, Pinkall, Schroeder 2013)",
    .options_size = sizeof(cf_spin_willmore_options),
    .options_default = options_default,
    .params = spin_params,
    .param_count = (int32_t)(sizeof spin_params / sizeof spin_params[0]),
    .create = spin_create,
    .step = spin_step,
    .reset = spin_reset,
    .destroy = spin_destroy,
};
