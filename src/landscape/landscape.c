/*
 * landscape.c - the landscape object (landscape.h): its grid and
 * options, its fields in space and time, its flow routing (the routing
 * module's, drainage.h) and, with a router, the network and model that
 * route and weigh the debris flows; the fields a user reads.
 *
 * The elevations live on the grid; the routing is redone whenever they
 * change.  The debris-flow model lives on the network of the data cells
 * (node k is the k-th data cell in index order), re-shaped after every
 * routing: receivers, D8 lengths (dx, dy or the diagonal), areas, widths
 * k_w A^b, the channel mask (A >= A_0: hillslopes are not eroded by the
 * model) and the sources, which are the channel heads.
 */
#include "landscape/landscape_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void dfle_landscape_opts_default(dfle_landscape_opts *o)
{
    memset(o, 0, sizeof *o);
    o->dx = o->dy = 30.0;
    o->x0 = 0.0;
    o->y0 = NAN; /* ny dy: the south edge at y = 0 */
    for (int s = 0; s < 4; s++)
        o->edge[s] = DFLE_DRAINAGE_BASE_LEVEL;
    o->nodata = DFLE_DRAINAGE_OPEN;
    o->df_combine = DFLE_DF_ANY;
    o->A0 = 1e4;
    o->k_w = 0.05;
    o->b = 0.3;
    o->hillslope = DFLE_HILLSLOPE_THRESHOLD;
    o->S_c = 0.8;
    o->cap_channels = 1;
    o->D = 0.01;
    o->U.value = 5e-4;
    o->K_scale.value = 1.0;
    o->df_scale.value = 1.0;
}

/* ---------------------------------------------------------------- */
/* Fields in space and time                                         */
/* ---------------------------------------------------------------- */

void ls_cell_centre(const dfle_landscape *ls, size_t c, double *x, double *y)
{
    *x = ls->o.x0 + ((double)(c % ls->nx) + 0.5) * ls->o.dx;
    *y = ls->o.y0 - ((double)(c / ls->nx) + 0.5) * ls->o.dy;
}

void ls_cell_name(const dfle_landscape *ls, size_t c, char *buf, size_t cap)
{
    double x, y;
    ls_cell_centre(ls, c, &x, &y);
    snprintf(buf, cap, "row %zu, column %zu (x = %.10g m, y = %.10g m)", c / ls->nx + 1,
             c % ls->nx + 1, x, y);
}

/* Every data cell's value: finite and in range, else the cell named, as
 * a number option would be (a raster's NoData, NaN, is no uplift). */
static int check_field(const dfle_landscape *ls, const ls_field *f, dfle_error *err)
{
    for (size_t c = 0; c < ls->n; c++) {
        double v;
        if (isnan(ls->z[c]))
            continue;
        v = ls_value(f, c);
        if (!(isfinite(v) && (f->strict ? v > f->lo : v >= f->lo))) {
            char when[64] = "", cell[160];
            if (f->fn != NULL) /* a function of time: when it gave it */
                snprintf(when, sizeof when, " at t = %g yr", ls->time);
            if (f->grid == NULL)
                return dfle_error_set(err, DFLE_EINVAL, "landscape: %s is %g; it must be "
                                      "finite and %s %g", f->name, v * f->show_scale,
                                      f->strict ? ">" : ">=", f->lo);
            ls_cell_name(ls, c, cell, sizeof cell);
            return dfle_error_set(err, DFLE_EINVAL,
                                  "landscape: %s is %g at %s, a data cell%s; it must be finite "
                                  "and %s %g there", f->name, v * f->show_scale, cell, when,
                                  f->strict ? ">" : ">=", f->lo);
        }
        if (f->grid == NULL)
            break; /* uniform: one check does */
    }
    return DFLE_OK;
}

static int init_field(dfle_landscape *ls, ls_field *f, const dfle_landscape_field *src,
                      const char *name, double lo, int strict, dfle_error *err)
{
    f->name = src->name != NULL ? src->name : name;
    f->show_scale = src->show_scale != 0 ? src->show_scale : 1.0;
    f->lo = lo;
    f->strict = strict;
    f->value = src->value;
    f->fn = src->fn;
    f->ud = src->ud;
    f->varies = src->fn != NULL && src->varies_in_time;
    if (src->grid == NULL && src->fn == NULL)
        return check_field(ls, f, err);
    if ((f->grid = malloc(ls->n * sizeof *f->grid)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory for %s", name);
    if (src->grid != NULL) {
        memcpy(f->grid, src->grid, ls->n * sizeof *f->grid);
        return check_field(ls, f, err);
    }
    return DFLE_OK;
}

static int refresh_field(dfle_landscape *ls, ls_field *f, dfle_error *err)
{
    int st;
    if (f->fn == NULL)
        return DFLE_OK;
    if ((st = f->fn(f->ud, ls->time, f->grid, err)) != DFLE_OK)
        return st;
    return check_field(ls, f, err);
}

/* The model's per-node scales from the grid fields. */
static int push_scales(dfle_landscape *ls, dfle_error *err)
{
    if (ls->model == NULL)
        return DFLE_OK;
    for (size_t k = 0; k < ls->n_data; k++) {
        size_t c = ls->cell_of[k];
        if (ls->s_Ks != NULL)
            ls->s_Ks[k] = ls_value(&ls->K_scale, c);
        if (ls->s_dfs != NULL)
            ls->s_dfs[k] = ls_value(&ls->df_scale, c);
    }
    ls->model_z_current = 0;
    return dfle_model_set_erodibility(ls->model, ls->s_Ks, ls->s_dfs, err);
}

int ls_update_fields(dfle_landscape *ls, int first, dfle_error *err)
{
    ls_field *f[3] = {&ls->U, &ls->K_scale, &ls->df_scale};
    int scales = 0, st;
    for (int k = 0; k < 3; k++) {
        if (f[k]->fn == NULL || (!first && !f[k]->varies))
            continue;
        if (first || f[k]->varies) {
            if ((st = refresh_field(ls, f[k], err)) != DFLE_OK)
                return st;
            scales |= k > 0;
        }
    }
    if (first || scales)
        return push_scales(ls, err);
    return DFLE_OK;
}

/* ---------------------------------------------------------------- */
/* The object                                                       */
/* ---------------------------------------------------------------- */

void dfle_landscape_free(dfle_landscape *ls)
{
    if (ls == NULL)
        return;
    dfle_model_free(ls->model);
    dfle_network_free(ls->net);
    dfle_drainage_free(ls->dr);
    free(ls->z);
    free(ls->z_undo);
    free(ls->rcv_prev);
    free(ls->dzdt);
    free(ls->U.grid);
    free(ls->K_scale.grid);
    free(ls->df_scale.grid);
    free(ls->node_of);
    free(ls->cell_of);
    free(ls->s_Ks);
    free(ls->s_dfs);
    free(ls->w_table);
    free(ls->par_stack);
    free(ls->par_chunk);
    free(ls);
}

static int check_opts(const dfle_landscape_opts *o, dfle_error *err)
{
    if (o->z == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "landscape: initial elevations z are required");
    if (o->router != NULL && o->law == NULL)
        return dfle_error_set(err, DFLE_EINVAL,
                              "landscape: a debris-flow router needs an erosion law (law)");
    if (!(isfinite(o->A0) && o->A0 >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: A0 (channel-head area) must be >= 0 "
                              "m^2 (got %g)", o->A0);
    if (!(isfinite(o->k_w) && o->k_w > 0 && isfinite(o->b)))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: k_w must be > 0 and b finite (got "
                              "k_w = %g, b = %g)", o->k_w, o->b);
    if (o->hillslope < DFLE_HILLSLOPE_THRESHOLD || o->hillslope > DFLE_HILLSLOPE_UPLIFT)
        return dfle_error_set(err, DFLE_EINVAL, "landscape: hillslope = %d is not a rule "
                              "(THRESHOLD, DIFFUSION, UPLIFT)", o->hillslope);
    if (o->hillslope == DFLE_HILLSLOPE_THRESHOLD && !(o->S_c > 0 && o->S_c < INFINITY))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: S_c (critical hillslope gradient) "
                              "must be finite and > 0 (got %g)", o->S_c);
    if (o->hillslope == DFLE_HILLSLOPE_DIFFUSION && !(isfinite(o->D) && o->D > 0))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: D (hillslope diffusivity) must be "
                              "finite and > 0 m^2/yr (got %g)", o->D);
    return DFLE_OK;
}

/* The network and model of the data cells, for debris flows. */
static int make_model(dfle_landscape *ls, dfle_error *err)
{
    const size_t n = ls->n, nd = ls->n_data;
    dfle_model_opts mo;
    size_t k = 0;
    int st;

    ls->node_of = malloc(n * sizeof *ls->node_of);
    ls->cell_of = malloc(nd * sizeof *ls->cell_of);
    /* The erodibility scales by node, where they are not 1. */
    if (ls->K_scale.grid != NULL || ls->K_scale.value != 1.0)
        ls->s_Ks = malloc(nd * sizeof *ls->s_Ks);
    if (ls->df_scale.grid != NULL || ls->df_scale.value != 1.0)
        ls->s_dfs = malloc(nd * sizeof *ls->s_dfs);
    if (ls->node_of == NULL || ls->cell_of == NULL ||
        (ls->s_Ks == NULL && (ls->K_scale.grid != NULL || ls->K_scale.value != 1.0)) ||
        (ls->s_dfs == NULL && (ls->df_scale.grid != NULL || ls->df_scale.value != 1.0)))
        return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory for the debris-flow "
                              "network (%zu cells)", nd);
    ls->n_w = nd < LS_W_TABLE ? nd + 1 : LS_W_TABLE;
    if ((ls->w_table = malloc(ls->n_w * sizeof *ls->w_table)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory for the debris-flow "
                              "network (%zu cells)", nd);
    for (size_t j = 0; j < ls->n_w; j++)
        ls->w_table[j] = ls->o.k_w * pow((double)j * ls->cell_area, ls->o.b);
    for (size_t c = 0; c < n; c++) {
        ls->node_of[c] = isnan(ls->z[c]) ? LS_NONE : (uint32_t)k;
        if (!isnan(ls->z[c]))
            ls->cell_of[k++] = (uint32_t)c;
    }
    if ((st = dfle_network_new(nd, &ls->net, err)) != DFLE_OK)
        return st;
    dfle_model_opts_default(&mo);
    mo.network = ls->net;
    mo.fluvial = ls->o.fluvial;
    mo.router = ls->o.router;
    mo.law = ls->o.law;
    mo.U = ls->U.grid != NULL ? 1.0 : ls->U.value; /* the landscape keeps U itself */
    mo.df_combine = ls->o.df_combine;
    mo.df_frequency = ls->o.df_frequency;
    mo.df_frequency_ud = ls->o.df_frequency_ud;
    return dfle_model_new(&mo, &ls->model, err);
}

int dfle_landscape_new(const dfle_landscape_opts *o, dfle_landscape **out, dfle_error *err)
{
    dfle_landscape *ls;
    dfle_drainage_opts dro;
    int st;

    *out = NULL;
    if (o == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "landscape: options are required");
    if ((st = check_opts(o, err)) != DFLE_OK)
        return st;
    /* Before anything is allocated (landscape_memory.c). */
    if ((st = dfle_landscape_check_grid(o, 0, err)) != DFLE_OK)
        return st;
    dfle_drainage_opts_default(&dro);
    dro.nx = o->nx;
    dro.ny = o->ny;
    dro.dx = o->dx;
    dro.dy = o->dy;
    for (int s = 0; s < 4; s++)
        dro.edge[s] = o->edge[s];
    dro.nodata = o->nodata;
    dro.depressions = DFLE_DRAINAGE_CARVE;
    dro.order = DFLE_DRAINAGE_CHAINS; /* built and swept with the cache, each step */
    if ((ls = calloc(1, sizeof *ls)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory");
    ls->o = *o;
    ls->o.z = NULL;
    if (isnan(ls->o.y0))
        ls->o.y0 = (double)o->ny * o->dy;
    ls->o.outlets = NULL;
    if ((st = dfle_drainage_new(&dro, &ls->dr, err)) != DFLE_OK)
        goto fail;
    ls->nx = o->nx;
    ls->ny = o->ny;
    ls->n = o->nx * o->ny;
    ls->cell_area = o->dx * o->dy;
    ls->rcv_tol = 0.005;
    for (int k = 0; k < 8; k++)
        ls->len[k] = dfle_drainage_length(ls->dr, k);
    if ((st = dfle_drainage_set_outlets(ls->dr, o->outlets, o->n_outlets, err)) != DFLE_OK ||
        (st = dfle_drainage_set_hysteresis(ls->dr, LS_TIE_MARGIN, err)) != DFLE_OK)
        goto fail;
    ls->z = malloc(ls->n * sizeof *ls->z);
    ls->rcv_prev = malloc(ls->n * sizeof *ls->rcv_prev);
    ls->dzdt = calloc(ls->n, sizeof *ls->dzdt);
    if (ls->z == NULL || ls->rcv_prev == NULL || ls->dzdt == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory for %zu x %zu cells",
                            o->nx, o->ny);
        goto fail;
    }
    for (size_t c = 0; c < ls->n; c++) {
        double v = o->z[c];
        if (isinf(v)) {
            st = dfle_error_set(err, DFLE_EINVAL, "landscape: z is infinite at cell %zu (row "
                                "%zu, column %zu); use NaN for NoData", c, c / ls->nx,
                                c % ls->nx);
            goto fail;
        }
        ls->z[c] = v;
        ls->n_data += !isnan(v);
        ls->rcv_prev[c] = LS_NONE;
    }
    if (ls->n_data < 2) {
        st = dfle_error_set(err, DFLE_EINVAL, "landscape: the grid has %zu data cells; need at "
                            "least 2", ls->n_data);
        goto fail;
    }
    /* No cell drains more than the grid: such an A0 leaves no channel,
     * and a run would call the bare hillslopes steady. */
    if (o->A0 > (double)ls->n_data * ls->cell_area) {
        st = dfle_error_set(err, DFLE_EINVAL, "landscape: A0 = %g m^2 (the channel-head area) "
                            "is more than the grid's %zu data cells drain (%g m^2): no cell "
                            "could be a channel", o->A0, ls->n_data,
                            (double)ls->n_data * ls->cell_area);
        goto fail;
    }
    if (o->fluvial != NULL) {
        ls->K = dfle_fluvial_K(o->fluvial);
        ls->m_exp = dfle_fluvial_m(o->fluvial);
        ls->n_exp = dfle_fluvial_n(o->fluvial);
        ls_pow_init(&ls->pow_n, ls->n_exp);
        ls_pow_init(&ls->pow_inv_n, 1.0 / ls->n_exp);
    }
    if ((st = init_field(ls, &ls->U, &o->U, "U (uplift, m/yr)", 0.0, 1, err)) != DFLE_OK ||
        (st = init_field(ls, &ls->K_scale, &o->K_scale, "the fluvial erodibility scale", 0.0, 0,
                         err)) != DFLE_OK ||
        (st = init_field(ls, &ls->df_scale, &o->df_scale, "the debris-flow erodibility scale",
                         0.0, 0, err)) != DFLE_OK)
        goto fail;
    if (o->router != NULL && (st = make_model(ls, err)) != DFLE_OK)
        goto fail;
    if ((st = ls_update_fields(ls, 1, err)) != DFLE_OK)
        goto fail;
    *out = ls;
    return DFLE_OK;
fail:
    dfle_landscape_free(ls);
    return st;
}

size_t dfle_landscape_nx(const dfle_landscape *ls) { return ls->nx; }
size_t dfle_landscape_ny(const dfle_landscape *ls) { return ls->ny; }
double dfle_landscape_dx(const dfle_landscape *ls) { return ls->o.dx; }
double dfle_landscape_dy(const dfle_landscape *ls) { return ls->o.dy; }
size_t dfle_landscape_data_cells(const dfle_landscape *ls) { return ls->n_data; }
double dfle_landscape_time(const dfle_landscape *ls) { return ls->time; }
const double *dfle_landscape_z(const dfle_landscape *ls) { return ls->z; }
const dfle_drainage *dfle_landscape_drainage(const dfle_landscape *ls) { return ls->dr; }
dfle_model *dfle_landscape_model(const dfle_landscape *ls) { return ls->model; }

int dfle_landscape_set_z(dfle_landscape *ls, const double *z, dfle_error *err)
{
    for (size_t c = 0; c < ls->n; c++)
        if (isnan(z[c]) != isnan(ls->z[c]) || isinf(z[c]))
            return dfle_error_set(err, DFLE_EINVAL, "landscape: z at cell %zu (row %zu, column "
                                  "%zu) is %g; NoData must stay NoData (NaN) and data finite",
                                  c, c / ls->nx, c % ls->nx, z[c]);
    memcpy(ls->z, z, ls->n * sizeof *z);
    ls->routed = 0;
    ls->model_z_current = 0;
    ls->have_rates = 0;
    ls->evolved = 1;
    return DFLE_OK;
}

int dfle_landscape_has_run(const dfle_landscape *ls) { return ls->evolved; }

size_t dfle_landscape_memory(const dfle_landscape *ls)
{
    size_t b = sizeof *ls + dfle_drainage_memory(ls->dr);
    b += ls->n * (sizeof *ls->z + sizeof *ls->rcv_prev + sizeof *ls->dzdt);
    b += (ls->z_undo != NULL) * ls->n * sizeof *ls->z_undo;
    b += (ls->U.grid != NULL) * ls->n * sizeof(double);
    b += (ls->K_scale.grid != NULL) * ls->n * sizeof(double);
    b += (ls->df_scale.grid != NULL) * ls->n * sizeof(double);
    if (ls->model != NULL) /* what the model made so far, not all it may make */
        b += dfle_model_memory(ls->model) + (size_t)ls_network_bytes(ls->n, ls->n_data) +
             ((ls->s_Ks != NULL) + (ls->s_dfs != NULL)) * ls->n_data * sizeof(double);
    return b + ls_par_bytes(ls);
}

/* ---------------------------------------------------------------- */
/* Routing, and the network of the debris-flow model                 */
/* ---------------------------------------------------------------- */

/* w = k_w A^b [m].  Areas are whole numbers of cells, mostly few (a
 * hillslope cell drains less than A_0), so the widths of areas up to
 * LS_W_TABLE cells are kept in a table: the same numbers as pow() gives,
 * without a pow() per cell at every routing. */
static double width(const dfle_landscape *ls, double A)
{
    const double cells = A / ls->cell_area;
    if (cells < (double)ls->n_w) {
        const size_t j = (size_t)(cells + 0.5);
        if ((double)j * ls->cell_area == A)
            return ls->w_table[j];
    }
    return ls->o.k_w * pow(A, ls->o.b);
}

/* The network of the data cells from the routing just done, written
 * into the network's own arrays (no copy of a shape a routing). */
static int shape_network(dfle_landscape *ls, dfle_error *err)
{
    const uint32_t *rcv = dfle_drainage_receivers(ls->dr), *off;
    const uint32_t *don = dfle_drainage_donors(ls->dr, &off);
    const unsigned char *dir = dfle_drainage_dir(ls->dr);
    const double *A = dfle_drainage_area(ls->dr);
    const double A0 = ls->o.A0;
    size_t n_stack, heads = 0, chan = 0;
    const uint32_t *stack = dfle_drainage_stack(ls->dr, &n_stack);
    dfle_network_edit_view v;
    int st;

    if ((st = dfle_network_edit(ls->net, 1, &v, err)) != DFLE_OK)
        return st;
    for (size_t k = 0; k < ls->n_data; k++) {
        const size_t c = ls->cell_of[k];
        const int is_chan = A[c] >= A0;
        int head = is_chan;
        v.receiver[k] = ls->node_of[rcv[c]];
        v.length[k] = dir[c] < 8 ? ls->len[dir[c]] : 1.0;
        v.A[k] = A[c];
        v.w[k] = width(ls, A[c]);
        for (uint32_t j = off[c]; head && j < off[c + 1]; j++)
            head = !(A[don[j]] >= A0);
        v.channel[k] = (unsigned char)is_chan;
        v.source[k] = (unsigned char)head;
        heads += (size_t)head;
        chan += (size_t)is_chan;
    }
    for (size_t k = 0; k < n_stack; k++)
        v.stack[k] = ls->node_of[stack[k]];
    if ((st = dfle_network_commit(ls->net, err)) != DFLE_OK)
        return st;
    ls->heads = heads;
    ls->channel_cells = chan;
    return DFLE_OK;
}

int ls_route(dfle_landscape *ls, dfle_error *err)
{
    const uint32_t *rcv;
    size_t changes = 0;
    int st;

    if (ls->routed)
        return DFLE_OK;
    if ((st = dfle_drainage_route(ls->dr, ls->z, err)) != DFLE_OK)
        return st;
    rcv = dfle_drainage_receivers(ls->dr);
    {
        /* The receivers' hash, to tell a network that returns to an
         * earlier routing (it cycles) from one still settling; without a
         * model the channel cells are counted in the same pass. */
        const double *A = dfle_drainage_area(ls->dr), A0 = ls->o.A0;
        const int count = ls->model == NULL;
        uint64_t h = 0xcbf29ce484222325ull;
        size_t chan = 0;
        for (size_t c = 0; c < ls->n; c++) {
            changes += rcv[c] != ls->rcv_prev[c];
            ls->rcv_prev[c] = rcv[c];
            h = (h ^ rcv[c]) * 0x100000001b3ull;
            chan += count && A[c] >= A0; /* NaN on NoData: not counted */
        }
        if (count)
            ls->channel_cells = chan;
        ls->rcv_repeat = 0;
        for (size_t k = 0; changes > 0 && k < ls->rcv_hashes; k++)
            ls->rcv_repeat |= ls->rcv_hash[k] == h;
        memmove(ls->rcv_hash + 1, ls->rcv_hash, (LS_RCV_HISTORY - 1) * sizeof *ls->rcv_hash);
        ls->rcv_hash[0] = h;
        ls->rcv_hashes += ls->rcv_hashes < LS_RCV_HISTORY;
    }
    ls->rcv_changes = changes;
    ls->stable = (double)changes <= floor(ls->rcv_tol * (double)ls->n_data) ? ls->stable + 1 : 0;
    ls->routings++;
    ls->routed = 1;
    /* Areas, widths, lengths and heads follow from the receivers alone:
     * where none changed (a landscape near its steady state) the network,
     * and every cache the router and model keep for its version, stand. */
    if (ls->model != NULL && (changes > 0 || !ls->shape_current)) {
        ls->shape_current = 0;
        if ((st = shape_network(ls, err)) != DFLE_OK)
            return st;
        ls->shape_current = 1;
    }
    ls->model_z_current = 0;
    return DFLE_OK;
}

int ls_model_evaluate(dfle_landscape *ls, dfle_error *err)
{
    double *zm;
    if (ls->model == NULL || ls->model_z_current)
        return DFLE_OK;
    zm = dfle_model_z(ls->model);
    for (size_t k = 0; k < ls->n_data; k++)
        zm[k] = ls->z[ls->cell_of[k]];
    dfle_model_invalidate_flow(ls->model);
    if (dfle_model_evaluate(ls->model, err) != DFLE_OK)
        return err != NULL ? err->code : DFLE_ENUMERIC;
    ls->model_z_current = 1;
    return DFLE_OK;
}

int ls_model_route(dfle_landscape *ls, const double **S, const double **reach, dfle_error *err)
{
    double *zm;
    if (ls->model_z_current)
        return dfle_model_route(ls->model, S, reach, err); /* evaluated: returns its fields */
    zm = dfle_model_z(ls->model);
    for (size_t k = 0; k < ls->n_data; k++)
        zm[k] = ls->z[ls->cell_of[k]];
    dfle_model_invalidate_flow(ls->model);
    return dfle_model_route(ls->model, S, reach, err);
}

double ls_reach(const dfle_landscape *ls, size_t c)
{
    return ls->model != NULL ? dfle_model_flow_reaches(ls->model, ls->node_of[c]) : 0.0;
}

double ls_fluvial_rate(const dfle_landscape *ls, size_t c, double A, double S)
{
    if (!(S > 0) || ls->K == 0)
        return 0.0;
    return ls->K * ls_value(&ls->K_scale, c) * pow(A, ls->m_exp) * pow(S, ls->n_exp);
}

/* ---------------------------------------------------------------- */
/* Fields                                                           */
/* ---------------------------------------------------------------- */

/* Names, units, and the CF long and standard names (a standard name
 * only where the CF table has one that means the same thing). */
static const struct {
    const char *name, *unit, *long_name, *standard_name;
} field_info[DFLE_LS_NFIELDS] = {
    [DFLE_LS_Z] = {"z", "m", "elevation of the land surface", "surface_altitude"},
    [DFLE_LS_A] = {"A", "m^2", "drainage area (D8)", NULL},
    [DFLE_LS_S] = {"S", "-", "slope to the D8 receiver", NULL},
    [DFLE_LS_E_F] = {"E_f", "m/yr", "fluvial erosion rate", NULL},
    [DFLE_LS_E_DF] = {"E_df", "m/yr", "debris-flow erosion rate", NULL},
    [DFLE_LS_REACH] = {"reach", "-", "debris flows going on at the cell (weighted count)", NULL},
    [DFLE_LS_CHANNEL] = {"channel", "-", "cell kind: 0 hillslope, 1 channel, 2 channel head",
                         NULL},
    [DFLE_LS_DZDT] = {"dzdt", "m/yr", "rate of change of the surface elevation", NULL},
    [DFLE_LS_U] = {"U", "m/yr", "rock uplift rate", NULL},
    [DFLE_LS_BASE] = {"base", "-", "base-level cell (1) or not (0)", NULL},
};

int dfle_landscape_field_lookup(const char *name)
{
    for (int f = 0; f < DFLE_LS_NFIELDS; f++)
        if (strcmp(name, field_info[f].name) == 0)
            return f;
    return -1;
}

const char *dfle_landscape_field_name(int f)
{
    return f >= 0 && f < DFLE_LS_NFIELDS ? field_info[f].name : NULL;
}

const char *dfle_landscape_field_unit(int f)
{
    return f >= 0 && f < DFLE_LS_NFIELDS ? field_info[f].unit : NULL;
}

const char *dfle_landscape_field_long_name(int f)
{
    return f >= 0 && f < DFLE_LS_NFIELDS ? field_info[f].long_name : NULL;
}

const char *dfle_landscape_field_standard_name(int f)
{
    return f >= 0 && f < DFLE_LS_NFIELDS ? field_info[f].standard_name : NULL;
}

int dfle_landscape_get(dfle_landscape *ls, int field, double *out, dfle_error *err)
{
    const uint32_t *rcv, *off, *don;
    const unsigned char *dir;
    const double *A;
    const dfle_model *m = ls->model;
    const double *Edf = NULL;
    int st;

    if (field < 0 || field >= DFLE_LS_NFIELDS)
        return dfle_error_set(err, DFLE_EINVAL, "landscape: no field number %d", field);
    if ((st = ls_route(ls, err)) != DFLE_OK)
        return st;
    if ((field == DFLE_LS_E_DF || field == DFLE_LS_REACH) && m != NULL) {
        if ((st = ls_model_evaluate(ls, err)) != DFLE_OK)
            return st;
        if ((Edf = dfle_model_field(ls->model, DFLE_FIELD_E_DF, err)) == NULL)
            return err != NULL ? err->code : DFLE_ENUMERIC;
    }
    rcv = dfle_drainage_receivers(ls->dr);
    dir = dfle_drainage_dir(ls->dr);
    A = dfle_drainage_area(ls->dr);
    don = dfle_drainage_donors(ls->dr, &off);
    for (size_t c = 0; c < ls->n; c++) {
        const double zc = ls->z[c];
        const double S = dir[c] < 8 ? (zc - ls->z[rcv[c]]) / ls->len[dir[c]] : 0.0;
        double v = NAN;
        if (isnan(zc)) {
            out[c] = NAN;
            continue;
        }
        switch (field) {
        case DFLE_LS_Z: v = zc; break;
        case DFLE_LS_A: v = A[c]; break;
        case DFLE_LS_S: v = S; break;
        case DFLE_LS_E_F:
            v = A[c] >= ls->o.A0 && rcv[c] != c ? ls_fluvial_rate(ls, c, A[c], S) : 0.0;
            break;
        case DFLE_LS_E_DF: v = Edf != NULL ? Edf[ls->node_of[c]] : 0.0; break;
        case DFLE_LS_REACH: v = ls_reach(ls, c); break;
        case DFLE_LS_CHANNEL:
            v = A[c] >= ls->o.A0;
            for (uint32_t j = off[c]; v > 0 && j < off[c + 1]; j++)
                if (A[don[j]] >= ls->o.A0)
                    v = 3; /* marked: not a head */
            v = v == 3 ? 1 : v > 0 ? 2 : 0;
            break;
        case DFLE_LS_DZDT: v = ls->have_rates ? ls->dzdt[c] : NAN; break;
        case DFLE_LS_U: v = ls_value(&ls->U, c); break;
        case DFLE_LS_BASE: v = rcv[c] == c; break;
        default: break;
        }
        out[c] = v;
    }
    return DFLE_OK;
}
