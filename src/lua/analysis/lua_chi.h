/*
 * lua_chi.h - what lua_chi.c (dfle.chi, dfle.concavity) shares with
 * lua_chi_plot.c (dfle.plot.chi, slope_area_chi, ksn_map).  Internal to
 * the binding.
 */
#ifndef DFLE_LUA_CHI_H
#define DFLE_LUA_CHI_H

#include "lua/core/dfle_lua.h"

#include "dfle/chi.h"
#include "dfle/record.h"

#define DFLE_LUA_CHI "dfle.chi"

/* A source's drainage tree and what the results need of it. */
typedef struct dfle_lua_chi_data {
    size_t n;
    size_t *rcv;           /* 0-based; rcv[i] == i: base level           */
    double *len, *A, *z;   /* flow length [m], area [m^2], elevation [m] */
    double *S, *E, *N, *x; /* slope, cell centre [m], x [m]; or NULL     */
    char kind[16];         /* "profile", "network", "model", ...         */
    double window, A_min;  /* the source's defaults                      */
    dfle_chi c;            /* the results, once computed                 */
} dfle_lua_chi_data;

/* The source at arg as a new dfle.chi object pushed on the stack (its
 * provenance into rec); raises for anything else. */
dfle_lua_chi_data *dfle_lua_chi_source(lua_State *L, int arg, dfle_record *rec);
void dfle_lua_chi_tree(const dfle_lua_chi_data *c, dfle_tree *t);

/* dfle_lua_open_chi (dfle_lua.h) adds dfle.chi and dfle.concavity;
 * this adds their plots to dfle.plot (lua_chi_plot.c). */
void dfle_lua_open_chi_plot(lua_State *L);

#endif
