/*
 * flow1d.h - depth-averaged two-phase debris flow on a 1D channel
 * (McGuire et al. 2023, Sect. 2.2, Eqs. 7-10; Iverson and Denlinger 2001).
 *
 * Unknowns per cell: slope-normal depth h [m] and unit discharge
 * q = h v [m^2/s] in a rectangular channel of width w(x) [m], in
 * coordinates along the bed:
 *
 *   d(h)/dt + d(hv)/dx = -(hv/w) dw/dx                                (7)
 *   d(hv)/dt + d(hv^2 + g_z h^2/2)/dx = g_x h
 *       - sgn(v) (1 - lambda) g_z h phi(I) - 2 v eta v_f / (rho h)
 *       - (v^2 h / w) dw/dx                                           (8)
 *   lambda = lambda0 erf(h / sqrt(D t))  (= lambda0 [1 - erfc(2h/sqrt(4Dt))])  (9)
 *   phi(I) = mu_s + (mu_2 - mu_s) / (I0/I + 1),
 *   I = (2|v|/h) D_eff / sqrt(P/rho_s),  P = rho g_z h                 (10)
 *
 * with g_x = g sin(theta), g_z = g cos(theta), theta = atan(S) per cell.
 *
 * Numerics (first order, explicit, as in the paper):
 *  - the volume per unit length w h and w q are the conserved variables,
 *    so volume is conserved to round-off; the width terms of (7)-(8)
 *    then reduce to the wall-pressure source (g_z h^2 / 2) dw/dx;
 *  - HLLC fluxes (Toro 2009) with dry-bed wave speeds;
 *  - a positivity limiter scales a cell's outgoing fluxes so that no
 *    step removes more volume than the cell holds;
 *  - gravity g_x h and the wall pressure explicitly, the viscous drag
 *    implicitly (it is stiff where h -> 0), then Coulomb friction as a
 *    stopping check: friction can stop a cell but never reverse it;
 *  - CFL-limited step; cells thinner than h_dry carry no momentum.
 * Boundaries: a wall at the upstream end; at the downstream end an open
 * outlet that lets material out but never in.
 *
 * Work per step follows the flow, not the grid: a step works only on the
 * wet window, the cells from the first to the last that hold any volume
 * plus one cell on each side (the stencil: a step moves volume by at most
 * one cell).  Outside it depth, discharge and every face flux are exactly
 * zero, so the window changes no result (doc/process-router.md).
 */
#ifndef DFLE_FLOW1D_H
#define DFLE_FLOW1D_H

#include <stddef.h>
#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_flow1d_params {
    double g;       /* gravity [m/s^2]                           (9.81)  */
    double rho;     /* bulk density of the mixture [kg/m^3]      (1800)  */
    double rho_s;   /* sediment density [kg/m^3]                 (2600)  */
    double mu_s;    /* static friction coefficient [-]           (0.384) */
    double mu_2;    /* limiting friction coefficient [-]         (0.62)  */
    double I0;      /* inertial-number scale [-]                 (0.279) */
    double D_eff;   /* grain diameter [m]                        (0.09)  */
    double lambda0; /* initial pore-pressure ratio [-]           (0.9)   */
    double D;       /* pore-pressure diffusivity [m^2/s]         (5e-6)  */
    double eta;     /* pore-fluid viscosity [Pa s]               (60)    */
    double v_f;     /* fluid volume fraction [-]                 (0.5)   */
    double cfl;     /* Courant number, (0, 1]                    (0.5)   */
    double h_dry;   /* depth below which a cell is dry [m]       (1e-6)  */
    int outlet_wall; /* 1: wall at the downstream end (tests)   (0)      */
    int full_domain; /* 1: step every cell, not just the wet window:
                      * the same results, slower; kept to check the
                      * window against (tests, make bench)      (0)      */
} dfle_flow1d_params;

void dfle_flow1d_params_default(dfle_flow1d_params *p);
/* Range checks with messages naming the parameter; `who` prefixes them. */
int dfle_flow1d_params_check(const dfle_flow1d_params *p, const char *who,
                             dfle_error *err);

typedef struct dfle_flow1d dfle_flow1d;

/* ncell cells of length dx [m]; w [m] (> 0) and S (slope tan(theta),
 * any sign) per cell are copied. */
int dfle_flow1d_new(size_t ncell, double dx, const double *w, const double *S,
                    const dfle_flow1d_params *p, dfle_flow1d **out,
                    dfle_error *err);
/* The same with a length per cell: dx[k] [m] (> 0) for cell k, copied
 * (NULL: every cell dx0).  A path down a drainage network has cells of
 * its links' lengths (a grid's diagonals are sqrt 2 longer); the finite
 * volumes hold w dx[k] h and the CFL step takes the shortest cell. */
int dfle_flow1d_new_cells(size_t ncell, const double *dx, double dx0, const double *w,
                          const double *S, const dfle_flow1d_params *p, dfle_flow1d **out,
                          dfle_error *err);
void dfle_flow1d_free(dfle_flow1d *f);

/* The state, writable: depth h [m] and unit discharge q [m^2/s].
 * Asking for either opens the window to the whole grid (the next step
 * works on every cell, then narrows it again), so write the state
 * between this call and the next step; a pointer kept across steps is
 * for reading (ask again to write again). */
double *dfle_flow1d_h(dfle_flow1d *f);
double *dfle_flow1d_q(dfle_flow1d *f);
/* The same, to read: the window stays as it is. */
const double *dfle_flow1d_depth(const dfle_flow1d *f);
const double *dfle_flow1d_discharge(const dfle_flow1d *f);
size_t dfle_flow1d_size(const dfle_flow1d *f);

/* The wet window: cells [*k0, *k1) that the last step worked on (the
 * whole grid before the first step and after dfle_flow1d_h/q).  Outside
 * it h = q = 0, and no face outside faces k0..k1 moved volume. */
void dfle_flow1d_window(const dfle_flow1d *f, size_t *k0, size_t *k1);

/* Pore-pressure ratio at depth h, `t` seconds after the flow entered
 * the domain (t < 0: not yet entered, lambda0). */
double dfle_flow1d_lambda(const dfle_flow1d *f, double h, double t);
/* The same in two parts, for many depths at one time: the diffusion
 * length L = sqrt(D t) [m] of Eq. (9) (0 when lambda stays lambda0: not
 * yet entered, or D = 0), then lambda0 erf(h / L).  Bit for bit
 * dfle_flow1d_lambda(f, h, t). */
double dfle_flow1d_pore_length(const dfle_flow1d *f, double t);
double dfle_flow1d_lambda_at(const dfle_flow1d *f, double h, double L);
/* Friction coefficient phi(I) at depth h [m], speed |v| [m/s], cell k. */
double dfle_flow1d_phi(const dfle_flow1d *f, size_t k, double h, double v);
/* A bound no value of dfle_flow1d_phi exceeds (mu_2, rounded up). */
double dfle_flow1d_phi_max(const dfle_flow1d *f);

/* The CFL time step of the current state [s] (+Inf when all is dry). */
double dfle_flow1d_stable_dt(const dfle_flow1d *f);

/* One step of length dt [s] (at most the stable step); t_entry is the
 * time [s] since the flow entered the domain (for lambda, Eq. 9).
 * *outflow receives the volume [m^3] that left through the outlet. */
int dfle_flow1d_step(dfle_flow1d *f, double dt, double t_entry,
                     double *outflow, dfle_error *err);

/* Volume in cells [k0, k1) [m^3]: sum of w h dx. */
double dfle_flow1d_volume(const dfle_flow1d *f, size_t k0, size_t k1);

/* Volume [m^3] that crossed the face between cells k-1 and k during the
 * last step (positive downstream); k in [1, ncell]. */
double dfle_flow1d_face_volume(const dfle_flow1d *f, size_t k);
/* All of them: ncell + 1 values, face k at [k] (face 0 the upstream
 * wall, face ncell the outlet); valid until the next step. */
const double *dfle_flow1d_face_volumes(const dfle_flow1d *f);

#ifdef __cplusplus
}
#endif
#endif
