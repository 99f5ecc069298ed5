/*
 * test_progress.c - the command's ETA estimate (src/cli/progress.c).
 */
#include "dfle_test.h"

#include "cli/progress.h"

/* A steady-state run's completion estimate races, then crawls: half done
 * after the first second, then 5 % a second.  The time left must come
 * from the crawl (10 s at 50 %), not from the average since the start,
 * which would say 1 s. */
static void test_eta_follows_the_recent_pace(void **state)
{
    dfle_progress_eta e;
    double left = -1;
    (void)state;
    dfle_progress_eta_init(&e);
    assert_true(dfle_progress_eta_update(&e, 100.0, 0.0) < 0);
    assert_true(dfle_progress_eta_update(&e, 100.5, 0.45) < 0); /* the first second */
    for (double t = 101.0; t <= 110.0 + 1e-9; t += 0.1)
        left = dfle_progress_eta_update(&e, t, 0.5 + 0.05 * (t - 101.0));
    /* At t = 110 the fraction is 0.95: 1 s left at 5 %/s. */
    assert_close(left, 1.0, 0.02, 0);
}

/* At a constant pace the estimate is exact from the first second on. */
static void test_eta_constant_pace(void **state)
{
    dfle_progress_eta e;
    (void)state;
    dfle_progress_eta_init(&e);
    for (int k = 0; k <= 40; k++) {
        double t = 0.1 * k, left = dfle_progress_eta_update(&e, t, t / 20.0);
        if (t >= 1.0)
            assert_close(left, 20.0 - t, 1e-9, 1e-9);
        else
            assert_true(left < 0);
    }
}

/* No progress lately (the rate ratio went up for a while): no estimate
 * rather than infinity or a negative time. */
static void test_eta_stalled(void **state)
{
    dfle_progress_eta e;
    (void)state;
    dfle_progress_eta_init(&e);
    dfle_progress_eta_update(&e, 0.0, 0.3);
    for (double t = 0.5; t <= 12.0; t += 0.5)
        assert_true(dfle_progress_eta_update(&e, t, 0.3) < 0);
    /* Moving again, the estimate returns. */
    assert_true(dfle_progress_eta_update(&e, 12.5, 0.4) > 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_eta_follows_the_recent_pace),
        cmocka_unit_test(test_eta_constant_pace),
        cmocka_unit_test(test_eta_stalled),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
