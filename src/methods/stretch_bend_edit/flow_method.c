/*
 * Mesh editing by local/global iteration — Zhao & Gortler, "A Report on
 * Shape Deformation with a Stretching and Bending Energy" (hybrid energy,
 * Eq. 17, and its stretch-only / bend-only limits), plus ARAP spokes
 * (Sorkine & Alexa 2007, Eq. 6) and spokes-and-rims (Eq. 7) for comparison.
 *
 * Global phase (Sec. 4.1): with R and u' fixed the energy is quadratic;
 * the normal equations (Eq. 23, with K = M L_pointwise = 2 L)
 *     [alpha K_t + beta K M^-1 K] x' = alpha b + beta K (|H| u')
 * are solved for the free vertices, the handle columns moved to the
 * right-hand side (linalg's cf_min_quad, fixed values). The matrix depends
 * only on the rest shape and the handle set, so it is factorised once per
 * handle set; each iteration solves three right-hand sides. Anderson
 * acceleration of the local/global map: linalg's cf_anderson. Local phase:
 * model.c.
 */
#include "methods/flow_internal.h"
#include "methods/stretch_bend_edit/stretch_bend_internal.h"

#include "curvflow/stretch_bend_edit.h"

#include <math.h>
#include <string.h>

typedef struct stretch_bend_state {
    cfi_stretch_bend_model model;
    cf_stretch_bend_options options;
    cfi_workspace ws;         /* the per-flow arrays: rest, rhs, hu, x_start, b_cols, x_cols, aa_g, aa_x
                               * (the handle arrays follow the handles: free_system) */
    /* The iteration runs in coordinates relative to `origin` (the centre of
     * the rest pose's bounding box): positions 1e6 from the origin keep
     * only ~1e-10 of absolute resolution, and re-rounding the state to it
     * at every iteration stalled the hybrid edit of a spot moved 1e6 away
     * at an energy 28 % above the same edit at the origin. flow->positions
     * gets origin + xr after each step (handles snapped to their targets
     * exactly); reset reads it back. */
    double origin[3];
    double *xr;               /* 3 nv: the current state, relative to origin */
    double *rest;             /* 3 nv, the rest pose relative to origin */
    double *a_rest;           /* 3 nv by coordinate: A_full rest (from its differences), for the global solve */
    int32_t handle_count;
    int32_t *handle_vertices; /* copy of the handle set */
    double *handle_targets;   /* 3 handle_count, absolute */
    double *handle_rel;       /* 3 handle_count: the targets relative to origin */
    cf_sparse *a_full;        /* nv x nv system matrix (before the handles are eliminated) */
    cf_min_quad *mq;          /* A_full with the handles fixed (linalg's precompute / solve) */
    double *y_cols;           /* 3 handle_count: target - rest by coordinate (known values of mq, displacements) */
    double *b_cols;           /* 3 nv: -rhs by coordinate (linear term of mq) */
    double *x_cols;           /* 3 nv: the solution by coordinate */
    double *rhs;              /* 3 nv interleaved right-hand side (full) */
    double *hu;               /* 3 nv interleaved |H| u' */
    double energy;            /* E at the current positions */
    double *x_start;          /* 3 nv: the starting state with its handles on their targets */
    int32_t first_pending;    /* the next step is the first after create/reset: two candidates */
    int64_t first_from_start; /* first steps won by the rotations of the unsnapped start (statistics) */
    double factorize_seconds; /* of the last (re)factorisation, reported once */
    /* Anderson acceleration of G = global(local(x)) (depth from
     * options.anderson, see stretch_bend_create; linalg's cf_anderson): */
    int32_t aa_depth;
    cf_anderson *aa;
    double *aa_g, *aa_x;      /* 3 nv each: G(x) and the mixed candidate */
    int64_t aa_accepted, aa_rejected;
    int32_t negative_warned;  /* the warning of a negative ARAP energy was logged */
} stretch_bend_state;

static const char *const energy_names[] = {"hybrid", "stretch", "bend", "arap", "arap-rims", NULL};
static const char *const mass_names[] = {"voronoi", "barycentric", NULL};
static const char *const arap_weight_names[] = {"cotan", "clamped", NULL};

const char *cf_stretch_bend_energy_name(cf_stretch_bend_energy_kind energy)
{
    if ((int)energy < 0 || (int)energy >= CF_STRETCH_BEND_ENERGY_COUNT) return NULL;
    return energy_names[energy];
}

cf_status cf_stretch_bend_energy_from_name(cf_context *ctx, const char *name, cf_stretch_bend_energy_kind *energy)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!name || !energy) return cfi_error(ctx, CF_ERR_INVALID_ARG, "energy name or output is NULL");
    for (int k = 0; k < CF_STRETCH_BEND_ENERGY_COUNT; ++k) {
        if (strcmp(name, energy_names[k]) == 0) {
            *energy = (cf_stretch_bend_energy_kind)k;
            return CF_OK;
        }
    }
    return cfi_error(ctx, CF_ERR_INVALID_ARG,
                     "unknown energy '%s' (expected hybrid, stretch, bend, arap or arap-rims)", name);
}

void cf_stretch_bend_options_default(cf_stretch_bend_options *o)
{
    if (!o) return;
    memset(o, 0, sizeof *o);
    o->energy = CF_STRETCH_BEND_HYBRID;
    o->lambda = 0.5;
    o->max_iterations = 100;
    o->relative_tolerance = 1e-6;
    o->mass = CF_STRETCH_BEND_MASS_VORONOI;
    o->scale_free = 1;
    o->anderson = -1;
}

static void options_default(void *options) { cf_stretch_bend_options_default(options); }

static const cf_param_desc params[] = {
    {"energy", CF_PARAM_CHOICE, offsetof(cf_stretch_bend_options, energy), 0, 4, energy_names,
     "energy: hybrid (Eq. 17), stretch (Eq. 5), bend (Eq. 15), arap (Eq. 6), arap-rims (Eq. 7)"},
    {"lambda", CF_PARAM_DOUBLE, offsetof(cf_stretch_bend_options, lambda), 0.0, 1.0, NULL,
     "hybrid weight: lambda E_s + (1 - lambda) E_db"},
    {"max_iterations", CF_PARAM_INT, offsetof(cf_stretch_bend_options, max_iterations), 1, 1e7, NULL,
     "local/global iterations for the one-off edit"},
    {"relative_tolerance", CF_PARAM_DOUBLE, offsetof(cf_stretch_bend_options, relative_tolerance), 0.0, 1.0, NULL,
     "converged when the relative energy decrease of a step is below this"},
    {"mass", CF_PARAM_CHOICE, offsetof(cf_stretch_bend_options, mass), 0, 1, mass_names,
     "dual area M_v of the bending energy"},
    {"scale_free", CF_PARAM_BOOL, offsetof(cf_stretch_bend_options, scale_free), 0, 1, NULL,
     "divide the stretching energy by the rest area so lambda does not depend on the model's size"},
    {"anderson", CF_PARAM_INT, offsetof(cf_stretch_bend_options, anderson), -1, 10, NULL,
     "Anderson acceleration depth (0 = plain local/global; -1 = 5 for hybrid/stretch/bend, 0 for ARAP); "
     "energy-safeguarded"},
    {"arap_weights", CF_PARAM_CHOICE, offsetof(cf_stretch_bend_options, arap_weights), 0, 1, arap_weight_names,
     "edge weights of arap and arap-rims: cotan (cot a + cot b, Eq. 6/7; negative on non-Delaunay edges, where the "
     "energy is not bounded below) or clamped (negative ones set to 0)"},
    {"handles", CF_PARAM_POINT_SETS, offsetof(cf_stretch_bend_options, handles), 1, 1, NULL,
     "handle vertices with their targets: a JSON handle file (format in docs/edit.md); required"},
};

static void free_system(stretch_bend_state *s, cf_context *ctx)
{
    cf_min_quad_destroy(&s->mq);
    CFI_FREE(ctx, s->handle_vertices, (size_t)s->handle_count);
    CFI_FREE(ctx, s->handle_targets, 3 * (size_t)s->handle_count);
    CFI_FREE(ctx, s->handle_rel, 3 * (size_t)s->handle_count);
    CFI_FREE(ctx, s->y_cols, 3 * (size_t)s->handle_count);
    s->handle_count = 0;
}

static void state_free(stretch_bend_state *s, cf_context *ctx)
{
    if (!s) return;
    free_system(s, ctx);
    cf_sparse_destroy(&s->a_full);
    cf_anderson_destroy(&s->aa);
    cfi_workspace_free_all(&s->ws);
    cfi_stretch_bend_model_free(&s->model);
    cfi_free(ctx, s, sizeof *s);
}

/* A = alpha K_t + beta K M^-1 K on all vertices (Eq. 23 times 1/2 of the
 * gradient), K_t = sum over terms w (d_i - d_j)(d_i - d_j)^T. */
static cf_status build_full_matrix(stretch_bend_state *s, cf_context *ctx)
{
    cfi_stretch_bend_model *m = &s->model;
    int32_t nv = m->nv;
    cf_sparse *kt = NULL, *dk = NULL, *kmk = NULL;
    cf_status st = CF_OK;
    if (m->alpha > 0.0 && m->term_count > 0) {
        int64_t n = 4 * (int64_t)m->term_count;
        int32_t *rows = CFI_ALLOC(ctx, int32_t, n);
        int32_t *cols = CFI_ALLOC(ctx, int32_t, n);
        double *vals = CFI_ALLOC(ctx, double, n);
        if (rows && cols && vals) {
            for (int32_t t = 0; t < m->term_count; ++t) {
                int32_t i = m->term_ij[2 * t], j = m->term_ij[2 * t + 1];
                double w = m->alpha * m->term_w[t];
                int64_t b = 4 * (int64_t)t;
                rows[b] = i; cols[b] = i; vals[b] = w;
                rows[b + 1] = j; cols[b + 1] = j; vals[b + 1] = w;
                rows[b + 2] = i; cols[b + 2] = j; vals[b + 2] = -w;
                rows[b + 3] = j; cols[b + 3] = i; vals[b + 3] = -w;
            }
            st = cf_sparse_from_triplets(ctx, nv, nv, n, rows, cols, vals, 1, &kt, NULL);
        } else {
            st = CF_ERR_NOMEM;
        }
        CFI_FREE(ctx, rows, n);
        CFI_FREE(ctx, cols, n);
        CFI_FREE(ctx, vals, n);
        if (st != CF_OK) return st;
    }
    if (m->beta > 0.0) {
        /* D K with D = beta M^-1 (rows scaled), then K (D K). */
        st = cf_sparse_add(ctx, 1.0, m->k, 0.0, m->k, &dk);
        if (st == CF_OK) {
            for (int32_t j = 0; j < dk->ncols; ++j)
                for (int32_t p = dk->colptr[j]; p < dk->colptr[j + 1]; ++p)
                    dk->values[p] *= m->beta / m->mass[dk->rowind[p]];
            st = cf_sparse_product(ctx, m->k, dk, &kmk);
        }
        cf_sparse_destroy(&dk);
        if (st == CF_OK && kmk) kmk->symmetric = 1;
    }
    if (st == CF_OK) {
        if (kt && kmk) {
            st = cf_sparse_add(ctx, 1.0, kt, 1.0, kmk, &s->a_full);
            if (st == CF_OK) s->a_full->symmetric = 1;
        } else if (kt) {
            s->a_full = kt;
            kt = NULL;
        } else if (kmk) {
            s->a_full = kmk;
            kmk = NULL;
        } else {
            st = cfi_error(ctx, CF_ERR_INVALID_ARG, "stretch-bend-edit: the energy has no terms");
        }
    }
    cf_sparse_destroy(&kt);
    cf_sparse_destroy(&kmk);
    return st;
}

/* Validates the handles against the mesh, reduces A to the free vertices,
 * factorises it and precomputes A_fc x_c (Sec. 4.1). */
static cf_status build_system(stretch_bend_state *s, cf_context *ctx, const cf_mesh *mesh, const cf_handle_set *h);

/* out = A_full x by coordinate (x interleaved, out column-major), through
 * the differences of the coordinates: A_full's rows sum to zero (the
 * energy sees positions only through their differences), and a mesh far
 * from the origin keeps its precision (cf_sparse_multiply_zero_row_sums). */
static void apply_full_matrix(stretch_bend_state *s, const double *x, double *out)
{
    int32_t nv = s->model.nv;
    double *xcol = s->model.xcol;
    for (int d = 0; d < 3; ++d) {
        for (int32_t v = 0; v < nv; ++v) xcol[v] = x[3 * (size_t)v + d];
        cf_sparse_multiply_zero_row_sums(s->a_full, xcol, out + (size_t)d * nv);
    }
}

/* Index of vertex v in the sorted handle list, or -1. */
static int32_t handle_index(const cf_handle_set *h, int32_t v)
{
    int32_t lo = 0, hi = h->count - 1;
    while (lo <= hi) {
        int32_t mid = lo + (hi - lo) / 2;
        if (h->vertices[mid] == v) return mid;
        if (h->vertices[mid] < v) lo = mid + 1;
        else hi = mid - 1;
    }
    return -1;
}

/* Targets that force a degenerate triangle: the two ends of an edge at the
 * same point, or the three corners of a face on one line. Any edit would
 * then have a zero-area face, which the mesh check (and every reader)
 * rejects, so the request is refused instead of producing such a mesh. */
static cf_status check_handle_geometry(cf_context *ctx, const cf_mesh *mesh, const cf_handle_set *h)
{
    const double *x = mesh->positions;
    for (int32_t e = 0; e < mesh->ne; ++e) {
        int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
        int32_t a = handle_index(h, i), b = a >= 0 ? handle_index(h, j) : -1;
        if (b < 0) continue;
        double d2 = 0.0, r2 = 0.0;
        for (int c = 0; c < 3; ++c) {
            double d = h->targets[3 * a + c] - h->targets[3 * b + c], r = x[3 * j + c] - x[3 * i + c];
            d2 += d * d;
            r2 += r * r;
        }
        if (d2 <= 1e-24 * r2)
            return cfi_error(ctx, CF_ERR_INVALID_ARG,
                             "stretch-bend-edit: vertices %d and %d share an edge but their handle targets coincide "
                             "(every edit would have a zero-area face)",
                             i, j);
    }
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * (size_t)f;
        int32_t k[3] = {handle_index(h, t[0]), -1, -1};
        if (k[0] < 0 || (k[1] = handle_index(h, t[1])) < 0 || (k[2] = handle_index(h, t[2])) < 0) continue;
        double l2;
        double area = cfi_triangle_area(h->targets + 3 * k[0], h->targets + 3 * k[1], h->targets + 3 * k[2], &l2);
        if (area <= CFI_ZERO_AREA_RATIO * l2) /* the mesh check's zero-area test */
            return cfi_error(ctx, CF_ERR_INVALID_ARG,
                             "stretch-bend-edit: face %d: its three vertices are handles with collinear targets "
                             "(the edit would have a zero-area face)",
                             f);
    }
    return CF_OK;
}

static cf_status setup_system(stretch_bend_state *s, cf_context *ctx, const cf_mesh *mesh, const cf_handle_set *h)
{
    int32_t nv = mesh->nv;
    if (!h)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "stretch-bend-edit needs handles: set cf_stretch_bend_options.handles "
                         "(cf_handle_set_read_json reads a handle file; tool: --handles FILE or `curvflow edit`)");
    if (h->count < 0 || (h->count > 0 && (!h->vertices || !h->targets)))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "stretch-bend-edit: malformed handle set");
    if (h->count == 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "stretch-bend-edit: the handle set is empty; at least one "
                                                  "vertex per connected component must be constrained");
    for (int32_t k = 0; k < h->count; ++k) {
        int32_t v = h->vertices[k];
        if (v < 0 || v >= nv)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "handle %d: vertex %d out of range (mesh has %d vertices)",
                             k, v, nv);
        if (k > 0 && v <= h->vertices[k - 1])
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "handle %d: vertex %d repeated or not sorted", k, v);
        if (cfi_first_unusable_point(h->targets + 3 * k, 1, 3) >= 0)
            return cfi_error(ctx, CF_ERR_NONFINITE, "handle %d (vertex %d): target is not finite or beyond %.0e", k, v,
                             CF_MAX_COORDINATE);
    }
    if (h->count >= nv)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "stretch-bend-edit: all %d vertices are handles; nothing to solve",
                         nv);
    cf_status st = check_handle_geometry(ctx, mesh, h);
    if (st != CF_OK) return st;

    st = build_system(s, ctx, mesh, h);
    /* A half-built system is released entirely (steps then report it). */
    if (st != CF_OK) free_system(s, ctx);
    return st;
}

static cf_status build_system(stretch_bend_state *s, cf_context *ctx, const cf_mesh *mesh, const cf_handle_set *h)
{
    int32_t nv = mesh->nv;
    free_system(s, ctx);
    s->handle_vertices = CFI_ALLOC(ctx, int32_t, (size_t)h->count);
    s->handle_targets = CFI_ALLOC(ctx, double, 3 * (size_t)h->count);
    s->handle_rel = CFI_ALLOC(ctx, double, 3 * (size_t)h->count);
    s->y_cols = CFI_ALLOC(ctx, double, 3 * (size_t)h->count);
    s->handle_count = h->count; /* the size free_system releases */
    if (!s->handle_vertices || !s->handle_targets || !s->handle_rel || !s->y_cols) return CF_ERR_NOMEM;
    memcpy(s->handle_vertices, h->vertices, (size_t)h->count * sizeof(int32_t));
    memcpy(s->handle_targets, h->targets, 3 * (size_t)h->count * sizeof(double));
    for (int32_t k = 0; k < h->count; ++k)
        for (int d = 0; d < 3; ++d) {
            s->handle_rel[3 * k + d] = h->targets[3 * k + d] - s->origin[d];
            s->y_cols[(size_t)d * h->count + k] = s->handle_rel[3 * k + d] - s->rest[3 * (size_t)h->vertices[k] + d];
        }

    /* Every connected component needs a handle, else the system is
     * singular (translations of that component cost nothing). */
    int32_t nc = mesh->component_count;
    uint8_t *has = CFI_ALLOC(ctx, uint8_t, (size_t)(nc > 0 ? nc : 1));
    if (!has) return CF_ERR_NOMEM;
    for (int32_t k = 0; k < h->count; ++k) has[mesh->vertex_component[h->vertices[k]]] = 1;
    int32_t missing = -1;
    for (int32_t v = 0; v < nv && missing < 0; ++v)
        if (!has[mesh->vertex_component[v]]) missing = v;
    CFI_FREE(ctx, has, (size_t)(nc > 0 ? nc : 1));
    if (missing >= 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "stretch-bend-edit: the connected component of vertex %d has no handle vertex "
                         "(the system would be singular)", missing);

    /* Sec. 4.1: the handle columns move to the right-hand side and the
     * free block is factorised once per handle set (linalg's cf_min_quad;
     * the three coordinates are its three right-hand sides). */
    double t0 = cfi_now_seconds();
    cf_min_quad_options qo;
    cf_min_quad_options_default(&qo);
    qo.block_size = 1;
    qo.max_rhs = 3;
    cf_status st = cf_min_quad_create(ctx, s->a_full, h->count, h->vertices, NULL, &qo, &s->mq);
    s->factorize_seconds = cfi_now_seconds() - t0;
    if (st == CF_ERR_NOT_POSDEF)
        return cfi_error(ctx, CF_ERR_NOT_POSDEF,
                         "stretch-bend-edit: the %s system is not positive definite on this mesh (negative cotan "
                         "weights; the ARAP spokes energy can be indefinite, try arap-rims or hybrid)",
                         cf_stretch_bend_energy_name(s->model.energy));
    return st;
}

/* The handle vertices of x (relative to origin) on their targets. */
static void snap_handles(const stretch_bend_state *s, double *x)
{
    for (int32_t k = 0; k < s->handle_count; ++k)
        memcpy(x + 3 * (size_t)s->handle_vertices[k], s->handle_rel + 3 * (size_t)k, 3 * sizeof(double));
}

/* out = origin + rel (out may be rel), the handles exactly on their targets. */
static void to_absolute(const stretch_bend_state *s, const double *rel, double *out)
{
    for (int32_t v = 0; v < s->model.nv; ++v)
        for (int d = 0; d < 3; ++d) out[3 * (size_t)v + d] = s->origin[d] + rel[3 * (size_t)v + d];
    for (int32_t k = 0; k < s->handle_count; ++k)
        memcpy(out + 3 * (size_t)s->handle_vertices[k], s->handle_targets + 3 * (size_t)k, 3 * sizeof(double));
}

/* flow->positions = origin + xr. */
static void publish_state(cf_flow *flow, const stretch_bend_state *s) { to_absolute(s, s->xr, flow->positions); }

/* xr = flow->positions - origin, then the starting state (start_state). */
static cf_status start_state(stretch_bend_state *s, double *x);
static cf_status load_state(cf_flow *flow, stretch_bend_state *s)
{
    for (int32_t v = 0; v < s->model.nv; ++v)
        for (int d = 0; d < 3; ++d) s->xr[3 * (size_t)v + d] = flow->positions[3 * (size_t)v + d] - s->origin[d];
    cf_status st = start_state(s, s->xr);
    if (st == CF_OK) publish_state(flow, s);
    return st;
}

static void fill_terms(const stretch_bend_state *s, cf_flow_info *info)
{
    int arap = s->model.energy == CF_STRETCH_BEND_ARAP || s->model.energy == CF_STRETCH_BEND_ARAP_RIMS;
    info->energy = s->energy;
    if (arap) {
        info->term_names[0] = cf_stretch_bend_energy_name(s->model.energy);
        info->energy_terms[0] = s->model.term_energy;
    } else {
        info->term_names[0] = "stretch";
        info->energy_terms[0] = s->model.term_energy;
        info->term_names[1] = "bend";
        info->energy_terms[1] = s->model.bend_energy;
    }
}

/* Starting state (create, reset, new handles): the handle vertices of x
 * are moved to their targets; E(x0) of that state (optimal rotations) is
 * reported as iteration 0. The first step then tries two sets of rotations
 * and u' for its global phase and keeps the result of lower energy:
 *  (a) those of x BEFORE the handles moved (the rest pose, or the previous
 *      solution when the handles change, as interactive ARAP editing
 *      does): the first global phase is the linear (bi-)Laplacian edit of
 *      the unrotated shape. Best for translations: on the cactus edit the
 *      energy after 10 iterations drops from 0.30 to 0.055;
 *  (b) those of the snapped state x0 (the plain local/global step), which
 *      carry the rotation of rotated handles into the triangles next to
 *      them: on the bar whose top face is turned by 90 degrees, (a) leads
 *      into a worse local minimum (0.382 against 0.311 after 3000 steps),
 *      and (b) has the lower energy after the first step (17 against 44).
 * (b) alone guarantees E(x1) <= E(x0), so the energy still never
 * increases. This function leaves the rotations of (a) in the model and x0
 * in x_start. */
static cf_status start_state(stretch_bend_state *s, double *x)
{
    size_t n3 = 3 * (size_t)s->model.nv;
    memcpy(s->x_start, x, n3 * sizeof(double));
    snap_handles(s, x);
    cf_status st = cfi_stretch_bend_local_step(&s->model, x, 1, &s->energy);
    if (st != CF_OK) return st;
    s->first_pending = 0;
    if (memcmp(s->x_start, x, n3 * sizeof(double)) != 0) {
        double term = s->model.term_energy, bend = s->model.bend_energy, unused = 0.0;
        st = cfi_stretch_bend_local_step(&s->model, s->x_start, 1, &unused);
        /* The reported terms stay those of the snapped state. */
        s->model.term_energy = term;
        s->model.bend_energy = bend;
        if (st != CF_OK) return st;
        memcpy(s->x_start, x, n3 * sizeof(double));
        s->first_pending = 1;
    }
    return CF_OK;
}

static cf_status stretch_bend_create(cf_flow *flow, const void *options)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    int32_t nv = mesh->nv;
    const cf_stretch_bend_options *o = options;
    stretch_bend_state *s = cfi_malloc(ctx, sizeof *s);
    if (!s) return CF_ERR_NOMEM;
    memset(s, 0, sizeof *s);
    s->model.nv = nv;
    flow->impl = s;
    s->options = *o;
    cfi_workspace_init(&s->ws, ctx);
    s->rest = CFI_WS_ALLOC(&s->ws, double, 3 * (size_t)nv);
    s->rhs = CFI_WS_ALLOC(&s->ws, double, 3 * (size_t)nv);
    s->hu = CFI_WS_ALLOC(&s->ws, double, 3 * (size_t)nv);
    s->x_start = CFI_WS_ALLOC(&s->ws, double, 3 * (size_t)nv);
    s->b_cols = CFI_WS_ALLOC(&s->ws, double, 3 * (size_t)nv);
    s->x_cols = CFI_WS_ALLOC(&s->ws, double, 3 * (size_t)nv);
    s->a_rest = CFI_WS_ALLOC(&s->ws, double, 3 * (size_t)nv);
    s->xr = CFI_WS_ALLOC(&s->ws, double, 3 * (size_t)nv);
    if (!s->rest || !s->rhs || !s->hu || !s->x_start || !s->b_cols || !s->x_cols || !s->a_rest || !s->xr)
        return CF_ERR_NOMEM;
    /* every table parameter (ranges, handles given, rest pose count) was
     * checked by cf_flow_create */
    /* -1 (default): depth 5 for the energies with per-triangle rotations
     * and u', whose plain iteration needs thousands of steps on large
     * edits; off for ARAP, which converges in tens to hundreds of steps,
     * and where Anderson mixing, a fixed-point solver, can settle on a
     * saddle plateau: on the sheet twist (n = 16) it stopped at E = 0.070
     * at the default tolerance where the plain iteration goes on to the
     * buckled minimum E = 0.041 (docs/edit.md). */
    int32_t depth_opt = o->anderson;
    if (depth_opt < 0) depth_opt = (o->energy == CF_STRETCH_BEND_ARAP || o->energy == CF_STRETCH_BEND_ARAP_RIMS) ? 0 : 5;
    if (depth_opt > 0) {
        size_t n3 = 3 * (size_t)nv;
        s->aa_depth = depth_opt;
        s->aa_g = CFI_WS_ALLOC(&s->ws, double, n3);
        s->aa_x = CFI_WS_ALLOC(&s->ws, double, n3);
        if (!s->aa_g || !s->aa_x) return CF_ERR_NOMEM;
        cf_status ast = cf_anderson_create(ctx, (int64_t)n3, depth_opt, &s->aa);
        if (ast != CF_OK) return ast;
    }
    const double *rest = o->rest_positions ? o->rest_positions : mesh->positions;
    for (int32_t i = 0; i < 3 * nv; ++i)
        if (!isfinite(rest[i]))
            return cfi_error(ctx, CF_ERR_NONFINITE, "vertex %d: rest position is not finite", i / 3);
    cfi_bounding_box_centre(rest, nv, s->origin);
    for (int32_t i = 0; i < 3 * nv; ++i) s->rest[i] = rest[i] - s->origin[i % 3];
    cf_status st = cfi_stretch_bend_model_init(&s->model, ctx, mesh, s->rest, o);
    if (st == CF_OK) {
        s->model.rhs = s->rhs;
        s->model.hu = s->hu;
        st = build_full_matrix(s, ctx);
        if (st == CF_OK) apply_full_matrix(s, s->rest, s->a_rest);
        if (s->model.clamped && s->model.negative_edges > 0)
            cfi_log(ctx, CF_LOG_INFO, "stretch-bend-edit: arap_weights clamped: %d of %d edge weights were negative "
                                      "and are 0", (int)s->model.negative_edges, (int)mesh->ne);
    }
    if (st == CF_OK) st = setup_system(s, ctx, mesh, o->handles);
    if (st != CF_OK) return st;
    /* The starting state has its handles at their targets; iteration 0
     * reports its energy with optimal rotations. */
    st = load_state(flow, s);
    if (st != CF_OK) return st;
    fill_terms(s, &flow->info);
    flow->info.factorize_seconds = s->factorize_seconds;
    flow->converged = 0;
    return CF_OK;
}

/* Right-hand side of Eq. 23 on all vertices (interleaved) into s->rhs. */
static void assemble_rhs(stretch_bend_state *s)
{
    s->model.hu = s->hu;
    cfi_stretch_bend_assemble_rhs(&s->model, s->rhs);
}

/* Global phase: x (3 nv interleaved) receives the minimiser over the free
 * vertices for the current rotations and u', handles at their targets. */
static cf_status global_solve(stretch_bend_state *s, double *x, double *assemble_seconds, double *solve_seconds)
{
    int32_t nv = s->model.nv;
    double t0 = cfi_now_seconds();
    /* The local step has assembled the right-hand side (model.rhs). */
    if (!s->model.rhs) assemble_rhs(s);
    /* A x = rhs, solved for the displacement from the rest pose d = x -
     * rest: d minimises 1/2 d^T A d + b^T d with b = A rest - rhs, the
     * handles at target - rest. The same minimiser; but a mesh far from the
     * origin keeps its precision: solving for x directly carried
     * cond(A) eps |x| of error (spot 1e6 away: the hybrid edit ended 2.5 %
     * of spot's size off, its energy 23 % higher). */
    const double *rhs = s->rhs;
    for (int32_t v = 0; v < nv; ++v)
        for (int d = 0; d < 3; ++d)
            s->b_cols[(size_t)d * nv + v] = s->a_rest[(size_t)d * nv + v] - rhs[3 * (size_t)v + d];
    double t1 = cfi_now_seconds();
    cf_status st = cf_min_quad_solve(s->mq, 3, s->b_cols, s->y_cols, NULL, s->x_cols);
    if (st != CF_OK) return st;
    double t2 = cfi_now_seconds();
    for (int32_t v = 0; v < nv; ++v)
        for (int d = 0; d < 3; ++d) x[3 * v + d] = s->rest[3 * (size_t)v + d] + s->x_cols[(size_t)d * nv + v];
    /* the handle vertices come back exactly on their targets */
    snap_handles(s, x);
    if (assemble_seconds) *assemble_seconds = t1 - t0;
    if (solve_seconds) *solve_seconds = t2 - t1;
    return CF_OK;
}

cf_status cfi_stretch_bend_flow_global_solve(cf_flow *flow, double *x)
{
    if (!flow || flow->method != &cfi_stretch_bend_edit_method || !flow->impl || !x) return CF_ERR_INVALID_ARG;
    stretch_bend_state *s = flow->impl;
    cf_status st = global_solve(s, x, NULL, NULL);
    if (st != CF_OK) return st;
    to_absolute(s, x, x); /* as the flow's positions */
    return CF_OK;
}

cf_status cfi_stretch_bend_flow_gradient(cf_flow *flow, const double *x, double *grad)
{
    if (!flow || flow->method != &cfi_stretch_bend_edit_method || !flow->impl || !x || !grad)
        return CF_ERR_INVALID_ARG;
    stretch_bend_state *s = flow->impl;
    int32_t nv = s->model.nv;
    assemble_rhs(s);
    double *ax = s->model.kx;
    apply_full_matrix(s, x, ax);
    /* The energy is x^T A x - 2 rhs^T x + const, so its gradient is
     * 2 (A x - rhs). */
    for (int32_t v = 0; v < nv; ++v)
        for (int d = 0; d < 3; ++d) grad[3 * v + d] = 2.0 * (ax[(size_t)d * nv + v] - s->rhs[3 * (size_t)v + d]);
    return CF_OK;
}

cfi_stretch_bend_model *cfi_stretch_bend_flow_model(cf_flow *flow)
{
    if (!flow || flow->method != &cfi_stretch_bend_edit_method || !flow->impl) return NULL;
    return &((stretch_bend_state *)flow->impl)->model;
}

/* A negative ARAP energy (possible only with negative edge weights, where
 * Eq. 6/7 is not bounded below) comes with vertices pulled off beside the
 * most negative edges: on chinese_lion_statue_10k one vertex beside a
 * 179.6 degree triangle moves half the bounding-box diagonal. Said once,
 * with the cure (docs/edit.md, "ARAP edge weights"). */
static void warn_negative_arap(const cf_flow *flow, stretch_bend_state *s)
{
    const cfi_stretch_bend_model *m = &s->model;
    if (s->negative_warned || m->clamped || m->negative_edges == 0 || !(s->energy < 0.0)) return;
    s->negative_warned = 1;
    const int32_t *ev = flow->mesh->edge_vertices + 2 * (size_t)m->most_negative_edge;
    cfi_log(flow->ctx, CF_LOG_WARNING,
            "stretch-bend-edit: iteration %lld: the %s energy is negative (%.6g): %d of %d edges have negative "
            "cotan weights (non-Delaunay; cot a + cot b down to %.3g at edge (%d, %d)), where the energy is not "
            "bounded below and vertices beside them can be pulled far off; arap_weights=clamped (edit "
            "--arap-weights clamped) sets those weights to 0",
            (long long)flow->info.iteration + 1, cf_stretch_bend_energy_name(m->energy), s->energy,
            (int)m->negative_edges, (int)flow->mesh->ne, m->most_negative_weight, (int)ev[0], (int)ev[1]);
}

/* One local/global iteration: global solve with the rotations and u' of the
 * current state, then the local step at the new state (which also gives the
 * energy E(x') reported for it). With Anderson acceleration the candidate
 * mixed from the history replaces the plain result when its energy is not
 * higher than the current one. */
static cf_status stretch_bend_step(cf_flow *flow, cf_flow_info *info)
{
    stretch_bend_state *s = flow->impl;
    cfi_stretch_bend_model *m = &s->model;
    double *x = s->xr;
    if (!s->mq)
        return cfi_error(flow->ctx, CF_ERR_INVALID_ARG,
                         "stretch-bend-edit: no valid handle set (the last cf_stretch_bend_set_handles failed)");
    size_t n3 = 3 * (size_t)m->nv;
    double assemble = 0.0, solve = 0.0, previous = s->energy;
    cf_status st;
    double t2, t3;
    if (s->first_pending) {
        /* Candidate (a) with the start rotations, then (b) with x0's own;
         * the model ends with the rotations of the state kept. */
        s->first_pending = 0;
        double ea = 0.0, eb = 0.0, e0 = 0.0;
        st = global_solve(s, x, &assemble, &solve);
        if (st != CF_OK) return st;
        t2 = cfi_now_seconds();
        st = cfi_stretch_bend_local_step(m, x, 0, &ea);
        if (st == CF_OK) st = cfi_stretch_bend_local_step(m, s->x_start, 1, &e0);
        if (st == CF_OK) st = global_solve(s, s->x_start, NULL, NULL);
        if (st == CF_OK) st = cfi_stretch_bend_local_step(m, s->x_start, 0, &eb);
        if (st != CF_OK) return st;
        if (eb <= ea) {
            memcpy(x, s->x_start, n3 * sizeof(double));
            s->energy = eb;
        } else {
            ++s->first_from_start;
            st = cfi_stretch_bend_local_step(m, x, 0, &s->energy);
            if (st != CF_OK) return st;
        }
        t3 = cfi_now_seconds();
    } else if (s->aa_depth == 0) {
        st = global_solve(s, x, &assemble, &solve);
        if (st != CF_OK) return st;
        t2 = cfi_now_seconds();
        st = cfi_stretch_bend_local_step(m, x, 0, &s->energy);
        if (st != CF_OK) return st;
        t3 = cfi_now_seconds();
    } else {
        st = global_solve(s, s->aa_g, &assemble, &solve);
        if (st != CF_OK) return st;
        t2 = cfi_now_seconds();
        int32_t have = 0;
        st = cf_anderson_step(s->aa, x, s->aa_g, s->aa_x, &have);
        if (st != CF_OK) return st;
        int accepted = 0;
        if (have) {
            double e_aa = 0.0;
            st = cfi_stretch_bend_local_step(m, s->aa_x, 0, &e_aa);
            if (st == CF_OK && isfinite(e_aa) && e_aa <= previous) {
                memcpy(x, s->aa_x, n3 * sizeof(double));
                s->energy = e_aa;
                accepted = 1;
                ++s->aa_accepted;
            } else {
                /* Rejected: restart the history from the plain step. */
                ++s->aa_rejected;
                cf_anderson_reset(s->aa);
            }
        }
        if (!accepted) {
            memcpy(x, s->aa_g, n3 * sizeof(double));
            st = cfi_stretch_bend_local_step(m, x, 0, &s->energy);
            if (st != CF_OK) return st;
        }
        t3 = cfi_now_seconds();
    }
    publish_state(flow, s);
    warn_negative_arap(flow, s);
    /* Stopping rule (the flow layer's step policy, see the vtable): relative
     * energy decrease below relative_tolerance; a rise stops the run. */
    double scale = fabs(previous) > 0.0 ? fabs(previous) : 1.0;
    double decrease = (previous - s->energy) / scale;

    info->time_step = 1.0;
    fill_terms(s, info);
    info->residual_names[0] = "relative_decrease";
    info->residuals[0] = decrease;
    if (s->aa_depth > 0) {
        info->residual_names[1] = "anderson_accepted";
        info->residuals[1] = (double)s->aa_accepted;
        info->residual_names[2] = "anderson_rejected";
        info->residuals[2] = (double)s->aa_rejected;
    }
    info->assemble_seconds = assemble + (t3 - t2);
    info->factorize_seconds = s->factorize_seconds;
    s->factorize_seconds = 0.0;
    info->solve_seconds = solve;
    return CF_OK;
}

/* After cf_flow_set_positions or a failed step: handles back on their
 * targets and the local step redone at the new state. */
static cf_status stretch_bend_reset(cf_flow *flow)
{
    stretch_bend_state *s = flow->impl;
    if (!s) return CF_OK;
    cf_anderson_reset(s->aa);
    cf_status st = load_state(flow, s);
    if (st == CF_OK) fill_terms(s, &flow->info);
    return st;
}

static void stretch_bend_destroy(cf_flow *flow)
{
    state_free(flow->impl, flow->ctx);
    flow->impl = NULL;
}

const cfi_flow_method cfi_stretch_bend_edit_method = {
    .kind = CF_FLOW_STRETCH_BEND_EDIT,
    .name = "stretch-bend-edit",
    .description = "stretching + bending mesh editing by local/global iteration (Zhao & Gortler), and ARAP",
    .options_size = sizeof(cf_stretch_bend_options),
    .options_default = options_default,
    .params = params,
    .param_count = (int32_t)(sizeof params / sizeof params[0]),
    .create = stretch_bend_create,
    .step = stretch_bend_step,
    .reset = stretch_bend_reset,
    .destroy = stretch_bend_destroy,
    /* no time step to reduce: a step that raises the energy ends the run
     * (the state before it kept); converged below relative_tolerance */
    .policy = {.rise_check = 1, .rise_stops = 1, .convergence = 1, .tolerance_param = "relative_tolerance"},
};

cf_status cf_stretch_bend_set_handles(cf_flow *flow, const cf_handle_set *handles)
{
    if (!flow) return CF_ERR_INVALID_ARG;
    if (flow->method != &cfi_stretch_bend_edit_method || !flow->impl)
        return cfi_error(flow->ctx, CF_ERR_INVALID_ARG, "cf_stretch_bend_set_handles: not a stretch-bend-edit flow");
    stretch_bend_state *s = flow->impl;
    cf_status st = setup_system(s, flow->ctx, flow->mesh, handles);
    if (st != CF_OK) return st; /* invalid handles: the old system stays; failed build: steps report it */
    s->options.handles = handles;
    flow->converged = 0;
    return stretch_bend_reset(flow);
}

cf_status cf_stretch_bend_edit(cf_context *ctx, const cf_mesh *mesh, const double *start,
                               const cf_stretch_bend_options *options, double *out_positions, cf_flow_info *info)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!mesh || !options || !out_positions)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_stretch_bend_edit: mesh, options or output is NULL");
    if (options->max_iterations < 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "max_iterations must be >= 0, got %d", (int)options->max_iterations);
    cf_flow_options fo;
    cf_flow_options_default(CF_FLOW_STRETCH_BEND_EDIT, &fo);
    memcpy(cf_flow_options_method(&fo), options, sizeof *options);
    cf_flow *flow = NULL;
    cf_status st = cf_flow_create(ctx, mesh, start, &fo, &flow);
    if (st != CF_OK) return st;
    st = cf_flow_run(flow, options->max_iterations, info);
    if (st == CF_OK) {
        memcpy(out_positions, flow->positions, 3 * (size_t)mesh->nv * sizeof(double));
        if (info) *info = flow->info;
    }
    cf_flow_destroy(&flow);
    return st;
}

cf_status cf_stretch_bend_energy(cf_context *ctx, const cf_mesh *mesh, const double *rest, const double *deformed,
                                 const cf_stretch_bend_options *options, double *stretch, double *bend, double *arap,
                                 double *total)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!mesh || !deformed || !options)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_stretch_bend_energy: mesh, deformed or options is NULL");
    const double *x0 = rest ? rest : mesh->positions;
    int is_arap = options->energy == CF_STRETCH_BEND_ARAP || options->energy == CF_STRETCH_BEND_ARAP_RIMS;
    cfi_stretch_bend_model m;
    cf_status st = cfi_stretch_bend_model_init(&m, ctx, mesh, x0, options);
    if (st != CF_OK) return st;
    double alpha = m.alpha, beta = m.beta;
    if (!is_arap && (alpha == 0.0 || beta == 0.0)) {
        /* A one-term model lacks the other term's data: evaluate both with
         * a two-term model and weight them with the requested alpha, beta. */
        cfi_stretch_bend_model_free(&m);
        cf_stretch_bend_options h = *options;
        h.energy = CF_STRETCH_BEND_HYBRID;
        h.lambda = 0.5;
        st = cfi_stretch_bend_model_init(&m, ctx, mesh, x0, &h);
        if (st != CF_OK) return st;
    }
    st = cfi_stretch_bend_local_step(&m, deformed, 1, NULL);
    double term = m.term_energy, bd = m.bend_energy;
    cfi_stretch_bend_model_free(&m);
    if (st != CF_OK) return st;
    if (stretch) *stretch = is_arap ? 0.0 : term;
    if (bend) *bend = is_arap ? 0.0 : bd;
    if (arap) *arap = is_arap ? term : 0.0;
    if (total) *total = alpha * term + beta * bd;
    return CF_OK;
}
