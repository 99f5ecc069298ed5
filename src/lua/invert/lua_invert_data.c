/*
 * lua_invert_data.c - dfle.invert's data: a DEM profile or network
 * binned as the Eq. (2) fit bins it, or binned pairs from a CSV file or
 * a table, reduced to areas and log slopes; and the bins a channel
 * cannot speak for left out.
 *
 * The same data in every state: binning is deterministic, and the
 * identity line carries a fingerprint of the result.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lua/invert/lua_invert_internal.h"

#include "dfle/analysis.h"
#include "dfle/csv.h"

static void *obs_alloc(lua_State *L, size_t n, size_t size)
{
    void *p = calloc(n ? n : 1, size);
    if (p == NULL)
        luaL_error(L, "dfle.invert: out of memory");
    return p;
}

/* ------------------------------------------------------------------ */
/* Data.                                                               */

static void set_obs(lua_State *L, inv_run *R, size_t n)
{
    R->nobs = n;
    R->A_obs = obs_alloc(L, n, sizeof *R->A_obs);
    R->lnS_obs = obs_alloc(L, n, sizeof *R->lnS_obs);
    R->r = obs_alloc(L, n, sizeof *R->r);
}

/* Binned pairs given as they are (a table or a file): every area and
 * slope must be positive and finite.  `where` names a pair in errors. */
static void take_binned(lua_State *L, inv_run *R, size_t n, const double *A, const double *S,
                        const char *source, const size_t *line)
{
    set_obs(L, R, n);
    for (size_t i = 0; i < n; i++) {
        if (!(isfinite(A[i]) && A[i] > 0 && isfinite(S[i]) && S[i] > 0)) {
            if (line != NULL)
                luaL_error(L, "dfle.invert: %s:%d: A = %s, S = %s; binned data need finite A > 0 "
                              "and S > 0 (a log-slope likelihood)", source, (int)line[i],
                           dfle_lua_number_text(L, A[i]), dfle_lua_number_text(L, S[i]));
            luaL_error(L, "dfle.invert: data pair %d: A = %s, S = %s; binned data need finite "
                          "A > 0 and S > 0 (a log-slope likelihood)", (int)i + 1,
                       dfle_lua_number_text(L, A[i]), dfle_lua_number_text(L, S[i]));
        }
        R->A_obs[i] = A[i];
        R->lnS_obs[i] = log(S[i]);
    }
}

/* data = profile | file | {A =, S =}; pushes the data table of the
 * result ({A, S, count, raw, kind}).  Returns 1 for DEM data. */
int inv_read_data(lua_State *L, int arg, inv_run *R, size_t nbins, int nbins_given)
{
    int data, dem = 0, out;
    lua_getfield(L, arg, "data");
    data = lua_gettop(L);
    lua_newtable(L);
    out = lua_gettop(L);
    if (luaL_testudata(L, data, "dfle.profile") != NULL) {
        const double *A, *S;
        size_t n, k = 0, nbad, *cnt;
        dfle_bins b;
        dfle_error err;
        dem = 1;
        lua_getfield(L, data, "kind");
        lua_setfield(L, out, "kind");
        n = dfle_lua_slope_area(L, data, "invert", &A, &S);
        lua_getfield(L, data, "slope_area");
        lua_pushvalue(L, data);
        lua_call(L, 1, 1);
        lua_setfield(L, out, "raw");
        /* counts: room made before the bins exist, so nothing raises
         * while they are held */
        cnt = lua_newuserdatauv(L, nbins * sizeof *cnt, 0);
        memset(&b, 0, sizeof b);
        if (dfle_bins_compute(n, A, S, nbins, &b, &err) != DFLE_OK)
            luaL_error(L, "dfle.invert: data: %s", err.msg);
        /* Bins whose mean slope is not positive have no logarithm (flats on
         * a filled DEM); they are left out, as the Eq. (2) fit leaves them. */
        for (size_t i = 0; i < b.n; i++)
            k += b.S_mean[i] > 0;
        nbad = b.n - k;
        R->nobs = k;
        R->A_obs = calloc(k ? k : 1, sizeof *R->A_obs);
        R->lnS_obs = calloc(k ? k : 1, sizeof *R->lnS_obs);
        R->r = calloc(k ? k : 1, sizeof *R->r);
        for (size_t i = 0, j = 0; i < b.n && R->A_obs != NULL && R->lnS_obs != NULL; i++)
            if (b.S_mean[i] > 0) {
                R->A_obs[j] = b.A[i];
                R->lnS_obs[j] = log(b.S_mean[i]);
                cnt[j++] = b.count[i];
            }
        dfle_bins_release(&b);
        if (R->A_obs == NULL || R->lnS_obs == NULL || R->r == NULL)
            luaL_error(L, "dfle.invert: out of memory");
        lua_createtable(L, (int)k, 0);
        for (size_t j = 0; j < k; j++) {
            lua_pushinteger(L, (lua_Integer)cnt[j]);
            lua_rawseti(L, -2, (lua_Integer)j + 1);
        }
        lua_setfield(L, out, "count");
        lua_pushinteger(L, (lua_Integer)nbad), lua_setfield(L, out, "nonpositive");
    } else if (lua_type(L, data) == LUA_TSTRING) {
        const char *path = dfle_lua_check_string(L, data, "invert", "parameter 'data' (a file)");
        const double *A, *S;
        dfle_error err;
        int st;
        if (nbins_given)
            luaL_error(L, "dfle.invert: 'nbins' bins DEM data; binned data from a file are used "
                          "as given");
        /* the table is held by the box, whose __gc frees it if we raise */
        st = dfle_csv_read(path, &R->csv, &err);
        if (st == DFLE_OK)
            st = dfle_csv_column(R->csv, "A", &A, &err);
        if (st == DFLE_OK)
            st = dfle_csv_column(R->csv, "S", &S, &err);
        if (st != DFLE_OK)
            luaL_error(L, "dfle.invert: data: %s", err.msg);
        if (R->csv->nrows < 1)
            luaL_error(L, "dfle.invert: data: %s has no rows", path);
        lua_pushliteral(L, "file");
        lua_setfield(L, out, "kind");
        take_binned(L, R, R->csv->nrows, A, S, path, R->csv->line);
        dfle_csv_free(R->csv);
        R->csv = NULL;
    } else if (lua_istable(L, data)) {
        const double *A, *S;
        size_t n;
        if (nbins_given)
            luaL_error(L, "dfle.invert: 'nbins' bins DEM data; binned data {A =, S =} are used "
                          "as given");
        n = dfle_lua_slope_area(L, data, "invert: data", &A, &S);
        lua_pushliteral(L, "table");
        lua_setfield(L, out, "kind");
        take_binned(L, R, n, A, S, NULL, NULL);
    } else {
        luaL_error(L, "dfle.invert: parameter 'data' must be a DEM profile or network "
                      "(dem:profile, dem:network), a CSV file of binned data (columns A, S) or "
                      "a table {A = {...}, S = {...}} of binned data, got %s",
                   dfle_lua_typename(L, data));
    }
    lua_settop(L, out);
    lua_remove(L, data);
    return dem;
}

/* Leave out the bins outside the channel's areas: the model says nothing
 * there (within the rounding dfle_slope_at forgives).  Returns how many
 * were dropped. */
size_t inv_clip_to_channel(inv_run *R, const dfle_channel *ch)
{
    const double *A = dfle_channel_A(ch);
    size_t n = dfle_channel_size(ch), k = 0;
    for (size_t i = 0; i < R->nobs; i++)
        if (R->A_obs[i] >= A[0] * (1 - 1e-9) && R->A_obs[i] <= A[n - 1] * (1 + 1e-9)) {
            R->A_obs[k] = R->A_obs[i];
            R->lnS_obs[k] = R->lnS_obs[i];
            k++;
        }
    n = R->nobs - k;
    R->nobs = k;
    return n;
}

