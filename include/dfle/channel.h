/*
 * channel.h - the 1D channel grid: node positions, drainage area, width.
 *
 * Nodes run from the channel head (i = 0, x = 0) to the outlet
 * (i = n - 1) at uniform spacing dx.  Geometry is fixed for the life of
 * the channel; elevations live in the model, so one channel can be
 * shared by several models.
 *
 * Default geometry (McGuire et al. 2023, Sect. 2.1):
 *   A(x) = A0 + hack_coef * x^hack_exp      [m^2], A0 = 1000, 25, 5/3
 *   w(A) = k_w * A^b                        [m],   k_w = 0.05, b = 0.3
 * The domain length is set either directly (`length`, m) or as the
 * drainage area the outlet must reach (`A_max`, m^2, default 8 km^2);
 * the outlet is then the first node whose area is >= A_max.
 */
#ifndef DFLE_CHANNEL_H
#define DFLE_CHANNEL_H

#include <stddef.h>
#include "dfle/error.h"
#include "dfle/param.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_channel dfle_channel;

typedef struct dfle_channel_opts {
    double dx;        /* node spacing [m], > 0                            */
    double A0;        /* drainage area at the head [m^2], > 0             */
    double hack_coef; /* coefficient of x^hack_exp [m^(2 - hack_exp)], >= 0 */
    double hack_exp;  /* exponent of x in A(x) [-], > 0                   */
    double k_w;       /* width coefficient [m^(1-2b)], > 0                */
    double b;         /* width-area exponent [-]                          */
    double A_max;     /* outlet drainage area [m^2]; used if length <= 0  */
    double length;    /* head-to-outlet distance [m]; 0 = use A_max       */
} dfle_channel_opts;

/* Fill `opts` with the paper's defaults (dx = 5 m, A_max = 8 km^2). */
void dfle_channel_opts_default(dfle_channel_opts *opts);

/* Build a channel from the Hack-law geometry in `opts`. */
int dfle_channel_new(const dfle_channel_opts *opts, dfle_channel **out,
                     dfle_error *err);

/* Build a channel from node arrays (e.g. a user's A(x), a DEM profile).
 * A [m^2] must be positive and non-decreasing, w [m] positive; n >= 3.
 * The arrays are copied. */
int dfle_channel_new_from_arrays(size_t n, double dx, const double *A,
                                 const double *w, dfle_channel **out,
                                 dfle_error *err);

void dfle_channel_free(dfle_channel *ch);

/* A number no other channel in this process has had or will have: lets
 * routers cache per-channel terms without being fooled by a freed
 * channel whose memory was reused. */
unsigned long long dfle_channel_id(const dfle_channel *ch);

size_t dfle_channel_size(const dfle_channel *ch);  /* number of nodes n */
double dfle_channel_dx(const dfle_channel *ch);    /* [m]               */
const double *dfle_channel_x(const dfle_channel *ch); /* [m], n values  */
const double *dfle_channel_A(const dfle_channel *ch); /* [m^2]          */
const double *dfle_channel_w(const dfle_channel *ch); /* [m]            */

/* How the channel was built: "hack" (dfle_channel_new, A(x) by Hack's
 * law) or "arrays" (dfle_channel_new_from_arrays). */
const char *dfle_channel_kind(const dfle_channel *ch);

/* The parameters (param.h), up to cap of them; returns how many there
 * are.  A "hack" channel lists the options it was built from (dx, A0,
 * hack_coef, hack_exp, k_w, b, A_max, length: A_max and length as asked,
 * so the list rebuilds the same channel); an "arrays" channel only dx,
 * its geometry being the arrays themselves. */
size_t dfle_channel_params(const dfle_channel *ch, dfle_param *out, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
