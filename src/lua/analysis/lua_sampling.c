/*
 * lua_sampling.c - Latin hypercube designs and PAWN sensitivity from Lua.
 *
 *   local design, names = dfle.lhs{ n = 100, seed = 1, params = {
 *       k_df = {5e-5, 1e-3, log = true}, gamma = {0, 1},
 *       alpha = {values = {2, 4, 6}} } }
 *   design[i].k_df, ...; names = {"alpha", "gamma", "k_df"}
 *
 *   local si, info = dfle.pawn{ file = "runs.csv", inputs = {"x1", "x2"},
 *       output = "y", S = 10, bootstrap = 1000, conf = 0.95, seed = 1,
 *       threads = 4 }
 *   si.x1.median, si.x1.ci.median.lo, ...
 *
 * The bootstrap runs on `threads` threads (default: all cores; the
 * ensemble layer passes the command's -j), with the same results for any
 * number.
 *
 * Parameters given as a keyed table have no order in Lua, so the design's
 * dimensions are the names in byte order (strcmp) unless `order` lists
 * them; this makes a design a function of the script alone.  Discrete
 * values may be any Lua values: the C design picks an index and the
 * binding hands back the value itself.
 *
 * Malloc'd objects (the design, a CSV table, a PAWN result) are held by a
 * "box" userdata whose __gc frees them, so an error raised while the
 * result tables are built cannot leak them.
 */
#include "lua/core/dfle_lua.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/csv.h"
#include "dfle/sampling.h"
#include "dfle/sensitivity.h"

#define BOX_META "dfle.sampling_box"

/* ---- Boxes: userdata that own one malloc'd object ----------------- */

typedef struct box {
    void *p;
    void (*free_fn)(void *);
} box;

static int box_gc(lua_State *L)
{
    box *b = luaL_checkudata(L, 1, BOX_META);
    if (b->p != NULL && b->free_fn != NULL)
        b->free_fn(b->p);
    b->p = NULL;
    return 0;
}

static box *push_box(lua_State *L, void (*free_fn)(void *))
{
    box *b = lua_newuserdatauv(L, sizeof *b, 0);
    b->p = NULL;
    b->free_fn = free_fn;
    luaL_setmetatable(L, BOX_META);
    return b;
}

static void free_lhs(void *p)
{
    dfle_lhs_free(p);
}

static void free_csv(void *p)
{
    dfle_csv_free(p);
}

static void free_pawn(void *p)
{
    dfle_pawn_release(p);
    free(p);
}

/* Scratch memory collected with the stack. */
static void *scratch(lua_State *L, size_t size)
{
    void *p = lua_newuserdatauv(L, size ? size : 1, 0);
    memset(p, 0, size ? size : 1);
    return p;
}

static int opt_boolean(lua_State *L, int idx, const char *fn, const char *key)
{
    int t = lua_getfield(L, idx, key), v;
    if (t != LUA_TNIL && t != LUA_TBOOLEAN)
        luaL_error(L, "dfle.%s: '%s' must be a boolean, got %s", fn, key,
                   dfle_lua_typename(L, -1));
    v = lua_toboolean(L, -1);
    lua_pop(L, 1);
    return v;
}

static void check_options_table(lua_State *L, const char *fn, const char *shape)
{
    if (!lua_istable(L, 1))
        luaL_error(L, "dfle.%s: expected a table %s, got %s", fn, shape,
                   dfle_lua_typename(L, 1));
}

/* ---- dfle.lhs ---------------------------------------------------- */

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* The parameter names of the params table at idx, in design order: the
 * `order` array at order_idx (0 if absent) or byte order.  The strings
 * stay anchored by the params table. */
static const char **design_order(lua_State *L, int idx, int order_idx, size_t *np)
{
    size_t D = 0, k = 0;
    const char **names;

    lua_pushnil(L);
    while (lua_next(L, idx) != 0) {
        if (lua_type(L, -2) != LUA_TSTRING)
            luaL_error(L, "dfle.lhs: params are named (params = { k_df = {lo, hi}, ... }); "
                          "got a %s key", luaL_typename(L, -2));
        /* A name is looked up again as a C string: "a\0b" would be "a". */
        dfle_lua_check_string(L, -2, "lhs", "a parameter name");
        if (!lua_istable(L, -1))
            luaL_error(L, "dfle.lhs: parameter '%s': expected {lo, hi}, {lo, hi, log = true} "
                          "or {values = {...}}, got %s", lua_tostring(L, -2),
                       dfle_lua_typename(L, -1));
        D++;
        lua_pop(L, 1);
    }
    if (D == 0)
        luaL_error(L, "dfle.lhs: params is empty; give at least one parameter");
    names = scratch(L, D * sizeof *names);
    if (order_idx == 0) {
        lua_pushnil(L);
        while (lua_next(L, idx) != 0) {
            names[k++] = lua_tostring(L, -2);
            lua_pop(L, 1);
        }
        qsort(names, D, sizeof *names, compare_names);
    } else {
        lua_Unsigned len = lua_rawlen(L, order_idx);
        if (len != D)
            luaL_error(L, "dfle.lhs: order lists %d names but params has %d parameters",
                       (int)len, (int)D);
        for (k = 0; k < D; k++) {
            if (lua_rawgeti(L, order_idx, (lua_Integer)k + 1) != LUA_TSTRING)
                luaL_error(L, "dfle.lhs: order[%d] must be a parameter name, got %s", (int)k + 1,
                           luaL_typename(L, -1));
            names[k] = dfle_lua_check_string(L, -1, "lhs", "an order name");
            lua_pop(L, 1); /* the string is anchored by the order table */
            if (lua_getfield(L, idx, names[k]) == LUA_TNIL)
                luaL_error(L, "dfle.lhs: order[%d] = '%s' is not in params", (int)k + 1,
                           names[k]);
            lua_pop(L, 1);
            for (size_t e = 0; e < k; e++)
                if (strcmp(names[e], names[k]) == 0)
                    luaL_error(L, "dfle.lhs: order lists '%s' twice", names[k]);
        }
    }
    *np = D;
    return names;
}

/* Read the spec of parameter `name` (table at spec) into *p.  A list of
 * values is left on the stack (its index in *values_idx), followed by a
 * scratch array of the indices 0 .. k-1 that the C design chooses from. */
static void read_spec(lua_State *L, int spec, const char *name, dfle_lhs_param *p,
                      int *values_idx)
{
    int has_log = 0, has_range = 0;

    lua_pushnil(L);
    while (lua_next(L, spec) != 0) {
        int ok = 0;
        if (lua_type(L, -2) == LUA_TNUMBER && lua_isinteger(L, -2)) {
            lua_Integer k = lua_tointeger(L, -2);
            ok = k == 1 || k == 2;
            has_range |= ok;
        } else if (lua_type(L, -2) == LUA_TSTRING) {
            const char *k = lua_tostring(L, -2);
            ok = strcmp(k, "log") == 0 || strcmp(k, "values") == 0;
            has_log |= strcmp(k, "log") == 0;
        }
        if (!ok) {
            lua_pushvalue(L, -2);
            luaL_error(L, "dfle.lhs: parameter '%s': unknown key '%s' (a parameter is {lo, hi}, "
                          "{lo, hi, log = true} or {values = {...}})", name,
                       luaL_tolstring(L, -1, NULL));
        }
        lua_pop(L, 1);
    }
    memset(p, 0, sizeof *p);
    p->name = name;
    *values_idx = 0;
    if (lua_getfield(L, spec, "values") != LUA_TNIL) {
        lua_Unsigned k;
        double *idx;
        if (has_range || has_log)
            luaL_error(L, "dfle.lhs: parameter '%s': give either a range {lo, hi} or values, "
                          "not both", name);
        if (!lua_istable(L, -1))
            luaL_error(L, "dfle.lhs: parameter '%s': values must be an array, got %s", name,
                       dfle_lua_typename(L, -1));
        k = lua_rawlen(L, -1);
        if (k == 0)
            luaL_error(L, "dfle.lhs: parameter '%s': values is empty", name);
        *values_idx = lua_gettop(L); /* stays on the stack, as does idx */
        idx = scratch(L, (size_t)k * sizeof *idx);
        for (lua_Unsigned i = 0; i < k; i++)
            idx[i] = (double)i;
        p->kind = DFLE_LHS_DISCRETE;
        p->values = idx;
        p->nvalues = (size_t)k;
        return;
    }
    lua_pop(L, 1);
    for (int i = 1; i <= 2; i++) {
        if (lua_rawgeti(L, spec, i) != LUA_TNUMBER)
            luaL_error(L, "dfle.lhs: parameter '%s': expected a range {lo, hi} of two numbers "
                          "(%s is %s)", name, i == 1 ? "lo" : "hi",
                       lua_isnil(L, -1) ? "missing" : dfle_lua_typename(L, -1));
        if (i == 1)
            p->lo = lua_tonumber(L, -1);
        else
            p->hi = lua_tonumber(L, -1);
        lua_pop(L, 1);
    }
    p->kind = DFLE_LHS_UNIFORM;
    if (lua_getfield(L, spec, "log") != LUA_TNIL) {
        if (!lua_isboolean(L, -1))
            luaL_error(L, "dfle.lhs: parameter '%s': log must be true or false, got %s", name,
                       dfle_lua_typename(L, -1));
        if (lua_toboolean(L, -1))
            p->kind = DFLE_LHS_LOG_UNIFORM;
    }
    lua_pop(L, 1);
}

/* dfle.lhs{ n =, seed = 1, params = {...}, centered = false, order = {...} }
 *   -> design (array of n tables), names (array, design order) */
static int l_lhs(lua_State *L)
{
    double n = -1.0, seed = 1.0;
    const dfle_lua_param numeric[] = {{"n", &n}, {"seed", &seed}};
    static const char *const other[] = {"params", "centered", "order", NULL};
    int params_idx, order_idx = 0, *values_idx;
    const char **names;
    dfle_lhs_param *ps;
    dfle_lhs_opts o;
    dfle_lhs *g = NULL;
    dfle_error err;
    box *b;
    size_t D, N;

    check_options_table(L, "lhs", "{n =, seed =, params = {...}}");
    lua_settop(L, 1);
    dfle_lua_read_params(L, 1, "lhs", numeric, 2, other);
    if (n < 0.0 && lua_getfield(L, 1, "n") == LUA_TNIL)
        luaL_error(L, "dfle.lhs: n (number of samples) is required");
    lua_settop(L, 1);
    dfle_lhs_opts_default(&o);
    o.n = (size_t)dfle_lua_check_whole(L, n, "lhs", "n", 1, 4294967295.0);
    o.seed = (unsigned long)dfle_lua_check_whole(L, seed, "lhs", "seed", 0, 4294967295.0);
    o.centered = opt_boolean(L, 1, "lhs", "centered");

    if (lua_getfield(L, 1, "params") != LUA_TTABLE)
        luaL_error(L, "dfle.lhs: params must be a table of named parameters "
                      "(params = { k_df = {lo, hi}, ... }), got %s", dfle_lua_typename(L, -1));
    params_idx = lua_gettop(L);
    if (lua_getfield(L, 1, "order") != LUA_TNIL) {
        if (!lua_istable(L, -1))
            luaL_error(L, "dfle.lhs: order must be an array of parameter names, got %s",
                       dfle_lua_typename(L, -1));
        order_idx = lua_gettop(L);
    }
    names = design_order(L, params_idx, order_idx, &D);
    ps = scratch(L, D * sizeof *ps);
    values_idx = scratch(L, D * sizeof *values_idx);
    luaL_checkstack(L, (int)(3 * D) + 10, "dfle.lhs: too many parameters");
    for (size_t d = 0; d < D; d++) {
        lua_getfield(L, params_idx, names[d]);
        read_spec(L, lua_gettop(L), names[d], &ps[d], &values_idx[d]);
    }

    b = push_box(L, free_lhs);
    if (dfle_lhs_new(&o, D, ps, &g, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    b->p = g;
    N = dfle_lhs_n(g);

    lua_createtable(L, N > (size_t)INT_MAX ? INT_MAX : (int)N, 0);
    for (size_t i = 0; i < N; i++) {
        const double *row = dfle_lhs_row(g, i);
        lua_createtable(L, 0, (int)D);
        for (size_t d = 0; d < D; d++) {
            if (ps[d].kind == DFLE_LHS_DISCRETE)
                lua_rawgeti(L, values_idx[d], (lua_Integer)dfle_lhs_choice(g, i, d) + 1);
            else
                lua_pushnumber(L, row[d]);
            lua_setfield(L, -2, names[d]);
        }
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
    lua_createtable(L, (int)D, 0);
    for (size_t d = 0; d < D; d++) {
        lua_pushstring(L, names[d]);
        lua_rawseti(L, -2, (lua_Integer)d + 1);
    }
    return 2;
}

/* ---- dfle.pawn --------------------------------------------------- */

/* The input names (array at idx) into a scratch array; strings anchored
 * by that table. */
static const char **input_names(lua_State *L, int idx, size_t *D)
{
    lua_Unsigned len;
    const char **names;

    if (!lua_istable(L, idx))
        luaL_error(L, "dfle.pawn: inputs must be an array of column names, got %s",
                   dfle_lua_typename(L, idx));
    len = lua_rawlen(L, idx);
    if (len == 0)
        luaL_error(L, "dfle.pawn: inputs is empty; name at least one input column");
    names = scratch(L, (size_t)len * sizeof *names);
    for (lua_Unsigned i = 0; i < len; i++) {
        if (lua_rawgeti(L, idx, (lua_Integer)i + 1) != LUA_TSTRING)
            luaL_error(L, "dfle.pawn: inputs[%d] must be a column name, got %s", (int)i + 1,
                       luaL_typename(L, -1));
        names[i] = dfle_lua_check_string(L, -1, "pawn", "an input name");
        lua_pop(L, 1);
        for (lua_Unsigned e = 0; e < i; e++)
            if (strcmp(names[e], names[i]) == 0)
                luaL_error(L, "dfle.pawn: inputs lists '%s' twice", names[i]);
    }
    *D = (size_t)len;
    return names;
}

/* List the keys of the data table at idx (for "no column" messages).
 * The names are gathered first and joined after the traversal: a
 * luaL_Buffer that grows pushes onto the stack, and lua_next then took
 * that for its key ("invalid key to 'next'" with a long column name). */
static const char *data_columns(lua_State *L, int idx)
{
    luaL_Buffer bf;
    lua_Integer n = 0;
    int names;

    idx = lua_absindex(L, idx);
    lua_newtable(L);
    names = lua_gettop(L);
    lua_pushnil(L);
    while (lua_next(L, idx) != 0) {
        lua_pop(L, 1);
        if (lua_type(L, -1) == LUA_TSTRING) {
            lua_pushvalue(L, -1);
            lua_rawseti(L, names, ++n);
        }
    }
    luaL_buffinit(L, &bf);
    for (lua_Integer i = 1; i <= n; i++) {
        if (i > 1)
            luaL_addstring(&bf, ", ");
        lua_rawgeti(L, names, i);
        luaL_addvalue(&bf);
    }
    luaL_pushresult(&bf);
    return lua_tostring(L, -1);
}

typedef struct table_cols {
    size_t N;              /* rows                                      */
    const double **col;    /* D + 1 columns: inputs, then the output    */
    const size_t *line;    /* file line of each row, or NULL (in memory) */
    const char *source;    /* file name, or NULL                        */
} table_cols;

static void columns_from_file(lua_State *L, const char *path, const char **names, size_t D,
                              const char *output, table_cols *t)
{
    box *b = push_box(L, free_csv);
    dfle_csv *csv;
    dfle_error err;

    if (dfle_csv_read(path, &csv, &err) != DFLE_OK)
        luaL_error(L, "dfle.pawn: %s", err.msg);
    b->p = csv;
    for (size_t d = 0; d <= D; d++)
        if (dfle_csv_column(csv, d < D ? names[d] : output, &t->col[d], &err) != DFLE_OK)
            luaL_error(L, "dfle.pawn: %s", err.msg);
    t->N = csv->nrows;
    t->line = csv->line;
    t->source = csv->source;
    /* the box stays on the stack until l_pawn returns */
}

static void columns_from_data(lua_State *L, int data, const char **names, size_t D,
                              const char *output, table_cols *t)
{
    if (!lua_istable(L, data))
        luaL_error(L, "dfle.pawn: data must be a table of columns (data = { x1 = {...}, "
                      "y = {...} }), got %s", dfle_lua_typename(L, data));
    for (size_t d = 0; d <= D; d++) {
        const char *name = d < D ? names[d] : output;
        char what[200];
        size_t n;
        if (lua_getfield(L, data, name) == LUA_TNIL)
            luaL_error(L, "dfle.pawn: data has no column '%s' (columns: %s)", name,
                       data_columns(L, data));
        snprintf(what, sizeof what, "pawn: data.%s", name);
        t->col[d] = dfle_lua_check_array(L, -1, what, &n);
        lua_remove(L, -2); /* keep the scratch copy, drop the Lua array */
        if (d == 0)
            t->N = n;
        else if (n != t->N)
            luaL_error(L, "dfle.pawn: data.%s has %d values but data.%s has %d", name, (int)n,
                       names[0], (int)t->N);
    }
    t->line = NULL;
    t->source = NULL;
}

static void set_number(lua_State *L, const char *k, double v)
{
    lua_pushnumber(L, v);
    lua_setfield(L, -2, k);
}

static void push_interval(lua_State *L, double lo, double hi)
{
    lua_createtable(L, 2, 2);
    lua_pushnumber(L, lo);
    lua_rawseti(L, -2, 1);
    lua_pushnumber(L, hi);
    lua_rawseti(L, -2, 2);
    set_number(L, "lo", lo);
    set_number(L, "hi", hi);
}

static void push_pawn_input(lua_State *L, const dfle_pawn_result *r, size_t d)
{
    const double *ix = r->index + d * DFLE_PAWN_NSTATS;
    const size_t S = r->S;

    lua_createtable(L, 0, 10);
    for (int k = 0; k < DFLE_PAWN_NSTATS; k++)
        set_number(L, dfle_pawn_stat_name(k), ix[k]);
    dfle_lua_push_array(L, r->ks + d * S, S);
    lua_setfield(L, -2, "ks");
    dfle_lua_push_array(L, r->edges + d * (S + 1), S + 1);
    lua_setfield(L, -2, "edges");
    lua_createtable(L, (int)S, 0);
    for (size_t s = 0; s < S; s++) {
        lua_pushinteger(L, (lua_Integer)r->count[d * S + s]);
        lua_rawseti(L, -2, (lua_Integer)s + 1);
    }
    lua_setfield(L, -2, "count");
    if (r->bootstrap > 0) {
        lua_createtable(L, 0, DFLE_PAWN_NSTATS);
        for (int k = 0; k < DFLE_PAWN_NSTATS; k++) {
            size_t i = d * DFLE_PAWN_NSTATS + (size_t)k;
            push_interval(L, r->lo[i], r->hi[i]);
            lua_setfield(L, -2, dfle_pawn_stat_name(k));
        }
        lua_setfield(L, -2, "ci");
    }
}

/* dfle.pawn{ file = | data =, inputs = {...}, output =, S = 10,
 *            bootstrap = 0, conf = 0.95, seed = 1, drop_nan = false,
 *            threads = cores }
 *   -> {[input] = {minimum, mean, median, maximum, CV, stdev, ks, count,
 *                  edges, ci}}, info {N, dropped, S, bootstrap, conf, threads} */
static int l_pawn(lua_State *L)
{
    double S = 10, nboot = 0, conf = 0.95, seed = 1, threads = dfle_lua_cores();
    const dfle_lua_param numeric[] = {{"S", &S},       {"bootstrap", &nboot}, {"conf", &conf},
                                      {"seed", &seed}, {"threads", &threads}};
    static const char *const other[] = {"file", "data", "inputs", "output", "drop_nan", NULL};
    const char **names, *output, *file = NULL;
    const double **xs;
    double *matrix;
    int drop_nan, has_data;
    size_t D, kept = 0;
    table_cols t;
    dfle_pawn_opts o;
    dfle_pawn_result *res;
    dfle_error err;
    box *b;

    check_options_table(L, "pawn",
                        "{file = | data =, inputs = {...}, output =, S = 10, ...}");
    lua_settop(L, 1);
    dfle_lua_read_params(L, 1, "pawn", numeric, 5, other);
    dfle_pawn_opts_default(&o);
    o.S = (size_t)dfle_lua_check_whole(L, S, "pawn", "S (slices)", 1, 1e6);
    o.bootstrap = (size_t)dfle_lua_check_whole(L, nboot, "pawn", "bootstrap", 0, 1e7);
    o.seed = (unsigned long)dfle_lua_check_whole(L, seed, "pawn", "seed", 0, 4294967295.0);
    o.threads = (size_t)dfle_lua_check_whole(L, threads, "pawn", "threads", 1,
                                             DFLE_PAWN_MAX_THREADS);
    if (!(conf > 0.0 && conf < 1.0))
        luaL_error(L, "dfle.pawn: conf (confidence level) must be in (0, 1) (got %s)",
                   dfle_lua_number_text(L, conf));
    o.conf = conf;
    drop_nan = opt_boolean(L, 1, "pawn", "drop_nan");

    lua_getfield(L, 1, "inputs"); /* index 2: anchors the input names */
    if (lua_isnil(L, 2))
        luaL_error(L, "dfle.pawn: inputs (array of input column names) is required");
    names = input_names(L, 2, &D); /* index 3: scratch */
    if (lua_getfield(L, 1, "output") != LUA_TSTRING) /* index 4 */
        luaL_error(L, "dfle.pawn: output (the output column name) must be a string, got %s",
                   dfle_lua_typename(L, -1));
    output = dfle_lua_check_string(L, 4, "pawn", "output");
    for (size_t d = 0; d < D; d++)
        if (strcmp(names[d], output) == 0)
            luaL_error(L, "dfle.pawn: '%s' is both the output and an input", output);

    lua_getfield(L, 1, "file"); /* index 5 */
    lua_getfield(L, 1, "data"); /* index 6 */
    has_data = !lua_isnil(L, 6);
    if (!lua_isnil(L, 5) && has_data)
        luaL_error(L, "dfle.pawn: give either file or data, not both");
    if (lua_isnil(L, 5) && !has_data)
        luaL_error(L, "dfle.pawn: give the table to analyse: file = \"runs.csv\" or "
                      "data = { x1 = {...}, y = {...} }");
    if (!has_data) {
        if (lua_type(L, 5) != LUA_TSTRING)
            luaL_error(L, "dfle.pawn: file must be a path, got %s", dfle_lua_typename(L, 5));
        file = dfle_lua_check_string(L, 5, "pawn", "file");
    }

    xs = scratch(L, (D + 1) * sizeof *xs);
    t.col = xs;
    if (file != NULL)
        columns_from_file(L, file, names, D, output, &t);
    else
        columns_from_data(L, 6, names, D, output, &t);

    /* Copy the rows used, checking (or dropping) non-finite values. */
    matrix = scratch(L, (D + 1) * (t.N ? t.N : 1) * sizeof *matrix);
    for (size_t i = 0; i < t.N; i++) {
        size_t bad = D + 1;
        for (size_t d = 0; d <= D && bad > D; d++)
            if (!isfinite(t.col[d][i]))
                bad = d;
        if (bad <= D) {
            const char *col = bad < D ? names[bad] : output;
            if (drop_nan)
                continue;
            if (t.line != NULL)
                luaL_error(L, "dfle.pawn: %s:%d: %s is %s; PAWN needs finite values (pass "
                              "drop_nan = true to leave such rows out)", t.source,
                           (int)t.line[i], col, dfle_lua_number_text(L, t.col[bad][i]));
            luaL_error(L, "dfle.pawn: data.%s[%d] is %s; PAWN needs finite values (pass "
                          "drop_nan = true to leave such rows out)", col, (int)i + 1,
                       dfle_lua_number_text(L, t.col[bad][i]));
        }
        for (size_t d = 0; d <= D; d++)
            matrix[d * t.N + kept] = t.col[d][i];
        kept++;
    }
    for (size_t d = 0; d <= D; d++)
        xs[d] = matrix + d * t.N;

    o.names = names;
    o.output = output;
    b = push_box(L, free_pawn);
    res = calloc(1, sizeof *res);
    if (res == NULL)
        return luaL_error(L, "dfle.pawn: out of memory");
    b->p = res;
    if (dfle_pawn(kept, D, xs, xs[D], &o, res, &err) != DFLE_OK) {
        /* Name the table the rows came from (a file, or data). */
        if (file != NULL)
            return luaL_error(L, "dfle.%s (in %s, %d of whose rows were used)", err.msg, file,
                              (int)kept);
        return dfle_lua_raise(L, &err);
    }

    lua_createtable(L, 0, (int)D);
    for (size_t d = 0; d < D; d++) {
        push_pawn_input(L, res, d);
        lua_setfield(L, -2, names[d]);
    }
    lua_createtable(L, 0, 6);
    lua_pushinteger(L, (lua_Integer)o.threads);
    lua_setfield(L, -2, "threads");
    lua_pushinteger(L, (lua_Integer)kept);
    lua_setfield(L, -2, "N");
    lua_pushinteger(L, (lua_Integer)(t.N - kept));
    lua_setfield(L, -2, "dropped");
    lua_pushinteger(L, (lua_Integer)o.S);
    lua_setfield(L, -2, "S");
    lua_pushinteger(L, (lua_Integer)o.bootstrap);
    lua_setfield(L, -2, "bootstrap");
    set_number(L, "conf", o.conf);
    return 2;
}

void dfle_lua_open_sampling(lua_State *L)
{
    static const luaL_Reg funcs[] = {{"lhs", l_lhs}, {"pawn", l_pawn}, {NULL, NULL}};
    if (luaL_newmetatable(L, BOX_META)) {
        lua_pushcfunction(L, box_gc);
        lua_setfield(L, -2, "__gc");
        lua_pushcfunction(L, box_gc);
        lua_setfield(L, -2, "__close");
        lua_pushliteral(L, "dfle objects do not share their metatable");
        lua_setfield(L, -2, "__metatable");
    }
    lua_pop(L, 1);
    luaL_setfuncs(L, funcs, 0);
}
