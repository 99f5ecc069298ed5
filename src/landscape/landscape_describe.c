/*
 * landscape_describe.c - what a landscape runs, into a record (record.h),
 * so that every file it writes can be reproduced from the file alone:
 * the grid, the channel and hillslope rules, the forcing (a number, or
 * the range of a field in space), and each component's parameters
 * through its params op, as the 1D model's records list them.
 */
#include "landscape/landscape_internal.h"

#include <stdio.h>

#include "dfle/fluvial.h"
#include "dfle/law.h"
#include "dfle/record.h"
#include "dfle/router.h"

/* A field: its value, or its range over the data cells and how it is
 * given (a grid, a function of space or of space and time). */
static void describe_field(const dfle_landscape *ls, const ls_field *f, const char *key,
                           const char *unit, dfle_record *rec)
{
    char name[64];
    double lo = INFINITY, hi = -INFINITY;
    if (f->grid == NULL) {
        dfle_record_param_number(rec, key, f->value, unit);
        return;
    }
    for (size_t c = 0; c < ls->n; c++)
        if (!isnan(ls->z[c])) {
            lo = f->grid[c] < lo ? f->grid[c] : lo;
            hi = f->grid[c] > hi ? f->grid[c] : hi;
        }
    snprintf(name, sizeof name, "%s_min", key);
    dfle_record_param_number(rec, name, lo, unit);
    snprintf(name, sizeof name, "%s_max", key);
    dfle_record_param_number(rec, name, hi, unit);
    snprintf(name, sizeof name, "%s_given", key);
    dfle_record_param_text(rec, name, f->fn == NULL   ? "grid"
                                      : f->varies ? "function of x, y and t"
                                                  : "function of x and y");
}

static void component(dfle_record *rec, const char *section, const char *kind, size_t n,
                      const dfle_param *p)
{
    dfle_record_section(rec, section, kind);
    if (n != (size_t)-1)
        dfle_record_params(rec, p, n < 64 ? n : 64);
}

void dfle_landscape_describe(const dfle_landscape *ls, dfle_record *rec)
{
    static const char *const edges[] = {"open", "base_level", "closed"};
    static const char *const sides[] = {"north", "east", "south", "west"};
    static const char *const hills[] = {"threshold", "diffusion", "uplift"};
    static const char *const combine[] = {"any", "count", "function"};
    const dfle_landscape_opts *o = &ls->o;
    dfle_param p[64];

    dfle_record_section(rec, "landscape", NULL);
    dfle_record_number(rec, "nx", (double)ls->nx, NULL);
    dfle_record_number(rec, "ny", (double)ls->ny, NULL);
    dfle_record_number(rec, "dx", o->dx, "m");
    dfle_record_number(rec, "dy", o->dy, "m");
    dfle_record_number(rec, "data_cells", (double)ls->n_data, NULL);
    dfle_record_number(rec, "time", ls->time, "yr");
    describe_field(ls, &ls->U, "U", "m/yr", rec);
    describe_field(ls, &ls->K_scale, "K_scale", "", rec);
    describe_field(ls, &ls->df_scale, "k_df_scale", "", rec);
    dfle_record_param_number(rec, "A0", o->A0, "m^2");
    dfle_record_param_number(rec, "k_w", o->k_w, "m^(1-2 b)");
    dfle_record_param_number(rec, "b", o->b, "");
    dfle_record_param_text(rec, "hillslope",
                           o->hillslope >= 0 && o->hillslope < 3 ? hills[o->hillslope] : "?");
    if (o->hillslope == DFLE_HILLSLOPE_THRESHOLD) {
        dfle_record_param_number(rec, "S_c", o->S_c, "");
        dfle_record_param_bool(rec, "cap_channels", o->cap_channels);
    } else if (o->hillslope == DFLE_HILLSLOPE_DIFFUSION) {
        dfle_record_param_number(rec, "D", o->D, "m^2/yr");
    }
    for (int s = 0; s < 4; s++) {
        char key[16];
        snprintf(key, sizeof key, "edge_%s", sides[s]);
        dfle_record_param_text(rec, key, (int)o->edge[s] >= 0 && (int)o->edge[s] < 3
                                             ? edges[o->edge[s]] : "?");
    }
    dfle_record_param_text(rec, "nodata", (int)o->nodata >= 0 && (int)o->nodata < 3
                                              ? edges[o->nodata] : "?");
    dfle_record_number(rec, "outlets", (double)o->n_outlets, NULL);
    if (o->fluvial != NULL)
        component(rec, "fluvial", dfle_fluvial_name(o->fluvial),
                  dfle_fluvial_params(o->fluvial, p, 64), p);
    else
        dfle_record_section(rec, "fluvial", "off");
    if (o->router != NULL) {
        component(rec, "router", dfle_router_name(o->router),
                  dfle_router_params(o->router, p, 64), p);
        component(rec, "law", dfle_law_name(o->law), dfle_law_params(o->law, p, 64), p);
        dfle_record_section(rec, "landscape", NULL);
        dfle_record_param_text(rec, "combine", o->df_combine >= 0 && o->df_combine < 3
                                                   ? combine[o->df_combine] : "?");
    } else {
        dfle_record_section(rec, "router", "off");
        dfle_record_section(rec, "law", "off");
    }
}
