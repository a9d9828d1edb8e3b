/*
 * Triangle meshes: validated connectivity built once from flat arrays.
 *
 * A cf_mesh holds connectivity and the rest positions it was created with.
 * Geometry changes (flows) are passed to operators as separate position
 * arrays, so one mesh serves every state of a flow.
 *
 * Conventions (docs/conventions.md):
 *  - triangles are counter-clockwise seen from outside (outward normals);
 *  - halfedge h = 3 f + k runs from corner k to corner (k + 1) % 3 of face f,
 *    and is opposite corner (k + 2) % 3;
 *  - edge e joins edge_vertices[2e] < edge_vertices[2e + 1];
 *  - the edge vector of e_ij is f_j - f_i.
 */
#ifndef CURVFLOW_MESH_H
#define CURVFLOW_MESH_H

#include "curvflow/curvflow.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cf_mesh cf_mesh;

/* Input description; the arrays are copied. */
typedef struct cf_mesh_desc {
    int32_t vertex_count;
    const double *positions;   /* 3 * vertex_count, xyz */
    int32_t face_count;
    const int32_t *triangles;  /* 3 * face_count, 0-based */
    /* Optional texture coordinates, passed through unchanged. Either per
     * vertex (uv_triangles == NULL, uv_count == vertex_count) or per corner
     * (uv_triangles: 3 * face_count indices into uv). */
    int32_t uv_count;
    const double *uv;          /* 2 * uv_count, or NULL */
    const int32_t *uv_triangles;
} cf_mesh_desc;

/* Validates the description and builds connectivity. On failure the status
 * names the first defect (CF_ERR_INDEX_RANGE, CF_ERR_REPEATED_INDEX,
 * CF_ERR_NONFINITE, CF_ERR_DEGENERATE_FACE, CF_ERR_NONMANIFOLD_EDGE,
 * CF_ERR_NONMANIFOLD_VERTEX, CF_ERR_ORIENTATION, CF_ERR_BAD_MESH for an
 * unreferenced vertex or an empty mesh) and the context message names the
 * element, e.g. "face 1832: edge (12, 977) is shared by 3 faces". */
CF_API cf_status cf_mesh_create(cf_context *ctx, const cf_mesh_desc *desc, cf_mesh **out);

/* Frees the mesh; accepts NULL; sets *mesh to NULL. */
CF_API void cf_mesh_destroy(cf_mesh **mesh);

/* Full validation report (for `curvflow info`): counts every defect instead
 * of stopping at the first. Never fails on bad geometry; returns CF_OK and
 * fills the report unless arguments are invalid or memory runs out. */
typedef struct cf_mesh_report {
    int32_t index_out_of_range;
    int32_t repeated_index;
    int32_t nonfinite_coordinates; /* NaN, Inf, or |x| > 1e50 (volumes would overflow) */
    int32_t degenerate_faces;      /* zero area, or every edge shorter than 1e-50 */
    int32_t nonmanifold_edges;
    int32_t nonmanifold_vertices;
    int32_t inconsistent_orientation_edges;
    int32_t unreferenced_vertices;
    cf_status first_status;    /* CF_OK if valid */
    char first_message[256];   /* message of the first defect found, "" if valid */
} cf_mesh_report;
CF_API cf_status cf_mesh_validate(cf_context *ctx, const cf_mesh_desc *desc, cf_mesh_report *report);

/* The same report for new positions of a built mesh (a flow's result): the
 * connectivity is the mesh's, already valid, so only the geometric checks
 * run (non-finite or out-of-range coordinates, degenerate faces). Equivalent
 * to cf_mesh_validate on the mesh's triangles with these positions, without
 * its O(faces) scratch memory. */
CF_API cf_status cf_mesh_check_positions(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                         cf_mesh_report *report);

/* Counts. */
CF_API int32_t cf_mesh_vertex_count(const cf_mesh *mesh);
CF_API int32_t cf_mesh_face_count(const cf_mesh *mesh);
CF_API int32_t cf_mesh_edge_count(const cf_mesh *mesh);
CF_API int32_t cf_mesh_boundary_loop_count(const cf_mesh *mesh);
CF_API int32_t cf_mesh_component_count(const cf_mesh *mesh);
/* V - E + F over the whole mesh. */
CF_API int32_t cf_mesh_euler_characteristic(const cf_mesh *mesh);
/* Sum over components of (2 - chi_c - b_c) / 2. */
CF_API int32_t cf_mesh_genus(const cf_mesh *mesh);

/* Arrays (owned by the mesh, valid for its lifetime). */
CF_API const double *cf_mesh_positions(const cf_mesh *mesh);        /* 3 nv rest positions */
CF_API const int32_t *cf_mesh_triangles(const cf_mesh *mesh);       /* 3 nf */
CF_API const int32_t *cf_mesh_edge_vertices(const cf_mesh *mesh);   /* 2 ne, i < j */
CF_API const int32_t *cf_mesh_halfedge_edge(const cf_mesh *mesh);   /* 3 nf: edge of halfedge 3f+k */
CF_API const int32_t *cf_mesh_halfedge_twin(const cf_mesh *mesh);   /* 3 nf: opposite halfedge, -1 on boundary */
CF_API const int32_t *cf_mesh_edge_faces(const cf_mesh *mesh);      /* 2 ne: face where the edge runs i->j, face where it runs j->i; -1 if none */
CF_API const uint8_t *cf_mesh_vertex_on_boundary(const cf_mesh *mesh); /* nv flags */
CF_API const int32_t *cf_mesh_vertex_component(const cf_mesh *mesh);   /* nv */
/* Boundary loops: loop b has vertices loop_vertices[offsets[b] .. offsets[b+1]),
 * in the direction of the boundary halfedges (interior on the left), starting
 * at the loop's lowest vertex; loops ordered by that vertex. loop_vertices is
 * NULL for a closed mesh. Edges are in lexicographic (i, j) order. */
CF_API const int32_t *cf_mesh_boundary_loop_offsets(const cf_mesh *mesh);  /* loops + 1 */
CF_API const int32_t *cf_mesh_boundary_loop_vertices(const cf_mesh *mesh);
/* Vertex rings as compressed rows: neighbours of v are
 * vertex_neighbors[offsets[v] .. offsets[v+1]), in increasing order, with the
 * joining edges at the same positions in vertex_edges. */
CF_API const int32_t *cf_mesh_vertex_ring_offsets(const cf_mesh *mesh);    /* nv + 1 */
CF_API const int32_t *cf_mesh_vertex_neighbors(const cf_mesh *mesh);
CF_API const int32_t *cf_mesh_vertex_edges(const cf_mesh *mesh);
/* Faces around v: vertex_faces[face_offsets[v] .. face_offsets[v+1]), in
 * increasing order. */
CF_API const int32_t *cf_mesh_vertex_face_offsets(const cf_mesh *mesh);    /* nv + 1 */
CF_API const int32_t *cf_mesh_vertex_faces(const cf_mesh *mesh);

/* Texture coordinates (NULL / 0 when absent). uv_triangles is always per
 * corner (3 nf), also when the input was per vertex. */
CF_API int32_t cf_mesh_uv_count(const cf_mesh *mesh);
CF_API const double *cf_mesh_uv(const cf_mesh *mesh);
CF_API const int32_t *cf_mesh_uv_triangles(const cf_mesh *mesh);

/* The context the mesh was created with. */
CF_API cf_context *cf_mesh_context(const cf_mesh *mesh);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_MESH_H */
