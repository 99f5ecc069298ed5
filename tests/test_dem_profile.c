/*
 * test_dem_profile.c - profiles, networks and their slope-area data:
 * on a synthetic valley whose answers are exact, and on the Big Tujunga
 * SRTM DEM ($DFLE_DATA_DIR/dem), read both as GeoTIFF and as ESRI ASCII,
 * with the outlets of the paper's Fig. 1.
 *
 * The test runner (tests/run-tests.sh) sets DFLE_DATA_DIR.
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "dfle/analysis.h"
#include "dfle/dem.h"
#include "dfle_test.h"
#include "utm_check.h"

static char data_path[1024];

static const char *dem_file(const char *name)
{
    const char *dir = getenv("DFLE_DATA_DIR");
    snprintf(data_path, sizeof data_path, "%s/dem/%s", dir ? dir : "(DFLE_DATA_DIR unset)", name);
    return data_path;
}

/* The paper's Fig. 1 outlets (UTM 11N, m). */
static const double black[2] = {396887, 3799338};
static const double blue[2] = {384971, 3799277};
static const double orange[2] = {417896, 3792642}; /* east of the DEM */

/* ---------------------------------------------------------------- */
/* A synthetic valley                                               */
/* ---------------------------------------------------------------- */

/*
 * 40 x 7 cells of 10 m, z = 100 - c + 5 |r - 3| (row r, column c): a
 * V-shaped valley along row 3 falling 1 m per 10 m towards the east
 * edge.  Side cells drain straight to the axis (S or N: drop 5 over
 * 10 m beats the diagonal's 6 over 14.1 m); the axis drains east (0.1).
 * The axis cell (3, c) collects its own column and everything west:
 * 7 (c + 1) cells of 100 m^2.
 */
static dfle_dem *valley(void)
{
    enum { NX = 40, NY = 7 };
    double z[NX * NY];
    dfle_dem_geo g = {5000.0, 8000.0, 10.0, 10.0};
    dfle_dem *d;
    dfle_error err;
    for (int r = 0; r < NY; r++)
        for (int c = 0; c < NX; c++)
            z[r * NX + c] = 100.0 - c + 5.0 * abs(r - 3);
    if (dfle_dem_new(NX, NY, z, &g, &d, &err) != DFLE_OK) {
        print_error("%s\n", err.msg);
        fail();
    }
    return d;
}

/* Centre of the valley cell (row 3, column c). */
static double valley_E(int c) { return 5000.0 + 10.0 * c + 5.0; }
static const double valley_N = 8000.0 - 35.0;

static void test_valley_profile_from_outlet(void **state)
{
    dfle_dem *d = valley();
    dfle_profile_opts o;
    dfle_profile *p;
    dfle_error err;
    const double *x, *A, *S, *z, *D;
    double given[2], snapped[2];
    (void)state;

    dfle_profile_opts_default(&o);
    /* 12 m off the outlet cell's centre, on a side cell: snapped to the
     * axis cell of largest area within the radius (2 diagonals, 28 m). */
    o.E = valley_E(39) - 3;
    o.N = valley_N + 12;
    o.A_min = 500; /* stop on the axis: side columns hold 300 m^2 */
    o.slope.ds = 30;
    assert_ok(dfle_dem_profile(d, &o, &p, &err), &err);
    assert_int_equal(dfle_profile_size(p), 40);
    assert_false(dfle_profile_is_network(p));
    dfle_profile_point(p, given, snapped);
    assert_close(snapped[0], valley_E(39), 0, 1e-9);
    assert_close(snapped[1], valley_N, 0, 1e-9);
    x = dfle_profile_field(p, DFLE_PROFILE_X);
    D = dfle_profile_field(p, DFLE_PROFILE_D);
    A = dfle_profile_field(p, DFLE_PROFILE_A);
    S = dfle_profile_field(p, DFLE_PROFILE_S);
    z = dfle_profile_field(p, DFLE_PROFILE_Z);
    for (int i = 0; i < 40; i++) {
        assert_close(x[i], 10.0 * i, 0, 1e-9);
        assert_close(D[i], 390.0 - 10.0 * i, 0, 1e-9);
        assert_close(A[i], 700.0 * (i + 1), 0, 1e-9);
        assert_close(z[i], 100.0 - i, 0, 0);
        assert_int_equal(dfle_profile_receiver(p)[i], i < 39 ? (size_t)i + 2 : 0);
        /* The window (15 m each way) lies on the axis from i = 2 on;
         * at the outlet it is cut short but the drop is still linear. */
        if (i >= 2)
            assert_close(S[i], 0.1, 1e-12, 0);
    }
    dfle_profile_free(p);

    /* The same with a vertical interval: 2 m of drop spans 20 m. */
    o.slope.ds = 0;
    o.slope.dz = 2;
    assert_ok(dfle_dem_profile(d, &o, &p, &err), &err);
    S = dfle_profile_field(p, DFLE_PROFILE_S);
    for (int i = 2; i < 40; i++)
        assert_close(S[i], 0.1, 1e-12, 0);
    assert_close(dfle_profile_slope(p).dz, 2.0, 0, 0);
    assert_close(dfle_profile_slope(p).ds, 0.0, 0, 0);
    dfle_profile_free(p);

    /* Defaults: ds = 3 cells. */
    o.slope.dz = 0;
    assert_ok(dfle_dem_profile(d, &o, &p, &err), &err);
    assert_close(dfle_profile_slope(p).ds, 30.0, 0, 0);
    dfle_profile_free(p);
    dfle_dem_free(d);
}

static void test_valley_profile_from_head(void **state)
{
    dfle_dem *d = valley();
    dfle_profile_opts o;
    dfle_profile *p;
    dfle_error err;
    (void)state;

    dfle_profile_opts_default(&o);
    o.from_head = 1;
    o.E = valley_E(5);
    o.N = valley_N;
    assert_ok(dfle_dem_profile(d, &o, &p, &err), &err);
    assert_int_equal(dfle_profile_size(p), 35); /* columns 5..39 */
    assert_close(dfle_profile_field(p, DFLE_PROFILE_A)[0], 700.0 * 6, 0, 1e-9);
    dfle_profile_free(p);

    /* Stop at the first cell with A >= 10000 m^2: 7 (c + 1) >= 100,
     * c = 14: columns 5..14. */
    o.A_max = 1e4;
    assert_ok(dfle_dem_profile(d, &o, &p, &err), &err);
    assert_int_equal(dfle_profile_size(p), 10);
    assert_close(dfle_profile_field(p, DFLE_PROFILE_A)[9], 10500.0, 0, 1e-9);
    dfle_profile_free(p);

    /* A head on the outlet itself: a single cell is no profile. */
    o.A_max = 0;
    o.E = valley_E(39);
    assert_int_equal(dfle_dem_profile(d, &o, &p, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "single cell");

    /* Outside the grid, named. */
    o.E = 4000;
    assert_int_equal(dfle_dem_profile(d, &o, &p, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "head (4000 E, 7965 N) is outside the grid");
    o.from_head = 0;
    assert_int_equal(dfle_dem_profile(d, &o, &p, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "outlet (4000 E");
    /* Both slope intervals at once. */
    o.E = valley_E(39);
    o.slope.ds = 30;
    o.slope.dz = 2;
    assert_int_equal(dfle_dem_profile(d, &o, &p, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "not both");
    dfle_dem_free(d);
}

static void test_valley_network_and_channel(void **state)
{
    dfle_dem *d = valley();
    dfle_network_opts no;
    dfle_profile_opts po;
    dfle_profile *net, *p;
    dfle_channel *ch;
    dfle_error err;
    size_t n;
    (void)state;

    /* A_min = 500 m^2: exactly the 40 axis cells (side cells hold at
     * most 300). */
    dfle_network_opts_default(&no);
    no.A_min = 500;
    no.slope.ds = 30;
    assert_ok(dfle_dem_network(d, &no, &net, &err), &err);
    n = dfle_profile_size(net);
    assert_int_equal(n, 40);
    assert_true(dfle_profile_is_network(net));
    for (size_t i = 0; i < n; i++) {
        const size_t r = dfle_profile_receiver(net)[i];
        /* Topological order: every receiver comes later. */
        assert_true(r == 0 || r > i + 1);
        if (dfle_profile_field(net, DFLE_PROFILE_A)[i] >= 2100) /* window on the axis */
            assert_close(dfle_profile_field(net, DFLE_PROFILE_S)[i], 0.1, 1e-12, 0);
    }
    assert_close(dfle_profile_field(net, DFLE_PROFILE_D)[0], 390.0, 0, 1e-9);
    assert_int_equal(dfle_profile_channel(net, 5, 0.05, 0.3, &ch, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "network");
    {
        /* Its main stem: the axis from the west edge to the outlet, head
         * first, x from the head, areas growing by 700 m^2 a cell; a
         * model channel runs on it. */
        dfle_profile *stem;
        assert_ok(dfle_profile_main_stem(net, &stem, &err), &err);
        assert_false(dfle_profile_is_network(stem));
        assert_int_equal(dfle_profile_size(stem), 40);
        for (size_t i = 0; i < 40; i++) {
            assert_close(dfle_profile_field(stem, DFLE_PROFILE_A)[i], 700.0 * (double)(i + 1),
                         1e-12, 0);
            assert_close(dfle_profile_field(stem, DFLE_PROFILE_X)[i], 10.0 * (double)i, 0, 1e-9);
            assert_close(dfle_profile_field(stem, DFLE_PROFILE_E)[i], valley_E((int)i), 0, 1e-9);
            assert_int_equal(dfle_profile_receiver(stem)[i], i + 1 < 40 ? i + 2 : 0);
        }
        assert_ok(dfle_profile_channel(stem, 5, 0.05, 0.3, &ch, &err), &err);
        assert_int_equal(dfle_channel_size(ch), 79);
        dfle_channel_free(ch);
        dfle_profile_free(stem);
    }
    dfle_profile_free(net);

    no.A_min = 1e9;
    assert_int_equal(dfle_dem_network(d, &no, &net, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "A_min");

    /* A model channel on the profile's A(x): nodes every 5 m over 390 m,
     * A interpolated linearly between the 10 m cells. */
    dfle_profile_opts_default(&po);
    po.E = valley_E(39);
    po.N = valley_N;
    po.A_min = 500;
    assert_ok(dfle_dem_profile(d, &po, &p, &err), &err);
    assert_ok(dfle_profile_channel(p, 5.0, 0.05, 0.3, &ch, &err), &err);
    assert_int_equal(dfle_channel_size(ch), 79);
    assert_close(dfle_channel_dx(ch), 5.0, 0, 0);
    assert_close(dfle_channel_A(ch)[0], 700.0, 1e-12, 0);
    assert_close(dfle_channel_A(ch)[1], 1050.0, 1e-12, 0);
    assert_close(dfle_channel_A(ch)[78], 28000.0, 1e-12, 0);
    assert_close(dfle_channel_w(ch)[78], 0.05 * pow(28000.0, 0.3), 1e-12, 0);
    dfle_channel_free(ch);
    assert_int_equal(dfle_profile_channel(p, 300, 0.05, 0.3, &ch, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "2 dx");
    assert_int_equal(dfle_profile_channel(p, 0, 0.05, 0.3, &ch, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "dx must be > 0");
    dfle_profile_free(p);
    dfle_dem_free(d);
}

/* ---------------------------------------------------------------- */
/* Big Tujunga                                                      */
/* ---------------------------------------------------------------- */

static dfle_dem *tif, *asc; /* filled and routed by the group setup */

static int setup(void **state)
{
    dfle_error err;
    (void)state;
    if (dfle_dem_read(dem_file("srtm_bigtujunga30m_utm11.tif"), NULL, &tif, &err) != DFLE_OK ||
        dfle_dem_read(dem_file("srtm_bigtujunga30m_utm11.asc"), NULL, &asc, &err) != DFLE_OK) {
        fprintf(stderr, "%s (run from the repository root or set DFLE_DATA_DIR)\n", err.msg);
        return -1;
    }
    return 0;
}

/* Tests after the first need the filled grid whatever the first did. */
static void filled_tif(void)
{
    dfle_error err;
    if (!dfle_dem_is_filled(tif))
        assert_ok(dfle_dem_fill(tif, NULL, &err), &err);
}

static int teardown(void **state)
{
    (void)state;
    dfle_dem_free(tif);
    dfle_dem_free(asc);
    return 0;
}

/* The same grid as GeoTIFF (Int16) and ESRI ASCII (+ .prj): identical
 * elevations, georeferencing, CRS, fill, directions and areas. */
static void test_tif_equals_asc(void **state)
{
    size_t n;
    double e1[4], e2[4];
    dfle_dem_fill_stats s1, s2;
    dfle_error err;
    (void)state;

    assert_int_equal(dfle_dem_nx(tif), 1197);
    assert_int_equal(dfle_dem_ny(tif), 643);
    assert_int_equal(dfle_dem_nx(asc), 1197);
    assert_int_equal(dfle_dem_ny(asc), 643);
    n = 1197 * 643;
    assert_close(dfle_dem_dx(tif), 30.0, 0, 1e-9);
    assert_close(dfle_dem_dy(asc), 30.0, 0, 1e-9);
    dfle_dem_extent(tif, e1);
    dfle_dem_extent(asc, e2);
    for (int k = 0; k < 4; k++)
        assert_close(e1[k], e2[k], 0, 1e-6);
    assert_close(e1[0], 376313.655, 0, 1e-3);
    assert_close(e1[3], 3807917.828, 0, 1e-3);
    assert_int_equal(dfle_dem_epsg(tif), 32611);
    assert_int_equal(dfle_dem_epsg(asc), 32611);
    assert_false(dfle_dem_is_geographic(tif));
    assert_int_equal(dfle_dem_nodata_count(tif), 0);
    assert_int_equal(dfle_dem_nodata_count(asc), 0);
    assert_memory_equal(dfle_dem_z(tif), dfle_dem_z(asc), n * sizeof(double));
    {
        double zmin = INFINITY, zmax = -INFINITY;
        for (size_t i = 0; i < n; i++) {
            zmin = fmin(zmin, dfle_dem_z(tif)[i]);
            zmax = fmax(zmax, dfle_dem_z(tif)[i]);
        }
        assert_close(zmin, 315, 0, 0); /* data/README.md: z = 315-2295 m */
        assert_close(zmax, 2295, 0, 0);
    }

    assert_ok(dfle_dem_fill(tif, &s1, &err), &err);
    assert_ok(dfle_dem_fill(asc, &s2, &err), &err);
    assert_int_equal(s1.raised, s2.raised);
    assert_true(s1.raised > 0);
    assert_memory_equal(dfle_dem_z(tif), dfle_dem_z(asc), n * sizeof(double));
    assert_ok(dfle_dem_route(tif, &err), &err);
    assert_ok(dfle_dem_route(asc, &err), &err);
    assert_int_equal(dfle_dem_sink_count(tif), 0);
    assert_memory_equal(dfle_dem_dir(tif), dfle_dem_dir(asc), n);
    assert_memory_equal(dfle_dem_area(tif), dfle_dem_area(asc), n * sizeof(double));
    /* Every cell drains off the grid somewhere: the outlets' areas sum
     * to cells x 900 m^2. */
    {
        double out = 0;
        for (size_t i = 0; i < n; i++)
            if (dfle_dem_receiver(tif, i) < 0)
                out += dfle_dem_area(tif)[i];
        assert_close(out, (double)n * 900.0, 1e-12, 0);
    }
}

/* Profiles from the two Fig. 1 outlets inside the DEM. */
static void test_fig1_profiles(void **state)
{
    const double *out[2] = {black, blue};
    dfle_error err;
    (void)state;
    filled_tif();

    for (int k = 0; k < 2; k++) {
        dfle_profile_opts o;
        dfle_profile *p;
        const double *x, *z, *A, *S, *E, *N;
        double given[2], snapped[2];
        dfle_eq2_fit fit;
        size_t n;

        dfle_profile_opts_default(&o);
        o.E = out[k][0];
        o.N = out[k][1];
        assert_ok(dfle_dem_profile(tif, &o, &p, &err), &err);
        n = dfle_profile_size(p);
        assert_true(n > 100);
        x = dfle_profile_field(p, DFLE_PROFILE_X);
        z = dfle_profile_field(p, DFLE_PROFILE_Z);
        A = dfle_profile_field(p, DFLE_PROFILE_A);
        S = dfle_profile_field(p, DFLE_PROFILE_S);
        E = dfle_profile_field(p, DFLE_PROFILE_E);
        N = dfle_profile_field(p, DFLE_PROFILE_N);
        /* Snapped within the default radius (2 diagonals = 84.9 m). */
        dfle_profile_point(p, given, snapped);
        assert_true(hypot(snapped[0] - given[0], snapped[1] - given[1]) <= 84.86);
        assert_close(E[n - 1], snapped[0], 0, 1e-9);
        assert_close(N[n - 1], snapped[1], 0, 1e-9);
        /* Head at a divide (one cell), ~10 km^2 at the outlet. */
        assert_close(A[0], 900.0, 0, 0);
        assert_true(A[n - 1] > 5e6 && A[n - 1] < 2e7);
        for (size_t i = 0; i < n; i++) {
            assert_true(isfinite(S[i]) && S[i] >= 0);
            if (i == 0)
                continue;
            assert_true(A[i] >= A[i - 1]); /* monotone area      */
            assert_true(z[i] <= z[i - 1]); /* and elevation      */
            assert_true(x[i] > x[i - 1]);
            /* Consecutive cells are D8 neighbours. */
            assert_true(fabs(E[i] - E[i - 1]) <= 30.0 + 1e-6 &&
                        fabs(N[i] - N[i - 1]) <= 30.0 + 1e-6);
        }
        /* The main stem's slope-area data give a fit of Eq. (2). */
        assert_ok(dfle_slope_area_fit(n, A, S, 100, NULL, &fit, &err), &err);
        assert_true(fit.r2 > 0.6);
        assert_true(fit.S_df > 0.1 && fit.S_df < 1.5);
        assert_true(fit.A_df > A[0] && fit.A_df < A[n - 1]);
        dfle_profile_free(p);
    }
}

/* The network above a Fig. 1 outlet, every cell (A_min = one cell):
 * its cells' areas add up to the catchment area, the outlet's drainage
 * area; and the binned fit is the paper's kind (R^2 > 0.9). */
static void test_fig1_network(void **state)
{
    dfle_network_opts o;
    dfle_profile *net;
    dfle_eq2_fit fit;
    dfle_error err;
    const double *A, *S;
    size_t n, outlet = 0;
    (void)state;
    filled_tif();

    dfle_network_opts_default(&o);
    o.A_min = 900;
    o.has_outlet = 1;
    o.E = black[0];
    o.N = black[1];
    assert_ok(dfle_dem_network(tif, &o, &net, &err), &err);
    n = dfle_profile_size(net);
    A = dfle_profile_field(net, DFLE_PROFILE_A);
    S = dfle_profile_field(net, DFLE_PROFILE_S);
    for (size_t i = 0; i < n; i++) {
        assert_true(isfinite(S[i]) && S[i] >= 0);
        if (dfle_profile_receiver(net)[i] == 0) {
            outlet++;
            assert_close((double)n * 900.0, A[i], 1e-12, 0);
            assert_int_equal(i, n - 1); /* the outlet comes last */
        }
    }
    assert_int_equal(outlet, 1);
    assert_ok(dfle_slope_area_fit(n, A, S, 100, NULL, &fit, &err), &err);
    assert_true(fit.r2 > 0.9);
    assert_true(fit.S_df > 0.2 && fit.S_df < 1.0);
    assert_true(fit.A_df > 1e4 && fit.A_df < 1e7);
    dfle_profile_free(net);
}

static void test_outlet_errors(void **state)
{
    dfle_profile_opts o;
    dfle_profile *p;
    dfle_dem *raw;
    dfle_error err;
    (void)state;

    /* The orange outlet lies east of the DEM (E 376314..412224). */
    dfle_profile_opts_default(&o);
    o.E = orange[0];
    o.N = orange[1];
    assert_int_equal(dfle_dem_profile(tif, &o, &p, &err), DFLE_EINVAL);
    assert_null(p);
    assert_msg_contains(err.msg, "outlet (417896 E, 3792642 N) is outside the grid "
                                 "(E 376314..412224, N 3788628..3807918)");

    /* An unfilled DEM has pits: a profile would stop short at them. */
    assert_ok(dfle_dem_read(dem_file("srtm_bigtujunga30m_utm11.tif"), NULL, &raw, &err), &err);
    o.E = black[0];
    o.N = black[1];
    assert_int_equal(dfle_dem_profile(raw, &o, &p, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "pit");
    assert_msg_contains(err.msg, "fill");
    dfle_dem_free(raw);
}

static void test_write_csv(void **state)
{
    dfle_profile_opts o;
    dfle_profile *p;
    dfle_error err;
    char path[] = "/tmp/dfle_test_profile_XXXXXX", line[256];
    int fd, lines = 0;
    FILE *f;
    (void)state;
    filled_tif();

    dfle_profile_opts_default(&o);
    o.E = blue[0];
    o.N = blue[1];
    assert_ok(dfle_dem_profile(tif, &o, &p, &err), &err);
    fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    assert_ok(dfle_profile_write_csv(p, path, NULL, &err), &err);
    f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(line, sizeof line, f));
    assert_string_equal(line, "# units: E=m, N=m, x=m, d=m, z=m, A=m^2, S=-, lon=degrees_east, "
                              "lat=degrees_north\n");
    assert_non_null(fgets(line, sizeof line, f));
    assert_string_equal(line, "E,N,x,d,z,A,S,receiver,lon,lat\n");
    while (fgets(line, sizeof line, f) != NULL) {
        /* lon and lat of the DEM's UTM 11N, against Snyder's formulas
         * (10 significant digits: 1e-7 degrees, about a centimetre) */
        double E, N, lon, lat, want_lon, want_lat;
        assert_int_equal(sscanf(line, "%lf,%lf,%*f,%*f,%*f,%*f,%*f,%*f,%lf,%lf", &E, &N, &lon,
                                &lat), 4);
        utm_to_lonlat(11, E, N, &want_lon, &want_lat);
        assert_close(lon, want_lon, 0, 2e-7);
        assert_close(lat, want_lat, 0, 2e-7);
        lines++;
    }
    fclose(f);
    remove(path);
    assert_int_equal(lines, (int)dfle_profile_size(p));
    {
        /* With its provenance: the CRS, the DEM, the point given and
         * snapped. */
        dfle_record *rec;
        char first[512];
        assert_ok(dfle_record_new(&rec, &err), &err);
        dfle_profile_describe(p, rec);
        assert_ok(dfle_profile_write_csv(p, path, rec, &err), &err);
        dfle_record_free(rec);
        f = fopen(path, "r");
        assert_non_null(f);
        assert_non_null(fgets(first, sizeof first, f));
        assert_string_equal(first, "# crs: \"WGS 84 / UTM zone 11N (EPSG:32611)\"\n");
        assert_non_null(fgets(first, sizeof first, f));
        assert_string_equal(first, "# lon_lat: \"degrees on WGS 84 (the CRS's datum)\"\n");
        assert_non_null(fgets(first, sizeof first, f));
        fclose(f);
        remove(path);
        assert_true(strncmp(first, "# profile profile: dem=", 23) == 0);
        assert_msg_contains(first, dfle_dem_path(tif));
        assert_msg_contains(first, ", from=outlet, given_E=");
        assert_msg_contains(first, " m, snapped_E=");
        assert_msg_contains(first, ", radius=");
        assert_msg_contains(first, ", ds=");
    }
    assert_int_equal(dfle_profile_write_csv(p, "/no/such/dir/p.csv", NULL, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "/no/such/dir/p.csv");
    assert_msg_contains(err.msg, strerror(ENOENT)); /* the system's reason */
    /* Written through dfle_file like every output (found by the fuzzer:
     * a plain fopen waited for ever on a FIFO nobody read, which an
     * alarm ends here, and left half a file on a full disk). */
    {
        char dir[] = "/tmp/dfle_test_profile_XXXXXX", fifo[64];
        assert_non_null(mkdtemp(dir));
        snprintf(fifo, sizeof fifo, "%s/pipe", dir);
        assert_int_equal(mkfifo(fifo, 0600), 0);
        alarm(20);
        assert_int_equal(dfle_profile_write_csv(p, fifo, NULL, &err), DFLE_EIO);
        alarm(0);
        assert_msg_contains(err.msg, "no process is reading");
        remove(fifo);
        rmdir(dir);
    }
    dfle_profile_free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_valley_profile_from_outlet),
        cmocka_unit_test(test_valley_profile_from_head),
        cmocka_unit_test(test_valley_network_and_channel),
        cmocka_unit_test(test_tif_equals_asc),
        cmocka_unit_test(test_fig1_profiles),
        cmocka_unit_test(test_fig1_network),
        cmocka_unit_test(test_outlet_errors),
        cmocka_unit_test(test_write_csv),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
