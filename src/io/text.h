/*
 * Text input shared by every reader of the library (OBJ, OFF, the PLY
 * header and ascii body, CSV / SVG polylines, per-vertex value files): the
 * whole input is one buffer followed by a NUL byte, a UTF-8 byte-order mark
 * at its start is skipped, a NUL byte inside it is refused with its offset,
 * and lines are [start, end) ranges of that buffer, so a line of any length
 * is one line (no fixed-size line buffer anywhere).
 */
#ifndef CF_IO_TEXT_H
#define CF_IO_TEXT_H

#include "core/core.h"

/* The UTF-8 encoding of U+FEFF that some editors put at the start of a file. */
#define CFI_UTF8_BOM "\xEF\xBB\xBF"

/* Iterates over the lines of a buffer. */
typedef struct cfi_text {
    const char *base;   /* start of the buffer as given (offsets count from here) */
    const char *p;      /* start of the next line */
    const char *end;    /* end of the text */
    const char *s, *e;  /* current line [s, e) without its '\n' ('\r' is kept: readers treat it as space) */
    int64_t line;       /* 1-based number of the current line, 0 before the first */
    bool unterminated;  /* the current line is the last one and no '\n' ends it */
} cfi_text;

/* Length of a byte-order mark at the start of buf (3 or 0). */
size_t cfi_bom_length(const char *buf, size_t size);

/* Starts at the beginning of buf[0, size), after a byte-order mark. */
void cfi_text_init(cfi_text *t, const char *buf, size_t size);

/* Starts at `from` (inside buf) as line number `line` (the number of the
 * line that begins at `from`). */
void cfi_text_init_at(cfi_text *t, const char *buf, size_t size, const char *from, int64_t line);

/* Moves to the next line; false at the end of the text. A file ending in
 * '\n' has no empty last line. */
bool cfi_text_next(cfi_text *t);

/* Refuses a NUL byte in buf[from, size): CF_ERR_PARSE with
 * "<name>: line L: NUL byte at offset K (not a text file?)", K counted from
 * buf[0] and L the line holding it. */
cf_status cfi_text_check_nul(cf_context *ctx, const char *name, const char *buf, size_t from, size_t size);

/* The 1-based line holding buf[offset]. */
int64_t cfi_text_line_of(const char *buf, size_t offset);

/* Reads a whole file into a context buffer of *cap bytes holding *size
 * bytes and a NUL after them (free with cfi_free(ctx, *buf, *cap)).
 * CF_ERR_IO names the path and the system's reason; CF_ERR_NOMEM. */
cf_status cfi_read_whole_file(cf_context *ctx, const char *path, char **buf, size_t *size, size_t *cap);

/* Next token of [*p, e) separated by whitespace (space, tab, CR, VT, FF) or any character of `seps`
 * (NULL: whitespace only); false when none is left. Inline: the readers call
 * it for every number of a file. */
static inline bool cfi_text_sep(char c, const char *seps)
{
    if (c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f') return true;
    for (; seps && *seps; ++seps)
        if (c == *seps) return true;
    return false;
}

static inline bool cfi_text_token(const char **p, const char *e, const char *seps, const char **ts, const char **te)
{
    const char *q = *p;
    while (q < e && cfi_text_sep(*q, seps)) ++q;
    if (q >= e) {
        *p = q;
        return false;
    }
    *ts = q;
    while (q < e && !cfi_text_sep(*q, seps)) ++q;
    *te = q;
    *p = q;
    return true;
}

/* Printable length of a token in messages: tokens are quoted as written up
 * to 64 characters. */
static inline int cfi_tok_len(const char *s, const char *e) { return (int)(e - s > 64 ? 64 : e - s); }

#endif /* CF_IO_TEXT_H */
