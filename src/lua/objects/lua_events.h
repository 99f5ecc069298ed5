/*
 * lua_events.h - what the run_events methods of dfle.model and
 * dfle.landscape share (lua_population.c): their options and their
 * result table.  Internal to the binding.
 */
#ifndef DFLE_LUA_EVENTS_H
#define DFLE_LUA_EVENTS_H

#include "lua/core/dfle_lua.h"

#include "dfle/model_events.h"

/* The options {years =, dt = 1, seed = 1, hold =} at stack index idx,
 * for fn ("model:run_events"); hold defaults to hold_default. */
void dfle_lua_read_events_opts(lua_State *L, int idx, const char *fn, int hold_default,
                               dfle_events_opts *o);

/* Pushes {events, steps, years, mean = sum / years, se = sqrt(sum2) /
 * years} of n values (mean and se NaN where sum is). */
void dfle_lua_push_events_result(lua_State *L, const dfle_events_result *res, const double *sum,
                                 const double *sum2, size_t n);

/* ls:run_events{...} (lua_landscape_events.c). */
int dfle_lua_ls_run_events(lua_State *L);

#endif
