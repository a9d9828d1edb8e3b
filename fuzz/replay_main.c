/* Replay driver for the fuzz targets in ordinary (non-libFuzzer) builds, so
 * that every build compiles them against the current API and CTest runs each
 * one on a few inputs (fuzz.<target>). Without arguments it feeds built-in
 * inputs (empty, short text, a numeric line, bytes with NULs); with
 * arguments it feeds each named file, like libFuzzer's own replay mode. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int replay_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "fuzz replay: cannot open %s\n", path);
        return 1;
    }
    size_t capacity = 1 << 16, size = 0;
    uint8_t *data = malloc(capacity);
    while (data) {
        size_t got = fread(data + size, 1, capacity - size, f);
        size += got;
        if (size < capacity) break;
        uint8_t *grown = realloc(data, capacity * 2);
        if (!grown) {
            free(data);
            data = NULL;
            break;
        }
        data = grown;
        capacity *= 2;
    }
    fclose(f);
    if (!data) {
        fprintf(stderr, "fuzz replay: out of memory reading %s\n", path);
        return 1;
    }
    LLVMFuzzerTestOneInput(data, size);
    free(data);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc > 1) {
        int failures = 0;
        for (int i = 1; i < argc; ++i) failures += replay_file(argv[i]);
        return failures ? 1 : 0;
    }
    static const char *const inputs[] = {
        "",
        "# comment only\n",
        "0 0 0 1\n1 0 0 1\n2 1 0 0\n",
        "0.5,0,0\n-1e308,1e308,nan\ninf\n",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n0\n",
        "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n",
        /* a tetrahedron as unshared triangles (its seams weld), and a bow tie (they do not) */
        "v 0 0 0\nv 0 1 0\nv 1 0 0\nv 0 0 0\nv 1 0 0\nv 0 0 1\nv 0 0 0\nv 0 0 1\nv 0 1 0\n"
        "v 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 4 5 6\nf 7 8 9\nf 10 11 12\n",
        "OFF\n6 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 0\n-1 0 0\n0 -1 0\n3 0 1 2\n3 3 4 5\n",
        "{\"handles\": [{\"vertices\": [0, 1], \"translation\": [0, 0, 1]}]}",
        "<svg><path d=\"M 0 0 L 1 0 L 1 1 Z\"/></svg>",
    };
    for (size_t i = 0; i < sizeof inputs / sizeof inputs[0]; ++i)
        LLVMFuzzerTestOneInput((const uint8_t *)inputs[i], strlen(inputs[i]));
    static const uint8_t binary[] = {0, 1, 2, 0xff, '\n', 0, '3', ' ', '4', 0};
    LLVMFuzzerTestOneInput(binary, sizeof binary);
    return 0;
}
