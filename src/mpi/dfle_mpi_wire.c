/*
 * dfle_mpi_wire.c - items and results as lines of text (dfle_mpi_wire.h).
 */
#include "mpi/dfle_mpi_wire.h"

#include <mpi.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void grow(wire_buf *b, size_t more)
{
    size_t cap;
    char *p;
    if (b->len + more + 1 <= b->cap)
        return;
    cap = 2 * (b->len + more + 1) + 256;
    p = realloc(b->s, cap);
    if (p == NULL) {
        fprintf(stderr, "dfle-mpi: out of memory for a message\n");
        MPI_Abort(MPI_COMM_WORLD, 1);
        return;
    }
    b->s = p;
    b->cap = cap;
}

void wire_add(wire_buf *b, const char *s, size_t len)
{
    grow(b, len);
    memcpy(b->s + b->len, s, len);
    b->len += len;
    b->s[b->len] = '\0';
}

void wire_printf(wire_buf *b, const char *fmt, ...)
{
    char small[160];
    va_list ap;
    int n;
    va_start(ap, fmt);
    n = vsnprintf(small, sizeof small, fmt, ap);
    va_end(ap);
    if (n < 0)
        return;
    if ((size_t)n < sizeof small) {
        wire_add(b, small, (size_t)n);
        return;
    }
    grow(b, (size_t)n);
    va_start(ap, fmt);
    vsnprintf(b->s + b->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
}

void wire_free(wire_buf *b)
{
    free(b->s);
    memset(b, 0, sizeof *b);
}

void wire_put_item(wire_buf *b, size_t item, const double *x, size_t n)
{
    wire_printf(b, "%zu", item);
    for (size_t j = 0; j < n; j++)
        wire_printf(b, " %a", x[j]);
    wire_add(b, "\n", 1);
}

void wire_put_result(wire_buf *b, size_t item, const dfle_eval_out *out, size_t m)
{
    wire_printf(b, "%zu %d %u", item, out->status, out->flags);
    for (size_t k = 0; k < m; k++)
        wire_printf(b, " %a", out->y[k]);
    wire_add(b, " ", 1);
    for (const char *c = out->reason; *c != '\0'; c++) {
        if (*c == '\\')
            wire_add(b, "\\\\", 2);
        else if (*c == '\n')
            wire_add(b, "\\n", 2);
        else if (*c == '\r')
            wire_add(b, "\\r", 2);
        else
            wire_add(b, c, 1);
    }
    wire_add(b, "\n", 1);
}

static int get_size(const char **p, size_t *v)
{
    char *end;
    unsigned long long u = strtoull(*p, &end, 10);
    if (end == *p)
        return -1;
    *v = (size_t)u;
    *p = end;
    return 0;
}

static int get_double(const char **p, double *v)
{
    char *end;
    *v = strtod(*p, &end);
    if (end == *p)
        return -1;
    *p = end;
    return 0;
}

/* Past the rest of the line. */
static void next_line(const char **p)
{
    const char *nl = strchr(*p, '\n');
    *p = nl != NULL ? nl + 1 : *p + strlen(*p);
}

int wire_get_item(const char **p, size_t *item, double *x, size_t n)
{
    int bad = get_size(p, item);
    for (size_t j = 0; j < n && !bad; j++)
        bad = get_double(p, &x[j]);
    next_line(p);
    return bad ? -1 : 0;
}

int wire_get_result(const char **p, size_t *item, dfle_eval_out *out, size_t m)
{
    size_t status = 0, flags = 0, k = 0;
    const char *c;
    int bad = get_size(p, item) || get_size(p, &status) || get_size(p, &flags);
    for (size_t j = 0; j < m && !bad; j++)
        bad = get_double(p, &out->y[j]);
    out->status = (int)status;
    out->flags = (unsigned)flags;
    out->reason[0] = '\0';
    if (!bad && **p == ' ') {
        for (c = *p + 1; *c != '\0' && *c != '\n' && k + 1 < sizeof out->reason; c++) {
            char ch = *c;
            if (ch == '\\' && (c[1] == '\\' || c[1] == 'n' || c[1] == 'r')) {
                c++;
                ch = *c == 'n' ? '\n' : *c == 'r' ? '\r' : '\\';
            }
            out->reason[k++] = ch;
        }
        out->reason[k] = '\0';
    }
    next_line(p);
    return bad ? -1 : 0;
}
