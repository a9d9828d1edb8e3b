/*
 * Internal helpers shared by the mesh readers: a growable buffer, a mesh
 * builder that collects what a file holds and turns it into a cf_mesh_data,
 * number parsing, and the per-format entry points.
 *
 * Every reader gets the whole file as one buffer followed by a NUL byte
 * (so strtod can never run past the end) and a name for messages.
 */
#ifndef CF_IO_IO_INTERNAL_H
#define CF_IO_IO_INTERNAL_H

#include "core/core.h"
#include "curvflow/io.h"

/* Growable array of `elem`-byte elements allocated through the context. */
typedef struct cfi_buf {
    void *data;
    size_t count;  /* elements in use */
    size_t cap;    /* elements allocated */
    size_t elem;   /* element size in bytes */
} cfi_buf;

void cfi_buf_init(cfi_buf *b, size_t elem);
/* Makes room for `extra` more elements (geometric growth). CF_ERR_NOMEM on failure. */
cf_status cfi_buf_reserve(cf_context *ctx, cfi_buf *b, size_t extra);
void cfi_buf_free(cf_context *ctx, cfi_buf *b);
/* Hands over the buffer's elements as an array of exactly its count (NULL
 * when empty) and leaves the buffer empty. CF_ERR_NOMEM on failure. */
cf_status cfi_buf_take(cf_context *ctx, cfi_buf *b, void **out);
/* Frees `count` NUL-terminated strings and their array (each allocated
 * through the context at strlen + 1 bytes); NULL is fine. */
void cfi_free_strings(cf_context *ctx, char **strings, int32_t count);

/* One named property being collected (values: double). */
typedef struct cfi_prop {
    char *name;
    size_t name_bytes;
    cfi_buf values;
} cfi_prop;

typedef struct cfi_mesh_builder {
    cf_context *ctx;
    cfi_buf positions;     /* double, 3 per vertex */
    cfi_buf triangles;     /* int32_t, 3 per triangle */
    cfi_buf uv;            /* double, 2 per uv */
    cfi_buf uv_triangles;  /* int32_t, 3 per triangle (per-corner uv) */
    bool uv_per_corner;    /* else uv (if any) is per vertex */
    cfi_buf vprops;        /* cfi_prop */
    cfi_buf fprops;        /* cfi_prop */
    int32_t polygon_count;
} cfi_mesh_builder;

void cfi_builder_init(cfi_mesh_builder *b, cf_context *ctx);
void cfi_builder_free(cfi_mesh_builder *b);
/* Adds a property with a copy of `name` (len bytes, not NUL-terminated);
 * *index receives its position. */
cf_status cfi_builder_add_prop(cfi_mesh_builder *b, bool face, const char *name, size_t len, int32_t *index);
/* How a file wrote its colour values. */
typedef enum cfi_colour_range {
    CFI_COLOURS_UNIT,  /* 0..1 (OFF colours written as floats; values past the range clamped) */
    CFI_COLOURS_BYTES, /* 0..255 (OFF colours written as integers) */
    CFI_COLOURS_GUESS  /* 0..1 when every value lies in [0, 1], else 0..255 (OBJ's `v x y z r g b`) */
} cfi_colour_range;
/* Adds the colour channels red, green, blue [, alpha] (channels = 3 or 4)
 * as properties, from `values`: n elements' values interleaved, as the file
 * wrote them. Values in 0..1 are scaled to [0, 255] and rounded: the PLY
 * convention, which the writers and viewers use; 0..255 values are kept as
 * written. */
cf_status cfi_builder_add_colours(cfi_mesh_builder *b, bool face, int channels, const double *values, size_t n,
                                  cfi_colour_range range);
/* Moves the collected arrays into a new cf_mesh_data (exact-size copies)
 * and frees the builder. On failure the builder is freed too. */
cf_status cfi_builder_finish(cfi_mesh_builder *b, cf_mesh_data **out);

static inline cf_status cfi_push_double(cf_context *ctx, cfi_buf *b, double v)
{
    if (b->count == b->cap && cfi_buf_reserve(ctx, b, 1) != CF_OK) return CF_ERR_NOMEM;
    ((double *)b->data)[b->count++] = v;
    return CF_OK;
}

static inline cf_status cfi_push_int3(cf_context *ctx, cfi_buf *b, int32_t a, int32_t c, int32_t d)
{
    if (b->count + 3 > b->cap && cfi_buf_reserve(ctx, b, 3) != CF_OK) return CF_ERR_NOMEM;
    int32_t *p = (int32_t *)b->data + b->count;
    p[0] = a;
    p[1] = c;
    p[2] = d;
    b->count += 3;
    return CF_OK;
}

/* Largest vertex/face count accepted: 3 * count must fit in int32_t so
 * that flat index arrays stay addressable with int32_t. */
#define CFI_MAX_ELEMENTS (INT32_MAX / 3)

static inline bool cfi_is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* Parses [s, e) as a double with strtod; false unless the whole token is
 * consumed. s[e - s] must be a character that ends a number (space, newline
 * or the buffer's NUL). */
bool cfi_parse_double(const char *s, const char *e, double *v);
/* Parses [s, e) as a decimal integer with optional sign; false on bad
 * syntax. Magnitudes beyond 2^62 saturate (callers range-check). */
bool cfi_parse_int(const char *s, const char *e, int64_t *v);

/* Case-insensitive ASCII comparison of [s, s+n) with a NUL-terminated word. */
bool cfi_word_eq(const char *s, size_t n, const char *word);

/* Format readers: buf[size] == '\0' is guaranteed. */
cf_status cfi_read_obj(cf_context *ctx, const char *buf, size_t size, const char *name, cf_mesh_data **out);
cf_status cfi_read_off(cf_context *ctx, const char *buf, size_t size, const char *name, cf_mesh_data **out);
cf_status cfi_read_ply(cf_context *ctx, const char *buf, size_t size, const char *name, cf_mesh_data **out);

#endif /* CF_IO_IO_INTERNAL_H */
