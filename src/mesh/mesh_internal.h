/*
 * Internal layout of cf_mesh. Operators and methods read these arrays
 * directly; only src/mesh/ writes them. Meanings as in curvflow/mesh.h.
 */
#ifndef CF_MESH_MESH_INTERNAL_H
#define CF_MESH_MESH_INTERNAL_H

#include "core/core.h"
#include "curvflow/mesh.h"

#include <math.h>

struct cf_mesh {
    cf_context *ctx;
    int32_t nv, nf, ne;
    double *positions;            /* 3 nv */
    int32_t *triangles;           /* 3 nf */
    int32_t *edge_vertices;       /* 2 ne, i < j */
    int32_t *halfedge_edge;       /* 3 nf */
    int32_t *halfedge_twin;       /* 3 nf, -1 on boundary */
    int32_t *edge_faces;          /* 2 ne */
    int32_t *edge_halfedge;       /* ne: a halfedge of the edge (the interior-side one on the boundary) */
    uint8_t *vertex_on_boundary;  /* nv */
    int32_t *vertex_component;    /* nv */
    int32_t *face_component;      /* nf */
    int32_t *ring_offsets;        /* nv + 1 */
    int32_t *ring_neighbors;      /* 2 ne */
    int32_t *ring_edges;          /* 2 ne */
    int32_t *vface_offsets;       /* nv + 1 */
    int32_t *vface_faces;         /* 3 nf */
    int32_t boundary_loop_count;
    int32_t *boundary_loop_offsets;   /* loops + 1 */
    int32_t *boundary_loop_vertices;  /* boundary vertex count */
    int32_t component_count;
    int32_t euler_characteristic;
    int32_t genus;
    int32_t uv_count;
    double *uv;                   /* 2 uv_count or NULL */
    int32_t *uv_triangles;        /* 3 nf or NULL */
    /* Added after the fixed layout above. */
    int32_t boundary_vertex_count;    /* length of boundary_loop_vertices */
};

/* Halfedge helpers: h = 3 f + k runs triangles[h] -> triangles[next(h)]. */
static inline int32_t cfi_he_face(int32_t h) { return h / 3; }
static inline int32_t cfi_he_next(int32_t h) { return h - h % 3 + (h % 3 + 1) % 3; }
static inline int32_t cfi_he_prev(int32_t h) { return h - h % 3 + (h % 3 + 2) % 3; }

/* Topology of one 1-to-4 split (used by the icosphere generator and Loop
 * subdivision): vertex v keeps index v, the midpoint of edge e gets index
 * nv + e, and face f becomes faces 4f .. 4f+3 of out (12 nf int32):
 * (a, m_ab, m_ca), (m_ab, b, m_bc), (m_ca, m_bc, c), (m_ab, m_bc, m_ca),
 * all oriented like f. */
void cfi_mesh_split4_triangles(const cf_mesh *mesh, int32_t *out);

/* The point q of triangle (a, b, c) nearest to p: p located in the
 * triangle's Voronoi regions (vertex, edge, interior) from barycentric dot
 * products (Ericson, Real-Time Collision Detection, 5.1.5). Shared by the
 * surface distance (metrics) and the tangential relaxation's projection
 * (ops). */
static inline void cfi_nearest_point_on_triangle(const double p[3], const double a[3], const double b[3],
                                                 const double c[3], double q[3])
{
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    for (int k = 0; k < 3; ++k) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = p[k] - a[k];
        bp[k] = p[k] - b[k];
        cp[k] = p[k] - c[k];
    }
#define CFI_DOT3(u, v) ((u)[0] * (v)[0] + (u)[1] * (v)[1] + (u)[2] * (v)[2])
    double d1 = CFI_DOT3(ab, ap), d2 = CFI_DOT3(ac, ap), d3 = CFI_DOT3(ab, bp), d4 = CFI_DOT3(ac, bp),
           d5 = CFI_DOT3(ab, cp), d6 = CFI_DOT3(ac, cp);
#undef CFI_DOT3
    double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d1 <= 0.0 && d2 <= 0.0) { /* vertex a */
        for (int k = 0; k < 3; ++k) q[k] = a[k];
    } else if (d3 >= 0.0 && d4 <= d3) { /* vertex b */
        for (int k = 0; k < 3; ++k) q[k] = b[k];
    } else if (d6 >= 0.0 && d5 <= d6) { /* vertex c */
        for (int k = 0; k < 3; ++k) q[k] = c[k];
    } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) { /* edge ab */
        double t = d1 / (d1 - d3);
        for (int k = 0; k < 3; ++k) q[k] = a[k] + t * ab[k];
    } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) { /* edge ac */
        double t = d2 / (d2 - d6);
        for (int k = 0; k < 3; ++k) q[k] = a[k] + t * ac[k];
    } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) { /* edge bc */
        double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int k = 0; k < 3; ++k) q[k] = b[k] + t * (c[k] - b[k]);
    } else { /* interior: barycentric (va, vb, vc) / sum */
        double sum = va + vb + vc;
        double v = vb / sum, w = vc / sum;
        for (int k = 0; k < 3; ++k) q[k] = a[k] + v * ab[k] + w * ac[k];
    }
}

/* A triangle has zero area for the mesh check when its area is at most this
 * times the square of its longest edge (scale-free). */
#define CFI_ZERO_AREA_RATIO 1e-14

/* Area of the triangle (a, b, c); *longest2 gets the square of its longest
 * edge, for the zero-area test above. */
static inline double cfi_triangle_area(const double *a, const double *b, const double *c, double *longest2)
{
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; ++k) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
        w[k] = c[k] - b[k];
    }
    double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2], z = u[0] * v[1] - u[1] * v[0];
    double lu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    double lv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    double lw = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    double l = lu > lv ? lu : lv;
    *longest2 = l > lw ? l : lw;
    return 0.5 * sqrt(x * x + y * y + z * z);
}

#endif /* CF_MESH_MESH_INTERNAL_H */
