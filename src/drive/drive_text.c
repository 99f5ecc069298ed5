/*
 * drive_text.c - growing text for the drivers' file lines, the text of
 * numbers and CSV fields, a clock, message prefixes (drive_internal.h).
 */
#include "drive/drive_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

void dfle_text_init(dfle_text *t) { memset(t, 0, sizeof *t); }

void dfle_text_free(dfle_text *t)
{
    free(t->s);
    memset(t, 0, sizeof *t);
}

void dfle_text_clear(dfle_text *t)
{
    t->len = 0;
    if (t->s != NULL)
        t->s[0] = '\0';
}

static int grow(dfle_text *t, size_t more)
{
    char *p;
    size_t cap;
    if (t->oom)
        return 0;
    if (t->len + more + 1 <= t->cap)
        return 1;
    cap = 2 * (t->len + more + 1) + 64;
    p = realloc(t->s, cap);
    if (p == NULL) {
        t->oom = 1;
        return 0;
    }
    t->s = p;
    t->cap = cap;
    return 1;
}

void dfle_text_add(dfle_text *t, const char *s, size_t len)
{
    if (!grow(t, len))
        return;
    memcpy(t->s + t->len, s, len);
    t->len += len;
    t->s[t->len] = '\0';
}

void dfle_text_str(dfle_text *t, const char *s) { dfle_text_add(t, s, strlen(s)); }

void dfle_text_printf(dfle_text *t, const char *fmt, ...)
{
    va_list ap;
    int n;
    char small[128];
    va_start(ap, fmt);
    n = vsnprintf(small, sizeof small, fmt, ap);
    va_end(ap);
    if (n < 0) {
        t->oom = 1;
        return;
    }
    if ((size_t)n < sizeof small) {
        dfle_text_add(t, small, (size_t)n);
        return;
    }
    if (!grow(t, (size_t)n))
        return;
    va_start(ap, fmt);
    vsnprintf(t->s + t->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    t->len += (size_t)n;
}

void dfle_text_number(dfle_text *t, double v)
{
    if (isnan(v))
        dfle_text_str(t, "nan");
    else if (isinf(v))
        dfle_text_str(t, v > 0 ? "inf" : "-inf");
    else
        dfle_text_printf(t, "%.17g", v);
}

void dfle_text_quoted(dfle_text *t, const char *s)
{
    dfle_text_str(t, "\"");
    for (; *s != '\0'; s++) {
        if (*s == '\n' || *s == '\r')
            dfle_text_str(t, " ");
        else if (*s == '"')
            dfle_text_str(t, "\"\"");
        else
            dfle_text_add(t, s, 1);
    }
    dfle_text_str(t, "\"");
}

char *dfle_text_take(dfle_text *t)
{
    char *s = t->oom ? NULL : t->s;
    if (t->oom)
        free(t->s);
    else if (s == NULL)
        s = calloc(1, 1);
    memset(t, 0, sizeof *t);
    return s;
}

void dfle_drive_copy(char *dst, size_t cap, const char *src)
{
    size_t n = 0;
    if (cap == 0)
        return;
    while (n + 1 < cap && src[n] != '\0')
        n++;
    memcpy(dst, src, n);
    dst[n] = '\0';
}

void dfle_drive_cut_utf8(char *s)
{
    size_t n = strlen(s), k = n;
    /* back over continuation bytes to the lead byte of the last character */
    while (k > 0 && ((unsigned char)s[k - 1] & 0xC0) == 0x80)
        k--;
    if (k > 0) {
        unsigned char lead = (unsigned char)s[k - 1];
        size_t want = lead >= 0xF0 ? 4 : lead >= 0xE0 ? 3 : lead >= 0xC0 ? 2 : 1;
        if (n - (k - 1) < want)
            s[k - 1] = '\0';
    }
}

double dfle_drive_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int dfle_drive_prefix(dfle_error *err, const char *who)
{
    size_t n = strlen(who);
    char buf[DFLE_ERROR_MSG_MAX];
    if (err == NULL)
        return DFLE_OK;
    if (strncmp(err->msg, who, n) == 0 && err->msg[n] == ':')
        return err->code;
    memcpy(buf, err->msg, sizeof buf);
    buf[sizeof buf - 1] = '\0';
    return dfle_error_set(err, err->code, "%s: %s", who, buf);
}
