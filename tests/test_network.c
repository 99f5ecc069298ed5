/* test_network.c - network shapes: the checks of a given stack,
 * positions that a shape without them leaves unset, and shapes written
 * into the network's own arrays. */
#include <math.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/network.h"

/* 0 <- 1 <- 2, 0 <- 3 (node 0 the base level). */
static const size_t recv4[4] = {0, 0, 1, 0};
static const double len4[4] = {1, 10, 10, 10}, A4[4] = {4e3, 2e3, 1e3, 1e3},
                    w4[4] = {2, 1.5, 1, 1};

static dfle_network_shape shape4(const size_t *stack)
{
    dfle_network_shape sh = {.receiver = recv4, .length = len4, .A = A4, .w = w4,
                             .stack = stack};
    return sh;
}

static void a_valid_stack_is_taken_as_given(void **state)
{
    const size_t stack[4] = {0, 3, 1, 2};
    dfle_network *net;
    dfle_network_shape sh = shape4(stack);
    dfle_error err;
    (void)state;
    assert_ok(dfle_network_new(4, &net, &err), &err);
    /* Twice: the check's scratch is kept between shapes. */
    for (int k = 0; k < 2; k++) {
        assert_ok(dfle_network_set(net, &sh, &err), &err);
        assert_memory_equal(dfle_network_stack(net), stack, sizeof stack);
    }
    dfle_network_free(net);
}

static void a_stack_that_repeats_a_node_is_refused(void **state)
{
    const size_t stack[4] = {0, 1, 1, 2};
    dfle_network *net;
    dfle_network_shape sh = shape4(stack);
    dfle_error err;
    (void)state;
    assert_ok(dfle_network_new(4, &net, &err), &err);
    assert_int_equal(dfle_network_set(net, &sh, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "not a permutation of the nodes (entry 3)");
    dfle_network_free(net);
}

static void a_node_before_its_receiver_is_named(void **state)
{
    const size_t stack[4] = {0, 2, 1, 3}; /* 2 drains to 1, which comes later */
    dfle_network *net;
    dfle_network_shape sh = shape4(stack);
    dfle_error err;
    (void)state;
    assert_ok(dfle_network_new(4, &net, &err), &err);
    assert_int_equal(dfle_network_set(net, &sh, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "node 3 comes before its receiver 2");
    /* The network is as it was: unshaped, every node its own base. */
    for (size_t i = 0; i < 4; i++)
        assert_int_equal(dfle_network_receivers(net)[i], i);
    dfle_network_free(net);
}

static void positions_follow_the_last_shape(void **state)
{
    const double x[4] = {0, 10, 20, 10};
    dfle_network *net;
    dfle_network_shape sh = shape4(NULL);
    dfle_error err;
    (void)state;
    assert_ok(dfle_network_new(4, &net, &err), &err);
    assert_ok(dfle_network_set(net, &sh, &err), &err);
    for (size_t i = 0; i < 4; i++)
        assert_true(isnan(dfle_network_x(net)[i]));
    sh.x = x;
    assert_ok(dfle_network_set(net, &sh, &err), &err);
    assert_memory_equal(dfle_network_x(net), x, sizeof x);
    sh.x = NULL; /* a shape without positions clears the last one's */
    assert_ok(dfle_network_set(net, &sh, &err), &err);
    for (size_t i = 0; i < 4; i++)
        assert_true(isnan(dfle_network_x(net)[i]));
    dfle_network_free(net);
}

/* A shape written into the network's own arrays is checked and derived
 * as one given by dfle_network_set; one that fails leaves it unshaped. */
static void an_edited_shape_is_checked_at_commit(void **state)
{
    const size_t stack[4] = {0, 3, 1, 2}, bad[4] = {0, 2, 1, 3};
    const unsigned char src[4] = {0, 0, 1, 1}, chan[4] = {1, 1, 1, 0};
    dfle_network *net, *ref;
    dfle_network_edit_view v;
    dfle_network_shape sh = shape4(stack);
    dfle_error err;
    (void)state;
    sh.source = src;
    sh.channel = chan;
    assert_ok(dfle_network_new(4, &net, &err), &err);
    assert_ok(dfle_network_new(4, &ref, &err), &err);
    assert_ok(dfle_network_set(ref, &sh, &err), &err);
    assert_int_equal(dfle_network_commit(net, &err), DFLE_ESTATE);
    for (int pass = 0; pass < 2; pass++) {
        const size_t *st = pass == 0 ? stack : bad;
        assert_ok(dfle_network_edit(net, 1, &v, &err), &err);
        for (size_t i = 0; i < 4; i++) {
            v.receiver[i] = recv4[i], v.stack[i] = st[i], v.length[i] = len4[i];
            v.A[i] = A4[i], v.w[i] = w4[i], v.source[i] = src[i], v.channel[i] = chan[i];
        }
        if (pass == 0) {
            const unsigned long long before = dfle_network_version(net);
            size_t nb_a, nb_b;
            assert_ok(dfle_network_commit(net, &err), &err);
            assert_true(dfle_network_version(net) != before);
            assert_memory_equal(dfle_network_receivers(net), dfle_network_receivers(ref),
                                4 * sizeof(size_t));
            assert_memory_equal(dfle_network_sources(net), dfle_network_sources(ref), 4);
            assert_memory_equal(dfle_network_channel(net), dfle_network_channel(ref), 4);
            assert_int_equal(dfle_network_bases(net, &nb_a)[0], dfle_network_bases(ref, &nb_b)[0]);
            assert_int_equal(nb_a, nb_b);
            assert_int_equal(dfle_network_base_donor(net, 0), dfle_network_base_donor(ref, 0));
            assert_true(isnan(dfle_network_x(net)[2]));
        } else {
            assert_int_equal(dfle_network_commit(net, &err), DFLE_EINVAL);
            assert_msg_contains(err.msg, "node 3 comes before its receiver 2");
            for (size_t i = 0; i < 4; i++)
                assert_int_equal(dfle_network_receivers(net)[i], i);
            assert_null(dfle_network_channel(net));
        }
    }
    dfle_network_free(ref);
    dfle_network_free(net);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(a_valid_stack_is_taken_as_given),
        cmocka_unit_test(a_stack_that_repeats_a_node_is_refused),
        cmocka_unit_test(a_node_before_its_receiver_is_named),
        cmocka_unit_test(positions_follow_the_last_shape),
        cmocka_unit_test(an_edited_shape_is_checked_at_commit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
