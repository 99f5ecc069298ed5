/*
 * param.c - the one helper behind every component's params op.
 */
#include "dfle/param.h"

#include <string.h>

size_t dfle_param_copy(const dfle_param *src, size_t n, dfle_param *out, size_t cap)
{
    if (out != NULL && cap > 0)
        memcpy(out, src, (n < cap ? n : cap) * sizeof *src);
    return n;
}
