/*
 * error.c - the error record shared by every dfle call.
 *
 * Messages are formatted once, at the point of failure, where the
 * parameter name and value are known; callers higher up only pass the
 * record along (or prefix context, e.g. the Lua binding adds file:line).
 */
#include "dfle/error.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* printf writes a NaN as "nan", or as "-nan" when its sign bit is set
 * (0/0 on x86), which means nothing to a user: every message says "NaN",
 * as the Lua binding does.  Only a number's word is rewritten (after a
 * space, '(', '[', '=' or ',', before a space, ')', ']', ',', ';', ':'
 * or the end), never "nan" inside a name, which messages quote
 * ('nan.csv'). */
static void nan_words(char *s)
{
    char *p = s;
    while ((p = strstr(p, "nan")) != NULL) {
        char *start = p > s && p[-1] == '-' ? p - 1 : p;
        int before = start == s || strchr(" (=,[", start[-1]) != NULL;
        int after = p[3] == '\0' || strchr(" ),;:]", p[3]) != NULL;
        if (before && after) {
            memcpy(start, "NaN", 3);
            if (start != p)
                memmove(start + 3, p + 3, strlen(p + 3) + 1);
            p = start + 3;
        } else {
            p += 3;
        }
    }
}

int dfle_error_set(dfle_error *err, int code, const char *fmt, ...)
{
    if (err != NULL) {
        va_list ap;
        err->code = code;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
        nan_words(err->msg);
    }
    return code;
}

void dfle_error_clear(dfle_error *err)
{
    if (err != NULL) {
        err->code = DFLE_OK;
        err->msg[0] = '\0';
    }
}

const char *dfle_status_string(int code)
{
    switch (code) {
    case DFLE_OK: return "ok";
    case DFLE_EINVAL: return "invalid parameter";
    case DFLE_ENOMEM: return "out of memory";
    case DFLE_ENUMERIC: return "non-finite value in simulation";
    case DFLE_EIO: return "input/output error";
    case DFLE_ECALLBACK: return "callback failed";
    case DFLE_ESTATE: return "invalid state";
    case DFLE_EFIT: return "fit failed";
    case DFLE_ECANCELED: return "canceled";
    case DFLE_EEXTERNAL: return "external program failed";
    default: return "unknown error";
    }
}
