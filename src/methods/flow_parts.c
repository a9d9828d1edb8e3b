/*
 * One flow per connected component, behind the flow of the whole mesh
 * (cfi_flow_method.per_component; flow_internal.h).
 *
 * A file with several objects is one mesh of several components. Most flows
 * act on each component alone anyway (the baselines' Laplacians are block
 * diagonal). spin-willmore does not: the smallest eigenvector of X(rho),
 * which is block diagonal too, puts its weight on the component of the
 * smallest eigenvalue, and its constraints (total curvature, inversion,
 * Moebius balancing, the area kept) are the whole surface's. Treated as one
 * surface, all but one component shrank to a point (docs/spin.md, "Several
 * connected components"). Each component is therefore its own flow: its own
 * eigenvector, constraints, time step and convergence, with the results
 * identical, bit for bit, to flowing that component alone. The flow of the
 * whole mesh keeps the positions (gathered after every step) and reports:
 *   energy and its terms: sums over the components (W, areas add up);
 *   residuals: the largest of the components' stepped this step;
 *   time_step: the largest of theirs (0 when every one stalled);
 *   converged: when every component has converged;
 *   timings: sums.
 * A component's failure names it ("component 2 of 3: ..."; vertex and face
 * numbers are then those of the component, in the mesh's order) and keeps
 * every component's last good state.
 */
#include "methods/flow_internal.h"
#include "curvflow/flow.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct cfi_flow_parts {
    int32_t count;
    cf_flow **flows;
    cf_mesh **meshes;
    int32_t **vertices;  /* per component: the mesh's index of each of its vertices */
    int32_t *vertex_counts;
    double *scratch;     /* 3 x the largest component's vertex count */
};

void cfi_flow_destroy_parts(cf_flow *flow)
{
    cfi_flow_parts *p = flow->parts;
    if (!p) return;
    cf_context *ctx = flow->ctx;
    int32_t largest = 0;
    for (int32_t c = 0; c < p->count; ++c) {
        if (p->flows) cf_flow_destroy(&p->flows[c]);
        if (p->meshes) cf_mesh_destroy(&p->meshes[c]);
        if (p->vertices && p->vertices[c]) CFI_FREE(ctx, p->vertices[c], p->vertex_counts[c]);
        if (p->vertex_counts && p->vertex_counts[c] > largest) largest = p->vertex_counts[c];
    }
    if (p->flows) CFI_FREE(ctx, p->flows, p->count);
    if (p->meshes) CFI_FREE(ctx, p->meshes, p->count);
    if (p->vertices) CFI_FREE(ctx, p->vertices, p->count);
    if (p->vertex_counts) CFI_FREE(ctx, p->vertex_counts, p->count);
    if (p->scratch) CFI_FREE(ctx, p->scratch, 3 * (size_t)largest);
    CFI_FREE(ctx, p, 1);
    flow->parts = NULL;
}

/* x's part of component c into the scratch buffer */
static const double *slice(const cfi_flow_parts *p, int32_t c, const double *x)
{
    for (int32_t k = 0; k < p->vertex_counts[c]; ++k)
        memcpy(p->scratch + 3 * (size_t)k, x + 3 * (size_t)p->vertices[c][k], 3 * sizeof(double));
    return p->scratch;
}

/* component c's positions into the whole mesh's */
static void gather(cf_flow *flow, int32_t c)
{
    const cfi_flow_parts *p = flow->parts;
    const double *x = cf_flow_positions(p->flows[c]);
    for (int32_t k = 0; k < p->vertex_counts[c]; ++k)
        memcpy(flow->positions + 3 * (size_t)p->vertices[c][k], x + 3 * (size_t)k, 3 * sizeof(double));
}

/* The components' energies and terms summed into *info (their current
 * states, stepped this time or not). */
static void sum_energies(const cf_flow *flow, cf_flow_info *info)
{
    const cfi_flow_parts *p = flow->parts;
    info->energy = 0.0;
    for (int t = 0; t < CF_FLOW_MAX_TERMS; ++t) {
        info->energy_terms[t] = 0.0;
        info->term_names[t] = NULL;
    }
    for (int32_t c = 0; c < p->count; ++c) {
        const cf_flow_info *pi = cf_flow_last_info(p->flows[c]);
        info->energy += pi->energy;
        for (int t = 0; t < CF_FLOW_MAX_TERMS; ++t) {
            if (!pi->term_names[t]) continue;
            info->term_names[t] = pi->term_names[t];
            info->energy_terms[t] += pi->energy_terms[t];
        }
    }
}

/* The residuals of component step pi merged into *info (the largest per
 * name), with its time step and timings. */
static void merge_step(cf_flow_info *info, const cf_flow_info *pi)
{
    info->time_step = fmax(info->time_step, pi->time_step);
    info->assemble_seconds += pi->assemble_seconds;
    info->factorize_seconds += pi->factorize_seconds;
    info->solve_seconds += pi->solve_seconds;
    for (int r = 0; r < CF_FLOW_MAX_RESIDUALS; ++r) {
        const char *name = pi->residual_names[r];
        if (!name) continue;
        int slot = -1;
        for (int k = 0; k < CF_FLOW_MAX_RESIDUALS && slot < 0; ++k)
            if (info->residual_names[k] && strcmp(info->residual_names[k], name) == 0) slot = k;
        for (int k = 0; k < CF_FLOW_MAX_RESIDUALS && slot < 0; ++k)
            if (!info->residual_names[k]) slot = k;
        if (slot < 0) continue;
        if (!info->residual_names[slot]) {
            info->residual_names[slot] = name;
            info->residuals[slot] = pi->residuals[r];
        } else {
            info->residuals[slot] = fmax(info->residuals[slot], pi->residuals[r]);
        }
    }
}

/* A copy of the options with every vertex and face array cut to component
 * c (arrays from the caller's heap into *owned, freed by the caller after
 * the component's flow is made: methods copy what they keep). */
#define CFI_PARTS_MAX_ARRAYS 16

static cf_status component_options(cf_flow *flow, int32_t c, const int32_t *face_of, int32_t face_count,
                                   cf_flow_options *out, double **owned, size_t *owned_sizes, int32_t *owned_count)
{
    cf_context *ctx = flow->ctx;
    const cfi_flow_method *m = flow->method;
    const cfi_flow_parts *p = flow->parts;
    *out = flow->options;
    *owned_count = 0;
    for (int32_t i = 0; i < m->param_count; ++i) {
        const cf_param_desc *d = &m->params[i];
        if (!cf_param_type_is_array(d->type)) continue;
        if (d->type == CF_PARAM_POINT_SETS)
            return cfi_error(ctx, CF_ERR_UNSUPPORTED, "%s: parameter '%s' on a mesh of several components", m->name,
                             d->name);
        cf_param_values *v = (cf_param_values *)(out->storage.bytes + d->offset);
        if (!v->values) continue;
        int width = d->type == CF_PARAM_VERTEX_VECTORS ? 3 : 1;
        int per_face = d->type == CF_PARAM_FACE_SCALARS;
        int32_t n = per_face ? face_count : p->vertex_counts[c];
        if (*owned_count == CFI_PARTS_MAX_ARRAYS)
            return cfi_error(ctx, CF_ERR_UNSUPPORTED, "%s: more than %d array parameters", m->name,
                             CFI_PARTS_MAX_ARRAYS);
        double *cut = CFI_ALLOC(ctx, double, (size_t)width * (size_t)n);
        if (!cut) return CF_ERR_NOMEM;
        owned_sizes[*owned_count] = (size_t)width * (size_t)n;
        owned[(*owned_count)++] = cut;
        for (int32_t k = 0; k < n; ++k) {
            int32_t src = per_face ? face_of[k] : p->vertices[c][k];
            memcpy(cut + (size_t)width * k, v->values + (size_t)width * src, (size_t)width * sizeof(double));
        }
        v->values = cut;
        v->count = n;
    }
    return CF_OK;
}

/* Component c's mesh (rest positions the mesh's, faces in the mesh's order)
 * and its flow from flow->positions; face_of: scratch of nf ints. */
static cf_status create_component(cf_flow *flow, int32_t c, const int32_t *local, int32_t *face_of, int32_t *tri)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    cfi_flow_parts *p = flow->parts;
    int32_t nvc = p->vertex_counts[c], nfc = 0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        if (mesh->face_component[f] != c) continue;
        for (int k = 0; k < 3; ++k) tri[3 * (size_t)nfc + k] = local[mesh->triangles[3 * (size_t)f + k]];
        face_of[nfc++] = f;
    }
    cf_mesh_desc desc = {.vertex_count = nvc,
                         .positions = slice(p, c, mesh->positions),
                         .face_count = nfc,
                         .triangles = tri};
    cf_status st = cf_mesh_create(ctx, &desc, &p->meshes[c]);
    if (st != CF_OK) return st;
    double *owned[CFI_PARTS_MAX_ARRAYS];
    size_t owned_sizes[CFI_PARTS_MAX_ARRAYS];
    int32_t owned_count = 0;
    cf_flow_options options;
    st = component_options(flow, c, face_of, nfc, &options, owned, owned_sizes, &owned_count);
    if (st == CF_OK) st = cf_flow_create(ctx, p->meshes[c], slice(p, c, flow->positions), &options, &p->flows[c]);
    for (int32_t k = 0; k < owned_count; ++k) CFI_FREE(ctx, owned[k], owned_sizes[k]);
    return st;
}

cf_status cfi_flow_create_parts(cf_flow *flow)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    int32_t nc = mesh->component_count;
    cfi_flow_parts *p = CFI_ALLOC(ctx, cfi_flow_parts, 1);
    if (!p) return CF_ERR_NOMEM;
    flow->parts = p;
    p->count = nc;
    p->flows = CFI_ALLOC(ctx, cf_flow *, nc);
    p->meshes = CFI_ALLOC(ctx, cf_mesh *, nc);
    p->vertices = CFI_ALLOC(ctx, int32_t *, nc);
    p->vertex_counts = CFI_ALLOC(ctx, int32_t, nc);
    int32_t *local = CFI_ALLOC(ctx, int32_t, mesh->nv);
    int32_t *face_of = CFI_ALLOC(ctx, int32_t, mesh->nf);
    int32_t *tri = CFI_ALLOC(ctx, int32_t, 3 * (size_t)mesh->nf);
    cf_status st = p->flows && p->meshes && p->vertices && p->vertex_counts && local && face_of && tri ? CF_OK
                                                                                                       : CF_ERR_NOMEM;
    int32_t largest = 0;
    if (st == CF_OK) {
        for (int32_t c = 0; c < nc; ++c) p->vertex_counts[c] = 0;
        for (int32_t v = 0; v < mesh->nv; ++v) local[v] = p->vertex_counts[mesh->vertex_component[v]]++;
        for (int32_t c = 0; c < nc && st == CF_OK; ++c) {
            if (p->vertex_counts[c] > largest) largest = p->vertex_counts[c];
            if (!(p->vertices[c] = CFI_ALLOC(ctx, int32_t, p->vertex_counts[c]))) st = CF_ERR_NOMEM;
        }
    }
    if (st == CF_OK && !(p->scratch = CFI_ALLOC(ctx, double, 3 * (size_t)largest))) st = CF_ERR_NOMEM;
    if (st == CF_OK)
        for (int32_t v = 0; v < mesh->nv; ++v) p->vertices[mesh->vertex_component[v]][local[v]] = v;
    for (int32_t c = 0; c < nc && st == CF_OK; ++c) {
        st = create_component(flow, c, local, face_of, tri);
        if (st != CF_OK) cfi_error_prefix(ctx, "component %d of %d", c + 1, nc);
    }
    CFI_FREE(ctx, local, mesh->nv);
    CFI_FREE(ctx, face_of, mesh->nf);
    CFI_FREE(ctx, tri, 3 * (size_t)mesh->nf);
    if (st != CF_OK) return st;
    memset(&flow->info, 0, sizeof flow->info);
    sum_energies(flow, &flow->info);
    for (int32_t c = 0; c < nc; ++c) merge_step(&flow->info, cf_flow_last_info(p->flows[c]));
    flow->info.time_step = 0.0;
    st = cfi_flow_measure(flow, &flow->info);
    flow->info.area_drift = flow->info.volume_drift = 0.0;
    return st;
}

cf_status cfi_flow_step_parts(cf_flow *flow, cf_flow_info *info)
{
    cf_context *ctx = flow->ctx;
    cfi_flow_parts *p = flow->parts;
    double t0 = cfi_now_seconds();
    cf_flow_info step;
    memset(&step, 0, sizeof step);
    int32_t converged = 1;
    cf_status st = CF_OK;
    for (int32_t c = 0; c < p->count && st == CF_OK; ++c) {
        cf_flow *part = p->flows[c];
        if (cf_flow_converged(part)) continue;
        int64_t attempts = part->attempts;
        cf_flow_info pi;
        st = cf_flow_step(part, &pi);
        flow->attempts += part->attempts - attempts;
        /* the component's state, or its last good one after a failure */
        gather(flow, c);
        if (st != CF_OK) {
            cfi_error_prefix(ctx, "component %d of %d", c + 1, p->count);
            break;
        }
        merge_step(&step, &pi);
        converged = converged && cf_flow_converged(part);
    }
    if (st != CF_OK) {
        /* the state kept is every component's last good one: report it */
        cf_status failed = st;
        char message[CF_MESSAGE_CAPACITY];
        memcpy(message, ctx->message, sizeof message);
        sum_energies(flow, &flow->info);
        (void)cfi_flow_measure(flow, &flow->info);
        memcpy(ctx->message, message, sizeof message);
        ctx->last_status = failed;
        return failed;
    }
    sum_energies(flow, &step);
    st = cfi_flow_measure(flow, &step);
    if (st != CF_OK) return st;
    flow->converged = converged;
    return cfi_flow_accept_step(flow, &step, info, t0);
}

cf_status cfi_flow_set_positions_parts(cf_flow *flow, const double *positions)
{
    cf_context *ctx = flow->ctx;
    cfi_flow_parts *p = flow->parts;
    cf_status st = CF_OK;
    int32_t c = 0;
    for (; c < p->count && st == CF_OK; ++c) st = cf_flow_set_positions(p->flows[c], slice(p, c, positions));
    if (st != CF_OK) {
        /* all or none: the components already moved go back */
        cf_status failed = st;
        char message[CF_MESSAGE_CAPACITY];
        cfi_error_prefix(ctx, "component %d of %d", c, p->count);
        memcpy(message, ctx->message, sizeof message);
        for (int32_t k = 0; k + 1 < c; ++k) (void)cf_flow_set_positions(p->flows[k], slice(p, k, flow->positions));
        memcpy(ctx->message, message, sizeof message);
        ctx->last_status = failed;
        return failed;
    }
    memcpy(flow->saved_positions, flow->positions, 3 * (size_t)flow->mesh->nv * sizeof(double));
    for (c = 0; c < p->count; ++c) gather(flow, c);
    sum_energies(flow, &flow->info);
    flow->converged = 0;
    return cfi_flow_measure(flow, &flow->info);
}
