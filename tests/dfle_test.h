/*
 * dfle_test.h - shared helpers for the cmocka tests.
 *
 * cmocka 1.1.5 has no double assert (assert_float_equal casts to float),
 * so tests compare doubles with an explicit relative/absolute tolerance
 * and print both values when they differ.
 */
#ifndef DFLE_TEST_H
#define DFLE_TEST_H

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "dfle/law.h"

/* Passes when |a - b| <= abs_tol + rel_tol * |b|.  NaN never passes. */
#define assert_close(a, b, rel_tol, abs_tol)                                  \
    dfle_assert_close_impl((a), (b), (rel_tol), (abs_tol), #a, #b,            \
                           __FILE__, __LINE__)

static inline void dfle_assert_close_impl(double a, double b, double rel,
                                          double abs_tol, const char *sa,
                                          const char *sb, const char *file,
                                          int line)
{
    double d = fabs(a - b);
    if (!(d <= abs_tol + rel * fabs(b))) {
        print_error("%s = %.17g and %s = %.17g differ by %.3g "
                    "(allowed %.3g)\n",
                    sa, a, sb, b, d, abs_tol + rel * fabs(b));
        _fail(file, line);
    }
}

/* The status must be DFLE_OK; otherwise print the error message. */
#define assert_ok(status, errp)                                               \
    do {                                                                      \
        int st_ = (status);                                                   \
        if (st_ != 0) {                                                       \
            print_error("status %d: %s\n", st_, (errp)->msg);                 \
            _fail(__FILE__, __LINE__);                                        \
        }                                                                     \
    } while (0)

/* The message must contain `needle`. */
#define assert_msg_contains(msg, needle)                                      \
    do {                                                                      \
        if (strstr((msg), (needle)) == NULL) {                                \
            print_error("message \"%s\" lacks \"%s\"\n", (msg), (needle));    \
            _fail(__FILE__, __LINE__);                                        \
        }                                                                     \
    } while (0)

/* `law` without its rate_dlnS op: a second handle on the same state
 * (which stays law's: free this one first) whose ops lack the
 * derivative, so the node solvers take the difference path with it.
 * `ops` holds the copied table and must outlive the handle. */
static inline dfle_law *dfle_test_without_rate_dlnS(dfle_law *law, dfle_law_ops *ops)
{
    dfle_law *out = NULL;
    *ops = *dfle_law_get_ops(law);
    ops->rate_dlnS = NULL;
    ops->destroy = NULL;
    assert_int_equal(dfle_law_new(ops, dfle_law_state(law), &out, NULL), 0);
    return out;
}

/* The whole of file `path` as a string (free it); the file must exist. */
static inline char *dfle_test_slurp(const char *path)
{
    FILE *fp = fopen(path, "rb");
    char *s;
    long n;
    assert_non_null(fp);
    fseek(fp, 0, SEEK_END);
    n = ftell(fp);
    rewind(fp);
    s = calloc((size_t)n + 1, 1);
    assert_non_null(s);
    assert_int_equal(fread(s, 1, (size_t)n, fp), (size_t)n);
    fclose(fp);
    return s;
}

#endif
