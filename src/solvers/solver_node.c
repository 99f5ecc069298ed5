/*
 * solver_node.c - the scalar root solve that the implicit and direct
 * solvers build on.
 *
 * Both solvers sweep the nodes one at a time: backward Euler from base
 * level up (the receiver's new elevation is already known), the steady
 * state from the heads down (the flow arriving from above is already
 * known).  Either way each node is one equation in its own slope,
 *
 *   U_eff = E(S) + c S,      E = E_f + E_df  (dfle_model_node_erosion),
 *
 * which has exactly one root when E is non-decreasing in S (every law
 * here; Theta is clamped at 0 where tau < tau_y, so E stays continuous).
 * The root is bracketed first, then found by Newton steps on ln(E + c S)
 * against ln S (nearly a straight line for power-law erosion, however
 * large alpha is) that fall back to geometric bisection whenever a step
 * would leave the bracket, so n_s < 1 (infinite dE/dS at 0), large alpha,
 * huge brackets (implicit steps of millions of years) and flat reaches
 * (E = 0) cannot make it stall or diverge; if it ever failed to
 * converge it says so rather than return a guess.
 */
#include <math.h>

#include "solvers/solver_internal.h"

#define SOLVE_MAX_ITER 200
#define SOLVE_REL_TOL 1e-10 /* slopes far beyond what tol = 1e-3 on dz/dt needs */
/* A slope below which a node is flat for any purpose here [-]: 5e-12 m
 * of drop over a 5 m node.  If erosion alone still exceeds U_eff there,
 * no positive slope balances it. */
#define SLOPE_FLOOR 1e-12

/* G(S) = E(S) + c S, non-decreasing in S. */
static int total(dfle_model *m, size_t i, double S, double c, double flows, double *G,
                 int *goes_on, dfle_error *err)
{
    double E;
    int st = dfle_model_node_erosion(m, i, S, flows, &E, goes_on, err);
    *G = E + c * S;
    return st;
}

int dfle_solve_node(dfle_model *m, size_t i, double U_eff, double c, double flows, double guess,
                    double *S_out, int *goes_on, dfle_error *err)
{
    int on = 0, on2;
    const double log_target = log(U_eff);
    double lo = 0.0, hi, G, S, lnS_prev = 0.0, phi_prev = 0.0;
    int st;

    if (goes_on != NULL)
        *goes_on = 0;
    if (c > 0 && U_eff <= 0) {
        *S_out = U_eff / c; /* sinks below its neighbour: no erosion */
        return DFLE_OK;
    }
    if (!(U_eff > 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: no slope balances U = %g at node %zu",
                              U_eff, i + 1);
    /* Bracket: G(0) = 0 < U_eff.  With c > 0 the erosion-free slope
     * U_eff/c bounds the root; otherwise grow from the guess. */
    if (c > 0) {
        hi = U_eff / c;
    } else {
        hi = guess > 0 ? 1.1 * guess : 1.0;
        for (;;) {
            if ((st = total(m, i, hi, c, flows, &G, &on, err)) != DFLE_OK)
                return st;
            if (G >= U_eff)
                break;
            lo = hi;
            hi *= 2.0;
            if (hi > 1e6) /* steeper than 89.9999 degrees: no slope does it */
                return dfle_error_set(err, DFLE_EFIT,
                                      "model: erosion never reaches U at node %zu (x = %g m): "
                                      "no steady slope there",
                                      i + 1, dfle_network_x(dfle_model_network(m))[i]);
        }
    }
    /* Newton on ln G against ln S, which is close to a straight line for
     * power-law erosion, so a few steps reach the root from anywhere in
     * the bracket; a step that leaves the bracket is replaced by a
     * geometric bisection. */
    S = guess > lo && guess < hi ? guess : (lo > 0 ? sqrt(lo * hi) : 0.5 * hi);
    for (int it = 0; it < SOLVE_MAX_ITER; it++) {
        double phi, next;
        if ((st = total(m, i, S, c, flows, &G, &on, err)) != DFLE_OK)
            return st;
        if (goes_on != NULL)
            *goes_on = on; /* the verdict at the last slope tried */
        if (G == U_eff) {
            *S_out = S;
            return DFLE_OK;
        }
        if (G < U_eff) {
            lo = S;
        } else {
            hi = S;
            /* Erosion that exceeds U_eff at every slope down to the floor
             * does not grow with slope (alpha = 0 with tau_y = 0 gives
             * E_df ~ h ~ S^(-1/3), unbounded as S -> 0): the bracket would
             * only close on S = 0.  Not a root, and not a numerical
             * failure either: say which it is, as a slope that cannot
             * balance U (the direct method then falls back). */
            if (lo == 0 && hi < SLOPE_FLOOR && G - c * S >= U_eff)
                return dfle_error_set(
                    err, DFLE_EFIT,
                    "model: at node %zu (x = %g m) erosion exceeds %g m/yr at every slope down "
                    "to 1e-12: it does not grow with slope (alpha = 0 with tau_y = 0 does that), "
                    "so no slope balances it",
                    i + 1, dfle_network_x(dfle_model_network(m))[i], U_eff);
        }
        phi = G > 0 ? log(G) - log_target : -INFINITY;
        next = -1.0;
        if (isfinite(phi)) {
            double slope = 0.0; /* d ln G / d ln S */
            if (isfinite(phi_prev) && phi_prev != phi && it > 0) {
                slope = (phi - phi_prev) / (log(S) - lnS_prev); /* secant */
            } else {
                double G2, h = 1e-7;
                if ((st = total(m, i, S * (1.0 + h), c, flows, &G2, &on2, err)) != DFLE_OK)
                    return st;
                if (G2 > G)
                    slope = (log(G2) - log(G)) / log1p(h);
            }
            if (slope > 0)
                next = S * exp(-phi / slope);
        }
        lnS_prev = log(S);
        phi_prev = phi;
        if (!(next > lo && next < hi))
            next = lo > 0 ? sqrt(lo * hi) : 0.5 * hi;
        if (fabs(next - S) <= SOLVE_REL_TOL * S || (hi - lo) <= SOLVE_REL_TOL * hi) {
            *S_out = next;
            return DFLE_OK;
        }
        S = next;
    }
    return dfle_error_set(err, DFLE_ENUMERIC,
                          "model: the slope at node %zu (x = %g m) did not converge (bracket "
                          "[%g, %g])", i + 1, dfle_network_x(dfle_model_network(m))[i], lo, hi);
}

int dfle_solver_node_slope(dfle_model *m, size_t i, double U_eff, double c, double flows,
                           double guess, double *S, int *goes_on, dfle_error *err)
{
    return dfle_solve_node(m, i, U_eff, c, flows, guess, S, goes_on, err);
}
