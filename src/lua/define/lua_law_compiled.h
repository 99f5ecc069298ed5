/*
 * lua_law_compiled.h - the middle layer of a dfle.law.define law: its
 * functions run as compiled programs (lua_trace.h), checked against the
 * Lua sweep below (lua_law_sweep.h).  Internal to the binding.
 */
#ifndef DFLE_LUA_LAW_COMPILED_H
#define DFLE_LUA_LAW_COMPILED_H

#include "lua/define/lua_law_sweep.h"

enum { TRY_LUA = 1 };
/* Run `op` compiled: 0, a negative dfle_status, or TRY_LUA when the Lua
 * sweep must do it instead. */
int ll_compiled_sweep(lua_law *ll, int op, const dfle_law_ctx *ctx, const double *F_in,
                      double *out, dfle_error *err);
/* The integrand compiled: 0 with *g set, a negative dfle_status, or
 * TRY_LUA when the Lua call must do it. */
int ll_compiled_integrand(lua_law *ll, double h, double v, double lambda, double *g,
                          dfle_error *err);
/* Whether the compiled programs can give dE/d ln S now (for the call
 * after the last flow_factor): compiled, checked against Lua, guards
 * current, every operation differentiable. */
int ll_compiled_can_dlnS(const lua_law *ll);
/* Check again the guards of the programs rate_dlnS needs whose epoch has
 * moved (inside the shell: T is the law's thread).  Never raises. */
void ll_compiled_refresh(lua_law *ll);
/* dE[0..n) = dE/d ln S by forward-mode differentiation of the programs
 * (law.h's rate_dlnS); NaN where there is none to give (a program not
 * ready, out of memory, an area not in the frequency memo). */
void ll_compiled_rate_dlnS(lua_law *ll, const dfle_law_ctx *ctx, const double *F,
                           const double *E, const dfle_flow_dlnS *d, double *dE);
/* Push law:compiled()'s table for ll: { factor =, rate =, integrand = },
 * each true (compiled), false (not used yet) or a string (why it runs
 * as Lua). */
void ll_push_compiled(lua_State *L, const lua_law *ll);

#endif
