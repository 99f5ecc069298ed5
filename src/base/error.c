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

int dfle_error_set(dfle_error *err, int code, const char *fmt, ...)
{
    if (err != NULL) {
        va_list ap;
        err->code = code;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
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
