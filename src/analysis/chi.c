/*
 * chi.c - the chi transform of Perron and Royden (2013) and normalised
 * channel steepness on a drainage tree (chi.h).
 *
 * chi is summed upstream from each base-level cell over the links, each
 * with the area of its upper cell: chi_i = chi_r + L_i (A0/A_i)^theta.
 * That is the rule of the slope a cell has to its receiver, S_i = (z_i -
 * z_r) / L_i, with which a model or landscape cell erodes (U = K A_i^m
 * S_i^n at steady state), so a steady state of dfle's lies on its chi-z
 * line exactly, and over one link the chi-z slope is S A^theta itself.
 * On a profile sampled from a continuous one it converges on the
 * integral at first order in the cell size.  (On the 30 m Big Tujunga
 * DEM its chi and the trapezoid rule's differ by under 1 % where A >=
 * 1 km^2; near channel heads, where area doubles from cell to cell, by
 * up to a factor of two: chi there says little either way.)
 *
 * k_sn of a cell is A0^theta times the chi-z slope over a window of flow
 * distance centred on it, rather than S A^theta: over the same window the
 * two measure the same drop, but the chi-z slope weighs the change of area
 * along the window correctly, and on a steady stream-power channel it is
 * exactly k_s wherever the window lies.  Upstream the window follows the
 * donor of largest area (the path a profile follows), downstream the
 * receivers.
 */
#include "dfle/chi.h"

#include "dfle/analysis.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define NONE SIZE_MAX

void dfle_chi_opts_default(dfle_chi_opts *o)
{
    memset(o, 0, sizeof *o);
    o->theta_ref = 0.45;
    o->A0 = 1.0;
}

void dfle_chi_release(dfle_chi *c)
{
    if (c == NULL)
        return;
    free(c->chi);
    free(c->k_sn);
    free(c->z_base);
    free(c->base);
    free(c->d);
    c->chi = c->k_sn = c->z_base = c->d = NULL;
    c->base = NULL;
}

int dfle_tree_check(const dfle_tree *t, size_t **order, dfle_error *err)
{
    size_t *count = NULL, *donors = NULL, *ord = NULL, head = 0, tail = 0, n;
    if (order != NULL)
        *order = NULL;
    if (t == NULL || t->n == 0 || t->receiver == NULL || t->length == NULL || t->A == NULL ||
        t->z == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "chi: the drainage tree is empty or lacks "
                              "receivers, lengths, areas or elevations");
    n = t->n;
    for (size_t i = 0; i < n; i++) {
        size_t r = t->receiver[i];
        if (r >= n)
            return dfle_error_set(err, DFLE_EINVAL, "chi: cell %zu drains to %zu, beyond the "
                                  "%zu cells", i, r, n);
        if (!(isfinite(t->A[i]) && t->A[i] > 0))
            return dfle_error_set(err, DFLE_EINVAL, "chi: cell %zu has drainage area %g m^2 "
                                  "(must be finite and > 0)", i, t->A[i]);
        if (!isfinite(t->z[i]))
            return dfle_error_set(err, DFLE_EINVAL, "chi: cell %zu has elevation %g m (must "
                                  "be finite)", i, t->z[i]);
        if (r != i && !(isfinite(t->length[i]) && t->length[i] > 0))
            return dfle_error_set(err, DFLE_EINVAL, "chi: cell %zu drains to cell %zu over "
                                  "%g m (must be finite and > 0)", i, r, t->length[i]);
    }
    /* Donors in compressed rows, then a breadth-first walk up from the
     * base levels: a cell it never reaches drains in a cycle. */
    count = calloc(n + 1, sizeof *count);
    donors = malloc(n * sizeof *donors);
    ord = malloc(n * sizeof *ord);
    if (count == NULL || donors == NULL || ord == NULL) {
        free(count), free(donors), free(ord);
        return dfle_error_set(err, DFLE_ENOMEM, "chi: out of memory");
    }
    for (size_t i = 0; i < n; i++)
        if (t->receiver[i] != i)
            count[t->receiver[i] + 1]++;
    for (size_t i = 0; i < n; i++)
        count[i + 1] += count[i];
    for (size_t i = 0; i < n; i++) {
        size_t r = t->receiver[i];
        if (r != i)
            donors[count[r]++] = i;
    }
    /* count[r] is now the end of r's row; its start is count[r - 1] */
    for (size_t i = 0; i < n; i++)
        if (t->receiver[i] == i)
            ord[tail++] = i;
    while (head < tail) {
        size_t c = ord[head++];
        for (size_t k = c > 0 ? count[c - 1] : 0; k < count[c]; k++)
            ord[tail++] = donors[k];
    }
    free(count);
    free(donors);
    if (tail < n) {
        size_t bad = 0;
        unsigned char *seen = calloc(n, 1);
        if (seen != NULL) {
            for (size_t k = 0; k < tail; k++)
                seen[ord[k]] = 1;
            while (bad < n && seen[bad])
                bad++;
            free(seen);
        }
        free(ord);
        return dfle_error_set(err, DFLE_EINVAL, "chi: %zu of the %zu cells (cell %zu the "
                              "first) never reach a base-level cell: their receivers form a "
                              "cycle", n - tail, n, bad);
    }
    if (order != NULL)
        *order = ord;
    else
        free(ord);
    return DFLE_OK;
}

static int check_opts(const dfle_chi_opts *o, dfle_error *err)
{
    if (!(isfinite(o->theta_ref) && o->theta_ref >= 0 && o->theta_ref <= 5))
        return dfle_error_set(err, DFLE_EINVAL, "chi: theta_ref must be in 0..5 (got %g)",
                              o->theta_ref);
    if (!(isfinite(o->A0) && o->A0 > 0))
        return dfle_error_set(err, DFLE_EINVAL, "chi: A0 must be a finite area > 0 m^2 (got "
                              "%g)", o->A0);
    if (!(isfinite(o->A_min) && o->A_min >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "chi: A_min must be a finite area >= 0 m^2 "
                              "(got %g)", o->A_min);
    if (!(isfinite(o->window) && o->window >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "chi: window must be a finite flow distance "
                              ">= 0 m (got %g)", o->window);
    return DFLE_OK;
}

/* chi, distance and base of every cell, in `order` (receivers first). */
static void integrate(const dfle_tree *t, const size_t *order, double theta, double A0,
                      double *chi, double *d, size_t *base)
{
    for (size_t k = 0; k < t->n; k++) {
        size_t i = order[k], r = t->receiver[i];
        if (r == i) {
            chi[i] = 0;
            if (d != NULL)
                d[i] = 0;
            if (base != NULL)
                base[i] = i;
            continue;
        }
        chi[i] = chi[r] + t->length[i] * pow(A0 / t->A[i], theta);
        if (d != NULL)
            d[i] = d[r] + t->length[i];
        if (base != NULL)
            base[i] = base[r];
    }
}

/* The point `half` m upstream (up = 1, along the largest donors) or
 * downstream of cell i: its z and chi, linear between cells; the path's
 * end where it is shorter. */
static void along(const dfle_tree *t, const size_t *upc, const double *chi, size_t i,
                  double half, int up, double *z, double *x)
{
    size_t c = i;
    double acc = 0;
    for (;;) {
        size_t nxt = up ? upc[c] : t->receiver[c];
        double len;
        if (nxt == NONE || nxt == c) /* a divide, or base level */
            break;
        len = up ? t->length[nxt] : t->length[c];
        if (acc + len >= half) {
            double f = (half - acc) / len;
            *z = t->z[c] + f * (t->z[nxt] - t->z[c]);
            *x = chi[c] + f * (chi[nxt] - chi[c]);
            return;
        }
        acc += len;
        c = nxt;
    }
    *z = t->z[c];
    *x = chi[c];
}

/* The least-squares line y = M x through the origin over cells with
 * chi > 0 and A in [A_min, A_max] (A_max 0: no bound). */
static void fit_line(const dfle_tree *t, const double *chi, const double *z_base, const size_t *base,
                     double A_min, double A_max, double *M, double *r2, size_t *nfit)
{
    double sxx = 0, sxy = 0, sy = 0, syy = 0, ss_res;
    size_t m = 0;
    for (size_t i = 0; i < t->n; i++) {
        double x = chi[i], y;
        if (!(x > 0) || t->A[i] < A_min || (A_max > 0 && t->A[i] > A_max))
            continue;
        y = t->z[i] - (z_base != NULL ? z_base[i] : t->z[base[i]]);
        sxx += x * x, sxy += x * y, sy += y, syy += y * y;
        m++;
    }
    *nfit = m;
    *M = m > 0 && sxx > 0 ? sxy / sxx : NAN;
    /* SS_res = syy - 2 M sxy + M^2 sxx = syy - sxy^2/sxx, SS_tot about the mean */
    ss_res = syy - (sxx > 0 ? sxy * sxy / sxx : 0);
    {
        double ss_tot = m > 0 ? syy - sy * sy / (double)m : 0;
        *r2 = m >= 2 && ss_tot > 0 ? 1 - fmax(ss_res, 0) / ss_tot : NAN;
    }
}

int dfle_chi_compute(const dfle_tree *t, const dfle_chi_opts *opts, dfle_chi *out,
                     dfle_error *err)
{
    dfle_chi_opts def;
    size_t *order = NULL, *upc = NULL, n;
    double scale;
    int rc;

    if (out == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "chi: no result to fill");
    memset(out, 0, sizeof *out);
    if (opts == NULL) {
        dfle_chi_opts_default(&def);
        opts = &def;
    }
    if ((rc = check_opts(opts, err)) < 0 || (rc = dfle_tree_check(t, &order, err)) < 0)
        return rc;
    n = t->n;
    out->n = n;
    out->theta_ref = opts->theta_ref;
    out->A0 = opts->A0;
    out->A_min = opts->A_min;
    out->window = opts->window;
    out->chi = malloc(n * sizeof *out->chi);
    out->k_sn = malloc(n * sizeof *out->k_sn);
    out->z_base = malloc(n * sizeof *out->z_base);
    out->d = malloc(n * sizeof *out->d);
    out->base = malloc(n * sizeof *out->base);
    upc = malloc(n * sizeof *upc);
    if (out->chi == NULL || out->k_sn == NULL || out->z_base == NULL || out->d == NULL ||
        out->base == NULL || upc == NULL) {
        free(order), free(upc);
        return dfle_error_set(err, DFLE_ENOMEM, "chi: out of memory (%zu cells)", n);
    }
    integrate(t, order, opts->theta_ref, opts->A0, out->chi, out->d, out->base);
    free(order);
    for (size_t i = 0; i < n; i++) {
        out->z_base[i] = t->z[out->base[i]];
        out->n_base += out->base[i] == i;
        upc[i] = NONE;
    }
    /* each cell's donor of largest area (ties: the first) */
    for (size_t i = 0; i < n; i++) {
        size_t r = t->receiver[i];
        if (r != i && (upc[r] == NONE || t->A[i] > t->A[upc[r]]))
            upc[r] = i;
    }
    scale = pow(opts->A0, opts->theta_ref);
    for (size_t i = 0; i < n; i++) {
        double zu, xu, zd, xd;
        out->k_sn[i] = NAN;
        if (t->A[i] < opts->A_min)
            continue;
        if (opts->window > 0) {
            along(t, upc, out->chi, i, opts->window / 2, 1, &zu, &xu);
            along(t, upc, out->chi, i, opts->window / 2, 0, &zd, &xd);
        } else if (t->receiver[i] != i) {
            zu = t->z[i], xu = out->chi[i];
            zd = t->z[t->receiver[i]], xd = out->chi[t->receiver[i]];
        } else {
            continue; /* a base-level cell has no link to measure over */
        }
        if (xu > xd)
            out->k_sn[i] = scale * (zu - zd) / (xu - xd);
    }
    free(upc);
    fit_line(t, out->chi, out->z_base, out->base, opts->A_min, 0, &out->M_chi, &out->r2,
             &out->n_fit);
    out->k_sn_fit = out->M_chi * scale;
    if (out->n_fit < 2 || !isfinite(out->M_chi))
        return dfle_error_set(err, DFLE_EFIT, "chi: %zu cell%s above base level with A >= "
                              "A_min = %g m^2: too few for the chi-z line", out->n_fit,
                              out->n_fit == 1 ? "" : "s", opts->A_min);
    return DFLE_OK;
}

/* ---- Concavity ------------------------------------------------------ */

void dfle_concavity_opts_default(dfle_concavity_opts *o)
{
    memset(o, 0, sizeof *o);
    o->A0 = 1.0;
    o->theta_lo = 0.05;
    o->theta_hi = 1.5;
    o->nbins = 100;
}

void dfle_concavity_release(dfle_concavity *c)
{
    if (c == NULL)
        return;
    free(c->curve_theta);
    free(c->curve_r2);
    c->curve_theta = c->curve_r2 = NULL;
    c->ncurve = 0;
}

static int check_concavity_opts(const dfle_concavity_opts *o, int chi, dfle_error *err)
{
    if (!(isfinite(o->A0) && o->A0 > 0))
        return dfle_error_set(err, DFLE_EINVAL, "concavity: A0 must be a finite area > 0 m^2 "
                              "(got %g)", o->A0);
    if (!(isfinite(o->A_min) && o->A_min >= 0) || !(isfinite(o->A_max) && o->A_max >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "concavity: A_min and A_max must be finite "
                              "areas >= 0 m^2 (got %g, %g)", o->A_min, o->A_max);
    if (o->A_max > 0 && !(o->A_max > o->A_min))
        return dfle_error_set(err, DFLE_EINVAL, "concavity: A_max = %g m^2 must exceed A_min "
                              "= %g m^2", o->A_max, o->A_min);
    if (chi && !(isfinite(o->theta_lo) && isfinite(o->theta_hi) && o->theta_lo >= 0 &&
                 o->theta_hi > o->theta_lo + 0.01 && o->theta_hi <= 5))
        return dfle_error_set(err, DFLE_EINVAL, "concavity: the range of theta searched must "
                              "be 0 <= lo < hi <= 5, at least 0.01 apart (got %g..%g)",
                              o->theta_lo, o->theta_hi);
    if (!chi && (o->nbins < 1 || o->nbins > 1000000))
        return dfle_error_set(err, DFLE_EINVAL, "concavity: nbins must be 1..1000000 (got "
                              "%zu)", o->nbins);
    return DFLE_OK;
}

/* R^2 of the chi-z line at theta (work: chi and base of each cell). */
typedef struct chi_work {
    const dfle_tree *t;
    const dfle_concavity_opts *o;
    const size_t *order;
    double *chi;
    size_t *base;
} chi_work;

static double r2_at(chi_work *w, double theta, double *M, size_t *m)
{
    double r2;
    integrate(w->t, w->order, theta, w->o->A0, w->chi, NULL, w->base);
    fit_line(w->t, w->chi, NULL, w->base, w->o->A_min, w->o->A_max, M, &r2, m);
    return isfinite(r2) ? r2 : -HUGE_VAL;
}

int dfle_concavity_chi(const dfle_tree *t, const dfle_concavity_opts *opts, dfle_concavity *out,
                       dfle_error *err)
{
    dfle_concavity_opts def;
    chi_work w;
    size_t *order = NULL, best = 0, m = 0, ng;
    double lo, hi, M, step = 0.05;
    int rc;

    if (out == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "concavity: no result to fill");
    memset(out, 0, sizeof *out);
    out->method = DFLE_CONCAVITY_CHI;
    if (opts == NULL) {
        dfle_concavity_opts_default(&def);
        opts = &def;
    }
    if ((rc = check_concavity_opts(opts, 1, err)) < 0 ||
        (rc = dfle_tree_check(t, &order, err)) < 0)
        return rc;
    out->theta_lo = lo = opts->theta_lo;
    out->theta_hi = hi = opts->theta_hi;
    ng = (size_t)floor((hi - lo) / step + 1e-9) + 1;
    if (lo + (double)(ng - 1) * step < hi - 1e-9)
        ng++; /* the upper end itself */
    w = (chi_work){t, opts, order, malloc(t->n * sizeof(double)), malloc(t->n * sizeof(size_t))};
    out->curve_theta = malloc(ng * sizeof *out->curve_theta);
    out->curve_r2 = malloc(ng * sizeof *out->curve_r2);
    if (w.chi == NULL || w.base == NULL || out->curve_theta == NULL || out->curve_r2 == NULL) {
        rc = dfle_error_set(err, DFLE_ENOMEM, "concavity: out of memory");
        goto done;
    }
    out->ncurve = ng;
    for (size_t k = 0; k < ng; k++) {
        double th = fmin(hi, lo + (double)k * step);
        out->curve_theta[k] = th;
        out->curve_r2[k] = r2_at(&w, th, &M, &m);
        if (m < 3) {
            rc = dfle_error_set(err, DFLE_EFIT, "concavity: %zu cell%s above base level with "
                                "A in range: too few for the chi-z line", m, m == 1 ? "" : "s");
            goto done;
        }
        if (out->curve_r2[k] > out->curve_r2[best])
            best = k;
    }
    /* Golden-section search between the grid neighbours of the best. */
    {
        const double g = 0.6180339887498949;
        double a = out->curve_theta[best > 0 ? best - 1 : 0];
        double b = out->curve_theta[best + 1 < ng ? best + 1 : ng - 1];
        double c = b - g * (b - a), d = a + g * (b - a);
        double fc = r2_at(&w, c, &M, &m), fd = r2_at(&w, d, &M, &m);
        while (b - a > 1e-4) {
            if (fc >= fd) {
                b = d, d = c, fd = fc;
                c = b - g * (b - a);
                fc = r2_at(&w, c, &M, &m);
            } else {
                a = c, c = d, fc = fd;
                d = a + g * (b - a);
                fd = r2_at(&w, d, &M, &m);
            }
        }
        out->theta = 0.5 * (a + b);
        /* the grid's own best when the search found nothing better */
        if (r2_at(&w, out->theta, &M, &m) < out->curve_r2[best])
            out->theta = out->curve_theta[best];
    }
    out->r2 = r2_at(&w, out->theta, &M, &m);
    out->n = m;
    out->k_s = M * pow(opts->A0, out->theta);
    out->at_bound = out->theta - lo < 2e-4 || hi - out->theta < 2e-4;
done:
    free(order);
    free(w.chi);
    free(w.base);
    if (rc < 0)
        dfle_concavity_release(out);
    return rc;
}

int dfle_concavity_slope_area(size_t n, const double *A, const double *S,
                              const dfle_concavity_opts *opts, dfle_concavity *out,
                              dfle_error *err)
{
    dfle_concavity_opts def;
    dfle_bins bins;
    double *a = NULL, *s = NULL, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
    size_t m = 0, k = 0;
    int rc;

    if (out == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "concavity: no result to fill");
    memset(out, 0, sizeof *out);
    memset(&bins, 0, sizeof bins);
    out->method = DFLE_CONCAVITY_SLOPE_AREA;
    out->theta_lo = out->theta_hi = NAN;
    if (opts == NULL) {
        dfle_concavity_opts_default(&def);
        opts = &def;
    }
    if ((rc = check_concavity_opts(opts, 0, err)) < 0)
        return rc;
    if (n == 0 || A == NULL || S == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "concavity: no slope-area pairs");
    a = malloc(n * sizeof *a);
    s = malloc(n * sizeof *s);
    if (a == NULL || s == NULL) {
        free(a), free(s);
        return dfle_error_set(err, DFLE_ENOMEM, "concavity: out of memory");
    }
    for (size_t i = 0; i < n; i++)
        if (isfinite(A[i]) && isfinite(S[i]) && A[i] > 0 && A[i] >= opts->A_min &&
            (opts->A_max == 0 || A[i] <= opts->A_max))
            a[k] = A[i], s[k] = S[i], k++;
    rc = dfle_bins_compute(k, a, s, opts->nbins, &bins, err);
    free(a);
    free(s);
    if (rc < 0)
        return rc == DFLE_EINVAL ? dfle_error_set(err, DFLE_EFIT, "concavity: %zu slope-area "
                                                  "pair%s with A in range: too few to bin", k,
                                                  k == 1 ? "" : "s")
                                 : rc;
    for (size_t j = 0; j < bins.n; j++) {
        double x, y;
        if (!(bins.S_geomean[j] > 0 && isfinite(bins.S_geomean[j])))
            continue;
        x = log10(bins.A[j]), y = log10(bins.S_geomean[j]);
        sx += x, sy += y, sxx += x * x, sxy += x * y, syy += y * y;
        m++;
    }
    dfle_bins_release(&bins);
    out->n = m;
    if (m < 3)
        return dfle_error_set(err, DFLE_EFIT, "concavity: %zu bin%s with a positive slope: too "
                              "few for the log S - log A line", m, m == 1 ? "" : "s");
    {
        double mx = sx / (double)m, my = sy / (double)m;
        double vxx = sxx - (double)m * mx * mx, vxy = sxy - (double)m * mx * my;
        double vyy = syy - (double)m * my * my, b;
        if (!(vxx > 0))
            return dfle_error_set(err, DFLE_EFIT, "concavity: every bin has the same area");
        b = vxy / vxx;
        out->theta = -b;
        out->k_s = pow(10.0, my - b * mx);
        out->r2 = vyy > 0 ? vxy * vxy / (vxx * vyy) : NAN;
    }
    return DFLE_OK;
}
