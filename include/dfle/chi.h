/*
 * chi.h - the chi transform and normalised channel steepness, and the
 * concavity of a channel network.
 *
 * On a steady channel of the stream-power law, U = K A^m S^n, slope
 * follows Flint's law S = k_s A^-theta with k_s = (U/K)^(1/n) and
 * theta = m/n.  Perron and Royden (2013) integrate it upstream from base
 * level x_b:
 *
 *   chi(x) = integral from x_b to x of (A0 / A(x'))^theta_ref dx'   [m]
 *   z(x)   = z(x_b) + k_sn / A0^theta_ref * chi(x)
 *
 * so that with theta_ref = theta every channel of the network lies on one
 * line in chi-z, of slope M_chi = dz/dchi = k_sn A0^-theta_ref (= k_sn for
 * the usual A0 = 1 m^2), whatever its drainage area.  k_sn = S A^theta_ref
 * is the normalised steepness [m^(2 theta_ref)].  The concavity theta is
 * the theta_ref that makes the network most collinear in chi-z, or the
 * slope of log S against log A.
 *
 * chi is summed over the links with the area of each link's upper cell,
 * chi_i = chi_r + L_i (A0/A_i)^theta_ref: the rule of the slope to the
 * receiver, so over one link the chi-z slope is k_sn = S A^theta_ref.
 *
 * Everything works on a drainage tree: cells that each drain to one
 * receiver over a flow length, the base-level cells (outlets) draining to
 * themselves.  A DEM profile or network, a model's nodes and a
 * landscape's cells are all such trees.
 */
#ifndef DFLE_CHI_H
#define DFLE_CHI_H

#include <stddef.h>
#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A drainage tree of n cells.  receiver[i] == i marks a base-level cell
 * (chi = 0 there); every other cell drains to receiver[i] over length[i]
 * m (> 0).  A [m^2] > 0 and z [m] finite everywhere; the receivers must
 * reach a base-level cell from every cell (no cycle). */
typedef struct dfle_tree {
    size_t n;
    const size_t *receiver;
    const double *length; /* flow distance to the receiver [m]; unused on base cells */
    const double *A;      /* drainage area [m^2]                                    */
    const double *z;      /* elevation [m]                                          */
} dfle_tree;

typedef struct dfle_chi_opts {
    double theta_ref; /* reference concavity [-] (0.45)                                   */
    double A0;        /* reference area [m^2] (1)                                         */
    double A_min;     /* cells of smaller area are integrated but left out of the
                       * chi-z fit and get no k_sn [m^2] (0: none left out)               */
    double window;    /* k_sn of a cell is the chi-z slope over this much flow distance
                       * centred on it [m] (cut short at a divide or the outlet); 0: over
                       * the link to its receiver                                         */
} dfle_chi_opts;

void dfle_chi_opts_default(dfle_chi_opts *o);

/* The result, per cell and for the network. */
typedef struct dfle_chi {
    size_t n;
    double theta_ref, A0, A_min, window; /* as used                               */
    double *chi;     /* chi [m]                                                   */
    double *k_sn;    /* A0^theta_ref dz/dchi over the window [m^(2 theta_ref)];
                      * NaN where A < A_min or the window has no length          */
    double *z_base;  /* elevation of the base-level cell the cell drains to [m]  */
    size_t *base;    /* that cell                                                 */
    double *d;       /* flow distance to it [m]                                   */
    size_t n_base;   /* base-level cells                                          */
    /* The least-squares line z - z_base = M_chi chi (through base level) over
     * the cells with A >= A_min. */
    double M_chi;    /* dz/dchi [-]                                               */
    double k_sn_fit; /* M_chi A0^theta_ref [m^(2 theta_ref)]                      */
    double r2;       /* 1 - SS_res / SS_tot of that line, SS_tot about the mean   */
    size_t n_fit;    /* cells in the fit                                          */
} dfle_chi;

/* chi, k_sn and the chi-z line of tree t.  out's arrays are allocated
 * here (release them with dfle_chi_release, also after a failure).
 * DFLE_EINVAL names the first bad cell or option; DFLE_EFIT when fewer
 * than two cells have A >= A_min or none has chi > 0. */
int dfle_chi_compute(const dfle_tree *t, const dfle_chi_opts *o, dfle_chi *out,
                     dfle_error *err);
void dfle_chi_release(dfle_chi *c); /* idempotent; c may be zeroed */

/* Check a tree (sizes, values, receivers in range, no cycle); on success
 * *order holds the cells base levels first, each after its receiver (an
 * array of n the caller frees), if order is not NULL. */
int dfle_tree_check(const dfle_tree *t, size_t **order, dfle_error *err);

/* ---- Concavity ------------------------------------------------------ */

enum dfle_concavity_method {
    DFLE_CONCAVITY_CHI = 0,       /* the theta of the most collinear chi-z      */
    DFLE_CONCAVITY_SLOPE_AREA = 1 /* the slope of log S against log A         */
};

typedef struct dfle_concavity_opts {
    double A0;                   /* reference area [m^2] (1)                        */
    double A_min, A_max;         /* cells (pairs) used: A_min <= A <= A_max [m^2]
                                  * (0, 0: all; A_max 0 means no upper bound)       */
    double theta_lo, theta_hi;   /* chi: the range searched (0.05, 1.5)             */
    size_t nbins;                /* slope-area: logarithmic bins (100)              */
} dfle_concavity_opts;

void dfle_concavity_opts_default(dfle_concavity_opts *o);

typedef struct dfle_concavity {
    int method;      /* enum dfle_concavity_method                                */
    double theta;    /* the concavity [-]                                         */
    double k_s;      /* steepness at theta: chi, M_chi A0^theta; slope-area, the
                      * fitted S at A = 1 m^2 [m^(2 theta)]                       */
    double r2;       /* chi: R^2 of the chi-z line; slope-area: of log S on log A */
    size_t n;        /* cells (chi) or bins (slope-area) fitted                   */
    int at_bound;    /* chi: the best theta is an end of the range searched, so
                      * the range, not the data, sets it                          */
    double theta_lo, theta_hi;
    /* chi: R^2 over the grid of theta searched (ncurve values) */
    size_t ncurve;
    double *curve_theta, *curve_r2;
} dfle_concavity;

/* The concavity of tree t by chi-z collinearity: R^2 of the chi-z line
 * (through base level, cells with A_min <= A <= A_max) over a grid of
 * theta_ref every 0.05 from theta_lo to theta_hi, the best refined by
 * golden-section search to 1e-4.  DFLE_EFIT when fewer than three cells
 * are in range. */
int dfle_concavity_chi(const dfle_tree *t, const dfle_concavity_opts *o, dfle_concavity *out,
                       dfle_error *err);

/* The concavity of n (A [m^2], S [m/m]) pairs by slope-area regression:
 * the pairs with A_min <= A <= A_max in nbins logarithmic area bins, a
 * least-squares line of log10 of each bin's geometric-mean slope on
 * log10 of its mean area, theta = -slope.  Bins without a positive slope
 * are left out.  DFLE_EFIT when fewer than three bins remain. */
int dfle_concavity_slope_area(size_t n, const double *A, const double *S,
                              const dfle_concavity_opts *o, dfle_concavity *out,
                              dfle_error *err);

void dfle_concavity_release(dfle_concavity *c); /* idempotent; c may be zeroed */

#ifdef __cplusplus
}
#endif
#endif
