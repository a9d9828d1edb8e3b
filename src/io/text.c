/*
 * Text input shared by every reader (see text.h): whole-file reading,
 * byte-order mark, NUL bytes, lines of any length, tokens.
 */
#include "io/text.h"
#include "curvflow/io.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>


size_t cfi_bom_length(const char *buf, size_t size)
{
    return size >= 3 && memcmp(buf, CFI_UTF8_BOM, 3) == 0 ? 3 : 0;
}

void cfi_text_init_at(cfi_text *t, const char *buf, size_t size, const char *from, int64_t line)
{
    t->base = buf;
    t->p = from;
    t->end = buf + size;
    t->s = t->e = from;
    t->line = line - 1;
    t->unterminated = false;
}

void cfi_text_init(cfi_text *t, const char *buf, size_t size)
{
    cfi_text_init_at(t, buf, size, buf + cfi_bom_length(buf, size), 1);
}

bool cfi_text_next(cfi_text *t)
{
    if (t->p >= t->end) return false;
    const char *nl = memchr(t->p, '\n', (size_t)(t->end - t->p));
    t->s = t->p;
    t->e = nl ? nl : t->end;
    t->unterminated = nl == NULL;
    t->p = nl ? nl + 1 : t->end;
    t->line++;
    return true;
}

int64_t cfi_text_line_of(const char *buf, size_t offset)
{
    int64_t line = 1;
    for (const char *p = buf, *end = buf + offset; (p = memchr(p, '\n', (size_t)(end - p))) != NULL; ++p) ++line;
    return line;
}

cf_status cfi_text_check_nul(cf_context *ctx, const char *name, const char *buf, size_t from, size_t size)
{
    if (from >= size) return CF_OK;
    const char *nul = memchr(buf + from, '\0', size - from);
    if (!nul) return CF_OK;
    size_t offset = (size_t)(nul - buf);
    return cfi_error(ctx, CF_ERR_PARSE, "%s: line %lld: NUL byte at offset %zu (not a text file?)", name,
                     (long long)cfi_text_line_of(buf, offset), offset);
}

cf_status cf_text_check(cf_context *ctx, const void *bytes, size_t size, const char *name, size_t *start)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!name) name = "<memory>";
    if (start) *start = 0;
    if (!bytes && size > 0) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: text check: bytes is NULL", name);
    if (size == 0) return CF_OK;
    cf_status st = cfi_text_check_nul(ctx, name, bytes, 0, size);
    if (st == CF_OK && start) *start = cfi_bom_length(bytes, size);
    return st;
}

cf_status cfi_read_whole_file(cf_context *ctx, const char *path, char **out, size_t *size_out, size_t *cap_out)
{
    *out = NULL;
    FILE *fp = fopen(path, "rb");
    if (!fp) return cfi_error(ctx, CF_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    size_t cap = 1 << 16, size = 0;
    char *buf = cfi_malloc(ctx, cap);
    if (!buf) {
        fclose(fp);
        return cfi_error(ctx, CF_ERR_NOMEM, "%s: out of memory reading the file", path);
    }
    for (;;) {
        if (cap - size < 2) {
            if (cap > SIZE_MAX / 2) break;
            char *p = cfi_realloc(ctx, buf, cap, cap * 2);
            if (!p) {
                cfi_free(ctx, buf, cap);
                fclose(fp);
                return cfi_error(ctx, CF_ERR_NOMEM, "%s: out of memory reading %zu bytes", path, cap * 2);
            }
            buf = p;
            cap *= 2;
        }
        size_t got = fread(buf + size, 1, cap - size - 1, fp);
        size += got;
        if (got == 0) break;
    }
    int err = ferror(fp) ? errno : 0;
    fclose(fp);
    if (err || size + 1 > cap) {
        cfi_free(ctx, buf, cap);
        return cfi_error(ctx, CF_ERR_IO, "%s: cannot read: %s", path, err ? strerror(err) : "file too large");
    }
    buf[size] = '\0';
    *out = buf;
    *size_out = size;
    *cap_out = cap;
    return CF_OK;
}
