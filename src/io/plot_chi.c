/*
 * plot_chi.c - chi plots: elevation against chi (Perron and Royden
 * 2013), alone or beside the slope-area figure of Eq. (2).
 *
 * On a steady network whose concavity is theta_ref every cell lies on
 * the line through base level whose slope is k_sn A0^-theta_ref, so the
 * line is drawn with the points: where tributaries leave it, or the
 * points bend away from it, the channels are not in that steady state
 * (or theta_ref is not their concavity).  Points are coloured by their
 * own k_sn, the quantity a k_sn map shows in plan view.
 */
#include "dfle/plot.h"

#include "io/plot_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct chi_panel {
    dfle_gp_panel panel;
    dfle_gp_layer L[3];
    double *y_grey, *y_fit; /* z where drawn grey / coloured, NaN elsewhere */
    double lx[2], ly[2];
    char ltitle[256], xlabel[200], clabel[120], gtitle[96];
    double c_lo, c_hi;      /* the colour range, when k_sn is drawn */
    int coloured;
} chi_panel;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void chi_panel_free(chi_panel *cp)
{
    free(cp->y_grey);
    cp->y_grey = cp->y_fit = NULL;
}

/* The layers of the chi plot of c, and its labels, in cp. */
static int chi_panel_new(chi_panel *cp, const dfle_gp_frame *fr, const dfle_plot_chi_data *c,
                         const dfle_plot_axis *y, dfle_error *err)
{
    size_t ng = 0, nf = 0, nk = 0;
    double xmax = 0, ps, *ks = NULL;
    char num[40], e2[24];
    memset(cp, 0, sizeof *cp);
    if (c == NULL || c->n == 0 || c->chi == NULL || c->z == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "plot: chi plot data missing (no cells, or chi "
                              "or z NULL)");
    if (!(isfinite(c->theta_ref) && isfinite(c->A0) && c->A0 > 0))
        return dfle_error_set(err, DFLE_EINVAL, "plot: the chi plot's theta_ref (%g) and A0 "
                              "(%g m^2) must be finite, A0 > 0", c->theta_ref, c->A0);
    if ((cp->y_grey = malloc(2 * c->n * sizeof *cp->y_grey)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
    cp->y_fit = cp->y_grey + c->n;
    ks = c->k_sn != NULL ? malloc(c->n * sizeof *ks) : NULL;
    if (c->k_sn != NULL && ks == NULL) {
        chi_panel_free(cp);
        return dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
    }
    for (size_t i = 0; i < c->n; i++) {
        int fitted = c->A == NULL || c->A[i] >= c->A_min;
        int colour = c->k_sn == NULL || isfinite(c->k_sn[i]);
        cp->y_grey[i] = fitted && colour ? NAN : c->z[i];
        cp->y_fit[i] = fitted && colour ? c->z[i] : NAN;
        ng += !(fitted && colour) && isfinite(c->z[i]) && isfinite(c->chi[i]);
        nf += fitted && colour;
        if (fitted && colour && ks != NULL)
            ks[nk++] = c->k_sn[i];
        if (fitted && isfinite(c->chi[i]))
            xmax = fmax(xmax, c->chi[i]);
    }
    ps = dfle_gp_ps(fr, c->n > 2000 ? 1.8 : 2.6);
    snprintf(e2, sizeof e2, "%.3g", 2 * c->theta_ref);
    if (ng > 0) {
        if (c->A != NULL && c->A_min > 0) {
            dfle_plot_number(num, sizeof num, c->A_min);
            snprintf(cp->gtitle, sizeof cp->gtitle, "{/:Italic A} < %s m^2 (not fitted)", num);
        } else {
            snprintf(cp->gtitle, sizeof cp->gtitle, "No {/:Italic k}_{sn} (base level)");
        }
        cp->L[cp->panel.nl] = (dfle_gp_layer){.n = c->n, .x = c->chi, .y = cp->y_grey,
                                              .title = cp->gtitle, .marks = 1};
        dfle_gp_look_set(&cp->L[cp->panel.nl].look, DFLE_GP_POINTS, "#c8c8c8", 1, 1, 7, ps, 0);
        cp->panel.nl++;
    }
    if (nf > 0) {
        dfle_gp_layer *l = &cp->L[cp->panel.nl++];
        *l = (dfle_gp_layer){.n = c->n, .x = c->chi, .y = cp->y_fit, .c = c->k_sn, .marks = 1,
                             .title = c->k_sn != NULL ? NULL : "Cells"};
        dfle_gp_look_set(&l->look, DFLE_GP_POINTS, "#000000", 1, 1, 7, ps, 0);
        cp->coloured = c->k_sn != NULL;
    }
    if (ks != NULL && nk > 0) {
        qsort(ks, nk, sizeof *ks, cmp_double);
        cp->c_lo = ks[(size_t)floor(0.02 * (double)(nk - 1))];
        cp->c_hi = ks[(size_t)ceil(0.98 * (double)(nk - 1))];
        if (!(cp->c_hi > cp->c_lo))
            cp->c_hi = cp->c_lo + fmax(fabs(cp->c_lo) * 0.1, 1);
    }
    free(ks);
    if (isfinite(c->M_chi) && isfinite(c->z_b) && xmax > 0) {
        dfle_gp_layer *l = &cp->L[cp->panel.nl++];
        double k = c->M_chi * pow(c->A0, c->theta_ref);
        char r2[40] = "";
        cp->lx[0] = 0, cp->lx[1] = xmax;
        cp->ly[0] = c->z_b, cp->ly[1] = c->z_b + c->M_chi * xmax;
        dfle_plot_number(num, sizeof num, k);
        if (isfinite(c->r2))
            snprintf(r2, sizeof r2, ", {/:Italic R}^2 = %.3f", c->r2);
        snprintf(cp->ltitle, sizeof cp->ltitle, "Line through base level: {/:Italic k}_{sn} = "
                 "%s m^{%s}%s", num, e2, r2);
        *l = (dfle_gp_layer){.n = 2, .x = cp->lx, .y = cp->ly, .title = cp->ltitle, .line = 1};
        dfle_gp_look_set(&l->look, DFLE_GP_LINES, DFLE_GP_FIT, 2.5, 1, 0, 0, 0);
    }
    dfle_plot_number(num, sizeof num, c->A0);
    snprintf(cp->xlabel, sizeof cp->xlabel, "{/:Italic χ} (m), {/:Italic θ}_{ref} = %.3g, "
             "{/:Italic A}_0 = %s m^2", c->theta_ref, num);
    snprintf(cp->clabel, sizeof cp->clabel, "{/:Italic k}_{sn} (m^{%s})", e2);
    cp->panel.layers = cp->L;
    cp->panel.y = y;
    cp->panel.ylabel = dfle_plot_label("z", NULL);
    return DFLE_OK;
}

/* The options of the chi panel: the caller's, with the colour scale's
 * label and range where the caller leaves them. */
static void chi_opts(dfle_plot_opts *o, const dfle_plot_opts *user, const chi_panel *cp)
{
    static const dfle_plot_opts none = {0};
    *o = user != NULL ? *user : none;
    if (!cp->coloured)
        return;
    if (o->c.label == NULL)
        o->c.label = cp->clabel;
    if (!o->c.has_lo)
        o->c.has_lo = 1, o->c.lo = cp->c_lo;
    if (!o->c.has_hi)
        o->c.has_hi = 1, o->c.hi = cp->c_hi;
    if (!(o->c.hi > o->c.lo)) /* one end given past the other's default */
        o->c.has_lo = user != NULL && user->c.has_lo, o->c.has_hi = user != NULL && user->c.has_hi;
}

int dfle_plot_chi(const char *path, const dfle_plot_opts *opts, const dfle_plot_chi_data *c,
                  dfle_error *err)
{
    dfle_gp_frame fr;
    dfle_plot_opts o;
    chi_panel cp;
    int rc = dfle_gp_frame_of(path, opts, 16, 11, &fr, err);
    if (rc < 0 ||
        (rc = chi_panel_new(&cp, &fr, c, opts != NULL ? &opts->y : NULL, err)) < 0)
        return rc;
    chi_opts(&o, opts, &cp);
    rc = dfle_gp_figure(path, &fr, &o, 0, cp.xlabel, &cp.panel, 1, err);
    chi_panel_free(&cp);
    return rc;
}

int dfle_plot_slope_area_chi(const char *path, const dfle_plot_opts *opts, size_t n,
                             const double *A, const double *S, const dfle_bins *bins,
                             const dfle_eq2_fit *fit, const dfle_plot_chi_data *c,
                             dfle_error *err)
{
    dfle_gp_frame fr;
    dfle_gp_sa_panel sp;
    chi_panel cp;
    dfle_plot_opts oa, ob;
    dfle_gp_plan *pa = NULL, *pb = NULL;
    dfle_gp_box ba, bb;
    dfle_gp_run r;
    const char *title = opts != NULL ? opts->title : NULL;
    double top;
    int rc = dfle_gp_frame_of(path, opts, 25, 10.5, &fr, err);
    if (rc < 0 || (rc = dfle_gp_slope_area_panel(&sp, &fr, path, n, A, S, bins, fit, NULL,
                                                 err)) < 0)
        return rc;
    if ((rc = chi_panel_new(&cp, &fr, c, NULL, err)) < 0)
        return rc;
    /* Each half its own figure: the page's title above both. */
    top = fr.h_pt - (title != NULL ? 1.6 * fr.font_pt : 0);
    ba = (dfle_gp_box){0, 0, fr.w_pt / 2, top};
    bb = (dfle_gp_box){fr.w_pt / 2, 0, fr.w_pt, top};
    memset(&oa, 0, sizeof oa);
    oa.title = "(a) Slope-area";
    chi_opts(&ob, NULL, &cp);
    ob.title = "(b) Elevation against {/:Italic χ}";
    if ((rc = dfle_gp_plan_new(path, &fr, &ba, &oa, 1, dfle_plot_label("A", NULL), &sp.panel, 1,
                               &pa, err)) == DFLE_OK &&
        (rc = dfle_gp_plan_new(path, &fr, &bb, &ob, 0, cp.xlabel, &cp.panel, 1, &pb, err)) ==
            DFLE_OK &&
        (rc = dfle_gp_begin_frame(&r, path, &fr, err)) == DFLE_OK) {
        /* the two frames side by side, of one height */
        double kb = fmax(dfle_gp_plan_key_below(pa), dfle_gp_plan_key_below(pb));
        dfle_gp_plan_set_key_below(pa, kb);
        dfle_gp_plan_set_key_below(pb, kb);
        fputs("set multiplot\n", r.f);
        if (title != NULL)
            dfle_gp_page_label(r.f, 99, title, fr.w_pt / 2, fr.h_pt - 1.0 * fr.font_pt, 0, 0,
                               &fr);
        dfle_gp_plan_put(r.f, pa, 0, 1);
        dfle_gp_plan_put(r.f, pb, 1, 1);
        fputs("unset multiplot\n", r.f);
        rc = dfle_gp_end(&r, err);
    }
    dfle_gp_plan_free(pa);
    dfle_gp_plan_free(pb);
    chi_panel_free(&cp);
    return rc;
}
