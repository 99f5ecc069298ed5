/*
 * landscape_step.c - how the landscape's surface moves: one backward-
 * Euler step in stack order and one explicit step (hillslope diffusion
 * is in landscape_diffuse.c, the direct steady state in
 * landscape_direct.c).
 *
 * Backward Euler (Braun and Willett 2013).  The stack lists every data
 * cell after its receiver, so when cell i is reached its receiver r
 * already has its new elevation and the cell's own equation,
 *   z_i' = z_i + dt (U - K A^m ((z_i' - z_r')/L)^n),
 * is one scalar equation.  With d = z_i' - z_r', d0 = z_i + U dt - z_r'
 * and F = K A^m dt / L^n it reads d + F d^n = d0:
 *   n = 1:  d = d0 / (1 + F), exactly;
 *   n != 1: Halley's iteration from min(d0, (d0/F)^(1/n)), an upper
 *           bound of the root, kept inside the bracket (0, d0), so it
 *           converges for any n > 0 (halley_step below).
 * d0 <= 0 (a cell below its receiver after uplift: along a path carved
 * through a depression) means no erosion: the cell rises with U, as the
 * model does for S <= 0.  A cell a debris flow reaches is solved by the
 * model's per-node root solve (solver.h), E = E_f + E_df; the flows are
 * those routed at the start of the step (lagged one step, as the 1D
 * implicit solver lags the runout).  Hillslope cells rise with U and are
 * capped at S_c above their receiver (THRESHOLD; channel cells too with
 * cap_channels, the excess counted as hillslope volume), or diffuse
 * after the sweep (DIFFUSION).  O(n), no linear system, no stability
 * limit.
 */
#include "landscape/landscape_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Iterations ahead that the sweep prefetches (see ls_implicit_step). */
#define LS_AHEAD 8
#if defined(__GNUC__) || defined(__clang__)
#define LS_PREFETCH(p) __builtin_prefetch(p)
#else
#define LS_PREFETCH(p) ((void)(p))
#endif

static double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void ls_pow_init(ls_pow *t, double p)
{
    t->p = p;
    t->table = p > 0 && p <= 6;
    for (int e = -LS_POW_E; e <= LS_POW_E; e++)
        t->two_e[e + LS_POW_E] = pow(ldexp(1.0, e), p); /* 2^e exact */
    for (int k = 0; k < LS_POW_M; k++) {
        double m = 1.0 + (k + 0.5) / LS_POW_M;
        t->m_p[k] = pow(m, p);
        t->inv_m[k] = 1.0 / m;
    }
    t->c[0] = 1.0;
    for (int j = 1; j < 6; j++)
        t->c[j] = t->c[j - 1] * (p - (j - 1)) / j;
}

/* d + F d^n = d0 for 0 < d < d0 (see the file comment): Halley's
 * iteration, cubic, one power a step for f, f' and f'', kept inside the
 * bracket.  It starts at the upper bound u = (d0/F)^(1/n), where
 * F u^n = d0 needs no power, when u < d0, else at d0 (erosion there,
 * F d0^n, is then at most d0 and the root within a factor 2 of d0).
 * The powers are ls_pow's tables: a few ulps, where the root needs the
 * residual to about 1e-15. */
/* Where Halley's iteration on d + F d^n = d0 starts: d, with Fd = F d^n. */
static inline void halley_start(double d0, double F, const ls_pow *pn, const ls_pow *pinv,
                                double *d, double *Fd)
{
    *d = ls_pow_eval(pinv, d0 / F);
    *Fd = d0;
    if (!(*d < d0)) {
        *d = d0;
        *Fd = F * ls_pow_eval(pn, d0);
    }
}

/* One step of it from d (Fd = F d^n) within [lo, hi]; 1, with the root
 * in *root, once the step is small enough. */
static inline int halley_step(double d0, double F, const ls_pow *pn, double *d, double *Fd,
                              double *lo, double *hi, double *root)
{
    const double n = pn->p, nn1 = n * (n - 1.0);
    /* Halley's step 2 f f' / (2 f'^2 - f f'') with f' = g / d, g = d + n F d^n,
     * and f'' = n (n - 1) F d^n / d^2, multiplied through by d^2: one
     * division. */
    const double f = *d + *Fd - d0, g = *d + n * *Fd;
    const double step = 2.0 * f * g * *d / (2.0 * g * g - f * nn1 * *Fd);
    double next = *d - step;
    /* Cubic convergence: the relative error after a step of
     * relative size s is about n^2 s^3, so s <= 1e-5 leaves ~5e-15,
     * the powers' own accuracy, and below the round-off of z = z_r + d
     * wherever z >= 50 d (tested before the bracket, which round-off
     * at the root can leave on either side). */
    if (fabs(step) <= 1e-5 * *d) {
        *root = next;
        return 1;
    }
    if (f > 0)
        *hi = *d;
    else
        *lo = *d;
    if (!(next > *lo && next < *hi))
        next = 0.5 * (*lo + *hi);
    *d = next;
    *Fd = F * ls_pow_eval(pn, next);
    return 0;
}

static double fluvial_delta(double d0, double F, const ls_pow *pn, const ls_pow *pinv)
{
    double lo = 0.0, hi = d0, d, Fd, root;
    halley_start(d0, F, pn, pinv, &d, &Fd);
    for (int it = 0; it < 100; it++)
        if (halley_step(d0, F, pn, &d, &Fd, &lo, &hi, &root))
            return root;
    return d;
}

/* Two equations at once, each solved exactly as alone: independent, they
 * interleave, and the processor overlaps their chains of dependent
 * operations. */
static void fluvial_delta2(const double *d0, const double *F, const ls_pow *pn,
                           const ls_pow *pinv, double *root)
{
    double lo0 = 0.0, hi0 = d0[0], d_0, Fd0, lo1 = 0.0, hi1 = d0[1], d_1, Fd1;
    int done0 = 0, done1 = 0;
    halley_start(d0[0], F[0], pn, pinv, &d_0, &Fd0);
    halley_start(d0[1], F[1], pn, pinv, &d_1, &Fd1);
    for (int it = 0; it < 100 && !(done0 && done1); it++) {
        if (!done0)
            done0 = halley_step(d0[0], F[0], pn, &d_0, &Fd0, &lo0, &hi0, &root[0]);
        if (!done1)
            done1 = halley_step(d0[1], F[1], pn, &d_1, &Fd1, &lo1, &hi1, &root[1]);
    }
    if (!done0)
        root[0] = d_0;
    if (!done1)
        root[1] = d_1;
}

static void status_network(const dfle_landscape *ls, dfle_landscape_status *st)
{
    st->rcv_changes = ls->rcv_changes;
    st->stable = ls->stable;
    st->channel_cells = ls->channel_cells;
    st->heads = ls->model != NULL ? ls->heads : 0;
}

/* A step that failed part-way: the surface as it was, nothing
 * evaluated. */
static int step_undone(dfle_landscape *ls, const double *z_before, int status)
{
    memcpy(ls->z, z_before, ls->n * sizeof *ls->z);
    ls->routed = 0;
    ls->model_z_current = 0;
    ls->have_rates = 0;
    return status;
}

/* The surface before a step, kept in the landscape (so that nothing
 * leaks if a callback raises through the step), to undo a step that
 * leaves no surface. */
static int keep_surface(dfle_landscape *ls, dfle_error *err)
{
    if (ls->z_undo == NULL && (ls->z_undo = malloc(ls->n * sizeof *ls->z_undo)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory for a step of %zu cells",
                              ls->n);
    memcpy(ls->z_undo, ls->z, ls->n * sizeof *ls->z);
    return DFLE_OK;
}

/* Everything a step produced is checked: a step of 1e300 yr, or a U of
 * 1e300 m/yr, overflowed the volumes and made the diffusion solve NaN,
 * and the step "succeeded" with a surface that was none.  `vol` holds
 * the step's volumes [m] (uplift, fluvial, debris flows, hillslope,
 * change). */
static int check_surface(dfle_landscape *ls, double dt, const double vol[5], double VU,
                         double Vh, dfle_error *err)
{
    size_t finite = 0;
    int vol_ok = 1;
    for (size_t c = 0; c < ls->n; c++)
        finite += isfinite(ls->z[c]) != 0;
    for (int k = 0; k < 5; k++) /* each as reported: times the cell area */
        vol_ok &= isfinite(vol[k] * ls->cell_area) != 0;
    if (finite == ls->n_data && vol_ok)
        return DFLE_OK;
    dfle_error_set(err, DFLE_EINVAL, "landscape: a step of dt = %g yr gave %s (uplift volume %g "
                   "m^3, hillslope %g m^3); it was undone: take shorter steps, or check U", dt,
                   finite != ls->n_data ? "elevations that are not finite"
                                        : "volumes that are not finite",
                   VU * ls->cell_area, Vh * ls->cell_area);
    return step_undone(ls, ls->z_undo, DFLE_EINVAL);
}

/* What the backward-Euler sweep carries from cell to cell. */
typedef struct ls_sweep {
    dfle_landscape *ls;
    const uint32_t *rcv, *stack;
    const unsigned char *dir;
    const double *A;
    size_t n_stack;
    double dt, A0, K, mexp, Sc, Ln[8];
    int hill, sqrt_m, n_one, cap_ch;
    double VU, Vf, Vh, dV; /* volumes so far [m] */
} ls_sweep;

/* A cell between its set-up and the end of its step. */
typedef struct ls_cell {
    size_t c, r;
    double z0, U, L, zn; /* zn: the new elevation as it stands */
    double d0, F;        /* the stream power equation d + F d^n = d0 */
    int channel, solve;  /* solve: that equation is to be solved   */
} ls_cell;

/* The sweep visits the grid in no spatial order: fetch the cells of
 * coming iterations ahead, in two stages (the receiver's elevation
 * needs the receiver), or it waits on memory.  A macro: GCC takes a
 * function that only prefetches for one without effects, and drops it. */
#define SWEEP_FETCH(k)                                                                    \
    do {                                                                                  \
        if ((k) + 2 * LS_AHEAD < n_stack) {                                               \
            const size_t c2_ = stack[(k) + 2 * LS_AHEAD], c1_ = stack[(k) + LS_AHEAD];    \
            LS_PREFETCH(&rcv[c2_]);                                                       \
            LS_PREFETCH(&z[c2_]);                                                         \
            LS_PREFETCH(&A[c2_]);                                                         \
            LS_PREFETCH(&dir[c2_]);                                                       \
            LS_PREFETCH(&z[rcv[c1_]]);                                                    \
        }                                                                                 \
    } while (0)

/* Cell c (receiver r != c) uplifted. */
static inline void cell_begin(const ls_sweep *w, const double *z, size_t c, size_t r, ls_cell *x)
{
    x->c = c;
    x->r = r;
    x->z0 = z[c];
    x->U = ls_value(&w->ls->U, c);
    x->L = w->ls->len[w->dir[c]];
    x->zn = x->z0 + x->U * w->dt;
    x->channel = w->A[c] >= w->A0;
    x->d0 = x->F = 0.0;
    x->solve = 0;
}

/* A channel cell's stream power equation; with n = 1 it is solved at
 * once. */
static inline void cell_stream_power(ls_sweep *w, const double *z, ls_cell *x)
{
    const double Am = w->sqrt_m ? sqrt(w->A[x->c]) : pow(w->A[x->c], w->mexp);
    x->d0 = x->zn - z[x->r];
    x->F = w->K * ls_value(&w->ls->K_scale, x->c) * Am * w->dt / w->Ln[w->dir[x->c]];
    x->solve = x->d0 > 0 && x->F > 0;
    if (x->solve && w->n_one) {
        const double d = x->d0 / (1.0 + x->F);
        x->zn = z[x->r] + d;
        w->Vf += x->d0 - d;
        x->solve = 0;
    }
}

/* The root d of the cell's equation found. */
static inline void cell_eroded(ls_sweep *w, const double *z, ls_cell *x, double d)
{
    x->zn = z[x->r] + d;
    w->Vf += x->d0 - d;
}

/* The threshold caps, and the cell's new elevation in place. */
static inline void cell_end(ls_sweep *w, double *z, const ls_cell *x)
{
    double zn = x->zn;
    const double cap = z[x->r] + w->Sc * x->L;
    if (x->channel ? w->cap_ch && zn > cap : w->hill == DFLE_HILLSLOPE_THRESHOLD && zn > cap) {
        w->Vh += zn - cap; /* S_c caps channels too with cap_channels */
        zn = cap;
    }
    z[x->c] = zn;
    w->ls->dzdt[x->c] = (float)((zn - x->z0) / w->dt);
    w->VU += x->U * w->dt;
    w->dV += zn - x->z0;
}

/* Cells a debris flow reaches, on the flow just evaluated. */
static size_t count_reached(const dfle_landscape *ls)
{
    size_t k = 0;
    if (ls->model != NULL)
        for (size_t c = 0; c < ls->n; c++)
            k += !isnan(ls->z[c]) && ls_reach(ls, c) > 0;
    return k;
}

/* The sweep over stack[0 .. n_stack): every cell after its receiver.
 * Volumes go to w, those of debris flows to *Vdf. */
static int sweep_cells(ls_sweep *w, const uint32_t *stack, size_t n_stack, const double *Sm,
                       const double *reach, double *Vdf, size_t *reached, dfle_error *err)
{
    dfle_landscape *ls = w->ls;
    const uint32_t *rcv = w->rcv;
    const unsigned char *dir = w->dir;
    const double *A = w->A;
    const double K = w->K, dt = w->dt;
    double *z = ls->z;
    /* Without debris flows every cell is plain stream power or hillslope */
    const int pairs = ls->model == NULL && !w->n_one;
    int st_ = DFLE_OK;

    for (size_t k = 0; k < n_stack;) {
        const size_t c = stack[k], r = rcv[c];
        ls_cell x;
        SWEEP_FETCH(k);
        if (r == c) {
            ls->dzdt[c] = 0.0f;
            k++;
            continue;
        }
        /* Two cells in a row, the second not draining to the first: no
         * debris flows, so their equations are solved together. */
        if (pairs && k + 1 < n_stack) {
            const size_t c2 = stack[k + 1], r2 = rcv[c2];
            if (r2 != c2 && r2 != c) {
                ls_cell y;
                SWEEP_FETCH(k + 1);
                cell_begin(w, z, c, r, &x);
                cell_begin(w, z, c2, r2, &y);
                if (x.channel && K > 0)
                    cell_stream_power(w, z, &x);
                if (y.channel && K > 0)
                    cell_stream_power(w, z, &y);
                if (x.solve && y.solve) {
                    const double d0[2] = {x.d0, y.d0}, F[2] = {x.F, y.F};
                    double d[2];
                    fluvial_delta2(d0, F, &w->ls->pow_n, &w->ls->pow_inv_n, d);
                    cell_eroded(w, z, &x, d[0]);
                    cell_eroded(w, z, &y, d[1]);
                } else if (x.solve) {
                    cell_eroded(w, z, &x, fluvial_delta(x.d0, x.F, &w->ls->pow_n, &w->ls->pow_inv_n));
                } else if (y.solve) {
                    cell_eroded(w, z, &y, fluvial_delta(y.d0, y.F, &w->ls->pow_n, &w->ls->pow_inv_n));
                }
                cell_end(w, z, &x);
                cell_end(w, z, &y);
                k += 2;
                continue;
            }
        }
        cell_begin(w, z, c, r, &x);
        if (x.channel) {
            const double flows = reach != NULL ? reach[ls->node_of[c]] : 0.0;
            if (flows > 0) {
                const size_t node = ls->node_of[c];
                const double uz = x.zn;
                double S, Ef;
                st_ = dfle_solver_node_slope(ls->model, node, x.U + (x.z0 - z[r]) / dt, x.L / dt,
                                             flows, Sm[node], &S, NULL, err);
                if (st_ != DFLE_OK)
                    return st_;
                x.zn = z[r] + S * x.L;
                Ef = ls_fluvial_rate(ls, c, A[c], S) * dt;
                w->Vf += Ef;
                *Vdf += uz - x.zn - Ef;
                (*reached)++;
            } else if (K > 0) {
                cell_stream_power(w, z, &x);
                if (x.solve)
                    cell_eroded(w, z, &x, fluvial_delta(x.d0, x.F, &w->ls->pow_n, &w->ls->pow_inv_n));
            }
        }
        cell_end(w, z, &x);
        k++;
    }
    return st_;
}

/* One chunk of the basins (landscape_par.c) on a thread of its own, its
 * volumes kept apart to be added in chunk order. */
typedef struct sweep_chunks {
    const ls_sweep *w;
    ls_sweep part[LS_PAR_CHUNKS];
} sweep_chunks;

static void sweep_chunk(void *arg, size_t j)
{
    sweep_chunks *sc = arg;
    const dfle_landscape *ls = sc->w->ls;
    ls_sweep w = *sc->w; /* a copy of its own: no cache line shared */
    double Vdf = 0;
    size_t reached = 0;
    w.VU = w.Vf = w.Vh = w.dV = 0.0;
    (void)sweep_cells(&w, ls->par_stack + ls->par_off[j], ls->par_off[j + 1] - ls->par_off[j],
                      NULL, NULL, &Vdf, &reached, NULL);
    sc->part[j] = w;
}

int ls_implicit_step(dfle_landscape *ls, double dt, const ls_judge *j,
                     dfle_landscape_status *st, dfle_error *err)
{
    const uint32_t *rcv, *stack;
    const unsigned char *dir;
    const double *A, *Sm = NULL, *reach = NULL; /* by node */
    const double A0 = ls->o.A0, K = ls->K, mexp = ls->m_exp, nexp = ls->n_exp;
    const double Sc = ls->o.S_c, ca = ls->cell_area;
    const int hill = ls->o.hillslope, n_one = nexp == 1.0;
    double *z = ls->z;
    double VU = 0, Vf = 0, Vdf = 0, Vh = 0, dV = 0;
    size_t n_stack, reached = 0;
    int st_ = DFLE_OK;
    double t0 = cpu_seconds(), t1;
    ls_sweep w;
    double *z_before;

    for (int d = 0; d < 8; d++) /* L^n by direction */
        w.Ln[d] = n_one ? ls->len[d] : pow(ls->len[d], nexp);
    if ((st_ = ls_route(ls, err)) != DFLE_OK)
        return st_;
    if ((st_ = keep_surface(ls, err)) != DFLE_OK)
        return st_;
    z_before = ls->z_undo;
    t1 = cpu_seconds();
    if (ls->model != NULL && (st_ = ls_model_route(ls, &Sm, &reach, err)) != DFLE_OK)
        return st_;
    rcv = dfle_drainage_receivers(ls->dr);
    dir = dfle_drainage_dir(ls->dr);
    A = dfle_drainage_area(ls->dr);
    stack = dfle_drainage_stack(ls->dr, &n_stack);
    w.ls = ls;
    w.rcv = rcv;
    w.stack = stack;
    w.dir = dir;
    w.A = A;
    w.n_stack = n_stack;
    w.dt = dt;
    w.A0 = A0;
    w.K = K;
    w.mexp = mexp;
    w.Sc = Sc;
    w.hill = hill;
    w.sqrt_m = mexp == 0.5;
    w.n_one = n_one;
    w.cap_ch = hill == DFLE_HILLSLOPE_THRESHOLD && ls->o.cap_channels;
    w.VU = w.Vf = w.Vh = w.dV = 0.0;
    if (ls->model == NULL && ls->par != NULL) {
        /* Basins in parallel: no debris flows (the model is one object),
         * so no cell can fail. */
        sweep_chunks sc;
        if ((st_ = ls_par_partition(ls, err)) != DFLE_OK)
            return step_undone(ls, z_before, st_);
        sc.w = &w;
        st_ = dfle_par_run(ls->par, LS_PAR_CHUNKS, sweep_chunk, &sc, err);
        for (size_t k = 0; st_ == DFLE_OK && k < LS_PAR_CHUNKS; k++) {
            w.VU += sc.part[k].VU;
            w.Vf += sc.part[k].Vf;
            w.Vh += sc.part[k].Vh;
            w.dV += sc.part[k].dV;
        }
        if (st_ != DFLE_OK)
            return step_undone(ls, z_before, st_);
    } else if ((st_ = sweep_cells(&w, stack, n_stack, Sm, reach, &Vdf, &reached, err))
               != DFLE_OK) {
        return step_undone(ls, z_before, st_);
    }
    VU = w.VU;
    Vf = w.Vf;
    Vh = w.Vh;
    dV = w.dV;
    ls->routed = 0;
    ls->model_z_current = 0;
    ls->have_rates = 1;
    ls->evolved = 1;
    if (hill == DFLE_HILLSLOPE_DIFFUSION) {
        double before = 0.0, after = 0.0;
        for (size_t c = 0; c < ls->n; c++)
            before += isnan(z[c]) ? 0.0 : z[c];
        if ((st_ = ls_diffuse(ls, dt, err)) != DFLE_OK)
            return step_undone(ls, z_before, st_);
        for (size_t c = 0; c < ls->n; c++)
            after += isnan(z[c]) ? 0.0 : z[c];
        /* What diffusion moved into channel and base cells left the
         * hillslopes: the hillslope term of the volume balance. */
        Vh += before - after;
        dV += after - before;
    }
    if ((st_ = check_surface(ls, dt, (const double[5]){VU, Vf, Vdf, Vh, dV}, VU, Vh, err))
        != DFLE_OK)
        return st_;
    if (st != NULL) {
        st->route_seconds = t1 - t0;
        st->solve_seconds = cpu_seconds() - t1;
        ls_ratios(ls, j, st);
        status_network(ls, st);
        st->reached = reached;
        st->dt = dt;
        st->dV = dV * ca;
        st->V_uplift = VU * ca;
        st->V_fluvial = Vf * ca;
        st->V_df = Vdf * ca;
        st->V_hillslope = Vh * ca;
    }
    return DFLE_OK;
}

int ls_check_step(const dfle_landscape *ls, double dt, double tol, const char *what,
                  dfle_error *err)
{
    double zmax = 1.0, Umin = INFINITY, ulp, need;
    const double *U = ls->U.grid;
    /* Plain comparisons (NaN, NoData, fails both; U is checked finite at
     * every data cell), and U read only where it varies in space. */
    for (size_t c = 0; c < ls->n; c++) {
        const double a = fabs(ls->z[c]);
        if (a > zmax)
            zmax = a;
        if (U != NULL && a == a && U[c] < Umin)
            Umin = U[c];
    }
    if (U == NULL && ls->n_data > 0)
        Umin = ls->U.value;
    /* z is resolved to about ulp; a step's uplift must be well above it
     * (a transient: 64 ulp, so that it carries more than a digit or
     * two), and for a steady run |dz/dt| = change / dt must resolve
     * tol U (an error of 16 ulp in the change is 1/16 of tol U dt). */
    ulp = zmax * DBL_EPSILON;
    need = tol > 0 ? 16.0 * ulp / tol : 64.0 * ulp;
    if (Umin * dt >= need)
        return DFLE_OK;
    return dfle_error_set(err, DFLE_EINVAL, "landscape: %s = %g yr is too short for the "
                          "precision of z: its uplift U dt = %g m is below %g m, what elevations "
                          "of up to %g m resolve%s; take %s of at least %g yr", what, dt,
                          Umin * dt, need, zmax, tol > 0 ? " to tell |dz/dt| from tol U" : "",
                          strcmp(what, "dt") == 0 ? "dt" : "steps", need / Umin);
}

int dfle_landscape_step(dfle_landscape *ls, double dt, double tol, dfle_landscape_status *st,
                        dfle_error *err)
{
    const ls_judge j = {tol, 0.99, 0.95};
    int s;
    if (!(isfinite(dt) && dt > 0))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: the time step must be > 0 yr (got "
                              "%g)", dt);
    if (!(isfinite(tol) && tol > 0))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: tol must be > 0 (got %g)", tol);
    if (st != NULL)
        memset(st, 0, sizeof *st);
    if ((s = ls_check_step(ls, dt, 0.0, "dt", err)) != DFLE_OK)
        return s;
    if ((s = ls_update_fields(ls, 0, err)) != DFLE_OK)
        return s;
    if ((s = ls_implicit_step(ls, dt, &j, st, err)) != DFLE_OK)
        return s;
    ls->time += dt;
    return DFLE_OK;
}

/* ---------------------------------------------------------------- */
/* Evaluated rates and explicit steps                               */
/* ---------------------------------------------------------------- */

int ls_evaluate_rates(dfle_landscape *ls, const ls_judge *j, dfle_landscape_status *st,
                      dfle_error *err)
{
    const uint32_t *rcv;
    const unsigned char *dir;
    const double *A, *Edf = NULL;
    const int cap = ls->o.hillslope == DFLE_HILLSLOPE_THRESHOLD && ls->o.cap_channels;
    int s;

    if ((s = ls_route(ls, err)) != DFLE_OK)
        return s;
    if (ls->model != NULL) {
        if ((s = ls_model_evaluate(ls, err)) != DFLE_OK)
            return s;
        if ((Edf = dfle_model_field(ls->model, DFLE_FIELD_E_DF, err)) == NULL)
            return err != NULL ? err->code : DFLE_ENUMERIC;
    }
    rcv = dfle_drainage_receivers(ls->dr);
    dir = dfle_drainage_dir(ls->dr);
    A = dfle_drainage_area(ls->dr);
    for (size_t c = 0; c < ls->n; c++) {
        double U, S, r;
        if (isnan(ls->z[c]))
            continue;
        if (rcv[c] == c) {
            ls->dzdt[c] = 0.0f;
            continue;
        }
        U = ls_value(&ls->U, c);
        S = (ls->z[c] - ls->z[rcv[c]]) / ls->len[dir[c]];
        if (A[c] >= ls->o.A0) {
            r = U - ls_fluvial_rate(ls, c, A[c], S) - (Edf != NULL ? Edf[ls->node_of[c]] : 0.0);
            if (r > 0 && cap && S >= ls->o.S_c * (1.0 - 1e-9))
                r = 0.0; /* held at S_c: what erosion leaves fails */
        } else if (ls->o.hillslope == DFLE_HILLSLOPE_THRESHOLD)
            r = S >= ls->o.S_c * (1.0 - 1e-9) ? 0.0 : U; /* held at S_c, or rising */
        else if (ls->o.hillslope == DFLE_HILLSLOPE_DIFFUSION)
            r = U + ls_laplacian(ls, c);
        else
            r = U;
        ls->dzdt[c] = (float)r;
    }
    ls->have_rates = 1;
    if (st != NULL) {
        ls_ratios(ls, j, st);
        status_network(ls, st);
        st->reached = count_reached(ls);
    }
    return DFLE_OK;
}

int ls_explicit_step(dfle_landscape *ls, double dt_cap, double cfl, const ls_judge *j,
                     double *dt_out, dfle_landscape_status *st, dfle_error *err)
{
    const uint32_t *rcv, *stack;
    const unsigned char *dir;
    const double *A, *cel = NULL;
    double dt = dt_cap, VU = 0, Vh = 0, dV = 0, Vf = 0, Vdf = 0;
    size_t n_stack;
    int s;

    if ((s = ls_evaluate_rates(ls, j, NULL, err)) != DFLE_OK)
        return s;
    if (ls->model != NULL && (s = dfle_model_celerity(ls->model, &cel, err)) != DFLE_OK)
        return s;
    rcv = dfle_drainage_receivers(ls->dr);
    dir = dfle_drainage_dir(ls->dr);
    A = dfle_drainage_area(ls->dr);
    stack = dfle_drainage_stack(ls->dr, &n_stack);
    /* The CFL step: a slope change travels upstream at c = dE/dS. */
    for (size_t c = 0; c < ls->n; c++) {
        double L, S, speed;
        if (isnan(ls->z[c]) || rcv[c] == c || !(A[c] >= ls->o.A0))
            continue;
        L = ls->len[dir[c]];
        S = (ls->z[c] - ls->z[rcv[c]]) / L;
        speed = S > 0 ? ls->n_exp * ls_fluvial_rate(ls, c, A[c], S) / S : 0.0;
        if (cel != NULL)
            speed = fmax(speed, cel[ls->node_of[c]]);
        if (speed > 0 && cfl * L / speed < dt)
            dt = cfl * L / speed;
    }
    if (ls->o.hillslope == DFLE_HILLSLOPE_DIFFUSION) {
        double h = fmin(ls->o.dx, ls->o.dy);
        dt = fmin(dt, cfl * h * h / (4.0 * ls->o.D));
    }
    if ((s = keep_surface(ls, err)) != DFLE_OK)
        return s;
    /* Rates were evaluated at the old surface: apply them, then the
     * threshold in stack order (receivers first). */
    for (size_t k = 0; k < n_stack; k++) {
        const size_t c = stack[k], r = rcv[c];
        const double z0 = ls->z[c], U = ls_value(&ls->U, c);
        double zn;
        if (r == c)
            continue;
        zn = z0 + dt * ls->dzdt[c];
        if (A[c] >= ls->o.A0) {
            double S = (z0 - ls->z[r]) / ls->len[dir[c]]; /* z[r] is new: close enough */
            double Ef = ls_fluvial_rate(ls, c, A[c], S > 0 ? S : 0);
            Vf += Ef * dt;
            Vdf += (U - ls->dzdt[c]) * dt - Ef * dt;
            if (ls->o.hillslope == DFLE_HILLSLOPE_THRESHOLD && ls->o.cap_channels &&
                zn > ls->z[r] + ls->o.S_c * ls->len[dir[c]]) { /* S_c caps channels too */
                Vh += zn - (ls->z[r] + ls->o.S_c * ls->len[dir[c]]);
                zn = ls->z[r] + ls->o.S_c * ls->len[dir[c]];
            }
        }
        if (!(A[c] >= ls->o.A0) && ls->o.hillslope == DFLE_HILLSLOPE_THRESHOLD) {
            double cap = ls->z[r] + ls->o.S_c * ls->len[dir[c]];
            zn = z0 + U * dt;
            if (zn > cap) {
                Vh += zn - cap;
                zn = cap;
            }
        }
        ls->dzdt[c] = (float)((zn - z0) / dt);
        VU += U * dt;
        dV += zn - z0;
        ls->z[c] = zn;
    }
    ls->routed = 0;
    ls->model_z_current = 0;
    ls->evolved = 1;
    if ((s = check_surface(ls, dt, (const double[5]){VU, Vf, Vdf, Vh, dV}, VU, Vh, err)) != DFLE_OK)
        return s;
    *dt_out = dt;
    if (st != NULL) {
        ls_ratios(ls, j, st);
        status_network(ls, st);
        st->dt = dt;
        st->dV = dV * ls->cell_area;
        st->V_uplift = VU * ls->cell_area;
        st->V_fluvial = Vf * ls->cell_area;
        st->V_df = Vdf * ls->cell_area;
        st->V_hillslope = Vh * ls->cell_area;
    }
    return DFLE_OK;
}
