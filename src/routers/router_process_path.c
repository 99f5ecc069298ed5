/*
 * router_process_path.c - one debris flow routed down one path of cells
 * with the two-phase solver (flow1d.h): the work of the process-based
 * router, whether the path is the single channel of a 1D model or the
 * receivers below one channel head of a network.
 *
 * The path gets n_ghost ghost cells above its head (the head's width,
 * slope and cell length), the pile of volume M0 on them, and the flow
 * is stepped until it has left or come to rest (router_process.h states
 * the criterion), the erosion law's integrand summed over the flow's own
 * time steps (Eq. 11).
 */
#include "routers/router_process_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void record_snapshots(const process_snaps *s, size_t *next, double t, const double *h,
                             size_t n)
{
    while (s != NULL && *next < s->n_snap && t >= s->times[*next]) {
        s->t[*next] = t;
        memcpy(s->h + *next * n, h, n * sizeof *h);
        (*next)++;
    }
}

int dfle_process_route_path(const dfle_process_opts *o, const process_path *p, dfle_flow *flow,
                            double *arrival, double *cos_theta, const process_snaps *snaps,
                            process_path_result *res, dfle_error *err)
{
    const size_t n = p->n, G = (size_t)o->n_ghost, N = G + n;
    const double *w = p->w, *S = p->S, *A = p->A;
    const double dx_head = p->dx != NULL ? p->dx[0] : p->dx0;
    double *cw = NULL, *cS = NULL, *cdx = NULL, *pile, released, out_total = 0.0, t = 0.0,
           t_entry = -1.0;
    const double *h, *q, *face_vol;
    double phi_max;
    dfle_flow1d *f = NULL;
    size_t steps = 0, next_snap = 0, cell_steps = 0;
    int st, end, moved = 0;

    cw = malloc(N * sizeof *cw);
    cS = malloc(N * sizeof *cS);
    if (p->dx != NULL)
        cdx = malloc(N * sizeof *cdx);
    if (cw == NULL || cS == NULL || (p->dx != NULL && cdx == NULL)) {
        st = dfle_error_set(err, DFLE_ENOMEM, "router.process: out of memory");
        goto done;
    }
    /* Ghost cells extend the head: its width, its slope, its length. */
    for (size_t k = 0; k < N; k++) {
        cw[k] = k < G ? w[0] : w[k - G];
        cS[k] = k < G ? S[0] : S[k - G];
        if (cdx != NULL)
            cdx[k] = k < G ? dx_head : p->dx[k - G];
    }
    if ((st = dfle_flow1d_new_cells(N, cdx, p->dx0, cw, cS, &o->flow, &f, err)) != DFLE_OK)
        goto done;
    pile = dfle_flow1d_h(f);
    for (size_t k = 0; k < G; k++)
        pile[k] = o->M0 / ((double)G * dx_head * w[0]); /* a static pile of volume M0 */
    released = dfle_flow1d_volume(f, 0, N);
    h = dfle_flow1d_depth(f);
    q = dfle_flow1d_discharge(f);
    face_vol = dfle_flow1d_face_volumes(f);
    phi_max = dfle_flow1d_phi_max(f);

    dfle_flow_clear(flow);
    flow->time_resolved = 1;
    for (size_t i = 0; i < n; i++)
        arrival[i] = NAN;
    for (size_t j = 0; snaps != NULL && j < snaps->n_snap; j++)
        snaps->t[j] = NAN;
    record_snapshots(snaps, &next_snap, 0.0, h + G, n);

    /* The loop's constants and record arrays as locals: the records'
     * stores cannot then be taken to change them, so they stay in
     * registers. */
    const double q_erode = o->q_erode, rho = o->flow.rho, grav = o->flow.g;
    double *const rec_h = flow->h, *const rec_M = flow->M, *const rec_tau = flow->tau,
                 *const rec_integral = flow->integral, *const rec_t_p = flow->t_p,
                 *const rec_v = flow->v, *const rec_Q = flow->Q;
    for (;;) {
        double dt = dfle_flow1d_stable_dt(f), outflow, left, qmax = 0.0, L;
        size_t k0, k1;
        if (isinf(dt)) { /* everything dry: nothing left to move */
            end = DFLE_PROCESS_LEFT;
            break;
        }
        if (dt > o->t_max - t)
            dt = o->t_max - t;
        if ((double)steps >= o->max_steps) {
            st = dfle_error_set(err, DFLE_ENUMERIC,
                                "router.process: the flow needed more than max_steps = %.0f time "
                                "steps (stopped at t = %g s of t_max = %g s, step %g s, cfl = %g); "
                                "raise cfl or max_steps",
                                o->max_steps, t, o->t_max, dt, o->flow.cfl);
            goto done;
        }
        if ((st = dfle_flow1d_step(f, dt, t_entry < 0 ? -1.0 : t - t_entry, &outflow, err)) != DFLE_OK)
            goto done;
        t += dt;
        steps++;
        out_total += outflow;
        /* The flow enters the domain when it first crosses the head. */
        if (t_entry < 0 && face_vol[G] > 0)
            t_entry = t;
        /* Only the cells the step worked on: outside its window the depth,
         * discharge and face volumes are exactly 0, which would add
         * nothing to any record below. */
        dfle_flow1d_window(f, &k0, &k1);
        cell_steps += k1 - k0;
        L = dfle_flow1d_pore_length(f, t_entry < 0 ? -1.0 : t - t_entry);
        for (size_t k = k0 > G ? k0 : G; k < k1; k++) {
            const size_t i = k - G;
            const double hk = h[k], qk = fabs(q[k]);
            if (qk > qmax)
                qmax = qk;
            if (hk > rec_h[i])
                rec_h[i] = hk;
            rec_M[i] += face_vol[k + 1];
            if (qk > q_erode) { /* Phi = 1 */
                const double v = qk / hk;
                const double lam = dfle_flow1d_lambda_at(f, hk, L);
                double tau, g;
                if (isnan(arrival[i])) { /* first erosion here */
                    arrival[i] = t;
                    cos_theta[i] = cos(atan(S[i]));
                }
                /* The peak Coulomb stress (1 - lambda) rho g_z h phi: phi
                 * (a division and a root) only when its bound could beat
                 * the peak so far. */
                tau = (1.0 - lam) * rho * grav * cos_theta[i] * hk * phi_max;
                if (tau > rec_tau[i])
                    tau = (1.0 - lam) * rho * grav * cos_theta[i] * hk *
                          dfle_flow1d_phi(f, k, hk, v);
                if ((st = flow->integrand(flow->integrand_state, hk, v, lam, &g, err)) != DFLE_OK)
                    goto done;
                rec_integral[i] += g * dt;
                rec_t_p[i] += dt;
                if (v > rec_v[i])
                    rec_v[i] = v;
                if (qk * w[i] > rec_Q[i])
                    rec_Q[i] = qk * w[i];
                if (tau > rec_tau[i])
                    rec_tau[i] = tau;
            }
        }
        for (size_t k = k0; k < k1 && k < G; k++)
            if (fabs(q[k]) > qmax)
                qmax = fabs(q[k]);
        record_snapshots(snaps, &next_snap, t, h + G, n);
        left = dfle_flow1d_volume(f, 0, N);
        if (!isfinite(left) || !isfinite(qmax)) {
            st = dfle_error_set(err, DFLE_ENUMERIC,
                                "router.process: the flow became non-finite at t = %g s", t);
            goto done;
        }
        if (left <= o->volume_tol * released) {
            end = DFLE_PROCESS_LEFT;
            break;
        }
        /* At rest: held still by friction (q = 0 everywhere), or moving
         * once and slow everywhere now.  A pile only just released is
         * slow too, because it has not had time to accelerate: after a
         * first step of 1e-8 s (a tiny cfl) it must not count as at rest. */
        moved = moved || qmax > o->q_rest;
        if (qmax == 0.0 || (moved && qmax <= o->q_rest)) {
            end = DFLE_PROCESS_REST;
            break;
        }
        if (t >= o->t_max) {
            end = DFLE_PROCESS_TIME;
            break;
        }
    }

    /* Results: reach, threshold factor, Appendix D scaling. */
    flow->runout_end = 0;
    for (size_t i = 0; i < n; i++) {
        if (flow->t_p[i] > 0) {
            flow->runout_end = i + 1;
            flow->Theta[i] = 1.0;
        }
        if (o->frequency_scaling)
            flow->integral[i] *= 1000.0 * pow(1e-6 * A[i], o->gamma) / o->M0;
    }
    /* The one flow reaches the channel down to its furthest wet node. */
    for (size_t i = 0; i < n; i++)
        flow->reach[i] = i < flow->runout_end;
    *res = (process_path_result){
        .end = end, .volume_in = released, .volume_out = out_total,
        .volume_left = dfle_flow1d_volume(f, 0, N), .duration = t, .steps = steps,
        .cell_steps = cell_steps,
    };
    st = DFLE_OK;
done:
    dfle_flow1d_free(f);
    free(cw);
    free(cS);
    free(cdx);
    return st;
}
