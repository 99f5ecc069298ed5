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
 * Both paths below take Newton steps on ln(E + c S) against ln S (nearly
 * a straight line for power-law erosion, however large alpha is) inside
 * a bracket, with a geometric bisection whenever a step would leave it,
 * so n_s < 1 (infinite dE/dS at 0), large alpha, huge brackets (implicit
 * steps of millions of years) and flat reaches (E = 0) cannot make them
 * stall or diverge; a solve that does not converge says so rather than
 * return a guess.  They differ in where the slope of ln E comes from:
 *
 *  - exact, when the router and the law give dE/d ln S (their optional
 *    node_flow_dlnS and rate_dlnS ops; every built-in one does, and a
 *    compiled Lua law differentiates its programs, doc/laws.md): one
 *    evaluation per step and a stopping rule that predicts the error of
 *    the step it is about to take, about 2.15 evaluations per node of a
 *    steady state (solve_newton);
 *  - otherwise from values alone (routers written in Lua, laws run as
 *    Lua): the
 *    root is bracketed first, then a difference derivative and secant
 *    slopes, until a step is below the tolerance, about 6.6 evaluations
 *    per node (solve_secant).
 *
 * Tolerance: 1e-10 relative in S on either path.
 */
#include <math.h>

#include "solvers/solver_internal.h"

#define SOLVE_MAX_ITER 200
#define SOLVE_REL_TOL 1e-10 /* slopes far beyond what tol = 1e-3 on dz/dt needs */
/* Newton's stopping rule accepts a slope whose predicted error is below
 * this: a hundredth of the tolerance, a margin for the estimate of the
 * curvature (from two points) it rests on. */
#define NEWTON_PREDICTED_TOL (0.01 * SOLVE_REL_TOL)
/* A derivative whose mean over the last move differs from the secant by
 * more than this (relative) is not the derivative of these values. */
#define DERIV_MISMATCH_MAX 0.25
/* A slope below which a node is flat for any purpose here [-]: 5e-12 m
 * of drop over a 5 m node.  If erosion alone still exceeds U_eff there,
 * no positive slope balances it. */
#define SLOPE_FLOOR 1e-12

/* Steeper than 89.9999 degrees [-]: if erosion is still below U_eff
 * there, no slope balances it. */
#define SLOPE_CEIL 1e6

static double node_x(dfle_model *m, size_t i)
{
    return dfle_network_x(dfle_model_network(m))[i];
}

static int never_reaches(dfle_model *m, size_t i, dfle_error *err)
{
    return dfle_error_set(err, DFLE_EFIT,
                          "model: erosion never reaches U at node %zu (x = %g m): no steady "
                          "slope there",
                          i + 1, node_x(m, i));
}

/* Erosion that exceeds U_eff at every slope down to the floor does not
 * grow with slope (alpha = 0 with tau_y = 0 gives E_df ~ h ~ S^(-1/3),
 * unbounded as S -> 0): the bracket would only close on S = 0.  Not a
 * root, and not a numerical failure either: say which it is, as a slope
 * that cannot balance U (the direct method then falls back). */
static int does_not_grow(dfle_model *m, size_t i, double U_eff, dfle_error *err)
{
    return dfle_error_set(err, DFLE_EFIT,
                          "model: at node %zu (x = %g m) erosion exceeds %g m/yr at every slope "
                          "down to 1e-12: it does not grow with slope (alpha = 0 with tau_y = 0 "
                          "does that), so no slope balances it",
                          i + 1, node_x(m, i), U_eff);
}

/* Slope S gives G = E + c S: the side of the root it lies on narrows the
 * bracket [lo, hi]. */
static int narrow(dfle_model *m, size_t i, double S, double G, double E, double U_eff,
                  double *lo, double *hi, dfle_error *err)
{
    if (G < U_eff) {
        *lo = S;
        return DFLE_OK;
    }
    *hi = S;
    return *lo == 0 && *hi < SLOPE_FLOOR && E >= U_eff ? does_not_grow(m, i, U_eff, err)
                                                         : DFLE_OK;
}

static int no_convergence(dfle_model *m, size_t i, double lo, double hi, dfle_error *err)
{
    return dfle_error_set(err, DFLE_ENUMERIC,
                          "model: the slope at node %zu (x = %g m) did not converge (bracket "
                          "[%g, %g])",
                          i + 1, node_x(m, i), lo, hi);
}

/* G(S) = E(S) + c S, non-decreasing in S. */
static int total(dfle_model *m, size_t i, double S, double c, double flows, double *G,
                 int *goes_on, dfle_error *err)
{
    double E;
    int st = dfle_model_node_erosion(m, i, S, flows, &E, goes_on, err);
    *G = E + c * S;
    return st;
}

/* The path for erosion known only by its values (a law or router
 * without the derivative ops): the root is bracketed, then Newton steps
 * with a difference derivative first and secant slopes after, until a
 * step or the bracket is below the tolerance. */
static int solve_secant(dfle_model *m, size_t i, double U_eff, double c, double flows,
                        double guess, double *S_out, int *goes_on, dfle_error *err)
{
    int on = 0, on2;
    const double log_target = log(U_eff);
    double lo = 0.0, hi, G, S, lnS_prev = 0.0, phi_prev = 0.0;
    int st;

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
            if (hi > SLOPE_CEIL)
                return never_reaches(m, i, err);
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
        if ((st = narrow(m, i, S, G, G - c * S, U_eff, &lo, &hi, err)) != DFLE_OK)
            return st;
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
    return no_convergence(m, i, lo, hi, err);
}

/* Newton in x = ln S on phi(x) = ln G - ln U_eff with the exact
 * phi' = (dE/d ln S + c S) / G (dfle_model_node_erosion_dlnS), one
 * evaluation per step.  Safeguards: the bracket [lo, hi] of slopes known
 * to give too little and too much (open above until a slope gives too
 * much when c = 0); a geometric bisection replaces any step that leaves
 * it or is more than half the step before last (so the bracket at least
 * halves every two steps, whatever E does: kinks and jumps where the
 * flow stops, Theta -> 0); without a usable derivative (G = 0, dG <= 0)
 * and no upper bound yet, the slope doubles.
 *
 * Stopping without a wasted evaluation: Newton's error after a step
 * delta is e' = K delta^2 with K = |phi'' / (2 phi')| near the root, so
 * the next slope is accepted unevaluated when K delta^2 is below a
 * hundredth of the tolerance, K estimated from the derivatives of this
 * and the last evaluation (their difference over their distance; both
 * on the same side of the runout rule, or the estimate would measure a
 * kink, not a curvature).  The margin covers an estimate of K from two
 * points some way from the root.  With it, and the check below, the
 * error of every accepted slope of the Fig. 9 steady state is below
 * 2e-14, at 2.15 evaluations per node (2.11 and 1e-12 without the
 * check).  A step already below the tolerance ends the solve too.
 * ln G is close to a straight line in ln S (a sum of powers of S), so K
 * is small and the second evaluation usually ends the solve from a
 * neighbour's slope: a first evaluation has no K to go by.
 *
 * The derivative is checked against the values: between two
 * evaluations on the same side of the runout rule the secant of phi
 * equals the mean of the two derivatives to phi''' delta^2 / 12 (the
 * trapezoid rule).  Their relative mismatch mu adds mu |delta| to the
 * predicted error (a derivative wrong by mu moves Newton's step by about
 * that much), and a mismatch above DERIV_MISMATCH_MAX marks the
 * derivative as wrong: that step bisects (or doubles) instead.  So an op
 * that gives a wrong derivative costs evaluations, not accuracy; with
 * the exact one the term is far below the tolerance and changes
 * nothing. */
static int solve_newton(dfle_model *m, size_t i, double U_eff, double c, double flows,
                        double guess, double *S_out, int *goes_on, dfle_error *err)
{
    const double log_target = log(U_eff);
    double lo = 0.0, hi = c > 0 ? U_eff / c : INFINITY, S, x;
    double moved = INFINITY, dphi_prev = NAN; /* the last move in ln S, phi' before it */
    double phi_prev = NAN;                /* phi before it                 */
    double moved_prev = INFINITY;         /* |the move before that| */
    int on_prev = -1;

    /* x = ln S is kept along (a move adds to it), so each step costs one
     * log (of G) and one exp. */
    S = guess > lo && guess < hi ? guess : (c > 0 ? 0.5 * hi : 1.0);
    x = log(S);
    for (int it = 0; it < SOLVE_MAX_ITER; it++) {
        double E, dE, G, phi = NAN, dphi = NAN, step = NAN, next, x_next;
        double mismatch = NAN; /* mu (above), when there is a last evaluation */
        int on, st, newton = 0, checked = 0;
        if ((st = dfle_model_node_erosion_dlnS(m, i, S, x, flows, &E, &dE, &on, err)) != DFLE_OK)
            return st;
        if (goes_on != NULL)
            *goes_on = on; /* the verdict at the last slope tried */
        G = E + c * S;
        if (G == U_eff) {
            *S_out = S;
            return DFLE_OK;
        }
        if ((st = narrow(m, i, S, G, E, U_eff, &lo, &hi, err)) != DFLE_OK)
            return st;
        if (G > 0) {
            phi = log(G) - log_target;
            dphi = (dE + c * S) / G;
            if (on == on_prev && dphi_prev > 0 && isfinite(phi_prev) && isfinite(moved) &&
                moved != 0) {
                mismatch = fabs((phi - phi_prev) / moved - 0.5 * (dphi + dphi_prev)) / dphi;
                checked = 1;
            }
            if (dphi > 0 && isfinite(dphi) && (!checked || mismatch <= DERIV_MISMATCH_MAX)) {
                step = -phi / dphi;
                newton = 1;
            }
        }
        next = newton ? S * exp(step) : NAN;
        x_next = x + step;
        if (newton && fabs(step) <= SOLVE_REL_TOL) {
            /* S is the root to the tolerance: a step this small may even
             * round to S itself, a bound of the bracket. */
            *S_out = next;
            return DFLE_OK;
        }
        if (isinf(hi)) {
            /* Nothing too steep yet: go up, by Newton or by doubling. */
            if (!newton)
                next = 2.0 * S, x_next = log(next);
            if (next > SLOPE_CEIL) {
                if (S >= SLOPE_CEIL)
                    return never_reaches(m, i, err);
                next = SLOPE_CEIL, x_next = log(SLOPE_CEIL);
                newton = 0; /* a cut step predicts nothing */
            }
        } else {
            if (!(next > lo && next < hi) || !(fabs(step) <= 0.5 * moved_prev)) {
                next = lo > 0 ? sqrt(lo * hi) : 0.5 * hi;
                x_next = log(next);
                newton = 0;
            }
            if (hi - lo <= SOLVE_REL_TOL * hi) {
                *S_out = next;
                return DFLE_OK;
            }
        }
        if (newton && checked) {
            /* The error predicted for next, K delta^2 + mu |delta|
             * (above). */
            double K = fabs(dphi - dphi_prev) / (2.0 * dphi * fabs(moved));
            if (K * step * step + mismatch * fabs(step) <= NEWTON_PREDICTED_TOL) {
                *S_out = next;
                return DFLE_OK;
            }
        }
        moved_prev = fabs(moved);
        moved = x_next - x;
        dphi_prev = dphi, phi_prev = phi, on_prev = on;
        S = next, x = x_next;
    }
    return no_convergence(m, i, lo, hi, err);
}

/* The checks both paths share, then the path: Newton when `newton` and
 * the model can give dE/d ln S. */
static int solve_node(dfle_model *m, size_t i, double U_eff, double c, double flows,
                      double guess, int newton, double *S_out, int *goes_on, dfle_error *err)
{
    if (goes_on != NULL)
        *goes_on = 0;
    if (c > 0 && U_eff <= 0) {
        *S_out = U_eff / c; /* sinks below its neighbour: no erosion */
        return DFLE_OK;
    }
    if (!(U_eff > 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: no slope balances U = %g at node %zu",
                              U_eff, i + 1);
    if (newton && dfle_model_node_dlnS(m))
        return solve_newton(m, i, U_eff, c, flows, guess, S_out, goes_on, err);
    return solve_secant(m, i, U_eff, c, flows, guess, S_out, goes_on, err);
}

int dfle_solve_node(dfle_model *m, size_t i, double U_eff, double c, double flows, double guess,
                    double *S_out, int *goes_on, dfle_error *err)
{
    /* Newton where the flow follows the slope (a router routed every
     * step, or none).  A router routed rarely keeps the difference path:
     * there routing is the cost, not these solves, and the rounds of a
     * direct steady state settle only to direct_tol, so slopes moved by
     * 1e-10 in one round can settle elsewhere within it (2 of the 24
     * process samples of examples/ensemble_alpha_beta.lua moved by 0.4
     * and 3 % in S_df): their results stay as they were. */
    const dfle_router *rt = dfle_model_router(m);
    return solve_node(m, i, U_eff, c, flows, guess, rt == NULL || dfle_router_is_local(rt), S_out,
                      goes_on, err);
}

int dfle_solver_node_slope(dfle_model *m, size_t i, double U_eff, double c, double flows,
                           double guess, double *S, int *goes_on, dfle_error *err)
{
    /* A landscape's sweeps take the solvers' path: Newton needs a third
     * of the evaluations, the cost of a debris-flow step's reached
     * cells.  Slopes move by up to the values path's 1e-10 relative; a
     * landscape still re-routing may carry that into which cell drains
     * where, within the steady-state rules' tolerance. */
    return dfle_solve_node(m, i, U_eff, c, flows, guess, S, goes_on, err);
}
