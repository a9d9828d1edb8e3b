/* Running the built tool from tests (cli_test.h). */
#define _POSIX_C_SOURCE 200809L
#include "cli_test.h"

#include "curvflow/io.h"
#include "curvflow/mesh.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

char cft_dir[1024];
char cft_out[1 << 16];
char cft_err[1 << 16];
const char *cft_cli_env = "";

int cft_cli_setup(const char *name)
{
    snprintf(cft_dir, sizeof cft_dir, "%s/%s_%ld", CF_TEST_BINARY_DIR, name, (long)getpid());
    if (mkdir(cft_dir, 0777) != 0) {
        fprintf(stderr, "cannot create %s\n", cft_dir);
        return 1;
    }
    return 0;
}

int cft_cli_finish(void)
{
    int rc = cft_finish();
    if (rc == 0) cft_remove_dir(cft_dir);
    return rc;
}

const char *cft_in_dir(const char *name)
{
    static char path[2048];
    snprintf(path, sizeof path, "%s/%s", cft_dir, name);
    return path;
}

void cft_read_small(const char *path, char *buf, size_t size)
{
    buf[0] = '\0';
    FILE *f = fopen(path, "rb");
    if (!f) return;
    size_t n = fread(buf, 1, size - 1, f);
    buf[n] = '\0';
    fclose(f);
}

int cft_shell(const char *command)
{
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "cd '%s' && %s %s > stdout.txt 2> stderr.txt", cft_dir, cft_cli_env, command);
    int st = system(cmd);
    cft_read_small(cft_in_dir("stdout.txt"), cft_out, sizeof cft_out);
    cft_read_small(cft_in_dir("stderr.txt"), cft_err, sizeof cft_err);
    return st != -1 && WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

int cft_run(const char *args)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "'%s' %s", CF_TEST_CLI, args);
    return cft_shell(cmd);
}

int cft_exists(const char *name)
{
    struct stat sb;
    return stat(cft_in_dir(name), &sb) == 0;
}

int cft_err_has(const char *part) { return !part || strstr(cft_err, part) != NULL; }

void cft_remove_dir(const char *path)
{
    DIR *d = opendir(path);
    if (!d) return;
    struct dirent *e;
    char p[2048];
    while ((e = readdir(d))) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        snprintf(p, sizeof p, "%s/%s", path, e->d_name);
        remove(p);
    }
    closedir(d);
    rmdir(path);
}

double *cft_load_positions(const char *name, int32_t *nv)
{
    cf_context *ctx = NULL;
    cf_mesh *mesh = NULL;
    double *x = NULL;
    if (cf_context_create(&ctx) == CF_OK && cf_load_mesh(ctx, cft_in_dir(name), &mesh) == CF_OK) {
        *nv = cf_mesh_vertex_count(mesh);
        x = malloc(3 * (size_t)*nv * sizeof *x);
        if (x) memcpy(x, cf_mesh_positions(mesh), 3 * (size_t)*nv * sizeof *x);
    }
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
    return x;
}
