/*
 * landscape_diffuse.c - hillslope diffusion (hillslope = "diffusion"):
 * the 9-point Laplacian of the surface, and the implicit step that
 * solves (z' - z)/dt = D lap(z') on the hillslope cells by conjugate
 * gradients, channel and base cells held (landscape_step.c calls it
 * after each sweep; landscape_direct.c with dt = INFINITY for the
 * hillslopes' steady state; the explicit step reads the Laplacian).
 */
#include "landscape/landscape_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The 9-point Laplacian (isotropic for dx = dy): weight 2/3 over the
 * sides' squared distances and 1/3 over the diagonals', so every D8
 * receiver is a neighbour of the stencil and no block of hillslope cells
 * is cut off from the channel cells that hold it.  Fluxes to NoData or
 * off the grid are zero. */
static double stencil_weight(const dfle_landscape *ls, int k)
{
    return (k % 2 == 0 ? 2.0 / 3.0 : 1.0 / 3.0) / (ls->len[k] * ls->len[k]);
}

double ls_laplacian(const dfle_landscape *ls, size_t c)
{
    double s = 0.0;
    for (int k = 0; k < 8; k++) {
        long long j = dfle_drainage_neighbour(ls->dr, c, k);
        if (j >= 0 && !isnan(ls->z[j]))
            s += stencil_weight(ls, k) * (ls->z[j] - ls->z[c]);
    }
    return ls->o.D * s;
}

/* Conjugate gradients with a Jacobi preconditioner on the hillslope
 * cells (the unknowns); channel and base cells are held. */
int ls_diffuse(dfle_landscape *ls, double dt, dfle_error *err)
{
    const size_t n = ls->n;
    const uint32_t *rcv;
    const double *A;
    const double D = ls->o.D, inv_dt = isinf(dt) ? 0.0 : 1.0 / dt;
    double *blk, *x, *r, *p, *q, *dg, rz = 0, b2 = 0;
    unsigned char *unk;
    size_t n_unk = 0;
    int st;

    if ((st = ls_route(ls, err)) != DFLE_OK)
        return st;
    rcv = dfle_drainage_receivers(ls->dr);
    A = dfle_drainage_area(ls->dr);
    blk = malloc(5 * n * sizeof *blk);
    unk = malloc(n);
    if (blk == NULL || unk == NULL) {
        free(blk);
        free(unk);
        return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory for diffusion");
    }
    x = blk, r = blk + n, p = blk + 2 * n, q = blk + 3 * n, dg = blk + 4 * n;
    for (size_t c = 0; c < n; c++) {
        unk[c] = !isnan(ls->z[c]) && rcv[c] != c && !(A[c] >= ls->o.A0);
        n_unk += unk[c];
    }
    /* b = z / dt (U for the steady state) + D sum w z_fixed; x0 = z. */
    for (size_t c = 0; c < n; c++) {
        double b, d = inv_dt;
        if (!unk[c])
            continue;
        b = isinf(dt) ? ls_value(&ls->U, c) : ls->z[c] * inv_dt;
        for (int k = 0; k < 8; k++) {
            long long j = dfle_drainage_neighbour(ls->dr, c, k);
            if (j < 0 || isnan(ls->z[j]))
                continue;
            d += D * stencil_weight(ls, k);
            if (!unk[j])
                b += D * stencil_weight(ls, k) * ls->z[j];
        }
        dg[c] = d;
        x[c] = ls->z[c];
        r[c] = b; /* minus A x below */
        b2 += b * b;
    }
#define APPLY(v, out)                                                             \
    for (size_t c = 0; c < n; c++) {                                              \
        double s_;                                                                \
        if (!unk[c])                                                              \
            continue;                                                             \
        s_ = dg[c] * (v)[c];                                                      \
        for (int k = 0; k < 8; k++) {                                             \
            long long j = dfle_drainage_neighbour(ls->dr, c, k);                  \
            if (j >= 0 && unk[j])                                                 \
                s_ -= D * stencil_weight(ls, k) * (v)[j];                         \
        }                                                                         \
        (out)[c] = s_;                                                            \
    }
    APPLY(x, q)
    for (size_t c = 0; c < n; c++)
        if (unk[c]) {
            r[c] -= q[c];
            p[c] = r[c] / dg[c];
            rz += r[c] * p[c];
        }
    st = DFLE_OK;
    for (size_t it = 0; n_unk > 0; it++) {
        double pq = 0, alpha, rz_new = 0, rr = 0;
        if (it > 20000 + 10 * n_unk) {
            st = dfle_error_set(err, DFLE_ENUMERIC, "landscape: hillslope diffusion did not "
                                "converge in %zu iterations", it);
            break;
        }
        APPLY(p, q)
        for (size_t c = 0; c < n; c++)
            if (unk[c])
                pq += p[c] * q[c];
        if (!(pq > 0))
            break;
        alpha = rz / pq;
        for (size_t c = 0; c < n; c++)
            if (unk[c]) {
                x[c] += alpha * p[c];
                r[c] -= alpha * q[c];
                rr += r[c] * r[c];
                rz_new += r[c] * r[c] / dg[c];
            }
        if (rr <= 1e-26 * b2)
            break;
        for (size_t c = 0; c < n; c++)
            if (unk[c])
                p[c] = r[c] / dg[c] + rz_new / rz * p[c];
        rz = rz_new;
    }
#undef APPLY
    if (st == DFLE_OK)
        for (size_t c = 0; c < n; c++)
            if (unk[c]) {
                if (!isinf(dt))
                    ls->dzdt[c] += (float)((x[c] - ls->z[c]) / dt);
                ls->z[c] = x[c];
            }
    ls->routed = 0;
    ls->model_z_current = 0;
    free(blk);
    free(unk);
    return st;
}
