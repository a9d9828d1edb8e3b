/*
 * The JSON constraint file (the editing tool's "handle file"; format and
 * decisions in docs/edit.md): sets of vertices selected by index list, box
 * or relative box, each with a target rule (fixed, explicit targets, or a
 * rigid transform plus uniform scale). Read into a cf_handle_set, or into a
 * cf_point_set when only the selection matters. The only user of jansson in
 * the library (its include directory and link are private to this module).
 */
#include "constraints/constraints_internal.h"
#include "mesh/mesh_internal.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- JSON ---------------------------------------------------------------- */

typedef struct json_reader {
    cf_context *ctx;
    const cf_mesh *mesh;
    const double *x;
    const char *src;
    int selection_only;  /* point-set reading: the target rule is optional */
    int32_t *owner;      /* nv: set index owning the vertex, -1 */
    double *target;      /* 3 nv */
    int32_t *members;    /* nv scratch: vertices of the current set */
} json_reader;

static cf_status jerr(const json_reader *r, const char *set, const char *fmt, const char *detail)
{
    if (set)
        return cfi_error(r->ctx, CF_ERR_PARSE, "%s: set '%s': %s%s", r->src, set, fmt, detail ? detail : "");
    return cfi_error(r->ctx, CF_ERR_PARSE, "%s: %s%s", r->src, fmt, detail ? detail : "");
}

static int read_vec3(json_t *a, double out[3])
{
    if (!json_is_array(a) || json_array_size(a) != 3) return 0;
    for (size_t k = 0; k < 3; ++k) {
        json_t *e = json_array_get(a, k);
        if (!json_is_number(e)) return 0;
        out[k] = json_number_value(e);
        if (!isfinite(out[k])) return 0;
    }
    return 1;
}

static cf_status select_box(json_reader *r, const char *name, json_t *box, int relative, int32_t *n)
{
    double lo[3], hi[3];
    json_t *jmin = json_object_get(box, "min"), *jmax = json_object_get(box, "max");
    if (!json_is_object(box) || !read_vec3(jmin, lo) || !read_vec3(jmax, hi))
        return jerr(r, name, relative ? "\"relative_box\"" : "\"box\"",
                    " must be an object with \"min\" and \"max\" arrays of 3 finite numbers");
    int32_t count = cfi_select_box(r->mesh->nv, r->x, lo, hi, relative, r->members);
    *n = count;
    return CF_OK;
}

static cf_status read_set(json_reader *r, json_t *set, size_t index, char *name_buf, size_t name_cap)
{
    cf_context *ctx = r->ctx;
    int32_t nv = r->mesh->nv;
    if (!json_is_object(set)) {
        snprintf(name_buf, name_cap, "#%zu", index);
        return jerr(r, name_buf, "a set must be a JSON object", NULL);
    }
    json_t *jname = json_object_get(set, "name");
    if (jname && json_is_string(jname)) {
        snprintf(name_buf, name_cap, "%s", json_string_value(jname));
    } else {
        snprintf(name_buf, name_cap, "#%zu", index);
        /* issue 15: silently ignored input gets a warning */
        if (jname)
            cfi_log(ctx, CF_LOG_WARNING, "%s: set #%zu: \"name\" is not a string; the set is called #%zu", r->src,
                    index, index);
        else
            cfi_log(ctx, CF_LOG_WARNING, "%s: set #%zu has no \"name\"; messages call it #%zu", r->src, index, index);
    }
    const char *name = name_buf;
    const char *key;
    json_t *val;
    json_object_foreach(set, key, val) {
        static const char *const known[] = {"name", "vertices", "box", "relative_box", "fixed", "targets",
                                            "transform", NULL};
        int ok = 0;
        for (int k = 0; known[k]; ++k) ok |= strcmp(key, known[k]) == 0;
        if (!ok) return jerr(r, name, "unknown key: ", key);
    }
    json_t *jv = json_object_get(set, "vertices"), *jbox = json_object_get(set, "box"),
           *jrel = json_object_get(set, "relative_box");
    if ((jv != NULL) + (jbox != NULL) + (jrel != NULL) != 1)
        return jerr(r, name, "give exactly one of \"vertices\", \"box\", \"relative_box\"", NULL);
    int32_t n = 0;
    if (jv) {
        if (!json_is_array(jv)) return jerr(r, name, "\"vertices\" must be an array of vertex indices", NULL);
        size_t count = json_array_size(jv);
        if (count > (size_t)nv)
            return cfi_error(ctx, CF_ERR_PARSE, "%s: set '%s': %zu vertices listed but the mesh has %d", r->src, name,
                             count, nv);
        for (size_t k = 0; k < count; ++k) {
            json_t *e = json_array_get(jv, k);
            if (!json_is_integer(e))
                return cfi_error(ctx, CF_ERR_PARSE, "%s: set '%s': vertices[%zu] is not an integer", r->src, name, k);
            json_int_t v = json_integer_value(e);
            if (v < 0 || v >= nv)
                return cfi_error(ctx, CF_ERR_PARSE, "%s: set '%s': unknown vertex %lld (mesh has %d vertices)",
                                 r->src, name, (long long)v, nv);
            r->members[n++] = (int32_t)v;
        }
    } else {
        cf_status st = select_box(r, name, jbox ? jbox : jrel, jrel != NULL, &n);
        if (st != CF_OK) return st;
    }
    if (n == 0) return jerr(r, name, "the set is empty (no vertex selected)", NULL);

    json_t *jfixed = json_object_get(set, "fixed"), *jt = json_object_get(set, "targets"),
           *jtr = json_object_get(set, "transform");
    if (jfixed && !json_is_true(jfixed))
        return jerr(r, name, "\"fixed\" may only be true (omit it for moving sets)", NULL);
    int rules = (jfixed != NULL) + (jt != NULL) + (jtr != NULL);
    if (rules > 1 || (rules == 0 && !r->selection_only))
        return jerr(r, name, "give exactly one of \"fixed\": true, \"targets\", \"transform\"", NULL);
    int32_t set_id = (int32_t)index;
    for (int32_t k = 0; k < n; ++k) {
        int32_t v = r->members[k];
        if (r->owner[v] == set_id)
            return cfi_error(ctx, CF_ERR_PARSE, "%s: set '%s': vertex %d is listed twice", r->src, name, v);
        if (r->owner[v] >= 0)
            return cfi_error(ctx, CF_ERR_PARSE, "%s: set '%s': vertex %d is already in set #%d (sets must not overlap)",
                             r->src, name, v, (int)r->owner[v]);
        r->owner[v] = set_id;
    }
    if (jfixed || rules == 0) {
        for (int32_t k = 0; k < n; ++k) memcpy(r->target + 3 * r->members[k], r->x + 3 * r->members[k], 3 * sizeof(double));
        return CF_OK;
    }
    if (jt) {
        if (!jv) return jerr(r, name, "\"targets\" needs an explicit \"vertices\" list", NULL);
        if (!json_is_array(jt) || json_array_size(jt) != (size_t)n)
            return cfi_error(ctx, CF_ERR_PARSE, "%s: set '%s': \"targets\" must hold %d positions, one per vertex",
                             r->src, name, (int)n);
        for (int32_t k = 0; k < n; ++k) {
            if (!read_vec3(json_array_get(jt, (size_t)k), r->target + 3 * r->members[k]))
                return cfi_error(ctx, CF_ERR_PARSE, "%s: set '%s': targets[%d] is not 3 finite numbers", r->src, name,
                                 (int)k);
            if (cfi_first_unusable_point(r->target + 3 * r->members[k], 1, 3) >= 0)
                return cfi_error(ctx, CF_ERR_PARSE, "%s: set '%s': targets[%d] is beyond the range of coordinates (|x| <= %.0e)",
                                 r->src, name, (int)k, CF_MAX_COORDINATE);
        }
        return CF_OK;
    }
    /* Rigid transform (plus uniform scale): x -> c + s R (x - c) + t. */
    if (!json_is_object(jtr)) return jerr(r, name, "\"transform\" must be an object", NULL);
    json_object_foreach(jtr, key, val) {
        if (strcmp(key, "translate") && strcmp(key, "rotate") && strcmp(key, "scale") && strcmp(key, "center"))
            return jerr(r, name, "unknown transform key: ", key);
    }
    cf_rigid_transform tr;
    cf_rigid_transform_identity(&tr);
    double *c = tr.center;
    for (int32_t k = 0; k < n; ++k)
        for (int d = 0; d < 3; ++d) c[d] += r->x[3 * r->members[k] + d] / n;
    json_t *jtt = json_object_get(jtr, "translate"), *jr = json_object_get(jtr, "rotate"),
           *js = json_object_get(jtr, "scale"), *jc = json_object_get(jtr, "center");
    if (jtt && !read_vec3(jtt, tr.translation)) return jerr(r, name, "\"translate\" must be 3 finite numbers", NULL);
    if (jc && !read_vec3(jc, c)) return jerr(r, name, "\"center\" must be 3 finite numbers", NULL);
    if (js) {
        if (!json_is_number(js) || !(json_number_value(js) > 0.0) || !isfinite(json_number_value(js)))
            return jerr(r, name, "\"scale\" must be a positive number", NULL);
        tr.scale = json_number_value(js);
    }
    if (jr) {
        double axis[3];
        json_t *ja = json_object_get(jr, "axis"), *jd = json_object_get(jr, "angle_degrees"),
               *jrc = json_object_get(jr, "center");
        if (!json_is_object(jr) || !read_vec3(ja, axis) || !json_is_number(jd))
            return jerr(r, name, "\"rotate\" needs \"axis\" (3 numbers) and \"angle_degrees\"", NULL);
        if (jrc && !read_vec3(jrc, c)) return jerr(r, name, "rotate \"center\" must be 3 finite numbers", NULL);
        double len = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        if (!(len > 0.0)) return jerr(r, name, "rotation axis is the zero vector", NULL);
        for (int d = 0; d < 3; ++d) axis[d] /= len;
        cfi_axis_angle_matrix(axis, json_number_value(jd) * 3.14159265358979323846 / 180.0, tr.rotation);
    }
    for (int32_t k = 0; k < n; ++k) {
        double *o = r->target + 3 * r->members[k];
        cfi_rigid_apply_point(&tr, r->x + 3 * r->members[k], o);
        if (cfi_first_unusable_point(o, 1, 3) >= 0)
            return cfi_error(ctx, CF_ERR_PARSE,
                             "%s: set '%s': the transform moves vertex %d to (%.3g, %.3g, %.3g), beyond the range of "
                             "coordinates (|x| <= %.0e)",
                             r->src, name, r->members[k], o[0], o[1], o[2], CF_MAX_COORDINATE);
    }
    return CF_OK;
}

/* Parses `text` into r (owner and target per vertex). Warns about
 * top-level keys other than "sets". */
static cf_status parse(json_reader *r, const char *text)
{
    cf_context *ctx = r->ctx;
    json_error_t jerror;
    json_t *root = json_loads(text, JSON_REJECT_DUPLICATES, &jerror);
    if (!root)
        return cfi_error(ctx, CF_ERR_PARSE, "%s:%d:%d: malformed JSON: %s", r->src, jerror.line, jerror.column,
                         jerror.text);
    int32_t nv = r->mesh->nv;
    cf_status st = CF_OK;
    json_t *sets = json_is_object(root) ? json_object_get(root, "sets") : NULL;
    if (!json_is_array(sets)) {
        st = jerr(r, NULL, "expected an object with a \"sets\" array", NULL);
        goto done;
    }
    {
        /* issue 15: silently ignored input gets a warning */
        const char *key;
        json_t *val;
        json_object_foreach(root, key, val) {
            if (strcmp(key, "sets") != 0)
                cfi_log(ctx, CF_LOG_WARNING, "%s: unknown top-level key '%s' ignored (only \"sets\" is read)", r->src,
                        key);
        }
    }
    if (json_array_size(sets) == 0) {
        st = jerr(r, NULL, r->selection_only ? "\"sets\" is empty: no vertex selected" : "\"sets\" is empty: no handle vertex",
                  NULL);
        goto done;
    }
    r->owner = CFI_ALLOC(ctx, int32_t, (size_t)nv);
    r->target = CFI_ALLOC(ctx, double, 3 * (size_t)nv);
    r->members = CFI_ALLOC(ctx, int32_t, (size_t)nv);
    if (!r->owner || !r->target || !r->members) {
        st = CF_ERR_NOMEM;
        goto done;
    }
    for (int32_t v = 0; v < nv; ++v) r->owner[v] = -1;
    char name[128];
    for (size_t k = 0; k < json_array_size(sets) && st == CF_OK; ++k)
        st = read_set(r, json_array_get(sets, k), k, name, sizeof name);
done:
    json_decref(root);
    return st;
}

static void reader_free(json_reader *r)
{
    int32_t nv = r->mesh->nv;
    CFI_FREE(r->ctx, r->owner, (size_t)nv);
    CFI_FREE(r->ctx, r->target, 3 * (size_t)nv);
    CFI_FREE(r->ctx, r->members, (size_t)nv);
}

cf_status cf_handle_set_parse_json(cf_context *ctx, const cf_mesh *mesh, const double *positions, const char *text,
                                   const char *source_name, cf_handle_set **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out || !mesh || !text) return cfi_error(ctx, CF_ERR_INVALID_ARG, "handle file: NULL argument");
    *out = NULL;
    const char *src = source_name ? source_name : "handles";
    int32_t nv = mesh->nv;
    json_reader r = {ctx, mesh, positions ? positions : mesh->positions, src, 0, NULL, NULL, NULL};
    cf_status st = parse(&r, text);
    if (st != CF_OK) goto done;
    int32_t count = 0, moved = 0;
    for (int32_t v = 0; v < nv; ++v) {
        if (r.owner[v] < 0) continue;
        ++count;
        for (int d = 0; d < 3; ++d)
            if (r.target[3 * v + d] != r.x[3 * v + d]) {
                ++moved;
                break;
            }
    }
    if (count == nv) {
        st = cfi_error(ctx, CF_ERR_PARSE, "%s: all %d vertices are constrained; nothing is left to deform", src, nv);
        goto done;
    }
    cf_handle_set *h = cfi_handle_set_alloc(ctx, count);
    if (!h) {
        st = CF_ERR_NOMEM;
        goto done;
    }
    int32_t k = 0;
    for (int32_t v = 0; v < nv; ++v) {
        if (r.owner[v] < 0) continue;
        h->vertices[k] = v;
        memcpy(h->targets + 3 * k, r.target + 3 * v, 3 * sizeof(double));
        ++k;
    }
    h->moved_count = moved;
    *out = h;
done:
    reader_free(&r);
    return st;
}

cf_status cf_point_set_parse_json(cf_context *ctx, const cf_mesh *mesh, const double *positions, const char *text,
                                  const char *source_name, cf_point_set **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out || !mesh || !text) return cfi_error(ctx, CF_ERR_INVALID_ARG, "point set file: NULL argument");
    *out = NULL;
    int32_t nv = mesh->nv;
    json_reader r = {ctx, mesh, positions ? positions : mesh->positions, source_name ? source_name : "points", 1,
                     NULL, NULL, NULL};
    cf_status st = parse(&r, text);
    if (st == CF_OK) {
        int32_t count = 0;
        for (int32_t v = 0; v < nv; ++v) count += r.owner[v] >= 0;
        cf_point_set *p = cfi_point_set_alloc(ctx, count);
        if (p) {
            int32_t k = 0;
            for (int32_t v = 0; v < nv; ++v)
                if (r.owner[v] >= 0) p->vertices[k++] = v;
            *out = p;
        } else {
            st = CF_ERR_NOMEM;
        }
    }
    reader_free(&r);
    return st;
}

/* The whole file, NUL-terminated, in a buffer of *cap bytes (freed by the
 * caller with that size). A NUL byte inside is an error (the JSON reader
 * would stop there). */
static cf_status read_text(cf_context *ctx, const char *path, const char *what, char **out, size_t *out_cap)
{
    *out = NULL;
    *out_cap = 0;
    FILE *f = fopen(path, "rb");
    if (!f) return cfi_error(ctx, CF_ERR_IO, "%s: cannot open %s", path, what);
    size_t cap = 4096, len = 0;
    char *buf = cfi_malloc(ctx, cap);
    cf_status st = buf ? CF_OK : CF_ERR_NOMEM;
    while (st == CF_OK) {
        if (len + 1 >= cap) {
            char *nb = cfi_realloc(ctx, buf, cap, 2 * cap);
            if (!nb) {
                st = CF_ERR_NOMEM;
                break;
            }
            buf = nb;
            cap *= 2;
        }
        size_t got = fread(buf + len, 1, cap - 1 - len, f);
        len += got;
        if (got == 0) {
            if (ferror(f)) st = cfi_error(ctx, CF_ERR_IO, "%s: read error", path);
            break;
        }
    }
    fclose(f);
    if (st == CF_OK) {
        buf[len] = '\0';
        if (strlen(buf) != len) st = cfi_error(ctx, CF_ERR_PARSE, "%s: the %s contains a NUL byte", path, what);
    }
    if (st != CF_OK) {
        if (buf) cfi_free(ctx, buf, cap);
        return st;
    }
    *out = buf;
    *out_cap = cap;
    return CF_OK;
}

cf_status cf_handle_set_read_json(cf_context *ctx, const cf_mesh *mesh, const double *positions, const char *path,
                                  cf_handle_set **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!path || !out || !mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "handle file: NULL argument");
    *out = NULL;
    char *buf = NULL;
    size_t cap = 0;
    cf_status st = read_text(ctx, path, "handle file", &buf, &cap);
    if (st == CF_OK) st = cf_handle_set_parse_json(ctx, mesh, positions, buf, path, out);
    if (buf) cfi_free(ctx, buf, cap);
    return st;
}

cf_status cf_point_set_read_json(cf_context *ctx, const cf_mesh *mesh, const double *positions, const char *path,
                                 cf_point_set **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!path || !out || !mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "point set file: NULL argument");
    *out = NULL;
    char *buf = NULL;
    size_t cap = 0;
    cf_status st = read_text(ctx, path, "point set file", &buf, &cap);
    if (st == CF_OK) st = cf_point_set_parse_json(ctx, mesh, positions, buf, path, out);
    if (buf) cfi_free(ctx, buf, cap);
    return st;
}
