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
 */
#include "dfle/flow1d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct dfle_flow1d {
    size_t n;
    double dx;
    dfle_flow1d_params p;
    /* One block; cell arrays have n values, face arrays n + 1 (face k lies
     * between cells k - 1 and k; face 0 is the upstream wall, face n the
     * outlet). */
    double *w, *gx, *gz, *h, *q, *limit, *held; /* cells */
    double *wf, *Fh, *Fq, *face_vol;       /* faces */
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

enum { CELL_ARRAYS = 7, FACE_ARRAYS = 4 };

int dfle_flow1d_new(size_t n, double dx, const double *w, const double *S,
                    const dfle_flow1d_params *p, dfle_flow1d **out,
                    dfle_error *err)
{
    dfle_flow1d *f;
    double *block;
    int st;

    *out = NULL;
    if ((st = dfle_flow1d_params_check(p, "flow1d", err)) != DFLE_OK)
        return st;
    if (n < 1 || !(isfinite(dx) && dx > 0))
        return dfle_error_set(err, DFLE_EINVAL, "flow1d: need n >= 1 cells and dx > 0 (got %zu, %g)",
                              n, dx);
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
    f->dx = dx;
    f->p = *p;
    f->w = block;
    f->gx = block + n;
    f->gz = block + 2 * n;
    f->h = block + 3 * n;
    f->q = block + 4 * n;
    f->limit = block + 5 * n;
    f->held = block + 6 * n;
    f->wf = block + CELL_ARRAYS * n;
    f->Fh = f->wf + (n + 1);
    f->Fq = f->Fh + (n + 1);
    f->face_vol = f->Fq + (n + 1);
    for (size_t k = 0; k < n; k++) {
        double theta = atan(S[k]);
        f->w[k] = w[k];
        f->gx[k] = p->g * sin(theta);
        f->gz[k] = p->g * cos(theta);
    }
    f->wf[0] = w[0];
    f->wf[n] = w[n - 1];
    for (size_t k = 1; k < n; k++)
        f->wf[k] = 0.5 * (w[k - 1] + w[k]);
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

double *dfle_flow1d_h(dfle_flow1d *f) { return f->h; }
double *dfle_flow1d_q(dfle_flow1d *f) { return f->q; }
size_t dfle_flow1d_size(const dfle_flow1d *f) { return f->n; }

double dfle_flow1d_lambda(const dfle_flow1d *f, double h, double t)
{
    /* Eq. (9): 1 - erfc(2h/sqrt(4Dt)) = erf(h/sqrt(Dt)); lambda0 until the
     * flow has entered (t <= 0) or without diffusion (D = 0). */
    if (t <= 0 || f->p.D <= 0)
        return f->p.lambda0;
    return f->p.lambda0 * erf(h / sqrt(f->p.D * t));
}

double dfle_flow1d_phi(const dfle_flow1d *f, size_t k, double h, double v)
{
    const dfle_flow1d_params *p = &f->p;
    double P, I;
    if (!(h > p->h_dry))
        return p->mu_s;
    P = p->rho * f->gz[k] * h; /* basal normal stress [Pa] */
    I = (2.0 * fabs(v) / h) * p->D_eff / sqrt(P / p->rho_s);
    /* Eq. (10) written as (mu_2 - mu_s) I / (I0 + I): no 1/0 at rest. */
    return p->mu_s + (p->mu_2 - p->mu_s) * I / (p->I0 + I);
}

double dfle_flow1d_stable_dt(const dfle_flow1d *f)
{
    double smax = 0.0;
    for (size_t k = 0; k < f->n; k++) {
        double h = f->h[k];
        if (h > f->p.h_dry) {
            double s = fabs(f->q[k] / h) + sqrt(f->gz[k] * h);
            if (s > smax)
                smax = s;
        }
    }
    return smax > 0 ? f->p.cfl * f->dx / smax : INFINITY;
}

/* HLLC flux per unit width between states (hL, qL) and (hR, qR), with
 * each side's own g_z in its physical flux (Toro 2009, Ch. 10). */
static void hllc(double hL, double qL, double gL, double hR, double qR, double gR,
                 double h_dry, double *Fh, double *Fq)
{
    int dryL = !(hL > h_dry), dryR = !(hR > h_dry);
    double uL, uR, cL, cR, SL, SR, Ss, FhL, FqL, FhR, FqR;

    if (dryL && dryR) {
        *Fh = *Fq = 0.0;
        return;
    }
    if (dryL)
        hL = qL = 0.0;
    if (dryR)
        hR = qR = 0.0;
    uL = dryL ? 0.0 : qL / hL;
    uR = dryR ? 0.0 : qR / hR;
    cL = sqrt(gL * hL);
    cR = sqrt(gR * hR);
    if (dryL) { /* wet-dry front moving into the dry side */
        SL = uR - 2.0 * cR;
        SR = uR + cR;
    } else if (dryR) {
        SL = uL - cL;
        SR = uL + 2.0 * cL;
    } else {
        SL = fmin(uL - cL, uR - cR);
        SR = fmax(uL + cL, uR + cR);
    }
    FhL = hL * uL;
    FqL = hL * uL * uL + 0.5 * gL * hL * hL;
    FhR = hR * uR;
    FqR = hR * uR * uR + 0.5 * gR * hR * hR;
    if (SL >= 0) {
        *Fh = FhL, *Fq = FqL;
        return;
    }
    if (SR <= 0) {
        *Fh = FhR, *Fq = FqR;
        return;
    }
    Ss = (SL * hR * (uR - SR) - SR * hL * (uL - SL)) / (hR * (uR - SR) - hL * (uL - SL));
    if (Ss >= 0) {
        double hs = hL * (SL - uL) / (SL - Ss);
        *Fh = FhL + SL * (hs - hL);
        *Fq = FqL + SL * (hs * Ss - qL);
    } else {
        double hs = hR * (SR - uR) / (SR - Ss);
        *Fh = FhR + SR * (hs - hR);
        *Fq = FqR + SR * (hs * Ss - qR);
    }
}

/* Flux through a wall next to cell k: the mirror-state Riemann problem,
 * whose mass flux is zero by symmetry (set exactly). */
static void wall_flux(const dfle_flow1d *f, size_t k, int right_side, double *Fh, double *Fq)
{
    double h = f->h[k], q = f->q[k];
    if (right_side)
        hllc(h, q, f->gz[k], h, -q, f->gz[k], f->p.h_dry, Fh, Fq);
    else
        hllc(h, -q, f->gz[k], h, q, f->gz[k], f->p.h_dry, Fh, Fq);
    *Fh = 0.0;
}

static void compute_fluxes(dfle_flow1d *f)
{
    const size_t n = f->n;
    for (size_t k = 1; k < n; k++)
        hllc(f->h[k - 1], f->q[k - 1], f->gz[k - 1], f->h[k], f->q[k], f->gz[k], f->p.h_dry,
             &f->Fh[k], &f->Fq[k]);
    wall_flux(f, 0, 0, &f->Fh[0], &f->Fq[0]);
    if (!f->p.outlet_wall && f->h[n - 1] > f->p.h_dry && f->q[n - 1] >= 0) {
        /* Open outlet: the outside copies the last cell (no reflection). */
        double h = f->h[n - 1], u = f->q[n - 1] / h;
        f->Fh[n] = h * u;
        f->Fq[n] = h * u * u + 0.5 * f->gz[n - 1] * h * h;
    } else {
        /* Nothing flows back in through the outlet. */
        wall_flux(f, n - 1, 1, &f->Fh[n], &f->Fq[n]);
    }
}

/* Scale each cell's outgoing fluxes so that a step never takes more
 * volume than the cell holds; the scale of a face is its upwind cell's,
 * so the flux stays single-valued and volume conserved. */
static void limit_outflow(dfle_flow1d *f, double dt)
{
    const size_t n = f->n;
    for (size_t k = 0; k < n; k++) {
        double out = dt * (fmax(0.0, f->wf[k + 1] * f->Fh[k + 1]) + fmax(0.0, -f->wf[k] * f->Fh[k]));
        double vol = f->w[k] * f->h[k] * f->dx;
        f->limit[k] = out > vol ? vol / out : 1.0;
    }
    for (size_t k = 0; k <= n; k++) {
        double s;
        if (f->Fh[k] > 0)
            s = k > 0 ? f->limit[k - 1] : 1.0;
        else if (f->Fh[k] < 0)
            s = k < n ? f->limit[k] : 1.0;
        else
            continue;
        f->Fh[k] *= s;
        f->Fq[k] *= s;
    }
}

/* Momentum w q dx after the flux and explicit source terms of one step,
 * before drag and friction. */
static double momentum_after_fluxes(const dfle_flow1d *f, size_t k, double dt)
{
    const double wdx = f->w[k] * f->dx, h0 = f->h[k];
    double mom = wdx * f->q[k] - dt * (f->wf[k + 1] * f->Fq[k + 1] - f->wf[k] * f->Fq[k]);
    /* Wall pressure of the width change and gravity along the bed, g_x h. */
    return mom + dt * (0.5 * f->gz[k] * h0 * h0 * (f->wf[k + 1] - f->wf[k]) + wdx * f->gx[k] * h0);
}

/* A cell at rest stays at rest while friction can resist what pushes it
 * (a pile on a slope below its friction angle).  The Riemann fluxes know
 * nothing of friction and would still spill its edges into dry
 * neighbours, so no face may draw volume out of a held cell: there the
 * face is a wall.  Fluxes stay single-valued, volume stays conserved. */
static void hold_resting_cells(dfle_flow1d *f, double dt, double t_entry)
{
    const size_t n = f->n;
    for (size_t k = 0; k < n; k++) {
        double h = f->h[k], push, resist;
        f->held[k] = 0.0;
        if (!(h > f->p.h_dry) || f->q[k] != 0.0)
            continue;
        push = fabs(momentum_after_fluxes(f, k, dt)) / (f->w[k] * f->dx);
        resist = dt * (1.0 - dfle_flow1d_lambda(f, h, t_entry)) * f->gz[k] * h * f->p.mu_s;
        f->held[k] = push <= resist;
    }
    for (size_t k = 0; k <= n; k++) {
        if (f->Fh[k] > 0 && k > 0 && f->held[k - 1])
            wall_flux(f, k - 1, 1, &f->Fh[k], &f->Fq[k]);
        else if (f->Fh[k] < 0 && k < n && f->held[k])
            wall_flux(f, k, 0, &f->Fh[k], &f->Fq[k]);
    }
}

int dfle_flow1d_step(dfle_flow1d *f, double dt, double t_entry, double *outflow,
                     dfle_error *err)
{
    const dfle_flow1d_params *p = &f->p;
    const size_t n = f->n;
    const double dx = f->dx;

    if (!(dt > 0 && isfinite(dt)))
        return dfle_error_set(err, DFLE_EINVAL, "flow1d: time step must be > 0 s (got %g)", dt);
    compute_fluxes(f);
    hold_resting_cells(f, dt, t_entry);
    limit_outflow(f, dt);
    for (size_t k = 0; k <= n; k++)
        f->face_vol[k] = dt * f->wf[k] * f->Fh[k];
    for (size_t k = 0; k < n; k++) {
        const double wdx = f->w[k] * dx, h0 = f->h[k];
        double vol = wdx * h0 - (f->face_vol[k + 1] - f->face_vol[k]);
        double mom = momentum_after_fluxes(f, k, dt);
        double h, qs, fc;

        h = vol > 0 ? vol / wdx : 0.0; /* only round-off can make vol < 0 */
        f->h[k] = h;
        if (!(h > p->h_dry) || f->held[k] != 0.0) {
            f->q[k] = 0.0;
            continue;
        }
        qs = mom / wdx;
        /* Viscous pore-fluid drag 2 eta v_f v / (rho h), implicitly. */
        qs /= 1.0 + dt * 2.0 * p->eta * p->v_f / (p->rho * h * h);
        /* Coulomb friction (1 - lambda) g_z h phi(I): stop, never reverse.
         * phi comes from the speed at the start of the step (explicit, as
         * the paper's sources): from the speed after a whole step of free
         * acceleration it would jump towards mu_2 and stall every flow
         * that starts from rest. */
        fc = dt * (1.0 - dfle_flow1d_lambda(f, h, t_entry)) * f->gz[k] * h *
             dfle_flow1d_phi(f, k, h, h0 > p->h_dry ? f->q[k] / h0 : 0.0);
        f->q[k] = fabs(qs) <= fc ? 0.0 : qs - copysign(fc, qs);
        if (!isfinite(f->q[k]))
            return dfle_error_set(err, DFLE_ENUMERIC,
                                  "flow1d: discharge not finite in cell %zu (h = %g m)", k + 1, h);
    }
    *outflow = f->face_vol[n];
    return DFLE_OK;
}

double dfle_flow1d_volume(const dfle_flow1d *f, size_t k0, size_t k1)
{
    double v = 0.0;
    for (size_t k = k0; k < k1 && k < f->n; k++)
        v += f->w[k] * f->h[k] * f->dx;
    return v;
}

double dfle_flow1d_face_volume(const dfle_flow1d *f, size_t k)
{
    return k <= f->n ? f->face_vol[k] : 0.0;
}
