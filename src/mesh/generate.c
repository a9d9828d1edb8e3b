/*
 * Built-in mesh generators (curvflow/generate.h): icosphere, torus, bumpy
 * sphere with a texture seam, sphere with limbs (the demo's shape), grid,
 * cylinder, box bar and sheet (Zhao & Gortler §5 and App. B test shapes),
 * bumpy height field and a genus-2 fixture. All are deterministic; random
 * ones use a seeded splitmix64. Each builds flat arrays through the context
 * and hands them to cf_mesh_create, so every generated mesh is validated.
 */
#include "curvflow/generate.h"
#include "mesh/mesh_internal.h"

#include <math.h>
#include <string.h>

#define CF_PI 3.14159265358979323846

/* ------------------------------------------------------------------------ */
/* Shared helpers */

typedef struct arrays {
    int32_t nv, nf, nuv;
    double *pos;     /* 3 nv */
    int32_t *tri;    /* 3 nf */
    double *uv;      /* 2 nuv or NULL */
    int32_t *uv_tri; /* 3 nf or NULL (per-vertex uv when uv != NULL) */
} arrays;

static cf_status arrays_alloc(cf_context *ctx, arrays *a, int64_t nv, int64_t nf, int64_t nuv, bool per_corner)
{
    memset(a, 0, sizeof *a);
    if (nv > INT32_MAX / 4 || nf > INT32_MAX / 12 || nuv > INT32_MAX / 4)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "generated mesh too large (%lld vertices, %lld faces)",
                         (long long)nv, (long long)nf);
    a->nv = (int32_t)nv;
    a->nf = (int32_t)nf;
    a->nuv = (int32_t)nuv;
    a->pos = CFI_ALLOC(ctx, double, 3 * (size_t)nv);
    a->tri = CFI_ALLOC(ctx, int32_t, 3 * (size_t)nf);
    if (nuv > 0) a->uv = CFI_ALLOC(ctx, double, 2 * (size_t)nuv);
    if (nuv > 0 && per_corner) a->uv_tri = CFI_ALLOC(ctx, int32_t, 3 * (size_t)nf);
    if (!a->pos || !a->tri || (nuv > 0 && !a->uv) || (nuv > 0 && per_corner && !a->uv_tri)) return CF_ERR_NOMEM;
    return CF_OK;
}

static void arrays_free(cf_context *ctx, arrays *a)
{
    CFI_FREE(ctx, a->pos, 3 * (size_t)a->nv);
    CFI_FREE(ctx, a->tri, 3 * (size_t)a->nf);
    CFI_FREE(ctx, a->uv, 2 * (size_t)a->nuv);
    CFI_FREE(ctx, a->uv_tri, 3 * (size_t)a->nf);
}

/* Creates the mesh from a and frees a (also on failure). */
static cf_status arrays_finish(cf_context *ctx, arrays *a, cf_status st, cf_mesh **out)
{
    if (st == CF_OK) {
        cf_mesh_desc d = {a->nv, a->pos, a->nf, a->tri, a->uv ? a->nuv : 0, a->uv, a->uv_tri};
        st = cf_mesh_create(ctx, &d, out);
    }
    arrays_free(ctx, a);
    return st;
}

static bool positive_finite(double x) { return isfinite(x) && x > 0.0; }

static cf_status check_out(cf_context *ctx, cf_mesh **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "output pointer is NULL");
    *out = NULL;
    return CF_OK;
}

/* splitmix64 (Steele et al. 2014): tiny, seedable, platform-independent. */
static uint64_t rng_next(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Uniform in [lo, hi). */
static double rng_uniform(uint64_t *state, double lo, double hi)
{
    return lo + (hi - lo) * ((double)(rng_next(state) >> 11) * (1.0 / 9007199254740992.0));
}

/* ------------------------------------------------------------------------ */
/* Icosphere */

static void icosahedron(double radius, double *pos, int32_t *tri)
{
    /* golden ratio; vertices are the cyclic permutations of (+-1, +-phi, 0) */
    const double g = 1.61803398874989484820;
    const double base[12][3] = {{-1, g, 0}, {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                                {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
    static const int32_t faces[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                         {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                         {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                         {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int v = 0; v < 12; ++v) {
        const double *p = base[v];
        double n = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (int k = 0; k < 3; ++k) pos[3 * v + k] = radius * p[k] / n;
    }
    /* orient every face outward (normal along its centroid) */
    for (int f = 0; f < 20; ++f) {
        const double *a = pos + 3 * faces[f][0], *b = pos + 3 * faces[f][1], *c = pos + 3 * faces[f][2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double nrm[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        bool outward = nrm[0] * (a[0] + b[0] + c[0]) + nrm[1] * (a[1] + b[1] + c[1]) + nrm[2] * (a[2] + b[2] + c[2]) > 0;
        tri[3 * f] = faces[f][0];
        tri[3 * f + 1] = outward ? faces[f][1] : faces[f][2];
        tri[3 * f + 2] = outward ? faces[f][2] : faces[f][1];
    }
}

cf_status cf_generate_icosphere(cf_context *ctx, int32_t subdivisions, double radius, cf_mesh **out)
{
    cf_status st = check_out(ctx, out);
    if (st != CF_OK) return st;
    if (subdivisions < 0 || subdivisions > 9)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "icosphere subdivisions %d outside [0, 9]", subdivisions);
    if (!positive_finite(radius)) return cfi_error(ctx, CF_ERR_INVALID_ARG, "icosphere radius %g must be > 0", radius);
    arrays a;
    st = arrays_alloc(ctx, &a, 12, 20, 0, false);
    if (st == CF_OK) icosahedron(radius, a.pos, a.tri);
    cf_mesh *m = NULL;
    st = arrays_finish(ctx, &a, st, &m);
    for (int32_t level = 0; st == CF_OK && level < subdivisions; ++level) {
        /* 1-to-4 split; each edge midpoint projected exactly onto the sphere */
        st = arrays_alloc(ctx, &a, (int64_t)m->nv + m->ne, 4 * (int64_t)m->nf, 0, false);
        if (st == CF_OK) {
            memcpy(a.pos, m->positions, 3 * (size_t)m->nv * sizeof(double));
            for (int32_t e = 0; e < m->ne; ++e) {
                const double *p = m->positions + 3 * (size_t)m->edge_vertices[2 * e];
                const double *q = m->positions + 3 * (size_t)m->edge_vertices[2 * e + 1];
                double mid[3] = {p[0] + q[0], p[1] + q[1], p[2] + q[2]};
                double n = sqrt(mid[0] * mid[0] + mid[1] * mid[1] + mid[2] * mid[2]);
                for (int k = 0; k < 3; ++k) a.pos[3 * ((size_t)m->nv + e) + k] = radius * mid[k] / n;
            }
            cfi_mesh_split4_triangles(m, a.tri);
        }
        cf_mesh_destroy(&m);
        st = arrays_finish(ctx, &a, st, &m);
    }
    if (st != CF_OK) {
        cf_mesh_destroy(&m);
        return st;
    }
    *out = m;
    return CF_OK;
}

/* ------------------------------------------------------------------------ */
/* Torus */

cf_status cf_generate_torus(cf_context *ctx, double major_radius, double minor_radius, int32_t n_major,
                            int32_t n_minor, cf_mesh **out)
{
    cf_status st = check_out(ctx, out);
    if (st != CF_OK) return st;
    if (!positive_finite(major_radius) || !positive_finite(minor_radius) || !(minor_radius < major_radius))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "torus radii need 0 < minor (%g) < major (%g)", minor_radius,
                         major_radius);
    if (n_major < 3 || n_minor < 3 || n_major > 100000 || n_minor > 100000)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "torus resolution %d x %d: each must be in [3, 100000]", n_major,
                         n_minor);
    arrays a;
    int64_t nv = (int64_t)n_major * n_minor;
    st = arrays_alloc(ctx, &a, nv, 2 * nv, 0, false);
    if (st == CF_OK) {
        for (int32_t i = 0; i < n_major; ++i) {
            double u = 2.0 * CF_PI * i / n_major;
            for (int32_t j = 0; j < n_minor; ++j) {
                double v = 2.0 * CF_PI * j / n_minor;
                double *p = a.pos + 3 * ((size_t)i * n_minor + j);
                double rr = major_radius + minor_radius * cos(v);
                p[0] = rr * cos(u);
                p[1] = rr * sin(u);
                p[2] = minor_radius * sin(v);
            }
        }
        /* d/du x d/dv points outward, so (i,j) -> (i+1,j) -> (i+1,j+1) is CCW */
        int32_t *t = a.tri;
        for (int32_t i = 0; i < n_major; ++i)
            for (int32_t j = 0; j < n_minor; ++j) {
                int32_t i1 = (i + 1) % n_major, j1 = (j + 1) % n_minor;
                int32_t v00 = i * n_minor + j, v10 = i1 * n_minor + j;
                int32_t v11 = i1 * n_minor + j1, v01 = i * n_minor + j1;
                *t++ = v00, *t++ = v10, *t++ = v11;
                *t++ = v00, *t++ = v11, *t++ = v01;
            }
    }
    return arrays_finish(ctx, &a, st, out);
}

/* ------------------------------------------------------------------------ */
/* Flat grids: grid, sheet, bumpy plane */

/* Splits cell (i, j) with corners v00, v10, v11, v01 (CCW seen from +z).
 * pattern 0: diagonal v00-v11; pattern 1: checkerboard of both diagonals. */
static int32_t *emit_quad(int32_t *t, int32_t v00, int32_t v10, int32_t v11, int32_t v01, int32_t pattern,
                          int32_t parity)
{
    if (pattern == 1 && (parity & 1)) {
        *t++ = v00, *t++ = v10, *t++ = v01;
        *t++ = v10, *t++ = v11, *t++ = v01;
    } else {
        *t++ = v00, *t++ = v10, *t++ = v11;
        *t++ = v00, *t++ = v11, *t++ = v01;
    }
    return t;
}

static cf_status plane(cf_context *ctx, int32_t nx, int32_t ny, double width, double height, int32_t pattern,
                       const double *bumps, int32_t n_bumps, double amplitude, cf_mesh **out)
{
    if (nx < 1 || ny < 1 || nx > 46000 || ny > 46000)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "grid resolution %d x %d: each must be in [1, 46000]", nx, ny);
    if (!positive_finite(width) || !positive_finite(height))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "grid size %g x %g must be positive", width, height);
    if (pattern != 0 && pattern != 1) return cfi_error(ctx, CF_ERR_INVALID_ARG, "pattern %d is not 0 or 1", pattern);
    arrays a;
    int64_t nv = (int64_t)(nx + 1) * (ny + 1);
    cf_status st = arrays_alloc(ctx, &a, nv, 2 * (int64_t)nx * ny, nv, false);
    if (st == CF_OK) {
        for (int32_t j = 0; j <= ny; ++j)
            for (int32_t i = 0; i <= nx; ++i) {
                size_t v = (size_t)j * (nx + 1) + i;
                double s = (double)i / nx, r = (double)j / ny;
                double z = 0.0;
                for (int32_t k = 0; k < n_bumps; ++k) {
                    const double *b = bumps + 4 * k; /* centre s, r, width, weight */
                    double ds = s - b[0], dr = r - b[1];
                    z += b[3] * exp(-(ds * ds + dr * dr) / (b[2] * b[2]));
                }
                a.pos[3 * v] = width * s;
                a.pos[3 * v + 1] = height * r;
                a.pos[3 * v + 2] = amplitude * z;
                a.uv[2 * v] = s;
                a.uv[2 * v + 1] = r;
            }
        int32_t *t = a.tri;
        for (int32_t j = 0; j < ny; ++j)
            for (int32_t i = 0; i < nx; ++i) {
                int32_t v00 = j * (nx + 1) + i;
                t = emit_quad(t, v00, v00 + 1, v00 + nx + 2, v00 + nx + 1, pattern, i + j);
            }
    }
    return arrays_finish(ctx, &a, st, out);
}

cf_status cf_generate_grid(cf_context *ctx, int32_t nx, int32_t ny, double width, double height, cf_mesh **out)
{
    cf_status st = check_out(ctx, out);
    if (st != CF_OK) return st;
    return plane(ctx, nx, ny, width, height, 0, NULL, 0, 0.0, out);
}

cf_status cf_generate_sheet(cf_context *ctx, int32_t n, double size, int32_t pattern, cf_mesh **out)
{
    cf_status st = check_out(ctx, out);
    if (st != CF_OK) return st;
    return plane(ctx, n, n, size, size, pattern, NULL, 0, 0.0, out);
}

cf_status cf_generate_bumpy_plane(cf_context *ctx, int32_t n, double size, double amplitude, uint32_t seed,
                                  cf_mesh **out)
{
    cf_status st = check_out(ctx, out);
    if (st != CF_OK) return st;
    if (!isfinite(amplitude)) return cfi_error(ctx, CF_ERR_INVALID_ARG, "amplitude is not finite");
    enum { NB = 5 };
    double bumps[4 * NB];
    uint64_t state = seed;
    for (int k = 0; k < NB; ++k) {
        bumps[4 * k] = rng_uniform(&state, 0.15, 0.85);
        bumps[4 * k + 1] = rng_uniform(&state, 0.15, 0.85);
        bumps[4 * k + 2] = rng_uniform(&state, 0.12, 0.3);
        bumps[4 * k + 3] = rng_uniform(&state, -1.0, 1.0);
    }
    /* normalise max |h| = 1 on a fine sample grid (resolution independent) */
    double hmax = 0.0;
    for (int j = 0; j <= 200; ++j)
        for (int i = 0; i <= 200; ++i) {
            double h = 0.0;
            for (int k = 0; k < NB; ++k) {
                double ds = i / 200.0 - bumps[4 * k], dr = j / 200.0 - bumps[4 * k + 1];
                h += bumps[4 * k + 3] * exp(-(ds * ds + dr * dr) / (bumps[4 * k + 2] * bumps[4 * k + 2]));
            }
            if (fabs(h) > hmax) hmax = fabs(h);
        }
    for (int k = 0; k < NB; ++k) bumps[4 * k + 3] /= hmax;
    if (!positive_finite(size)) return cfi_error(ctx, CF_ERR_INVALID_ARG, "size %g must be positive", size);
    return plane(ctx, n, n, size, size, 0, bumps, NB, amplitude * size, out);
}

/* ------------------------------------------------------------------------ */
/* Bumpy sphere with a texture seam */

enum { BUMPY_SPHERE_BUMPS = 6 };

static double bump_field(const double *bumps, const double *n)
{
    double h = 0.0;
    for (int k = 0; k < BUMPY_SPHERE_BUMPS; ++k) {
        const double *b = bumps + 5 * k; /* direction xyz, width, weight */
        double c = n[0] * b[0] + n[1] * b[1] + n[2] * b[2];
        h += b[4] * exp(-(1.0 - c) / (b[3] * b[3]));
    }
    return h;
}

/* The unit icosphere `sphere` pushed out radially to radius[v] at vertex v,
 * with per-corner texture coordinates (longitude / 2 pi, latitude / pi +
 * 1/2): corners of faces that straddle the longitude-pi seam get a shifted
 * copy (u + 1) so the texture does not jump, and each pole corner gets its
 * own uv at the face's mean longitude. Shared by the radial shapes below. */
static cf_status radial_sphere_with_uv(cf_context *ctx, const cf_mesh *sphere, const double *radius, cf_mesh **out)
{
    cf_status st = CF_OK;
    const int32_t nv = sphere->nv, nf = sphere->nf;
    const double *sp = sphere->positions;
    /* uv: one entry per vertex, plus a shifted copy (u + 1) for vertices
     * used by faces that straddle the seam, plus one entry per pole corner */
    int32_t *shifted = CFI_ALLOC(ctx, int32_t, nv);
    double *vu = CFI_ALLOC(ctx, double, 2 * (size_t)nv);
    arrays a;
    memset(&a, 0, sizeof a);
    if (!shifted || !vu) st = CF_ERR_NOMEM;
    if (st == CF_OK) st = arrays_alloc(ctx, &a, nv, nf, (int64_t)nv + 3 * (int64_t)nf, true);
    if (st == CF_OK) {
        for (int32_t v = 0; v < nv; ++v) {
            const double *n = sp + 3 * (size_t)v;
            for (int k = 0; k < 3; ++k) a.pos[3 * (size_t)v + k] = radius[v] * n[k];
            bool pole = hypot(n[0], n[1]) < 1e-12;
            vu[2 * v] = pole ? -1.0 : (atan2(n[1], n[0]) + CF_PI) / (2.0 * CF_PI);
            vu[2 * v + 1] = asin(n[2] < -1.0 ? -1.0 : (n[2] > 1.0 ? 1.0 : n[2])) / CF_PI + 0.5;
            a.uv[2 * v] = vu[2 * v] < 0 ? 0.5 : vu[2 * v];
            a.uv[2 * v + 1] = vu[2 * v + 1];
            shifted[v] = -1;
        }
        memcpy(a.tri, sphere->triangles, 3 * (size_t)nf * sizeof(int32_t));
        int32_t nuv = nv;
        for (int32_t f = 0; f < nf; ++f) {
            const int32_t *t = a.tri + 3 * (size_t)f;
            double u[3];
            double lo = 2.0, hi = -1.0;
            for (int k = 0; k < 3; ++k) {
                u[k] = vu[2 * t[k]];
                if (u[k] < 0) continue; /* pole */
                if (u[k] < lo) lo = u[k];
                if (u[k] > hi) hi = u[k];
            }
            bool seam = hi - lo > 0.5;
            double sum = 0.0;
            int cnt = 0;
            for (int k = 0; k < 3; ++k) {
                if (u[k] < 0) continue;
                if (seam && u[k] < 0.5) u[k] += 1.0;
                sum += u[k];
                ++cnt;
            }
            for (int k = 0; k < 3; ++k) {
                int32_t v = t[k];
                int32_t idx = v;
                if (u[k] < 0) { /* pole: own uv at the face's mean longitude */
                    idx = nuv++;
                    a.uv[2 * (size_t)idx] = cnt ? sum / cnt : 0.5;
                    a.uv[2 * (size_t)idx + 1] = vu[2 * v + 1];
                } else if (u[k] >= 1.0 && vu[2 * v] < 0.5) { /* shifted across the seam */
                    if (shifted[v] < 0) {
                        shifted[v] = nuv++;
                        a.uv[2 * (size_t)shifted[v]] = u[k];
                        a.uv[2 * (size_t)shifted[v] + 1] = vu[2 * v + 1];
                    }
                    idx = shifted[v];
                }
                a.uv_tri[3 * (size_t)f + k] = idx;
            }
        }
        /* shrink the uv count to what was used (arrays_free uses a.nuv) */
        double *uv = CFI_ALLOC(ctx, double, 2 * (size_t)nuv);
        if (!uv) {
            st = CF_ERR_NOMEM;
        } else {
            memcpy(uv, a.uv, 2 * (size_t)nuv * sizeof(double));
            CFI_FREE(ctx, a.uv, 2 * (size_t)a.nuv);
            a.uv = uv;
            a.nuv = nuv;
        }
    }
    CFI_FREE(ctx, shifted, nv);
    CFI_FREE(ctx, vu, 2 * (size_t)nv);
    return arrays_finish(ctx, &a, st, out);
}

cf_status cf_generate_bumpy_sphere(cf_context *ctx, int32_t subdivisions, double amplitude, uint32_t seed,
                                   cf_mesh **out)
{
    cf_status st = check_out(ctx, out);
    if (st != CF_OK) return st;
    if (!isfinite(amplitude) || fabs(amplitude) >= 0.5)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "bumpy sphere amplitude %g must be in (-0.5, 0.5)", amplitude);
    cf_mesh *sphere = NULL;
    st = cf_generate_icosphere(ctx, subdivisions, 1.0, &sphere);
    if (st != CF_OK) return st;

    double bumps[5 * BUMPY_SPHERE_BUMPS];
    uint64_t state = seed;
    for (int k = 0; k < BUMPY_SPHERE_BUMPS; ++k) {
        double z = rng_uniform(&state, -1.0, 1.0), phi = rng_uniform(&state, 0.0, 2.0 * CF_PI);
        double r = sqrt(1.0 - z * z);
        double *b = bumps + 5 * k;
        b[0] = r * cos(phi), b[1] = r * sin(phi), b[2] = z;
        b[3] = rng_uniform(&state, 0.35, 0.7);
        b[4] = rng_uniform(&state, -1.0, 1.0);
    }
    const int32_t nv = sphere->nv;
    const double *sp = sphere->positions;
    /* normalise so max |h| = 1 over the vertices */
    double hmax = 0.0;
    for (int32_t v = 0; v < nv; ++v) {
        double h = fabs(bump_field(bumps, sp + 3 * (size_t)v));
        if (h > hmax) hmax = h;
    }
    if (!(hmax > 0.0)) hmax = 1.0;

    double *radius = CFI_ALLOC(ctx, double, nv);
    if (!radius) {
        cf_mesh_destroy(&sphere);
        return CF_ERR_NOMEM;
    }
    for (int32_t v = 0; v < nv; ++v) radius[v] = 1.0 + amplitude * bump_field(bumps, sp + 3 * (size_t)v) / hmax;
    st = radial_sphere_with_uv(ctx, sphere, radius, out);
    CFI_FREE(ctx, radius, nv);
    cf_mesh_destroy(&sphere);
    return st;
}

/* ------------------------------------------------------------------------ */
/* Sphere with smooth limbs (the demo's shape) */

cf_status cf_generate_limb_sphere(cf_context *ctx, int32_t subdivisions, int32_t limbs, double length, double width,
                                  cf_mesh **out)
{
    cf_status st = check_out(ctx, out);
    if (st != CF_OK) return st;
    if (limbs < 1 || limbs > CF_LIMB_SPHERE_MAX_LIMBS)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "limb sphere: %d limbs outside [1, %d]", limbs,
                         CF_LIMB_SPHERE_MAX_LIMBS);
    if (!isfinite(length) || length < 0.0 || length > 10.0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "limb sphere: limb length %g outside [0, 10]", length);
    if (!isfinite(width) || width < 0.05 || width > 2.0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "limb sphere: limb width %g outside [0.05, 2]", width);
    cf_mesh *sphere = NULL;
    st = cf_generate_icosphere(ctx, subdivisions, 1.0, &sphere);
    if (st != CF_OK) return st;
    /* the cube's corner directions, ordered so that the first four form a
     * regular tetrahedron (limbs as far apart as possible for 1..4) */
    static const double corners[CF_LIMB_SPHERE_MAX_LIMBS][3] = {{1, 1, 1},   {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1},
                                                                {-1, -1, -1}, {-1, 1, 1}, {1, -1, 1},  {1, 1, -1}};
    const double inv_sqrt3 = 1.0 / sqrt(3.0), inv_w2 = 1.0 / (width * width);
    const int32_t nv = sphere->nv;
    double *radius = CFI_ALLOC(ctx, double, nv);
    if (!radius) {
        cf_mesh_destroy(&sphere);
        return CF_ERR_NOMEM;
    }
    for (int32_t v = 0; v < nv; ++v) {
        const double *n = sphere->positions + 3 * (size_t)v;
        double r = 1.0;
        for (int32_t k = 0; k < limbs; ++k) {
            const double *d = corners[k];
            double c = inv_sqrt3 * (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]);
            r += length * exp(-(1.0 - c) * inv_w2);
        }
        radius[v] = r;
    }
    st = radial_sphere_with_uv(ctx, sphere, radius, out);
    CFI_FREE(ctx, radius, nv);
    cf_mesh_destroy(&sphere);
    return st;
}

/* ------------------------------------------------------------------------ */
/* Cylinder */

cf_status cf_generate_cylinder(cf_context *ctx, int32_t n_around, int32_t n_along, double radius, double height,
                               cf_mesh **out)
{
    cf_status st = check_out(ctx, out);
    if (st != CF_OK) return st;
    if (n_around < 3 || n_along < 1 || n_around > 100000 || n_along > 100000)
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "cylinder resolution %d around x %d along: need [3, 100000] x [1, 100000]", n_around, n_along);
    if (!positive_finite(radius) || !positive_finite(height))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cylinder radius %g and height %g must be positive", radius,
                         height);
    arrays a;
    int64_t nv = (int64_t)n_around * (n_along + 1);
    int64_t nuv = (int64_t)(n_around + 1) * (n_along + 1);
    st = arrays_alloc(ctx, &a, nv, 2 * (int64_t)n_around * n_along, nuv, true);
    if (st == CF_OK) {
        for (int32_t j = 0; j <= n_along; ++j) {
            for (int32_t i = 0; i < n_around; ++i) {
                double th = 2.0 * CF_PI * i / n_around;
                double *p = a.pos + 3 * ((size_t)j * n_around + i);
                p[0] = radius * cos(th);
                p[1] = radius * sin(th);
                p[2] = height * j / n_along;
            }
            for (int32_t i = 0; i <= n_around; ++i) {
                size_t t = (size_t)j * (n_around + 1) + i;
                a.uv[2 * t] = (double)i / n_around;
                a.uv[2 * t + 1] = (double)j / n_along;
            }
        }
        /* around x along = outward radial, so (i,j),(i+1,j),(i+1,j+1) is CCW */
        int32_t *t = a.tri, *tu = a.uv_tri;
        for (int32_t j = 0; j < n_along; ++j)
            for (int32_t i = 0; i < n_around; ++i) {
                int32_t i1 = (i + 1) % n_around;
                int32_t v00 = j * n_around + i, v10 = j * n_around + i1;
                int32_t v11 = (j + 1) * n_around + i1, v01 = (j + 1) * n_around + i;
                int32_t u00 = j * (n_around + 1) + i, u10 = u00 + 1;
                int32_t u11 = u10 + n_around + 1, u01 = u00 + n_around + 1;
                *t++ = v00, *t++ = v10, *t++ = v11, *t++ = v00, *t++ = v11, *t++ = v01;
                *tu++ = u00, *tu++ = u10, *tu++ = u11, *tu++ = u00, *tu++ = u11, *tu++ = u01;
            }
    }
    return arrays_finish(ctx, &a, st, out);
}

/* ------------------------------------------------------------------------ */
/* Voxel surfaces: bar and genus-2 fixture */

typedef struct voxels {
    int32_t dim[3];
    double scale[3];
    int32_t hole_cell; /* > 0: genus-2 fixture, cells of this many voxels */
} voxels;

static bool voxel_filled(const voxels *vx, int32_t i, int32_t j, int32_t k)
{
    if (i < 0 || j < 0 || k < 0 || i >= vx->dim[0] || j >= vx->dim[1] || k >= vx->dim[2]) return false;
    if (vx->hole_cell > 0) {
        /* 5 x 3 x 1 slab of unit cells with holes at cells (1, 1) and (3, 1) */
        int32_t ci = i / vx->hole_cell, cj = j / vx->hole_cell;
        if (cj == 1 && (ci == 1 || ci == 3)) return false;
    }
    return true;
}

/* Emits (emit = true) or counts the boundary quads of the voxel set, two
 * triangles each; lattice maps lattice points to vertex indices. */
static int64_t voxel_surface(const voxels *vx, int32_t pattern, bool emit, int32_t *lattice, arrays *a)
{
    const int32_t X = vx->dim[0], Y = vx->dim[1], Z = vx->dim[2];
    int64_t quads = 0;
    int32_t nv = 0;
    int32_t *t = emit ? a->tri : NULL;
    for (int32_t k = 0; k < Z; ++k)
        for (int32_t j = 0; j < Y; ++j)
            for (int32_t i = 0; i < X; ++i) {
                if (!voxel_filled(vx, i, j, k)) continue;
                int32_t c[3] = {i, j, k};
                for (int32_t axis = 0; axis < 3; ++axis)
                    for (int32_t side = 0; side < 2; ++side) {
                        int32_t nb[3] = {i, j, k};
                        nb[axis] += side ? 1 : -1;
                        if (voxel_filled(vx, nb[0], nb[1], nb[2])) continue;
                        ++quads;
                        if (!emit) continue;
                        /* outward normal +-axis = e_b x e_c */
                        int32_t b = (axis + 1) % 3, cc = (axis + 2) % 3;
                        if (!side) {
                            int32_t tmp = b;
                            b = cc;
                            cc = tmp;
                        }
                        int32_t corner[4];
                        for (int q = 0; q < 4; ++q) {
                            int32_t l[3] = {c[0], c[1], c[2]};
                            l[axis] += side;
                            if (q == 1 || q == 2) ++l[b];
                            if (q == 2 || q == 3) ++l[cc];
                            size_t li = ((size_t)l[2] * (Y + 1) + l[1]) * (X + 1) + l[0];
                            if (lattice[li] < 0) {
                                lattice[li] = nv;
                                for (int d = 0; d < 3; ++d) a->pos[3 * (size_t)nv + d] = vx->scale[d] * l[d];
                                ++nv;
                            }
                            corner[q] = lattice[li];
                        }
                        t = emit_quad(t, corner[0], corner[1], corner[2], corner[3], pattern, c[b] + c[cc]);
                    }
            }
    if (emit) a->nv = nv;
    return quads;
}

static cf_status voxel_mesh(cf_context *ctx, const voxels *vx, int32_t pattern, cf_mesh **out)
{
    int64_t quads = voxel_surface(vx, pattern, false, NULL, NULL);
    size_t lattice_n = (size_t)(vx->dim[0] + 1) * (size_t)(vx->dim[1] + 1) * (size_t)(vx->dim[2] + 1);
    /* surface vertices <= 4 quads; the exact count is known after emitting */
    arrays a;
    cf_status st = arrays_alloc(ctx, &a, 4 * quads, 2 * quads, 0, false);
    int32_t *lattice = st == CF_OK ? CFI_ALLOC(ctx, int32_t, lattice_n) : NULL;
    if (st == CF_OK && !lattice) st = CF_ERR_NOMEM;
    if (st == CF_OK) {
        for (size_t i = 0; i < lattice_n; ++i) lattice[i] = -1;
        int32_t cap = a.nv;
        voxel_surface(vx, pattern, true, lattice, &a);
        /* shrink positions to the vertices used */
        double *pos = CFI_ALLOC(ctx, double, 3 * (size_t)a.nv);
        if (!pos) {
            st = CF_ERR_NOMEM;
        } else {
            memcpy(pos, a.pos, 3 * (size_t)a.nv * sizeof(double));
        }
        CFI_FREE(ctx, a.pos, 3 * (size_t)cap);
        a.pos = pos;
    }
    CFI_FREE(ctx, lattice, lattice_n);
    return arrays_finish(ctx, &a, st, out);
}

cf_status cf_generate_bar(cf_context *ctx, int32_t nx, int32_t ny, int32_t nz, double lx, double ly, double lz,
                          int32_t pattern, cf_mesh **out)
{
    cf_status st = check_out(ctx, out);
    if (st != CF_OK) return st;
    if (nx < 1 || ny < 1 || nz < 1 || nx > 2000 || ny > 2000 || nz > 2000)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "bar resolution %d x %d x %d: each must be in [1, 2000]", nx, ny,
                         nz);
    if ((int64_t)(nx + 1) * (ny + 1) * (nz + 1) > 200000000)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "bar resolution %d x %d x %d too large", nx, ny, nz);
    if (!positive_finite(lx) || !positive_finite(ly) || !positive_finite(lz))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "bar size %g x %g x %g must be positive", lx, ly, lz);
    if (pattern != 0 && pattern != 1) return cfi_error(ctx, CF_ERR_INVALID_ARG, "pattern %d is not 0 or 1", pattern);
    voxels vx = {{nx, ny, nz}, {lx / nx, ly / ny, lz / nz}, 0};
    return voxel_mesh(ctx, &vx, pattern, out);
}

cf_status cf_generate_double_torus(cf_context *ctx, int32_t resolution, cf_mesh **out)
{
    cf_status st = check_out(ctx, out);
    if (st != CF_OK) return st;
    if (resolution < 1 || resolution > 200)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "double torus resolution %d outside [1, 200]", resolution);
    double s = 1.0 / (5.0 * resolution);
    voxels vx = {{5 * resolution, 3 * resolution, resolution}, {s, s, s}, resolution};
    return voxel_mesh(ctx, &vx, 1, out);
}
