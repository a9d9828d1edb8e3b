/*
 * Shared fixtures of the stretch/bend editing tests: building a handle set
 * from a per-vertex rule (which vertices are handles, and where they go).
 */
#ifndef CF_TESTS_STRETCH_BEND_TEST_UTIL_H
#define CF_TESTS_STRETCH_BEND_TEST_UTIL_H

#include "curvflow/stretch_bend_edit.h"
#include "test.h"

#include <stdint.h>
#include <stdlib.h>

/* Returns nonzero if vertex v (rest position p) is a handle, and then
 * writes its target position to t. */
typedef int (*stretch_bend_handle_rule)(int32_t v, const double *p, double *t, const void *user);

/* The handle set of the vertices `rule` selects, in vertex order. */
static inline cf_handle_set *stretch_bend_handles_where(cf_context *ctx, const cf_mesh *mesh, stretch_bend_handle_rule rule,
                                               const void *user)
{
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double *x = cf_mesh_positions(mesh);
    int32_t *vs = malloc(sizeof(int32_t) * (size_t)nv);
    double *ts = malloc(sizeof(double) * 3 * (size_t)nv);
    int32_t n = 0;
    for (int32_t v = 0; v < nv; ++v)
        if (rule(v, x + 3 * v, ts + 3 * n, user)) vs[n++] = v;
    cf_handle_set *h = NULL;
    CHECK_OK(ctx, cf_handle_set_create(ctx, n, vs, ts, &h));
    free(vs);
    free(ts);
    return h;
}

#endif /* CF_TESTS_STRETCH_BEND_TEST_UTIL_H */
