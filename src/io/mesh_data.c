/*
 * cf_mesh_data (what a mesh file holds), the builder the readers fill,
 * number parsing, format detection, and the reading entry points
 * cf_read_mesh_file / cf_read_mesh_memory / cf_load_mesh.
 */
#include "io/io_internal.h"
#include "io/text.h"

#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>

/* ---- growable buffer ---------------------------------------------------- */

void cfi_buf_init(cfi_buf *b, size_t elem)
{
    b->data = NULL;
    b->count = 0;
    b->cap = 0;
    b->elem = elem;
}

cf_status cfi_buf_reserve(cf_context *ctx, cfi_buf *b, size_t extra)
{
    if (b->cap - b->count >= extra) return CF_OK;
    size_t max_elems = SIZE_MAX / b->elem / 2;
    if (extra > max_elems || b->count > max_elems - extra)
        return cfi_error(ctx, CF_ERR_NOMEM, "out of memory: buffer of %zu + %zu elements", b->count, extra);
    size_t need = b->count + extra;
    size_t cap = b->cap ? b->cap : 16;
    while (cap < need) cap = cap > max_elems / 2 ? max_elems : cap * 2;
    void *p = cfi_realloc(ctx, b->data, b->cap * b->elem, cap * b->elem);
    if (!p) return cfi_error(ctx, CF_ERR_NOMEM, "out of memory growing a buffer to %zu x %zu bytes", cap, b->elem);
    b->data = p;
    b->cap = cap;
    return CF_OK;
}

void cfi_buf_free(cf_context *ctx, cfi_buf *b)
{
    if (b->data) cfi_free(ctx, b->data, b->cap * b->elem);
    b->data = NULL;
    b->count = 0;
    b->cap = 0;
}

/* Detaches the buffer's array resized to exactly count elements (NULL when
 * empty). On failure the buffer is unchanged. */
cf_status cfi_buf_take(cf_context *ctx, cfi_buf *b, void **out)
{
    *out = NULL;
    if (b->count == 0) {
        cfi_buf_free(ctx, b);
        return CF_OK;
    }
    if (b->count != b->cap) {
        void *p = cfi_realloc(ctx, b->data, b->cap * b->elem, b->count * b->elem);
        if (!p) return cfi_error(ctx, CF_ERR_NOMEM, "out of memory shrinking a buffer");
        b->data = p;
        b->cap = b->count;
    }
    *out = b->data;
    b->data = NULL;
    b->count = 0;
    b->cap = 0;
    return CF_OK;
}

/* ---- builder ------------------------------------------------------------- */

void cfi_builder_init(cfi_mesh_builder *b, cf_context *ctx)
{
    memset(b, 0, sizeof *b);
    b->ctx = ctx;
    cfi_buf_init(&b->positions, sizeof(double));
    cfi_buf_init(&b->triangles, sizeof(int32_t));
    cfi_buf_init(&b->uv, sizeof(double));
    cfi_buf_init(&b->uv_triangles, sizeof(int32_t));
    cfi_buf_init(&b->vprops, sizeof(cfi_prop));
    cfi_buf_init(&b->fprops, sizeof(cfi_prop));
}

static void free_props(cf_context *ctx, cfi_buf *props)
{
    cfi_prop *p = props->data;
    for (size_t i = 0; i < props->count; ++i) {
        cfi_free(ctx, p[i].name, p[i].name_bytes);
        cfi_buf_free(ctx, &p[i].values);
    }
    cfi_buf_free(ctx, props);
}

void cfi_builder_free(cfi_mesh_builder *b)
{
    cf_context *ctx = b->ctx;
    cfi_buf_free(ctx, &b->positions);
    cfi_buf_free(ctx, &b->triangles);
    cfi_buf_free(ctx, &b->uv);
    cfi_buf_free(ctx, &b->uv_triangles);
    free_props(ctx, &b->vprops);
    free_props(ctx, &b->fprops);
}

cf_status cfi_builder_add_prop(cfi_mesh_builder *b, bool face, const char *name, size_t len, int32_t *index)
{
    cf_context *ctx = b->ctx;
    cfi_buf *props = face ? &b->fprops : &b->vprops;
    if (len == 0 || memchr(name, '\0', len)) return cfi_error(ctx, CF_ERR_PARSE, "bad property name");
    if (props->count >= INT32_MAX) return cfi_error(ctx, CF_ERR_PARSE, "too many properties");
    if (cfi_buf_reserve(ctx, props, 1) != CF_OK) return CF_ERR_NOMEM;
    char *copy = cfi_malloc(ctx, len + 1);
    if (!copy) return cfi_error(ctx, CF_ERR_NOMEM, "out of memory copying a property name");
    memcpy(copy, name, len);
    copy[len] = '\0';
    cfi_prop *p = (cfi_prop *)props->data + props->count;
    p->name = copy;
    p->name_bytes = len + 1;
    cfi_buf_init(&p->values, sizeof(double));
    *index = (int32_t)props->count;
    props->count++;
    return CF_OK;
}

cf_status cfi_builder_add_colours(cfi_mesh_builder *b, bool face, int channels, const double *values, size_t n,
                                  cfi_colour_range range)
{
    static const char *const names[4] = {"red", "green", "blue", "alpha"};
    bool unit = range == CFI_COLOURS_UNIT;
    if (range == CFI_COLOURS_GUESS) {
        unit = true;
        for (size_t i = 0; i < n * (size_t)channels; ++i) unit = unit && values[i] >= 0.0 && values[i] <= 1.0;
    }
    for (int c = 0; c < channels; ++c) {
        int32_t index = 0;
        cf_status st = cfi_builder_add_prop(b, face, names[c], strlen(names[c]), &index);
        if (st != CF_OK) return st;
        cfi_buf *dst = &((cfi_prop *)(face ? b->fprops.data : b->vprops.data))[index].values;
        if (cfi_buf_reserve(b->ctx, dst, n) != CF_OK) return CF_ERR_NOMEM;
        double *out = dst->data;
        for (size_t i = 0; i < n; ++i) {
            double v = values[i * (size_t)channels + (size_t)c];
            if (unit) v = floor(255.0 * (v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v) + 0.5); /* a 0..1 colour past its range: its end */
            out[i] = v;
        }
        dst->count = n;
    }
    return CF_OK;
}

static cf_status take_props(cf_context *ctx, cfi_buf *props, int32_t *count_out, cf_mesh_property **out)
{
    if (props->count == 0) return CF_OK;
    cf_mesh_property *arr = CFI_ALLOC(ctx, cf_mesh_property, props->count);
    if (!arr) return CF_ERR_NOMEM;
    *out = arr;
    *count_out = (int32_t)props->count;
    cfi_prop *p = props->data;
    for (size_t i = 0; i < props->count; ++i) {
        void *values = NULL;
        if (cfi_buf_take(ctx, &p[i].values, &values) != CF_OK) return CF_ERR_NOMEM;
        arr[i].values = values;
        arr[i].name = p[i].name;
        p[i].name = NULL;
        p[i].name_bytes = 0;
    }
    return CF_OK;
}

cf_status cfi_builder_finish(cfi_mesh_builder *b, cf_mesh_data **out)
{
    cf_context *ctx = b->ctx;
    *out = NULL;
    cf_status st = CF_ERR_NOMEM;
    cf_mesh_data *d = CFI_ALLOC(ctx, cf_mesh_data, 1);
    if (!d) goto fail;
    d->context = ctx;
    int32_t nv = (int32_t)(b->positions.count / 3), nf = (int32_t)(b->triangles.count / 3);
    void *p = NULL;
    if (cfi_buf_take(ctx, &b->positions, &p) != CF_OK) goto fail;
    d->positions = p;
    d->vertex_count = nv;
    if (cfi_buf_take(ctx, &b->triangles, &p) != CF_OK) goto fail;
    d->triangles = p;
    d->face_count = nf;
    if (b->uv.count > 0) {
        int32_t nuv = (int32_t)(b->uv.count / 2);
        if (b->uv_per_corner) {
            if (cfi_buf_take(ctx, &b->uv_triangles, &p) != CF_OK) goto fail;
            d->uv_triangles = p;
        }
        if (cfi_buf_take(ctx, &b->uv, &p) != CF_OK) goto fail;
        d->uv = p;
        d->uv_count = nuv;
    }
    if (take_props(ctx, &b->vprops, &d->vertex_property_count, &d->vertex_properties) != CF_OK) goto fail;
    if (take_props(ctx, &b->fprops, &d->face_property_count, &d->face_properties) != CF_OK) goto fail;
    d->polygon_count = b->polygon_count;
    cfi_builder_free(b);
    *out = d;
    return CF_OK;
fail:
    cfi_builder_free(b);
    cf_mesh_data_destroy(&d);
    return st;
}

/* ---- cf_mesh_data ---------------------------------------------------------- */

static void destroy_props(cf_context *ctx, cf_mesh_property *props, int32_t count, int32_t n)
{
    if (!props) return;
    for (int32_t i = 0; i < count; ++i) {
        if (props[i].name) cfi_free(ctx, props[i].name, strlen(props[i].name) + 1);
        if (props[i].values) cfi_free(ctx, props[i].values, (size_t)n * sizeof(double));
    }
    cfi_free(ctx, props, (size_t)count * sizeof *props);
}

void cfi_free_strings(cf_context *ctx, char **strings, int32_t count)
{
    if (!strings) return;
    for (int32_t i = 0; i < count; ++i)
        if (strings[i]) cfi_free(ctx, strings[i], strlen(strings[i]) + 1);
    cfi_free(ctx, strings, (size_t)count * sizeof *strings);
}

void cf_mesh_data_destroy(cf_mesh_data **data)
{
    if (!data || !*data) return;
    cf_mesh_data *d = *data;
    cf_context *ctx = d->context;
    size_t nv = (size_t)d->vertex_count, nf = (size_t)d->face_count;
    cfi_free(ctx, d->positions, 3 * nv * sizeof(double));
    cfi_free(ctx, d->triangles, 3 * nf * sizeof(int32_t));
    cfi_free(ctx, d->uv, 2 * (size_t)d->uv_count * sizeof(double));
    cfi_free(ctx, d->uv_triangles, 3 * nf * sizeof(int32_t));
    destroy_props(ctx, d->vertex_properties, d->vertex_property_count, d->vertex_count);
    destroy_props(ctx, d->face_properties, d->face_property_count, d->face_count);
    cfi_free_strings(ctx, d->material_libraries, d->material_library_count);
    cfi_free_strings(ctx, d->material_names, d->material_count);
    cfi_free(ctx, d->face_materials, nf * sizeof(int32_t));
    cfi_free(ctx, d, sizeof *d);
    *data = NULL;
}

cf_status cf_mesh_data_desc(const cf_mesh_data *data, cf_mesh_desc *desc)
{
    if (!data || !desc) return CF_ERR_INVALID_ARG;
    memset(desc, 0, sizeof *desc);
    desc->vertex_count = data->vertex_count;
    desc->positions = data->positions;
    desc->face_count = data->face_count;
    desc->triangles = data->triangles;
    desc->uv_count = data->uv_count;
    desc->uv = data->uv;
    desc->uv_triangles = data->uv_triangles;
    return CF_OK;
}

static const cf_mesh_property *find_prop(const cf_mesh_property *props, int32_t count, const char *name)
{
    if (!props || !name) return NULL;
    for (int32_t i = 0; i < count; ++i)
        if (strcmp(props[i].name, name) == 0) return &props[i];
    return NULL;
}

const cf_mesh_property *cf_mesh_data_vertex_property(const cf_mesh_data *data, const char *name)
{
    return data ? find_prop(data->vertex_properties, data->vertex_property_count, name) : NULL;
}

const cf_mesh_property *cf_mesh_data_face_property(const cf_mesh_data *data, const char *name)
{
    return data ? find_prop(data->face_properties, data->face_property_count, name) : NULL;
}

/* ---- tokens ------------------------------------------------------------------ */

bool cfi_parse_double(const char *s, const char *e, double *v)
{
    if (s >= e) return false;
    char *end = NULL;
    *v = strtod(s, &end);
    return end == e;
}

bool cfi_parse_int(const char *s, const char *e, int64_t *v)
{
    bool neg = false;
    if (s < e && (*s == '-' || *s == '+')) neg = *s++ == '-';
    if (s >= e) return false;
    int64_t x = 0;
    for (; s < e; ++s) {
        if (*s < '0' || *s > '9') return false;
        /* saturate at 2^62 without ever overflowing */
        x = x <= ((int64_t)1 << 58) ? x * 10 + (*s - '0') : ((int64_t)1 << 62);
    }
    *v = neg ? -x : x;
    return true;
}

static char lower(char c) { return c >= 'A' && c <= 'Z' ? (char)(c - 'A' + 'a') : c; }

bool cfi_word_eq(const char *s, size_t n, const char *word)
{
    size_t i = 0;
    for (; i < n; ++i)
        if (word[i] == '\0' || lower(s[i]) != lower(word[i])) return false;
    return word[i] == '\0';
}

/* ---- entry points ------------------------------------------------------------ */

cf_status cf_mesh_format_from_path(cf_context *ctx, const char *path, cf_mesh_format *format)
{
    if (!path || !format) return cfi_error(ctx, CF_ERR_INVALID_ARG, "mesh path or format is NULL");
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    if (dot) {
        size_t n = strlen(dot + 1);
        if (cfi_word_eq(dot + 1, n, "obj")) *format = CF_FORMAT_OBJ;
        else if (cfi_word_eq(dot + 1, n, "off")) *format = CF_FORMAT_OFF;
        else if (cfi_word_eq(dot + 1, n, "ply")) *format = CF_FORMAT_PLY;
        else dot = NULL;
    }
    if (!dot)
        return cfi_error(ctx, CF_ERR_UNSUPPORTED, "%s: unknown mesh format (expected extension .obj, .off or .ply)",
                         path);
    return CF_OK;
}

static cf_status dispatch(cf_context *ctx, const char *buf, size_t size, cf_mesh_format format, const char *name,
                          cf_mesh_data **out)
{
    switch (format) {
    case CF_FORMAT_OBJ: return cfi_read_obj(ctx, buf, size, name, out);
    case CF_FORMAT_OFF: return cfi_read_off(ctx, buf, size, name, out);
    case CF_FORMAT_PLY: return cfi_read_ply(ctx, buf, size, name, out);
    case CF_FORMAT_AUTO: break;
    }
    return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: mesh format must be given (not CF_FORMAT_AUTO)", name);
}

cf_status cf_read_mesh_memory(cf_context *ctx, const void *bytes, size_t size, cf_mesh_format format,
                              const char *name, cf_mesh_data **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_read_mesh_memory: out is NULL");
    *out = NULL;
    if (!name) name = "<memory>";
    if (!bytes && size > 0) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: bytes is NULL", name);
    if (size == SIZE_MAX) return cfi_error(ctx, CF_ERR_NOMEM, "%s: input too large", name);
    char *buf = cfi_malloc(ctx, size + 1);
    if (!buf) return cfi_error(ctx, CF_ERR_NOMEM, "%s: out of memory copying %zu bytes", name, size);
    if (size) memcpy(buf, bytes, size);
    buf[size] = '\0';
    cf_status st = dispatch(ctx, buf, size, format, name, out);
    cfi_free(ctx, buf, size + 1);
    return st;
}

cf_status cf_read_mesh_file(cf_context *ctx, const char *path, cf_mesh_data **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out || !path) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_read_mesh_file: path or out is NULL");
    *out = NULL;
    cf_mesh_format format;
    cf_status st = cf_mesh_format_from_path(ctx, path, &format);
    if (st != CF_OK) return st;
    char *buf = NULL;
    size_t size = 0, cap = 0;
    st = cfi_read_whole_file(ctx, path, &buf, &size, &cap);
    if (st != CF_OK) return st;
    st = dispatch(ctx, buf, size, format, path, out);
    cfi_free(ctx, buf, cap);
    return st;
}

cf_status cf_load_mesh(cf_context *ctx, const char *path, cf_mesh **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out || !path) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_load_mesh: path or out is NULL");
    *out = NULL;
    cf_mesh_data *data = NULL;
    cf_status st = cf_read_mesh_file(ctx, path, &data);
    if (st != CF_OK) return st;
    cf_mesh_desc desc;
    cf_mesh_data_desc(data, &desc);
    st = cf_mesh_create(ctx, &desc, out);
    /* The mesh core names the element; the file name makes the message
     * usable from the command line. */
    if (st != CF_OK) cfi_error_prefix(ctx, "%s", path);
    cf_mesh_data_destroy(&data);
    return st;
}
