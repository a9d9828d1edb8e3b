/*
 * The common flow layer (include/curvflow/flow.h): registry of the methods,
 * generic option parsing from each method's parameter table, and the
 * per-step safety net shared by every method (saved state, finiteness
 * checks, restore on failure, area/volume drift, timing, progress callback).
 */
#include "methods/flow_internal.h"

#include "curvflow/constraints.h"
#include "curvflow/ops.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* One entry per cf_flow_kind, in enum order. */
static const cfi_flow_method *const registry[CF_FLOW_KIND_COUNT] = {
    &cfi_explicit_mcf_method,
    &cfi_implicit_mcf_method,
    &cfi_conformal_mcf_method,
    &cfi_explicit_bilaplacian_method,
    &cfi_implicit_bilaplacian_method,
    &cfi_spin_willmore_method,
    &cfi_stretch_bend_edit_method,
};

const cfi_flow_method *cfi_flow_method_of(cf_flow_kind kind)
{
    if ((int)kind < 0 || (int)kind >= CF_FLOW_KIND_COUNT) return NULL;
    const cfi_flow_method *m = registry[kind];
    if (CF_NEVER(m->kind != kind)) return NULL;
    return m;
}

const char *cf_flow_kind_name(cf_flow_kind kind)
{
    const cfi_flow_method *m = cfi_flow_method_of(kind);
    return m ? m->name : NULL;
}

const char *cf_flow_kind_description(cf_flow_kind kind)
{
    const cfi_flow_method *m = cfi_flow_method_of(kind);
    return m ? m->description : NULL;
}

cf_status cf_flow_kind_from_name(const char *name, cf_flow_kind *kind)
{
    if (!name || !kind) return CF_ERR_INVALID_ARG;
    for (int k = 0; k < CF_FLOW_KIND_COUNT; ++k) {
        if (strcmp(registry[k]->name, name) == 0) {
            *kind = (cf_flow_kind)k;
            return CF_OK;
        }
    }
    return CF_ERR_INVALID_ARG;
}

/* ---- options ------------------------------------------------------------ */

cf_status cf_flow_options_default(cf_flow_kind kind, cf_flow_options *options)
{
    const cfi_flow_method *m = cfi_flow_method_of(kind);
    if (!m || !options) return CF_ERR_INVALID_ARG;
    if (CF_NEVER(m->options_size > CFI_STEP_POLICY_OFFSET)) return CF_ERR_INVALID_ARG;
    memset(options, 0, sizeof *options);
    options->kind = kind;
    if (m->options_default) m->options_default(options->storage.bytes);
    cfi_step_policy_default_for(cf_flow_options_policy(options), &m->policy);
    return CF_OK;
}

void *cf_flow_options_method(cf_flow_options *options) { return options ? options->storage.bytes : NULL; }

void *cf_flow_options_method_as(cf_flow_options *options, cf_flow_kind expected)
{
    return options && options->kind == expected && cfi_flow_method_of(expected) ? options->storage.bytes : NULL;
}

const void *cf_flow_options_method_as_const(const cf_flow_options *options, cf_flow_kind expected)
{
    return options && options->kind == expected && cfi_flow_method_of(expected) ? options->storage.bytes : NULL;
}

int32_t cf_param_type_is_array(cf_param_type type)
{
    return type == CF_PARAM_VERTEX_SCALARS || type == CF_PARAM_VERTEX_VECTORS || type == CF_PARAM_FACE_SCALARS ||
           type == CF_PARAM_POINT_SETS;
}

const char *cf_param_type_name(cf_param_type type)
{
    switch (type) {
    case CF_PARAM_DOUBLE: return "double";
    case CF_PARAM_INT: return "int";
    case CF_PARAM_BOOL: return "bool";
    case CF_PARAM_CHOICE: return "choice";
    case CF_PARAM_VERTEX_SCALARS: return "vertex-scalars";
    case CF_PARAM_VERTEX_VECTORS: return "vertex-vectors";
    case CF_PARAM_FACE_SCALARS: return "face-scalars";
    case CF_PARAM_POINT_SETS: return "point-set";
    }
    return NULL;
}

/* Bytes of a parameter's field in the options struct. */
static size_t param_field_bytes(const cf_param_desc *p)
{
    switch (p->type) {
    case CF_PARAM_DOUBLE: return sizeof(double);
    case CF_PARAM_VERTEX_SCALARS:
    case CF_PARAM_VERTEX_VECTORS:
    case CF_PARAM_FACE_SCALARS: return sizeof(cf_param_values);
    case CF_PARAM_POINT_SETS: return sizeof(const cf_handle_set *);
    default: return sizeof(int32_t);
    }
}

const void *cf_flow_options_method_const(const cf_flow_options *options)
{
    return options ? options->storage.bytes : NULL;
}

cf_status cf_flow_params(cf_flow_kind kind, const cf_param_desc **params, int32_t *count)
{
    const cfi_flow_method *m = cfi_flow_method_of(kind);
    if (!m || !params || !count) return CF_ERR_INVALID_ARG;
    *params = m->params;
    *count = m->params ? m->param_count : 0;
    return CF_OK;
}

static const cf_param_desc *find_param(const cfi_flow_method *m, const char *name)
{
    for (int32_t i = 0; m->params && i < m->param_count; ++i)
        if (strcmp(m->params[i].name, name) == 0) return &m->params[i];
    return NULL;
}

/* Appends the parameter names of m to buf ("a, b, c"). */
static void list_param_names(const cfi_flow_method *m, char *buf, size_t size)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int32_t i = 0; m->params && i < m->param_count && used + 1 < size; ++i) {
        int n = snprintf(buf + used, size - used, "%s%s", i ? ", " : "", m->params[i].name);
        if (n < 0) break;
        used += (size_t)n;
    }
    if (used >= size) used = size - 1;
    buf[used] = '\0';
}

/* Shortest text that strtod reads back as v ("0.001", "1.5707963267948966",
 * "1e-09"), so a limit printed in a message or by --list-params can be typed
 * back and means the same number; integral values below 1e15 without an
 * exponent ("100000"). */
static void format_number(double v, char *buf, size_t size)
{
    if (v == floor(v) && fabs(v) < 1e15) {
        snprintf(buf, size, "%.0f", v);
        return;
    }
    snprintf(buf, size, "%.17g", v);
    for (int prec = 1; prec < 17; ++prec) {
        char tmp[64];
        snprintf(tmp, sizeof tmp, "%.*g", prec, v);
        if (strtod(tmp, NULL) == v) {
            snprintf(buf, size, "%s", tmp);
            return;
        }
    }
}

/* The whole of `text` as a finite double: 0 ok, 1 not a number, 2 a number
 * that is not finite (nan, inf, or beyond the double range). A value below
 * the smallest normal double (1e-320) is a number like any other: strtod
 * flags it with ERANGE but returns it (or 0), and the range check decides. */
static int parse_number(const char *text, double *out)
{
    char *end = NULL;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end != '\0') return 1;
    if (!isfinite(v) || (errno == ERANGE && fabs(v) > 1.0)) return 2;
    *out = v;
    return 0;
}

/* "'time_step': 1e-320 is outside [1e-09, 10] (below the smallest accepted
 * value)": the value as written, the limits as they read back exactly. */
static cf_status range_error(cf_context *ctx, const cf_param_desc *p, const char *value, double v)
{
    char range[160];
    if (cf_flow_param_range_format(p, range, sizeof range) != CF_OK) snprintf(range, sizeof range, "its range");
    return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': %s is outside %s (%s accepted value)", p->name, value,
                     range, v < p->min_value ? "below the smallest" : "above the largest");
}

static int parse_bool(const char *s, int32_t *out)
{
    static const char *const yes[] = {"1", "true", "yes", "on"};
    static const char *const no[] = {"0", "false", "no", "off"};
    for (size_t i = 0; i < sizeof yes / sizeof yes[0]; ++i) {
        if (strcasecmp(s, yes[i]) == 0) { *out = 1; return 1; }
        if (strcasecmp(s, no[i]) == 0) { *out = 0; return 1; }
    }
    return 0;
}

cf_status cf_flow_options_set(cf_context *ctx, cf_flow_options *options, const char *name, const char *value)
{
    if (!options) return cfi_error(ctx, CF_ERR_INVALID_ARG, "options is NULL");
    if (!name || !value) return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter name or value is NULL");
    const cfi_flow_method *m = cfi_flow_method_of(options->kind);
    if (!m) return cfi_error(ctx, CF_ERR_INVALID_ARG, "options have an invalid method kind %d", (int)options->kind);
    const cf_param_desc *p = find_param(m, name);
    /* the common step policy's parameters (step_policy.c), after the method's */
    size_t limit = m->options_size;
    if (!p && (p = cfi_step_policy_find_param(name)) != NULL) limit = CF_FLOW_OPTIONS_STORAGE;
    if (!p) {
        char known[256];
        list_param_names(m, known, sizeof known);
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': unknown for method %s (known: %s)", name, m->name,
                         known[0] ? known : "none");
    }
    if (cf_param_type_is_array(p->type))
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "parameter '%s': a %s parameter takes data, not text (set the options field; the CLI "
                         "loads it with -p %s=FILE)",
                         name, cf_param_type_name(p->type), name);
    size_t field_bytes = param_field_bytes(p);
    if (CF_NEVER(p->offset + field_bytes > limit))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': table entry outside the options struct", name);
    unsigned char *base = options->storage.bytes;
    switch (p->type) {
    case CF_PARAM_DOUBLE: {
        double v = 0.0;
        int bad = parse_number(value, &v);
        if (bad)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': '%s' is not a %snumber", name, value,
                             bad == 2 ? "finite " : "");
        if (v < p->min_value || v > p->max_value) return range_error(ctx, p, value, v);
        memcpy(base + p->offset, &v, sizeof v);
        return CF_OK;
    }
    case CF_PARAM_INT: {
        char *end = NULL;
        errno = 0;
        long long v = strtoll(value, &end, 10);
        if (end == value || *end != '\0' || errno == ERANGE || v < INT32_MIN || v > INT32_MAX)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': '%s' is not an integer", name, value);
        if ((double)v < p->min_value || (double)v > p->max_value) return range_error(ctx, p, value, (double)v);
        int32_t iv = (int32_t)v;
        memcpy(base + p->offset, &iv, sizeof iv);
        return CF_OK;
    }
    case CF_PARAM_BOOL: {
        int32_t b = 0;
        if (!parse_bool(value, &b))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': '%s' is not a boolean (true/false/yes/no/1/0)",
                             name, value);
        memcpy(base + p->offset, &b, sizeof b);
        return CF_OK;
    }
    case CF_PARAM_CHOICE: {
        for (int32_t i = 0; p->choices && p->choices[i]; ++i) {
            if (strcmp(p->choices[i], value) == 0) {
                memcpy(base + p->offset, &i, sizeof i);
                return CF_OK;
            }
        }
        char known[256];
        size_t used = 0;
        known[0] = '\0';
        for (int32_t i = 0; p->choices && p->choices[i] && used + 1 < sizeof known; ++i) {
            int n = snprintf(known + used, sizeof known - used, "%s%s", i ? ", " : "", p->choices[i]);
            if (n < 0) break;
            used += (size_t)n;
        }
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': '%s' is not one of: %s", name, value, known);
    }
    case CF_PARAM_VERTEX_SCALARS:
    case CF_PARAM_VERTEX_VECTORS:
    case CF_PARAM_FACE_SCALARS:
    case CF_PARAM_POINT_SETS: break; /* refused above */
    }
    return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': unknown parameter type", name);
}

cf_status cf_flow_options_format(const cf_flow_options *options, const cf_param_desc *param, char *buf, size_t size)
{
    if (!options || !param || !buf || size == 0) return CF_ERR_INVALID_ARG;
    const unsigned char *base = options->storage.bytes;
    size_t field_bytes = param_field_bytes(param);
    if (param->offset > CF_FLOW_OPTIONS_STORAGE - field_bytes) return CF_ERR_INVALID_ARG;
    int n = 0;
    switch (param->type) {
    case CF_PARAM_DOUBLE: {
        double v;
        memcpy(&v, base + param->offset, sizeof v);
        char text[64];
        format_number(v, text, sizeof text);
        n = snprintf(buf, size, "%s", text);
        break;
    }
    case CF_PARAM_INT: {
        int32_t v;
        memcpy(&v, base + param->offset, sizeof v);
        n = snprintf(buf, size, "%d", (int)v);
        break;
    }
    case CF_PARAM_BOOL: {
        int32_t v;
        memcpy(&v, base + param->offset, sizeof v);
        n = snprintf(buf, size, "%s", v ? "true" : "false");
        break;
    }
    case CF_PARAM_CHOICE: {
        int32_t v;
        memcpy(&v, base + param->offset, sizeof v);
        const char *s = NULL;
        for (int32_t i = 0; param->choices && param->choices[i]; ++i)
            if (i == v) s = param->choices[i];
        n = snprintf(buf, size, "%s", s ? s : "?");
        break;
    }
    case CF_PARAM_VERTEX_SCALARS:
    case CF_PARAM_VERTEX_VECTORS:
    case CF_PARAM_FACE_SCALARS: {
        cf_param_values v;
        memcpy(&v, base + param->offset, sizeof v);
        n = v.values ? snprintf(buf, size, "%d values", (int)v.count) : snprintf(buf, size, "none");
        break;
    }
    case CF_PARAM_POINT_SETS: {
        const cf_handle_set *h;
        memcpy(&h, base + param->offset, sizeof h);
        n = h ? snprintf(buf, size, "%d points", (int)h->count) : snprintf(buf, size, "none");
        break;
    }
    default: return CF_ERR_INVALID_ARG;
    }
    return (n < 0 || (size_t)n >= size) ? CF_ERR_INVALID_ARG : CF_OK;
}

cf_status cf_flow_param_range_format(const cf_param_desc *param, char *buf, size_t size)
{
    if (!param || !buf || size == 0) return CF_ERR_INVALID_ARG;
    int n = 0;
    if (param->type == CF_PARAM_DOUBLE || param->type == CF_PARAM_INT) {
        char lo[64], hi[64];
        format_number(param->min_value, lo, sizeof lo);
        format_number(param->max_value, hi, sizeof hi);
        n = snprintf(buf, size, "[%s, %s]", lo, hi);
    } else if (param->type == CF_PARAM_BOOL) {
        n = snprintf(buf, size, "true|false");
    } else if (param->type == CF_PARAM_CHOICE) {
        size_t used = 0;
        buf[0] = '\0';
        for (int32_t i = 0; param->choices && param->choices[i]; ++i) {
            n = snprintf(buf + used, size - used, "%s%s", i ? "|" : "", param->choices[i]);
            if (n < 0 || (size_t)n >= size - used) return CF_ERR_INVALID_ARG;
            used += (size_t)n;
        }
        return CF_OK;
    } else if (cf_param_type_is_array(param->type)) {
        n = snprintf(buf, size, "%s", param->min_value >= 1.0 ? "required" : "optional");
    } else {
        return CF_ERR_INVALID_ARG;
    }
    return (n < 0 || (size_t)n >= size) ? CF_ERR_INVALID_ARG : CF_OK;
}

/* ---- validation of a whole options struct (cf_flow_create) --------------- */

/* Checks one parameter's field in `base` against its table entry, with the
 * messages of cf_flow_options_set (the value as it reads back). Array types:
 * the element count against the mesh, and presence when required. */
static cf_status check_param(cf_context *ctx, const char *method, const cf_param_desc *p, const unsigned char *base,
                             const cf_mesh *mesh)
{
    char text[64];
    switch (p->type) {
    case CF_PARAM_DOUBLE: {
        double v;
        memcpy(&v, base + p->offset, sizeof v);
        if (!isfinite(v))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': '%s' is not a finite number", p->name,
                             isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf"));
        if (v < p->min_value || v > p->max_value) {
            format_number(v, text, sizeof text);
            return range_error(ctx, p, text, v);
        }
        return CF_OK;
    }
    case CF_PARAM_INT: {
        int32_t v;
        memcpy(&v, base + p->offset, sizeof v);
        if ((double)v < p->min_value || (double)v > p->max_value) {
            snprintf(text, sizeof text, "%d", (int)v);
            return range_error(ctx, p, text, (double)v);
        }
        return CF_OK;
    }
    case CF_PARAM_BOOL: {
        int32_t v;
        memcpy(&v, base + p->offset, sizeof v);
        if (v != 0 && v != 1)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': %d is not a boolean (true|false, stored as 1|0)",
                             p->name, (int)v);
        return CF_OK;
    }
    case CF_PARAM_CHOICE: {
        int32_t v, n = 0;
        memcpy(&v, base + p->offset, sizeof v);
        while (p->choices && p->choices[n]) ++n;
        if (v < 0 || v >= n) {
            char range[256];
            if (cf_flow_param_range_format(p, range, sizeof range) != CF_OK) snprintf(range, sizeof range, "?");
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': index %d is not one of %s (0..%d)", p->name,
                             (int)v, range, (int)n - 1);
        }
        return CF_OK;
    }
    case CF_PARAM_VERTEX_SCALARS:
    case CF_PARAM_VERTEX_VECTORS:
    case CF_PARAM_FACE_SCALARS: {
        cf_param_values v;
        memcpy(&v, base + p->offset, sizeof v);
        int per_face = p->type == CF_PARAM_FACE_SCALARS;
        int32_t expected = per_face ? mesh->nf : mesh->nv;
        const char *what = p->type == CF_PARAM_VERTEX_SCALARS ? "vertex values"
                           : p->type == CF_PARAM_VERTEX_VECTORS ? "vertex vectors (x y z)"
                                                                 : "face values";
        if (!v.values) {
            if (v.count != 0)
                return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': count %d given without values", p->name,
                                 (int)v.count);
            if (p->min_value >= 1.0)
                return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': required by %s (%d %s), not given",
                                 p->name, method, (int)expected, what);
            return CF_OK;
        }
        if (v.count != expected)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': %d %s given, expected %d (one per %s of the mesh)",
                             p->name, (int)v.count, what, (int)expected, per_face ? "face" : "vertex");
        return CF_OK;
    }
    case CF_PARAM_POINT_SETS: {
        const cf_handle_set *h;
        memcpy(&h, base + p->offset, sizeof h);
        if (!h) {
            if (p->min_value >= 1.0)
                return cfi_error(ctx, CF_ERR_INVALID_ARG,
                                 "parameter '%s': required by %s (a point set: vertices with targets), not given",
                                 p->name, method);
            return CF_OK;
        }
        if (h->count < 0 || (h->count > 0 && (!h->vertices || !h->targets)))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': malformed point set (count %d)", p->name,
                             (int)h->count);
        for (int32_t i = 0; i < h->count; ++i)
            if (h->vertices[i] < 0 || h->vertices[i] >= mesh->nv)
                return cfi_error(ctx, CF_ERR_INVALID_ARG,
                                 "parameter '%s': vertex %d out of range (expected 0..%d, the mesh has %d vertices)",
                                 p->name, (int)h->vertices[i], (int)mesh->nv - 1, (int)mesh->nv);
        return CF_OK;
    }
    }
    return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': unknown parameter type %d", p->name, (int)p->type);
}

/* Every parameter of the method's table, in table order: the single place
 * where options are validated (cf_flow_options_set checks text on the way
 * in; this checks the struct, however it was filled). */
static cf_status check_method_options(cf_context *ctx, const cfi_flow_method *m, const unsigned char *base,
                                      const cf_mesh *mesh)
{
    for (int32_t i = 0; m->params && i < m->param_count; ++i) {
        const cf_param_desc *p = &m->params[i];
        if (CF_NEVER(p->offset + param_field_bytes(p) > m->options_size))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': table entry outside the options struct",
                             p->name);
        cf_status st = check_param(ctx, m->name, p, base, mesh);
        if (st != CF_OK) return st;
    }
    return CF_OK;
}

/* ---- flow life cycle ---------------------------------------------------- */

/* CF_OK if every coordinate is finite and within the range the mesh check
 * accepts (CF_MAX_COORDINATE); else `status` with a message naming the first
 * bad vertex, e.g. "vertex 7: starting position is not finite". */
static cf_status check_positions(cf_context *ctx, const double *x, int32_t nv, cf_status status, const char *what)
{
    int64_t v = cfi_first_unusable_point(x, nv, 3);
    if (v < 0) return CF_OK;
    const double *p = x + 3 * v;
    if (isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]))
        return cfi_error(ctx, status, "vertex %d: %s (%.3g, %.3g, %.3g) is out of range (|x| > %.0e)", (int)v, what,
                         p[0], p[1], p[2], CF_MAX_COORDINATE);
    return cfi_error(ctx, status, "vertex %d: %s is not finite", (int)v, what);
}

cf_status cfi_flow_measure(cf_flow *flow, cf_flow_info *info)
{
    double area = 0.0, volume = 0.0;
    cf_status st = cf_total_area(flow->ctx, flow->mesh, flow->positions, &area);
    if (st == CF_OK) st = cf_enclosed_volume(flow->ctx, flow->mesh, flow->positions, &volume);
    if (st != CF_OK) return st;
    info->area = area;
    info->volume = volume;
    info->area_drift = flow->initial_area > 0.0 ? area / flow->initial_area - 1.0 : 0.0;
    info->volume_drift = flow->initial_volume != 0.0 ? volume / flow->initial_volume - 1.0 : 0.0;
    return CF_OK;
}

/* The step policy's state of a new flow: the common options (checked
 * against their table; a policy left all zero by a caller that filled
 * cf_flow_options without cf_flow_options_default means the defaults), the
 * unit of the energy floor, and the method's convergence tolerance (its
 * parameter `tolerance`) when the flow layer decides convergence. */
static cf_status policy_init(cf_flow *flow, const cfi_flow_method *m)
{
    cfi_step_policy_state *p = &flow->policy;
    const cf_step_policy *given = cf_flow_options_policy_const(&flow->options);
    static const cf_step_policy zero;
    if (memcmp(given, &zero, sizeof zero) == 0)
        cfi_step_policy_default_for(&p->opt, &m->policy);
    else
        p->opt = *given;
    cf_status st = cfi_step_policy_validate(flow->ctx, &p->opt);
    if (st != CF_OK) return st;
    p->full_step = 1.0; /* until the method gives its own (cfi_flow_set_time_step) */
    p->step = 1.0;
    /* energy_check=false accepts every step as the method gives it: no
     * rise test and nothing to redo */
    p->rise_check = m->policy.rise_check && p->opt.energy_check;
    p->backtrack = m->policy.backtrack && p->opt.backtrack && p->opt.energy_check;
    /* a method that opts out of a check ignores its option */
    p->blowup_factor = m->policy.blowup_check ? p->opt.blowup_factor : 0.0;
    p->divergence_factor = m->policy.divergence_check ? p->opt.divergence_factor : 0.0;
    switch (m->policy.unit) {
    case CFI_ENERGY_UNIT_4PI: p->unit = 4.0 * 3.14159265358979323846; break;
    case CFI_ENERGY_UNIT_INITIAL_AREA: p->unit = flow->initial_area > 0.0 ? flow->initial_area : 1.0; break;
    default: p->unit = 1.0; break;
    }
    p->tolerance = 0.0;
    if (m->policy.convergence) {
        const cf_param_desc *tol = find_param(m, m->policy.tolerance_param ? m->policy.tolerance_param : "tolerance");
        if (CF_NEVER(!tol || tol->type != CF_PARAM_DOUBLE || tol->offset + sizeof(double) > m->options_size))
            return cfi_error(flow->ctx, CF_ERR_INVALID_ARG, "%s: no tolerance parameter for the step policy", m->name);
        memcpy(&p->tolerance, flow->options.storage.bytes + tol->offset, sizeof p->tolerance);
        if (!(p->tolerance >= 0.0 && p->tolerance <= tol->max_value))
            return cfi_error(flow->ctx, CF_ERR_INVALID_ARG, "parameter '%s': must be in [0, %g], got %g", tol->name,
                             tol->max_value, p->tolerance);
    }
    return CF_OK;
}

void cfi_flow_set_time_step(cf_flow *flow, double full_step)
{
    if (CF_NEVER(!(full_step >= 0.0) || !isfinite(full_step))) return;
    flow->policy.full_step = full_step;
    flow->policy.step = full_step;
}

void cfi_flow_policy_restrict(cf_flow *flow, int keep_rise_check, int keep_backtrack)
{
    flow->policy.rise_check = flow->policy.rise_check && keep_rise_check;
    flow->policy.backtrack = flow->policy.backtrack && keep_backtrack;
}

void cfi_flow_policy_restrict_checks(cf_flow *flow, int keep_blowup, int keep_divergence)
{
    if (!keep_blowup) flow->policy.blowup_factor = 0.0;
    if (!keep_divergence) flow->policy.divergence_factor = 0.0;
}

void cf_flow_destroy(cf_flow **pflow)
{
    if (!pflow || !*pflow) return;
    cf_flow *flow = *pflow;
    cf_context *ctx = flow->ctx;
    if (flow->parts) cfi_flow_destroy_parts(flow);
    else if (flow->method && flow->method->destroy) flow->method->destroy(flow);
    int32_t nv = flow->mesh->nv;
    CFI_FREE(ctx, flow->positions, 3 * (size_t)nv);
    CFI_FREE(ctx, flow->saved_positions, 3 * (size_t)nv);
    CFI_FREE(ctx, flow, 1);
    *pflow = NULL;
}

cf_status cf_flow_create(cf_context *ctx, const cf_mesh *mesh, const double *positions, const cf_flow_options *options,
                         cf_flow **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "flow output pointer is NULL");
    *out = NULL;
    if (!mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "mesh is NULL");
    if (!options) return cfi_error(ctx, CF_ERR_INVALID_ARG, "flow options are NULL");
    const cfi_flow_method *m = cfi_flow_method_of(options->kind);
    if (!m) return cfi_error(ctx, CF_ERR_INVALID_ARG, "unknown flow kind %d", (int)options->kind);
    int32_t nv = mesh->nv;
    const double *start = positions ? positions : mesh->positions;
    cf_status bad = check_method_options(ctx, m, options->storage.bytes, mesh);
    if (bad != CF_OK) return bad;
    bad = check_positions(ctx, start, nv, CF_ERR_NONFINITE, "starting position");
    if (bad != CF_OK) return bad;

    cf_flow *flow = CFI_ALLOC(ctx, cf_flow, 1);
    if (!flow) return CF_ERR_NOMEM;
    flow->ctx = ctx;
    flow->mesh = mesh;
    flow->options = *options;
    flow->positions = CFI_ALLOC(ctx, double, 3 * (size_t)nv);
    flow->saved_positions = CFI_ALLOC(ctx, double, 3 * (size_t)nv);
    if (!flow->positions || !flow->saved_positions) {
        cf_flow_destroy(&flow);
        return CF_ERR_NOMEM;
    }
    memcpy(flow->positions, start, 3 * (size_t)nv * sizeof(double));
    memcpy(flow->saved_positions, start, 3 * (size_t)nv * sizeof(double));

    double area = 0.0, volume = 0.0;
    cf_status st = cf_total_area(ctx, mesh, flow->positions, &area);
    if (st == CF_OK) st = cf_enclosed_volume(ctx, mesh, flow->positions, &volume);
    if (st != CF_OK) {
        cf_flow_destroy(&flow);
        return st;
    }
    flow->initial_area = area;
    flow->initial_volume = volume;

    st = policy_init(flow, m);
    if (st != CF_OK) {
        cf_flow_destroy(&flow);
        return st;
    }

    /* Only now is the method attached, so that destroy calls its destructor
     * exactly when its create has run (it must accept a partial state). */
    flow->method = m;
    if (m->per_component && mesh->component_count > 1) {
        st = cfi_flow_create_parts(flow);
        if (st != CF_OK) {
            cf_flow_destroy(&flow);
            return st;
        }
        *out = flow;
        return CF_OK;
    }
    st = m->create(flow, flow->options.storage.bytes);
    if (st != CF_OK) {
        cf_flow_destroy(&flow);
        return st;
    }
    flow->info.iteration = 0;
    flow->info.time = 0.0;
    flow->info.area = area;
    flow->info.volume = volume;
    flow->info.area_drift = 0.0;
    flow->info.volume_drift = 0.0;
    if (!isfinite(flow->info.energy)) {
        cf_flow_destroy(&flow);
        return cfi_error(ctx, CF_ERR_NUMERICAL, "%s: initial energy is not finite", m->name);
    }
    flow->policy.initial_energy = flow->info.energy;
    *out = flow;
    return CF_OK;
}

/* A successful step leaves a surface that passes the mesh check's geometric
 * tests (the connectivity cannot change): no zero-area face (the check's
 * scale-free test) and no face shrunk below the range of lengths. Otherwise
 * the state written as the result would not load again. */
static cf_status check_faces(cf_flow *flow)
{
    const cf_mesh *mesh = flow->mesh;
    const double *x = flow->positions;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * (int64_t)f;
        double longest2 = 0.0;
        double area = cfi_triangle_area(x + 3 * (int64_t)t[0], x + 3 * (int64_t)t[1], x + 3 * (int64_t)t[2], &longest2);
        if (longest2 < CF_MIN_EDGE_LENGTH * CF_MIN_EDGE_LENGTH)
            return cfi_error(flow->ctx, CF_ERR_NUMERICAL,
                             "face %d: shrank below the range of lengths (%.0e); the result would not load again", f,
                             CF_MIN_EDGE_LENGTH);
        if (!(area > CFI_ZERO_AREA_RATIO * longest2))
            return cfi_error(flow->ctx, CF_ERR_NUMERICAL,
                             "face %d: degenerated to zero area (the result would fail the mesh check)", f);
    }
    return CF_OK;
}

/* After a failed step: put the last good state back (the positions, and
 * the policy's step as it was at the start of the step), let the method
 * resynchronise, and keep the step's status and message (prefixed with the
 * iteration). */
static cf_status fail_step(cf_flow *flow, cf_status status, int64_t iteration, double start_step)
{
    cf_context *ctx = flow->ctx;
    int32_t nv = flow->mesh->nv;
    char message[CF_MESSAGE_CAPACITY];
    memcpy(message, ctx->message, sizeof message);
    memcpy(flow->positions, flow->saved_positions, 3 * (size_t)nv * sizeof(double));
    flow->policy.step = start_step;
    if (flow->method->reset) (void)flow->method->reset(flow);
    memcpy(ctx->message, message, sizeof message);
    ctx->last_status = status;
    cfi_error_prefix(ctx, "iteration %lld", (long long)iteration);
    return status;
}

/* A method's hook failed: a failure that records no message gets one, and
 * a face that degenerates during a step is a numerical failure of the flow
 * (the input passed the mesh check at creation), not bad input. */
static cf_status fail_method(cf_flow *flow, cf_status st, int64_t iteration, double start_step)
{
    if (flow->ctx->last_status == CF_OK)
        cfi_error(flow->ctx, st, "%s step failed (%s)", flow->method->name, cf_status_name(st));
    if (st == CF_ERR_DEGENERATE_FACE || st == CF_ERR_BAD_MESH) st = CF_ERR_NUMERICAL;
    return fail_step(flow, st, iteration, start_step);
}

/* The policy rejected a rising step and may not retry it (no backtracking):
 * the failure names the energies, the step and what may help. */
static cf_status fail_rise(cf_flow *flow, double before, const cf_flow_info *step, int64_t iteration,
                           double start_step)
{
    const cfi_flow_method *m = flow->method;
    cfi_error(flow->ctx, CF_ERR_NUMERICAL, "%s: energy rose from %.9g to %.9g (time step %g): %s", m->name, before,
              step->energy, step->time_step,
              m->policy.rise_hint ? m->policy.rise_hint
                                  : "a smaller time_step or backtrack=true may help; energy_check=false accepts rising "
                                    "steps");
    return fail_step(flow, CF_ERR_NUMERICAL, iteration, start_step);
}

/* The run stops at the state before the step (already restored), which
 * does not count as a step: the flow reports convergence and a warning
 * says why the run ends early. `tried` is the step of the last attempt. */
static cf_status stop_at_start(cf_flow *flow, double before, const cf_flow_info *step, int64_t iteration,
                               double tried, cf_flow_info *info)
{
    cf_context *ctx = flow->ctx;
    flow->converged = 1;
    if (!flow->policy.backtrack)
        cfi_log(ctx, CF_LOG_WARNING,
                "iteration %lld: %s: stopped: the step raised the energy (%.9g -> %.9g); the state before it is kept "
                "(energy_check=false accepts rising steps)",
                (long long)iteration, flow->method->name, before, step->energy);
    else
        cfi_log(ctx, CF_LOG_WARNING,
                "iteration %lld: %s: stopped: the energy rises (%.9g -> %.9g) at every time step down to %g "
                "(time_step / %.0f); the last state that lowered it is kept (energy_check=false accepts rising steps)",
                (long long)iteration, flow->method->name, before, step->energy, step->time_step,
                flow->policy.full_step / tried);
    if (info) *info = flow->info;
    return CF_OK;
}

/* Why the policy rejected an attempt. */
enum { ACCEPTED, REJECT_RISE, REJECT_METHOD, REJECT_FAILURE };

/* The policy's rise test of a step from `before` to `after`. */
static int rose(const cf_flow *flow, double before, double after)
{
    if (flow->method->policy.rise_exact) return cfi_step_policy_exceeds(after, before, 0.0, 0.0);
    return cfi_step_policy_rose(&flow->policy, before, after);
}

/* After a rejected attempt: the positions of the step's start, the method
 * resynchronised (its energy is the one before the step again). */
static cf_status back_to_start(cf_flow *flow)
{
    const cfi_flow_method *m = flow->method;
    memcpy(flow->positions, flow->saved_positions, 3 * (size_t)flow->mesh->nv * sizeof(double));
    if (m->revert) return m->revert(flow);
    return m->reset ? m->reset(flow) : CF_OK;
}

/* The policy's checks of an accepted step (also of a stall, at the state
 * before it): a blow-up (energy above blowup_factor times the energy
 * before the step) and a divergence (above divergence_factor times the
 * starting energy) are numerical failures, whatever the rise check said:
 * a method that allows single rising steps (spin-willmore without
 * `adaptive`, an explicit flow with energy_check=false) fails cleanly
 * instead of going on from an exploded state. CF_OK or CF_ERR_NUMERICAL
 * with the message (the caller restores the state). */
static cf_status check_energy_jumps(cf_flow *flow, double before, const cf_flow_info *step)
{
    const cfi_flow_method *m = flow->method;
    const cfi_step_policy_state *pol = &flow->policy;
    if (cfi_step_policy_blew_up(pol, before, step->energy, pol->blowup_factor))
        return cfi_error(flow->ctx, CF_ERR_NUMERICAL,
                         "%s: energy grew from %.6g to %.6g in one step (more than %gx): the step blew up; try a "
                         "smaller time_step",
                         m->name, before, step->energy, pol->blowup_factor);
    if (cfi_step_policy_diverged(pol, step->energy, pol->initial_energy, pol->divergence_factor)) {
        /* shown in the unit of the floor when it is 4pi (W/4pi: 1 for a round sphere) */
        int per_4pi = m->policy.unit == CFI_ENERGY_UNIT_4PI;
        double shown = per_4pi ? pol->unit : 1.0;
        const char *hint = m->policy.divergence_hint;
        return cfi_error(flow->ctx, CF_ERR_NUMERICAL,
                         "%s: %s%s rose to %.6g, above %g times its starting value %.6g: the flow diverges "
                         "(time_step %g%s); try a smaller time_step%s%s",
                         m->name, m->policy.energy_name ? m->policy.energy_name : "the energy", per_4pi ? "/4pi" : "",
                         step->energy / shown, pol->divergence_factor, pol->initial_energy / shown, step->time_step,
                         m->policy.divergence_cause ? m->policy.divergence_cause : "", hint ? ", " : "",
                         hint ? hint : "");
    }
    return CF_OK;
}

/* A round of halvings that searches (option halving_search, for a method
 * whose descriptor allows it): a rise at step t after rises at 2 t and 4 t
 * that each shrank like a first-order rise (rise_halved_as_first_order)
 * says the rise is unlikely to turn into a descent within the halvings
 * left. The round then tries the smallest step it may reach, t 2^-j with j
 * the halvings left, first. If that is rejected too, the round ends there
 * (the method's fallback or a stall) as it would have after trying every
 * step in between; if it is accepted, a bisection on the exponent finds
 * the smallest exponent whose attempt is accepted. Where acceptance is
 * monotone in the step (every attempt below the first accepted one is
 * accepted), that is the step plain halving takes, so the result is the
 * same and only the rejected attempts in between are saved. A failed
 * attempt (no factorisation, a degenerate face) ends the search: plain
 * halving goes on from t. */
typedef struct halving_search {
    int active;
    double step;      /* t: the last step of the plain halving, rejected (exponent 0) */
    int32_t halvings; /* the halvings counted at t */
    int32_t lo;       /* the largest exponent whose attempt was rejected */
    int32_t hi;       /* the smallest exponent whose attempt was accepted, -1: none yet */
    int32_t j;        /* the exponent of the attempt under way */
    double slope;     /* the first-order term of the rise at t, per unit step (rise_slope) */
} halving_search;

/* Whether a halving shrank a rise as a first-order rise shrinks: rise at
 * step t and last_rise at 2 t (the attempt just before), both above
 * rounding (1e-8 |before|), with last_rise / rise in [1.5, 3.5]. With the
 * rise modelled as a t + b t^2, that ratio is 4 (a + b t) / (2 a + b t):
 * 2 where the first-order term dominates, 4 where the second-order one
 * does, above 4 when a < 0 (a descent at small enough steps) and b > 0.
 * The band keeps away from 4, and from the ratios below 1.5 of rises that
 * do not follow the model at all (a rise that grows when the step is
 * halved). */
/* The search's next attempt, of exponent j, from the step's start. */
static cf_status search_probe(cf_flow *flow, halving_search *search, int32_t j)
{
    search->j = j;
    flow->policy.step = ldexp(search->step, -j);
    return back_to_start(flow);
}

/* a of the rise a s + b s^2 through rise at step t and last_rise at 2 t. */
static double rise_slope(double last_rise, double rise, double step) { return (4.0 * rise - last_rise) / (2.0 * step); }

static int rise_halved_as_first_order(double last_rise, double last_rise_step, double rise, double step, double before)
{
    double noise = 1e-8 * fabs(before);
    return isfinite(last_rise) && isfinite(rise) && step == 0.5 * last_rise_step && rise > noise &&
           last_rise >= 1.5 * rise && last_rise <= 3.5 * rise;
}

/* One step under the shared safety net and step policy. The method's
 * begin_step (if any), then attempts (its attempt, or its whole step) at
 * the policy's current step. An attempt is rejected when the method says
 * so (its verdict), when the step fails to factorise or degenerates a face
 * (CF_ERR_NOT_POSDEF, CF_ERR_DEGENERATE_FACE) while backtracking, or when
 * it raises the energy beyond rise_tolerance and energy_floor (rise_exact:
 * at all) and the rise check applies. An accepted attempt must also leave
 * finite positions, faces that pass the mesh check and a finite energy, or
 * the step fails. With backtracking a rejected attempt is redone from the
 * saved state with half the step (or less, as the method's verdict asks),
 * up to the limit max_halvings sets; at the limit a failure fails and a
 * rise or the method's rejection is a stall: the run stops as converged at
 * the state before the step, unless the method's fallback switches to
 * another variant of its attempt, which then gets the same halvings from
 * the full step or the smaller step the method asks for (asked again at
 * that variant's stall, at most 4 times per step).
 * Without backtracking a rise fails (or, with rise_stops, stops the run). The accepted step (after the method's
 * end_step) then passes the blow-up and divergence checks or fails
 * (check_energy_jumps). After an accepted step without retries a reduced
 * step grows back by step_growth unless the method's verdict holds it
 * (hold_step); the convergence tolerance is tested. */
cf_status cf_flow_step(cf_flow *flow, cf_flow_info *info)
{
    if (!flow) return CF_ERR_INVALID_ARG;
    if (flow->parts) return cfi_flow_step_parts(flow, info);
    cf_context *ctx = flow->ctx;
    const cfi_flow_method *m = flow->method;
    int32_t nv = flow->mesh->nv;
    int64_t iteration = flow->info.iteration + 1;
    double t0 = cfi_now_seconds();
    const cfi_step_policy_desc *desc = &m->policy;
    cfi_step_policy_state *pol = &flow->policy;
    double before = flow->info.energy;
    double start_step = pol->step;
    int32_t halvings = 0;
    int stalled = 0, fell_back = 0;
    int32_t hold_step = 0;
    /* the rise of the round's last attempt, if it was rejected for a rise,
     * its step, and how many halvings in a row shrank the rise like a
     * first-order one (halving_search) */
    double last_rise = NAN, last_rise_step = 0.0;
    int32_t first_order_halvings = 0;
    halving_search search = {0, 0.0, 0, 0, -1, 0, 0.0};
    cf_status st = CF_OK;

    memcpy(flow->saved_positions, flow->positions, 3 * (size_t)nv * sizeof(double));
    cf_flow_info step;
    memset(&step, 0, sizeof step);
    step.iteration = iteration;
    if (m->begin_step) {
        cf_context_clear_error(ctx);
        st = m->begin_step(flow, &step);
        if (st != CF_OK) return fail_method(flow, st, iteration, start_step);
    }
    for (;;) {
        if (!m->begin_step) {
            memset(&step, 0, sizeof step);
            step.iteration = iteration;
        }
        cfi_step_verdict verdict = {0, 0.5, 0};
        /* so that a failing method that records no message is noticed */
        cf_context_clear_error(ctx);
        st = m->attempt ? m->attempt(flow, pol->step, &step, &verdict) : m->step(flow, &step);
        ++flow->attempts;
        hold_step = verdict.hold_step; /* the accepted attempt's is the one that counts */
        int reason = ACCEPTED;
        if (st != CF_OK) {
            /* a matrix that does not factorise, or a face that degenerates,
             * at this step may not at a smaller one */
            if (!pol->backtrack || (st != CF_ERR_NOT_POSDEF && st != CF_ERR_DEGENERATE_FACE))
                return fail_method(flow, st, iteration, start_step);
            if (ctx->last_status == CF_OK)
                cfi_error(ctx, st, "%s step failed (%s)", m->name, cf_status_name(st));
            reason = REJECT_FAILURE;
        } else if (verdict.rejected) {
            reason = REJECT_METHOD;
        } else {
            /* a result that would not load again (non-finite, a face of zero
             * area) is a failed attempt: with backtracking it is retried at
             * a smaller step like a failed factorisation, else the step fails */
            cf_status valid = check_positions(ctx, flow->positions, nv, CF_ERR_NUMERICAL, "position");
            if (valid == CF_OK) valid = check_faces(flow);
            if (valid == CF_OK && !isfinite(step.energy))
                valid = cfi_error(ctx, CF_ERR_NUMERICAL, "energy is %s", isnan(step.energy) ? "NaN" : "infinite");
            if (valid != CF_OK) {
                if (!pol->backtrack) return fail_step(flow, CF_ERR_NUMERICAL, iteration, start_step);
                st = CF_ERR_NUMERICAL;
                reason = REJECT_FAILURE;
            } else if (!pol->rise_check || !rose(flow, before, step.energy)) {
                if (!search.active) break;
                /* the search found an accepted step: it is the round's
                 * answer once no larger one is left to try */
                search.hi = search.j;
                if (search.hi - search.lo <= 1) {
                    halvings = search.halvings + search.hi;
                    break;
                }
                st = search_probe(flow, &search, (search.lo + search.hi) / 2);
                if (st != CF_OK) return fail_method(flow, st, iteration, start_step);
                continue;
            } else {
                reason = REJECT_RISE;
            }
        }
        if (!pol->backtrack) {
            if (CF_NEVER(reason != REJECT_RISE)) {
                cfi_error(ctx, CF_ERR_NUMERICAL, "%s: step rejected without backtracking", m->name);
                return fail_step(flow, CF_ERR_NUMERICAL, iteration, start_step);
            }
            if (!desc->rise_stops) return fail_rise(flow, before, &step, iteration, start_step);
            st = back_to_start(flow);
            if (st != CF_OK) return fail_method(flow, st, iteration, start_step);
            return stop_at_start(flow, before, &step, iteration, pol->step, info);
        }
        /* max_halvings bounds the step against the full step, not per step
         * (or a run near its minimum would creep on with ever smaller
         * steps): when no step down to time_step / 2^max_halvings lowers the
         * energy, the run stops at the last state that did, as converged
         * (the flow has reached the state its step can lower no further: the
         * round sphere of the bi-Laplacian flow, a state from which the
         * frozen-operator step is no descent direction). A method with
         * halvings_per_step counts the retries of each step instead. */
        int at_limit = desc->halvings_per_step ? halvings >= pol->opt.max_halvings
                                               : pol->step <= pol->full_step * ldexp(1.0, -pol->opt.max_halvings);
        if (search.active) {
            if (reason == REJECT_FAILURE || search.j == search.hi) {
                /* a failed attempt, or the accepted step of the search that
                 * does not repeat: the plain halving from where the search
                 * began */
                search.active = 0;
                pol->step = search.step;
                halvings = search.halvings;
            } else {
                search.lo = search.j;
                double rise = step.energy - before, expected = search.slope * pol->step;
                if (search.hi < 0 && reason == REJECT_RISE && rise >= 0.5 * expected && rise <= 2.0 * expected) {
                    /* the smallest step rose as the first-order term
                     * predicts: the round's end, as if every halving down
                     * to it had been tried */
                    halvings = search.halvings + search.j;
                    at_limit = 1;
                } else if (search.hi < 0) {
                    /* rejected otherwise (a rise the model does not
                     * predict: rounding of the step at tiny tau, or a
                     * rise that bends): plain halving from t */
                    search.active = 0;
                    pol->step = search.step;
                    halvings = search.halvings;
                } else {
                    /* between the largest rejected and the smallest
                     * accepted; the latter again when they are adjacent */
                    st = search_probe(flow, &search,
                                      search.hi - search.lo <= 1 ? search.hi : (search.lo + search.hi) / 2);
                    if (st != CF_OK) return fail_method(flow, st, iteration, start_step);
                    continue;
                }
            }
            last_rise = NAN;
            first_order_halvings = 0;
        } else if (reason == REJECT_RISE && desc->halving_search && desc->halvings_per_step && pol->opt.halving_search) {
            double rise = step.energy - before, last_rise_before = last_rise;
            first_order_halvings = rise_halved_as_first_order(last_rise, last_rise_step, rise, pol->step, before)
                                       ? first_order_halvings + 1
                                       : 0;
            last_rise = rise;
            last_rise_step = pol->step;
            int32_t left = pol->opt.max_halvings - halvings;
            if (first_order_halvings >= 2 && left >= 2) {
                /* the rises look as if they persist down to the limit: the
                 * smallest step first (halving_search) */
                double slope = rise_slope(last_rise_before, rise, pol->step);
                search = (halving_search){1, pol->step, halvings, 0, -1, 0, slope};
                st = search_probe(flow, &search, left);
                if (st != CF_OK) return fail_method(flow, st, iteration, start_step);
                continue;
            }
        } else {
            last_rise = NAN;
            first_order_halvings = 0;
        }
        if (at_limit && reason == REJECT_FAILURE) {
            if (halvings > 0)
                cfi_error_prefix(ctx, "at every time step down to %g (time_step / %.0f)", pol->step,
                                 pol->full_step / pol->step);
            return fail_method(flow, st, iteration, start_step);
        }
        st = back_to_start(flow);
        if (st != CF_OK) return fail_method(flow, st, iteration, start_step);
        if (at_limit && m->fallback && fell_back < 4) {
            /* the method's other variant of the step, from the full step
             * or the smaller step the method asks for */
            int32_t switched = 0;
            double restart_step = pol->full_step;
            cf_context_clear_error(ctx);
            st = m->fallback(flow, &switched, &restart_step);
            if (st != CF_OK) return fail_method(flow, st, iteration, start_step);
            ++fell_back;
            if (switched) {
                pol->step = restart_step > 0.0 && restart_step < pol->full_step ? restart_step : pol->full_step;
                halvings = 0;
                last_rise = NAN;
                first_order_halvings = 0;
                search.active = 0;
                continue;
            }
        }
        if (at_limit) {
            stalled = 1;
            break;
        }
        pol->step *= reason == REJECT_METHOD ? fmin(0.5, verdict.shrink) : 0.5;
        ++halvings;
    }
    if (stalled) {
        double tried = pol->step;
        /* the next step (after new positions, or a caller stepping on) starts where this one did */
        pol->step = start_step;
        if (!desc->stall_as_step) return stop_at_start(flow, before, &step, iteration, tried, info);
        const char *term = flow->info.term_names[0];
        cfi_log(ctx, CF_LOG_INFO, "%s: %s does not decrease for any time step down to %g; stopping at %s = %.6g",
                m->name, desc->energy_name ? desc->energy_name : "the energy", tried, term ? term : "energy",
                term ? flow->info.energy_terms[0] : flow->info.energy);
    }
    if (m->end_step) {
        cf_context_clear_error(ctx);
        st = m->end_step(flow, &step);
        if (st != CF_OK) return fail_method(flow, st, iteration, start_step);
    }
    if (check_energy_jumps(flow, before, &step) != CF_OK) return fail_step(flow, CF_ERR_NUMERICAL, iteration, start_step);
    if (stalled) {
        /* an accepted step of time step 0 at the state before it */
        step.time_step = 0.0;
        flow->converged = 1;
    }
    st = cfi_flow_measure(flow, &step);
    if (st != CF_OK) return fail_step(flow, st, iteration, start_step);
    if (!isfinite(step.area) || !isfinite(step.volume)) {
        cfi_error(ctx, CF_ERR_NUMERICAL, "area or volume is not finite");
        return fail_step(flow, CF_ERR_NUMERICAL, iteration, start_step);
    }
    if (pol->backtrack) {
        /* in the log: the first free residual slot */
        for (int r = 0; r < CF_FLOW_MAX_RESIDUALS; ++r) {
            if (step.residual_names[r]) continue;
            step.residuals[r] = halvings;
            step.residual_names[r] = "time_step_halvings";
            break;
        }
        if (halvings == 0 && !stalled && !hold_step)
            pol->step = fmin(pol->full_step, pol->step * pol->opt.step_growth);
    }
    if (desc->convergence && cfi_step_policy_converged(before, step.energy, pol->tolerance)) flow->converged = 1;
    return cfi_flow_accept_step(flow, &step, info, t0);
}

cf_status cfi_flow_accept_step(cf_flow *flow, cf_flow_info *step, cf_flow_info *info, double t0)
{
    step->iteration = flow->info.iteration + 1;
    step->time = flow->info.time + step->time_step;
    step->total_seconds = cfi_now_seconds() - t0;
    flow->info = *step;
    if (info) *info = *step;
    if (flow->progress && flow->progress(flow->progress_user, &flow->info) != 0)
        return cfi_error(flow->ctx, CF_ERR_CANCELLED, "iteration %lld: cancelled by the progress callback",
                         (long long)step->iteration);
    return CF_OK;
}

cf_status cf_flow_run(cf_flow *flow, int64_t steps, cf_flow_info *info)
{
    if (!flow) return CF_ERR_INVALID_ARG;
    if (steps < 0) return cfi_error(flow->ctx, CF_ERR_INVALID_ARG, "steps must be >= 0, got %lld", (long long)steps);
    cf_status st = CF_OK;
    for (int64_t i = 0; i < steps && !flow->converged; ++i) {
        st = cf_flow_step(flow, NULL);
        if (st != CF_OK) break;
    }
    if (info) *info = flow->info;
    return st;
}

void cf_flow_set_progress(cf_flow *flow, cf_progress_fn fn, void *user)
{
    if (!flow) return;
    flow->progress = fn;
    flow->progress_user = user;
}

const double *cf_flow_positions(const cf_flow *flow) { return flow ? flow->positions : NULL; }

cf_status cf_flow_set_positions(cf_flow *flow, const double *positions)
{
    if (!flow) return CF_ERR_INVALID_ARG;
    cf_context *ctx = flow->ctx;
    if (!positions) return cfi_error(ctx, CF_ERR_INVALID_ARG, "positions are NULL");
    int32_t nv = flow->mesh->nv;
    cf_status bad = check_positions(ctx, positions, nv, CF_ERR_NONFINITE, "position");
    if (bad != CF_OK) return bad;
    if (flow->parts) return cfi_flow_set_positions_parts(flow, positions);
    memcpy(flow->saved_positions, flow->positions, 3 * (size_t)nv * sizeof(double));
    memcpy(flow->positions, positions, 3 * (size_t)nv * sizeof(double));
    cf_status st = flow->method->reset ? flow->method->reset(flow) : CF_OK;
    if (st == CF_OK) st = cfi_flow_measure(flow, &flow->info);
    if (st != CF_OK) {
        char message[CF_MESSAGE_CAPACITY];
        memcpy(message, ctx->message, sizeof message);
        memcpy(flow->positions, flow->saved_positions, 3 * (size_t)nv * sizeof(double));
        if (flow->method->reset) (void)flow->method->reset(flow);
        memcpy(ctx->message, message, sizeof message);
        ctx->last_status = st;
        return st;
    }
    flow->converged = 0;
    flow->policy.step = flow->policy.full_step; /* a new state: the step policy starts from time_step again */
    flow->policy.initial_energy = flow->info.energy; /* and the divergence check from its energy */
    return CF_OK;
}

const cf_mesh *cf_flow_mesh(const cf_flow *flow) { return flow ? flow->mesh : NULL; }
cf_flow_kind cf_flow_get_kind(const cf_flow *flow) { return flow ? flow->options.kind : CF_FLOW_KIND_COUNT; }
double cf_flow_energy(const cf_flow *flow) { return flow ? flow->info.energy : NAN; }
const cf_flow_info *cf_flow_last_info(const cf_flow *flow) { return flow ? &flow->info : NULL; }
int32_t cf_flow_converged(const cf_flow *flow) { return flow ? flow->converged : 0; }

cf_status cf_flow_apply(cf_context *ctx, const cf_mesh *mesh, const cf_flow_options *options, int64_t steps,
                        double *out_positions, cf_flow_info *info)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out_positions) return cfi_error(ctx, CF_ERR_INVALID_ARG, "out_positions is NULL");
    cf_flow *flow = NULL;
    cf_status st = cf_flow_create(ctx, mesh, NULL, options, &flow);
    if (st != CF_OK) return st;
    st = cf_flow_run(flow, steps, info);
    /* The state reached is returned also on failure (it is the last good one). */
    memcpy(out_positions, flow->positions, 3 * (size_t)mesh->nv * sizeof(double));
    cf_flow_destroy(&flow);
    return st;
}
