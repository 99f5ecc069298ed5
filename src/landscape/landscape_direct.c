/*
 * landscape_direct.c - one round of the direct steady state: the steady
 * surface of the network the current surface routes to.
 *
 *  - Channel cells (A >= A_0) get their steady slope from the heads
 *    down: every cell after its donors, so the debris flows arriving at
 *    a cell are known when it is solved.  Rivers alone: E_f = U gives
 *    S = (U / K A^m)^(1/n).  Where flows arrive: the model's per-node
 *    root solve of E_f + E_df = U (solver.h, dfle_solver_node_slope),
 *    which also says whether the flows go on (tau >= tau_y at that
 *    slope: exactly the runout rule).  With threshold hillslopes and
 *    cap_channels, a slope above S_c is held at S_c and the flows go on
 *    or stop by their verdict there (a head steeper than the hillslope
 *    beside it loses its donors to it, and back, every round: no steady
 *    network; doc/landscape.md).  Elevations then follow from base
 *    level up, z = z_r + S L, in stack order.
 *  - Threshold hillslopes (A < A_0).  A hillslope cell rises with U
 *    until it stands S_c above its steepest-descent receiver, so at
 *    steady state it stands at
 *        z_i = min over its neighbours j of (z_j + S_c L_ij),
 *    its receiver being the steepest exactly when no neighbour offers a
 *    lower cap.  Given the channels, that is a shortest-path problem
 *    from the channel and base-level cells (a chamfer distance, in
 *    metres of elevation), solved here by raster sweeps: forward, each
 *    cell from its W, NW, N, NE neighbours, then backward from E, SE,
 *    S, SW, until a pair of sweeps changes nothing.  A sweep carries a
 *    lowering any distance along its own direction, so hillslopes
 *    between channels settle in a few pairs; a path that must turn
 *    against the sweeps takes one pair more per turn (Bellman-Ford's
 *    bound: at most one pair per cell, never approached).  Building the
 *    hillslopes on the receivers of the last routing instead, z = z_r +
 *    S_c L, leaves most of them above a lower neighbour; re-routing then
 *    lowers them one cell per round, which made the rounds on a 200 x
 *    200 grid drift for more than 60 rounds without settling.
 *  - Diffusive hillslopes: built at S_c on the receivers, then the
 *    steady state D lap(z) = -U between the channels (ls_diffuse).
 */
#include "landscape/landscape_internal.h"

#include <math.h>
#include <stdlib.h>

/* One cell of a sweep: lower z[i] to the least z_j + S_c L over the
 * four neighbours k0..k0+3 (those already swept); 1 when it moved. */
static int relax_cell(const dfle_landscape *ls, double *z, size_t r, size_t c, int k0,
                      const int *drow, const int *dcol, const long long *step, const double *w)
{
    const size_t i = r * ls->nx + c;
    double best = z[i];
    if (r > 0 && c > 0 && r + 1 < ls->ny && c + 1 < ls->nx) {
        for (int k = k0; k < k0 + 4; k++) {
            const double v = z[(long long)i + step[k]] + w[k]; /* NaN: never less */
            best = v < best ? v : best;
        }
    } else {
        for (int k = k0; k < k0 + 4; k++) {
            const long long rr = (long long)r + drow[k], cc = (long long)c + dcol[k];
            double v;
            if (rr < 0 || cc < 0 || rr >= (long long)ls->ny || cc >= (long long)ls->nx)
                continue;
            v = z[rr * (long long)ls->nx + cc] + w[k];
            best = v < best ? v : best;
        }
    }
    if (best < z[i]) {
        z[i] = best;
        return 1;
    }
    return 0;
}

/* Lower each hillslope cell (free[c]) to min over its neighbours of
 * z_j + S_c L; free cells start at an upper bound (S_c L steps down
 * their receivers: one path among those the minimum is over), every
 * other data cell is held.  Neighbours k = 4..7 (W, NW, N, NE) come
 * before a cell in row-major order, k = 0..3 (E, SE, S, SW) after it. */
static int relax_hillslopes(dfle_landscape *ls, const unsigned char *free_, dfle_error *err)
{
    static const int drow[8] = {0, 1, 1, 1, 0, -1, -1, -1};
    static const int dcol[8] = {1, 1, 0, -1, -1, -1, 0, 1};
    const size_t nx = ls->nx, ny = ls->ny;
    double *z = ls->z, w[8];
    long long step[8];
    for (int k = 0; k < 8; k++) {
        w[k] = ls->o.S_c * ls->len[k];
        step[k] = drow[k] * (long long)nx + dcol[k];
    }
    /* Only the box around the free cells is swept (a DEM's catchment
     * may fill a tenth of its grid). */
    size_t r_lo = ny, r_hi = 0, c_lo = nx, c_hi = 0;
    for (size_t r = 0; r < ny; r++)
        for (size_t c = 0; c < nx; c++)
            if (free_[r * nx + c]) {
                r_lo = r < r_lo ? r : r_lo, r_hi = r > r_hi ? r : r_hi;
                c_lo = c < c_lo ? c : c_lo, c_hi = c > c_hi ? c : c_hi;
            }
    if (r_lo > r_hi)
        return DFLE_OK; /* no hillslope cell */
    for (size_t pair = 0; pair <= ls->n_data; pair++) {
        int changed = 0;
        for (int back = 0; back < 2; back++) { /* forward from W, NW, N, NE; back from E, ... */
            const int k0 = back ? 0 : 4;
            for (size_t q = r_lo; q <= r_hi; q++) {
                const size_t r = back ? r_lo + r_hi - q : q;
                const int edge_row = r == 0 || r + 1 == ny;
                const unsigned char *fr = free_ + r * nx;
                double *zr = z + r * nx;
                for (size_t p = c_lo; p <= c_hi; p++) {
                    const size_t c = back ? c_lo + c_hi - p : p;
                    double best;
                    if (!fr[c])
                        continue;
                    if (edge_row || c == 0 || c + 1 == nx) { /* bounds checked */
                        changed |= relax_cell(ls, z, r, c, k0, drow, dcol, step, w);
                        continue;
                    }
                    best = zr[c];
                    for (int k = k0; k < k0 + 4; k++) {
                        const double v = zr[(long long)c + step[k]] + w[k]; /* NaN: never less */
                        best = v < best ? v : best;
                    }
                    if (best < zr[c]) {
                        zr[c] = best;
                        changed = 1;
                    }
                }
            }
        }
        if (!changed)
            return DFLE_OK;
    }
    return dfle_error_set(err, DFLE_ENUMERIC, "landscape: the threshold hillslopes did not "
                          "settle in %zu sweeps; this is a bug in dfle", 2 * ls->n_data + 2);
}

/* The steady slope of every channel cell, from the heads down, into S
 * (S_c elsewhere). */
static int channel_slopes(dfle_landscape *ls, double *S, double *flows, dfle_error *err)
{
    const uint32_t *rcv = dfle_drainage_receivers(ls->dr);
    const unsigned char *dir = dfle_drainage_dir(ls->dr);
    const double *A = dfle_drainage_area(ls->dr);
    size_t n_stack;
    const uint32_t *stack = dfle_drainage_stack(ls->dr, &n_stack);
    int st;

    if (ls->model != NULL) {
        const unsigned char *src = dfle_network_sources(ls->net);
        for (size_t k = 0; k < ls->n_data; k++)
            flows[k] = src[k];
    }
    const int cap = ls->o.hillslope == DFLE_HILLSLOPE_THRESHOLD && ls->o.cap_channels;
    for (size_t k = n_stack; k-- > 0;) {
        const size_t c = stack[k], r = rcv[c];
        const double U = ls_value(&ls->U, c);
        if (r == c)
            continue;
        if (!(A[c] >= ls->o.A0)) {
            if (ls->o.hillslope == DFLE_HILLSLOPE_UPLIFT)
                return dfle_error_set(err, DFLE_EFIT, "landscape: hillslopes that only rise with "
                                      "uplift (hillslope = uplift) have no steady state");
            S[c] = ls->o.S_c;
            continue;
        }
        if (flows != NULL && flows[ls->node_of[c]] > 0) {
            /* The slope now, which after the first rounds is the last
             * round's root, or close to it: two or three iterations. */
            const double S0 = (ls->z[c] - ls->z[r]) / ls->len[dir[c]];
            const size_t node = ls->node_of[c];
            int goes_on = 0;
            st = dfle_solver_node_slope(ls->model, node, U, 0.0, flows[node], S0 > 0 ? S0 : 0.1,
                                        &S[c], &goes_on, err);
            if (st != DFLE_OK)
                return st;
            if (cap && S[c] > ls->o.S_c) {
                /* Held at S_c (E < U there: the rest fails as a
                 * hillslope does); whether the flows go on is decided
                 * at that slope, as the model's routing of this surface
                 * will decide it. */
                double E;
                S[c] = ls->o.S_c;
                st = dfle_model_node_erosion(ls->model, node, S[c], flows[node], &E, &goes_on,
                                             err);
                if (st != DFLE_OK)
                    return st;
            }
            if (goes_on)
                flows[ls->node_of[r]] += flows[node];
        } else {
            const double Kc = ls->K * ls_value(&ls->K_scale, c);
            if (!(Kc > 0))
                return dfle_error_set(err, DFLE_EFIT, "landscape: channel cell %zu (row %zu, "
                                      "column %zu, A = %g m^2) has no steady slope: no fluvial "
                                      "erosion and no debris flow reaches it", c, c / ls->nx,
                                      c % ls->nx, A[c]);
            S[c] = pow(U / (Kc * pow(A[c], ls->m_exp)), 1.0 / ls->n_exp);
            if (cap && S[c] > ls->o.S_c)
                S[c] = ls->o.S_c;
        }
    }
    return DFLE_OK;
}

int ls_direct_round(dfle_landscape *ls, dfle_error *err)
{
    const uint32_t *rcv, *stack;
    const unsigned char *dir;
    const double *A;
    const int threshold = ls->o.hillslope == DFLE_HILLSLOPE_THRESHOLD;
    double *S, *flows = NULL;
    unsigned char *free_ = NULL;
    size_t n_stack;
    int st;

    if ((st = ls_route(ls, err)) != DFLE_OK)
        return st;
    S = malloc(ls->n * sizeof *S);
    if (ls->model != NULL)
        flows = malloc(ls->n_data * sizeof *flows);
    if (threshold)
        free_ = malloc(ls->n);
    if (S == NULL || (ls->model != NULL && flows == NULL) || (threshold && free_ == NULL)) {
        st = dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory");
        goto done;
    }
    if ((st = channel_slopes(ls, S, flows, err)) != DFLE_OK)
        goto done;
    rcv = dfle_drainage_receivers(ls->dr);
    dir = dfle_drainage_dir(ls->dr);
    A = dfle_drainage_area(ls->dr);
    stack = dfle_drainage_stack(ls->dr, &n_stack);
    if (threshold)
        for (size_t c = 0; c < ls->n; c++)
            free_[c] = 0;
    /* Base level up: a channel's receiver is a channel or a root. */
    for (size_t k = 0; k < n_stack; k++) {
        const size_t c = stack[k], r = rcv[c];
        if (r == c)
            continue;
        if (threshold && !(A[c] >= ls->o.A0))
            free_[c] = 1; /* S[c] = S_c: an upper bound, lowered below */
        ls->z[c] = ls->z[r] + S[c] * ls->len[dir[c]];
    }
    if (threshold)
        st = relax_hillslopes(ls, free_, err);
    ls->routed = 0;
    ls->model_z_current = 0;
    ls->have_rates = 0;
    ls->evolved = 1;
    if (st == DFLE_OK && ls->o.hillslope == DFLE_HILLSLOPE_DIFFUSION) {
        /* The hillslopes between the channels just built. */
        ls->routed = 1; /* the receivers are those of this round */
        st = ls_diffuse(ls, INFINITY, err);
        ls->routed = 0;
    }
done:
    free(S);
    free(flows);
    free(free_);
    return st;
}
