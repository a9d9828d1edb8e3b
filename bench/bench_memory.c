/*
 * Peak memory and time of creation plus one step of every flow that runs on
 * a closed mesh, on icospheres of 164k and 655k vertices (issue 15, "Memory
 * and scale"; table in docs/memory.md). Each (mesh, method) runs in a child
 * process of its own, which generates the icosphere, creates the flow and
 * takes one step; the parent reads the child's peak resident set size
 * (ru_maxrss from wait4) and CPU time, the child reports its phase times
 * through a pipe. Prints TSV; asserts nothing. One run at a time: the
 * machine's other load shows in wall time, not in peak memory.
 *
 *   bench_memory [--subdivisions 7,8] [--methods spin-willmore,implicit-mcf,...]
 *
 * Columns: mesh_MB is the peak after generating the mesh (before the flow),
 * peak_MB the peak of the whole child, create_MB the peak by the end of
 * cf_flow_create, held_MB the resident size after the step (what the flow
 * keeps: the difference to peak_MB is what the step needed only while it
 * ran); create_s / step_s are wall seconds of cf_flow_create / the first
 * cf_flow_step, cpu_s the child's user + system time.
 */
#define _DEFAULT_SOURCE 1 /* wait4 */
#include "curvflow/flow.h"
#include "curvflow/generate.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* VmRSS of this process in MB (0 if /proc is not there) */
static double resident_mb(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return 0.0;
    char line[256];
    double kb = 0.0;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "VmRSS: %lf", &kb) == 1) break;
    fclose(f);
    return kb / 1024.0;
}

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct child_report {
    int status;         /* cf_status of the first failing call, 0 if none */
    int32_t nv, nf;
    double mesh_mb, create_mb, held_mb, create_s, step_s;
    char message[200];
} child_report;

/* The child: generate, create, one step; the report goes up the pipe. */
static void run_child(int fd, int32_t sub, cf_flow_kind kind)
{
    child_report r;
    memset(&r, 0, sizeof r);
    cf_context *ctx = NULL;
    cf_mesh *mesh = NULL;
    cf_flow *flow = NULL;
    if (cf_context_create(&ctx) != CF_OK) _exit(1);
    cf_status st = cf_generate_icosphere(ctx, sub, 1.0, &mesh);
    if (st == CF_OK) {
        r.nv = cf_mesh_vertex_count(mesh);
        r.nf = cf_mesh_face_count(mesh);
        struct rusage ru;
        getrusage(RUSAGE_SELF, &ru);
        r.mesh_mb = (double)ru.ru_maxrss / 1024.0;
        cf_flow_options o;
        cf_flow_options_default(kind, &o);
        double t0 = now();
        st = cf_flow_create(ctx, mesh, NULL, &o, &flow);
        r.create_s = now() - t0;
        getrusage(RUSAGE_SELF, &ru);
        r.create_mb = (double)ru.ru_maxrss / 1024.0;
    }
    if (st == CF_OK) {
        cf_flow_info info;
        double t0 = now();
        st = cf_flow_step(flow, &info);
        r.step_s = now() - t0;
        r.held_mb = resident_mb();
    }
    r.status = (int)st;
    if (st != CF_OK) snprintf(r.message, sizeof r.message, "%s", cf_context_message(ctx));
    if (write(fd, &r, sizeof r) != (ssize_t)sizeof r) _exit(1);
    cf_flow_destroy(&flow);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
    _exit(0);
}

static void run(int32_t sub, cf_flow_kind kind)
{
    int fds[2];
    if (pipe(fds) != 0) return;
    double t0 = now();
    pid_t pid = fork();
    if (pid < 0) return;
    if (pid == 0) {
        close(fds[0]);
        run_child(fds[1], sub, kind);
    }
    close(fds[1]);
    child_report r;
    memset(&r, 0, sizeof r);
    ssize_t got = read(fds[0], &r, sizeof r);
    close(fds[0]);
    int wstatus = 0;
    struct rusage ru;
    memset(&ru, 0, sizeof ru);
    wait4(pid, &wstatus, 0, &ru);
    double wall = now() - t0;
    double cpu = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
                 1e-6 * (double)ru.ru_stime.tv_usec;
    const char *result = got != (ssize_t)sizeof r ? "child died" : r.status ? r.message : "ok";
    printf("%s\t%d\t%d\t%.0f\t%.0f\t%.0f\t%.0f\t%.2f\t%.2f\t%.2f\t%.2f\t%s\n", cf_flow_kind_name(kind), r.nv, r.nf,
           r.mesh_mb, (double)ru.ru_maxrss / 1024.0, r.create_mb, r.held_mb, r.create_s, r.step_s, wall, cpu, result);
    fflush(stdout);
}

int main(int argc, char **argv)
{
    const char *subs = "7,8";
    const char *methods = "explicit-mcf,implicit-mcf,conformal-mcf,explicit-bilaplacian,implicit-bilaplacian,"
                          "spin-willmore";
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--subdivisions") && i + 1 < argc) subs = argv[++i];
        else if (!strcmp(argv[i], "--methods") && i + 1 < argc) methods = argv[++i];
        else {
            fprintf(stderr, "usage: bench_memory [--subdivisions 7,8] [--methods NAME,...]\n");
            return 1;
        }
    }
    printf("method\tV\tF\tmesh_MB\tpeak_MB\tcreate_MB\theld_MB\tcreate_s\tstep_s\twall_s\tcpu_s\tresult\n");
    char sbuf[256];
    snprintf(sbuf, sizeof sbuf, "%s", subs);
    for (char *s = strtok(sbuf, ","); s; s = strtok(NULL, ",")) {
        char mbuf[512];
        snprintf(mbuf, sizeof mbuf, "%s", methods);
        char *save = NULL;
        for (char *m = strtok_r(mbuf, ",", &save); m; m = strtok_r(NULL, ",", &save)) {
            cf_flow_kind kind;
            if (cf_flow_kind_from_name(m, &kind) != CF_OK) {
                fprintf(stderr, "unknown method %s\n", m);
                return 1;
            }
            run(atoi(s), kind);
        }
    }
    return 0;
}
