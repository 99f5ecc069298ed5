/*
 * lua_chi.c - dfle.chi and dfle.concavity: chi, k_sn and the concavity
 * of DEM profiles and networks, models and landscapes (chi.h).
 *
 *   local c = dfle.chi(net, { theta_ref = 0.45, A_min = 1e5 })
 *   c.k_sn, c.r2, c:get("chi"), c:get("k_sn"), c:write_csv("chi.csv")
 *   local k = dfle.concavity(net, { method = "chi", A_min = 1e5 })
 *
 * A source becomes a drainage tree here: its cells, their receivers and
 * the flow length to each, their area and elevation, copied into the
 * "dfle.chi" object (which outlives the source); where the cells are
 * (E, N), their slope and the source's record of provenance go with it.
 * The object's user values: 1 the record, 2 the source (a k_sn map draws
 * a landscape's own relief), 3 the source's CRS (WKT) or nil.
 */
#include "lua/analysis/lua_chi.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/dem.h"
#include "dfle/drainage.h"
#include "dfle/landscape.h"
#include "lua/objects/lua_landscape.h"

static void chi_free(void *obj)
{
    dfle_lua_chi_data *c = obj;
    if (c == NULL)
        return;
    free(c->rcv);
    free(c->len);
    free(c->A);
    free(c->z);
    free(c->S);
    free(c->E);
    free(c->N);
    free(c->x);
    dfle_chi_release(&c->c);
    free(c);
}

/* n doubles, or raise (the object frees what it holds). */
static double *alloc_doubles(lua_State *L, size_t n)
{
    double *v = malloc((n ? n : 1) * sizeof *v);
    if (v == NULL)
        luaL_error(L, "dfle.chi: out of memory (%d cells)", (int)n);
    return v;
}

static dfle_lua_chi_data *new_chi(lua_State *L, size_t n, int with_E, int with_S, int with_x)
{
    dfle_lua_object *u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_CHI, 3);
    dfle_lua_chi_data *c = calloc(1, sizeof *c);
    if (c == NULL)
        luaL_error(L, "dfle.chi: out of memory");
    u->ptr = c;
    c->n = n;
    if ((c->rcv = malloc((n ? n : 1) * sizeof *c->rcv)) == NULL)
        luaL_error(L, "dfle.chi: out of memory (%d cells)", (int)n);
    c->len = alloc_doubles(L, n);
    c->A = alloc_doubles(L, n);
    c->z = alloc_doubles(L, n);
    if (with_S)
        c->S = alloc_doubles(L, n);
    if (with_E)
        c->E = alloc_doubles(L, n), c->N = alloc_doubles(L, n);
    if (with_x)
        c->x = alloc_doubles(L, n);
    return c;
}

/* A DEM profile or network: its receivers (1-based, 0 for the outlet)
 * and flow distances to the outlet give the links. */
static dfle_lua_chi_data *from_profile(lua_State *L, int arg, dfle_record *rec)
{
    dfle_profile *p = dfle_lua_check_object(L, arg, "dfle.profile");
    const size_t n = dfle_profile_size(p), *r1 = dfle_profile_receiver(p);
    const double *d = dfle_profile_field(p, DFLE_PROFILE_D);
    dfle_lua_chi_data *c = new_chi(L, n, 1, 1, 1);
    dfle_slope_opts so = dfle_profile_slope(p);
    memcpy(c->E, dfle_profile_field(p, DFLE_PROFILE_E), n * sizeof *c->E);
    memcpy(c->N, dfle_profile_field(p, DFLE_PROFILE_N), n * sizeof *c->N);
    memcpy(c->x, dfle_profile_field(p, DFLE_PROFILE_X), n * sizeof *c->x);
    memcpy(c->A, dfle_profile_field(p, DFLE_PROFILE_A), n * sizeof *c->A);
    memcpy(c->z, dfle_profile_field(p, DFLE_PROFILE_Z), n * sizeof *c->z);
    memcpy(c->S, dfle_profile_field(p, DFLE_PROFILE_S), n * sizeof *c->S);
    for (size_t i = 0; i < n; i++) {
        c->rcv[i] = r1[i] > 0 ? r1[i] - 1 : i;
        c->len[i] = r1[i] > 0 ? d[i] - d[r1[i] - 1] : 0;
    }
    snprintf(c->kind, sizeof c->kind, "%s", dfle_profile_is_network(p) ? "network" : "profile");
    /* k_sn over the interval the profile's slopes are measured over: ds,
     * or three cells where slope is measured over a drop dz */
    if (so.ds > 0) {
        c->window = so.ds;
    } else {
        double *l = alloc_doubles(L, n);
        size_t k = 0;
        for (size_t i = 0; i < n; i++)
            if (c->rcv[i] != i)
                l[k++] = c->len[i];
        c->window = 0;
        if (k > 0) {
            double m = 0;
            for (size_t i = 0; i < k; i++) /* the shortest link: a cell's width */
                m = i == 0 || l[i] < m ? l[i] : m;
            c->window = 3 * m;
        }
        free(l);
    }
    dfle_profile_describe(p, rec);
    return c;
}

/* A model: its nodes, receivers and flow lengths; slope S to the receiver. */
static dfle_lua_chi_data *from_model(lua_State *L, int arg, dfle_record *rec)
{
    dfle_model *m = dfle_lua_check_model(L, arg);
    const size_t n = dfle_model_size(m);
    const double *x = dfle_lua_model_field(L, arg, DFLE_FIELD_X, "dfle.chi");
    const double *z = dfle_lua_model_field(L, arg, DFLE_FIELD_Z, "dfle.chi");
    const double *A = dfle_lua_model_field(L, arg, DFLE_FIELD_A, "dfle.chi");
    const double *S = dfle_lua_model_field(L, arg, DFLE_FIELD_S, "dfle.chi");
    const size_t *r = dfle_model_receivers(m);
    const double *len = dfle_model_flow_length(m);
    dfle_lua_chi_data *c = new_chi(L, n, 0, 1, 1);
    memcpy(c->x, x, n * sizeof *x);
    memcpy(c->z, z, n * sizeof *z);
    memcpy(c->A, A, n * sizeof *A);
    memcpy(c->S, S, n * sizeof *S);
    for (size_t i = 0; i < n; i++) {
        c->rcv[i] = r[i];
        c->len[i] = r[i] != i ? len[i] : 0;
    }
    snprintf(c->kind, sizeof c->kind, "model");
    dfle_lua_record_model(L, rec, arg);
    return c;
}

/* A landscape: its data cells (NoData left out), D8 receivers and
 * lengths as routed now; k_sn and the line on its channel cells. */
static dfle_lua_chi_data *from_landscape(lua_State *L, int arg, dfle_record *rec)
{
    dfle_landscape *ls = dfle_lua_check_object(L, arg, "dfle.landscape");
    const size_t nx = dfle_landscape_nx(ls), ny = dfle_landscape_ny(ls), ncell = nx * ny;
    const double dx = dfle_landscape_dx(ls), dy = dfle_landscape_dy(ls);
    double *z = lua_newuserdatauv(L, 4 * ncell * sizeof *z, 0), *A = z + ncell, *S = A + ncell,
           *ch = S + ncell, x0, y0, a_ch = HUGE_VAL;
    size_t *index = lua_newuserdatauv(L, ncell * sizeof *index, 0), n = 0;
    const dfle_drainage *dr;
    const uint32_t *rv;
    const unsigned char *dir;
    dfle_lua_chi_data *c;
    dfle_error err;

    if (dfle_landscape_get(ls, DFLE_LS_Z, z, &err) != DFLE_OK ||
        dfle_landscape_get(ls, DFLE_LS_A, A, &err) != DFLE_OK ||
        dfle_landscape_get(ls, DFLE_LS_S, S, &err) != DFLE_OK ||
        dfle_landscape_get(ls, DFLE_LS_CHANNEL, ch, &err) != DFLE_OK)
        dfle_lua_raise(L, &err);
    dr = dfle_landscape_drainage(ls); /* routed by the calls above */
    rv = dfle_drainage_receivers(dr);
    dir = dfle_drainage_dir(dr);
    lua_getfield(L, arg, "x0");
    lua_getfield(L, arg, "y0");
    x0 = lua_tonumber(L, -2), y0 = lua_tonumber(L, -1);
    lua_pop(L, 2);
    for (size_t k = 0; k < ncell; k++)
        index[k] = isnan(z[k]) ? SIZE_MAX : n++;
    c = new_chi(L, n, 1, 1, 0);
    for (size_t k = 0; k < ncell; k++) {
        size_t i = index[k];
        if (i == SIZE_MAX)
            continue;
        c->z[i] = z[k], c->A[i] = A[k], c->S[i] = S[k];
        c->E[i] = x0 + ((double)(k % nx) + 0.5) * dx;
        c->N[i] = y0 - ((double)(k / nx) + 0.5) * dy;
        /* a cell off the grid's edge or in a pit is its own base level */
        c->rcv[i] = dir[k] < 8 && index[rv[k]] != SIZE_MAX ? index[rv[k]] : i;
        c->len[i] = c->rcv[i] != i ? dfle_drainage_length(dr, dir[k]) : 0;
        if (ch[k] > 0)
            a_ch = fmin(a_ch, A[k]);
    }
    snprintf(c->kind, sizeof c->kind, "landscape");
    c->A_min = a_ch < HUGE_VAL ? a_ch : 0; /* the channel cells, A >= A0 */
    dfle_record_section(rec, "landscape", NULL);
    dfle_record_number(rec, "nx", (double)nx, NULL);
    dfle_record_number(rec, "ny", (double)ny, NULL);
    dfle_record_number(rec, "dx", dx, "m");
    dfle_record_number(rec, "dy", dy, "m");
    dfle_record_number(rec, "data_cells", (double)n, NULL);
    dfle_record_number(rec, "time", dfle_landscape_time(ls), "yr");
    lua_getiuservalue(L, arg, UV_CRS);
    lua_setiuservalue(L, -2, 3);
    return c;
}

/* Array `key` of the table at t (n values, or *n set by the first). */
static const double *table_array(lua_State *L, int t, const char *key, size_t *n, int need)
{
    char what[48];
    size_t m;
    double *v;
    if (lua_getfield(L, t, key) == LUA_TNIL) {
        lua_pop(L, 1);
        if (need)
            luaL_error(L, "dfle.chi: the table needs '%s' (an array of numbers)", key);
        return NULL;
    }
    snprintf(what, sizeof what, "chi: %s", key);
    v = dfle_lua_check_array(L, -1, what, &m);
    if (*n == 0)
        *n = m;
    else if (m != *n)
        luaL_error(L, "dfle.chi: '%s' has %d values, 'z' %d", key, (int)m, (int)*n);
    return v;
}

/* A table {z =, A =, receiver =, length = | d =, E =, N =, x =, S =}. */
static dfle_lua_chi_data *from_table(lua_State *L, int t, dfle_record *rec)
{
    static const char *const keys[] = {"z", "A", "receiver", "length", "d", "E", "N", "x", "S",
                                       NULL};
    size_t n = 0;
    const double *z, *A, *rcv, *len, *d, *E, *N, *x, *S;
    dfle_lua_chi_data *c;
    dfle_lua_read_params(L, t, "chi", NULL, 0, keys);
    z = table_array(L, t, "z", &n, 1);
    A = table_array(L, t, "A", &n, 1);
    rcv = table_array(L, t, "receiver", &n, 1);
    len = table_array(L, t, "length", &n, 0);
    d = table_array(L, t, "d", &n, 0);
    E = table_array(L, t, "E", &n, 0);
    N = table_array(L, t, "N", &n, 0);
    x = table_array(L, t, "x", &n, 0);
    S = table_array(L, t, "S", &n, 0);
    if ((len == NULL) == (d == NULL))
        luaL_error(L, "dfle.chi: give the flow length of each cell to its receiver ('length', m) "
                      "or its flow distance to the outlet ('d', m), not both");
    if ((E == NULL) != (N == NULL))
        luaL_error(L, "dfle.chi: give both 'E' and 'N', or neither");
    c = new_chi(L, n, E != NULL, S != NULL, x != NULL);
    for (size_t i = 0; i < n; i++) {
        double r = rcv[i];
        if (!(r >= 0 && r <= (double)n && r == floor(r)))
            luaL_error(L, "dfle.chi: receiver[%d] must be the 1-based index of a cell, or 0 for "
                          "a base-level cell (got %s)", (int)i + 1, dfle_lua_number_text(L, r));
        c->rcv[i] = r > 0 ? (size_t)r - 1 : i;
    }
    for (size_t i = 0; i < n; i++) {
        c->z[i] = z[i], c->A[i] = A[i];
        c->len[i] = c->rcv[i] == i ? 0 : len != NULL ? len[i] : d[i] - d[c->rcv[i]];
        if (c->rcv[i] != i && !(c->len[i] > 0 && isfinite(c->len[i])))
            luaL_error(L, "dfle.chi: cell %d drains to cell %d over %s m (must be > 0%s)",
                       (int)i + 1, (int)c->rcv[i] + 1, dfle_lua_number_text(L, c->len[i]),
                       d != NULL ? ": d must grow upstream" : "");
        if (S != NULL) c->S[i] = S[i];
        if (E != NULL) c->E[i] = E[i], c->N[i] = N[i];
        if (x != NULL) c->x[i] = x[i];
    }
    snprintf(c->kind, sizeof c->kind, "table");
    dfle_record_section(rec, "data", "table");
    dfle_record_number(rec, "cells", (double)n, NULL);
    return c;
}

dfle_lua_chi_data *dfle_lua_chi_source(lua_State *L, int arg, dfle_record *rec)
{
    dfle_lua_chi_data *c;
    arg = lua_absindex(L, arg);
    if (luaL_testudata(L, arg, "dfle.profile") != NULL)
        c = from_profile(L, arg, rec);
    else if (luaL_testudata(L, arg, DFLE_LUA_MODEL) != NULL)
        c = from_model(L, arg, rec);
    else if (luaL_testudata(L, arg, DFLE_LUA_LANDSCAPE) != NULL)
        c = from_landscape(L, arg, rec);
    else if (lua_istable(L, arg))
        c = from_table(L, arg, rec);
    else
        return luaL_error(L, "dfle.chi: expected a dfle.profile (a DEM profile or network), a "
                             "dfle.model, a dfle.landscape or a table {z =, A =, receiver =, "
                             "length = | d =}, got %s", dfle_lua_typename(L, arg)),
               NULL;
    lua_pushvalue(L, arg);
    lua_setiuservalue(L, -2, 2); /* the source, for maps of it */
    return c;
}

void dfle_lua_chi_tree(const dfle_lua_chi_data *c, dfle_tree *t)
{
    *t = (dfle_tree){c->n, c->rcv, c->len, c->A, c->z};
}

/* Raise a chi.h message as the binding's ("dfle.chi: ..."), cells 1-based. */
static int raise_chi(lua_State *L, const char *fn, const dfle_error *err)
{
    const char *m = err->msg;
    if (strncmp(m, "chi: ", 5) == 0)
        m += 5;
    else if (strncmp(m, "concavity: ", 11) == 0)
        m += 11;
    return luaL_error(L, "dfle.%s: %s%s", fn, m,
                      strstr(m, "cell ") != NULL ? " (cells numbered from 0)" : "");
}

/* dfle.chi(source [, {theta_ref = 0.45, A0 = 1, A_min =, window =}]) */
static int l_chi(lua_State *L)
{
    dfle_chi_opts o;
    dfle_lua_chi_data *c;
    dfle_record *rec;
    dfle_tree t;
    dfle_error err;
    double theta = 0.45, A0 = 1, A_min = NAN, window = NAN;
    const dfle_lua_param params[] = {{"theta_ref", &theta}, {"A0", &A0}, {"A_min", &A_min},
                                     {"window", &window}};
    int st;

    lua_settop(L, 2);
    if (!lua_isnil(L, 2))
        luaL_checktype(L, 2, LUA_TTABLE);
    dfle_lua_read_params(L, 2, "chi", params, 4, NULL);
    rec = dfle_lua_push_record(L, "chi and k_sn: one row per cell, each with its receiver");
    c = dfle_lua_chi_source(L, 1, rec);
    lua_pushvalue(L, 3);
    lua_setiuservalue(L, -2, 1); /* the record */
    dfle_chi_opts_default(&o);
    o.theta_ref = theta;
    o.A0 = A0;
    o.A_min = isnan(A_min) ? c->A_min : A_min;
    o.window = isnan(window) ? c->window : window;
    dfle_lua_chi_tree(c, &t);
    st = dfle_chi_compute(&t, &o, &c->c, &err);
    if (st != DFLE_OK)
        return raise_chi(L, "chi", &err);
    dfle_record_section(rec, "chi", "Perron and Royden 2013");
    dfle_record_param_number(rec, "theta_ref", o.theta_ref, "-");
    dfle_record_param_number(rec, "A0", o.A0, "m^2");
    dfle_record_param_number(rec, "A_min", o.A_min, "m^2");
    dfle_record_param_number(rec, "window", o.window, "m");
    {
        char unit[24];
        snprintf(unit, sizeof unit, "m^%.6g", 2 * o.theta_ref);
        dfle_record_number(rec, "k_sn", c->c.k_sn_fit, unit);
    }
    dfle_record_number(rec, "r2", c->c.r2, "-");
    dfle_record_number(rec, "cells_fitted", (double)c->c.n_fit, NULL);
    return 1;
}

/* ---- The dfle.chi object -------------------------------------------- */

static dfle_lua_chi_data *check_chi(lua_State *L, int arg)
{
    return dfle_lua_check_object(L, arg, DFLE_LUA_CHI);
}

static const char *const chi_fields[] = {"chi", "k_sn", "z", "A", "S", "d", "E", "N", "x",
                                         "z_base", "receiver", NULL};

/* The values of field k of c, or NULL when c has none. */
static const double *field_of(const dfle_lua_chi_data *c, int k)
{
    const double *v[] = {c->c.chi, c->c.k_sn, c->z, c->A, c->S, c->c.d, c->E, c->N, c->x,
                         c->c.z_base};
    return k < 10 ? v[k] : NULL;
}

static int l_chi_get(lua_State *L)
{
    dfle_lua_chi_data *c = check_chi(L, 1);
    int k = dfle_lua_check_option(L, 2, "chi:get", "the field", chi_fields);
    if (k == 10) {
        lua_createtable(L, (int)c->n, 0);
        for (size_t i = 0; i < c->n; i++) {
            lua_pushinteger(L, c->rcv[i] == i ? 0 : (lua_Integer)c->rcv[i] + 1);
            lua_rawseti(L, -2, (lua_Integer)i + 1);
        }
        return 1;
    }
    if (field_of(c, k) == NULL)
        return luaL_error(L, "dfle.chi:get: this %s has no '%s'", c->kind, chi_fields[k]);
    dfle_lua_push_array(L, field_of(c, k), c->n);
    return 1;
}

/* c:write_csv(path [, {record =}]): E, N (where known), x, d, z, A, S,
 * chi, k_sn, z_base, receiver. */
static int l_chi_write_csv(lua_State *L)
{
    static const char *const keys[] = {"record", NULL};
    dfle_lua_chi_data *c = check_chi(L, 1);
    const char *path = dfle_lua_check_string(L, 2, "chi:write_csv", "the path"), *jpath;
    dfle_column cols[11];
    double *rcv;
    char ksn_unit[24];
    size_t nc = 0;
    dfle_record *rec;
    dfle_error err;

    lua_settop(L, 3);
    if (!lua_isnil(L, 3)) {
        luaL_checktype(L, 3, LUA_TTABLE);
        dfle_lua_read_params(L, 3, "chi:write_csv", NULL, 0, keys);
    }
    lua_getiuservalue(L, 1, 1);
    rec = *(dfle_record **)lua_touserdata(L, -1);
    dfle_record_stamp(rec);
    jpath = dfle_lua_record_path(L, rec, 3, path, "chi:write_csv");
    rcv = lua_newuserdatauv(L, (c->n ? c->n : 1) * sizeof *rcv, 0);
    for (size_t i = 0; i < c->n; i++)
        rcv[i] = c->rcv[i] == i ? 0 : (double)c->rcv[i] + 1;
    snprintf(ksn_unit, sizeof ksn_unit, "m^%.6g", 2 * c->c.theta_ref);
    if (c->E != NULL) {
        cols[nc++] = (dfle_column){"E", "m", c->E, NULL};
        cols[nc++] = (dfle_column){"N", "m", c->N, NULL};
    }
    if (c->x != NULL)
        cols[nc++] = (dfle_column){"x", "m", c->x, NULL};
    cols[nc++] = (dfle_column){"d", "m", c->c.d, NULL};
    cols[nc++] = (dfle_column){"z", "m", c->z, NULL};
    cols[nc++] = (dfle_column){"A", "m^2", c->A, NULL};
    if (c->S != NULL)
        cols[nc++] = (dfle_column){"S", "-", c->S, NULL};
    cols[nc++] = (dfle_column){"chi", "m", c->c.chi, NULL};
    cols[nc++] = (dfle_column){"k_sn", ksn_unit, c->c.k_sn, NULL};
    cols[nc++] = (dfle_column){"z_base", "m", c->c.z_base, NULL};
    cols[nc++] = (dfle_column){"receiver", NULL, rcv, NULL};
    if (dfle_table_write(path, "chi:write_csv", rec, cols, nc, c->n, 0, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_record_done(L, rec, path, jpath);
    lua_settop(L, 1);
    return 1;
}

static int l_chi_property(lua_State *L)
{
    dfle_lua_chi_data *c = check_chi(L, 1);
    const char *key = lua_tostring(L, 2);
    const struct { const char *k; double v; } num[] = {
        {"theta_ref", c->c.theta_ref}, {"A0", c->c.A0},         {"A_min", c->c.A_min},
        {"window", c->c.window},       {"k_sn", c->c.k_sn_fit}, {"M_chi", c->c.M_chi},
        {"r2", c->c.r2}};
    for (size_t k = 0; k < sizeof num / sizeof num[0]; k++)
        if (strcmp(key, num[k].k) == 0) {
            lua_pushnumber(L, num[k].v);
            return 1;
        }
    if (strcmp(key, "n") == 0)
        lua_pushinteger(L, (lua_Integer)c->n);
    else if (strcmp(key, "n_fit") == 0)
        lua_pushinteger(L, (lua_Integer)c->c.n_fit);
    else if (strcmp(key, "n_base") == 0)
        lua_pushinteger(L, (lua_Integer)c->c.n_base);
    else if (strcmp(key, "kind") == 0)
        lua_pushstring(L, c->kind);
    else
        lua_pushnil(L);
    return 1;
}

static int l_chi_len(lua_State *L)
{
    lua_pushinteger(L, (lua_Integer)check_chi(L, 1)->n);
    return 1;
}

static void chi_describe(lua_State *L, void *obj)
{
    const dfle_lua_chi_data *c = obj;
    lua_pushfstring(L, "dfle.chi(%s, %d cells, theta_ref = %f, k_sn = %f m^%f, R^2 = %f)",
                    c->kind, (int)c->n, c->c.theta_ref, c->c.k_sn_fit, 2 * c->c.theta_ref,
                    c->c.r2);
}

/* ---- dfle.concavity ------------------------------------------------- */

static const char *const methods[] = {"chi", "slope_area", NULL};

/* dfle.concavity(source [, {method = "chi", A_min =, A_max =, range =,
 * A0 = 1, nbins = 100}]) -> {theta, k_s, r2, n, ...} or nil, message */
static int l_concavity(lua_State *L)
{
    static const char *const other[] = {"method", "range", NULL};
    dfle_concavity_opts o;
    dfle_concavity res;
    dfle_error err;
    double A_min = NAN, A_max = 0, A0 = 1, nbins = 100;
    const dfle_lua_param params[] = {{"A_min", &A_min}, {"A_max", &A_max}, {"A0", &A0},
                                     {"nbins", &nbins}};
    int method = DFLE_CONCAVITY_CHI, st;

    lua_settop(L, 2);
    if (!lua_isnil(L, 2))
        luaL_checktype(L, 2, LUA_TTABLE);
    dfle_lua_read_params(L, 2, "concavity", params, 4, other);
    dfle_concavity_opts_default(&o);
    if (lua_istable(L, 2)) {
        if (lua_getfield(L, 2, "method") != LUA_TNIL)
            method = dfle_lua_check_option(L, -1, "concavity", "method", methods);
        if (lua_getfield(L, 2, "range") != LUA_TNIL) {
            if (!lua_istable(L, -1) || lua_rawlen(L, -1) != 2 ||
                lua_rawgeti(L, -1, 1) != LUA_TNUMBER || lua_rawgeti(L, -2, 2) != LUA_TNUMBER)
                luaL_error(L, "dfle.concavity: 'range' must be {lo, hi}, the theta searched");
            o.theta_lo = lua_tonumber(L, -2), o.theta_hi = lua_tonumber(L, -1);
        }
        lua_settop(L, 2);
    }
    o.A0 = A0;
    o.A_max = A_max;
    o.nbins = (size_t)dfle_lua_check_whole(L, nbins, "concavity", "nbins", 1, 1e6);
    if (method == DFLE_CONCAVITY_CHI) {
        dfle_record *rec = dfle_lua_push_empty_record(L);
        dfle_lua_chi_data *c = dfle_lua_chi_source(L, 1, rec);
        dfle_tree t;
        o.A_min = isnan(A_min) ? c->A_min : A_min;
        dfle_lua_chi_tree(c, &t);
        st = dfle_concavity_chi(&t, &o, &res, &err);
    } else {
        const double *A, *S;
        size_t n = dfle_lua_slope_area(L, 1, "concavity", &A, &S);
        o.A_min = isnan(A_min) ? 0 : A_min;
        st = dfle_concavity_slope_area(n, A, S, &o, &res, &err);
    }
    if (st == DFLE_EFIT) {
        lua_pushnil(L);
        lua_pushfstring(L, "dfle.concavity: %s", strncmp(err.msg, "concavity: ", 11) == 0
                                                     ? err.msg + 11 : err.msg);
        return 2;
    }
    if (st != DFLE_OK)
        return raise_chi(L, "concavity", &err);
    lua_createtable(L, 0, 12);
    lua_pushstring(L, methods[method]), lua_setfield(L, -2, "method");
    lua_pushnumber(L, res.theta), lua_setfield(L, -2, "theta");
    lua_pushnumber(L, res.k_s), lua_setfield(L, -2, "k_s");
    lua_pushnumber(L, res.r2), lua_setfield(L, -2, "r2");
    lua_pushinteger(L, (lua_Integer)res.n), lua_setfield(L, -2, "n");
    lua_pushnumber(L, o.A_min), lua_setfield(L, -2, "A_min");
    lua_pushnumber(L, o.A_max), lua_setfield(L, -2, "A_max");
    lua_pushnumber(L, o.A0), lua_setfield(L, -2, "A0");
    lua_pushboolean(L, res.at_bound), lua_setfield(L, -2, "at_bound");
    if (method == DFLE_CONCAVITY_CHI) {
        lua_createtable(L, 2, 0);
        lua_pushnumber(L, res.theta_lo), lua_rawseti(L, -2, 1);
        lua_pushnumber(L, res.theta_hi), lua_rawseti(L, -2, 2);
        lua_setfield(L, -2, "range");
        lua_createtable(L, 0, 2);
        dfle_lua_push_array(L, res.curve_theta, res.ncurve), lua_setfield(L, -2, "theta");
        dfle_lua_push_array(L, res.curve_r2, res.ncurve), lua_setfield(L, -2, "r2");
        lua_setfield(L, -2, "curve");
    } else {
        lua_pushinteger(L, (lua_Integer)o.nbins), lua_setfield(L, -2, "nbins");
    }
    if (res.at_bound) {
        /* the range searched, not the data, sets this theta: say so */
        lua_pushfstring(L, "the most collinear theta is the end of the range searched "
                           "(%f..%f): the range, not the data, sets theta = %f; widen 'range'",
                        res.theta_lo, res.theta_hi, res.theta);
        dfle_lua_warn(L, "concavity", lua_tostring(L, -1));
        lua_setfield(L, -2, "note");
    }
    dfle_concavity_release(&res);
    dfle_lua_strict_table(L, -1, "a dfle.concavity result");
    return 1;
}

void dfle_lua_open_chi(lua_State *L)
{
    static const luaL_Reg chi_methods[] = {
        {"get", l_chi_get}, {"write_csv", l_chi_write_csv}, {NULL, NULL}};
    static const luaL_Reg chi_meta[] = {{"__len", l_chi_len}, {NULL, NULL}};
    static const dfle_lua_type chi_type = {
        .name = DFLE_LUA_CHI, .free = chi_free, .describe = chi_describe,
        .methods = chi_methods, .property = l_chi_property, .meta = chi_meta,
        .fields = "n, kind, theta_ref, A0, A_min, window, k_sn, M_chi, r2, n_fit, n_base",
        .closable = 1,
    };
    dfle_lua_register(L, &chi_type);
    lua_pushcfunction(L, l_chi);
    lua_setfield(L, -2, "chi");
    lua_pushcfunction(L, l_concavity);
    lua_setfield(L, -2, "concavity");
    dfle_lua_open_chi_plot(L);
}
