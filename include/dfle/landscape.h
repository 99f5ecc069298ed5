/*
 * landscape.h - the model on a raster grid: debris-flow and fluvial
 * erosion over a whole drainage network (doc/landscape.md).
 *
 *   dz/dt = U(x, y, t) - E_f - E_df        (channel cells, A >= A_0)
 *   slopes capped at S_c, or linear diffusion  (hillslope cells, A < A_0)
 *
 * A landscape holds elevations on an nx x ny grid (row-major, row 0 at
 * the north, NaN = NoData: outside), routes flow over them with the
 * routing module (drainage.h: D8, flats, depressions through the basin
 * graph) every time step, and erodes the data cells in stack order
 * (Braun and Willett 2013): each cell after its receiver, so a backward-
 * Euler step is one O(n) sweep with no linear system.
 *
 *  - Channel cells (drainage area >= A_0) erode by the fluvial law,
 *    E_f = K A^m S^n (closed form for n = 1, Halley's iteration for n != 1), and
 *    by debris flows.  A channel head (a channel cell none of whose
 *    donors is one) releases a debris flow that travels down the
 *    receivers with the router's rules; where the flows of several heads
 *    meet they combine by the model's rule (model.h, dfle_df_combine).
 *    Debris-flow erosion needs a dfle_model on the network of the data
 *    cells, which the landscape builds and re-shapes after each routing
 *    when it has a router; a cell a flow reaches is solved with the
 *    model's per-node root solve (solver.h, dfle_solver_node_slope).
 *  - Hillslope cells (A < A_0) are not eroded by channel processes: they
 *    rise with uplift until their slope to the receiver reaches S_c
 *    (THRESHOLD), or diffuse (DIFFUSION, implicit).  With THRESHOLD and
 *    cap_channels (the default) S_c caps channel cells too: it is the
 *    steepest slope the material holds, and a channel head steeper than
 *    the hillslopes beside it has no steady state (doc/landscape.md).
 *  - Every root of the routing (a cell that drains off the grid, or the
 *    lowest pit of a region with no way out) is a base level, held at
 *    its elevation.
 *
 * Steady state (doc/landscape.md, "What steady means"): judged on the
 * cells that matter.  A landscape is steady when at most 1 % of its
 * channel cells (1 - channel_quantile) and 5 % of its hillslope cells
 * (1 - hillslope_quantile) have |dz/dt| > tol U, the volume it loses
 * through its base levels balances uplift to tol, and the network holds
 * (no receiver changed at each of the last `stable_steps` routings;
 * a fraction rcv_tol_cycle where the network cycles).  A state that
 * meets that is then checked as a fixed point: verify_steps implicit
 * steps of verify_dt from it must leave the criterion met, or the run
 * does not say converged.
 *
 * One object is used by one thread at a time; the library starts no
 * threads of its own.  Given threads (dfle_landscape_set_par), a step
 * sweeps basins that drain to different base levels on them; elevations,
 * receivers and areas are the same bytes for any number of threads, and
 * so a run gives the same numbers wherever it runs.  Rates in
 * m/yr, lengths in m, areas in m^2, time in yr.
 */
#ifndef DFLE_LANDSCAPE_H
#define DFLE_LANDSCAPE_H

#include <signal.h>
#include <stddef.h>
#include <stdint.h>

#include "dfle/drainage.h"
#include "dfle/error.h"
#include "dfle/fluvial.h"
#include "dfle/law.h"
#include "dfle/model.h"
#include "dfle/par.h"
#include "dfle/router.h"
#include "dfle/record.h"
#include "dfle/solver.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_landscape dfle_landscape;

/* What hillslope cells (A < A_0) do. */
enum dfle_hillslope {
    DFLE_HILLSLOPE_THRESHOLD = 0, /* slope to the receiver capped at S_c (default) */
    DFLE_HILLSLOPE_DIFFUSION = 1, /* dz/dt = U + D lap(z), implicit              */
    DFLE_HILLSLOPE_UPLIFT = 2     /* uplift only (nothing erodes hillslopes)     */
};

/* A quantity in space, and perhaps in time: a number, a raster or a
 * function.  fn fills out[nx * ny] for model time t [yr] (NoData cells
 * are ignored) and returns DFLE_OK or a status with err set; it is
 * called once at the start if varies_in_time is 0, else before every
 * step. */
typedef int (*dfle_landscape_field_fn)(void *ud, double t, double *out, dfle_error *err);
typedef struct dfle_landscape_field {
    double value;                /* everywhere, when grid and fn are NULL */
    const double *grid;          /* nx * ny values, copied                */
    dfle_landscape_field_fn fn;
    void *ud;
    int varies_in_time;
    /* For messages: what the caller calls it (NULL: the C name, "U",
     * "K_scale", "df_scale") and the factor from the values here to the
     * caller's (0: 1), so a bad value is named as it was given. */
    const char *name;
    double show_scale;
} dfle_landscape_field;

/* Every value of a field (a grid, or what fn gives) is checked at every
 * data cell: finite and in range (U > 0, the scales >= 0), or an error
 * naming the cell by row, column and map coordinates. */

typedef struct dfle_landscape_opts {
    size_t nx, ny;               /* columns, rows (>= 1; at least 2 data cells) */
    double dx, dy;               /* cell size [m]                         */
    /* Map coordinates of the grid's north-west corner [m] (messages name
     * cells by them): x0 (0) and y0 (NaN: ny dy, the south edge at 0).
     * Cell centres must stay distinct: |x0|, |y0| below 1e11 cells. */
    double x0, y0;
    const double *z;             /* nx * ny elevations [m], NaN = NoData;
                                  * copied; required                      */
    enum dfle_drainage_edge edge[4]; /* by dfle_drainage_side  (BASE_LEVEL) */
    enum dfle_drainage_edge nodata;  /* NoData border          (OPEN)       */
    const size_t *outlets;       /* cells held at base level, or NULL     */
    size_t n_outlets;
    const dfle_fluvial *fluvial; /* E_f = K A^m S^n; NULL: none (borrowed) */
    dfle_router *router;         /* debris flows; NULL: none (borrowed)    */
    dfle_law *law;               /* required with a router (borrowed)      */
    int df_combine;              /* model.h, enum dfle_df_combine (ANY)    */
    double (*df_frequency)(void *ud, double count, double A);
    void *df_frequency_ud;
    double A0;                   /* channel-head area [m^2], >= 0 and at
                                  * most the area of the data cells (1e4) */
    double k_w, b;               /* channel width w = k_w A^b [m] (0.05, 0.3) */
    int hillslope;               /* enum dfle_hillslope          (THRESHOLD) */
    double S_c;                  /* THRESHOLD: critical slope [-] > 0 (0.8) */
    int cap_channels;            /* THRESHOLD: S_c caps channel cells too (1) */
    double D;                    /* DIFFUSION: diffusivity [m^2/yr] > 0 (0.01) */
    dfle_landscape_field U;      /* uplift [m/yr] > 0             (5e-4)   */
    dfle_landscape_field K_scale;  /* multiplier of K, >= 0         (1)      */
    dfle_landscape_field df_scale; /* multiplier of E_df, >= 0      (1)      */
} dfle_landscape_opts;

void dfle_landscape_opts_default(dfle_landscape_opts *o);

int dfle_landscape_new(const dfle_landscape_opts *opts, dfle_landscape **out, dfle_error *err);
void dfle_landscape_free(dfle_landscape *ls);

size_t dfle_landscape_nx(const dfle_landscape *ls);
size_t dfle_landscape_ny(const dfle_landscape *ls);
double dfle_landscape_dx(const dfle_landscape *ls);
double dfle_landscape_dy(const dfle_landscape *ls);
size_t dfle_landscape_data_cells(const dfle_landscape *ls);
double dfle_landscape_time(const dfle_landscape *ls);   /* [yr] */
/* The elevations [m], nx * ny (NaN = NoData); set_z copies new ones
 * (NoData must stay NoData). */
const double *dfle_landscape_z(const dfle_landscape *ls);
int dfle_landscape_set_z(dfle_landscape *ls, const double *z, dfle_error *err);
const dfle_drainage *dfle_landscape_drainage(const dfle_landscape *ls);
/* The model on the network of the data cells (a router only), else NULL. */
dfle_model *dfle_landscape_model(const dfle_landscape *ls);
/* Threads for its steps (par.h; borrowed, must outlive its use; NULL:
 * none).  With threads, the implicit sweep of a landscape without debris
 * flows runs basin by basin on them; it holds 5 bytes a cell more.  The
 * volumes a step reports are then summed basin chunk by basin chunk:
 * the same for any number of threads, and within the last bits of those
 * without threads. */
int dfle_landscape_set_par(dfle_landscape *ls, const dfle_par *par, dfle_error *err);
/* Bytes held now (grid, routing, model and network, scratch: the
 * elevations before a step once it has stepped, fields in space). */
size_t dfle_landscape_memory(const dfle_landscape *ls);
/* Bytes a landscape of these options with n_data data cells needs at
 * most: what dfle_landscape_memory reports after a run plus what a run
 * holds while it goes (the direct rounds' scratch, the state kept for
 * its checks).  opts->z is not read, nor are the components: only
 * whether there is a router (debris flows) and which fields are grids
 * or functions. */
size_t dfle_landscape_memory_estimate(const dfle_landscape_opts *opts, size_t n_data);
/* The grid of opts checked before anything is allocated (opts->z is
 * not read): its size and cell size, its corner (cell centres must be
 * told apart: DFLE_EINVAL), and its memory: DFLE_ENOMEM, naming the
 * estimate (with `extra` bytes the caller needs beside it, every cell
 * taken as data) and the limit, when that is more than the memory
 * available to this process (physical memory, a cgroup's limit,
 * ulimit -v or -d, whichever is least).  dfle_landscape_new calls it
 * first; a caller that builds z itself calls it before. */
int dfle_landscape_check_grid(const dfle_landscape_opts *opts, size_t extra, dfle_error *err);
/* 1 once the surface has moved by a step or a run, or was set by
 * dfle_landscape_set_z; 0 while it is the start it was built with. */
int dfle_landscape_has_run(const dfle_landscape *ls);

/* Fields, nx * ny values written to out (NaN on NoData), for the
 * current elevations (routed first if they changed). */
enum dfle_landscape_field_id {
    DFLE_LS_Z,        /* elevation [m]                                    */
    DFLE_LS_A,        /* drainage area [m^2]                              */
    DFLE_LS_S,        /* slope to the receiver [-] (0 on base levels)     */
    DFLE_LS_E_F,      /* fluvial erosion [m/yr]                           */
    DFLE_LS_E_DF,     /* debris-flow erosion [m/yr]                       */
    DFLE_LS_REACH,    /* debris flows that go on at the cell [-]          */
    DFLE_LS_CHANNEL,  /* 1 channel, 0 hillslope, 2 channel head           */
    DFLE_LS_DZDT,     /* dz/dt of the last step or evaluation [m/yr]      */
    DFLE_LS_U,        /* uplift [m/yr]                                    */
    DFLE_LS_BASE,     /* 1 where the cell is a base level (a root)        */
    DFLE_LS_NFIELDS
};
int dfle_landscape_field_lookup(const char *name);  /* or -1 */
const char *dfle_landscape_field_name(int field);
const char *dfle_landscape_field_unit(int field);
/* In words, for outputs; the CF standard name where one fits, else NULL. */
const char *dfle_landscape_field_long_name(int field);
const char *dfle_landscape_field_standard_name(int field);
int dfle_landscape_get(dfle_landscape *ls, int field, double *out, dfle_error *err);

/* What the landscape runs, into a record (record.h; landscape_describe.c):
 * section "landscape" (the grid, time, U, the K and k_df scales as
 * values or ranges, A0, k_w, b, the hillslope rule and its S_c or D,
 * edges, NoData border, outlets, combine) and "fluvial", "router",
 * "law" with each component's params ("off" for a process that is). */
void dfle_landscape_describe(const dfle_landscape *ls, dfle_record *rec);

/* --- Runs -------------------------------------------------------------- */

typedef struct dfle_landscape_status {
    double time;        /* years simulated in this run                     */
    double max_time;
    size_t steps;       /* steps (direct: rounds) taken in this run       */
    double dt;          /* last step [yr]                                 */
    /* |dz/dt| / U over the non-base data cells, for the state (the last
     * step's change over its length, or rates evaluated on a fresh
     * routing after a direct round).  The criterion reads the channel
     * and hillslope parts; all cells are for comparison. */
    double q_ratio;     /* all cells: the 0.95 quantile (9 % bins)        */
    double mean_ratio;  /* all cells: mean                                */
    double max_ratio;   /* all cells: max                                 */
    double frac_above;  /* all cells: fraction with |dz/dt| > tol U       */
    double channel_q_ratio;    /* channel cells (A >= A0): the
                                * channel_quantile quantile (9 % bins)  */
    double channel_max_ratio;  /* ... their max                          */
    double channel_frac_above; /* ... fraction with |dz/dt| > tol U      */
    size_t channel_above;      /* ... how many                           */
    double hillslope_q_ratio;  /* hillslope cells: the hillslope_quantile quantile */
    double hillslope_max_ratio;
    double hillslope_frac_above;
    /* The state's volume balance [m^3/yr]: what uplift adds over the
     * non-base data cells, what erosion of every kind removes there (at
     * steady state it all leaves through the base levels), and
     * (outflux - uplift) / uplift. */
    double uplift_flux, outflux, volume_balance;
    size_t rcv_changes; /* cells whose receiver changed at the last routing */
    size_t stable;      /* routings in a row with no receiver change      */
    size_t channel_cells, heads, reached; /* the network and its debris flows */
    /* Volumes of the last step [m^3]: change, uplift, and what fluvial,
     * debris-flow and hillslope processes removed. */
    double dV, V_uplift, V_fluvial, V_df, V_hillslope;
    double fraction;    /* rough completion estimate in [0, 1]            */
    double route_seconds, solve_seconds; /* CPU time of the last step's
                                          * routing and erosion [s]    */
} dfle_landscape_status;

typedef struct dfle_landscape_run_opts {
    int method;          /* solver.h: AUTO (default: DIRECT for steady
                          * states, IMPLICIT for transients), ...      */
    double years;        /* > 0: a transient of this length (no steady stop) */
    /* Steady (doc/landscape.md): |dz/dt| <= tol U ...                 */
    double tol;          /*                                       (1e-3)   */
    double channel_quantile;   /* ... in this fraction of the channel
                                * cells                           (0.99)   */
    double hillslope_quantile; /* ... and of the hillslope cells  (0.95)   */
    /* ... the volume balance within tol, and the network stable for
     * stable_steps routings in a row (5): at most a fraction rcv_tol of
     * the cells changed receiver (0), or rcv_tol_cycle (0.005) once the
     * network is seen to cycle (no new fewest changes for max(30, the
     * grid's width) rounds or steps; the note says so). */
    size_t stable_steps;
    double rcv_tol, rcv_tol_cycle;
    /* The fixed-point check of a state that met the criterion:
     * verify_steps (3; 0: none) implicit steps of verify_dt (1e4 yr)
     * from it, each judged by the criterion but the network's; the run
     * keeps the state it checked. */
    size_t verify_steps;
    double verify_dt;
    double max_time;     /* steady runs: give up after [yr]       (1e7)    */
    size_t max_steps;    /* hard cap on steps (direct: rounds)    (1e6)    */
    double dt;           /* IMPLICIT step [yr] (1000); EXPLICIT: the cap   */
    double cfl;          /* EXPLICIT Courant number               (0.5)    */
    /* Optional: doubts in words (a run that cannot reach `years` in
     * max_steps, a transient stopped short, a steady state without a
     * channel), before the run where they can be known then. */
    void (*warn)(void *ud, const char *msg);
    void *warn_ud;
    /* Called after every step (and once at the start, steps = 0); return
     * nonzero to stop the run (DFLE_ECANCELED).  May read the landscape
     * (fields, z) but not run it. */
    int (*on_step)(void *ud, dfle_landscape *ls, const dfle_landscape_status *st);
    void *on_step_ud;
    /* Progress: every `progress_every` steps (default 16). */
    int (*progress)(void *ud, const dfle_landscape_status *st);
    void *progress_ud;
    size_t progress_every;
    const volatile sig_atomic_t *interrupt; /* stop before the next step */
    /* Records: the steps land exactly on these times [yr since the start
     * of the run, increasing, <= years or max_time], and on_record is
     * called at each (k = 0, 1, ...; a time of 0 is recorded before the
     * first step); nonzero stops the run (DFLE_ECANCELED). */
    size_t n_record;
    const double *record_times;
    int (*on_record)(void *ud, dfle_landscape *ls, size_t k, double t);
    void *on_record_ud;
} dfle_landscape_run_opts;

void dfle_landscape_run_opts_default(dfle_landscape_run_opts *o);

typedef struct dfle_landscape_result {
    int converged;       /* the steady-state criterion was met and the
                          * state passed its fixed-point check         */
    int reason;          /* solver.h enum dfle_stop_reason               */
    int method;          /* the method that produced the result          */
    int fallback;        /* DIRECT did not settle: continued implicitly  */
    size_t direct_rounds; /* with fallback: the direct rounds before      */
    dfle_landscape_status last; /* the state the run ended with        */
    /* The fixed-point check: its steps taken (0: none), whether the last
     * check passed, and the figures of its worst step by channel_frac_above. */
    size_t verify_steps;
    int verified;
    dfle_landscape_status verify;
    double rcv_tol;      /* the network rule the run ended judged by   */
    double dt_min, dt_max;
    size_t routings;
    size_t n_recorded;   /* record times reached                         */
    char note[768];      /* why it stopped, in words                     */
} dfle_landscape_result;

/* Run from the current state: a transient of opts->years, or to steady
 * state.  Reaching max_time or max_steps is not an error: res->converged
 * is 0 and res->note says which part of the criterion was not met. */
int dfle_landscape_run(dfle_landscape *ls, const dfle_landscape_run_opts *opts,
                       dfle_landscape_result *res, dfle_error *err);

/* One backward-Euler step of dt [yr] (route, erode in stack order,
 * hillslopes); st (may be NULL) receives its figures (the quantiles of
 * the runs' defaults). */
int dfle_landscape_step(dfle_landscape *ls, double dt, double tol, dfle_landscape_status *st,
                        dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
