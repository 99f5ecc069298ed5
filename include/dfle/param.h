/*
 * param.h - a component's parameters as (name, value, unit) triples.
 *
 * Routers and erosion laws list their parameters through an optional
 * `params` op, so a caller (the Lua binding's rt:params() and
 * tostring(), a run record) can show any component without knowing its
 * kind.  The names are those of the constructor's options, so a list can
 * be fed back to build the same component.
 */
#ifndef DFLE_PARAM_H
#define DFLE_PARAM_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_param {
    const char *name; /* the option's name, e.g. "tau_y"                  */
    double value;     /* in the unit below                                 */
    const char *unit; /* e.g. "Pa", "m^3"; "" for a dimensionless number   */
    int is_switch;    /* 1: an on/off option (value 0 or 1)                */
} dfle_param;

/* Copy `n` parameters from `src` into `out` (room for `cap`) and return
 * n: the helper every params op ends with. */
size_t dfle_param_copy(const dfle_param *src, size_t n, dfle_param *out, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
