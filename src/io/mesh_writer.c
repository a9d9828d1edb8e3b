/*
 * Mesh writers: PLY (binary little/big endian or ASCII, fields as
 * properties), OBJ (v, vt, f v/vt; fields in side CSV files) and OFF.
 * Every file goes through the atomic writer (temp file + fsync + rename).
 * Vertex order and count are those of the mesh; ASCII numbers use %.17g so
 * that reading them back gives the same doubles.
 */
#include "io/atomic_file.h"
#include "io/io_internal.h"

#include <math.h>
#include <string.h>

void cf_write_options_default(cf_write_options *options)
{
    if (!options) return;
    memset(options, 0, sizeof *options);
    options->format = CF_FORMAT_AUTO;
    options->ply_encoding = CF_PLY_BINARY_LITTLE_ENDIAN;
    options->write_uv = 1;
}

/* ---- argument checks ------------------------------------------------------ */

int32_t cf_field_name_valid(const char *name)
{
    static const char *const reserved[] = {"x", "y", "z", "u", "v", "vertex_indices", "texcoord", "index"};
    if (!name) return 0;
    size_t n = strlen(name);
    if (n == 0 || n > 128) return false;
    for (size_t i = 0; i < n; ++i) {
        char c = name[i];
        bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                  c == '.' || c == '-';
        if (!ok) return false;
    }
    for (size_t i = 0; i < sizeof reserved / sizeof reserved[0]; ++i)
        if (strcmp(name, reserved[i]) == 0) return false;
    return true;
}

static cf_status check_fields(cf_context *ctx, const char *path, const cf_field *fields, int32_t count)
{
    if (count < 0 || (count > 0 && !fields))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: bad field list (%d fields)", path, count);
    for (int32_t i = 0; i < count; ++i) {
        const cf_field *f = &fields[i];
        if (!cf_field_name_valid(f->name))
            return cfi_error(ctx, CF_ERR_INVALID_ARG,
                             "%s: field %d: name '%s' must be 1-128 characters of [A-Za-z0-9_.-] and not one of "
                             "x y z u v vertex_indices texcoord index",
                             path, i, f->name ? f->name : "(null)");
        if (f->location != CF_FIELD_VERTEX && f->location != CF_FIELD_FACE)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: field '%s': bad location %d", path, f->name,
                             (int)f->location);
        if (!f->values) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: field '%s' has no values", path, f->name);
        for (int32_t j = 0; j < i; ++j)
            if (fields[j].location == f->location && strcmp(fields[j].name, f->name) == 0)
                return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: field '%s' given twice", path, f->name);
    }
    return CF_OK;
}

/* A material name or library: non-empty, on one line. */
static bool material_text_ok(const char *t) { return t && *t && !strpbrk(t, "\r\n"); }

static cf_status check_materials(cf_context *ctx, const char *path, const cf_write_options *o, int32_t nf)
{
    if (o->material_library_count < 0 || (o->material_library_count > 0 && !o->material_libraries) ||
        o->material_count < 0 || (o->material_count > 0 && !o->material_names) ||
        (o->face_materials && o->material_count == 0))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: bad material lists", path);
    for (int32_t l = 0; l < o->material_library_count; ++l)
        if (!material_text_ok(o->material_libraries[l]))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: material library %d is empty or holds a line break", path,
                             l);
    for (int32_t m = 0; m < o->material_count; ++m)
        if (!material_text_ok(o->material_names[m]))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: material %d's name is empty or holds a line break", path, m);
    for (int32_t f = 0; o->face_materials && f < nf; ++f)
        if (o->face_materials[f] < -1 || o->face_materials[f] >= o->material_count)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: face %d: material %d out of range (%d materials)", path, f,
                             o->face_materials[f], o->material_count);
    return CF_OK;
}

/* ---- texture coordinate layout ------------------------------------------------ */

typedef enum uv_layout { UV_NONE = 0, UV_PER_VERTEX = 1, UV_PER_CORNER = 2 } uv_layout;

/* Per vertex when every corner of a vertex uses the same uv entry (then
 * map[v] is that entry); per corner otherwise. map has nv entries. */
static uv_layout find_uv_layout(const cf_mesh *mesh, int32_t *map)
{
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    const int32_t *tri = cf_mesh_triangles(mesh), *uvt = cf_mesh_uv_triangles(mesh);
    for (int32_t v = 0; v < nv; ++v) map[v] = -1;
    for (int64_t c = 0; c < 3 * (int64_t)nf; ++c) {
        int32_t v = tri[c];
        if (map[v] < 0) map[v] = uvt[c];
        else if (map[v] != uvt[c]) return UV_PER_CORNER;
    }
    for (int32_t v = 0; v < nv; ++v)
        if (map[v] < 0) return UV_PER_CORNER; /* unreferenced vertex: no uv for it */
    return UV_PER_VERTEX;
}

/* ---- PLY -------------------------------------------------------------------- */

static unsigned char *put_f64(unsigned char *p, double v, bool big)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    for (int i = 0; i < 8; ++i) p[big ? 7 - i : i] = (unsigned char)(u >> (8 * i));
    return p + 8;
}

static unsigned char *put_i32(unsigned char *p, int32_t v, bool big)
{
    uint32_t u = (uint32_t)v;
    for (int i = 0; i < 4; ++i) p[big ? 3 - i : i] = (unsigned char)(u >> (8 * i));
    return p + 4;
}

typedef struct write_job {
    cf_context *ctx;
    const char *path;
    const cf_mesh *mesh;
    const double *x;
    const cf_field *fields;
    int32_t field_count;
    int32_t nvf, nff;     /* vertex / face field counts */
    bool use_uv;
    uint8_t *uchar;       /* PLY: per field, 1 when it is written as uchar (a colour channel) */
    const cf_write_options *opts;
    int32_t obj_rgb[3];   /* OBJ: the fields written as `v x y z r g b` (red, green, blue), or -1 */
} write_job;

/* A colour channel: named red, green, blue or alpha, and every value a
 * whole number in [0, 255]. PLY viewers read colours from uchar
 * properties, so these are written as uchar (the values read back the
 * same); every other field is written as double. */
static bool is_colour_channel(const cf_field *f, int32_t n)
{
    static const char *const names[] = {"red", "green", "blue", "alpha"};
    bool named = false;
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) named = named || strcmp(f->name, names[i]) == 0;
    for (int32_t k = 0; named && k < n; ++k) {
        double v = f->values[k];
        named = v >= 0.0 && v <= 255.0 && v == floor(v);
    }
    return named;
}

static const char *ply_type(const write_job *j, int32_t i) { return j->uchar && j->uchar[i] ? "uchar" : "double"; }

/* A field's value in its PLY type (ply_type). */
static unsigned char *put_field(const write_job *j, int32_t i, unsigned char *p, double v, bool big)
{
    if (j->uchar && j->uchar[i]) {
        *p++ = (unsigned char)v;
        return p;
    }
    return put_f64(p, v, big);
}

static cf_status write_ply_body(write_job *j, FILE *fp, cf_ply_encoding enc, int32_t *map)
{
    cf_context *ctx = j->ctx;
    const cf_mesh *mesh = j->mesh;
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    const int32_t *tri = cf_mesh_triangles(mesh);
    const double *uv = cf_mesh_uv(mesh);
    const int32_t *uvt = cf_mesh_uv_triangles(mesh);
    uv_layout layout = j->use_uv ? find_uv_layout(mesh, map) : UV_NONE;
    fprintf(fp, "ply\nformat %s 1.0\ncomment written by curvflow %s\nelement vertex %d\n",
            enc == CF_PLY_ASCII ? "ascii"
            : enc == CF_PLY_BINARY_BIG_ENDIAN ? "binary_big_endian"
                                              : "binary_little_endian",
            cf_version_string(), nv);
    fputs("property double x\nproperty double y\nproperty double z\n", fp);
    if (layout == UV_PER_VERTEX) fputs("property double u\nproperty double v\n", fp);
    for (int32_t i = 0; i < j->field_count; ++i)
        if (j->fields[i].location == CF_FIELD_VERTEX)
            fprintf(fp, "property %s %s\n", ply_type(j, i), j->fields[i].name);
    fprintf(fp, "element face %d\nproperty list uchar int vertex_indices\n", nf);
    if (layout == UV_PER_CORNER) fputs("property list uchar double texcoord\n", fp);
    for (int32_t i = 0; i < j->field_count; ++i)
        if (j->fields[i].location == CF_FIELD_FACE) fprintf(fp, "property %s %s\n", ply_type(j, i), j->fields[i].name);
    fputs("end_header\n", fp);

    if (enc == CF_PLY_ASCII) {
        for (int32_t v = 0; v < nv; ++v) {
            fprintf(fp, "%.17g %.17g %.17g", j->x[3 * v], j->x[3 * v + 1], j->x[3 * v + 2]);
            if (layout == UV_PER_VERTEX) fprintf(fp, " %.17g %.17g", uv[2 * map[v]], uv[2 * map[v] + 1]);
            for (int32_t i = 0; i < j->field_count; ++i)
                if (j->fields[i].location == CF_FIELD_VERTEX) fprintf(fp, " %.17g", j->fields[i].values[v]);
            fputc('\n', fp);
        }
        for (int32_t f = 0; f < nf; ++f) {
            fprintf(fp, "3 %d %d %d", tri[3 * f], tri[3 * f + 1], tri[3 * f + 2]);
            if (layout == UV_PER_CORNER) {
                fputs(" 6", fp);
                for (int k = 0; k < 3; ++k) fprintf(fp, " %.17g %.17g", uv[2 * uvt[3 * f + k]], uv[2 * uvt[3 * f + k] + 1]);
            }
            for (int32_t i = 0; i < j->field_count; ++i)
                if (j->fields[i].location == CF_FIELD_FACE) fprintf(fp, " %.17g", j->fields[i].values[f]);
            fputc('\n', fp);
        }
        return CF_OK;
    }
    bool big = enc == CF_PLY_BINARY_BIG_ENDIAN;
    /* One record buffer for the largest element: face = 1 + 12 + 1 + 48 + 8 per field. */
    size_t rec_bytes = 8 * (size_t)(5 + j->field_count) + 64;
    unsigned char *rec = cfi_malloc(ctx, rec_bytes);
    if (!rec) return cfi_error(ctx, CF_ERR_NOMEM, "%s: out of memory", j->path);
    for (int32_t v = 0; v < nv; ++v) {
        unsigned char *p = rec;
        for (int k = 0; k < 3; ++k) p = put_f64(p, j->x[3 * v + k], big);
        if (layout == UV_PER_VERTEX) {
            p = put_f64(p, uv[2 * map[v]], big);
            p = put_f64(p, uv[2 * map[v] + 1], big);
        }
        for (int32_t i = 0; i < j->field_count; ++i)
            if (j->fields[i].location == CF_FIELD_VERTEX) p = put_field(j, i, p, j->fields[i].values[v], big);
        fwrite(rec, 1, (size_t)(p - rec), fp);
    }
    for (int32_t f = 0; f < nf; ++f) {
        unsigned char *p = rec;
        *p++ = 3;
        for (int k = 0; k < 3; ++k) p = put_i32(p, tri[3 * f + k], big);
        if (layout == UV_PER_CORNER) {
            *p++ = 6;
            for (int k = 0; k < 3; ++k) {
                p = put_f64(p, uv[2 * uvt[3 * f + k]], big);
                p = put_f64(p, uv[2 * uvt[3 * f + k] + 1], big);
            }
        }
        for (int32_t i = 0; i < j->field_count; ++i)
            if (j->fields[i].location == CF_FIELD_FACE) p = put_field(j, i, p, j->fields[i].values[f], big);
        fwrite(rec, 1, (size_t)(p - rec), fp);
    }
    cfi_free(ctx, rec, rec_bytes);
    return CF_OK;
}

static cf_status write_ply(write_job *j, cf_ply_encoding enc)
{
    cf_context *ctx = j->ctx;
    cfi_atomic_file af;
    cf_status st = cfi_atomic_open(ctx, j->path, &af);
    if (st != CF_OK) return st;
    int32_t nv = cf_mesh_vertex_count(j->mesh), nf = cf_mesh_face_count(j->mesh);
    int32_t *map = NULL;
    if (j->use_uv && !(map = CFI_ALLOC(ctx, int32_t, nv))) st = CF_ERR_NOMEM;
    if (st == CF_OK && j->field_count > 0 && !(j->uchar = CFI_ALLOC(ctx, uint8_t, j->field_count))) st = CF_ERR_NOMEM;
    for (int32_t i = 0; st == CF_OK && i < j->field_count; ++i)
        j->uchar[i] = is_colour_channel(&j->fields[i], j->fields[i].location == CF_FIELD_VERTEX ? nv : nf);
    if (st == CF_OK) st = write_ply_body(j, af.fp, enc, map);
    if (map) CFI_FREE(ctx, map, nv);
    if (j->uchar) CFI_FREE(ctx, j->uchar, j->field_count);
    j->uchar = NULL;
    if (st != CF_OK) {
        cfi_atomic_abort(ctx, &af);
        return st;
    }
    return cfi_atomic_commit(ctx, &af);
}

/* ---- OBJ + CSV, OFF ------------------------------------------------------------ */

/* The index of the field of `location` named `name`, or -1. */
static int32_t find_field(const cf_field *fields, int32_t count, cf_field_location location, const char *name)
{
    for (int32_t i = 0; i < count; ++i)
        if (fields[i].location == location && fields[i].name && strcmp(fields[i].name, name) == 0) return i;
    return -1;
}

static bool in_colour_range(const cf_field *f, int32_t n)
{
    for (int32_t k = 0; k < n; ++k)
        if (!(f->values[k] >= 0.0 && f->values[k] <= 255.0)) return false;
    return true;
}

/* The colour channels of one location: rgba[0..3] field indices of red,
 * green, blue, alpha with values in [0, 255] (alpha -1 when absent), all
 * -1 when red, green and blue are not all there in range. What OFF holds,
 * and (red green blue) what OBJ writes on its v lines. */
static void colour_fields(const cf_field *fields, int32_t count, cf_field_location location, int32_t n,
                              int32_t rgba[4])
{
    static const char *const names[4] = {"red", "green", "blue", "alpha"};
    for (int c = 0; c < 4; ++c) {
        rgba[c] = find_field(fields, count, location, names[c]);
        if (rgba[c] >= 0 && !in_colour_range(&fields[rgba[c]], n)) rgba[c] = -1;
    }
    if (rgba[0] < 0 || rgba[1] < 0 || rgba[2] < 0) rgba[0] = rgba[1] = rgba[2] = rgba[3] = -1;
}

static bool is_obj_colour(const write_job *j, int32_t i)
{
    return i == j->obj_rgb[0] || i == j->obj_rgb[1] || i == j->obj_rgb[2];
}

/* Vertex fields red, green and blue with values in [0, 255] (the PLY
 * convention, which the readers use) are written in the OBJ itself, as
 * `v x y z r g b` with r g b in [0, 1], where viewers read vertex colours;
 * the CSV files get the other fields. */
static void find_obj_colours(write_job *j)
{
    int32_t rgba[4];
    colour_fields(j->fields, j->field_count, CF_FIELD_VERTEX, cf_mesh_vertex_count(j->mesh), rgba);
    for (int c = 0; c < 3; ++c) j->obj_rgb[c] = rgba[c];
    if (rgba[0] >= 0) j->nvf -= 3;
}

static cf_status write_csv(write_job *j, const char *csv_path, cf_field_location loc, int32_t n)
{
    cf_context *ctx = j->ctx;
    cfi_atomic_file af;
    cf_status st = cfi_atomic_open(ctx, csv_path, &af);
    if (st != CF_OK) return st;
    fputs("index", af.fp);
    for (int32_t i = 0; i < j->field_count; ++i)
        if (j->fields[i].location == loc && !is_obj_colour(j, i)) fprintf(af.fp, ",%s", j->fields[i].name);
    fputc('\n', af.fp);
    for (int32_t e = 0; e < n; ++e) {
        fprintf(af.fp, "%d", e);
        for (int32_t i = 0; i < j->field_count; ++i)
            if (j->fields[i].location == loc && !is_obj_colour(j, i)) fprintf(af.fp, ",%.17g", j->fields[i].values[e]);
        fputc('\n', af.fp);
    }
    return cfi_atomic_commit(ctx, &af);
}

/* "<stem>.vertex.csv" / "<stem>.face.csv" next to the OBJ. */
static cf_status write_obj_sidecars(write_job *j)
{
    cf_context *ctx = j->ctx;
    if (j->nvf == 0 && j->nff == 0) return CF_OK;
    size_t len = strlen(j->path);
    const char *slash = strrchr(j->path, '/');
    const char *dot = strrchr(slash ? slash + 1 : j->path, '.');
    size_t stem = dot ? (size_t)(dot - j->path) : len;
    size_t bytes = stem + sizeof ".vertex.csv";
    char *csv = cfi_malloc(ctx, bytes);
    if (!csv) return cfi_error(ctx, CF_ERR_NOMEM, "%s: out of memory", j->path);
    cf_status st = CF_OK;
    if (j->nvf > 0) {
        snprintf(csv, bytes, "%.*s.vertex.csv", (int)stem, j->path);
        st = write_csv(j, csv, CF_FIELD_VERTEX, cf_mesh_vertex_count(j->mesh));
    }
    if (st == CF_OK && j->nff > 0) {
        snprintf(csv, bytes, "%.*s.face.csv", (int)stem, j->path);
        st = write_csv(j, csv, CF_FIELD_FACE, cf_mesh_face_count(j->mesh));
    }
    cfi_free(ctx, csv, bytes);
    return st;
}

static cf_status write_obj(write_job *j)
{
    cf_context *ctx = j->ctx;
    find_obj_colours(j);
    cf_status st = write_obj_sidecars(j);
    if (st != CF_OK) return st;
    cfi_atomic_file af;
    if ((st = cfi_atomic_open(ctx, j->path, &af)) != CF_OK) return st;
    FILE *fp = af.fp;
    const cf_mesh *mesh = j->mesh;
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh), nuv = cf_mesh_uv_count(mesh);
    const int32_t *tri = cf_mesh_triangles(mesh), *uvt = cf_mesh_uv_triangles(mesh);
    const double *uv = cf_mesh_uv(mesh);
    fprintf(fp, "# written by curvflow %s: %d vertices, %d triangles\n", cf_version_string(), nv, nf);
    const cf_write_options *o = j->opts;
    for (int32_t l = 0; l < o->material_library_count; ++l) fprintf(fp, "mtllib %s\n", o->material_libraries[l]);
    int32_t material = -1;
    for (int32_t v = 0; v < nv; ++v) {
        fprintf(fp, "v %.17g %.17g %.17g", j->x[3 * v], j->x[3 * v + 1], j->x[3 * v + 2]);
        if (j->obj_rgb[0] >= 0)
            fprintf(fp, " %.17g %.17g %.17g", j->fields[j->obj_rgb[0]].values[v] / 255.0,
                    j->fields[j->obj_rgb[1]].values[v] / 255.0, j->fields[j->obj_rgb[2]].values[v] / 255.0);
        fputc('\n', fp);
    }
    if (j->use_uv)
        for (int32_t t = 0; t < nuv; ++t) fprintf(fp, "vt %.17g %.17g\n", uv[2 * t], uv[2 * t + 1]);
    for (int32_t f = 0; f < nf; ++f) {
        const int32_t *c = tri + 3 * f;
        if (o->face_materials && o->face_materials[f] != material && o->face_materials[f] >= 0)
            fprintf(fp, "usemtl %s\n", o->material_names[o->face_materials[f]]);
        if (o->face_materials) material = o->face_materials[f];
        if (j->use_uv) {
            const int32_t *t = uvt + 3 * f;
            fprintf(fp, "f %d/%d %d/%d %d/%d\n", c[0] + 1, t[0] + 1, c[1] + 1, t[1] + 1, c[2] + 1, t[2] + 1);
        } else {
            fprintf(fp, "f %d %d %d\n", c[0] + 1, c[1] + 1, c[2] + 1);
        }
    }
    return cfi_atomic_commit(ctx, &af);
}

/* Field i is one of the vertex or face colour channels v, f (colour_fields). */
static bool is_channel(int32_t i, const int32_t v[4], const int32_t f[4])
{
    for (int c = 0; c < 4; ++c)
        if (i == v[c] || i == f[c]) return true;
    return false;
}

int32_t cf_off_fields_writable(const cf_field *fields, int32_t field_count, int32_t vertex_count, int32_t face_count,
                               uint8_t *writable)
{
    int32_t v[4] = {-1, -1, -1, -1}, f[4] = {-1, -1, -1, -1}, n = 0;
    if (fields && field_count > 0) {
        colour_fields(fields, field_count, CF_FIELD_VERTEX, vertex_count, v);
        colour_fields(fields, field_count, CF_FIELD_FACE, face_count, f);
    }
    for (int32_t i = 0; fields && i < field_count; ++i) {
        bool w = is_channel(i, v, f);
        if (writable) writable[i] = w;
        n += w;
    }
    return n;
}

/* A colour channel's value as OFF writes it: a whole number 0..255
 * (integers read back as 0..255, floats would be read as 0..1). */
static long off_channel(const write_job *j, int32_t field, int32_t k)
{
    return field < 0 ? 255L : lround(j->fields[field].values[k]);
}

static cf_status write_off(write_job *j)
{
    cf_context *ctx = j->ctx;
    int32_t nv = cf_mesh_vertex_count(j->mesh), nf = cf_mesh_face_count(j->mesh);
    int32_t v[4], f[4];
    colour_fields(j->fields, j->field_count, CF_FIELD_VERTEX, nv, v);
    colour_fields(j->fields, j->field_count, CF_FIELD_FACE, nf, f);
    for (int32_t i = 0; i < j->field_count; ++i) {
        if (!is_channel(i, v, f))
            return cfi_error(ctx, CF_ERR_UNSUPPORTED,
                             "%s: OFF holds only colours (red green blue [alpha] of vertices or faces, in [0, 255]); "
                             "field '%s' cannot be written (write PLY, or OBJ with CSV files)",
                             j->path, j->fields[i].name);
    }
    cfi_atomic_file af;
    cf_status st = cfi_atomic_open(ctx, j->path, &af);
    if (st != CF_OK) return st;
    const int32_t *tri = cf_mesh_triangles(j->mesh);
    fprintf(af.fp, "%s\n%d %d 0\n", v[0] >= 0 ? "COFF" : "OFF", nv, nf);
    for (int32_t k = 0; k < nv; ++k) {
        fprintf(af.fp, "%.17g %.17g %.17g", j->x[3 * k], j->x[3 * k + 1], j->x[3 * k + 2]);
        if (v[0] >= 0)
            fprintf(af.fp, " %ld %ld %ld %ld", off_channel(j, v[0], k), off_channel(j, v[1], k),
                    off_channel(j, v[2], k), off_channel(j, v[3], k));
        fputc('\n', af.fp);
    }
    for (int32_t k = 0; k < nf; ++k) {
        fprintf(af.fp, "3 %d %d %d", tri[3 * k], tri[3 * k + 1], tri[3 * k + 2]);
        if (f[0] >= 0) {
            fprintf(af.fp, " %ld %ld %ld", off_channel(j, f[0], k), off_channel(j, f[1], k), off_channel(j, f[2], k));
            if (f[3] >= 0) fprintf(af.fp, " %ld", off_channel(j, f[3], k));
        }
        fputc('\n', af.fp);
    }
    return cfi_atomic_commit(ctx, &af);
}

/* ---- entry points ----------------------------------------------------------------- */

cf_status cf_write_mesh_file_ex(cf_context *ctx, const char *path, const cf_mesh *mesh, const double *positions,
                                const cf_field *fields, int32_t field_count, const cf_write_options *options)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!path || !mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_write_mesh_file: path or mesh is NULL");
    cf_write_options opts;
    if (options) opts = *options;
    else cf_write_options_default(&opts);
    cf_mesh_format format = opts.format;
    cf_status st = CF_OK;
    if (format == CF_FORMAT_AUTO && (st = cf_mesh_format_from_path(ctx, path, &format)) != CF_OK) return st;
    if (format != CF_FORMAT_OBJ && format != CF_FORMAT_OFF && format != CF_FORMAT_PLY)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: bad output format %d", path, (int)format);
    if (opts.ply_encoding != CF_PLY_ASCII && opts.ply_encoding != CF_PLY_BINARY_LITTLE_ENDIAN &&
        opts.ply_encoding != CF_PLY_BINARY_BIG_ENDIAN)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: bad PLY encoding %d", path, (int)opts.ply_encoding);
    if ((st = check_fields(ctx, path, fields, field_count)) != CF_OK) return st;
    if ((st = check_materials(ctx, path, &opts, cf_mesh_face_count(mesh))) != CF_OK) return st;
    write_job j = {ctx, path, mesh, positions ? positions : cf_mesh_positions(mesh), fields, field_count, 0, 0,
                   false, NULL, &opts, {-1, -1, -1}};
    int32_t nv = cf_mesh_vertex_count(mesh);
    for (int32_t v = 0; v < nv; ++v)
        if (!isfinite(j.x[3 * v]) || !isfinite(j.x[3 * v + 1]) || !isfinite(j.x[3 * v + 2]))
            return cfi_error(ctx, CF_ERR_NONFINITE, "%s: vertex %d has a non-finite coordinate", path, v);
    for (int32_t i = 0; i < field_count; ++i) {
        if (fields[i].location == CF_FIELD_VERTEX) j.nvf++;
        else j.nff++;
    }
    j.use_uv = opts.write_uv && cf_mesh_uv_count(mesh) > 0 && cf_mesh_uv(mesh) && cf_mesh_uv_triangles(mesh);
    switch (format) {
    case CF_FORMAT_PLY: return write_ply(&j, opts.ply_encoding);
    case CF_FORMAT_OBJ: return write_obj(&j);
    case CF_FORMAT_OFF: return write_off(&j);
    case CF_FORMAT_AUTO: break;
    }
    return CF_ERR_INVALID_ARG;
}

cf_status cf_write_mesh_file(cf_context *ctx, const char *path, const cf_mesh *mesh, const double *positions,
                             const cf_field *fields, int32_t field_count)
{
    return cf_write_mesh_file_ex(ctx, path, mesh, positions, fields, field_count, NULL);
}
