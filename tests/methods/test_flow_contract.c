/*
 * The flow contract (issue 12 item 5), checked for EVERY kind of the
 * registry (0 .. CF_FLOW_KIND_COUNT - 1), so a new method is covered by
 * adding it to the registry: its table's defaults lie inside the table's
 * ranges; every scalar parameter survives format -> set bit for bit; a
 * struct field set by hand out of range is refused by cf_flow_create with a
 * message naming the parameter; an array parameter of the wrong size is
 * refused naming the parameter and the expected count; create fails
 * cleanly (CF_ERR_NOMEM, nothing leaked) whatever allocation fails; steps
 * do not allocate; a failed step leaves the state it started from; and
 * every scalar parameter at each end of its listed range (both limits, the
 * other bool, every choice) creates and steps cleanly on four small meshes
 * (closed, torus, disk, a band without interior vertex), or is refused for
 * what the mesh cannot take, never as out of range.
 *
 * Fixture hooks (fixture_for): what a kind needs beyond its defaults (the
 * edit flow's handles) and how to make one of its steps fail. A new kind
 * needs a hook only if its defaults cannot create a flow on the icosphere.
 */
#include "curvflow/constraints.h"
#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/stretch_bend_edit.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct fixture {
    const cf_mesh *mesh;
    cf_handle_set *handles; /* edit: one vertex fixed, one moved */
} fixture;

/* Hook: fills what the kind's defaults lack (the options already hold the
 * defaults). */
static void fixture_options(cf_flow_kind kind, fixture *fx, cf_flow_options *o)
{
    if (kind == CF_FLOW_STRETCH_BEND_EDIT) {
        cf_stretch_bend_options *so = cf_flow_options_method_as(o, CF_FLOW_STRETCH_BEND_EDIT);
        CHECK(so != NULL);
        if (so) so->handles = fx->handles;
    }
}

static cf_handle_set *make_handles(cf_context *ctx, const cf_mesh *mesh)
{
    const double *x = cf_mesh_positions(mesh);
    int32_t nv = cf_mesh_vertex_count(mesh);
    int32_t v[2] = {0, nv - 1};
    double t[6] = {x[0], x[1], x[2], x[3 * (nv - 1)] + 0.1, x[3 * (nv - 1) + 1], x[3 * (nv - 1) + 2]};
    cf_handle_set *h = NULL;
    CHECK_OK(ctx, cf_handle_set_create(ctx, 2, v, t, &h));
    return h;
}

static size_t field_size(cf_param_type t)
{
    if (t == CF_PARAM_DOUBLE) return sizeof(double);
    if (t == CF_PARAM_POINT_SETS) return sizeof(void *);
    if (cf_param_type_is_array(t)) return sizeof(cf_param_values);
    return sizeof(int32_t);
}

static int choice_count(const cf_param_desc *p)
{
    int n = 0;
    while (p->choices && p->choices[n]) ++n;
    return n;
}

/* Defaults inside the ranges; format -> set round trip of every scalar
 * parameter, at the default and at both limits. */
static void check_table(cf_context *ctx, cf_flow_kind kind)
{
    const char *name = cf_flow_kind_name(kind);
    const cf_param_desc *params = NULL;
    int32_t count = 0;
    CHECK_OK(ctx, cf_flow_params(kind, &params, &count));
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(kind, &o));
    unsigned char *base = cf_flow_options_method_as(&o, kind);
    CHECK(base != NULL);
    CHECK(cf_flow_options_method_as(&o, (cf_flow_kind)((kind + 1) % CF_FLOW_KIND_COUNT)) == NULL);
    if (!base) return;
    for (int32_t i = 0; i < count; ++i) {
        const cf_param_desc *p = &params[i];
        CHECK(cf_param_type_name(p->type) != NULL);
        char text[128], range[256];
        CHECK_OK(ctx, cf_flow_param_range_format(p, range, sizeof range));
        CHECK_OK(ctx, cf_flow_options_format(&o, p, text, sizeof text));
        if (cf_param_type_is_array(p->type)) {
            /* arrays carry data: text is refused, naming the parameter */
            CHECK_STATUS(cf_flow_options_set(ctx, &o, p->name, "x.txt"), CF_ERR_INVALID_ARG);
            CHECK(strstr(cf_context_message(ctx), p->name) != NULL);
            continue;
        }
        double def = 0.0;
        int32_t iv = 0;
        if (p->type == CF_PARAM_DOUBLE) memcpy(&def, base + p->offset, sizeof def);
        else {
            memcpy(&iv, base + p->offset, sizeof iv);
            def = iv;
        }
        int inside = p->type == CF_PARAM_BOOL     ? (iv == 0 || iv == 1)
                     : p->type == CF_PARAM_CHOICE ? (iv >= 0 && iv < choice_count(p))
                                                  : (def >= p->min_value && def <= p->max_value);
        if (!inside) fprintf(stderr, "   %s: default of '%s' (%s) is outside %s\n", name, p->name, text, range);
        CHECK(inside);
        /* the default, then the limits (numbers), read back bit for bit */
        double probes[3] = {def, p->min_value, p->max_value};
        int nprobes = (p->type == CF_PARAM_DOUBLE || p->type == CF_PARAM_INT) ? 3 : 1;
        for (int k = 0; k < nprobes; ++k) {
            unsigned char before[sizeof(double)];
            if (p->type == CF_PARAM_DOUBLE) memcpy(base + p->offset, &probes[k], sizeof(double));
            else if (k > 0) {
                int32_t v = (int32_t)probes[k];
                memcpy(base + p->offset, &v, sizeof v);
            }
            memcpy(before, base + p->offset, field_size(p->type));
            CHECK_OK(ctx, cf_flow_options_format(&o, p, text, sizeof text));
            memset(base + p->offset, 0x5a, field_size(p->type));
            CHECK_OK(ctx, cf_flow_options_set(ctx, &o, p->name, text));
            int same = memcmp(before, base + p->offset, field_size(p->type)) == 0;
            if (!same) fprintf(stderr, "   %s: '%s' = %s does not read back\n", name, p->name, text);
            CHECK(same);
        }
        memcpy(base + p->offset, p->type == CF_PARAM_DOUBLE ? (const void *)&def : (const void *)&iv,
               field_size(p->type));
    }
}

/* A field set by hand out of range: refused by create, naming the parameter. */
static void check_create_validates(cf_context *ctx, cf_flow_kind kind, fixture *fx)
{
    const char *name = cf_flow_kind_name(kind);
    const cf_param_desc *params = NULL;
    int32_t count = 0;
    CHECK_OK(ctx, cf_flow_params(kind, &params, &count));
    int refused = 0;
    for (int32_t i = 0; i < count; ++i) {
        const cf_param_desc *p = &params[i];
        cf_flow_options o;
        CHECK_OK(ctx, cf_flow_options_default(kind, &o));
        fixture_options(kind, fx, &o);
        unsigned char *base = cf_flow_options_method_as(&o, kind);
        if (p->type == CF_PARAM_DOUBLE) {
            if (!(fabs(p->max_value) < 1e300)) continue;
            double v = p->max_value + fmax(1.0, fabs(p->max_value));
            memcpy(base + p->offset, &v, sizeof v);
        } else if (p->type == CF_PARAM_INT) {
            if (p->max_value >= 2147483647.0) continue;
            int32_t v = (int32_t)p->max_value + 1;
            memcpy(base + p->offset, &v, sizeof v);
        } else if (p->type == CF_PARAM_BOOL || p->type == CF_PARAM_CHOICE) {
            int32_t v = p->type == CF_PARAM_BOOL ? 2 : choice_count(p);
            memcpy(base + p->offset, &v, sizeof v);
        } else if (p->type == CF_PARAM_POINT_SETS) {
            if (p->min_value < 1.0) continue;
            const cf_handle_set *none = NULL; /* required but not given */
            memcpy(base + p->offset, &none, sizeof none);
        } else {
            /* one element short of the mesh */
            static const double dummy[3] = {1.0, 0.0, 0.0};
            int32_t n = p->type == CF_PARAM_FACE_SCALARS ? cf_mesh_face_count(fx->mesh) : cf_mesh_vertex_count(fx->mesh);
            cf_param_values v = {dummy, n - 1};
            memcpy(base + p->offset, &v, sizeof v);
        }
        cf_flow *flow = NULL;
        cf_status st = cf_flow_create(ctx, fx->mesh, NULL, &o, &flow);
        CHECK_STATUS(st, CF_ERR_INVALID_ARG);
        CHECK(flow == NULL);
        char quoted[160];
        snprintf(quoted, sizeof quoted, "parameter '%s'", p->name);
        int named = strstr(cf_context_message(ctx), quoted) != NULL;
        if (!named) fprintf(stderr, "   %s: '%s' out of range: message '%s'\n", name, p->name, cf_context_message(ctx));
        CHECK(named);
        if (p->type == CF_PARAM_VERTEX_SCALARS || p->type == CF_PARAM_VERTEX_VECTORS) {
            char expected[64];
            snprintf(expected, sizeof expected, "expected %d", (int)cf_mesh_vertex_count(fx->mesh));
            CHECK(strstr(cf_context_message(ctx), expected) != NULL);
        }
        cf_flow_destroy(&flow);
        ++refused;
    }
    fprintf(stderr, "   %-22s %d of %d parameters refused out of range by create\n", name, refused, (int)count);
}

typedef struct create_call {
    const cf_mesh *mesh;
    const cf_flow_options *options;
} create_call;

static cf_status call_create(cf_context *ctx, void *user)
{
    const create_call *c = user;
    cf_flow *flow = NULL;
    cf_status st = cf_flow_create(ctx, c->mesh, NULL, c->options, &flow);
    if (st != CF_OK && flow) st = CF_ERR_INVALID_ARG; /* failed but left an object */
    cf_flow_destroy(&flow);
    return st;
}

/* Steps allocate nothing; a failed step keeps the state before it. */
static void check_steps(cf_context *ctx, cf_flow_kind kind, fixture *fx, const cf_flow_options *o)
{
    const char *name = cf_flow_kind_name(kind);
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, fx->mesh, NULL, o, &flow));
    if (!flow) return;
    int64_t before = cf_context_allocation_count(ctx);
    size_t bytes = cf_context_bytes_in_use(ctx);
    for (int i = 0; i < 3; ++i) CHECK_OK(ctx, cf_flow_step(flow, NULL));
    int64_t allocs = cf_context_allocation_count(ctx) - before;
    if (allocs != 0) fprintf(stderr, "   %s: %lld allocations in 3 steps\n", name, (long long)allocs);
    CHECK(allocs == 0);
    CHECK(cf_context_bytes_in_use(ctx) == bytes);

    /* Provoke a failing step: edit loses its system (an allocation failure
     * while new handles are set up); the others take their largest time step
     * until a step fails (at most 12 tries). */
    int32_t nv = cf_mesh_vertex_count(fx->mesh);
    double *x = malloc(3 * sizeof(double) * (size_t)nv);
    int failed = 0;
    if (kind == CF_FLOW_STRETCH_BEND_EDIT) {
        cf_context_fail_allocation(ctx, 1, 1);
        cf_status st = cf_stretch_bend_set_handles(flow, fx->handles);
        cf_context_fail_allocation(ctx, 0, 0);
        CHECK(st != CF_OK);
    } else {
        cf_flow_options big = *o;
        const cf_param_desc *params = NULL;
        int32_t count = 0;
        CHECK_OK(ctx, cf_flow_params(kind, &params, &count));
        /* no retries with smaller steps: the method's own (spin's adaptive)
         * nor the common policy's backtracking */
        for (int32_t i = 0; i < count; ++i)
            if (strcmp(params[i].name, "adaptive") == 0) CHECK_OK(ctx, cf_flow_options_set(ctx, &big, "adaptive", "false"));
        (void)cf_flow_options_set(ctx, &big, "backtrack", "false");
        for (int32_t i = 0; i < count; ++i)
            if (strcmp(params[i].name, "time_step") == 0) {
                char text[64];
                snprintf(text, sizeof text, "%.17g", params[i].max_value);
                CHECK_OK(ctx, cf_flow_options_set(ctx, &big, "time_step", text));
            }
        /* a new flow from the current state with the large step */
        cf_flow *fast = NULL;
        CHECK_OK(ctx, cf_flow_create(ctx, fx->mesh, cf_flow_positions(flow), &big, &fast));
        cf_flow_destroy(&flow);
        flow = fast;
    }
    for (int i = 0; flow && i < 12 && !failed; ++i) {
        memcpy(x, cf_flow_positions(flow), 3 * sizeof(double) * (size_t)nv);
        cf_flow_info last = *cf_flow_last_info(flow);
        cf_status st = cf_flow_step(flow, NULL);
        if (st == CF_OK) continue;
        failed = 1;
        CHECK(memcmp(x, cf_flow_positions(flow), 3 * sizeof(double) * (size_t)nv) == 0);
        CHECK(cf_flow_last_info(flow)->iteration == last.iteration);
        CHECK(strstr(cf_context_message(ctx), "iteration") != NULL);
        fprintf(stderr, "   %-22s failed step restored: %s\n", name, cf_context_message(ctx));
    }
    if (!failed) fprintf(stderr, "   %-22s no step failed at its largest time step (restore not exercised)\n", name);
    /* every method of the registry today is provoked; a new one should be */
    CHECK(failed);
    free(x);
    cf_flow_destroy(&flow);
}

/* The probes of one scalar parameter at the ends of what its listing
 * accepts: both limits of a number, the other value of a bool, every other
 * choice. Text as the CLI takes it; returns the count. */
static int param_probes(const cf_param_desc *p, const unsigned char *base, char probes[][64])
{
    int n = 0;
    if (p->type == CF_PARAM_DOUBLE || p->type == CF_PARAM_INT) {
        snprintf(probes[n++], 64, "%.17g", p->min_value);
        snprintf(probes[n++], 64, "%.17g", p->max_value);
    } else if (p->type == CF_PARAM_BOOL) {
        int32_t v;
        memcpy(&v, base + p->offset, sizeof v);
        snprintf(probes[n++], 64, "%s", v ? "false" : "true");
    } else if (p->type == CF_PARAM_CHOICE) {
        int32_t v;
        memcpy(&v, base + p->offset, sizeof v);
        for (int c = 0; c < choice_count(p) && n < 8; ++c)
            if (c != v) snprintf(probes[n++], 64, "%s", p->choices[c]);
    }
    return n;
}

typedef struct extreme_counts {
    int runs, refused, failed;
} extreme_counts;

/* One flow with one parameter at one probe: create, two steps. What may
 * happen: a refusal at creation for what the mesh cannot take (a boundary
 * mode on a closed mesh, a filter that does not factorise), never for the
 * listed value itself; a step that fails numerically, naming its iteration
 * and keeping its state; otherwise finite positions and energy. Nothing
 * leaks. */
static void run_extreme(cf_context *ctx, cf_flow_kind kind, fixture *fx, const char *mesh_name, const char *param,
                        const char *value, extreme_counts *counts)
{
    const char *name = cf_flow_kind_name(kind);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(kind, &o));
    fixture_options(kind, fx, &o);
    /* every value the listing shows is taken */
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, param, value));
    size_t bytes = cf_context_bytes_in_use(ctx);
    cf_flow *flow = NULL;
    cf_status st = cf_flow_create(ctx, fx->mesh, NULL, &o, &flow);
    ++counts->runs;
    if (st != CF_OK) {
        ++counts->refused;
        char quoted[160];
        snprintf(quoted, sizeof quoted, "parameter '%s'", param);
        const char *msg = cf_context_message(ctx);
        /* what the mesh cannot take, or a conflict of this value with another
         * parameter's default ("parameters 'rescale' and 'boundary': ...");
         * a listed value is never refused as out of range, and an internal
         * error is not a refusal */
        int fair = (st == CF_ERR_BAD_MESH || st == CF_ERR_UNSUPPORTED || st == CF_ERR_NUMERICAL ||
                    (st == CF_ERR_INVALID_ARG && strstr(msg, "parameters '") && !strstr(msg, quoted))) &&
                   msg[0] != '\0';
        fprintf(stderr, "   %s, %s, %s=%s: refused (%s): %s\n", name, mesh_name, param, value, cf_status_name(st), msg);
        CHECK(fair);
        CHECK(flow == NULL);
        CHECK(cf_context_bytes_in_use(ctx) == bytes);
        return;
    }
    int32_t nv = cf_mesh_vertex_count(fx->mesh);
    for (int i = 0; flow && i < 2; ++i) {
        int64_t before = cf_flow_last_info(flow)->iteration;
        st = cf_flow_step(flow, NULL);
        if (st != CF_OK) {
            ++counts->failed;
            int named = st == CF_ERR_NUMERICAL && strstr(cf_context_message(ctx), "iteration") != NULL;
            if (!named)
                fprintf(stderr, "   %s, %s, %s=%s: step %d: %s: %s\n", name, mesh_name, param, value, i + 1,
                        cf_status_name(st), cf_context_message(ctx));
            CHECK(named);
            CHECK(cf_flow_last_info(flow)->iteration == before);
        }
        const double *x = cf_flow_positions(flow);
        int finite = isfinite(cf_flow_energy(flow));
        for (int64_t k = 0; k < 3 * (int64_t)nv && finite; ++k) finite = isfinite(x[k]);
        if (!finite) fprintf(stderr, "   %s, %s, %s=%s: step %d left a non-finite state\n", name, mesh_name, param, value, i + 1);
        CHECK(finite);
        if (st != CF_OK) break;
    }
    cf_flow_destroy(&flow);
    CHECK(cf_context_bytes_in_use(ctx) == bytes);
}

/* Every scalar parameter of the kind and of the common step policy at the
 * ends of its listed range, on a closed surface, a torus, a disk and a band
 * whose every vertex is on its boundary (issue
 * 13: every README promise under hostile input; session 29 found
 * boundary=fixed on a band without interior vertices failing inside the
 * Poisson solver, and implicit-mcf listing time_step 0 that it refused). */
static void check_extremes(cf_context *ctx, cf_flow_kind kind, fixture *fxs, const char *const *mesh_names, int nmesh)
{
    const cf_param_desc *tables[2];
    int32_t counts_of[2];
    CHECK_OK(ctx, cf_flow_params(kind, &tables[0], &counts_of[0]));
    CHECK_OK(ctx, cf_flow_common_params(&tables[1], &counts_of[1]));
    extreme_counts counts = {0, 0, 0};
    for (int t = 0; t < 2; ++t)
        for (int32_t i = 0; i < counts_of[t]; ++i) {
            const cf_param_desc *p = &tables[t][i];
            if (cf_param_type_is_array(p->type)) continue;
            cf_flow_options o;
            CHECK_OK(ctx, cf_flow_options_default(kind, &o));
            const unsigned char *base =
                t == 0 ? cf_flow_options_method_as(&o, kind) : (const unsigned char *)cf_flow_options_policy(&o);
            char probes[8][64];
            int n = param_probes(p, base, probes);
            for (int k = 0; k < n; ++k)
                for (int m = 0; m < nmesh; ++m) run_extreme(ctx, kind, &fxs[m], mesh_names[m], p->name, probes[k], &counts);
        }
    fprintf(stderr, "   %-22s %d runs at the ends of the listed ranges: %d refused by the mesh, %d failed a step cleanly\n",
            cf_flow_kind_name(kind), counts.runs, counts.refused, counts.failed);
    CHECK(counts.runs > 0);
}

static void test_every_kind(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &mesh));
    if (!mesh) return;
    fixture fx = {mesh, make_handles(ctx, mesh)};
    for (int k = 0; k < CF_FLOW_KIND_COUNT; ++k) {
        cf_flow_kind kind = (cf_flow_kind)k;
        fprintf(stderr, "-- kind %d: %s\n", k, cf_flow_kind_name(kind));
        check_table(ctx, kind);
        check_create_validates(ctx, kind, &fx);
        cf_flow_options o;
        CHECK_OK(ctx, cf_flow_options_default(kind, &o));
        fixture_options(kind, &fx, &o);
        create_call call = {mesh, &o};
        int64_t n = cft_allocation_sweep(ctx, cf_flow_kind_name(kind), call_create, &call, 1);
        fprintf(stderr, "   %-22s create makes %lld allocations; each failing one gives CF_ERR_NOMEM\n",
                cf_flow_kind_name(kind), (long long)n);
        CHECK(n > 0);
        check_steps(ctx, kind, &fx, &o);
    }
    cf_handle_set_destroy(&fx.handles);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_range_ends(void)
{
    cf_context *ctx = cft_context();
    enum { NMESH = 4 };
    cf_mesh *meshes[NMESH] = {NULL, NULL, NULL, NULL};
    static const char *const names[NMESH] = {"bumpy sphere", "torus", "bumpy disk", "band (no interior vertex)"};
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.25, 1u, &meshes[0]));
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.4, 16, 8, &meshes[1]));
    CHECK_OK(ctx, cf_generate_bumpy_plane(ctx, 8, 1.0, 0.1, 3u, &meshes[2]));
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 16, 1, 1.0, 2.0, &meshes[3]));
    fixture fxs[NMESH];
    int ok = 1;
    for (int m = 0; m < NMESH; ++m) {
        ok = ok && meshes[m];
        fxs[m] = (fixture){meshes[m], meshes[m] ? make_handles(ctx, meshes[m]) : NULL};
    }
    for (int k = 0; ok && k < CF_FLOW_KIND_COUNT; ++k) {
        fprintf(stderr, "-- kind %d: %s\n", k, cf_flow_kind_name((cf_flow_kind)k));
        check_extremes(ctx, (cf_flow_kind)k, fxs, names, NMESH);
    }
    for (int m = 0; m < NMESH; ++m) {
        cf_handle_set_destroy(&fxs[m].handles);
        cf_mesh_destroy(&meshes[m]);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_every_kind);
    CFT_RUN(test_range_ends);
    return cft_finish();
}
