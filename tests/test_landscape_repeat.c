/*
 * test_landscape_repeat.c - a landscape's steps are a function of its
 * inputs alone: two landscapes built from the same start, stepped with
 * another landscape of other inputs stepped between them, hold the same
 * elevations, receivers and drainage areas, byte for byte, with and
 * without debris flows, for n = 1 and n = 2.33.  (State shared between
 * landscapes, memory read before it is written, or an order that
 * depends on where buffers lie would each show here.)
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/landscape.h"
#include "dfle/law_power.h"
#include "dfle/router_empirical.h"
#include "dfle_test.h"

enum { SIDE = 64, N = SIDE * SIDE, STEPS = 3 };

typedef struct snapshot {
    double z[N], A[N];
    uint32_t rcv[N];
} snapshot;

/* Noise of 1 m on a pyramid of slope `tilt` (debris flows travel on it). */
static void start(double *z, double tilt, uint64_t seed)
{
    for (size_t i = 0; i < N; i++) {
        size_t r = i / SIDE, c = i % SIDE, e = r < c ? r : c;
        e = e < SIDE - 1 - r ? e : SIDE - 1 - r;
        e = e < SIDE - 1 - c ? e : SIDE - 1 - c;
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        z[i] = (double)(seed >> 11) / 9007199254740992.0 + tilt * 30.0 * (double)e;
    }
}

/* STEPS steps of 1e3 yr from z; the state after them in *s (or none). */
static void run(const double *z, double n_exp, int debris, snapshot *s, size_t *reached)
{
    dfle_fluvial *fl;
    dfle_router *rt = NULL;
    dfle_law *law = NULL;
    dfle_landscape *ls;
    dfle_landscape_opts o;
    dfle_landscape_status st;
    dfle_error err;
    assert_ok(dfle_fluvial_new_stream_power(n_exp == 1 ? 2e-5 : 1e-3, 0.5, n_exp, &fl, &err),
              &err);
    dfle_landscape_opts_default(&o);
    o.nx = o.ny = SIDE;
    o.dx = o.dy = 30.0;
    o.z = z;
    o.A0 = debris ? 1e4 : 0.0;
    o.U.value = 1e-3;
    o.fluvial = fl;
    if (debris) {
        dfle_empirical_opts eo;
        dfle_power_law_opts po;
        dfle_empirical_opts_default(&eo);
        dfle_power_law_opts_default(&po);
        assert_ok(dfle_router_new_empirical(&eo, &rt, &err), &err);
        assert_ok(dfle_law_new_power(&po, &law, &err), &err);
        o.router = rt;
        o.law = law;
    }
    assert_ok(dfle_landscape_new(&o, &ls, &err), &err);
    for (int k = 0; k < STEPS; k++)
        assert_ok(dfle_landscape_step(ls, 1e3, 1e-3, &st, &err), &err);
    if (s != NULL) {
        const dfle_drainage *dr = dfle_landscape_drainage(ls);
        memcpy(s->z, dfle_landscape_z(ls), sizeof s->z);
        memcpy(s->rcv, dfle_drainage_receivers(dr), sizeof s->rcv);
        memcpy(s->A, dfle_drainage_area(dr), sizeof s->A);
    }
    if (reached != NULL)
        *reached = st.reached;
    dfle_landscape_free(ls);
    dfle_law_free(law);
    dfle_router_free(rt);
    dfle_fluvial_free(fl);
}

static void check(double n_exp, int debris)
{
    static double z[N], other[N];
    snapshot *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    size_t reached = 0;
    assert_non_null(a);
    assert_non_null(b);
    start(z, debris ? 0.05 : 0.0, 7);
    start(other, 0.1, 99);
    run(z, n_exp, debris, a, &reached);
    run(other, n_exp, !debris, NULL, NULL);
    run(z, n_exp, debris, b, NULL);
    if (debris) /* the flows reach some cells, not all */
        assert_true(reached > 0 && reached < N / 2);
    assert_memory_equal(a->z, b->z, sizeof a->z);
    assert_memory_equal(a->rcv, b->rcv, sizeof a->rcv);
    assert_memory_equal(a->A, b->A, sizeof a->A);
    free(a);
    free(b);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rivers_n1),
        cmocka_unit_test(test_rivers_n233),
        cmocka_unit_test(test_debris_n1),
        cmocka_unit_test(test_debris_n233),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
