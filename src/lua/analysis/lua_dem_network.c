/*
 * lua_dem_network.c - a model on a DEM's channel network from Lua:
 *
 *   local net = dem:network{ A_min = 1e5, outlet = {E, N} }
 *   local m = dfle.model{ network = net, k_w = 0.05, b = 0.3,
 *                         router = dfle.router.process{} }
 *
 * Every cell of the network is a node draining to its receiver over the
 * flow distance between the two cell centres (a diagonal step is sqrt 2
 * cells long), with the cell's drainage area and the width w = k_w A^b;
 * cells whose receiver is not in the network (the outlet) are base
 * levels, and the model starts from the DEM's elevations.  The model
 * holds the network (a "dfle.network" object in its channel slot), so
 * the profile may be dropped.
 */
#include "lua/analysis/lua_dem.h"

#include "dfle/channel.h"
#include "dfle/network.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DFLE_LUA_NETWORK "dfle.network"

typedef struct { dfle_network *net; DFLE_LUA_IN_USE; } dfle_lua_network;

static void network_free(void *obj) { dfle_network_free(obj); }

static void network_describe(lua_State *L, void *obj)
{
    lua_pushfstring(L, "dfle.network(n = %d)", (int)dfle_network_size(obj));
}

static int network_property(lua_State *L)
{
    dfle_network *net = dfle_lua_check_object(L, 1, DFLE_LUA_NETWORK);
    if (strcmp(lua_tostring(L, 2), "n") == 0) {
        lua_pushinteger(L, (lua_Integer)dfle_network_size(net));
        return 1;
    }
    return 0;
}

void dfle_lua_open_network(lua_State *L)
{
    static const dfle_lua_type type = {
        .name = DFLE_LUA_NETWORK, .free = network_free, .describe = network_describe,
        .property = network_property, .fields = "n",
    };
    dfle_lua_register(L, &type);
}

/* The arrays of a shape, in one userdata: freed by the collector
 * whatever raises meanwhile. */
typedef struct shape_arrays {
    size_t *recv;
    double *len, *A, *w;
} shape_arrays;

static shape_arrays push_arrays(lua_State *L, size_t n)
{
    const size_t bytes = n * (sizeof(size_t) + 3 * sizeof(double));
    char *b = lua_newuserdatauv(L, bytes, 0);
    shape_arrays s;
    s.len = (double *)b;
    s.A = s.len + n;
    s.w = s.A + n;
    s.recv = (size_t *)(s.w + n);
    return s;
}

int dfle_lua_model_network(lua_State *L, int opts, const dfle_network **out)
{
    const char *fn = "model";
    dfle_profile *p;
    const double *D, *A;
    const size_t *rcv;
    dfle_channel_opts co;
    double k_w, b;
    size_t n;
    shape_arrays s;
    dfle_network_shape sh;
    dfle_lua_network *u;
    dfle_error err;

    *out = NULL;
    if (!lua_istable(L, opts) || lua_getfield(L, opts, "network") == LUA_TNIL) {
        if (lua_istable(L, opts)) {
            lua_pop(L, 1);
            for (const char *const *k = (const char *const[]){"k_w", "b", NULL}; *k; k++)
                if (lua_getfield(L, opts, *k) != LUA_TNIL)
                    luaL_error(L, "dfle.%s: '%s' is for a DEM network (network =); a channel "
                                  "has its own widths", fn, *k);
                else
                    lua_pop(L, 1);
        }
        return 0;
    }
    if (luaL_testudata(L, -1, DFLE_LUA_PROFILE) == NULL)
        luaL_error(L, "dfle.%s: parameter 'network' must be a dfle.profile (dem:network{...}), "
                      "got %s", fn, dfle_lua_typename(L, -1));
    p = dfle_lua_check_object(L, lua_gettop(L), DFLE_LUA_PROFILE);
    if (lua_getfield(L, opts, "channel") != LUA_TNIL)
        luaL_error(L, "dfle.%s: give 'channel' or 'network', not both", fn);
    lua_pop(L, 1);
    dfle_channel_opts_default(&co);
    k_w = co.k_w, b = co.b;
    {
        const dfle_lua_param params[] = {{"k_w", &k_w}, {"b", &b}};
        for (size_t k = 0; k < 2; k++)
            if (lua_getfield(L, opts, params[k].name) != LUA_TNIL) {
                if (!lua_isnumber(L, -1))
                    luaL_error(L, "dfle.%s: parameter '%s' must be a number, got %s", fn,
                               params[k].name, dfle_lua_typename(L, -1));
                *params[k].dst = lua_tonumber(L, -1);
                lua_pop(L, 1);
            } else {
                lua_pop(L, 1);
            }
    }
    if (!(isfinite(k_w) && k_w > 0 && isfinite(b)))
        luaL_error(L, "dfle.%s: k_w must be > 0 and b finite (got k_w = %f, b = %f)", fn, k_w, b);

    n = dfle_profile_size(p);
    D = dfle_profile_field(p, DFLE_PROFILE_D);
    A = dfle_profile_field(p, DFLE_PROFILE_A);
    rcv = dfle_profile_receiver(p);
    s = push_arrays(L, n);
    for (size_t i = 0; i < n; i++) {
        s.recv[i] = rcv[i] == 0 ? i : rcv[i] - 1;
        s.len[i] = rcv[i] == 0 ? 1.0 : D[i] - D[rcv[i] - 1];
        s.A[i] = A[i];
        s.w[i] = k_w * pow(A[i], b);
    }
    memset(&sh, 0, sizeof sh);
    sh.receiver = s.recv, sh.length = s.len, sh.A = s.A, sh.w = s.w, sh.x = D;
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_NETWORK, 0);
    if (dfle_network_new(n, &u->net, &err) != DFLE_OK ||
        dfle_network_set(u->net, &sh, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    /* Keep only the network object (under the profile and the arrays). */
    lua_replace(L, -3);
    lua_pop(L, 1);
    *out = u->net;
    return 1;
}

int dfle_lua_model_network_z(lua_State *L, int opts, dfle_model *m)
{
    dfle_profile *p;
    dfle_error err;
    lua_getfield(L, opts, "network");
    p = dfle_lua_check_object(L, lua_gettop(L), DFLE_LUA_PROFILE);
    lua_pop(L, 1);
    if (dfle_model_set_z(m, dfle_profile_field(p, DFLE_PROFILE_Z), dfle_profile_size(p), &err) !=
        DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 0;
}
