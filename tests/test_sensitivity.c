/*
 * test_sensitivity.c - PAWN against the real SALib, its numpy/scipy
 * building blocks, the bootstrap intervals, and the CSV reader that
 * feeds them.
 *
 * The reference cases are the *_pawn.json files of $DFLE_DATA_DIR/salib (SALib
 * commit 1c375488, numpy 1.24, scipy 1.10): every index is compared with
 * its C99 hex float in `indices_hex` and must agree to MAX_ULPS units in
 * the last place (0: bit for bit); per slice the edges, row counts and
 * the KS fraction h / lcm must agree exactly.  KS statistics are also
 * checked against an independent restatement of scipy's ks_2samp
 * (searchsorted on the two sorted samples) in both its exact (N <= 10000)
 * and floating-point (N > 10000) regimes.
 *
 * Tests run from the repository root, so data paths are relative to it.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/csv.h"
#include "dfle/sampling.h"
#include "dfle/sensitivity.h"
#include "dfle_test.h"

/* The reference files, under $DFLE_DATA_DIR/salib (the test runner sets
 * DFLE_DATA_DIR). */
static const char *salib(const char *name)
{
    static char buf[8][1024];
    static int k;
    const char *dir = getenv("DFLE_DATA_DIR");
    char *b = buf[k++ % 8];
    snprintf(b, sizeof buf[0], "%s/salib/%s", dir != NULL ? dir : "(DFLE_DATA_DIR unset)", name);
    return b;
}
#define MAX_ULPS 0

/* ---------------------------------------------------------------- */
/* Helpers                                                          */
/* ---------------------------------------------------------------- */

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    char *text;
    long len;
    if (f == NULL) {
        print_error("cannot open %s (tests run from the repository root)\n", path);
        return NULL;
    }
    fseek(f, 0, SEEK_END);
    len = ftell(f);
    fseek(f, 0, SEEK_SET);
    text = malloc((size_t)len + 1);
    if (text != NULL) {
        size_t got = fread(text, 1, (size_t)len, f);
        text[got] = '\0';
    }
    fclose(f);
    return text;
}

/* Distance in units in the last place between two finite doubles. */
static uint64_t ulps_apart(double a, double b)
{
    int64_t ia, ib;
    memcpy(&ia, &a, sizeof ia);
    memcpy(&ib, &b, sizeof ib);
    if (ia < 0)
        ia = INT64_MIN - ia;
    if (ib < 0)
        ib = INT64_MIN - ib;
    return ia > ib ? (uint64_t)(ia - ib) : (uint64_t)(ib - ia);
}

#define assert_ulps(a, b, max_ulps)                                                \
    do {                                                                           \
        double a_ = (a), b_ = (b);                                                 \
        uint64_t u_ = ulps_apart(a_, b_);                                          \
        if (!(u_ <= (uint64_t)(max_ulps))) {                                       \
            print_error("%s = %a and %s = %a are %llu ulps apart (allowed %d)\n", #a, \
                        a_, #b, b_, (unsigned long long)u_, (int)(max_ulps));      \
            _fail(__FILE__, __LINE__);                                             \
        }                                                                          \
    } while (0)

/* The d-th hex float of `"stat": [...]` inside "indices_hex". */
static double json_index_hex(const char *json, const char *stat, size_t d)
{
    char key[64];
    const char *p = strstr(json, "\"indices_hex\"");
    assert_non_null(p);
    snprintf(key, sizeof key, "\"%s\": [", stat);
    p = strstr(p, key);
    assert_non_null(p);
    p += strlen(key);
    for (size_t k = 0; k <= d; k++) {
        p = strstr(p, "\"0x");
        assert_non_null(p);
        p++;
        if (k < d)
            p++;
    }
    return strtod(p, NULL);
}

/* Value of "key": in the text range [obj, end), or NAN if absent/null. */
static double json_field(const char *obj, const char *end, const char *key)
{
    char k[64];
    const char *p;
    char *stop;
    double v;
    snprintf(k, sizeof k, "\"%s\":", key);
    p = strstr(obj, k);
    if (p == NULL || p >= end)
        return NAN;
    p += strlen(k);
    v = strtod(p, &stop);
    return stop == p ? NAN : v;
}

typedef struct ref_slice {
    double x_lo, x_hi, n, h, lcm; /* h, lcm NaN for an empty slice */
} ref_slice;

/* Slice s of input `name` from "per_slice". */
static ref_slice json_slice(const char *json, const char *name, size_t s)
{
    char key[64];
    const char *p = strstr(json, "\"per_slice\""), *end;
    ref_slice r;
    assert_non_null(p);
    snprintf(key, sizeof key, "\"%s\": [", name);
    p = strstr(p, key);
    assert_non_null(p);
    snprintf(key, sizeof key, "\"s\": %zu,", s);
    p = strstr(p, key);
    assert_non_null(p);
    end = strchr(p, '}');
    assert_non_null(end);
    r.x_lo = json_field(p, end, "x_lo");
    r.x_hi = json_field(p, end, "x_hi");
    r.n = json_field(p, end, "n_in_slice");
    r.h = json_field(p, end, "ks_h");
    r.lcm = json_field(p, end, "ks_lcm");
    return r;
}

typedef struct dataset {
    dfle_csv *csv;
    const double *x[3];
    const double *y;
} dataset;

static void load(dataset *ds, const char *file, const char *const names[3])
{
    dfle_error err;
    assert_ok(dfle_csv_read(file, &ds->csv, &err), &err);
    for (int d = 0; d < 3; d++)
        assert_ok(dfle_csv_column(ds->csv, names[d], &ds->x[d], &err), &err);
    assert_ok(dfle_csv_column(ds->csv, "y", &ds->y, &err), &err);
}

/* Run PAWN on `csv_file` with S slices and compare with `json_file`. */
static void check_reference(const char *csv_file, const char *json_file,
                            const char *const names[3], size_t S, size_t N_expected)
{
    dataset ds;
    dfle_pawn_opts o;
    dfle_pawn_result r;
    dfle_error err;
    char *json = slurp(json_file);

    assert_non_null(json);
    load(&ds, csv_file, names);
    assert_int_equal(ds.csv->nrows, N_expected);
    dfle_pawn_opts_default(&o);
    o.S = S;
    assert_ok(dfle_pawn(ds.csv->nrows, 3, ds.x, ds.y, &o, &r, &err), &err);
    for (size_t d = 0; d < 3; d++) {
        for (int k = 0; k < DFLE_PAWN_NSTATS; k++) {
            double ref = json_index_hex(json, dfle_pawn_stat_name(k), d);
            double got = r.index[d * DFLE_PAWN_NSTATS + (size_t)k];
            assert_true(isfinite(ref));
            assert_ulps(got, ref, MAX_ULPS);
        }
        for (size_t s = 0; s < S; s++) {
            ref_slice rs = json_slice(json, names[d], s);
            assert_true(r.edges[d * (S + 1) + s] == rs.x_lo);
            assert_true(r.edges[d * (S + 1) + s + 1] == rs.x_hi);
            assert_true((double)r.count[d * S + s] == rs.n);
            if (rs.n == 0) {
                assert_true(isnan(r.ks[d * S + s]));
            } else {
                assert_true((double)r.ks_h[d * S + s] == rs.h);
                assert_true((double)r.ks_lcm[d * S + s] == rs.lcm);
                assert_true(r.ks[d * S + s] == rs.h / rs.lcm);
            }
        }
    }
    dfle_pawn_release(&r);
    dfle_csv_free(ds.csv);
    free(json);
}

static const char *const ishigami_names[3] = {"x1", "x2", "x3"};
static const char *const ties_names[3] = {"k1", "k2", "u3"};

/* ---------------------------------------------------------------- */
/* SALib references                                                 */
/* ---------------------------------------------------------------- */

static void test_salib_ishigami_S10(void **state)
{
    (void)state;
    check_reference(salib("ishigami_N4000.csv"), salib("ishigami_N4000_pawn.json"),
                    ishigami_names, 10, 4000);
}

static void test_salib_ishigami_S5(void **state)
{
    (void)state;
    check_reference(salib("ishigami_N4000.csv"), salib("ishigami_N4000_S5_pawn.json"),
                    ishigami_names, 5, 4000);
}

static void test_salib_ishigami_S20(void **state)
{
    (void)state;
    check_reference(salib("ishigami_N4000.csv"), salib("ishigami_N4000_S20_pawn.json"),
                    ishigami_names, 20, 4000);
}

/* Ties, edges that are data values, and one empty slice (k1's last). */
static void test_salib_ties(void **state)
{
    (void)state;
    check_reference(salib("ties_N1001.csv"), salib("ties_N1001_pawn.json"), ties_names,
                    10, 1001);
}

/* ---------------------------------------------------------------- */
/* numpy building blocks                                            */
/* ---------------------------------------------------------------- */

static void test_quantile_linear(void **state)
{
    const double x[] = {1, 2, 3, 4};
    const double ab[] = {0.495, 1.258};
    (void)state;
    assert_true(dfle_quantile_linear(x, 4, 0.0) == 1.0);
    assert_true(dfle_quantile_linear(x, 4, 1.0) == 4.0);
    assert_true(dfle_quantile_linear(x, 4, 0.5) == 2.5);
    assert_true(dfle_quantile_linear(x, 4, 1.0 / 3.0) == 2.0);
    assert_true(dfle_quantile_linear(x, 4, 0.25) == 1.75);
    assert_true(dfle_quantile_linear(x, 1, 0.7) == 1.0);
    /* t >= 0.5 interpolates down from b, as numpy's _lerp: here
     * a + (b - a) t would be one ulp higher. */
    assert_true(dfle_quantile_linear(ab, 2, 0.7) == 0x1.077318fc50481p+0);
    assert_true(0.495 + (1.258 - 0.495) * 0.7 == 0x1.077318fc50482p+0);
    assert_true(isnan(dfle_quantile_linear(x, 0, 0.5)));
}

static void test_sum_pairwise(void **state)
{
    const double a[10] = {0.2, 0.1, 0.2, 0.001, 0.001, 0.7, 0.2, 0.2, 0.1, 0.1};
    double seq = 0.0, tree, big[300], exact = 0.0;
    (void)state;
    for (int i = 0; i < 10; i++)
        seq += a[i];
    tree = ((a[0] + a[1]) + (a[2] + a[3])) + ((a[4] + a[5]) + (a[6] + a[7]));
    tree += a[8];
    tree += a[9];
    /* Eight accumulators, then the rest in order: not the plain sum. */
    assert_true(dfle_sum_pairwise(a, 10) == tree);
    assert_true(seq != tree);
    /* Fewer than eight values: plain left-to-right. */
    assert_true(dfle_sum_pairwise(a, 5) == (((a[0] + a[1]) + a[2]) + a[3]) + a[4]);
    assert_true(dfle_sum_pairwise(a, 0) == 0.0);
    /* Above 128 values: halves split at a multiple of 8 (300 -> 144 + 156). */
    for (int i = 0; i < 300; i++) {
        big[i] = 1.0 / (i + 1.0);
        exact += big[i];
    }
    assert_true(dfle_sum_pairwise(big, 300) ==
                dfle_sum_pairwise(big, 144) + dfle_sum_pairwise(big + 144, 156));
    assert_close(dfle_sum_pairwise(big, 300), exact, 1e-15, 0);
}

/* ---------------------------------------------------------------- */
/* KS statistic vs an independent restatement of scipy's ks_2samp   */
/* ---------------------------------------------------------------- */

static int cmp_double(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return (a > b) - (a < b);
}

/* Count of sorted[0..n-1] <= v (numpy searchsorted side='right'). */
static size_t upper_bound(const double *sorted, size_t n, double v)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (sorted[mid] <= v)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* scipy.stats.ks_2samp(d1, d2).statistic, mode 'auto', two-sided. */
static double scipy_ks(double *d1, size_t n1, double *d2, size_t n2)
{
    double dmax = -INFINITY, dmin = INFINITY, d;
    qsort(d1, n1, sizeof *d1, cmp_double);
    qsort(d2, n2, sizeof *d2, cmp_double);
    for (size_t i = 0; i < n1 + n2; i++) {
        double v = i < n1 ? d1[i] : d2[i - n1];
        double c1 = (double)upper_bound(d1, n1, v) / (double)n1;
        double c2 = (double)upper_bound(d2, n2, v) / (double)n2;
        double diff = c1 - c2;
        if (diff > dmax)
            dmax = diff;
        if (diff < dmin)
            dmin = diff;
    }
    {
        double minS = fmin(fmax(-dmin, 0.0), 1.0); /* np.clip(-min, 0, 1) */
        d = minS > dmax ? minS : dmax;
    }
    if ((n1 > n2 ? n1 : n2) <= 10000) {
        uint64_t a = n1, b = n2, g, lcm, h;
        while (b != 0) {
            uint64_t t = a % b;
            a = b;
            b = t;
        }
        g = a;
        lcm = (n1 / g) * n2;
        h = (uint64_t)llround(d * (double)lcm);
        d = (double)h / (double)lcm;
    }
    return d;
}

/* PAWN's slice statistics equal ks_2samp on the slice's outputs. */
static void check_ks_restatement(size_t N, size_t S, int with_ties)
{
    double *x = malloc(N * sizeof *x), *y = malloc(N * sizeof *y);
    double *sel = malloc(N * sizeof *sel), *all = malloc(N * sizeof *all);
    const double *xs[1];
    dfle_rng *rng;
    dfle_pawn_opts o;
    dfle_pawn_result r;
    dfle_error err;

    assert_non_null(x);
    assert_non_null(y);
    assert_non_null(sel);
    assert_non_null(all);
    assert_ok(dfle_rng_new(3, &rng, &err), &err);
    for (size_t i = 0; i < N; i++) {
        x[i] = dfle_rng_uniform(rng);
        y[i] = sin(6.0 * x[i]) + dfle_rng_uniform(rng);
        if (with_ties) {
            x[i] = floor(x[i] * 7.0);
            y[i] = floor(y[i] * 4.0);
        }
    }
    xs[0] = x;
    dfle_pawn_opts_default(&o);
    o.S = S;
    assert_ok(dfle_pawn(N, 1, xs, y, &o, &r, &err), &err);
    for (size_t s = 0; s < S; s++) {
        size_t n1 = 0;
        for (size_t i = 0; i < N; i++)
            if (x[i] >= r.edges[s] && x[i] < r.edges[s + 1])
                sel[n1++] = y[i];
        assert_int_equal(n1, r.count[s]);
        if (n1 == 0) {
            assert_true(isnan(r.ks[s]));
            continue;
        }
        memcpy(all, y, N * sizeof *y);
        assert_true(r.ks[s] == scipy_ks(sel, n1, all, N));
        if (N <= DFLE_PAWN_EXACT_MAX_N)
            assert_true(r.ks_lcm[s] > 0);
        else
            assert_true(r.ks_lcm[s] == 0);
    }
    /* Edges are numpy's quantiles of x at s * (1/S). */
    memcpy(all, x, N * sizeof *x);
    qsort(all, N, sizeof *all, cmp_double);
    for (size_t s = 0; s <= S; s++)
        assert_true(r.edges[s] == dfle_quantile_linear(all, N, (double)s * (1.0 / (double)S)));
    dfle_pawn_release(&r);
    dfle_rng_free(rng);
    free(x);
    free(y);
    free(sel);
    free(all);
}

static void test_ks_exact_fraction(void **state)
{
    (void)state;
    check_ks_restatement(997, 10, 0);
    check_ks_restatement(600, 7, 1);
    check_ks_restatement(10000, 3, 0);
}

static void test_ks_floating_above_10000(void **state)
{
    (void)state;
    check_ks_restatement(10001, 4, 0);
    check_ks_restatement(12000, 5, 1);
}

/* ---------------------------------------------------------------- */
/* Degenerate data and errors                                       */
/* ---------------------------------------------------------------- */

static void test_constant_output(void **state)
{
    double x[50], y[50];
    const double *xs[1] = {x};
    dfle_pawn_result r;
    dfle_error err;
    (void)state;
    for (int i = 0; i < 50; i++) {
        x[i] = i;
        y[i] = 3.0;
    }
    assert_ok(dfle_pawn(50, 1, xs, y, NULL, &r, &err), &err);
    /* Every slice has the output's distribution: KS 0, CV = 0/0. */
    assert_true(r.index[DFLE_PAWN_MAXIMUM] == 0.0);
    assert_true(r.index[DFLE_PAWN_MEAN] == 0.0);
    assert_true(isnan(r.index[DFLE_PAWN_CV]));
    dfle_pawn_release(&r);
    dfle_pawn_release(&r); /* idempotent */
}

static void test_constant_input_all_slices_empty(void **state)
{
    double x[20], y[20];
    const double *xs[1] = {x};
    dfle_pawn_result r;
    dfle_error err;
    (void)state;
    for (int i = 0; i < 20; i++) {
        x[i] = 1.5;
        y[i] = i;
    }
    assert_ok(dfle_pawn(20, 1, xs, y, NULL, &r, &err), &err);
    for (int k = 0; k < DFLE_PAWN_NSTATS; k++)
        assert_true(isnan(r.index[k]));
    for (size_t s = 0; s < r.S; s++)
        assert_int_equal(r.count[s], 0);
    dfle_pawn_release(&r);
}

static void test_pawn_errors(void **state)
{
    double x[5] = {1, 2, 3, 4, 5}, y[5] = {1, 2, 3, 4, 5};
    const double *xs[2] = {x, x};
    const char *names[2] = {"k_df", "gamma"};
    dfle_pawn_opts o;
    dfle_pawn_result r;
    dfle_error err;
    (void)state;
    dfle_pawn_opts_default(&o);
    o.names = names;
    o.output = "A_df";
    assert_int_equal(dfle_pawn(1, 1, xs, y, &o, &r, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "at least 2 rows");
    assert_int_equal(dfle_pawn(5, 0, xs, y, &o, &r, &err), DFLE_EINVAL);
    y[3] = NAN;
    assert_int_equal(dfle_pawn(5, 2, xs, y, &o, &r, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "output 'A_df'");
    assert_msg_contains(err.msg, "row 4");
    y[3] = 4;
    x[1] = INFINITY;
    assert_int_equal(dfle_pawn(5, 2, xs, y, &o, &r, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "input 'k_df'");
    assert_msg_contains(err.msg, "row 2");
    x[1] = 2;
    o.S = 0;
    assert_int_equal(dfle_pawn(5, 2, xs, y, &o, &r, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "S (slices)");
    o.S = 2;
    o.conf = 1.0;
    assert_int_equal(dfle_pawn(5, 2, xs, y, &o, &r, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "conf");
    o.conf = 0.9;
    o.threads = DFLE_PAWN_MAX_THREADS + 1;
    assert_int_equal(dfle_pawn(5, 2, xs, y, &o, &r, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "threads");
    o.threads = 2;
    assert_int_equal(dfle_pawn(5, 2, xs, y, &o, NULL, &err), DFLE_EINVAL);
    assert_ok(dfle_pawn(5, 2, xs, y, &o, &r, &err), &err);
    dfle_pawn_release(&r);
    assert_string_equal(dfle_pawn_stat_name(DFLE_PAWN_CV), "CV");
    assert_null(dfle_pawn_stat_name(DFLE_PAWN_NSTATS));
}

/* ---------------------------------------------------------------- */
/* Bootstrap                                                        */
/* ---------------------------------------------------------------- */

static void run_boot(const dataset *ds, size_t S, size_t B, unsigned long seed,
                     dfle_pawn_result *r)
{
    dfle_pawn_opts o;
    dfle_error err;
    dfle_pawn_opts_default(&o);
    o.S = S;
    o.bootstrap = B;
    o.seed = seed;
    assert_ok(dfle_pawn(ds->csv->nrows, 3, ds->x, ds->y, &o, r, &err), &err);
}

/* For clearly influential inputs the percentile interval contains the
 * point estimate, and lo <= hi for every index.  Not asserted for weak
 * inputs: there the resampled indices are biased upwards (duplicated
 * rows make each slice's empirical CDF noisier) and the interval can sit
 * above the estimate; e.g. Ishigami x3's mean at S = 10 in 17 of seeds
 * 1-20, ties k2's mean in 8 of 20 (doc/sensitivity.md). */
static void check_coverage(const char *file, const char *const names[3], size_t S,
                           const size_t *influential, size_t ninfl)
{
    dataset ds;
    dfle_pawn_result r;
    load(&ds, file, names);
    run_boot(&ds, S, 200, 1, &r);
    assert_int_equal(r.bootstrap, 200);
    for (size_t i = 0; i < 3 * DFLE_PAWN_NSTATS; i++)
        assert_true(r.lo[i] <= r.hi[i]);
    for (size_t k = 0; k < ninfl; k++) {
        size_t d = influential[k];
        for (int s = 0; s < DFLE_PAWN_NSTATS; s++) {
            size_t i = d * DFLE_PAWN_NSTATS + (size_t)s;
            if (!(r.lo[i] <= r.index[i] && r.index[i] <= r.hi[i])) {
                print_error("%s %s: %g not in [%g, %g]\n", names[d], dfle_pawn_stat_name(s),
                            r.index[i], r.lo[i], r.hi[i]);
                fail();
            }
        }
    }
    dfle_pawn_release(&r);
    dfle_csv_free(ds.csv);
}

static void test_bootstrap_covers_estimate(void **state)
{
    const size_t all[] = {0, 1, 2}, x1x2[] = {0, 1}, k1[] = {0};
    (void)state;
    check_coverage(salib("ishigami_N4000.csv"), ishigami_names, 5, all, 3);
    check_coverage(salib("ishigami_N4000.csv"), ishigami_names, 10, x1x2, 2);
    check_coverage(salib("ties_N1001.csv"), ties_names, 10, k1, 1);
}

/* One replicate equals PAWN on the materialised resample drawn with the
 * documented rule (N draws of dfle_rng_below(N) from the seed). */
static void test_bootstrap_is_row_resampling(void **state)
{
    dataset ds;
    dfle_pawn_result boot, plain;
    dfle_pawn_opts o;
    dfle_error err;
    dfle_rng *rng;
    size_t N;
    double *cols[4];
    const double *xs[3];
    (void)state;

    load(&ds, salib("ties_N1001.csv"), ties_names);
    N = ds.csv->nrows;
    run_boot(&ds, 10, 1, 77, &boot);
    assert_ok(dfle_rng_new(77, &rng, &err), &err);
    for (int c = 0; c < 4; c++) {
        cols[c] = malloc(N * sizeof *cols[c]);
        assert_non_null(cols[c]);
    }
    for (size_t i = 0; i < N; i++) {
        size_t r = (size_t)dfle_rng_below(rng, N);
        for (int c = 0; c < 3; c++)
            cols[c][i] = ds.x[c][r];
        cols[3][i] = ds.y[r];
    }
    for (int c = 0; c < 3; c++)
        xs[c] = cols[c];
    dfle_pawn_opts_default(&o);
    assert_ok(dfle_pawn(N, 3, xs, cols[3], &o, &plain, &err), &err);
    for (size_t i = 0; i < 3 * DFLE_PAWN_NSTATS; i++) {
        if (isnan(plain.index[i])) {
            assert_true(isnan(boot.lo[i]) && isnan(boot.hi[i]));
            continue;
        }
        assert_true(boot.lo[i] == plain.index[i]);
        assert_true(boot.hi[i] == plain.index[i]);
    }
    /* The point estimate is not changed by bootstrapping. */
    {
        dfle_pawn_result p0;
        for (int c = 0; c < 3; c++)
            xs[c] = ds.x[c];
        assert_ok(dfle_pawn(N, 3, xs, ds.y, &o, &p0, &err), &err);
        for (size_t i = 0; i < 3 * DFLE_PAWN_NSTATS; i++)
            assert_true(boot.index[i] == p0.index[i] ||
                        (isnan(boot.index[i]) && isnan(p0.index[i])));
        dfle_pawn_release(&p0);
    }
    for (int c = 0; c < 4; c++)
        free(cols[c]);
    dfle_rng_free(rng);
    dfle_pawn_release(&boot);
    dfle_pawn_release(&plain);
    dfle_csv_free(ds.csv);
}

static void test_bootstrap_reproducible(void **state)
{
    dataset ds;
    dfle_pawn_result a, b, c;
    size_t differ = 0;
    (void)state;
    load(&ds, salib("ties_N1001.csv"), ties_names);
    run_boot(&ds, 5, 50, 9, &a);
    run_boot(&ds, 5, 50, 9, &b);
    run_boot(&ds, 5, 50, 10, &c);
    assert_memory_equal(a.lo, b.lo, 3 * DFLE_PAWN_NSTATS * sizeof(double));
    assert_memory_equal(a.hi, b.hi, 3 * DFLE_PAWN_NSTATS * sizeof(double));
    for (size_t i = 0; i < 3 * DFLE_PAWN_NSTATS; i++)
        differ += a.lo[i] != c.lo[i] || a.hi[i] != c.hi[i];
    assert_true(differ > 0);
    /* A wider level gives a wider (or equal) interval. */
    {
        dfle_pawn_opts o;
        dfle_pawn_result w;
        dfle_error err;
        dfle_pawn_opts_default(&o);
        o.S = 5;
        o.bootstrap = 50;
        o.seed = 9;
        o.conf = 0.99;
        assert_ok(dfle_pawn(ds.csv->nrows, 3, ds.x, ds.y, &o, &w, &err), &err);
        for (size_t i = 0; i < 3 * DFLE_PAWN_NSTATS; i++) {
            assert_true(w.lo[i] <= a.lo[i]);
            assert_true(w.hi[i] >= a.hi[i]);
        }
        dfle_pawn_release(&w);
    }
    dfle_pawn_release(&a);
    dfle_pawn_release(&b);
    dfle_pawn_release(&c);
    dfle_csv_free(ds.csv);
}

/* ---------------------------------------------------------------- */
/* One pass per input, and threads: the same numbers                */
/* ---------------------------------------------------------------- */

/* Everything two results hold, bit for bit. */
static void assert_same_result(const dfle_pawn_result *a, const dfle_pawn_result *b)
{
    const size_t D = a->D, S = a->S;
    assert_int_equal(a->N, b->N);
    assert_int_equal(D, b->D);
    assert_int_equal(S, b->S);
    assert_memory_equal(a->index, b->index, D * DFLE_PAWN_NSTATS * sizeof *a->index);
    assert_memory_equal(a->edges, b->edges, D * (S + 1) * sizeof *a->edges);
    assert_memory_equal(a->ks, b->ks, D * S * sizeof *a->ks);
    assert_memory_equal(a->count, b->count, D * S * sizeof *a->count);
    assert_memory_equal(a->ks_h, b->ks_h, D * S * sizeof *a->ks_h);
    assert_memory_equal(a->ks_lcm, b->ks_lcm, D * S * sizeof *a->ks_lcm);
    assert_int_equal(a->bootstrap, b->bootstrap);
    if (a->bootstrap > 0) {
        assert_memory_equal(a->lo, b->lo, D * DFLE_PAWN_NSTATS * sizeof *a->lo);
        assert_memory_equal(a->hi, b->hi, D * DFLE_PAWN_NSTATS * sizeof *a->hi);
    }
}

/* PAWN of D synthetic inputs (and the output, column D) with options o. */
static void run_on(double **cols, size_t N, size_t D, const dfle_pawn_opts *o,
                   dfle_pawn_result *r)
{
    const double *xs[4];
    dfle_error err;
    for (size_t d = 0; d < D; d++)
        xs[d] = cols[d];
    assert_ok(dfle_pawn(N, D, xs, cols[D], o, r, &err), &err);
}

/* The slices of every input found in one pass (the default) and in a pass
 * per slice give the same result, bootstrap included: continuous data,
 * ties in x and y, more slices than rows, both KS regimes. */
static void check_fused(size_t N, size_t D, size_t S, int ties, size_t B)
{
    double *cols[4];
    dfle_rng *rng;
    dfle_error err;
    dfle_pawn_opts o;
    dfle_pawn_result fused, ref;

    assert_true(D <= 3);
    assert_ok(dfle_rng_new(11, &rng, &err), &err);
    for (size_t d = 0; d <= D; d++) {
        cols[d] = malloc(N * sizeof *cols[d]);
        assert_non_null(cols[d]);
    }
    for (size_t i = 0; i < N; i++) {
        double y = 0.0;
        for (size_t d = 0; d < D; d++) {
            double u = dfle_rng_uniform(rng);
            cols[d][i] = ties ? floor(u * 9.0) : u;
            y += (double)(d + 1) * u * u;
        }
        y += 0.3 * dfle_rng_uniform(rng);
        cols[D][i] = ties ? floor(y * 5.0) : y;
    }
    dfle_pawn_opts_default(&o);
    o.S = S;
    o.bootstrap = B;
    o.seed = 5;
    run_on(cols, N, D, &o, &fused);
    o.per_slice = 1;
    run_on(cols, N, D, &o, &ref);
    assert_same_result(&fused, &ref);
    dfle_pawn_release(&fused);
    dfle_pawn_release(&ref);
    for (size_t d = 0; d <= D; d++)
        free(cols[d]);
    dfle_rng_free(rng);
}

static void test_one_pass_per_input_equals_per_slice(void **state)
{
    dataset ds;
    dfle_pawn_opts o;
    dfle_pawn_result fused, ref;
    dfle_error err;
    (void)state;
    check_fused(997, 3, 10, 0, 20);
    check_fused(600, 2, 7, 1, 20);
    check_fused(40, 2, 90, 1, 10);  /* more slices than rows: most are empty */
    check_fused(300, 1, 1, 0, 5);   /* one slice */
    check_fused(12000, 2, 5, 0, 3); /* the floating-point KS regime */
    check_fused(10001, 1, 4, 1, 2);
    /* and the SALib case with ties and an empty slice */
    load(&ds, salib("ties_N1001.csv"), ties_names);
    dfle_pawn_opts_default(&o);
    o.bootstrap = 30;
    assert_ok(dfle_pawn(ds.csv->nrows, 3, ds.x, ds.y, &o, &fused, &err), &err);
    o.per_slice = 1;
    assert_ok(dfle_pawn(ds.csv->nrows, 3, ds.x, ds.y, &o, &ref, &err), &err);
    assert_same_result(&fused, &ref);
    dfle_pawn_release(&fused);
    dfle_pawn_release(&ref);
    dfle_csv_free(ds.csv);
}

/* Bootstrap replicates spread over threads give what one thread gives,
 * bit for bit, for any count (more threads than replicates included). */
static void test_bootstrap_threads_identical(void **state)
{
    static const size_t counts[] = {2, 3, 7, 64};
    dataset ds;
    dfle_pawn_opts o;
    dfle_pawn_result one, many;
    dfle_error err;
    (void)state;
    load(&ds, salib("ties_N1001.csv"), ties_names);
    dfle_pawn_opts_default(&o);
    o.S = 7;
    o.bootstrap = 41;
    o.seed = 123;
    assert_ok(dfle_pawn(ds.csv->nrows, 3, ds.x, ds.y, &o, &one, &err), &err);
    for (size_t k = 0; k < sizeof counts / sizeof counts[0]; k++) {
        o.threads = counts[k];
        assert_ok(dfle_pawn(ds.csv->nrows, 3, ds.x, ds.y, &o, &many, &err), &err);
        assert_same_result(&one, &many);
        dfle_pawn_release(&many);
    }
    dfle_pawn_release(&one);
    dfle_csv_free(ds.csv);
}

/* ---------------------------------------------------------------- */
/* CSV reader                                                       */
/* ---------------------------------------------------------------- */

static dfle_csv *parse_ok(const char *text)
{
    dfle_csv *c = NULL;
    dfle_error err;
    assert_ok(dfle_csv_parse(text, strlen(text), "t.csv", &c, &err), &err);
    return c;
}

static void expect_parse_error(const char *text, const char *needle)
{
    dfle_csv *c = (dfle_csv *)&c;
    dfle_error err;
    assert_int_equal(dfle_csv_parse(text, strlen(text), "t.csv", &c, &err), DFLE_EINVAL);
    assert_null(c);
    assert_msg_contains(err.msg, needle);
}

static void test_csv_basic(void **state)
{
    dfle_csv *c;
    const double *col;
    dfle_error err;
    (void)state;
    c = parse_ok("# a comment\r\n a , \"b, c\",d\r\n1,2.5,0x1p-2\r\n\r\n  # more\n-3e2, ,nan\n4,5,6");
    assert_int_equal(c->ncols, 3);
    assert_int_equal(c->nrows, 3);
    assert_string_equal(c->names[0], "a");
    assert_string_equal(c->names[1], "b, c");
    assert_ok(dfle_csv_column(c, "d", &col, &err), &err);
    assert_true(col[0] == 0.25);
    assert_true(isnan(col[1]));
    assert_true(col[2] == 6);
    assert_ok(dfle_csv_column(c, "b, c", &col, &err), &err);
    assert_true(col[0] == 2.5);
    assert_true(isnan(col[1])); /* empty field: missing */
    assert_ok(dfle_csv_column(c, "a", &col, &err), &err);
    assert_true(col[1] == -300);
    assert_int_equal(c->line[0], 3);
    assert_int_equal(c->line[1], 6);
    assert_int_equal(c->line[2], 7);
    assert_int_equal(dfle_csv_find(c, "zz"), -1);
    dfle_csv_free(c);
    dfle_csv_free(NULL);
}

/* Hostile bytes: a NUL ends a C string, so "7\0junk" once read as 7;
 * a UTF-8 byte-order mark once became part of the first name ("no
 * column 'x1'"); a device such as /dev/zero was read without end. */
static void test_csv_hostile_bytes(void **state)
{
    static const char nul[] = "x1,y\n1,2\n7\0junk,3\n";
    dfle_csv *c = NULL;
    const double *col;
    dfle_error err;
    (void)state;
    assert_int_equal(dfle_csv_parse(nul, sizeof nul - 1, "t.csv", &c, &err), DFLE_EINVAL);
    assert_null(c);
    assert_msg_contains(err.msg, "t.csv:3:");
    assert_msg_contains(err.msg, "NUL");
    c = parse_ok("\xEF\xBB\xBFx1,y\n1,2\n");
    assert_ok(dfle_csv_column(c, "x1", &col, &err), &err);
    assert_true(col[0] == 1);
    dfle_csv_free(c);
    assert_int_equal(dfle_csv_read("/dev/zero", &c, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "not a regular file");
    assert_int_equal(dfle_csv_read("/", &c, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "directory");
}

static void test_csv_text_column(void **state)
{
    dfle_csv *c;
    const double *col;
    dfle_error err;
    (void)state;
    c = parse_ok("x,status,y\n1,ok,2\n3,\"diverged, NaN slope\",4\n5,ok,6\n");
    assert_ok(dfle_csv_column(c, "y", &col, &err), &err);
    assert_true(col[2] == 6);
    assert_int_equal(dfle_csv_column(c, "status", &col, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "t.csv:2:");
    assert_msg_contains(err.msg, "'ok'");
    assert_int_equal(dfle_csv_column(c, "S_df", &col, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "no column 'S_df'");
    assert_msg_contains(err.msg, "x, status, y");
    dfle_csv_free(c);
}

static void test_csv_errors(void **state)
{
    dfle_csv *c = NULL;
    dfle_error err;
    (void)state;
    expect_parse_error("a,b\n1,2\n3\n", "t.csv:3: 1 fields, but the header has 2");
    expect_parse_error("a,b\n1,2,3\n", "t.csv:2: 3 fields");
    expect_parse_error("a,,c\n", "t.csv:1: column 2 of the header has no name");
    expect_parse_error("a,b,a\n", "'a' appears twice");
    expect_parse_error("# only a comment\n\n", "no header");
    expect_parse_error("a,b\n\"1,2\n", "t.csv:2: unterminated quote");
    assert_int_equal(dfle_csv_read("no/such/file.csv", &c, &err), DFLE_EIO);
    assert_null(c);
    assert_msg_contains(err.msg, "no/such/file.csv");
    c = parse_ok("a,b\n");
    assert_int_equal(c->nrows, 0);
    dfle_csv_free(c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_salib_ishigami_S10),
        cmocka_unit_test(test_salib_ishigami_S5),
        cmocka_unit_test(test_salib_ishigami_S20),
        cmocka_unit_test(test_salib_ties),
        cmocka_unit_test(test_quantile_linear),
        cmocka_unit_test(test_sum_pairwise),
        cmocka_unit_test(test_ks_exact_fraction),
        cmocka_unit_test(test_ks_floating_above_10000),
        cmocka_unit_test(test_constant_output),
        cmocka_unit_test(test_constant_input_all_slices_empty),
        cmocka_unit_test(test_pawn_errors),
        cmocka_unit_test(test_bootstrap_covers_estimate),
        cmocka_unit_test(test_bootstrap_is_row_resampling),
        cmocka_unit_test(test_bootstrap_reproducible),
        cmocka_unit_test(test_one_pass_per_input_equals_per_slice),
        cmocka_unit_test(test_bootstrap_threads_identical),
        cmocka_unit_test(test_csv_basic),
        cmocka_unit_test(test_csv_text_column),
        cmocka_unit_test(test_csv_hostile_bytes),
        cmocka_unit_test(test_csv_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
