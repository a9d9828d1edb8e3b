/*
 * The conformal class of a closed surface of genus g >= 1, measured from
 * its discrete harmonic 1-forms: what the conformal Willmore flow (Crane,
 * Pinkall, Schroeder 2013, Sec. 6.2 and App. C) keeps, and what a
 * tangential motion or a non-conformal flow changes.
 *
 * Homology generators come from a tree-cotree split (Eppstein 2003;
 * Erickson & Whittlesey 2005): a breadth-first spanning tree of the
 * vertices from vertex 0, a spanning tree of the faces from face 0 across
 * the edges not in it; each of the 2g edges left closes one cycle through
 * the vertex tree. They depend on the connectivity alone, so two position
 * sets of one mesh are measured against the same marked cycles.
 *
 * With h_1 .. h_2g the harmonic forms of the positions (cf_harmonic_basis,
 * orthonormal under *1) and P_ik the period of h_i along cycle k, the forms
 * eta = h P^-T have period delta_jk along cycle j (the cohomology basis dual
 * to the cycles), and their Gram matrix is G = (P^T P)^-1. The Hodge star
 * on H^1 in that integral basis is S = I^-1 G, where I_jk = int eta_j ^
 * eta_k is the intersection form (integers: a cohomological quantity, the
 * same for any positions), and S determines the period matrix: G is a
 * complete invariant of the marked conformal class. In the smooth setting
 * det G = det I = 1 (S^2 = -1); the discrete star misses that by
 * `hodge_defect`.
 *
 * Genus 1: for the flat torus C / (Z + tau Z), the forms dual to the cycles
 * 1 and tau are dx - (x / y) dy and dy / y (tau = x + i y), whose Gram
 * matrix is (1 / y) [[|tau|^2, -x], [-x, 1]] when int eta_1 ^ eta_2 = +1;
 * hence x = K12 / K11 and y = sqrt(det K) / K11 with K = P^T P (the square
 * root scales out the discrete det K != 1). tau is then brought into the
 * standard fundamental domain |x| <= 1/2, |tau| >= 1.
 *
 * The class alone is J = S (-S^2)^-1/2, the complex structure nearest the
 * discrete star (whose S^2 = -1 holds only to O(h^2): g^2 numbers of G
 * belong to the triangles, not to the Riemann surface), reported as
 * G^ = I J (cf_conformal_class_normalize). The distance between two
 * classes of one marked surface is sqrt(sum log^2 mu / 2) over the
 * eigenvalues mu of the pencil (G^_a, G^_b): the hyperbolic distance between
 * tau_a and tau_b in the upper half-plane for genus 1 (G(tau) above is the
 * standard map of the half-plane onto the 2 x 2 positive matrices of det 1).
 *
 * The derivative of G in the positions holds the harmonic representatives
 * fixed: each minimises the Dirichlet energy within its cohomology class,
 * so its own change does not enter at first order (the envelope argument;
 * checked against central differences in test `metrics.conformal_class`).
 */
#include "metrics/metrics_internal.h"
#include "curvflow/linalg.h"
#include "curvflow/ops.h"

#include <math.h>
#include <string.h>

/* edge flags of the tree-cotree split */
enum { EDGE_FREE = 0, EDGE_TREE = 1, EDGE_COTREE = 2 };

/* The marked cycles: the vertex tree (BFS order and each vertex's edge to
 * its parent) and the 2g generator edges. */
typedef struct homology_cycles {
    int32_t dim;
    int32_t *order;       /* nv, parents first */
    int32_t *parent_edge; /* nv, -1 at the root */
    int32_t *generators;  /* dim edges */
    double *potential;    /* nv scratch: a form integrated along the tree */
} homology_cycles;

static void cycles_free(cf_context *ctx, const cf_mesh *mesh, homology_cycles *c)
{
    CFI_FREE(ctx, c->order, mesh->nv);
    CFI_FREE(ctx, c->parent_edge, mesh->nv);
    CFI_FREE(ctx, c->generators, c->dim);
    CFI_FREE(ctx, c->potential, mesh->nv);
}

/* Closed, connected, genus >= 1: the surfaces whose class this measures. */
static cf_status check_surface(cf_context *ctx, const cf_mesh *mesh, const char *fn)
{
    if (mesh->component_count != 1)
        return cfi_error(ctx, CF_ERR_BAD_MESH, "%s: one connected surface needed, the mesh has %d components", fn,
                         (int)mesh->component_count);
    if (cf_mesh_boundary_loop_count(mesh) != 0)
        return cfi_error(ctx, CF_ERR_BAD_MESH, "%s: closed surfaces only, the mesh has %d boundary loops", fn,
                         (int)cf_mesh_boundary_loop_count(mesh));
    if (cf_mesh_genus(mesh) < 1)
        return cfi_error(ctx, CF_ERR_BAD_MESH, "%s: genus >= 1 needed (a sphere has one conformal class)", fn);
    return CF_OK;
}

static cf_status find_cycles(cf_context *ctx, const cf_mesh *mesh, homology_cycles *c)
{
    int32_t nv = mesh->nv, nf = mesh->nf, ne = mesh->ne;
    c->dim = 2 * cf_mesh_genus(mesh);
    c->order = CFI_ALLOC(ctx, int32_t, nv);
    c->parent_edge = CFI_ALLOC(ctx, int32_t, nv);
    c->generators = CFI_ALLOC(ctx, int32_t, c->dim);
    c->potential = CFI_ALLOC(ctx, double, nv);
    uint8_t *flag = CFI_ALLOC(ctx, uint8_t, ne);
    int32_t *face_queue = CFI_ALLOC(ctx, int32_t, nf);
    uint8_t *face_seen = CFI_ALLOC(ctx, uint8_t, nf);
    cf_status st = CF_OK;
    if (!c->order || !c->parent_edge || !c->generators || !c->potential || !flag || !face_queue || !face_seen) {
        st = CF_ERR_NOMEM;
        goto done;
    }
    memset(flag, EDGE_FREE, (size_t)ne);
    memset(face_seen, 0, (size_t)nf);
    for (int32_t v = 0; v < nv; ++v) c->parent_edge[v] = -2; /* unseen */
    int32_t head = 0, tail = 0;
    c->order[tail++] = 0;
    c->parent_edge[0] = -1;
    while (head < tail) {
        int32_t u = c->order[head++];
        for (int32_t k = mesh->ring_offsets[u]; k < mesh->ring_offsets[u + 1]; ++k) {
            int32_t w = mesh->ring_neighbors[k];
            if (c->parent_edge[w] != -2) continue;
            c->parent_edge[w] = mesh->ring_edges[k];
            flag[mesh->ring_edges[k]] = EDGE_TREE;
            c->order[tail++] = w;
        }
    }
    head = tail = 0;
    face_queue[tail++] = 0;
    face_seen[0] = 1;
    while (head < tail) {
        int32_t f = face_queue[head++];
        for (int k = 0; k < 3; ++k) {
            int32_t e = mesh->halfedge_edge[3 * f + k], twin = mesh->halfedge_twin[3 * f + k];
            if (flag[e] == EDGE_TREE || twin < 0 || face_seen[twin / 3]) continue;
            face_seen[twin / 3] = 1;
            flag[e] = EDGE_COTREE;
            face_queue[tail++] = twin / 3;
        }
    }
    int32_t count = 0;
    for (int32_t e = 0; e < ne; ++e) {
        if (flag[e] != EDGE_FREE) continue;
        if (count == c->dim) break;
        c->generators[count++] = e;
    }
    /* nv - 1 tree edges and nf - 1 cotree edges leave ne - nv - nf + 2 = 2g */
    if (count != c->dim || tail != nf)
        st = cfi_error(ctx, CF_ERR_BAD_MESH, "cf_conformal_class: the tree-cotree split left %d cycles for genus %d",
                       (int)count, (int)(c->dim / 2));
done:
    CFI_FREE(ctx, flag, ne);
    CFI_FREE(ctx, face_queue, nf);
    CFI_FREE(ctx, face_seen, nf);
    return st;
}

/* The checks both entry points make (positions finite, a closed connected
 * surface of genus >= 1) and its marked cycles; c is freed on failure. */
static cf_status open_surface(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b, const char *fn,
                              homology_cycles *c)
{
    cf_status st = cfi_metrics_check_pair(ctx, mesh, a, b, fn);
    if (st == CF_OK) st = check_surface(ctx, mesh, fn);
    if (st == CF_OK) st = find_cycles(ctx, mesh, c);
    if (st != CF_OK && c->dim > 0) cycles_free(ctx, mesh, c);
    return st;
}

/* Periods of the 1-form `form` (ne values on edges i -> j, i < j) along the
 * marked cycles: row `row` of periods (dim x dim, column-major; column k
 * for cycle k). */
static void form_periods(const cf_mesh *mesh, const homology_cycles *c, const double *form, double *periods,
                         int32_t row)
{
    double *phi = c->potential;
    phi[0] = 0.0;
    for (int32_t k = 1; k < mesh->nv; ++k) {
        int32_t v = c->order[k], e = c->parent_edge[v];
        int32_t a = mesh->edge_vertices[2 * e], b = mesh->edge_vertices[2 * e + 1];
        phi[v] = v == b ? phi[a] + form[e] : phi[b] - form[e];
    }
    for (int32_t k = 0; k < c->dim; ++k) {
        int32_t e = c->generators[k];
        periods[row + (int64_t)k * c->dim] =
            phi[mesh->edge_vertices[2 * e]] + form[e] - phi[mesh->edge_vertices[2 * e + 1]];
    }
}

/* The harmonic forms of positions x (cf_harmonic_basis, or the workspace
 * hw's when not NULL: ne x dim) and their periods P along the marked
 * cycles (dim x dim). */
static cf_status harmonic_periods(cf_context *ctx, const cf_mesh *mesh, const double *x, const homology_cycles *c,
                                  cf_harmonic_workspace *hw, double *forms, double *periods)
{
    int32_t got = hw ? cf_harmonic_workspace_dimension(hw) : 0;
    cf_status st = hw ? cf_harmonic_workspace_compute(hw, x, forms) : cf_harmonic_basis(ctx, mesh, x, &got, forms);
    if (st != CF_OK) return st;
    if (got != c->dim)
        return cfi_error(ctx, CF_ERR_NUMERICAL, "cf_conformal_class: %d harmonic forms for genus %d", (int)got,
                         (int)(c->dim / 2));
    for (int32_t i = 0; i < c->dim; ++i) form_periods(mesh, c, forms + (int64_t)i * mesh->ne, periods, i);
    return CF_OK;
}

/* K = P^T P of positions x (dim x dim), and optionally the harmonic forms'
 * wedge matrix int h_i ^ h_j (dim x dim) and P itself. */
static cf_status class_matrix(cf_context *ctx, const cf_mesh *mesh, const double *x, const homology_cycles *c,
                              double *k_matrix, double *wedge, double *periods_out)
{
    int32_t dim = c->dim, ne = mesh->ne, nf = mesh->nf;
    double *forms = CFI_ALLOC(ctx, double, (int64_t)ne * dim);
    double *periods = CFI_ALLOC(ctx, double, (int64_t)dim * dim);
    double *fields = wedge ? CFI_ALLOC(ctx, double, 3 * (int64_t)nf * dim) : NULL;
    cf_status st = CF_OK;
    if (!forms || !periods || (wedge && !fields)) {
        st = CF_ERR_NOMEM;
        goto done;
    }
    st = harmonic_periods(ctx, mesh, x, c, NULL, forms, periods);
    if (st != CF_OK) goto done;
    for (int32_t k = 0; k < dim; ++k)
        for (int32_t l = 0; l < dim; ++l) {
            double s = 0.0;
            for (int32_t i = 0; i < dim; ++i) s += periods[i + (int64_t)k * dim] * periods[i + (int64_t)l * dim];
            k_matrix[k + (int64_t)l * dim] = s;
        }
    if (periods_out) memcpy(periods_out, periods, (size_t)dim * dim * sizeof(double));
    if (wedge) {
        for (int32_t i = 0; i < dim && st == CF_OK; ++i)
            st = cf_one_form_to_vector_field(ctx, mesh, x, forms + (int64_t)i * ne, fields + 3 * (int64_t)i * nf);
        if (st != CF_OK) goto done;
        memset(wedge, 0, (size_t)dim * dim * sizeof(double));
        for (int32_t f = 0; f < nf; ++f) {
            const int32_t *t = mesh->triangles + 3 * f;
            double e1[3], e2[3];
            for (int q = 0; q < 3; ++q) {
                e1[q] = x[3 * t[1] + q] - x[3 * t[0] + q];
                e2[q] = x[3 * t[2] + q] - x[3 * t[0] + q];
            }
            /* twice the area times the unit normal of the face's winding */
            double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
            for (int32_t i = 0; i < dim; ++i)
                for (int32_t j = i + 1; j < dim; ++j) {
                    const double *a = fields + 3 * ((int64_t)i * nf + f), *b = fields + 3 * ((int64_t)j * nf + f);
                    /* int_f alpha ^ beta = area (a x b) . n for constant a, b */
                    double w = 0.5 * ((a[1] * b[2] - a[2] * b[1]) * n[0] + (a[2] * b[0] - a[0] * b[2]) * n[1] +
                                      (a[0] * b[1] - a[1] * b[0]) * n[2]);
                    wedge[i + (int64_t)j * dim] += w;
                    wedge[j + (int64_t)i * dim] -= w;
                }
        }
    }
done:
    CFI_FREE(ctx, forms, (int64_t)ne * dim);
    CFI_FREE(ctx, periods, (int64_t)dim * dim);
    if (fields) CFI_FREE(ctx, fields, 3 * (int64_t)nf * dim);
    return st;
}

#define PERIODS_SINGULAR "cf_conformal_class: the matrix of the harmonic forms' periods"

/* Solves the square system a x = b column by column (a: n x n, kept; b: n x
 * m, overwritten by x) through the dense least-squares routine; a singular
 * a fails with CF_ERR_NUMERICAL, "<what> is singular". */
static cf_status dense_solve(cf_context *ctx, int32_t n, int32_t m, const double *a, double *b, const char *what)
{
    int64_t lwork = cf_dense_least_squares_work_size(n, n);
    double *copy = CFI_ALLOC(ctx, double, (int64_t)n * n), *work = CFI_ALLOC(ctx, double, lwork);
    cf_status st = copy && work ? CF_OK : CF_ERR_NOMEM;
    for (int32_t j = 0; j < m && st == CF_OK; ++j) {
        memcpy(copy, a, (size_t)n * n * sizeof(double));
        int32_t rank = 0;
        st = cf_dense_least_squares(n, n, copy, b + (int64_t)j * n, 1e-13, work, lwork, &rank);
        if (st == CF_OK && rank < n)
            st = cfi_error(ctx, CF_ERR_NUMERICAL, "%s is singular", what);
    }
    CFI_FREE(ctx, copy, (int64_t)n * n);
    CFI_FREE(ctx, work, lwork);
    return st;
}

/* log det of the positive definite k (n x n) from its eigenvalues */
static cf_status log_determinant(cf_context *ctx, int32_t n, const double *k, double *logdet)
{
    int64_t lwork = cf_dense_generalized_eigenvalues_work_size(n);
    double *a = CFI_ALLOC(ctx, double, (int64_t)n * n), *b = CFI_ALLOC(ctx, double, (int64_t)n * n);
    double *mu = CFI_ALLOC(ctx, double, n), *work = CFI_ALLOC(ctx, double, lwork);
    cf_status st = a && b && mu && work ? CF_OK : CF_ERR_NOMEM;
    if (st == CF_OK) {
        memcpy(a, k, (size_t)n * n * sizeof(double));
        memset(b, 0, (size_t)n * n * sizeof(double));
        for (int32_t i = 0; i < n; ++i) b[i + (int64_t)i * n] = 1.0;
        st = cf_dense_generalized_eigenvalues(n, a, b, mu, work, lwork);
    }
    *logdet = 0.0;
    for (int32_t i = 0; i < n && st == CF_OK; ++i) {
        if (!(mu[i] > 0.0)) st = cfi_error(ctx, CF_ERR_NUMERICAL, "cf_conformal_class: the periods are singular");
        else *logdet += log(mu[i]);
    }
    CFI_FREE(ctx, a, (int64_t)n * n);
    CFI_FREE(ctx, b, (int64_t)n * n);
    CFI_FREE(ctx, mu, n);
    CFI_FREE(ctx, work, lwork);
    return st;
}

/* tau into |Re tau| <= 1/2, |tau| >= 1 (the modular group's standard
 * fundamental domain) */
static void reduce_modulus(double *x, double *y)
{
    for (int it = 0; it < 200; ++it) {
        *x -= nearbyint(*x);
        double r2 = *x * *x + *y * *y;
        if (r2 >= 1.0 - 1e-15) break;
        *x = -*x / r2;
        *y = *y / r2;
    }
}

/* G = K^-1 (dim x dim) */
static cf_status gram_of(cf_context *ctx, int32_t dim, const double *k, double *gram)
{
    memset(gram, 0, (size_t)dim * dim * sizeof(double));
    for (int32_t i = 0; i < dim; ++i) gram[i + (int64_t)i * dim] = 1.0;
    return dense_solve(ctx, dim, dim, k, gram, PERIODS_SINGULAR);
}

/* The class of positions x on the marked cycles c: K = P^T P (k, dim x dim),
 * *out, and G = K^-1 into gram if not NULL. */
static cf_status measure_class(cf_context *ctx, const cf_mesh *mesh, const double *x, const homology_cycles *c,
                               double *k, double *gram, double *form, cf_conformal_class *out)
{
    int32_t dim = c->dim;
    int64_t n2 = (int64_t)dim * dim;
    double *wedge = CFI_ALLOC(ctx, double, n2), *periods = CFI_ALLOC(ctx, double, n2);
    double *inv = CFI_ALLOC(ctx, double, n2); /* the intersection form */
    cf_status st = wedge && periods && inv ? CF_OK : CF_ERR_NOMEM;
    if (st == CF_OK) st = class_matrix(ctx, mesh, x, c, k, wedge, periods);
    /* the intersection form P^-1 W P^-T of the dual forms */
    if (st == CF_OK) st = dense_solve(ctx, dim, dim, periods, wedge, PERIODS_SINGULAR);
    if (st == CF_OK) {
        for (int32_t i = 0; i < dim; ++i)
            for (int32_t j = 0; j < dim; ++j) inv[i + (int64_t)j * dim] = wedge[j + (int64_t)i * dim];
        st = dense_solve(ctx, dim, dim, periods, inv, PERIODS_SINGULAR); /* P^-1 W^T P^-T, W antisymmetric */
        for (int64_t q = 0; q < n2; ++q) inv[q] = -inv[q];
    }
    double logdet = 0.0;
    if (st == CF_OK) st = log_determinant(ctx, dim, k, &logdet);
    if (st == CF_OK) {
        memset(out, 0, sizeof *out);
        out->genus = dim / 2;
        double worst = 0.0;
        for (int64_t q = 0; q < n2; ++q) worst = fmax(worst, fabs(inv[q] - nearbyint(inv[q])));
        out->intersection_error = worst;
        if (form) {
            /* integers: what is left is rounding (checked above, reported) */
            if (!(worst < 0.25))
                st = cfi_error(ctx, CF_ERR_NUMERICAL,
                               "cf_conformal_class: the intersection numbers of the dual forms are %.3g from integers",
                               worst);
            for (int64_t q = 0; q < n2; ++q) form[q] = nearbyint(inv[q]);
        }
        /* det G = 1 / det K, 1 for the smooth surface */
        out->hodge_defect = fabs(expm1(-logdet / dim));
        out->modulus[0] = out->modulus[1] = NAN;
        if (dim == 2) {
            /* int eta_1 ^ eta_2 = -1: the cycles in the other order */
            double kaa = inv[2] > 0.0 ? k[0] : k[3];
            double xr = k[2] / kaa, yi = sqrt(exp(logdet)) / kaa;
            reduce_modulus(&xr, &yi);
            out->modulus[0] = xr;
            out->modulus[1] = yi;
        }
        if (gram && st == CF_OK) st = gram_of(ctx, dim, k, gram);
    }
    CFI_FREE(ctx, wedge, n2);
    CFI_FREE(ctx, periods, n2);
    CFI_FREE(ctx, inv, n2);
    return st;
}

/* One position set's class (cf_conformal_class_compute, and the intersection
 * form of cf_conformal_class_intersection_form): the checks, the marked
 * cycles, measure_class. */
static cf_status measure_one(cf_context *ctx, const cf_mesh *mesh, const double *positions, const char *fn,
                             double *gram, double *form, cf_conformal_class *out)
{
    homology_cycles c = {0};
    cf_status st = open_surface(ctx, mesh, positions, positions, fn, &c);
    if (st != CF_OK) return st;
    int64_t n2 = (int64_t)c.dim * c.dim;
    double *k = CFI_ALLOC(ctx, double, n2);
    st = k ? measure_class(ctx, mesh, positions, &c, k, gram, form, out) : CF_ERR_NOMEM;
    CFI_FREE(ctx, k, n2);
    cycles_free(ctx, mesh, &c);
    return st;
}

cf_status cf_conformal_class_compute(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *gram,
                                     cf_conformal_class *out)
{
    static const char fn[] = "cf_conformal_class_compute";
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: out is NULL", fn);
    return measure_one(ctx, mesh, positions, fn, gram, NULL, out);
}

cf_status cf_conformal_class_distance(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                      cf_conformal_class *class_a, cf_conformal_class *class_b, double *distance)
{
    static const char fn[] = "cf_conformal_class_distance";
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!distance) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: distance is NULL", fn);
    *distance = NAN;
    homology_cycles c = {0};
    cf_status st = open_surface(ctx, mesh, a, b, fn, &c);
    if (st != CF_OK) return st;
    int32_t dim = c.dim;
    int64_t n2 = (int64_t)dim * dim, lwork = cf_dense_generalized_eigenvalues_work_size(dim);
    double *ka = CFI_ALLOC(ctx, double, n2), *kb = CFI_ALLOC(ctx, double, n2);
    double *mu = CFI_ALLOC(ctx, double, dim), *work = CFI_ALLOC(ctx, double, lwork);
    if (st == CF_OK && (!ka || !kb || !mu || !work)) st = CF_ERR_NOMEM;
    double *form = CFI_ALLOC(ctx, double, n2), *g = CFI_ALLOC(ctx, double, n2);
    if (st == CF_OK && (!form || !g)) st = CF_ERR_NOMEM;
    /* a's class in full (it makes the intersection form), b's only when asked */
    cf_conformal_class own_a;
    if (st == CF_OK) st = measure_class(ctx, mesh, a, &c, ka, NULL, form, class_a ? class_a : &own_a);
    if (st == CF_OK)
        st = class_b ? measure_class(ctx, mesh, b, &c, kb, NULL, NULL, class_b)
                     : class_matrix(ctx, mesh, b, &c, kb, NULL, NULL);
    /* the classes alone: G^ of G = K^-1 (cf_conformal_class_normalize) */
    for (int side = 0; side < 2 && st == CF_OK; ++side) {
        double *k = side ? kb : ka;
        st = gram_of(ctx, dim, k, g);
        if (st == CF_OK) st = cf_conformal_class_normalize(ctx, dim, form, g, k, NULL);
    }
    if (st == CF_OK) st = cf_dense_generalized_eigenvalues(dim, ka, kb, mu, work, lwork);
    if (st == CF_OK) {
        /* G^ has det 1 (J^2 = -1, I unimodular): the log eigenvalues' mean
         * is rounding, taken out as when G itself was scaled to det 1 */
        double mean = 0.0, sum2 = 0.0;
        for (int32_t i = 0; i < dim && st == CF_OK; ++i) {
            if (!(mu[i] > 0.0)) st = cfi_error(ctx, CF_ERR_NUMERICAL, "%s: the periods are singular", fn);
            else mean += log(mu[i]) / dim;
        }
        for (int32_t i = 0; i < dim && st == CF_OK; ++i) sum2 += (log(mu[i]) - mean) * (log(mu[i]) - mean);
        if (st == CF_OK) *distance = sqrt(0.5 * sum2);
    }
    CFI_FREE(ctx, ka, n2);
    CFI_FREE(ctx, kb, n2);
    CFI_FREE(ctx, form, n2);
    CFI_FREE(ctx, g, n2);
    CFI_FREE(ctx, mu, dim);
    CFI_FREE(ctx, work, lwork);
    cycles_free(ctx, mesh, &c);
    return st;
}

/* d/dx of F = area <v_a, v_b> on one face, for the constant fields v of two
 * closed forms with values a = (a1, a2), b on its edges e1 = x1 - x0,
 * e2 = x2 - x0: with E the Gram matrix of e1, e2, F = sqrt(det E) / 2
 * a^T E^-1 b, so dF = 1/2 (d sqrt(det E) q - sqrt(det E) alpha^T dE beta)
 * with q = a^T E^-1 b, alpha = E^-1 a, beta = E^-1 b, and dE_ij =
 * de_i . e_j + e_i . de_j. Adds scale * dF/dx to the face's three
 * vertices of grad. Returns F. */
static double face_pair_gradient(const double *e1, const double *e2, const double a[2], const double b[2],
                                 double scale, double *g0, double *g1, double *g2)
{
    double e11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2];
    double e12 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
    double e22 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
    double det = e11 * e22 - e12 * e12, s = sqrt(det);
    /* E^-1 = [[e22, -e12], [-e12, e11]] / det */
    double inv[2][2] = {{e22 / det, -e12 / det}, {-e12 / det, e11 / det}};
    double alpha[2] = {inv[0][0] * a[0] + inv[0][1] * a[1], inv[1][0] * a[0] + inv[1][1] * a[1]};
    double beta[2] = {inv[0][0] * b[0] + inv[0][1] * b[1], inv[1][0] * b[0] + inv[1][1] * b[1]};
    double q = a[0] * beta[0] + a[1] * beta[1];
    /* S_ij = dF / dE_ij with E's entries taken apart; T = S + S^T */
    double sij[2][2], t[2][2];
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) sij[i][j] = 0.5 * (0.5 * s * q * inv[j][i] - s * alpha[i] * beta[j]);
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) t[i][j] = sij[i][j] + sij[j][i];
    for (int c = 0; c < 3; ++c) {
        double d1 = scale * (t[0][0] * e1[c] + t[0][1] * e2[c]);
        double d2 = scale * (t[1][0] * e1[c] + t[1][1] * e2[c]);
        g1[c] += d1;
        g2[c] += d2;
        g0[c] -= d1 + d2;
    }
    return 0.5 * s * q;
}

struct cf_conformal_class_workspace {
    cf_context *ctx;
    const cf_mesh *mesh;
    homology_cycles cycles;
    cf_harmonic_workspace *harmonic;
    double *forms, *dual;               /* ne x dim: the harmonic forms, the forms dual to the cycles */
    double *periods, *coef, *transposed; /* dim x dim */
    double *vals;                       /* 2 dim: one face's values of the dual forms */
};

void cf_conformal_class_workspace_destroy(cf_conformal_class_workspace **wp)
{
    cf_conformal_class_workspace *w = wp ? *wp : NULL;
    if (!w) return;
    cf_context *ctx = w->ctx;
    const cf_mesh *mesh = w->mesh;
    int32_t dim = w->cycles.dim;
    int64_t n2 = (int64_t)dim * dim;
    cf_harmonic_workspace_destroy(&w->harmonic);
    CFI_FREE(ctx, w->forms, (int64_t)mesh->ne * dim);
    CFI_FREE(ctx, w->dual, (int64_t)mesh->ne * dim);
    CFI_FREE(ctx, w->periods, n2);
    CFI_FREE(ctx, w->coef, n2);
    CFI_FREE(ctx, w->transposed, n2);
    CFI_FREE(ctx, w->vals, 2 * (int64_t)dim);
    if (dim > 0) cycles_free(ctx, mesh, &w->cycles);
    cfi_free(ctx, w, sizeof *w);
    *wp = NULL;
}

cf_status cf_conformal_class_workspace_create(cf_context *ctx, const cf_mesh *mesh, cf_conformal_class_workspace **out)
{
    static const char fn[] = "cf_conformal_class_workspace_create";
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: out is NULL", fn);
    *out = NULL;
    if (!mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: mesh is NULL", fn);
    cf_status st = check_surface(ctx, mesh, fn);
    if (st != CF_OK) return st;
    cf_conformal_class_workspace *w = cfi_malloc(ctx, sizeof *w);
    if (!w) return CF_ERR_NOMEM;
    memset(w, 0, sizeof *w);
    w->ctx = ctx;
    w->mesh = mesh;
    st = find_cycles(ctx, mesh, &w->cycles);
    if (st != CF_OK) {
        cycles_free(ctx, mesh, &w->cycles);
        w->cycles.dim = 0;
    }
    int32_t dim = w->cycles.dim;
    int64_t n2 = (int64_t)dim * dim;
    if (st == CF_OK) st = cf_harmonic_workspace_create(ctx, mesh, &w->harmonic);
    if (st == CF_OK && cf_harmonic_workspace_dimension(w->harmonic) != dim)
        st = cfi_error(ctx, CF_ERR_NUMERICAL, "cf_conformal_class: %d harmonic forms for genus %d",
                       (int)cf_harmonic_workspace_dimension(w->harmonic), (int)(dim / 2));
    if (st == CF_OK) {
        w->forms = CFI_ALLOC(ctx, double, (int64_t)mesh->ne * dim);
        w->dual = CFI_ALLOC(ctx, double, (int64_t)mesh->ne * dim);
        w->periods = CFI_ALLOC(ctx, double, n2);
        w->coef = CFI_ALLOC(ctx, double, n2);
        w->transposed = CFI_ALLOC(ctx, double, n2);
        w->vals = CFI_ALLOC(ctx, double, 2 * (int64_t)dim);
        if (!w->forms || !w->dual || !w->periods || !w->coef || !w->transposed || !w->vals) st = CF_ERR_NOMEM;
    }
    if (st != CF_OK) {
        cf_conformal_class_workspace_destroy(&w);
        return st;
    }
    *out = w;
    return CF_OK;
}

cf_status cf_conformal_class_workspace_gram_gradient(cf_conformal_class_workspace *w, const double *positions,
                                                     double *gram, double *gradient)
{
    static const char fn[] = "cf_conformal_class_gram_gradient";
    if (!w) return CF_ERR_INVALID_ARG;
    cf_context *ctx = w->ctx;
    const cf_mesh *mesh = w->mesh;
    if (!gram) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: gram is NULL", fn);
    cf_status st = cfi_metrics_check_pair(ctx, mesh, positions, positions, fn);
    if (st != CF_OK) return st;
    const homology_cycles *c = &w->cycles;
    int32_t dim = c->dim, ne = mesh->ne, nf = mesh->nf, nv = mesh->nv;
    int64_t n2 = (int64_t)dim * dim, pairs = (int64_t)dim * (dim + 1) / 2;
    double *forms = w->forms, *dual = w->dual, *periods = w->periods, *coef = w->coef, *vals = w->vals;
    st = harmonic_periods(ctx, mesh, positions, c, w->harmonic, forms, periods);
    if (st == CF_OK) {
        /* C = P^-T: P^T C = I */
        double *pt = w->transposed;
        for (int32_t i = 0; i < dim; ++i)
            for (int32_t k = 0; k < dim; ++k) {
                pt[i + (int64_t)k * dim] = periods[k + (int64_t)i * dim];
                coef[i + (int64_t)k * dim] = i == k;
            }
        st = dense_solve(ctx, dim, dim, pt, coef, PERIODS_SINGULAR);
    }
    if (st == CF_OK) {
        /* eta_k = sum_i h_i C_ik: the harmonic forms dual to the cycles */
        memset(dual, 0, (size_t)ne * dim * sizeof(double));
        for (int32_t k = 0; k < dim; ++k)
            for (int32_t i = 0; i < dim; ++i) {
                double ck = coef[i + (int64_t)k * dim];
                const double *h = forms + (int64_t)i * ne;
                double *eta = dual + (int64_t)k * ne;
                for (int32_t e = 0; e < ne; ++e) eta[e] += ck * h[e];
            }
        memset(gram, 0, (size_t)n2 * sizeof(double));
        if (gradient) memset(gradient, 0, (size_t)(pairs * 3 * nv) * sizeof(double));
        for (int32_t f = 0; f < nf; ++f) {
            const int32_t *t = mesh->triangles + 3 * f;
            double e1[3], e2[3];
            for (int q = 0; q < 3; ++q) {
                e1[q] = positions[3 * t[1] + q] - positions[3 * t[0] + q];
                e2[q] = positions[3 * t[2] + q] - positions[3 * t[0] + q];
            }
            /* each form's values along t0 -> t1 and t0 -> t2 (= t0 -> t1 -> t2: closed) */
            for (int32_t k = 0; k < dim; ++k) {
                double along[2];
                for (int h = 0; h < 2; ++h) {
                    int32_t ed = mesh->halfedge_edge[3 * f + h];
                    double sgn = mesh->edge_vertices[2 * ed] == t[h] ? 1.0 : -1.0;
                    along[h] = sgn * dual[(int64_t)k * ne + ed];
                }
                vals[2 * k] = along[0];
                vals[2 * k + 1] = along[0] + along[1];
            }
            int64_t pair = 0;
            for (int32_t l = 0; l < dim; ++l)
                for (int32_t k = 0; k <= l; ++k, ++pair) {
                    double *g = gradient ? gradient + pair * 3 * nv : NULL;
                    double dummy[9] = {0};
                    double F = face_pair_gradient(e1, e2, &vals[2 * k], &vals[2 * l], g ? 1.0 : 0.0,
                                                  g ? g + 3 * t[0] : dummy, g ? g + 3 * t[1] : dummy + 3,
                                                  g ? g + 3 * t[2] : dummy + 6);
                    gram[k + (int64_t)l * dim] += F;
                    if (k != l) gram[l + (int64_t)k * dim] += F;
                }
        }
    }
    return st;
}

cf_status cf_conformal_class_gram_gradient(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *gram,
                                           double *gradient)
{
    static const char fn[] = "cf_conformal_class_gram_gradient";
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!gram) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: gram is NULL", fn);
    cf_status st = cfi_metrics_check_pair(ctx, mesh, positions, positions, fn);
    if (st != CF_OK) return st;
    cf_conformal_class_workspace *w = NULL;
    st = cf_conformal_class_workspace_create(ctx, mesh, &w);
    if (st == CF_OK) st = cf_conformal_class_workspace_gram_gradient(w, positions, gram, gradient);
    cf_conformal_class_workspace_destroy(&w);
    return st;
}

cf_status cf_conformal_class_intersection_form(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                               double *form)
{
    static const char fn[] = "cf_conformal_class_intersection_form";
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!form) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: form is NULL", fn);
    cf_conformal_class cls;
    return measure_one(ctx, mesh, positions, fn, NULL, form, &cls);
}

/* c = a b (n x n, column-major) */
static void dense_product(int32_t n, const double *a, const double *b, double *c)
{
    for (int32_t j = 0; j < n; ++j)
        for (int32_t i = 0; i < n; ++i) {
            double s = 0.0;
            for (int32_t k = 0; k < n; ++k) s += a[i + (int64_t)k * n] * b[k + (int64_t)j * n];
            c[i + (int64_t)j * n] = s;
        }
}

/* The Newton iteration S <- (S - S^-1) / 2 for the complex structure
 * converges quadratically from a star whose eigenvalues are near +-i (they
 * are +-i mu, mu = 1 + O(h^2) on a discrete surface); from far off it
 * takes about log2 |log mu| steps more. */
#define NORMALIZE_MAX_ITERATIONS 100

cf_status cf_conformal_class_normalize(cf_context *ctx, int32_t dim, const double *form, const double *gram,
                                       double *normalized, double *derivative)
{
    static const char fn[] = "cf_conformal_class_normalize";
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!form || !gram || !normalized) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: NULL argument", fn);
    if (dim < 2 || dim % 2 != 0 || dim > 4096)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: dim %d is not 2 g for a genus g >= 1", fn, (int)dim);
    int64_t n2 = (int64_t)dim * dim, pairs = (int64_t)dim * (dim + 1) / 2;
    for (int64_t q = 0; q < n2; ++q)
        if (!isfinite(form[q]) || !isfinite(gram[q]))
            return cfi_error(ctx, CF_ERR_NONFINITE, "%s: the %s matrix has a non-finite entry", fn,
                             isfinite(form[q]) ? "Gram" : "intersection");
    double *finv = CFI_ALLOC(ctx, double, n2), *s = CFI_ALLOC(ctx, double, n2), *sinv = CFI_ALLOC(ctx, double, n2);
    double *tmp = CFI_ALLOC(ctx, double, n2), *tmp2 = CFI_ALLOC(ctx, double, n2);
    double *ds = derivative ? CFI_ALLOC(ctx, double, pairs * n2) : NULL;
    cf_status st = finv && s && sinv && tmp && tmp2 && (!derivative || ds) ? CF_OK : CF_ERR_NOMEM;
    if (st == CF_OK) {
        memset(finv, 0, (size_t)n2 * sizeof(double));
        for (int32_t i = 0; i < dim; ++i) finv[i + (int64_t)i * dim] = 1.0;
        st = dense_solve(ctx, dim, dim, form, finv, "cf_conformal_class_normalize: the intersection form");
        if (st == CF_ERR_NUMERICAL) st = CF_ERR_INVALID_ARG;
    }
    if (st == CF_OK) {
        /* S = I^-1 G; dS / dG_kl = I^-1 E_kl (E_kl: 1 at (k, l) and (l, k)) */
        dense_product(dim, finv, gram, s);
        int64_t p = 0;
        for (int32_t l = 0; ds && l < dim; ++l)
            for (int32_t k = 0; k <= l; ++k, ++p) {
                double *d = ds + p * n2;
                for (int32_t i = 0; i < dim; ++i) {
                    d[i + (int64_t)k * dim] = finv[i + (int64_t)l * dim];
                    d[i + (int64_t)l * dim] = k == l ? finv[i + (int64_t)l * dim] : finv[i + (int64_t)k * dim];
                }
                for (int32_t j = 0; j < dim; ++j)
                    if (j != k && j != l)
                        for (int32_t i = 0; i < dim; ++i) d[i + (int64_t)j * dim] = 0.0;
            }
    }
    /* a relative change below 1e-8 leaves an error of about 1e-16 after one
     * more step (quadratic convergence), which the loop then takes */
    int converged = 0, last = 0;
    for (int it = 0; st == CF_OK && it < NORMALIZE_MAX_ITERATIONS && !converged; ++it) {
        memset(sinv, 0, (size_t)n2 * sizeof(double));
        for (int32_t i = 0; i < dim; ++i) sinv[i + (int64_t)i * dim] = 1.0;
        st = dense_solve(ctx, dim, dim, s, sinv, "cf_conformal_class_normalize: the Hodge star");
        if (st != CF_OK) break;
        /* forward derivative of the same map: dS <- (dS + S^-1 dS S^-1) / 2 */
        for (int64_t p = 0; ds && p < pairs; ++p) {
            double *d = ds + p * n2;
            dense_product(dim, sinv, d, tmp);
            dense_product(dim, tmp, sinv, tmp2);
            for (int64_t q = 0; q < n2; ++q) d[q] = 0.5 * (d[q] + tmp2[q]);
        }
        double change = 0.0, size = 0.0;
        for (int64_t q = 0; q < n2; ++q) {
            double next = 0.5 * (s[q] - sinv[q]);
            change += (next - s[q]) * (next - s[q]);
            size += next * next;
            s[q] = next;
        }
        if (!isfinite(change)) st = cfi_error(ctx, CF_ERR_NUMERICAL, "%s: the iteration diverged (step %d)", fn, it);
        converged = last;
        last = change <= 1e-16 * size;
    }
    if (st == CF_OK) {
        /* J^2 = -1 holds only if the star's eigenvalues were imaginary (G
         * positive definite, I antisymmetric) */
        dense_product(dim, s, s, tmp);
        double err = 0.0;
        for (int32_t i = 0; i < dim; ++i)
            for (int32_t j = 0; j < dim; ++j) err = fmax(err, fabs(tmp[i + (int64_t)j * dim] + (i == j)));
        if (!converged || !(err < 1e-8))
            st = cfi_error(ctx, CF_ERR_NUMERICAL,
                           "%s: no complex structure (|J^2 + 1| = %.3g): is G positive definite and I antisymmetric?",
                           fn, err);
    }
    if (st == CF_OK) {
        /* G^ = I J, symmetric up to rounding: its mean with the transpose */
        dense_product(dim, form, s, tmp);
        for (int32_t i = 0; i < dim; ++i)
            for (int32_t j = 0; j < dim; ++j)
                normalized[i + (int64_t)j * dim] = 0.5 * (tmp[i + (int64_t)j * dim] + tmp[j + (int64_t)i * dim]);
        for (int64_t q = 0; ds && q < pairs; ++q) {
            dense_product(dim, form, ds + q * n2, tmp);
            int64_t p = 0;
            for (int32_t l = 0; l < dim; ++l)
                for (int32_t k = 0; k <= l; ++k, ++p)
                    derivative[p + q * pairs] = 0.5 * (tmp[k + (int64_t)l * dim] + tmp[l + (int64_t)k * dim]);
        }
    }
    CFI_FREE(ctx, finv, n2);
    CFI_FREE(ctx, s, n2);
    CFI_FREE(ctx, sinv, n2);
    CFI_FREE(ctx, tmp, n2);
    CFI_FREE(ctx, tmp2, n2);
    if (ds) CFI_FREE(ctx, ds, pairs * n2);
    return st;
}
