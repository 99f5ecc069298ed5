/*
 * flow1d.c - the depth-averaged two-phase flow solver of flow1d.h.
 *
 * Why the pieces are as they are:
 *  - Conserving w h and w q (not h and hv) makes the channel's width
 *    variation part of the flux balance, so a router can promise that
 *    the volume released equals the volume out plus the volume left, to
 *    round-off; only the wall pressure (g_z h^2/2) dw/dx remains a source,
 *    and it balances the flux exactly for still water in a flat channel.
 *  - The slope enters as the explicit source g_x h of Eq. (8), as in the
 *    paper.  A hydrostatic reconstruction (well balanced for lakes on
 *    sloping beds) was rejected: on 5 m cells with slopes near 1 it caps
 *    the driving force of any flow thinner than S dx, i.e. of every
 *    debris flow here.
 *  - Viscous drag 2 eta v_f v / (rho h) grows like 1/h^2 per unit q and
 *    would force tiny steps at thin fronts; solved implicitly it is
 *    unconditionally stable and only ever slows the flow.
 *  - Coulomb friction is applied last, as a stopping check: if the
 *    impulse friction can deliver in dt exceeds the momentum, the cell
 *    stops (q = 0) instead of the friction reversing it.  This is what
 *    lets a pile come to rest on a slope below its friction angle.
 *  - A step works on the wet window only (the cells holding volume and
 *    one more on each side: a first-order step moves volume no further),
 *    and computes nothing twice; where a bound decides (friction's erf),
 *    the exact value is not computed.  Every number stays what the
 *    whole-grid sweep computes, to the bit (doc/process-router.md, the
 *    wet window).
 *  - Divisions are few and do not wait for each other (the divider is
 *    what a step's time is made of): 1 / (w dx) per cell, drag and phi
 *    in one division each, HLLC's star depth as the HLL average; the
 *    same numbers to rounding (doc/process-router.md).
 */
#include "dfle/flow1d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct dfle_flow1d {
    size_t n;
    double dx_min; /* the shortest cell [m]: the CFL step's length */
    dfle_flow1d_params p;
    /* The wet window: cells [lo, hi) the last step worked on, and faces
     * lo..hi its fluxes.  Outside, h = q = u = c = 0 and every face array
     * is 0, which is what a step over the whole grid would compute there
     * (two dry cells exchange nothing), so skipping them changes nothing. */
    size_t lo, hi;
    /* 1 after h or q was handed out for writing: the next step derives u,
     * c, smax and the volume afresh over the whole grid. */
    int stale;
    /* The wet cells at rest (q = 0) lie in [rest_lo, rest_hi) (empty if
     * rest_lo >= rest_hi): the only cells friction can hold, so the only
     * ones hold_resting_cells looks at.  A flow's resting cells are a
     * few at its tail and front, its window a hundred. */
    size_t rest_lo, rest_hi;
    double smax;   /* max |u| + c over wet cells [m/s]: the CFL speed     */
    double phi_k;  /* I0 sqrt(rho / rho_s) / (2 D_eff) [s/m] (phi_wet)   */
    double volume; /* sum of w h dx over the grid, in cell order [m^3]    */
    /* One block; cell arrays have n values, face arrays n + 1 (face k lies
     * between cells k - 1 and k; face 0 is the upstream wall, face n the
     * outlet).  Per cell, fixed: w, w dx, its reciprocal (a step
     * multiplies by it: a division costs several multiplications), g_x,
     * g_z, g_z / 2, w dx g_x and the width step wf[k+1] - wf[k].  Per
     * cell, the state and what a step derives from it once: the velocity
     * u = q/h and wave speed c = sqrt(g_z h) of wet cells (0 in dry
     * ones), used by both faces, the CFL step and friction. */
    double *w, *dx, *wdx, *rwdx, *gx, *gz, *hg, *wgx, *dwf; /* cells, geometry */
    double *h, *q, *u, *c, *limit, *held;             /* cells, state    */
    double *wf, *Fh, *Fq, *face_vol;                  /* faces           */
};

void dfle_flow1d_params_default(dfle_flow1d_params *p)
{
    p->g = 9.81;
    p->rho = 1800.0;
    p->rho_s = 2600.0;
    p->mu_s = 0.384;
    p->mu_2 = 0.62;
    p->I0 = 0.279;
    p->D_eff = 0.09;
    p->lambda0 = 0.9;
    p->D = 5e-6;
    p->eta = 60.0;
    p->v_f = 0.5;
    p->cfl = 0.5;
    p->h_dry = 1e-6;
    p->outlet_wall = 0;
    p->full_domain = 0;
}

int dfle_flow1d_params_check(const dfle_flow1d_params *p, const char *who,
                             dfle_error *err)
{
    const struct { const char *name; double v, lo, hi; int lo_open; } r[] = {
        {"g", p->g, 0, INFINITY, 1},         {"rho", p->rho, 0, INFINITY, 1},
        {"rho_s", p->rho_s, 0, INFINITY, 1}, {"mu_s", p->mu_s, 0, INFINITY, 0},
        {"mu_2", p->mu_2, 0, INFINITY, 0},   {"I0", p->I0, 0, INFINITY, 1},
        {"D_eff", p->D_eff, 0, INFINITY, 1}, {"lambda0", p->lambda0, 0, 1, 0},
        {"D", p->D, 0, INFINITY, 0},         {"eta", p->eta, 0, INFINITY, 0},
        {"v_f", p->v_f, 0, 1, 0},            {"cfl", p->cfl, 0, 1, 1},
        {"h_dry", p->h_dry, 0, INFINITY, 1},
    };
    for (size_t i = 0; i < sizeof r / sizeof r[0]; i++) {
        double v = r[i].v;
        if (!(isfinite(v) && (r[i].lo_open ? v > r[i].lo : v >= r[i].lo) && v <= r[i].hi)) {
            if (isinf(r[i].hi))
                return dfle_error_set(err, DFLE_EINVAL, "%s: %s must be %s 0 (got %g)", who,
                                      r[i].name, r[i].lo_open ? ">" : ">=", v);
            return dfle_error_set(err, DFLE_EINVAL, "%s: %s must be in %s0, %g] (got %g)", who,
                                  r[i].name, r[i].lo_open ? "(" : "[", r[i].hi, v);
        }
    }
    if (p->lambda0 >= 1)
        return dfle_error_set(err, DFLE_EINVAL,
                              "%s: lambda0 must be < 1 (at 1 friction vanishes) (got %g)", who,
                              p->lambda0);
    if (p->mu_2 < p->mu_s)
        return dfle_error_set(err, DFLE_EINVAL, "%s: mu_2 must be >= mu_s = %g (got %g)", who,
                              p->mu_s, p->mu_2);
    return DFLE_OK;
}

enum { CELL_ARRAYS = 15, FACE_ARRAYS = 4 };

int dfle_flow1d_new(size_t n, double dx, const double *w, const double *S,
                    const dfle_flow1d_params *p, dfle_flow1d **out,
                    dfle_error *err)
{
    return dfle_flow1d_new_cells(n, NULL, dx, w, S, p, out, err);
}

int dfle_flow1d_new_cells(size_t n, const double *dxs, double dx, const double *w,
                          const double *S, const dfle_flow1d_params *p, dfle_flow1d **out,
                          dfle_error *err)
{
    dfle_flow1d *f;
    double *block, **cell[CELL_ARRAYS], **face[FACE_ARRAYS];
    int st;

    *out = NULL;
    if ((st = dfle_flow1d_params_check(p, "flow1d", err)) != DFLE_OK)
        return st;
    if (n < 1 || (dxs == NULL && !(isfinite(dx) && dx > 0)))
        return dfle_error_set(err, DFLE_EINVAL, "flow1d: need n >= 1 cells and dx > 0 (got %zu, %g)",
                              n, dx);
    for (size_t k = 0; dxs != NULL && k < n; k++)
        if (!(isfinite(dxs[k]) && dxs[k] > 0))
            return dfle_error_set(err, DFLE_EINVAL, "flow1d: cell %zu needs dx > 0 (got %g)",
                                  k + 1, dxs[k]);
    for (size_t k = 0; k < n; k++)
        if (!(isfinite(w[k]) && w[k] > 0 && isfinite(S[k])))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "flow1d: cell %zu needs w > 0 and a finite slope (w = %g, S = %g)",
                                  k + 1, w[k], S[k]);
    f = malloc(sizeof *f);
    block = calloc(CELL_ARRAYS * n + FACE_ARRAYS * (n + 1), sizeof *block);
    if (f == NULL || block == NULL) {
        free(f);
        free(block);
        return dfle_error_set(err, DFLE_ENOMEM, "flow1d: out of memory for %zu cells", n);
    }
    f->n = n;
    f->p = *p;
    f->lo = 0;
    f->hi = n;
    f->stale = 1;
    f->smax = f->volume = 0.0;
    f->phi_k = p->I0 * sqrt(p->rho / p->rho_s) / (2.0 * p->D_eff);
    cell[0] = &f->w; /* first: the block starts at w */
    cell[1] = &f->wdx, cell[2] = &f->gx, cell[3] = &f->gz, cell[4] = &f->hg;
    cell[5] = &f->rwdx, cell[6] = &f->wgx, cell[7] = &f->dwf, cell[8] = &f->h;
    cell[9] = &f->q, cell[10] = &f->u, cell[11] = &f->c, cell[12] = &f->limit;
    cell[13] = &f->held, cell[14] = &f->dx;
    face[0] = &f->wf, face[1] = &f->Fh, face[2] = &f->Fq, face[3] = &f->face_vol;
    for (size_t a = 0; a < CELL_ARRAYS; a++)
        *cell[a] = block + a * n;
    for (size_t a = 0; a < FACE_ARRAYS; a++)
        *face[a] = block + CELL_ARRAYS * n + a * (n + 1);
    f->wf[0] = w[0];
    f->wf[n] = w[n - 1];
    for (size_t k = 1; k < n; k++)
        f->wf[k] = 0.5 * (w[k - 1] + w[k]);
    f->dx_min = INFINITY;
    for (size_t k = 0; k < n; k++) {
        double theta = atan(S[k]);
        f->dx[k] = dxs != NULL ? dxs[k] : dx;
        f->dx_min = f->dx[k] < f->dx_min ? f->dx[k] : f->dx_min;
        f->w[k] = w[k];
        f->wdx[k] = w[k] * f->dx[k];
        f->gx[k] = p->g * sin(theta);
        f->gz[k] = p->g * cos(theta);
        f->hg[k] = 0.5 * f->gz[k];
        f->rwdx[k] = 1.0 / f->wdx[k];
        f->wgx[k] = f->wdx[k] * f->gx[k];
        f->dwf[k] = f->wf[k + 1] - f->wf[k];
    }
    *out = f;
    return DFLE_OK;
}

void dfle_flow1d_free(dfle_flow1d *f)
{
    if (f == NULL)
        return;
    free(f->w); /* the block starts at w */
    free(f);
}

/* Handing out the state for writing opens the window to the whole grid:
 * the caller may put volume anywhere. */
static double *open_state(dfle_flow1d *f, double *a)
{
    f->stale = 1;
    f->lo = 0;
    f->hi = f->n;
    return a;
}

double *dfle_flow1d_h(dfle_flow1d *f) { return open_state(f, f->h); }
double *dfle_flow1d_q(dfle_flow1d *f) { return open_state(f, f->q); }
const double *dfle_flow1d_depth(const dfle_flow1d *f) { return f->h; }
const double *dfle_flow1d_discharge(const dfle_flow1d *f) { return f->q; }
size_t dfle_flow1d_size(const dfle_flow1d *f) { return f->n; }

void dfle_flow1d_window(const dfle_flow1d *f, size_t *k0, size_t *k1)
{
    *k0 = f->lo;
    *k1 = f->hi;
}

double dfle_flow1d_pore_length(const dfle_flow1d *f, double t)
{
    /* Eq. (9): lambda0 until the flow has entered (t <= 0) or without
     * diffusion (D = 0); 0 says so. */
    if (t <= 0 || f->p.D <= 0)
        return 0.0;
    return sqrt(f->p.D * t);
}

/* The helpers of a step take the parameters and the cell's geometry as
 * values (a step passes a local copy): stores into the state arrays then
 * cannot alias them, and the compiler keeps them in registers. */
static inline double lambda_of(const dfle_flow1d_params *p, double h, double L)
{
    /* 1 - erfc(2h/sqrt(4Dt)) = erf(h/sqrt(Dt)).  From h / L = 6 on (to
     * within rounding: from 5.93), erf is 1 to the bit (1 - erf(6) =
     * 2e-17, under half an ulp of 1, and libm returns 1 there): the
     * call is skipped, as it is for most cells of a flow older than a
     * few seconds. */
    if (L == 0.0 || h >= 6.0 * L)
        return p->lambda0;
    return p->lambda0 * erf(h / L);
}

double dfle_flow1d_lambda_at(const dfle_flow1d *f, double h, double L)
{
    return lambda_of(&f->p, h, L);
}

double dfle_flow1d_lambda(const dfle_flow1d *f, double h, double t)
{
    return dfle_flow1d_lambda_at(f, h, dfle_flow1d_pore_length(f, t));
}

/* Eq. (10) at depth h > h_dry where the wave speed is c = sqrt(g_z h):
 * with P = rho g_z h, sqrt(P / rho_s) = c sqrt(rho / rho_s), so
 * I = |v| / (phi_k h c) I0 and I / (I0 + I) = |v| / (|v| + phi_k h c),
 * one division where Eq. (10) as written takes four and a root (c is
 * at hand in a step).  No 1/0 at rest: phi = mu_s there exactly. */
static inline double phi_wet(const dfle_flow1d_params *p, double phi_k, double c, double h,
                             double v)
{
    const double a = fabs(v);
    return p->mu_s + (p->mu_2 - p->mu_s) * a / (a + phi_k * h * c);
}

double dfle_flow1d_phi(const dfle_flow1d *f, size_t k, double h, double v)
{
    return h > f->p.h_dry ? phi_wet(&f->p, f->phi_k, sqrt(f->gz[k] * h), h, v) : f->p.mu_s;
}

double dfle_flow1d_phi_max(const dfle_flow1d *f)
{
    /* phi -> mu_2 as I -> inf; the operations of phi_wet round it up by a
     * few units in the last place at most, far below this margin. */
    return f->p.mu_2 * (1.0 + 1e-12);
}

/* Velocity and wave speed of cell k as the fluxes see it (0 if dry). */
static inline void cell_speeds(const dfle_flow1d *f, size_t k, double *u, double *c)
{
    const double h = f->h[k];
    if (h > f->p.h_dry) {
        *u = f->q[k] / h;
        *c = sqrt(f->gz[k] * h);
    } else {
        *u = *c = 0.0;
    }
}

double dfle_flow1d_stable_dt(const dfle_flow1d *f)
{
    double smax = f->smax;
    if (f->stale) { /* the state was written: from scratch */
        smax = 0.0;
        for (size_t k = 0; k < f->n; k++) {
            double u, c, s;
            cell_speeds(f, k, &u, &c);
            s = fabs(u) + c;
            if (s > smax)
                smax = s;
        }
    }
    return smax > 0 ? f->p.cfl * f->dx_min / smax : INFINITY;
}

/* HLLC flux per unit width between states (h, q) with velocity u, wave
 * speed c and g_z / 2 = hg each (u = c = 0 on a dry side), each side with
 * its own g_z in its physical flux (Toro 2009, Ch. 10). */
static inline void hllc(double hL, double qL, double uL, double cL, double hgL, double hR,
                        double qR, double uR, double cR, double hgR, double h_dry, double *Fh,
                        double *Fq)
{
    int dryL = !(hL > h_dry), dryR = !(hR > h_dry);
    double SL, SR, Ss, hs, A, B, FhL, FqL, FhR, FqR;

    if (dryL && dryR) {
        *Fh = *Fq = 0.0;
        return;
    }
    if (dryL)
        hL = qL = 0.0;
    if (dryR)
        hR = qR = 0.0;
    if (dryL) { /* wet-dry front moving into the dry side */
        SL = uR - 2.0 * cR;
        SR = uR + cR;
    } else if (dryR) {
        SL = uL - cL;
        SR = uL + 2.0 * cL;
    } else { /* min and max inline: fmin/fmax are library calls */
        double a = uL - cL, b = uR - cR;
        SL = a < b ? a : b;
        a = uL + cL, b = uR + cR;
        SR = a > b ? a : b;
    }
    FhL = hL * uL;
    FqL = hL * uL * uL + hgL * hL * hL;
    FhR = hR * uR;
    FqR = hR * uR * uR + hgR * hR * hR;
    if (SL >= 0) {
        *Fh = FhL, *Fq = FqL;
        return;
    }
    if (SR <= 0) {
        *Fh = FhR, *Fq = FqR;
        return;
    }
    /* The contact speed and the star depth, which for shallow water is
     * the HLL average h* = (hL (uL - SL) - hR (uR - SR)) / (SR - SL) on
     * either side of the contact (Toro's hL (SL - uL) / (SL - S*), and
     * its mirror, rewritten with S*): two divisions side by side, not
     * one after the other, and h* >= 0 by construction. */
    A = hR * (uR - SR);
    B = hL * (uL - SL);
    Ss = (SL * A - SR * B) / (A - B);
    hs = (B - A) / (SR - SL);
    if (Ss >= 0) {
        *Fh = FhL + SL * (hs - hL);
        *Fq = FqL + SL * (hs * Ss - qL);
    } else {
        *Fh = FhR + SR * (hs - hR);
        *Fq = FqR + SR * (hs * Ss - qR);
    }
}

/* Flux through a wall next to cell k: the mirror-state Riemann problem,
 * whose mass flux is zero by symmetry (set exactly).  The mirror's
 * velocity -u is (-q)/h to the bit. */
static void wall_flux(const dfle_flow1d *f, size_t k, int right_side, double *Fh, double *Fq)
{
    const double h = f->h[k], q = f->q[k], u = f->u[k], c = f->c[k], hg = f->hg[k];
    if (right_side)
        hllc(h, q, u, c, hg, h, -q, -u, c, hg, f->p.h_dry, Fh, Fq);
    else
        hllc(h, -q, -u, c, hg, h, q, u, c, hg, f->p.h_dry, Fh, Fq);
    *Fh = 0.0;
}

/* Fluxes at faces lo..hi of the window [lo, hi). */
static void compute_fluxes(dfle_flow1d *f, size_t lo, size_t hi)
{
    const size_t n = f->n;
    const double h_dry = f->p.h_dry;
    const double *h = f->h, *q = f->q, *u = f->u, *hg = f->hg;
    {
        /* restrict: the stores to Fh and Fq touch none of the states. */
        const double *restrict hr = f->h, *restrict qr = f->q, *restrict ur = f->u,
                     *restrict cr = f->c, *restrict hgr = f->hg;
        double *restrict Fh = f->Fh, *restrict Fq = f->Fq;
        for (size_t k = lo > 0 ? lo : 1; k <= hi && k < n; k++)
            hllc(hr[k - 1], qr[k - 1], ur[k - 1], cr[k - 1], hgr[k - 1], hr[k], qr[k], ur[k],
                 cr[k], hgr[k], h_dry, &Fh[k], &Fq[k]);
    }
    if (lo == 0)
        wall_flux(f, 0, 0, &f->Fh[0], &f->Fq[0]);
    if (hi < n)
        return; /* the outlet is outside the window: dry, no flux */
    if (!f->p.outlet_wall && h[n - 1] > h_dry && q[n - 1] >= 0) {
        /* Open outlet: the outside copies the last cell (no reflection). */
        const double hn = h[n - 1], un = u[n - 1];
        f->Fh[n] = hn * un;
        f->Fq[n] = hn * un * un + hg[n - 1] * hn * hn;
    } else {
        /* Nothing flows back in through the outlet. */
        wall_flux(f, n - 1, 1, &f->Fh[n], &f->Fq[n]);
    }
}

/* Momentum w q dx of cell k (depth h0, discharge q0) after the fluxes
 * of one step (dF = wf Fq downstream minus upstream) and the explicit
 * sources, before drag and friction: the wall pressure of the width
 * change and gravity along the bed, g_x h. */
static inline double momentum_after_fluxes(const dfle_flow1d *f, size_t k, double dt, double h0,
                                           double q0, double dF)
{
    const double mom = f->wdx[k] * q0 - dt * dF;
    return mom + dt * (f->hg[k] * h0 * h0 * f->dwf[k] + f->wgx[k] * h0);
}

/* The Coulomb impulse dt (1 - lambda) g_z h mu at depth h per unit width
 * [m^2/s], given 1 - lambda. */
static inline double coulomb(double dt, double one_minus_lambda, double gz, double h, double mu)
{
    return dt * one_minus_lambda * gz * h * mu;
}

/* Whether the Coulomb impulse at lambda = lambda0 erf(h / L) (Eq. 9)
 * resists `push` [m^2/s].  The erf is the dearest part of a step, and
 * often the answer does not need it: 0 <= lambda <= lambda0 bounds the
 * impulse between its values at lambda0 and at 0, computed by the same
 * operations in the same order, and rounding is monotone, so the bounds
 * hold in floating point too and give the answer the exact impulse
 * would. */
static inline int coulomb_resists(const dfle_flow1d_params *p, double dt, double gz, double h,
                                  double mu, double L, double push)
{
    if (push <= coulomb(dt, 1.0 - p->lambda0, gz, h, mu))
        return 1;
    if (push > coulomb(dt, 1.0, gz, h, mu))
        return 0;
    return push <= coulomb(dt, 1.0 - lambda_of(p, h, L), gz, h, mu);
}

/* A cell at rest stays at rest while friction can resist what pushes it
 * (a pile on a slope below its friction angle).  The Riemann fluxes know
 * nothing of friction and would still spill its edges into dry
 * neighbours, so no face may draw volume out of a held cell: there the
 * face is a wall.  Fluxes stay single-valued, volume stays conserved.
 * L: the pore-pressure diffusion length of this step.  Returns whether
 * any cell is held; held[] is set only then, and only in [rest_lo,
 * rest_hi) (every other cell of the window is not held). */
static int hold_resting_cells(dfle_flow1d *f, double dt, double L, size_t lo, size_t hi)
{
    const size_t n = f->n;
    const dfle_flow1d_params p = f->p;
    int any = 0;
    /* Elsewhere no cell is held: the window is inside the grid and the
     * resting cells inside the window (the rest holds no volume). */
    if (f->rest_lo > lo)
        lo = f->rest_lo;
    if (f->rest_hi < hi)
        hi = f->rest_hi;
    if (lo >= hi)
        return 0;
    {
        const double *restrict h = f->h, *restrict q = f->q, *restrict wf = f->wf,
                     *restrict Fq = f->Fq;
        double *restrict held = f->held;
        for (size_t k = lo; k < hi; k++) {
            double push;
            held[k] = 0.0;
            if (!(h[k] > p.h_dry) || q[k] != 0.0)
                continue;
            push = fabs(momentum_after_fluxes(f, k, dt, h[k], q[k],
                                              wf[k + 1] * Fq[k + 1] - wf[k] * Fq[k])) *
                   f->rwdx[k];
            held[k] = coulomb_resists(&p, dt, f->gz[k], h[k], p.mu_s, L, push);
            any |= held[k] != 0.0;
        }
    }
    if (!any)
        return 0;
    /* Faces lo..hi touch every held cell. */
    for (size_t k = lo; k <= hi; k++) {
        if (f->Fh[k] > 0 && k > 0 && f->held[k - 1])
            wall_flux(f, k - 1, 1, &f->Fh[k], &f->Fq[k]);
        else if (f->Fh[k] < 0 && k < n && f->held[k])
            wall_flux(f, k, 0, &f->Fh[k], &f->Fq[k]);
    }
    return 1;
}

/* Scale each cell's outgoing fluxes so that a step never takes more
 * volume than the cell holds; the scale of a face is its upwind cell's
 * (finish_face), so the flux stays single-valued and volume conserved.
 * Here: each cell's scale. */
static void limit_outflow(dfle_flow1d *f, double dt, size_t lo, size_t hi)
{
    const double *restrict wf = f->wf, *restrict Fh = f->Fh, *restrict w = f->w,
                 *restrict h = f->h;
    double *restrict limit = f->limit;
    for (size_t k = lo; k < hi; k++) {
        const double down = wf[k + 1] * Fh[k + 1], up = -wf[k] * Fh[k];
        /* max(0, .) inline: fmax is a library call (the same value here). */
        double out = dt * ((down > 0 ? down : 0.0) + (up > 0 ? up : 0.0));
        double vol = w[k] * h[k] * f->dx[k];
        limit[k] = out > vol ? vol / out : 1.0;
    }
}

/* Face k scaled by its upwind cell's limit: the volume it carries in this
 * step (stored, and returned in *vol) and its momentum flux wf Fq. */
static inline void finish_face(dfle_flow1d *f, size_t k, double dt, double *vol, double *mflux)
{
    double s = 1.0;
    if (f->Fh[k] > 0)
        s = k > 0 ? f->limit[k - 1] : 1.0;
    else if (f->Fh[k] < 0)
        s = k < f->n ? f->limit[k] : 1.0;
    if (s != 1.0) {
        f->Fh[k] *= s;
        f->Fq[k] *= s;
    }
    *vol = f->face_vol[k] = dt * f->wf[k] * f->Fh[k];
    *mflux = f->wf[k] * f->Fq[k];
}

/* The new state of cells [lo, hi): volume and momentum from the face
 * fluxes (each face finished just before the cell below it needs it) and
 * sources, drag, friction; then u, c, the CFL speed and the volume of the
 * new state (summed in cell order, as dfle_flow1d_volume does), and the
 * span of the cells at rest.  any_held: whether hold_resting_cells held
 * any cell (else held[] was not set). */
static int update(dfle_flow1d *f, double dt, double L, size_t lo, size_t hi, int any_held,
                  dfle_error *err)
{
    const dfle_flow1d_params p = f->p;
    const double *restrict dx = f->dx, phi_k = f->phi_k;
    /* Per step: the drag 2 eta v_f dt [kg/(m s)]; dt (1 - lambda0), the
     * first factor of every Coulomb bound at lambda0 (coulomb multiplies
     * left to right, so the bound is the same to the bit); and 6 L, the
     * depth from which erf(h / L) is 1 to the bit (lambda_of), 0 while
     * lambda is lambda0 everywhere. */
    const double drag = dt * 2.0 * p.eta * p.v_f, dt_free = dt * (1.0 - p.lambda0),
                 six_L = 6.0 * L;
    const double *restrict w = f->w, *restrict wdx = f->wdx, *restrict rwdx = f->rwdx,
                 *restrict gz = f->gz, *restrict held = f->held;
    double *restrict hs = f->h, *restrict qa = f->q, *restrict u = f->u, *restrict c = f->c;
    double smax = 0.0, volume = 0.0, fv0, fv1, mf0, mf1;
    size_t rest_lo = hi, rest_hi = lo;
    /* The held cells lie in [hold_lo, hold_lo + hold_n) (hold_resting_cells). */
    const size_t hold_lo = f->rest_lo, hold_n = any_held ? f->rest_hi - f->rest_lo : 0;

    finish_face(f, lo, dt, &fv0, &mf0);
    for (size_t k = lo; k < hi; k++, fv0 = fv1, mf0 = mf1) {
        const double h0 = hs[k], q0 = qa[k];
        double vol, h, rh, rhh, drag_factor, qs, fc, qn, phi, b0, ck, uk;

        finish_face(f, k + 1, dt, &fv1, &mf1);
        vol = wdx[k] * h0 - (fv1 - fv0);
        h = vol > 0 ? vol * rwdx[k] : 0.0; /* only round-off can make vol < 0 */
        hs[k] = h;
        volume += w[k] * h * dx[k];
        if (!(h > p.h_dry)) {
            qa[k] = u[k] = c[k] = 0.0;
            continue;
        }
        /* What depends on h alone first, so that its divisions and root
         * overlap the momentum balance: 1/h, the implicit viscous drag
         * 2 eta v_f v / (rho h) as the factor rho h^2 / (rho h^2 + dt 2
         * eta v_f) on q, the wave speed and phi (Eq. 10, at the speed u
         * of the start of the step, explicit as the paper's sources:
         * from the speed after a whole step of free acceleration it
         * would jump towards mu_2 and stall every flow that starts from
         * rest). */
        rh = 1.0 / h;
        rhh = p.rho * h * h;
        drag_factor = rhh / (rhh + drag);
        ck = sqrt(gz[k] * h);
        phi = phi_wet(&p, phi_k, ck, h, u[k]);
        qs = momentum_after_fluxes(f, k, dt, h0, q0, mf1 - mf0) * rwdx[k] * drag_factor;
        /* Coulomb friction (1 - lambda) g_z h phi(I): stop, never
         * reverse.  At lambda = lambda0 (the impulse's lower bound, by
         * the same operations: rounding is monotone) a cell that stops
         * needs no erf, and below 6 L hardly any cell does. */
        b0 = dt_free * gz[k] * h; /* coulomb(dt, 1 - lambda0, gz, h, .) / mu */
        fc = b0 * phi;
        if (!(h >= six_L) && !(fabs(qs) <= fc))
            fc = coulomb(dt, 1.0 - lambda_of(&p, h, L), gz[k], h, phi);
        qn = fabs(qs) <= fc ? 0.0 : qs - copysign(fc, qs);
        /* A held cell stays at rest (hold_resting_cells). */
        if (k - hold_lo < hold_n && held[k] != 0.0) /* k < hold_lo wraps around */
            qn = 0.0;
        if (!isfinite(qn))
            return dfle_error_set(err, DFLE_ENUMERIC,
                                  "flow1d: discharge not finite in cell %zu (h = %g m)", k + 1, h);
        if (qn == 0.0) {
            rest_lo = rest_lo < k ? rest_lo : k;
            rest_hi = k + 1;
        }
        uk = qn * rh; /* 0 when qn is */
        qa[k] = qn;
        u[k] = uk;
        c[k] = ck;
        smax = fabs(uk) + ck > smax ? fabs(uk) + ck : smax;
    }
    f->smax = smax;
    f->volume = volume;
    f->rest_lo = rest_lo;
    f->rest_hi = rest_hi;
    return DFLE_OK;
}

static void zero_faces(dfle_flow1d *f, size_t k0, size_t k1)
{
    for (size_t k = k0; k < k1; k++)
        f->Fh[k] = f->Fq[k] = f->face_vol[k] = 0.0;
}

/* The window of the next step: the cells holding any volume (all of it
 * lies in the last step's window) and one more on each side, which is
 * as far as one step can move volume.  Faces leaving the window are
 * cleared, so that outside it every face reads 0. */
static void narrow_window(dfle_flow1d *f)
{
    const size_t n = f->n, lo0 = f->lo, hi0 = f->hi;
    size_t a = lo0, b = hi0, lo, hi;
    while (a < b && f->h[a] == 0.0)
        a++;
    while (b > a && f->h[b - 1] == 0.0)
        b--;
    if (a == b) { /* nothing left on the grid */
        lo = hi = 0;
        if (lo0 < hi0)
            zero_faces(f, lo0, hi0 + 1);
    } else {
        lo = a > 0 ? a - 1 : 0;
        hi = b < n ? b + 1 : n;
        if (lo > lo0)
            zero_faces(f, lo0, lo);
        if (hi < hi0)
            zero_faces(f, hi + 1, hi0 + 1);
    }
    f->lo = lo;
    f->hi = hi;
}

/* After the caller wrote h or q: velocities and wave speeds afresh. */
static void refresh(dfle_flow1d *f)
{
    f->rest_lo = f->n;
    f->rest_hi = 0;
    for (size_t k = 0; k < f->n; k++) {
        cell_speeds(f, k, &f->u[k], &f->c[k]);
        if (f->h[k] > f->p.h_dry && f->q[k] == 0.0) {
            f->rest_lo = f->rest_lo < k ? f->rest_lo : k;
            f->rest_hi = k + 1;
        }
    }
    f->lo = 0;
    f->hi = f->n;
    f->stale = 0;
}

int dfle_flow1d_step(dfle_flow1d *f, double dt, double t_entry, double *outflow,
                     dfle_error *err)
{
    double L;
    int st, any_held;

    if (!(dt > 0 && isfinite(dt)))
        return dfle_error_set(err, DFLE_EINVAL, "flow1d: time step must be > 0 s (got %g)", dt);
    if (f->stale)
        refresh(f);
    else if (!f->p.full_domain)
        narrow_window(f);
    L = dfle_flow1d_pore_length(f, t_entry);
    compute_fluxes(f, f->lo, f->hi);
    any_held = hold_resting_cells(f, dt, L, f->lo, f->hi);
    limit_outflow(f, dt, f->lo, f->hi);
    if ((st = update(f, dt, L, f->lo, f->hi, any_held, err)) != DFLE_OK) {
        f->stale = 1; /* the state is half updated */
        f->lo = 0;
        f->hi = f->n;
        return st;
    }
    *outflow = f->face_vol[f->n];
    return DFLE_OK;
}

double dfle_flow1d_volume(const dfle_flow1d *f, size_t k0, size_t k1)
{
    double v = 0.0;
    if (k1 > f->n)
        k1 = f->n;
    if (!f->stale) {
        if (k0 == 0 && k1 == f->n)
            return f->volume; /* the same sum, made by the last step */
        /* Cells outside the window hold nothing: adding their zeros
         * would not change the sum. */
        if (k0 < f->lo)
            k0 = f->lo;
        if (k1 > f->hi)
            k1 = f->hi;
    }
    for (size_t k = k0; k < k1; k++)
        v += f->w[k] * f->h[k] * f->dx[k];
    return v;
}

double dfle_flow1d_face_volume(const dfle_flow1d *f, size_t k)
{
    return k <= f->n ? f->face_vol[k] : 0.0;
}

const double *dfle_flow1d_face_volumes(const dfle_flow1d *f)
{
    return f->face_vol;
}
