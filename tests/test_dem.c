/*
 * test_dem.c - reading DEMs (GDAL), depression filling, D8 and flats,
 * drainage area, on the small ArcASCII grids of $DFLE_DATA_DIR/dem/small
 * (RichDEM's test data) whose answers are worked out by hand below.
 * The test runner (tests/run-tests.sh) sets DFLE_DATA_DIR.
 *
 * Flow directions are written as numeric-keypad digits, the way the
 * grid looks on the page: 6 = E, 3 = SE, 2 = S, 1 = SW, 4 = W, 7 = NW,
 * 8 = N, 9 = NE; 5 = drains off the grid; x = pit (no outflow).
 */
#define _DEFAULT_SOURCE 1 /* mkstemps */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "dfle/dem.h"
#include "dfle/raster.h"
#include "dfle_test.h"

static char data_path[1024];

static const char *dem_file(const char *name)
{
    const char *dir = getenv("DFLE_DATA_DIR");
    snprintf(data_path, sizeof data_path, "%s/dem/%s", dir ? dir : "(DFLE_DATA_DIR unset)", name);
    return data_path;
}

static dfle_dem *read_dem(const char *name)
{
    dfle_dem *d = NULL;
    dfle_error err = {0, ""};
    int st = dfle_dem_read(dem_file(name), NULL, &d, &err);
    if (st != DFLE_OK) {
        print_error("reading %s: %s (run from the repository root or set DFLE_DATA_DIR)\n",
                    data_path, err.msg);
        fail();
    }
    return d;
}

static char keypad(unsigned char code)
{
    static const char k[8] = {'6', '3', '2', '1', '4', '7', '8', '9'};
    return code < 8 ? k[code] : code == DFLE_DEM_DIR_OUT ? '5' : code == DFLE_DEM_DIR_SINK ? 'x'
                                                                                         : '.';
}

/* Compare the D8 grid with rows of keypad digits. */
static void assert_dirs(const dfle_dem *d, const char *const *rows)
{
    size_t nx = dfle_dem_nx(d), ny = dfle_dem_ny(d);
    const unsigned char *dir = dfle_dem_dir(d);
    int bad = 0;
    assert_non_null(dir);
    for (size_t r = 0; r < ny; r++) {
        char got[256];
        for (size_t c = 0; c < nx; c++)
            got[c] = keypad(dir[r * nx + c]);
        got[nx] = '\0';
        if (strcmp(got, rows[r]) != 0) {
            print_error("row %zu: expected %s, got %s\n", r, rows[r], got);
            bad = 1;
        }
    }
    if (bad)
        fail();
}

static void assert_z(const dfle_dem *d, const double *expected)
{
    size_t n = dfle_dem_nx(d) * dfle_dem_ny(d);
    for (size_t i = 0; i < n; i++)
        if (dfle_dem_z(d)[i] != expected[i]) {
            print_error("cell %zu (row %zu, col %zu): z = %g, expected %g\n", i,
                        i / dfle_dem_nx(d), i % dfle_dem_nx(d), dfle_dem_z(d)[i], expected[i]);
            fail();
        }
}

/* Invariants of any routed, filled DEM: no pits; every data cell's
 * receiver is no higher; the order lists every data cell before its
 * receiver; drainage area counts the cell itself; the areas leaving the
 * grid add up to cells x cell area. */
static void check_routing_invariants(const dfle_dem *d)
{
    size_t n = dfle_dem_nx(d) * dfle_dem_ny(d), n_order, n_data = 0;
    const double *z = dfle_dem_z(d), *A = dfle_dem_area(d);
    const uint32_t *order = dfle_dem_order(d, &n_order);
    double cell = dfle_dem_dx(d) * dfle_dem_dy(d), out_area = 0;
    size_t *pos = calloc(n, sizeof *pos);

    assert_non_null(pos);
    assert_int_equal(dfle_dem_sink_count(d), 0);
    for (size_t j = 0; j < n_order; j++)
        pos[order[j]] = j + 1;
    for (size_t i = 0; i < n; i++) {
        long long r = dfle_dem_receiver(d, i);
        if (isnan(z[i])) {
            assert_true(isnan(A[i]));
            assert_int_equal(pos[i], 0);
            continue;
        }
        n_data++;
        assert_true(pos[i] > 0);
        assert_true(A[i] >= cell);
        if (r >= 0) {
            assert_true(z[r] <= z[i]);
            assert_true(pos[r] > pos[i]);
        } else {
            assert_int_equal(dfle_dem_dir(d)[i], DFLE_DEM_DIR_OUT);
            out_area += A[i];
        }
    }
    assert_int_equal(n_order, n_data);
    assert_close(out_area, (double)n_data * cell, 1e-12, 0);
    free(pos);
}

/* ---------------------------------------------------------------- */
/* garbrecht.dem: Garbrecht and Martz (1997)'s flat                 */
/* ---------------------------------------------------------------- */

/*
 *   9 9 9 9 9 9 9      A 5 x 5 flat at 6 (rows 1-5, cols 1-5) inside a
 *   9 6 6 6 6 6 9      rim, with one outlet: the 5 at row 6, col 2.
 *   8 6 6 6 6 6 9      Nothing is below its spill level, so filling
 *   8 6 6 6 6 6 9      changes nothing.
 *   7 6 6 6 6 6 8
 *   7 6 6 6 6 6 8
 *   7 7 5 7 7 8 8
 *
 * D8 proper: (5,1), (5,2), (5,3) see the 5 and drain to it (3, 2, 1);
 * they are the flat's low edges.  The 5 has no lower neighbour and is on
 * the edge: it drains off the grid (5).  The rim drains to its steepest
 * lower neighbour, e.g. (0,0) = 9 -> (1,1) = 6 (SE: drop 3 over 4.24 m
 * beats everything else), (6,1) = 7 -> the 5 (E: 2/3 m/m beats N: 1/3),
 * (6,4) = 7 -> (5,4) (N: 1/3 beats the diagonals' 1/4.24), (6,6) = 8 ->
 * (5,5) (NW: 2/4.24 = 0.47 beats W: 0/3, N: 0).
 *
 * The remaining 22 flat cells: `towards` = 1 + Chebyshev distance to the
 * low edges (the flat is convex, so BFS gives exactly that); high edges
 * are the flat cells on the rim (rows 1 and 5 except the low edges, cols
 * 1 and 5), `away` = 1 there, 2 one step in, 3 at the centre (3,3), so
 * the flat's height H = 3; mask = 2 towards + H - away (low edges: 2):
 *
 *   towards       away          mask
 *   5 5 5 5 5     1 1 1 1 1     12 12 12 12 12
 *   4 4 4 4 4     1 2 2 2 1     10  9  9  9 10
 *   3 3 3 3 3     1 2 3 2 1      8  7  6  7  8
 *   2 2 2 2 3     1 2 2 2 1      6  5  5  5  8
 *   1 1 1 2 3     - - - 1 1      2  2  2  6  8
 *
 * Each flat cell drains to the neighbour of least mask, the first in the
 * order E, SE, S, SW, W, NW, N, NE on ties: (1,1): SE 9 < S 10 -> 3;
 * (1,2): SE 9 = S 9 -> SE, 3; (1,4): S 9 first -> 2; (1,5): SW 9 -> 1;
 * (2,3): S 6 -> 2; (3,4): S 5 = SW 5 -> S, 2; (4,3): S 2 = SW 2 -> 2;
 * (4,5): W 5 < SW 6 -> 4; (5,4): W 2 -> 4; (5,5): NW 5 < W 6 -> 7 ...
 * Every cell ends at the outlet: its area is all 49 cells.  The centre
 * (3,3) collects (2,2), (2,3), (2,4) and itself: (2,2) = itself + (1,1),
 * which has (0,0), (0,1), (1,0): 5; (2,3) = itself + (1,2) + (0,2): 3;
 * (2,4) = itself + (1,3) + (0,3) + (1,4) + (0,4) + (1,5), which has
 * (0,5), (0,6), (1,6): 9; so 1 + 5 + 3 + 9 = 18 cells.
 */
static void test_garbrecht_flat(void **state)
{
    static const char *const dirs[] = {
        "3222221",
        "6333214",
        "6332114",
        "6333214",
        "6332144",
        "6321474",
        "9654887",
    };
    dfle_dem *d = read_dem("small/garbrecht.dem");
    dfle_dem_fill_stats st;
    dfle_error err;
    (void)state;

    assert_ok(dfle_dem_fill(d, &st, &err), &err);
    assert_int_equal(st.raised, 0);
    assert_ok(dfle_dem_route(d, &err), &err);
    assert_dirs(d, dirs);
    assert_int_equal(dfle_dem_flat_count(d), 22);
    assert_close(dfle_dem_area(d)[6 * 7 + 2], 49 * 9.0, 0, 0); /* 3 m cells */
    assert_close(dfle_dem_area(d)[3 * 7 + 3], 18 * 9.0, 0, 0); /* centre  */
    check_routing_invariants(d);
    dfle_dem_free(d);
}

/* ---------------------------------------------------------------- */
/* pit.dem: a depression that spills over a 6                       */
/* ---------------------------------------------------------------- */

/*
 *   0 0 0 0 0 0 0 0 0 0     The 5s (rows 2-3, cols 2-5) are ringed by
 *   0 9 9 9 9 9 9 9 9 0     9s, the 8 and 7 at col 6, and the 6s of
 *   0 9 5 5 5 5 8 9 9 0     row 4, which touch the 0s of the edge.  The
 *   0 9 5 5 5 5 7 8 9 0     lowest way out is over a 6, so the 8 cells
 *   0 9 6 6 6 6 6 7 9 0     of 5 are raised to 6: 8 cells, 1 m each,
 *   0 0 0 0 0 0 0 0 0 0     volume 8 x 1 m x 9 m^2 = 72 m^3.
 *
 * Routing: the 0s on the edge drain off the grid.  Row 4 drains S to the
 * 0s (drop z/3; (4,1) = 9: S 3 and W 3 tie, S comes first).  The 9s of
 * row 1 drain N to the 0s except (1,1) (W 3 ties N 3; W first) and (1,8)
 * (E first); (2,1), (3,1) drain W, (2,8), (3,8) E.  (2,6) = 8: W to a 6
 * (2/3) beats SW (2/4.24) and S to the 7 (1/3); (2,7) = 9: SW to the 7
 * (2/4.24 = 0.47) beats S, W (1/3); (3,6) = 7: S (1/3) ties W, S first;
 * (3,7) = 8: SW to (4,6) = 6 (0.47).
 * The filled flat (rows 2-3, cols 2-5): low edges are (4,2)..(4,6);
 * towards = 2 on row 3, 3 on row 2; away = 1 on the flat's rim, 2 at
 * (3,3), (3,4); H = 2; mask = row 2: 7 7 7 7, row 3: 5 4 4 5; low edges
 * 2.  (2,2): SE 4 -> 3; (2,3): SE 4 = S 4 -> 3; (2,4): S 4 -> 2;
 * (2,5): SW 4 -> 1; row 3: SE to a low edge (2) -> 3.
 */
static void test_pit_fill_and_route(void **state)
{
    static const double filled[] = {
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 9, 9, 9, 9, 9, 9, 9, 9, 0,
        0, 9, 6, 6, 6, 6, 8, 9, 9, 0,
        0, 9, 6, 6, 6, 6, 7, 8, 9, 0,
        0, 9, 6, 6, 6, 6, 6, 7, 9, 0,
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    };
    static const char *const dirs[] = {
        "5555555555",
        "5488888865",
        "5433214165",
        "5433332165",
        "5222222265",
        "5555555555",
    };
    dfle_dem *d = read_dem("small/pit.dem");
    dfle_dem_fill_stats st;
    dfle_error err;
    (void)state;

    assert_int_equal(dfle_dem_nx(d), 10);
    assert_int_equal(dfle_dem_ny(d), 6);
    assert_close(dfle_dem_dx(d), 3.0, 0, 0);
    assert_ok(dfle_dem_fill(d, &st, &err), &err);
    assert_int_equal(st.raised, 8);
    assert_close(st.max_raise, 1.0, 0, 0);
    assert_close(st.volume, 72.0, 1e-12, 0);
    assert_z(d, filled);
    assert_true(dfle_dem_is_filled(d));
    assert_ok(dfle_dem_route(d, &err), &err);
    assert_dirs(d, dirs);
    assert_int_equal(dfle_dem_flat_count(d), 8);
    check_routing_invariants(d);
    dfle_dem_free(d);
}

/* Unfilled, the 5s are a pit: 8 cells with no outflow. */
static void test_pit_unfilled_has_sinks(void **state)
{
    dfle_dem *d = read_dem("small/pit.dem");
    dfle_error err;
    (void)state;
    assert_ok(dfle_dem_route(d, &err), &err);
    assert_int_equal(dfle_dem_sink_count(d), 8);
    assert_int_equal(dfle_dem_dir(d)[2 * 10 + 2], DFLE_DEM_DIR_SINK);
    assert_false(dfle_dem_is_filled(d));
    dfle_dem_free(d);
}

/* ---------------------------------------------------------------- */
/* testdem1.dem: rings of 2 around zeros                            */
/* ---------------------------------------------------------------- */

/*
 * Original (NODATA_value 9, which no cell has):
 *   row 2: 0 2 2 2 2 0 0 0 0 0
 *   row 3: 0 2 0 0 2 2 2 2 0 0    (3,2), (3,3): ringed by 2s
 *   row 4: 0 2 2 2 2 0 0 2 0 0    (4,5), (4,6), (5,5), (5,6), (6,5),
 *   row 5: 0 0 2 0 2 0 0 2 0 0    (6,6): ringed by 2s on rows 3 and 7,
 *   row 6: 0 0 2 2 2 0 0 2 0 0    cols 4 and 7; (5,3): ringed too.
 *   row 7: 0 0 0 0 2 2 2 2 0 0
 * Diagonal steps count (D8), and none of these leaks diagonally, so all
 * 9 zeros rise to 2: 9 cells x 2 m x 9 m^2 = 162 m^3.
 */
static void test_testdem1_fill(void **state)
{
    static const double filled[] = {
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 2, 2, 2, 2, 0, 0, 0, 0, 0,
        0, 2, 2, 2, 2, 2, 2, 2, 0, 0,
        0, 2, 2, 2, 2, 2, 2, 2, 0, 0,
        0, 0, 2, 2, 2, 2, 2, 2, 0, 0,
        0, 0, 2, 2, 2, 2, 2, 2, 0, 0,
        0, 0, 0, 0, 2, 2, 2, 2, 0, 0,
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    };
    dfle_dem *d = read_dem("small/testdem1.dem");
    dfle_dem_fill_stats st;
    dfle_error err;
    (void)state;
    assert_int_equal(dfle_dem_nodata_count(d), 0);
    assert_ok(dfle_dem_fill(d, &st, &err), &err);
    assert_int_equal(st.raised, 9);
    assert_close(st.max_raise, 2.0, 0, 0);
    assert_close(st.volume, 162.0, 1e-12, 0);
    assert_z(d, filled);
    assert_ok(dfle_dem_route(d, &err), &err);
    check_routing_invariants(d);
    /* Filling is idempotent. */
    assert_ok(dfle_dem_fill(d, &st, &err), &err);
    assert_int_equal(st.raised, 0);
    assert_true(dfle_dem_is_routed(d)); /* nothing changed: kept */
    dfle_dem_free(d);
}

/* multi_flat.dem and garbrecht_valley.dem: many flats, one of them an
 * enclosed pair of zeros at (3,19), (4,19) ringed by 4s (raised to 4);
 * after routing every flat drains and area is conserved. */
static void test_flats_all_drain(void **state)
{
    static const char *const names[] = {"small/multi_flat.dem", "small/garbrecht_valley.dem"};
    (void)state;
    for (int k = 0; k < 2; k++) {
        dfle_dem *d = read_dem(names[k]);
        dfle_dem_fill_stats st;
        dfle_error err;
        assert_ok(dfle_dem_fill(d, &st, &err), &err);
        if (k == 0) {
            assert_int_equal(st.raised, 2);
            assert_close(dfle_dem_z(d)[3 * 21 + 19], 4.0, 0, 0);
            assert_close(dfle_dem_z(d)[4 * 21 + 19], 4.0, 0, 0);
        } else {
            assert_int_equal(st.raised, 0);
        }
        assert_ok(dfle_dem_route(d, &err), &err);
        assert_true(dfle_dem_flat_count(d) > 0);
        check_routing_invariants(d);
        dfle_dem_free(d);
    }
}

/* In multi_flat.dem the zeros of row 7, of column 13 and at (6,2),
 * (6,8), (1,14), (6,14), (6,18), (6,19) form one flat.  Its only cell
 * with a lower neighbour is (7,19), next to the -1 in the corner (8,20):
 * the flat's single low edge.  So `towards` grows westwards along row 7
 * and every cell of the row drains E (where the NE neighbour ties, as
 * at (7,12), E comes first in the order); (7,19) steps SE (drop 1 over
 * 4.24 m) to the corner, which has no lower neighbour and is on the
 * edge: an outlet.  The other -1, (0,20), is one too; (1,20) = 4 drains
 * N to it (drop 5 over 3 m), (7,20) = 4 S to (8,20). */
static void test_multi_flat_outlets(void **state)
{
    dfle_dem *d = read_dem("small/multi_flat.dem");
    dfle_error err;
    const unsigned char *dir;
    (void)state;
    assert_ok(dfle_dem_fill(d, NULL, &err), &err);
    assert_ok(dfle_dem_route(d, &err), &err);
    dir = dfle_dem_dir(d);
    /* The -1 corners have no lower neighbour: outlets. */
    assert_int_equal(dir[0 * 21 + 20], DFLE_DEM_DIR_OUT);
    assert_int_equal(dir[8 * 21 + 20], DFLE_DEM_DIR_OUT);
    /* (1,20) = 4 drains N to the -1 (drop 5 over 3 m), (7,20) = 4 S. */
    assert_int_equal(keypad(dir[1 * 21 + 20]), '8');
    assert_int_equal(keypad(dir[7 * 21 + 20]), '2');
    /* (7,19) = 0, the channel's last cell, steps SE to the corner. */
    assert_int_equal(keypad(dir[7 * 21 + 19]), '3');
    /* The zero channel along row 7 flows east (towards its outlet). */
    for (int c = 1; c < 19; c++)
        assert_int_equal(keypad(dir[7 * 21 + c]), '6');
    dfle_dem_free(d);
}

/* ---------------------------------------------------------------- */
/* Reading: errors, NoData, CRS                                     */
/* ---------------------------------------------------------------- */

static char tmpdir[256];

static int make_tmpdir(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/dfle_test_dem_XXXXXX");
    return mkdtemp(tmpdir) != NULL ? 0 : -1;
}

static int remove_tmpdir(void **state)
{
    char cmd[300];
    (void)state;
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

static const char *write_tmp(const char *name, const char *text)
{
    static char p[512];
    FILE *f;
    snprintf(p, sizeof p, "%s/%s", tmpdir, name);
    f = fopen(p, "w");
    if (f == NULL)
        return NULL;
    fputs(text, f);
    fclose(f);
    return p;
}

static void test_read_errors(void **state)
{
    dfle_dem *d = (dfle_dem *)1;
    dfle_error err;
    const char *p;
    (void)state;

    assert_int_equal(dfle_dem_read("no/such/dem.tif", NULL, &d, &err), DFLE_EIO);
    assert_null(d);
    assert_msg_contains(err.msg, "no/such/dem.tif");
    assert_msg_contains(err.msg, "no such file");

    p = write_tmp("notes.txt", "this is not a raster\n");
    assert_int_equal(dfle_dem_read(p, NULL, &d, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "notes.txt");

    assert_int_equal(dfle_dem_read(tmpdir, NULL, &d, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "directory");

    assert_int_equal(dfle_dem_read("", NULL, &d, &err), DFLE_EINVAL);

    /* A FIFO: GDAL's open waited for a writer for ever (found by the
     * fuzzer); SIGALRM ends such a hang here. */
    {
        char fifo[300];
        snprintf(fifo, sizeof fifo, "%s/pipe.asc", tmpdir);
        assert_int_equal(mkfifo(fifo, 0600), 0);
        alarm(20);
        assert_int_equal(dfle_dem_read(fifo, NULL, &d, &err), DFLE_EIO);
        alarm(0);
        assert_msg_contains(err.msg, "not a regular file");
    }

    /* A band that does not exist. */
    {
        dfle_dem_read_opts o = {2, 0, 0, NULL};
        assert_int_equal(dfle_dem_read(dem_file("small/pit.dem"), &o, &d, &err), DFLE_EINVAL);
        assert_msg_contains(err.msg, "band 2");
    }
    /* Every cell NoData. */
    p = write_tmp("empty.asc", "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n"
                               "NODATA_value -9999\n-9999 -9999\n-9999 -9999\n");
    assert_int_equal(dfle_dem_read(p, NULL, &d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "NoData");
}

/* A grid in degrees reads, fills, but refuses to route; the same grid
 * without its .prj is caught by its degree-like cell size; assigning a
 * metric CRS is the user's way out. */
static void test_geographic_grid(void **state)
{
    static const char grid[] = "ncols 4\nnrows 3\nxllcorner -118.2\nyllcorner 34.2\n"
                               "cellsize 0.000277777778\n"
                               "5 4 3 2\n5 4 3 1\n5 4 3 2\n";
    const char *p;
    dfle_dem *d;
    dfle_error err;
    dfle_profile_opts po;
    dfle_profile *prof;
    dfle_dem_read_opts o = {0, 0, 0, "EPSG:32611"};
    (void)state;

    write_tmp("geo.prj", "GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,"
                         "298.257223563]],PRIMEM[\"Greenwich\",0],UNIT[\"degree\","
                         "0.0174532925199433]]");
    p = write_tmp("geo.asc", grid);
    assert_ok(dfle_dem_read(p, NULL, &d, &err), &err);
    assert_true(dfle_dem_is_geographic(d));
    assert_int_equal(dfle_dem_epsg(d), 4326);
    assert_ok(dfle_dem_fill(d, NULL, &err), &err);
    assert_int_equal(dfle_dem_route(d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "geographic");
    assert_msg_contains(err.msg, "geo.asc");
    assert_msg_contains(err.msg, "metres");
    dfle_profile_opts_default(&po);
    po.E = -118.1999;
    po.N = 34.2001;
    assert_int_equal(dfle_dem_profile(d, &po, &prof, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "geographic");
    dfle_dem_free(d);

    p = write_tmp("noprj.asc", grid);
    assert_ok(dfle_dem_read(p, NULL, &d, &err), &err);
    assert_false(dfle_dem_is_geographic(d));
    assert_null(dfle_dem_crs_name(d));
    assert_int_equal(dfle_dem_route(d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "look like degrees");
    dfle_dem_free(d);

    assert_ok(dfle_dem_read(p, &o, &d, &err), &err);
    assert_int_equal(dfle_dem_epsg(d), 32611);
    assert_ok(dfle_dem_route(d, &err), &err);
    dfle_dem_free(d);

    o.crs = "not a CRS at all";
    assert_int_equal(dfle_dem_read(p, &o, &d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "not a CRS at all");
}

/* hugo_site.asc declares NODATA_value -9999; hugo_site_filled.asc has no
 * NODATA line and writes the value as -9.999e+03: read plainly, those
 * cells would be elevations 10 km below the rest.  With nodata = -9999
 * both grids have the same NoData cells, and routing never lets a NaN
 * into an area. */
static void test_nodata(void **state)
{
    dfle_dem *a = read_dem("hugo_site.asc"), *b = read_dem("hugo_site_filled.asc"), *c;
    dfle_dem_read_opts o = {0, 1, -9999.0, NULL};
    size_t n = dfle_dem_nx(a) * dfle_dem_ny(a), nodata = 0;
    dfle_error err;
    (void)state;

    assert_true(dfle_dem_nodata_count(a) > 0);
    assert_int_equal(dfle_dem_nodata_count(b), 0);
    assert_ok(dfle_dem_read(dem_file("hugo_site_filled.asc"), &o, &c, &err), &err);
    assert_int_equal(dfle_dem_nodata_count(c), dfle_dem_nodata_count(a));
    for (size_t i = 0; i < n; i++) {
        assert_int_equal(isnan(dfle_dem_z(a)[i]), isnan(dfle_dem_z(c)[i]));
        nodata += isnan(dfle_dem_z(a)[i]) != 0;
    }
    assert_int_equal(nodata, dfle_dem_nodata_count(a));
    /* Landlab filled this catchment with its NoData ring closed (one
     * outlet); dfle lets water leave into NoData, as RichDEM and
     * TopoToolbox do, so its pits next to the ring drain there.  More
     * ways out can only lower a spill level: dfle's filled surface is
     * never above Landlab's, and equal on all but 16 of 2152 cells (the
     * pits by the ring and the cells upstream of them). */
    {
        size_t equal = 0, data = 0;
        assert_ok(dfle_dem_fill(a, NULL, &err), &err);
        for (size_t i = 0; i < n; i++) {
            if (isnan(dfle_dem_z(a)[i]))
                continue;
            data++;
            assert_true(dfle_dem_z(a)[i] <= dfle_dem_z(c)[i]);
            equal += dfle_dem_z(a)[i] == dfle_dem_z(c)[i];
        }
        assert_int_equal(data, 2152);
        assert_int_equal(equal, 2136);
    }
    assert_ok(dfle_dem_route(a, &err), &err);
    check_routing_invariants(a);
    dfle_dem_free(a);
    dfle_dem_free(b);
    dfle_dem_free(c);
}

/* ---------------------------------------------------------------- */
/* In-memory grids and geometry                                     */
/* ---------------------------------------------------------------- */

static void test_new_and_geometry(void **state)
{
    const double z[6] = {3, 2, 1, 3, NAN, 1};
    dfle_dem_geo g = {1000.0, 2000.0, 10.0, 20.0};
    dfle_dem *d;
    dfle_error err;
    double e[4], E, N;
    size_t i;
    (void)state;

    assert_ok(dfle_dem_new(3, 2, z, &g, &d, &err), &err);
    assert_int_equal(dfle_dem_nodata_count(d), 1);
    dfle_dem_extent(d, e);
    assert_close(e[0], 1000, 0, 0);
    assert_close(e[1], 1030, 0, 0);
    assert_close(e[2], 1960, 0, 0);
    assert_close(e[3], 2000, 0, 0);
    assert_ok(dfle_dem_cell_at(d, 1025, 1961, "point", &i, &err), &err);
    assert_int_equal(i, 5);
    dfle_dem_cell_centre(d, 5, &E, &N);
    assert_close(E, 1025, 0, 0);
    assert_close(N, 1970, 0, 0);
    assert_int_equal(dfle_dem_cell_at(d, 1030, 1970, "outlet", &i, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "outlet (1030 E, 1970 N) is outside the grid");
    assert_msg_contains(err.msg, "E 1000..1030, N 1960..2000");
    /* Non-square cells: areas are dx dy = 200 m^2 per cell. */
    assert_ok(dfle_dem_route(d, &err), &err);
    check_routing_invariants(d);
    dfle_dem_free(d);

    g.dx = 0;
    assert_int_equal(dfle_dem_new(3, 2, z, &g, &d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "cell size");
    g.dx = 10;
    assert_int_equal(dfle_dem_new(0, 2, z, &g, &d, &err), DFLE_EINVAL);
    dfle_dem_free(NULL);
}

/* One row of 200000 cells falling east: a single flow path 200000
 * cells long.  Routing, accumulation and profile tracing are iterative,
 * so this is no deeper for the stack than a 3 x 3 grid; the last cell
 * collects every cell, and the profile from it reaches the first. */
static void test_long_path(void **state)
{
    size_t nx = 200000;
    double *z = malloc(nx * sizeof *z);
    dfle_dem_geo g = {0, 10, 10, 10};
    dfle_dem *d;
    dfle_profile_opts o;
    dfle_profile *p;
    dfle_error err;
    (void)state;
    assert_non_null(z);
    for (size_t c = 0; c < nx; c++)
        z[c] = 1e5 - 0.1 * (double)c;
    assert_ok(dfle_dem_new(nx, 1, z, &g, &d, &err), &err);
    free(z);
    assert_ok(dfle_dem_fill(d, NULL, &err), &err);
    assert_ok(dfle_dem_route(d, &err), &err);
    check_routing_invariants(d);
    assert_close(dfle_dem_area(d)[nx - 1], (double)nx * 100.0, 0, 0);
    dfle_profile_opts_default(&o);
    o.E = 10.0 * (double)nx - 5;
    o.N = 5;
    assert_ok(dfle_dem_profile(d, &o, &p, &err), &err);
    assert_int_equal(dfle_profile_size(p), nx);
    assert_close(dfle_profile_field(p, DFLE_PROFILE_S)[nx / 2], 0.01, 1e-9, 0);
    dfle_profile_free(p);
    dfle_dem_free(d);
}


/* Damaged files: every one is refused with a message that names the
 * file and the fault, never read as plausible-looking numbers. */
static void test_damaged_files(void **state)
{
    static const char head[] = "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\n";
    char text[512];
    dfle_dem *d = NULL;
    dfle_error err;
    const char *p;
    (void)state;

    /* A word GDAL would read as 0. */
    snprintf(text, sizeof text, "%s1 2 3\n4 x 6\n7 8 9\n", head);
    p = write_tmp("word.asc", text);
    assert_int_equal(dfle_dem_read(p, NULL, &d, &err), DFLE_EINVAL);
    assert_null(d);
    assert_msg_contains(err.msg, "word.asc' line 7: 'x' is not a number");
    /* A header value GDAL would read as NoData 0, making the real
     * marker's cells elevations. */
    snprintf(text, sizeof text, "%sNODATA_value abc\n1 2 3\n4 -9999 6\n7 8 9\n", head);
    p = write_tmp("nodata_word.asc", text);
    assert_int_equal(dfle_dem_read(p, NULL, &d, &err), DFLE_EINVAL);
    assert_null(d);
    assert_msg_contains(err.msg, "line 6: the header's NODATA_value is 'abc', not a number");
    snprintf(text, sizeof text, "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0 0\ncellsize 10\n"
             "1 2 3\n4 5 6\n7 8 9\n");
    p = write_tmp("two_words.asc", text);
    assert_int_equal(dfle_dem_read(p, NULL, &d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "yllcorner is '0 0'");
    /* A decimal comma. */
    snprintf(text, sizeof text, "%s1 2 3\n4 5,5 6\n7 8 9\n", head);
    p = write_tmp("comma.asc", text);
    assert_int_equal(dfle_dem_read(p, NULL, &d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "'5,5' is not a number");
    /* Values past the last row, which GDAL ignores. */
    snprintf(text, sizeof text, "%s1 2 3\n4 5 6\n7 8 9\n10 11 12\n", head);
    p = write_tmp("extra.asc", text);
    assert_int_equal(dfle_dem_read(p, NULL, &d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "holds 12 values where its header (ncols x nrows) says 9");
    /* A cell size or corner no DEM has. */
    p = write_tmp("far.asc", "ncols 3\nnrows 3\nxllcorner 1e308\nyllcorner 0\ncellsize 1e300\n"
                             "1 2 3\n4 5 6\n7 8 9\n");
    assert_int_equal(dfle_dem_read(p, NULL, &d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "far.asc' has cells of 1e+300 x 1e+300");
    assert_msg_contains(err.msg, "header damaged");
    /* A tie point so far out that its cells cannot be told apart (every
     * cell centre the same number: maps failed later, in gnuplot). */
    p = write_tmp("tie.asc", "ncols 3\nnrows 3\nxllcorner 1e300\nyllcorner 0\ncellsize 30\n"
                             "1 2 3\n4 5 6\n7 8 9\n");
    assert_int_equal(dfle_dem_read(p, NULL, &d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "its corner at (1e+300");
    assert_msg_contains(err.msg, "header damaged");
    {
        const double z[4] = {1, 2, 3, 4};
        dfle_dem_geo g = {1e300, 20, 10, 10};
        assert_int_equal(dfle_dem_new(2, 2, z, &g, &d, &err), DFLE_EINVAL);
        assert_msg_contains(err.msg, "cannot be told apart");
        g.x0 = 6e5, g.y0 = 4.2e6; /* UTM */
        assert_ok(dfle_dem_new(2, 2, z, &g, &d, &err), &err);
        dfle_dem_free(d);
    }
    p = write_tmp("infcell.asc", "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize inf\n"
                                 "1 2 3\n4 5 6\n7 8 9\n");
    assert_int_equal(dfle_dem_read(p, NULL, &d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "not a north-up grid");
    /* A value that is no elevation in metres. */
    snprintf(text, sizeof text, "%s1 2 3\n4 1e30 6\n7 8 9\n", head);
    p = write_tmp("huge.asc", text);
    assert_int_equal(dfle_dem_read(p, NULL, &d, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "at row 2, column 2, which is no elevation in metres");
    assert_msg_contains(err.msg, "nodata = ");
    /* ... unless it is declared NoData. */
    snprintf(text, sizeof text, "%sNODATA_value 1e30\n1 2 3\n4 1e30 6\n7 8 9\n", head);
    p = write_tmp("declared.asc", text);
    assert_ok(dfle_dem_read(p, NULL, &d, &err), &err);
    assert_int_equal(dfle_dem_nodata_count(d), 1);
    dfle_dem_free(d);
    /* The same from memory. */
    {
        const double z[4] = {1, 2, -1e12, 4};
        const dfle_dem_geo g = {0, 20, 10, 10};
        assert_int_equal(dfle_dem_new(2, 2, z, &g, &d, &err), DFLE_EINVAL);
        assert_msg_contains(err.msg, "the grid holds -1e+12 at row 2, column 1");
    }
}

/* Undeclared NoData markers and heights beyond any on land read, and
 * are named for the caller to warn about. */
static void test_plausible_elevations(void **state)
{
    static const char head[] = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n";
    char text[512], msg[400];
    dfle_dem *d = NULL;
    dfle_error err;
    (void)state;

    snprintf(text, sizeof text, "%s100 101 102\n-9999 103 -9999\n", head);
    assert_ok(dfle_dem_read(write_tmp("marker.asc", text), NULL, &d, &err), &err);
    assert_int_equal(dfle_dem_check_plausible(d, msg, sizeof msg), 1);
    assert_msg_contains(msg, "2 cells hold -9999");
    assert_msg_contains(msg, "pass nodata = -9999");
    dfle_dem_free(d);
    /* Declared, the marker is NoData and nothing is odd. */
    snprintf(text, sizeof text, "%sNODATA_value -9999\n100 101 102\n-9999 103 -9999\n", head);
    assert_ok(dfle_dem_read(write_tmp("marked.asc", text), NULL, &d, &err), &err);
    assert_int_equal(dfle_dem_check_plausible(d, msg, sizeof msg), 0);
    dfle_dem_free(d);
    /* Centimetres. */
    snprintf(text, sizeof text, "%s31500 40000 229500\n31000 32000 33000\n", head);
    assert_ok(dfle_dem_read(write_tmp("cm.asc", text), NULL, &d, &err), &err);
    assert_int_equal(dfle_dem_check_plausible(d, msg, sizeof msg), 1);
    assert_msg_contains(msg, "elevations run from 31000 to 229500 m");
    dfle_dem_free(d);
    /* The real DEM is fine. */
    d = read_dem("srtm_bigtujunga30m_utm11.tif");
    assert_int_equal(dfle_dem_check_plausible(d, msg, sizeof msg), 0);
    dfle_dem_free(d);
}
/* A GeoTIFF whose GDAL_NODATA tag is no number: GDAL reads "abc" as 0,
 * which made every 0 m cell NoData; dfle refuses it, naming the text,
 * unless the caller says what NoData is. */
static void test_nodata_tag(void **state)
{
    static const unsigned char entry[12] = {0x81, 0xA4, 0x02, 0x00, 0x04, 0x00,
                                            0x00, 0x00, 'n', 'a', 'n', 0x00};
    const double z[4] = {0, 1, 2, 3};
    const dfle_raster_band b[1] = {{z, "z", "m"}};
    const dfle_raster_geo geo = {0, 20, 10, 10, NULL};
    char path[] = "/tmp/dfle_test_nodata_XXXXXX.tif";
    dfle_dem_read_opts o = {0, 1, -9999, NULL};
    dfle_dem *d;
    dfle_error err;
    char *bytes;
    long n, at = -1;
    FILE *f;
    int fd = mkstemps(path, 4);
    (void)state;
    assert_true(fd >= 0);
    close(fd);
    assert_ok(dfle_raster_write_geotiff(path, 2, 2, &geo, 1, b, NULL, &err), &err);
    assert_ok(dfle_dem_read(path, NULL, &d, &err), &err); /* "nan": a number */
    assert_int_equal(dfle_dem_nodata_count(d), 0);
    dfle_dem_free(d);
    /* The tag's IFD entry (42113, ASCII, 4 bytes inline): "nan" -> "abc". */
    assert_non_null(f = fopen(path, "r+b"));
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    rewind(f);
    bytes = malloc((size_t)n);
    assert_int_equal(fread(bytes, 1, (size_t)n, f), (size_t)n);
    for (long i = 0; i + 12 <= n && at < 0; i++)
        if (memcmp(bytes + i, entry, 12) == 0)
            at = i;
    assert_true(at >= 0);
    fseek(f, at + 8, SEEK_SET);
    fwrite("abc", 1, 3, f);
    fclose(f);
    free(bytes);
    assert_int_equal(dfle_dem_read(path, NULL, &d, &err), DFLE_EINVAL);
    assert_null(d);
    assert_msg_contains(err.msg, "declares its NoData value as 'abc' (the GDAL_NODATA tag), "
                                 "which is not a number");
    assert_msg_contains(err.msg, "nodata = ");
    /* Said by the caller: read, the 0 m cell an elevation. */
    assert_ok(dfle_dem_read(path, &o, &d, &err), &err);
    assert_int_equal(dfle_dem_nodata_count(d), 0);
    assert_close(dfle_dem_z(d)[0], 0, 0, 0);
    dfle_dem_free(d);
    unlink(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_garbrecht_flat),
        cmocka_unit_test(test_pit_fill_and_route),
        cmocka_unit_test(test_pit_unfilled_has_sinks),
        cmocka_unit_test(test_testdem1_fill),
        cmocka_unit_test(test_flats_all_drain),
        cmocka_unit_test(test_multi_flat_outlets),
        cmocka_unit_test(test_read_errors),
        cmocka_unit_test(test_geographic_grid),
        cmocka_unit_test(test_nodata),
        cmocka_unit_test(test_new_and_geometry),
        cmocka_unit_test(test_long_path),
        cmocka_unit_test(test_damaged_files),
        cmocka_unit_test(test_plausible_elevations),
        cmocka_unit_test(test_nodata_tag),
    };
    return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}
