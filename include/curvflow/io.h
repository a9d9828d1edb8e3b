/*
 * Mesh file I/O: OBJ, OFF and PLY readers and writers, atomic output.
 *
 *   cf_mesh *mesh;
 *   if (cf_load_mesh(ctx, "spot.obj", &mesh) != CF_OK)
 *       fprintf(stderr, "%s\n", cf_context_message(ctx));   // "spot.obj: line 12: ..."
 *   cf_field q = {"quality", CF_FIELD_FACE, per_face_values};
 *   cf_write_mesh_file(ctx, "out.ply", mesh, new_positions, &q, 1);
 *
 * Readers fill a cf_mesh_data (what the file holds, unvalidated apart from
 * syntax, index ranges and finite coordinates); cf_load_mesh also builds a
 * validated cf_mesh. Messages name the file (the path as given) and the
 * line (text formats) or element index (binary PLY), e.g.
 * "truncated_spot.obj: line 7063: face has 2 vertices (file ends inside a
 * face line: truncated?)".
 *
 * Numbers are parsed and printed in the "C" locale (the library never calls
 * setlocale). ASCII output uses %.17g, so positions round-trip bit-exactly.
 *
 * Writers are atomic: the file is written to a temporary file in the same
 * directory, flushed and fsync'ed, then renamed over the target. On any
 * failure the temporary file is removed and an existing target is left
 * untouched.
 */
#ifndef CURVFLOW_IO_H
#define CURVFLOW_IO_H

#include "curvflow/curvflow.h"
#include "curvflow/mesh.h"

#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cf_mesh_format {
    CF_FORMAT_AUTO = 0, /* from the file name's extension (.obj .off .ply, case-insensitive) */
    CF_FORMAT_OBJ = 1,
    CF_FORMAT_OFF = 2,
    CF_FORMAT_PLY = 3
} cf_mesh_format;

/* Format of a path from its extension; CF_ERR_UNSUPPORTED (with a message)
 * for an unknown extension. */
CF_API cf_status cf_mesh_format_from_path(cf_context *ctx, const char *path, cf_mesh_format *format);

/* A named per-vertex or per-face array of doubles read from a file (PLY
 * properties other than x, y, z, u, v and the face index list). */
typedef struct cf_mesh_property {
    char *name;      /* NUL-terminated, owned by the cf_mesh_data */
    double *values;  /* vertex_count or face_count values */
} cf_mesh_property;

/* What a mesh file holds. Created by the readers, freed with
 * cf_mesh_data_destroy; every array is owned by it. Faces are triangles:
 * polygons were fan-triangulated (v0, v_i, v_i+1), and per-face properties
 * of a polygon are repeated on each of its triangles. */
typedef struct cf_mesh_data {
    int32_t vertex_count;
    double *positions;          /* 3 * vertex_count, xyz */
    int32_t face_count;         /* triangles */
    int32_t *triangles;         /* 3 * face_count, 0-based */
    /* Texture coordinates (uv_count == 0 and NULL when absent). Per vertex
     * when uv_triangles is NULL (uv_count == vertex_count, PLY u,v), else per
     * corner: uv_triangles holds 3 * face_count indices into uv (OBJ vt,
     * PLY face texcoord lists). */
    int32_t uv_count;
    double *uv;                 /* 2 * uv_count */
    int32_t *uv_triangles;      /* 3 * face_count or NULL */
    int32_t vertex_property_count;
    cf_mesh_property *vertex_properties;
    int32_t face_property_count;
    cf_mesh_property *face_properties;
    /* Faces of the file with more than 3 vertices (each was fan-triangulated;
     * a warning was logged). */
    int32_t polygon_count;
    cf_context *context;        /* owner, used by cf_mesh_data_destroy */
    /* OBJ materials (session 29): the text after each `mtllib` in file
     * order, the `usemtl` names in order of first use, and each triangle's
     * material (an index into material_names, -1 before the first usemtl;
     * NULL when the file has no usemtl). 0 / NULL for other formats. */
    int32_t material_library_count;
    char **material_libraries;
    int32_t material_count;
    char **material_names;
    int32_t *face_materials;
} cf_mesh_data;

/* Frees the data; accepts NULL and *data == NULL; sets *data to NULL. */
CF_API void cf_mesh_data_destroy(cf_mesh_data **data);

/* Fills a mesh description that points into `data` (no copy): positions,
 * triangles and uv. CF_ERR_INVALID_ARG for NULL arguments. */
CF_API cf_status cf_mesh_data_desc(const cf_mesh_data *data, cf_mesh_desc *desc);

/* Property of the given name, or NULL. */
CF_API const cf_mesh_property *cf_mesh_data_vertex_property(const cf_mesh_data *data, const char *name);
CF_API const cf_mesh_property *cf_mesh_data_face_property(const cf_mesh_data *data, const char *name);

/* What cf_mesh_data_weld found and did. */
typedef struct cf_weld_report {
    int32_t candidates;     /* boundary vertices at exactly the position of another boundary vertex */
    int32_t groups;         /* positions they share */
    int32_t welded;         /* 1: the data was changed */
    int32_t removed;        /* vertices joined onto an earlier one (0 unless welded) */
    int32_t vertices;       /* vertex count of the data afterwards */
    int32_t differing_properties; /* removed vertices whose vertex properties differed from the kept copy's */
    char refused[256];      /* why candidates were left apart ("" if welded or none), e.g.
                             * "after welding, vertex 4 is non-manifold (...)" */
} cf_weld_report;

/* Joins the seams of a file: every boundary vertex (on an edge of one face)
 * that has exactly, bit for bit, the position of another boundary vertex is
 * replaced by the one of lowest index, and the vertices are renumbered in
 * their order (docs/io.md, "Seams"). Exporters split vertices where a
 * per-vertex attribute changes (texture seams, hard normals, unshared
 * triangles), and a flow would treat such cuts as free boundaries. Per-vertex
 * texture coordinates become per-corner ones (each corner keeps its own);
 * a vertex property keeps the value of the kept copy. Welds only if the
 * result is a valid mesh (cf_mesh_validate): otherwise nothing changes and
 * report->refused says why. new_index (may be NULL; vertex_count entries,
 * the count before) receives the new index of every vertex. CF_OK whether
 * or not it welded; CF_ERR_NOMEM leaves the data unchanged. */
CF_API cf_status cf_mesh_data_weld(cf_context *ctx, cf_mesh_data *data, int32_t *new_index,
                                   cf_weld_report *report);

/* The same weld for arrays (a mesh not read from a file, e.g. the Python
 * package's weld()): fills new_index (vertex_count entries) with the new
 * index of every vertex, the identity when nothing is welded. A vertex v
 * is kept when new_index[v] equals the number of vertices kept before it;
 * the welded triangles are new_index[triangles]. The report as above
 * (differing_properties 0: arrays carry no properties). CF_ERR_INDEX_RANGE
 * for an index outside [0, vertex_count). */
CF_API cf_status cf_weld_map(cf_context *ctx, int32_t vertex_count, const double *positions, int32_t face_count,
                             const int32_t *triangles, int32_t *new_index, cf_weld_report *report);

/* Drops the vertices that no face uses (left by scanners and editors: a
 * mesh with one is refused) and renumbers the others in their order
 * (docs/io.md, "Unused vertices"); per-vertex texture coordinates and vertex
 * properties follow. *dropped: how many (0: nothing changed; also for data
 * without faces, which the mesh check refuses as empty). new_index (may be
 * NULL; vertex_count entries, the count before) receives the new index of
 * every vertex, -1 for a dropped one. CF_ERR_INDEX_RANGE for a face index
 * outside [0, vertex_count); CF_ERR_NOMEM leaves the data unchanged. */
CF_API cf_status cf_mesh_data_drop_unreferenced(cf_context *ctx, cf_mesh_data *data, int32_t *new_index,
                                                int32_t *dropped);

/* Reads a mesh file; the format comes from the extension. Statuses:
 * CF_ERR_IO (cannot open/read), CF_ERR_PARSE (malformed content),
 * CF_ERR_TRUNCATED (file ends early), CF_ERR_INDEX_RANGE (a face index
 * that is 0, negative beyond the start or past the vertices defined),
 * CF_ERR_NONFINITE (NaN/Inf coordinate), CF_ERR_UNSUPPORTED (extension,
 * PLY variant), CF_ERR_NOMEM, CF_ERR_INVALID_ARG. *out is NULL on failure. */
CF_API cf_status cf_read_mesh_file(cf_context *ctx, const char *path, cf_mesh_data **out);

/* Reads a mesh from memory (`bytes` need not be NUL-terminated). `format`
 * must not be CF_FORMAT_AUTO. `name` is used in messages (NULL: "<memory>").
 * Same statuses as cf_read_mesh_file. */
CF_API cf_status cf_read_mesh_memory(cf_context *ctx, const void *bytes, size_t size, cf_mesh_format format,
                                     const char *name, cf_mesh_data **out);

/* Reads a file and builds a validated mesh (positions, triangles, uv).
 * Validation failures keep the mesh core's status (CF_ERR_NONMANIFOLD_EDGE,
 * CF_ERR_ORIENTATION, ...) with the message prefixed by the path,
 * e.g. "beetle.obj: face 12: edge (3, 9) is shared by 3 faces". */
CF_API cf_status cf_load_mesh(cf_context *ctx, const char *path, cf_mesh **out);

/* The check every text input of the library gets (meshes, polylines,
 * per-vertex values), for readers outside io (the curve flow's CSV / SVG):
 * *start (may be NULL) receives the offset of the text after a UTF-8
 * byte-order mark at the start (3, else 0); a NUL byte in the `size` bytes
 * is CF_ERR_PARSE "<name>: line L: NUL byte at offset K (not a text file?)",
 * K counted from bytes[0]. `name` may be NULL ("<memory>"). */
CF_API cf_status cf_text_check(cf_context *ctx, const void *bytes, size_t size, const char *name, size_t *start);

/* ---- per-vertex values from text files ------------------------------------
 * The inputs of `curvflow spin --rho FILE` and `curvflow flow
 * --boundary-targets FILE`. Lines may have any length; a UTF-8 byte-order
 * mark at the start is skipped; '#' starts a comment that runs to the end of
 * its line; a NUL byte is refused (CF_ERR_PARSE naming its offset). Messages
 * name the file and line: "rho.txt: line 3: bad number 'x'". The _memory
 * variants read `size` bytes (need not be NUL-terminated; `name`, may be
 * NULL, stands for the file); the _file variants add CF_ERR_IO. */

/* One number per vertex, in vertex order, separated by whitespace, commas
 * or line breaks (one per line, all on one comma-separated line, or any
 * mix). `out` (caller-allocated) receives vertex_count doubles. Statuses:
 * CF_ERR_PARSE (a token that is not a number; more or fewer values than
 * vertex_count), CF_ERR_NONFINITE (nan, inf, or a number that overflows),
 * CF_ERR_NOMEM, CF_ERR_INVALID_ARG. */
CF_API cf_status cf_read_vertex_scalars_file(cf_context *ctx, const char *path, int32_t vertex_count, double *out);
CF_API cf_status cf_read_vertex_scalars_memory(cf_context *ctx, const void *bytes, size_t size, const char *name,
                                               int32_t vertex_count, double *out);

/* A direction per chosen vertex: one line "VERTEX X Y Z" (0-based vertex
 * index, whitespace-separated) for each vertex with required[v] != 0
 * (`required`: vertex_count bytes; NULL = every vertex), each exactly once;
 * a line for any other vertex is an error that calls it "not a
 * <required_name> of the mesh" (e.g. "boundary vertex"; NULL: "vertex").
 * A direction must be finite, within |c| <= CF_MAX_COORDINATE, and not zero
 * (largest component >= CF_MIN_EDGE_LENGTH): it gets normalised. `out`
 * (caller-allocated) receives 3 vertex_count doubles, xyz, zero for
 * vertices not listed. Statuses: CF_ERR_PARSE (malformed line, vertex not
 * required, listed twice or missing, zero direction), CF_ERR_INDEX_RANGE
 * (vertex index outside [0, vertex_count), quoted as written),
 * CF_ERR_NONFINITE (NaN, Inf, beyond CF_MAX_COORDINATE), CF_ERR_NOMEM,
 * CF_ERR_INVALID_ARG. */
CF_API cf_status cf_read_vertex_directions_file(cf_context *ctx, const char *path, int32_t vertex_count,
                                                const uint8_t *required, const char *required_name, double *out);
CF_API cf_status cf_read_vertex_directions_memory(cf_context *ctx, const void *bytes, size_t size, const char *name,
                                                  int32_t vertex_count, const uint8_t *required,
                                                  const char *required_name, double *out);

/* A named scalar field attached to the output. */
typedef enum cf_field_location {
    CF_FIELD_VERTEX = 0, /* vertex_count values */
    CF_FIELD_FACE = 1    /* face_count values */
} cf_field_location;

typedef struct cf_field {
    const char *name;            /* [A-Za-z0-9_.-]+, unique per location, not a reserved name (x y z u v
                                    vertex_indices texcoord index) */
    cf_field_location location;
    const double *values;
} cf_field;

typedef enum cf_ply_encoding {
    CF_PLY_BINARY_LITTLE_ENDIAN = 0, /* default */
    CF_PLY_BINARY_BIG_ENDIAN = 1,
    CF_PLY_ASCII = 2
} cf_ply_encoding;

typedef struct cf_write_options {
    cf_mesh_format format;        /* CF_FORMAT_AUTO: from the extension */
    cf_ply_encoding ply_encoding; /* PLY only */
    int32_t write_uv;             /* write the mesh's texture coordinates if it has any (default 1) */
    /* OBJ only (default none): `mtllib` lines, and `usemtl` before each run
     * of faces of one material (material_names[face_materials[f]]; -1: the
     * faces before the first usemtl). Names: no line breaks. */
    int32_t material_library_count;
    const char *const *material_libraries;
    int32_t material_count;
    const char *const *material_names;
    const int32_t *face_materials;
} cf_write_options;

CF_API void cf_write_options_default(cf_write_options *options);

/* Writes `mesh` with `positions` (3 nv; NULL = the mesh's rest positions)
 * and `field_count` fields, atomically. Vertex order and count are kept.
 *  - PLY: x y z (double) [u v (double) when the uv is per vertex] + vertex
 *    fields as double properties; faces as `list uchar int vertex_indices`
 *    [+ `list uchar double texcoord` (u0 v0 u1 v1 u2 v2) when uv is per
 *    corner] + face fields as double properties.
 *  - OBJ: v (%.17g), vt and f v/vt when the mesh has uv; fields go to side
 *    CSV files next to it: "<stem>.vertex.csv" and "<stem>.face.csv"
 *    (stem = path without its extension), header "index,<name>,...", one
 *    row per element with values in %.17g. Each CSV is written atomically
 *    before the OBJ. Vertex fields red, green and blue with values in
 *    [0, 255] go on the v lines instead, as `v x y z r g b` in [0, 1].
 *  - OFF: positions and triangles, and colours only (cf_off_fields_writable):
 *    vertex fields red green blue [alpha] as `COFF` (x y z r g b a), face
 *    fields red green blue [alpha] after each face's indices, as whole
 *    numbers 0..255 (rounded; alpha 255 when absent); any other field is
 *    rejected (CF_ERR_UNSUPPORTED).
 * Statuses: CF_ERR_INVALID_ARG (NULL, bad field), CF_ERR_NONFINITE
 * (non-finite position), CF_ERR_IO (with the path and the system's reason),
 * CF_ERR_UNSUPPORTED, CF_ERR_NOMEM. */
CF_API cf_status cf_write_mesh_file(cf_context *ctx, const char *path, const cf_mesh *mesh,
                                    const double *positions, const cf_field *fields, int32_t field_count);

/* 1 when `name` may name a written field: 1-128 characters of
 * [A-Za-z0-9_.-], not one the writers use themselves (x y z u v
 * vertex_indices texcoord index); 0 otherwise (also for NULL). The rule
 * cf_write_mesh_file checks, for callers that pass fields on from a file. */
CF_API int32_t cf_field_name_valid(const char *name);

/* Which of `fields` an OFF file holds: the colour channels red, green,
 * blue [, alpha] of vertices or of faces, each with values in [0, 255], when
 * red, green and blue of that location are all given. Sets writable[i] to
 * 1 or 0 (writable may be NULL) and returns the number of 1s. For callers
 * that pass a file's properties on to an OFF output (the rest would be
 * refused). */
CF_API int32_t cf_off_fields_writable(const cf_field *fields, int32_t field_count, int32_t vertex_count,
                                      int32_t face_count, uint8_t *writable);

/* As cf_write_mesh_file with options (NULL = defaults). */
CF_API cf_status cf_write_mesh_file_ex(cf_context *ctx, const char *path, const cf_mesh *mesh,
                                       const double *positions, const cf_field *fields, int32_t field_count,
                                       const cf_write_options *options);

/* Writes `size` bytes of `text` to `path` atomically (temp file + fsync +
 * rename). CF_ERR_IO names the path and the reason. */
CF_API cf_status cf_write_text_file_atomic(cf_context *ctx, const char *path, const char *text, size_t size);

/* ---- atomic output beyond whole buffers; temporary files ----------------
 * Every writer above (and cf_write_png, cf_curve_write) writes a target that
 * is a symbolic link through to the link's final target (the link stays a
 * link). The temporary file is ".<name>.tmp-<pid>-<n>" next to that target. */

/* A file written atomically as a stream (e.g. a log written while a run
 * lasts): write to cf_atomic_writer_stream(); the text goes to the
 * temporary file, and the target appears (or is replaced) only at commit.
 * Statuses as cf_write_text_file_atomic; *out is NULL on failure. */
typedef struct cf_atomic_writer cf_atomic_writer;
CF_API cf_status cf_atomic_writer_open(cf_context *ctx, const char *path, cf_atomic_writer **out);
/* The stream to write to (NULL for a NULL writer). */
CF_API FILE *cf_atomic_writer_stream(cf_atomic_writer *writer);
/* Checks for write errors, flushes, fsyncs and renames over the target;
 * on failure removes the temporary file (CF_ERR_IO naming the path and the
 * reason). Always frees the writer and sets *writer to NULL. */
CF_API cf_status cf_atomic_writer_commit(cf_atomic_writer **writer);
/* Removes the temporary file, leaves the target untouched, frees the
 * writer; accepts NULL and *writer == NULL. */
CF_API void cf_atomic_writer_abort(cf_atomic_writer **writer);

/* Removes the temporary files of the atomic writes this process has in
 * progress (every thread). Async-signal-safe: meant for a SIGINT / SIGTERM /
 * SIGHUP handler that then ends the process (re-raising the signal); the
 * targets stay untouched, and the interrupted writes cannot be committed.
 * At most 16 writes in progress at once are tracked. */
CF_API void cf_atomic_remove_pending(void);

/* Removes the temporary files that atomic writes of `path` left behind in
 * processes that no longer run (killed with SIGKILL, power loss): the files
 * ".<name>.tmp-<pid>-<n>" next to path's target whose pid is not a running
 * process. Files of running processes (and of this one) are kept. Best
 * effort: a folder that cannot be listed removes nothing. *removed (may be
 * NULL) receives the count. Statuses: CF_OK, CF_ERR_INVALID_ARG, CF_ERR_IO
 * (cycle of symbolic links), CF_ERR_NOMEM. */
CF_API cf_status cf_atomic_remove_stale(cf_context *ctx, const char *path, int32_t *removed);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_IO_H */
