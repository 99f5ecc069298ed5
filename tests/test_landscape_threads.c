/*
 * test_landscape_threads.c - a landscape's steps on threads
 * (dfle_landscape_set_par) give the same elevations, receivers and
 * drainage areas, byte for byte, as without threads, for 1, 2 and 3
 * threads of the worker pool, with and without debris flows, for
 * n = 1 and n = 2.33; and the volumes a step reports are the same for
 * any number of threads (summed by chunk of basins), within the last
 * bits of those summed down the whole stack.  A cell swept before its
 * receiver, swept twice or missed would change the bytes.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/landscape.h"
#include "dfle/law_power.h"
#include "dfle/pool.h"
#include "dfle/router_empirical.h"
#include "dfle_test.h"

enum { SIDE = 120, N = SIDE * SIDE, STEPS = 4 };

static uint64_t fnv1a(const void *p, size_t bytes, uint64_t h)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < bytes; i++) {
        h ^= b[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

typedef struct outcome {
    uint64_t z, rcv, A;
    double V[5]; /* the last step's dV, uplift, fluvial, debris-flow, hillslope volumes */
    size_t reached;
} outcome;

/* Noise of 1 m on a pyramid of slope `tilt` (debris flows travel on it). */
static void start(double *z, double tilt)
{
    uint64_t seed = 11;
    for (size_t i = 0; i < N; i++) {
        size_t r = i / SIDE, c = i % SIDE, e = r < c ? r : c;
        e = e < SIDE - 1 - r ? e : SIDE - 1 - r;
        e = e < SIDE - 1 - c ? e : SIDE - 1 - c;
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        z[i] = (double)(seed >> 11) / 9007199254740992.0 + tilt * 30.0 * (double)e;
    }
}

/* STEPS steps of 1e3 yr on `threads` threads (0: no pool at all). */
static void run(const double *z, double n_exp, int debris, int threads, outcome *out)
{
    dfle_fluvial *fl;
    dfle_router *rt = NULL;
    dfle_law *law = NULL;
    dfle_landscape *ls;
    dfle_landscape_opts o;
    dfle_landscape_status st;
    dfle_pool_par *pp = NULL;
    dfle_error err;
    assert_ok(dfle_fluvial_new_stream_power(n_exp == 1 ? 2e-5 : 1e-3, 0.5, n_exp, &fl, &err),
              &err);
    dfle_landscape_opts_default(&o);
    o.nx = o.ny = SIDE;
    o.dx = o.dy = 30.0;
    o.z = z;
    o.A0 = debris ? 1e4 : 2e3; /* hillslopes held at S_c besides channels */
    o.S_c = 0.05;
    o.U.value = 1e-3;
    o.fluvial = fl;
    if (debris) {
        dfle_empirical_opts eo;
        dfle_power_law_opts po;
        dfle_empirical_opts_default(&eo);
        dfle_power_law_opts_default(&po);
        o.S_c = 0.8;
        assert_ok(dfle_router_new_empirical(&eo, &rt, &err), &err);
        assert_ok(dfle_law_new_power(&po, &law, &err), &err);
        o.router = rt;
        o.law = law;
    }
    assert_ok(dfle_landscape_new(&o, &ls, &err), &err);
    if (threads > 0) {
        assert_ok(dfle_pool_par_new(threads, &pp, &err), &err);
        assert_ok(dfle_landscape_set_par(ls, dfle_pool_par_get(pp), &err), &err);
    }
    for (int k = 0; k < STEPS; k++)
        assert_ok(dfle_landscape_step(ls, 1e3, 1e-3, &st, &err), &err);
    {
        const dfle_drainage *dr = dfle_landscape_drainage(ls);
        out->z = fnv1a(dfle_landscape_z(ls), N * sizeof(double), 0xcbf29ce484222325ull);
        out->rcv = fnv1a(dfle_drainage_receivers(dr), N * sizeof(uint32_t), 0xcbf29ce484222325ull);
        out->A = fnv1a(dfle_drainage_area(dr), N * sizeof(double), 0xcbf29ce484222325ull);
    }
    out->V[0] = st.dV;
    out->V[1] = st.V_uplift;
    out->V[2] = st.V_fluvial;
    out->V[3] = st.V_df;
    out->V[4] = st.V_hillslope;
    out->reached = st.reached;
    dfle_landscape_free(ls);
    dfle_pool_par_free(pp);
    dfle_law_free(law);
    dfle_router_free(rt);
    dfle_fluvial_free(fl);
}

static void check(double n_exp, int debris)
{
    static double z[N];
    outcome none, t[4];
    start(z, debris ? 0.05 : 0.0);
    run(z, n_exp, debris, 0, &none);
    for (int k = 1; k <= 3; k++)
        run(z, n_exp, debris, k, &t[k]);
    if (debris) /* the flows reach some cells, not all */
        assert_true(none.reached > 0 && none.reached < N / 2);
    assert_true(none.V[2] > 0 && (debris || none.V[4] > 0)); /* rivers (and caps) at work */
    for (int k = 1; k <= 3; k++) {
        assert_true(t[k].z == none.z);
        assert_true(t[k].rcv == none.rcv);
        assert_true(t[k].A == none.A);
        assert_true(t[k].reached == none.reached);
        assert_memory_equal(t[k].V, t[1].V, sizeof t[k].V);
        for (int v = 0; v < 5; v++) /* another order of the same sum */
            assert_true(fabs(t[k].V[v] - none.V[v]) <= 1e-12 * fabs(none.V[1]));
    }
}

static void test_rivers_n1(void **state)
{
    (void)state;
    check(1.0, 0);
}

static void test_rivers_n233(void **state)
{
    (void)state;
    check(2.33, 0);
}

static void test_debris_n1(void **state)
{
    (void)state;
    check(1.0, 1);
}

static void test_debris_n233(void **state)
{
    (void)state;
    check(2.33, 1);
}

/* Threads are asked for properly or not at all. */
static void test_bad_threads(void **state)
{
    dfle_pool_par *pp = (dfle_pool_par *)1;
    dfle_error err;
    (void)state;
    assert_int_equal(dfle_pool_par_new(0, &pp, &err), DFLE_EINVAL);
    assert_null(pp);
    assert_non_null(strstr(err.msg, "threads"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rivers_n1),   cmocka_unit_test(test_rivers_n233),
        cmocka_unit_test(test_debris_n1),   cmocka_unit_test(test_debris_n233),
        cmocka_unit_test(test_bad_threads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
