/* test_router_empirical.c - Sect. 2.3: flow properties and runout. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/network.h"
#include "dfle/router_empirical.h"

typedef struct fixture {
    dfle_channel *ch;
    dfle_network *net; /* the channel as routers see it */
    dfle_router *rt;
    dfle_flow flow;
    dfle_empirical_opts o;
} fixture;

static int setup(void **state)
{
    static fixture f;
    dfle_channel_opts co;
    memset(&f, 0, sizeof f);
    dfle_channel_opts_default(&co);
    dfle_empirical_opts_default(&f.o);
    if (dfle_channel_new(&co, &f.ch, NULL) != DFLE_OK ||
        dfle_network_new_chain(f.ch, &f.net, NULL) != DFLE_OK ||
        dfle_router_new_empirical(&f.o, &f.rt, NULL) != DFLE_OK ||
        dfle_flow_init(&f.flow, dfle_channel_size(f.ch), NULL) != DFLE_OK)
        return -1;
    *state = &f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    dfle_flow_release(&f->flow);
    dfle_router_free(f->rt);
    dfle_network_free(f->net);
    dfle_channel_free(f->ch);
    return 0;
}

/* tau written out from the definitions, independently of the router. */
static double tau_of(const dfle_empirical_opts *o, double A, double w, double S)
{
    double M = o->M0 * pow(1e-6 * A, o->gamma);
    double h = pow(3 * o->mu * o->c1 * pow(M, o->c2) / (o->rho_b * o->g * S * w), 1.0 / 3.0);
    double Rh = w * h / (w + 2 * h);
    return o->rho_b * o->g * Rh * sin(atan(S));
}

static void properties_follow_eqs_12_to_17(void **state)
{
    fixture *f = *state;
    size_t n = dfle_channel_size(f->ch);
    const double *A = dfle_channel_A(f->ch), *w = dfle_channel_w(f->ch);
    double S[403];
    dfle_error err;

    assert_int_equal(n, 403);
    for (size_t i = 0; i < n; i++)
        S[i] = 0.8;
    assert_ok(dfle_router_route(f->rt, f->net, S, &f->flow, &err), &err);
    for (size_t i = 0; i < f->flow.runout_end; i += 13) {
        double M = 3000 * pow(1e-6 * A[i], 0.5);
        double Q = 0.135 * pow(M, 0.78);
        /* Eq. (15), with A and w written out. */
        double h = pow(3 * 500 * 0.135 * pow(3000 * pow(1e-6 * A[i], 0.5), 0.78) /
                           (1800 * 9.81 * 0.8 * 0.05 * pow(A[i], 0.3)), 1.0 / 3.0);
        assert_close(f->flow.M[i], M, 1e-12, 0);
        assert_close(f->flow.Q[i], Q, 1e-12, 0);
        assert_close(f->flow.h[i], h, 1e-12, 0);
        assert_close(f->flow.t_p[i], M / Q, 1e-12, 0); /* Eq. (16) */
        /* Eq. (13): v = rho_b g h^2 S / (3 mu), and Q = v w h. */
        assert_close(f->flow.v[i], 1800 * 9.81 * h * h * 0.8 / (3 * 500), 1e-10, 0);
        assert_close(f->flow.tau[i], tau_of(&f->o, A[i], w[i], 0.8), 1e-12, 0);
        assert_close(f->flow.Theta[i], 1 - 300 / f->flow.tau[i], 1e-12, 0);
    }
}

static void runout_stops_where_tau_first_drops_below_tau_y(void **state)
{
    fixture *f = *state;
    size_t n = dfle_channel_size(f->ch), expected = n;
    const double *A = dfle_channel_A(f->ch), *w = dfle_channel_w(f->ch);
    double S[403];
    dfle_error err;

    /* A concave profile: tau falls downstream; then a steep reach below
     * the stop point that the flow must still not reach. */
    for (size_t i = 0; i < n; i++)
        S[i] = 0.9 * pow(A[i] / 1000.0, -0.8);
    for (size_t i = 300; i < n; i++)
        S[i] = 1.0;
    for (size_t i = 0; i < n; i++)
        if (tau_of(&f->o, A[i], w[i], S[i]) < 300.0) {
            expected = i;
            break;
        }
    assert_true(expected > 5 && expected < 300);
    assert_ok(dfle_router_route(f->rt, f->net, S, &f->flow, &err), &err);
    assert_int_equal(f->flow.runout_end, expected);
    assert_true(f->flow.tau[expected - 1] >= 300.0);
    assert_true(f->flow.Theta[expected - 1] >= 0.0);
    for (size_t i = expected; i < n; i++) {
        assert_close(f->flow.h[i], 0, 0, 0);
        assert_close(f->flow.Theta[i], 0, 0, 0);
    }
}

static void reverse_slope_stops_the_flow(void **state)
{
    fixture *f = *state;
    double S[403];
    (void)state;
    for (size_t i = 0; i < 403; i++)
        S[i] = 1.0;
    S[40] = -0.01;
    assert_int_equal(dfle_router_route(f->rt, f->net, S, &f->flow, NULL), DFLE_OK);
    assert_int_equal(f->flow.runout_end, 40);
}

static void zero_yield_strength_reaches_everywhere(void **state)
{
    fixture *f = *state;
    dfle_empirical_opts o = f->o;
    dfle_router *rt;
    double S[403];
    o.tau_y = 0;
    assert_int_equal(dfle_router_new_empirical(&o, &rt, NULL), DFLE_OK);
    for (size_t i = 0; i < 403; i++)
        S[i] = 0.02;
    assert_int_equal(dfle_router_route(rt, f->net, S, &f->flow, NULL), DFLE_OK);
    assert_int_equal(f->flow.runout_end, 403);
    assert_close(f->flow.Theta[402], 1.0, 0, 0);
    dfle_router_free(rt);
}

static void cache_follows_the_channel(void **state)
{
    fixture *f = *state;
    double A[5] = {1e4, 2e4, 3e4, 4e4, 5e4}, w[5] = {1, 1, 1, 1, 1}, S[5];
    double A2[5] = {1e5, 2e5, 3e5, 4e5, 5e5};
    dfle_channel *c1, *c2;
    dfle_network *n1, *n2;
    dfle_flow fl;
    (void)state;
    for (int i = 0; i < 5; i++)
        S[i] = 0.5;
    assert_int_equal(dfle_flow_init(&fl, 5, NULL), DFLE_OK);
    assert_int_equal(dfle_channel_new_from_arrays(5, 5, A, w, &c1, NULL), DFLE_OK);
    assert_int_equal(dfle_network_new_chain(c1, &n1, NULL), DFLE_OK);
    assert_int_equal(dfle_router_route(f->rt, n1, S, &fl, NULL), DFLE_OK);
    assert_close(fl.M[0], 3000 * pow(1e-2, 0.5), 1e-12, 0);
    dfle_network_free(n1);
    dfle_channel_free(c1);
    /* Same size, maybe the same address: the router must not reuse c1's terms. */
    assert_int_equal(dfle_channel_new_from_arrays(5, 5, A2, w, &c2, NULL), DFLE_OK);
    assert_int_equal(dfle_network_new_chain(c2, &n2, NULL), DFLE_OK);
    assert_int_equal(dfle_router_route(f->rt, n2, S, &fl, NULL), DFLE_OK);
    assert_close(fl.M[0], 3000 * pow(1e-1, 0.5), 1e-12, 0);
    dfle_network_free(n2);
    dfle_channel_free(c2);
    dfle_flow_release(&fl);
}

static void bad_parameters_are_named(void **state)
{
    dfle_empirical_opts o;
    dfle_router *rt = NULL;
    dfle_error err;
    (void)state;
    const struct { const char *name; double *field; double bad; } cases[] = {
        {"M0 must be > 0", &o.M0, 0}, {"gamma must be >= 0", &o.gamma, -0.1},
        {"mu must be > 0", &o.mu, -5}, {"tau_y must be >= 0", &o.tau_y, NAN},
        {"c2 must be > 0", &o.c2, INFINITY},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        dfle_empirical_opts_default(&o);
        *cases[k].field = cases[k].bad;
        assert_int_equal(dfle_router_new_empirical(&o, &rt, &err), DFLE_EINVAL);
        assert_null(rt);
        assert_msg_contains(err.msg, cases[k].name);
    }
}

/* Each parameter valid, the flow not: c2 = 2.5e6 makes Q = c1 M^c2
 * overflow.  Routing (and the one-node flow the solvers use) must fail
 * naming the term, never hand out h = inf and NaN stresses. */
static void parameters_without_a_finite_flow_are_named(void **state)
{
    fixture *f = *state;
    dfle_empirical_opts o;
    dfle_router *rt;
    dfle_error err;
    double *S = malloc(dfle_channel_size(f->ch) * sizeof *S);
    int goes_on = 1;
    assert_non_null(S);
    for (size_t i = 0; i < dfle_channel_size(f->ch); i++)
        S[i] = 0.5;
    dfle_empirical_opts_default(&o);
    o.c2 = 2.5e6;
    o.g = 1e-7;
    assert_ok(dfle_router_new_empirical(&o, &rt, &err), &err);
    assert_int_equal(dfle_router_route(rt, f->net, S, &f->flow, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "peak discharge Q = c1 M^c2");
    assert_msg_contains(err.msg, "c2 = 2.5e+06");
    assert_int_equal(dfle_router_node_flow(rt, f->net, 3, 0.5, &f->flow, &goes_on, &err),
                     DFLE_EINVAL);
    assert_int_equal(goes_on, 0);
    dfle_router_free(rt);
    free(S);
}

/* A random tree of n nodes: node i > 0 drains to an earlier node, node 0
 * is the base level; A counts the nodes upstream (1e3 m^2 each). */
static void random_tree(size_t n, unsigned *seed, size_t *recv, double *A, double *w,
                        unsigned char *src, double *S)
{
    for (size_t i = 0; i < n; i++) {
        recv[i] = i == 0 ? 0 : (size_t)(rand_r(seed) % i);
        A[i] = 1e3;
        S[i] = 0.05 + 0.55 * rand_r(seed) / (double)RAND_MAX;
    }
    for (size_t i = n; i-- > 1;)
        A[recv[i]] += A[i];
    for (size_t i = 0; i < n; i++) {
        w[i] = 0.5 + 1e-3 * sqrt(A[i]);
        src[i] = rand_r(seed) % 3 == 0; /* any node may start flows */
    }
}

/* The router keeps its area terms from one shape of a network to the
 * next and zeroes only nodes that stopped being reachable: every routing
 * after a re-shaping must equal, bit for bit, that of a new router into
 * a new flow. */
static void reshaped_network_routes_as_a_new_router(void **state)
{
    enum { N = 300 };
    fixture *f = *state;
    dfle_network *net;
    dfle_router *kept;
    dfle_flow flow;
    size_t recv[N];
    double A[N], w[N], S[N], len[N];
    unsigned char src[N];
    unsigned seed = 7;
    dfle_error err;
    int darkened = 0;

    for (size_t i = 0; i < N; i++)
        len[i] = 10.0;
    assert_ok(dfle_network_new(N, &net, &err), &err);
    assert_ok(dfle_router_new_empirical(&f->o, &kept, &err), &err);
    assert_ok(dfle_flow_init(&flow, N, &err), &err);
    for (int round = 0; round < 12; round++) {
        dfle_network_shape sh = {.receiver = recv, .length = len, .A = A, .w = w,
                                 .source = src};
        dfle_router *fresh;
        dfle_flow ref;
        unsigned char was[N];
        if (round == 0 || round % 4 == 0) {
            random_tree(N, &seed, recv, A, w, src, S);
        } else {
            /* A few sources off and on, a few slopes moved: areas stay. */
            memcpy(was, src, N);
            for (int k = 0; k < 20; k++)
                src[rand_r(&seed) % N] ^= 1;
            for (int k = 0; k < 30; k++)
                S[rand_r(&seed) % N] *= 0.5 + rand_r(&seed) / (double)RAND_MAX;
            for (size_t i = 0; i < N; i++)
                darkened |= was[i] && !src[i];
        }
        assert_ok(dfle_network_set(net, &sh, &err), &err);
        assert_ok(dfle_router_route(kept, net, S, &flow, &err), &err);
        assert_ok(dfle_router_new_empirical(&f->o, &fresh, &err), &err);
        assert_ok(dfle_flow_init(&ref, N, &err), &err);
        assert_ok(dfle_router_route(fresh, net, S, &ref, &err), &err);
        assert_int_equal(flow.runout_end, ref.runout_end);
        assert_memory_equal(flow.M, ref.M, 8 * N * sizeof *flow.M); /* M .. reach */
        dfle_flow_release(&ref);
        dfle_router_free(fresh);
    }
    assert_true(darkened); /* the zeroing of nodes no longer reachable ran */
    dfle_flow_release(&flow);
    dfle_router_free(kept);
    dfle_network_free(net);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(properties_follow_eqs_12_to_17),
        cmocka_unit_test(runout_stops_where_tau_first_drops_below_tau_y),
        cmocka_unit_test(reverse_slope_stops_the_flow),
        cmocka_unit_test(zero_yield_strength_reaches_everywhere),
        cmocka_unit_test(cache_follows_the_channel),
        cmocka_unit_test(bad_parameters_are_named),
        cmocka_unit_test(parameters_without_a_finite_flow_are_named),
        cmocka_unit_test(reshaped_network_routes_as_a_new_router),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
