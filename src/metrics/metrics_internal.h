/* Shared argument checks of the metrics files (internal). */
#ifndef CF_METRICS_METRICS_INTERNAL_H
#define CF_METRICS_METRICS_INTERNAL_H

#include "core/core.h"
#include "curvflow/metrics.h"
#include "mesh/mesh_internal.h"

/* ctx/mesh non-NULL, both position sets non-NULL and finite. */
cf_status cfi_metrics_check_pair(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                 const char *fn);

#endif /* CF_METRICS_METRICS_INTERNAL_H */
