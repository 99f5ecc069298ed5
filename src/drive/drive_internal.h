/*
 * drive_internal.h - what the files of the driver layer share (not
 * installed): growing text for the lines of their files, the text of a
 * number and of a CSV field, a clock, and error messages given the
 * driver's prefix once.
 */
#ifndef DFLE_DRIVE_INTERNAL_H
#define DFLE_DRIVE_INTERNAL_H

#include <stdarg.h>
#include <stddef.h>

#include "dfle/error.h"

/* Text that grows; an allocation failure is kept (oom) and every later
 * call does nothing, so builders check once at the end. */
typedef struct dfle_text {
    char *s;
    size_t len, cap;
    int oom;
} dfle_text;

void dfle_text_init(dfle_text *t);
void dfle_text_free(dfle_text *t);
void dfle_text_clear(dfle_text *t); /* empty, memory kept */
void dfle_text_add(dfle_text *t, const char *s, size_t len);
void dfle_text_str(dfle_text *t, const char *s);
void dfle_text_printf(dfle_text *t, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* A number as the drivers' files write it: 17 significant digits (it
 * reads back to the same double), "nan", "inf", "-inf". */
void dfle_text_number(dfle_text *t, double v);
/* A text as a quoted CSV field: quotes doubled, line breaks as spaces
 * (rows are lines). */
void dfle_text_quoted(dfle_text *t, const char *s);
/* The text, malloc'd (the buffer handed over), or NULL if memory ran out. */
char *dfle_text_take(dfle_text *t);

/* src into dst (cap bytes with the NUL), cut to fit. */
void dfle_drive_copy(char *dst, size_t cap, const char *src);

/* Cut s, in place, at the last whole UTF-8 character (a cut by snprintf
 * may have split one). */
void dfle_drive_cut_utf8(char *s);

/* Seconds on a monotonic clock. */
double dfle_drive_now(void);

/* err's message given "<who>: " in front unless it starts so already
 * (messages of lower layers name their own layer: "ensemble: ...";
 * others, a file's "x.csv: ...", get it); returns err's code. */
int dfle_drive_prefix(dfle_error *err, const char *who);

#endif
