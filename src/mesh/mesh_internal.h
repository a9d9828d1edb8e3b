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
