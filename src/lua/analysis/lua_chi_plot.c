/*
 * lua_chi_plot.c - the figures of a dfle.chi result (plot.h):
 *
 *   dfle.plot.chi(c, "chi.png" [, {<options>}])
 *   dfle.plot.slope_area_chi(net, c, "sa_chi.png" [, fit [, {nbins =, <page options>}]])
 *   dfle.plot.ksn_map(c, "ksn.png" [, {dem =, margin =, <options>}])
 */
#include "lua/analysis/lua_chi.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dfle/analysis.h"
#include "dfle/dem.h"
#include "dfle/landscape.h"
#include "dfle/plot.h"

static dfle_lua_chi_data *check_chi(lua_State *L, int arg)
{
    return dfle_lua_check_object(L, arg, DFLE_LUA_CHI);
}

/* The chi plot's data of c: elevations, or heights above base level
 * where the cells drain to several base levels (scratch on the stack);
 * *ylabel the label that goes with them. */
static void chi_data(lua_State *L, const dfle_lua_chi_data *c, dfle_plot_chi_data *d,
                     const char **ylabel)
{
    const double *z = c->z;
    double zb = c->n > 0 ? c->c.z_base[0] : 0;
    *ylabel = NULL;
    if (c->c.n_base > 1) {
        double *h = lua_newuserdatauv(L, c->n * sizeof *h, 0);
        for (size_t i = 0; i < c->n; i++)
            h[i] = c->z[i] - c->c.z_base[i];
        z = h, zb = 0;
        *ylabel = "Height above base level, {/:Italic z} − {/:Italic z}_b (m)";
    }
    *d = (dfle_plot_chi_data){.n = c->n, .chi = c->c.chi, .z = z, .k_sn = c->c.k_sn, .A = c->A,
                              .A_min = c->c.A_min, .theta_ref = c->c.theta_ref, .A0 = c->c.A0,
                              .M_chi = c->c.M_chi, .z_b = zb, .r2 = c->c.r2};
}

/* dfle.plot.chi(c, path [, opts]) */
static int l_plot_chi(lua_State *L)
{
    dfle_lua_chi_data *c = check_chi(L, 1);
    const char *path = dfle_lua_check_string(L, 2, "plot.chi", "the path"), *ylabel;
    dfle_plot_chi_data d;
    dfle_plot_opts o;
    dfle_error err;

    lua_settop(L, 3);
    dfle_lua_plot_opts(L, 3, "plot.chi", DFLE_LUA_PLOT_AXES, NULL, 0, NULL, &o);
    chi_data(L, c, &d, &ylabel);
    if (o.y.label == NULL)
        o.y.label = ylabel;
    if (dfle_plot_chi(path, &o, &d, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path);
    return 0;
}

/* dfle.plot.slope_area_chi(data, c, path [, fit [, {nbins = 100, ...}]]) */
static int l_plot_slope_area_chi(lua_State *L)
{
    const double *A = NULL, *S = NULL;
    double nbins = 100;
    const dfle_lua_param params[] = {{"nbins", &nbins}};
    dfle_lua_chi_data *c = check_chi(L, 2);
    const char *path = dfle_lua_check_string(L, 3, "plot.slope_area_chi", "the path"), *ylabel;
    dfle_plot_chi_data d;
    dfle_plot_opts o;
    dfle_eq2_fit fit;
    const dfle_eq2_fit *fitp;
    dfle_bins bins;
    dfle_error err;
    size_t n;
    int st;

    lua_settop(L, 5);
    dfle_lua_plot_opts(L, 5, "plot.slope_area_chi", DFLE_LUA_PLOT_PAGE, params, 1, NULL, &o);
    dfle_lua_check_whole(L, nbins, "plot.slope_area_chi", "nbins", 1, 1e6);
    chi_data(L, c, &d, &ylabel); /* (may allocate: before the bins) */
    (void)ylabel;                /* panel (b) keeps the house label */
    fitp = dfle_lua_plot_slope_area_data(L, 1, 4, "plot.slope_area_chi", (size_t)nbins, &n, &A,
                                         &S, &bins, &fit);
    st = dfle_plot_slope_area_chi(path, &o, n, A, S, &bins, fitp, &d, &err);
    dfle_bins_release(&bins);
    if (st != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path);
    return 0;
}

/* The relief under a k_sn map: the DEM `dem` cropped to the cells'
 * box and a margin, or the landscape c came from. */
typedef struct relief {
    size_t nx, ny;
    double x0, y0, dx, dy;
    const double *z;
    const char *crs;
} relief;

static void relief_of_dem(lua_State *L, int idx, const dfle_lua_chi_data *c, double margin,
                          relief *r)
{
    dfle_dem *dem = dfle_lua_check_object(L, idx, "dfle.dem");
    const size_t nx = dfle_dem_nx(dem), ny = dfle_dem_ny(dem);
    const double dx = dfle_dem_dx(dem), dy = dfle_dem_dy(dem), *z = dfle_dem_z(dem);
    double e[4], lo_x = HUGE_VAL, hi_x = -HUGE_VAL, lo_y = HUGE_VAL, hi_y = -HUGE_VAL, pad;
    long c0, c1, r0, r1;
    double *out;

    dfle_dem_extent(dem, e);
    for (size_t i = 0; i < c->n; i++) {
        if (!(c->E[i] >= e[0] && c->E[i] <= e[1] && c->N[i] >= e[2] && c->N[i] <= e[3]))
            luaL_error(L, "dfle.plot.ksn_map: cell %d (%f E, %f N) is outside the DEM given (E "
                          "%f..%f, N %f..%f): give the DEM the cells came from", (int)i + 1,
                       c->E[i], c->N[i], e[0], e[1], e[2], e[3]);
        lo_x = fmin(lo_x, c->E[i]), hi_x = fmax(hi_x, c->E[i]);
        lo_y = fmin(lo_y, c->N[i]), hi_y = fmax(hi_y, c->N[i]);
    }
    pad = fmax(margin * fmax(hi_x - lo_x, hi_y - lo_y), 5 * fmax(dx, dy));
    c0 = (long)floor((lo_x - pad - e[0]) / dx), c1 = (long)floor((hi_x + pad - e[0]) / dx);
    r0 = (long)floor((e[3] - hi_y - pad) / dy), r1 = (long)floor((e[3] - lo_y + pad) / dy);
    c0 = c0 < 0 ? 0 : c0, r0 = r0 < 0 ? 0 : r0;
    c1 = c1 >= (long)nx ? (long)nx - 1 : c1, r1 = r1 >= (long)ny ? (long)ny - 1 : r1;
    r->nx = (size_t)(c1 - c0 + 1), r->ny = (size_t)(r1 - r0 + 1);
    out = lua_newuserdatauv(L, r->nx * r->ny * sizeof *out, 0);
    for (size_t rr = 0; rr < r->ny; rr++)
        memcpy(out + rr * r->nx, z + ((size_t)r0 + rr) * nx + (size_t)c0,
               r->nx * sizeof *out);
    r->x0 = e[0] + (double)c0 * dx, r->y0 = e[3] - (double)r0 * dy;
    r->dx = dx, r->dy = dy, r->z = out;
    r->crs = dfle_dem_crs_wkt(dem);
}

static void relief_of_landscape(lua_State *L, int idx, relief *r)
{
    dfle_landscape *ls = dfle_lua_check_object(L, idx, "dfle.landscape");
    double *z;
    dfle_error err;
    r->nx = dfle_landscape_nx(ls), r->ny = dfle_landscape_ny(ls);
    r->dx = dfle_landscape_dx(ls), r->dy = dfle_landscape_dy(ls);
    z = lua_newuserdatauv(L, r->nx * r->ny * sizeof *z, 0);
    if (dfle_landscape_get(ls, DFLE_LS_Z, z, &err) != DFLE_OK)
        dfle_lua_raise(L, &err);
    lua_getfield(L, idx, "x0");
    lua_getfield(L, idx, "y0");
    r->x0 = lua_tonumber(L, -2), r->y0 = lua_tonumber(L, -1);
    lua_pop(L, 2);
    r->z = z;
}

/* dfle.plot.ksn_map(c, path [, {dem =, margin = 0.1, <options>}]) */
static int l_plot_ksn_map(lua_State *L)
{
    static const char *const own[] = {"dem", NULL};
    dfle_lua_chi_data *c = check_chi(L, 1);
    const char *path = dfle_lua_check_string(L, 2, "plot.ksn_map", "the path");
    double margin = 0.1;
    const dfle_lua_param params[] = {{"margin", &margin}};
    dfle_plot_map_points pts;
    dfle_plot_map m;
    dfle_plot_opts o;
    relief r;
    char clabel[120];
    dfle_error err;
    int dem_idx = 0;

    lua_settop(L, 3);
    dfle_lua_plot_opts(L, 3, "plot.ksn_map", DFLE_LUA_PLOT_AXES, params, 1, own, &o);
    if (!(margin >= 0 && margin <= 10))
        luaL_error(L, "dfle.plot.ksn_map: margin must be 0..10 (a fraction of the cells' "
                      "extent), got %s", dfle_lua_number_text(L, margin));
    if (c->E == NULL)
        luaL_error(L, "dfle.plot.ksn_map: the cells of this %s have no map coordinates (a DEM "
                      "profile or network, a landscape, or a table with E and N has them)",
                   c->kind);
    if (lua_istable(L, 3) && lua_getfield(L, 3, "dem") != LUA_TNIL)
        dem_idx = lua_gettop(L);
    memset(&r, 0, sizeof r);
    if (dem_idx > 0) {
        relief_of_dem(L, dem_idx, c, margin, &r);
    } else {
        lua_getiuservalue(L, 1, 2);
        if (luaL_testudata(L, -1, "dfle.landscape") == NULL)
            luaL_error(L, "dfle.plot.ksn_map: give dem = the DEM the %s came from: a map "
                          "draws its relief", c->kind);
        relief_of_landscape(L, lua_gettop(L), &r);
        lua_getiuservalue(L, 1, 3);
        r.crs = lua_tostring(L, -1);
    }
    pts = (dfle_plot_map_points){.n = c->n, .x = c->E, .y = c->N, .value = c->c.k_sn,
                                 .size = c->A};
    memset(&m, 0, sizeof m);
    m.nx = r.nx, m.ny = r.ny, m.x0 = r.x0, m.y0 = r.y0, m.dx = r.dx, m.dy = r.dy;
    m.z = r.z;
    m.crs = r.crs;
    m.points = &pts;
    if (o.c.label == NULL) {
        snprintf(clabel, sizeof clabel, "{/:Italic k}_{sn} (m^{%.3g}), {/:Italic θ}_{ref} = %.3g",
                 2 * c->c.theta_ref, c->c.theta_ref);
        o.c.label = clabel;
    }
    if (dfle_plot_map_draw(path, &o, &m, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path);
    return 0;
}

void dfle_lua_open_chi_plot(lua_State *L)
{
    lua_getfield(L, -1, "plot");
    lua_pushcfunction(L, l_plot_chi);
    lua_setfield(L, -2, "chi");
    lua_pushcfunction(L, l_plot_slope_area_chi);
    lua_setfield(L, -2, "slope_area_chi");
    lua_pushcfunction(L, l_plot_ksn_map);
    lua_setfield(L, -2, "ksn_map");
    lua_pop(L, 1);
}
