/*
 * landscape_internal.h - the landscape object, shared by the files of
 * src/landscape/ (not installed):
 *   landscape.c        the object, its fields in space, routing and the
 *                      network of the debris-flow model, output fields;
 *   landscape_step.c   one step: backward Euler in stack order (the
 *                      fluvial closed form / Newton, debris-flow cells
 *                      through the model's root solve), explicit steps,
 *                      hillslopes (threshold, implicit diffusion);
 *   landscape_direct.c one round of the direct steady state (channels
 *                      from the heads down, threshold hillslopes as the
 *                      lowest caps over the channels);
 *   landscape_steady.c what steady means: |dz/dt|/U on channel and
 *                      hillslope cells, the volume balance, the
 *                      criterion in words, the fixed-point check;
 *   landscape_run.c    runs: the options, time steps weighed against
 *                      the time asked, the solvers' stepping loop for
 *                      implicit and explicit steps, the direct rounds;
 *   landscape_memory.c what a grid needs and what the process may have.
 *
 * Memory per cell is the constraint (a 2000^2 grid is 4e6 cells): the
 * state is z (8 bytes), the receivers of the last routing (4, to count
 * changes) and dz/dt as a float (4), besides the routing's own arrays.
 * Fields in space cost 8 bytes a cell only when they are not uniform;
 * the debris-flow model and its network exist only with a router.
 */
#ifndef DFLE_LANDSCAPE_INTERNAL_H
#define DFLE_LANDSCAPE_INTERNAL_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "dfle/landscape.h"
#include "dfle/network.h"
#include "dfle/par.h"

#define LS_NONE UINT32_MAX

/* Receivers are chosen with this hysteresis (drainage.h): a cell keeps
 * the receiver of the last routing while its slope is within this
 * relative margin of the steepest.  Exact ties are common on a
 * landscape (hillslopes at S_c are planes, built by sums of S_c L in
 * different orders), and D8 broke them by round-off, differently at
 * every routing: a steady landscape then kept "changing" hundreds of
 * receivers a step without any change in elevation or area.  Slopes
 * that differ by more than round-off (1e-9 relative) choose as plain
 * D8 does. */
#define LS_TIE_MARGIN 1e-9

/* Widths w = k_w A^b are tabled for areas of up to this many cells. */
#define LS_W_TABLE 4096

/* x^p for one fixed exponent p, faster than pow (the
 * implicit fluvial sweep calls it about three times a cell for n != 1):
 * x = 2^e m with m in [1, 2), m = m_k (1 + delta), m_k the centre of
 * one of LS_POW_M slices of [1, 2) (|delta| < 1 / (2 LS_POW_M)), so
 *   x^p = (2^e)^p  m_k^p  (1 + delta)^p,
 * the first two from tables made with pow, the last a binomial series
 * to delta^5 (the next term is below 1e-16 for p <= 6).  A few ulps
 * from pow's value in about a third of its time; x outside
 * 2^-LS_POW_E .. 2^LS_POW_E (or not a positive normal number) goes to
 * pow. */
#define LS_POW_BITS 8
#define LS_POW_M (1 << LS_POW_BITS)
#define LS_POW_E 64
typedef struct ls_pow {
    double p;
    int table;                      /* 0: p > 6, where the series would not
                                       do: every call goes to pow        */
    double two_e[2 * LS_POW_E + 1]; /* (2^e)^p, e = -LS_POW_E .. LS_POW_E */
    double m_p[LS_POW_M];           /* m_k^p                              */
    double inv_m[LS_POW_M];         /* 1 / m_k                            */
    double c[6];                    /* binomial coefficients C(p, j)      */
} ls_pow;

void ls_pow_init(ls_pow *t, double p);

static inline double ls_pow_eval(const ls_pow *t, double x)
{
    uint64_t bits, mbits;
    double m, d;
    int e;
    unsigned k;
    memcpy(&bits, &x, sizeof bits);
    e = (int)(bits >> 52) - 1023; /* x > 0: no sign bit */
    if (!t->table || !(x > 0) || e < -LS_POW_E || e > LS_POW_E)
        return pow(x, t->p); /* also NaN, infinity, subnormals */
    k = (unsigned)(bits >> (52 - LS_POW_BITS)) & (LS_POW_M - 1);
    mbits = (bits & 0x000FFFFFFFFFFFFFull) | 0x3FF0000000000000ull;
    memcpy(&m, &mbits, sizeof m);
    d = (m - (1.0 + (k + 0.5) / LS_POW_M)) * t->inv_m[k];
    d = t->c[0] + d * (t->c[1] + d * (t->c[2] + d * (t->c[3] + d * (t->c[4] + d * t->c[5]))));
    return t->two_e[e + LS_POW_E] * t->m_p[k] * d;
}

/* A field in space (and time): value, or grid (owned) filled by fn. */
typedef struct ls_field {
    double value;
    double *grid;              /* n cells, or NULL: uniform */
    dfle_landscape_field_fn fn;
    void *ud;
    int varies;
    const char *name;          /* for messages: "U", "K_scale", ... */
    double show_scale;         /* messages show value * show_scale  */
    double lo;                 /* values must be >= lo (U: > 0)     */
    int strict;                /* 1: > lo                            */
} ls_field;

/* How a state is judged (doc/landscape.md, "What steady means"). */
typedef struct ls_judge {
    double tol;                /* |dz/dt| <= tol U                  */
    double channel_quantile;   /* ... on this fraction of channel cells */
    double hillslope_quantile; /* ... and of hillslope cells        */
} ls_judge;

/* The basins are shared among this many chunks for sweeps on threads
 * (landscape_par.c): a number of the grid's, not of the threads, so
 * that the volumes, summed chunk by chunk in order, are the same for
 * any number of threads. */
#define LS_PAR_CHUNKS 64

/* Routings whose receivers are remembered (by a hash) to tell a
 * network that cycles from one that still settles. */
#define LS_RCV_HISTORY 8

static inline double ls_value(const ls_field *f, size_t c)
{
    return f->grid != NULL ? f->grid[c] : f->value;
}

struct dfle_landscape {
    dfle_landscape_opts o;     /* scalars; component pointers borrowed */
    size_t nx, ny, n, n_data;
    double cell_area;          /* dx dy [m^2]                           */
    double len[8];             /* distance to neighbour k [m]           */
    double time;               /* [yr]                                  */

    double *z;                 /* n: elevations, NaN = NoData           */
    double *z_undo;            /* n: z before the step under way (made on
                                * the first step; a step that leaves no
                                * surface is undone from it)            */
    dfle_drainage *dr;
    int routed;                /* the routing matches z                 */
    uint32_t *rcv_prev;        /* receivers of the previous routing     */
    size_t rcv_changes, stable, routings;
    /* Direct rounds with a router routed rarely (landscape_direct.c):
     * the damping of the slopes' update (0: the rounds begin) and the
     * last round's largest relative change. */
    double df_omega, df_change_prev;
    double rcv_tol;            /* the run's: changes a stable routing allows */
    uint64_t rcv_hash[LS_RCV_HISTORY]; /* of the last routings' receivers */
    size_t rcv_hashes;         /* how many of them are set               */
    int rcv_repeat;            /* the last routing changed receivers back
                                * to those of one of the last few: the
                                * network cycles                        */
    int evolved;               /* dfle_landscape_has_run                */
    float *dzdt;               /* n: dz/dt of the last step [m/yr]      */
    int have_rates;            /* dzdt holds something                  */

    ls_field U, K_scale, df_scale;
    double K, m_exp, n_exp;    /* the fluvial law (K = 0: none)         */
    ls_pow pow_n, pow_inv_n;   /* x^n and x^(1/n) (n != 1)             */

    /* Debris flows (a router): the model on the data cells. */
    dfle_network *net;
    dfle_model *model;
    uint32_t *node_of;         /* n: cell -> node (LS_NONE on NoData)   */
    uint32_t *cell_of;         /* n_data: node -> cell                  */
    double *s_Ks, *s_dfs;      /* n_data: the scales by node, or NULL   */
    double *w_table;           /* k_w (j dx dy)^b for j < n_w cells     */
    size_t n_w;
    int model_z_current;       /* the model's z and flow match ours     */
    int shape_current;         /* the model's network is that of the
                                * receivers in rcv_prev: a routing that
                                * changes none need not re-shape it     */
    size_t channel_cells, heads;

    /* Threads (dfle_landscape_set_par; NULL: none): the stack by chunk
     * of basins, par_off[j] .. par_off[j + 1] the cells of chunk j in
     * stack order, and each cell's chunk (made on the first step). */
    const dfle_par *par;
    uint32_t *par_stack;       /* n_data                                */
    unsigned char *par_chunk;  /* n                                     */
    size_t par_off[LS_PAR_CHUNKS + 1];
};

/* landscape.c */
/* Route z if it changed since the last routing; count receiver changes;
 * give the debris-flow model the new network. */
int ls_route(dfle_landscape *ls, dfle_error *err);
/* "row r, column c (x = .. m, y = .. m)" of cell c, for messages. */
void ls_cell_name(const dfle_landscape *ls, size_t c, char *buf, size_t cap);
/* The map coordinates of cell c's centre [m]. */
void ls_cell_centre(const dfle_landscape *ls, size_t c, double *x, double *y);
/* Fields in time: refresh those that vary for the landscape's time. */
int ls_update_fields(dfle_landscape *ls, int first, dfle_error *err);
/* Copy z into the model and evaluate it (routes the debris flows). */
int ls_model_evaluate(dfle_landscape *ls, dfle_error *err);
/* Copy z into the model and route the debris flows only (what the
 * implicit step reads): S and reach by node (dfle_model_route). */
int ls_model_route(dfle_landscape *ls, const double **S, const double **reach, dfle_error *err);
/* The debris flows that go on at cell c (0 without a router). */
double ls_reach(const dfle_landscape *ls, size_t c);
/* E_f [m/yr] at cell c for slope S. */
double ls_fluvial_rate(const dfle_landscape *ls, size_t c, double A, double S);

/* landscape_step.c */
/* Evaluated dz/dt of the current state into ls->dzdt (explicit
 * rates; the residual the direct method is judged by); fills the
 * status's ratios. */
int ls_evaluate_rates(dfle_landscape *ls, const ls_judge *j, dfle_landscape_status *st,
                      dfle_error *err);
/* One explicit step of at most dt_cap (CFL); *dt receives its length. */
int ls_explicit_step(dfle_landscape *ls, double dt_cap, double cfl, const ls_judge *j,
                     double *dt, dfle_landscape_status *st, dfle_error *err);
/* Hillslope diffusion, implicit: (z' - z)/dt = D lap(z') on hillslope
 * cells with channel and base cells held; dt = INFINITY solves the
 * steady state D lap(z) = -U with those cells fixed. */
int ls_diffuse(dfle_landscape *ls, double dt, dfle_error *err);
/* D lap(z) at data cell c [m/yr], the stencil ls_diffuse solves with. */
double ls_laplacian(const dfle_landscape *ls, size_t c);
/* One backward-Euler sweep as dfle_landscape_step, judged by j. */
int ls_implicit_step(dfle_landscape *ls, double dt, const ls_judge *j,
                     dfle_landscape_status *st, dfle_error *err);
/* DFLE_EINVAL naming `what` (a step, "dt", or "the explicit (CFL)
 * step") when U dt is below what z resolves: nothing would move (a
 * transient), or |dz/dt| could not be told from tol U (tol > 0). */
int ls_check_step(const dfle_landscape *ls, double dt, double tol, const char *what,
                  dfle_error *err);
/* The steady state of the current network, node by node (direct). */
int ls_direct_round(dfle_landscape *ls, dfle_error *err);

/* landscape_steady.c */
/* The status's ratios (all, channel, hillslope cells) and volume
 * balance from ls->dzdt, on the current routing's channel mask. */
void ls_ratios(const dfle_landscape *ls, const ls_judge *j, dfle_landscape_status *st);
/* 1 when the rates and the volume balance meet the criterion (the
 * network is the caller's to judge). */
int ls_rates_met(const ls_judge *j, const dfle_landscape_status *st);
/* Why a state is not steady, in words (stable_steps: what the network
 * needed; 0 leaves the network out). */
void ls_explain(const ls_judge *j, const dfle_landscape_status *st, size_t stable_steps,
                double rcv_tol, char *buf, size_t cap);
/* The state a fixed-point check starts from, kept to go back to. */
typedef struct ls_saved {
    double *z;
    uint32_t *rcv_prev;
    float *dzdt;
    unsigned char *dir;        /* the routing's, for its hysteresis */
} ls_saved;
void ls_saved_free(ls_saved *sv);
/* The fixed-point check: `steps` implicit steps of dt [yr] from the
 * current state, each judged by j (the rates and the volume balance);
 * *passed says whether all met it, *worst has the figures of the step
 * with the most channel cells above tol U, *taken how many steps were
 * taken (it stops at the first that fails).  The state is then put back
 * as it was (z, routing, rates). */
int ls_verify(dfle_landscape *ls, const ls_judge *j, size_t steps, double dt, ls_saved *sv,
              int *passed, size_t *taken, dfle_landscape_status *worst, dfle_error *err);

/* landscape_par.c */
/* The stack of the current routing by chunk of basins (ls->par_stack,
 * ls->par_off): every cell in the chunk of its root, in stack order. */
int ls_par_partition(dfle_landscape *ls, dfle_error *err);
/* Bytes of that for n cells (0 without threads). */
size_t ls_par_bytes(const dfle_landscape *ls);

/* landscape_memory.c */
/* Bytes of the debris-flow model (every array its implicit and direct
 * runs make), its network and the landscape's shape scratch for n cells, n_data of
 * them data; of the network and the scratch alone. */
double ls_model_bytes(size_t n, size_t n_data);
double ls_network_bytes(size_t n, size_t n_data);
/* Bytes this process can still have: the least of the memory available
 * (MemAvailable), a cgroup's limit less its use, and ulimit -v and -d
 * less what the process holds; which one, in words, into what.
 * SIZE_MAX when nothing is known. */
size_t ls_memory_available(char *what, size_t cap);

#endif
