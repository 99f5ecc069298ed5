/*
 * dfle_mpi_wire.h - items and results as the ranks of dfle-mpi send
 * them (private to src/mpi): one line each, numbers in C99's hexadecimal
 * floating form (%a), which reads back to the same double, so a result
 * computed on another rank is the one this rank would have written.
 *
 *   item:    "<item> <x_1> ... <x_n>"
 *   result:  "<item> <status> <flags> <y_1> ... <y_m> <reason>"
 *
 * The reason is the rest of the line, with '\' and line breaks escaped
 * ("\\", "\n", "\r").
 */
#ifndef DFLE_MPI_WIRE_H
#define DFLE_MPI_WIRE_H

#include <stddef.h>

#include "dfle/evaluator.h"

/* Text that grows; out of memory ends the job (MPI_Abort). */
typedef struct wire_buf {
    char *s;
    size_t len, cap;
} wire_buf;

void wire_add(wire_buf *b, const char *s, size_t len);
void wire_printf(wire_buf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
void wire_free(wire_buf *b);

/* Append one line (with its '\n'). */
void wire_put_item(wire_buf *b, size_t item, const double *x, size_t n);
void wire_put_result(wire_buf *b, size_t item, const dfle_eval_out *out, size_t m);

/* Read the line at *p (ends at '\n' or '\0'), moving *p past it.
 * 0 on success, -1 for a malformed line.  out->y must have m values. */
int wire_get_item(const char **p, size_t *item, double *x, size_t n);
int wire_get_result(const char **p, size_t *item, dfle_eval_out *out, size_t m);

#endif
