/*
 * test_drainage.c - flow routing on a plain grid (drainage.h): small
 * grids whose directions, areas and counts are worked out by hand below,
 * the invariants every routing must keep (checked on random grids with
 * NoData holes, in every mode and with every kind of edge), and
 * re-routing changed elevations against a fresh object.
 *
 * Directions are written as codes 0..7 = E, SE, S, SW, W, NW, N, NE;
 * O = off the grid, X = sink, . = NoData.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/drainage.h"
#include "dfle_test.h"

enum { O = DFLE_DRAINAGE_DIR_OUT, X = DFLE_DRAINAGE_DIR_SINK, N_ = DFLE_DRAINAGE_DIR_NODATA };

static dfle_drainage_opts grid(size_t nx, size_t ny, double dx, double dy,
                               enum dfle_drainage_depressions dep)
{
    dfle_drainage_opts o;
    dfle_drainage_opts_default(&o);
    o.nx = nx;
    o.ny = ny;
    o.dx = dx;
    o.dy = dy;
    o.depressions = dep;
    return o;
}

static dfle_drainage *make(const dfle_drainage_opts *o)
{
    dfle_drainage *dr = NULL;
    dfle_error err = {0, ""};
    assert_ok(dfle_drainage_new(o, &dr, &err), &err);
    return dr;
}

static void route(dfle_drainage *dr, const double *z)
{
    dfle_error err = {0, ""};
    assert_ok(dfle_drainage_route(dr, z, &err), &err);
}

static void assert_codes(const dfle_drainage *dr, const unsigned char *expected)
{
    dfle_drainage_opts o;
    const unsigned char *dir = dfle_drainage_dir(dr);
    int bad = 0;
    dfle_drainage_get_opts(dr, &o);
    assert_non_null(dir);
    for (size_t i = 0; i < o.nx * o.ny; i++)
        if (dir[i] != expected[i]) {
            print_error("cell %zu (row %zu, col %zu): code %d, expected %d\n", i, i / o.nx,
                        i % o.nx, dir[i], expected[i]);
            bad = 1;
        }
    if (bad)
        fail();
}

/* Every routing, whatever the grid: receivers are the neighbours the
 * codes name, and roots exactly the cells with no code 0..7; the stack
 * holds each data cell once, after its receiver (so there is no cycle),
 * and depth-first, each cell's tree as one block inside its receiver's;
 * the donor rows hold each non-root once, under its receiver, in index
 * order; area is the cell plus its donors' areas, and the roots' areas
 * add up to exactly cells x cell area; the counts match the codes. */
static void check_invariants(const dfle_drainage *dr, const double *z)
{
    dfle_drainage_opts o;
    dfle_drainage_counts k = dfle_drainage_get_counts(dr);
    const uint32_t *rcv = dfle_drainage_receivers(dr), *off, *don, *stack;
    const unsigned char *dir = dfle_drainage_dir(dr);
    const double *A = dfle_drainage_area(dr);
    size_t n, n_stack, n_data = 0, n_out = 0, n_sink = 0, n_nonroot = 0;
    size_t *pos;
    double cell, root_area = 0;

    dfle_drainage_get_opts(dr, &o);
    n = o.nx * o.ny;
    cell = o.dx * o.dy;
    don = dfle_drainage_donors(dr, &off);
    stack = dfle_drainage_stack(dr, &n_stack);
    assert_non_null(rcv);
    assert_non_null(dir);
    assert_non_null(A);
    assert_non_null(don);
    assert_non_null(stack);
    pos = calloc(n, sizeof *pos);
    assert_non_null(pos);
    for (size_t j = 0; j < n_stack; j++) {
        assert_true(stack[j] < n);
        assert_int_equal(pos[stack[j]], 0); /* once */
        pos[stack[j]] = j + 1;
    }
    assert_int_equal(off[0], 0);
    for (size_t i = 0; i < n; i++) {
        double donated = 0;
        assert_true(off[i + 1] >= off[i]);
        for (uint32_t d = off[i]; d < off[i + 1]; d++) {
            assert_int_equal(rcv[don[d]], i);
            assert_true(don[d] != i);
            if (d > off[i])
                assert_true(don[d] > don[d - 1]);
            donated += A[don[d]];
        }
        if (isnan(z[i])) {
            assert_int_equal(dir[i], N_);
            assert_int_equal(rcv[i], i);
            assert_int_equal(pos[i], 0);
            assert_true(isnan(A[i]));
            assert_int_equal(off[i + 1] - off[i], 0);
            continue;
        }
        n_data++;
        assert_true(pos[i] > 0);
        assert_true(A[i] == cell + donated);
        if (dir[i] < 8) {
            assert_int_equal((long long)rcv[i], dfle_drainage_neighbour(dr, i, dir[i]));
            assert_false(isnan(z[rcv[i]]));
            assert_true(pos[rcv[i]] < pos[i]); /* receiver first */
            if (o.order == DFLE_DRAINAGE_DEPTH_FIRST) /* blocks of A / cell cells */
                assert_true((double)pos[i] + A[i] / cell <= (double)pos[rcv[i]] + A[rcv[i]] / cell);
            n_nonroot++;
        } else {
            assert_true(dir[i] == O || dir[i] == X);
            assert_int_equal(rcv[i], i);
            n_out += dir[i] == O;
            n_sink += dir[i] == X;
            root_area += A[i];
        }
    }
    assert_int_equal(off[n], n_nonroot);
    assert_int_equal(n_stack, n_data);
    assert_int_equal(k.data, n_data);
    assert_int_equal(k.outlets, n_out);
    assert_int_equal(k.sinks, n_sink);
    assert_true(root_area == (double)n_data * cell);
    free(pos);
}

/* ---------------------------------------------------------------- */
/* A tilted plane                                                   */
/* ---------------------------------------------------------------- */

/* z = row: the north edge is lowest.  Every cell below row 0 drains N
 * (drop 1 over 10 m beats 1 over 14.1 m to NE and NW); row 0 has no
 * lower neighbour and is on the (open) edge: off the grid.  Each column
 * drains to its top cell: area 4 cells.  Making the west edge a base
 * level sends column 0 off the grid cell by cell, though each cell of it
 * has a lower neighbour. */
static void test_tilted_plane(void **state)
{
    static const unsigned char open[] = {
        O, O, O, O, O,
        6, 6, 6, 6, 6,
        6, 6, 6, 6, 6,
        6, 6, 6, 6, 6,
    };
    static const unsigned char west_base[] = {
        O, O, O, O, O,
        O, 6, 6, 6, 6,
        O, 6, 6, 6, 6,
        O, 6, 6, 6, 6,
    };
    dfle_drainage_opts o = grid(5, 4, 10, 10, DFLE_DRAINAGE_KEEP);
    dfle_drainage *dr;
    double z[20];
    dfle_drainage_counts k;
    (void)state;

    for (size_t i = 0; i < 20; i++)
        z[i] = (double)(i / 5);
    dr = make(&o);
    route(dr, z);
    assert_codes(dr, open);
    for (size_t c = 0; c < 5; c++) {
        assert_true(dfle_drainage_area(dr)[c] == 400.0);
        assert_true(dfle_drainage_area(dr)[15 + c] == 100.0);
        assert_int_equal(dfle_drainage_receivers(dr)[5 + c], c);
    }
    k = dfle_drainage_get_counts(dr);
    assert_int_equal(k.outlets, 5);
    assert_int_equal(k.sinks + k.pits + k.flats, 0);
    check_invariants(dr, z);
    dfle_drainage_free(dr);

    o.edge[DFLE_DRAINAGE_WEST] = DFLE_DRAINAGE_BASE_LEVEL;
    dr = make(&o);
    route(dr, z);
    assert_codes(dr, west_base);
    assert_true(dfle_drainage_area(dr)[0] == 100.0);
    assert_true(dfle_drainage_area(dr)[1] == 400.0);
    assert_int_equal(dfle_drainage_get_counts(dr).outlets, 8);
    check_invariants(dr, z);
    dfle_drainage_free(dr);
}

/* The stack of plane z (20 cells) with options o is want, and valid. */
static void expect_stack(const dfle_drainage_opts *o, const double *z, const uint32_t *want)
{
    dfle_drainage *dr = make(o);
    size_t n;
    route(dr, z);
    assert_memory_equal(dfle_drainage_stack(dr, &n), want, 20 * sizeof *want);
    assert_int_equal(n, 20);
    check_invariants(dr, z);
    dfle_drainage_free(dr);
}

/* The stack of that plane, each way.  Kahn's: the cells without
 * donors (row 3) first, then each row as its donors are done; read
 * backwards, row 0 from the east end first.  Depth-first: each column's
 * top cell (a root, in index order), then down its column.  Chains:
 * each cell of row 3 in index order, then the cells below it, each
 * completed by it (one donor each); read backwards, the east column
 * first, from its root. */
static void test_stack_orders(void **state)
{
    static const uint32_t depth_first[20] = {0, 5, 10, 15, 1, 6, 11, 16, 2, 7,
                                             12, 17, 3, 8, 13, 18, 4, 9, 14, 19};
    static const uint32_t kahn[20] = {4, 3, 2, 1, 0, 9, 8, 7, 6, 5,
                                      14, 13, 12, 11, 10, 19, 18, 17, 16, 15};
    static const uint32_t chains[20] = {4, 9, 14, 19, 3, 8, 13, 18, 2, 7,
                                        12, 17, 1, 6, 11, 16, 0, 5, 10, 15};
    dfle_drainage_opts o = grid(5, 4, 10, 10, DFLE_DRAINAGE_KEEP);
    double z[20];
    (void)state;

    for (size_t i = 0; i < 20; i++)
        z[i] = (double)(i / 5);
    expect_stack(&o, z, kahn); /* the default */
    o.order = DFLE_DRAINAGE_DEPTH_FIRST;
    expect_stack(&o, z, depth_first);
    o.order = DFLE_DRAINAGE_CHAINS;
    expect_stack(&o, z, chains);
}

/* The same plane with the north edge closed.  Row 0 cannot leave
 * northwards; its corners still may, through the open west and east
 * edges, so they are outlets and the rest of row 0 is a flat (z = 0)
 * with those two low edges.  Every cell of it touches row 1 (higher),
 * so away = 1 everywhere and H = 1: the mask is 2 x towards, with
 * towards = 2, 3, 2 for columns 1..3.  Column 1 drains W to its corner
 * (mask 2), column 2 E to column 3 (4 < 6; E is first of the equal
 * E and W), column 3 E to its corner. */
static void test_closed_edge_flat(void **state)
{
    static const unsigned char expected[] = {
        O, 4, 0, 0, O,
        6, 6, 6, 6, 6,
        6, 6, 6, 6, 6,
        6, 6, 6, 6, 6,
    };
    dfle_drainage_opts o = grid(5, 4, 10, 10, DFLE_DRAINAGE_KEEP);
    dfle_drainage *dr;
    double z[20];
    (void)state;

    for (size_t i = 0; i < 20; i++)
        z[i] = (double)(i / 5);
    o.edge[DFLE_DRAINAGE_NORTH] = DFLE_DRAINAGE_CLOSED;
    dr = make(&o);
    route(dr, z);
    assert_codes(dr, expected);
    assert_int_equal(dfle_drainage_get_counts(dr).flats, 3);
    assert_int_equal(dfle_drainage_get_counts(dr).sinks, 0);
    assert_true(dfle_drainage_area(dr)[0] == 800.0);  /* columns 0, 1 */
    assert_true(dfle_drainage_area(dr)[4] == 1200.0); /* columns 2-4 */
    check_invariants(dr, z);
    dfle_drainage_free(dr);
}

/* A flat 3 x 3 grid: the rim is on the edge and drains off; the centre
 * is a sink on a flat whose low edges are the whole rim (towards = 1
 * there, 2 at the centre; no higher ground, so no away term): it drains
 * to its first neighbour of mask 2 < 4, E. */
static void test_flat_grid(void **state)
{
    static const unsigned char expected[] = {O, O, O, O, 0, O, O, O, O};
    dfle_drainage_opts o = grid(3, 3, 1, 1, DFLE_DRAINAGE_KEEP);
    double z[9] = {7, 7, 7, 7, 7, 7, 7, 7, 7};
    dfle_drainage *dr = make(&o);
    (void)state;
    route(dr, z);
    assert_codes(dr, expected);
    assert_int_equal(dfle_drainage_get_counts(dr).flats, 1);
    assert_true(dfle_drainage_area(dr)[5] == 2.0);
    check_invariants(dr, z);
    dfle_drainage_free(dr);
}

/* ---------------------------------------------------------------- */
/* A pit, three ways                                                */
/* ---------------------------------------------------------------- */

/*
 *   9 9 9 9 9      10 m cells, every edge open.  The centre (2) is a
 *   9 5 5 5 9      pit inside a ring of 5s; the lowest way out is over
 *   9 5 2 5 9      a 5 to the 4 on the south edge, which has no lower
 *   9 5 5 5 9      neighbour and drains off.
 *   9 9 4 9 9
 *
 * The rim of 9s drains inwards (drop 4 over 10 m to a side beats 4 over
 * 14.1 m to a diagonal: (0,0) has only the diagonal, SE; (4,1) and
 * (4,3) see the 4 at 0.5, better than the 5s at 0.4).
 *
 * KEEP: the ring of 5s drains to the pit, e.g. (3,2): N (0.3) beats S
 * to the 4 (0.1); (3,1): NE (0.21) beats SE (0.07).  The pit is a sink
 * collecting 22 cells; the outlet has only (4,1), (4,3) and itself.
 *
 * FILL: priority-flood raises the pit to its spill level 5 (1 cell, 3 m,
 * 300 m^3).  The 3 x 3 block of 5s is then a flat: its south row drains
 * to the 4 and forms the low edges; the other six are sinks, all but the
 * centre touching the 9s (away = 1; the centre 2; H = 2).  towards = 3
 * on row 1, 2 on row 2, so mask = 2 towards + H - away = 7 on row 1,
 * 5 4 5 on row 2, and 2 on the low edges: row 1 drains to the centre
 * (SE, S, SW), (2,1) and the centre SE to a low edge (2 < 4, before the
 * equal S), (2,3) S.  Everything reaches the outlet: 25 cells.
 *
 * CARVE: elevations stay; the pit's basin (22 cells) touches the
 * outside (the 3 cells around the outlet) at passes of cost max(5, 4)
 * = 5 from (3,1), (3,2) and (3,3) to the 4, and at cost 9 elsewhere.
 * Its cells are looked at from the pit up its donors, in index order,
 * so (3,1) is met first and its pass is kept (the others only tie).
 * The path from (3,1) down to the pit is reversed: (3,1) drains SE over
 * the pass, the pit SW to (3,1); 2 cells carved.
 */
static const double pit_z[25] = {
    9, 9, 9, 9, 9,
    9, 5, 5, 5, 9,
    9, 5, 2, 5, 9,
    9, 5, 5, 5, 9,
    9, 9, 4, 9, 9,
};

/* Route the pit with `dep`: codes as expected, invariants kept. */
static dfle_drainage *route_pit(enum dfle_drainage_depressions dep, const unsigned char *expected)
{
    dfle_drainage_opts o = grid(5, 5, 10, 10, dep);
    dfle_drainage *dr = make(&o);
    route(dr, pit_z);
    assert_codes(dr, expected);
    check_invariants(dr, pit_z);
    return dr;
}

static void test_pit_keep(void **state)
{
    static const unsigned char expected[] = {
        1, 2, 2, 2, 3,
        0, 1, 2, 3, 4,
        0, 0, X, 4, 4,
        0, 7, 6, 5, 4,
        7, 0, O, 4, 5,
    };
    dfle_drainage *dr = route_pit(DFLE_DRAINAGE_KEEP, expected);
    dfle_drainage_counts k = dfle_drainage_get_counts(dr);
    (void)state;
    assert_int_equal(k.sinks, 1);
    assert_int_equal(k.pits, 1);
    assert_int_equal(k.outlets, 1);
    assert_true(dfle_drainage_area(dr)[12] == 2200.0);
    assert_true(dfle_drainage_area(dr)[22] == 300.0);
    dfle_drainage_free(dr);
}

static void test_pit_fill(void **state)
{
    static const unsigned char expected[] = {
        1, 2, 2, 2, 3,
        0, 1, 2, 3, 4,
        0, 1, 1, 2, 4,
        0, 1, 2, 3, 4,
        7, 0, O, 4, 5,
    };
    dfle_drainage_opts o = grid(5, 5, 10, 10, DFLE_DRAINAGE_KEEP);
    dfle_drainage *dr = route_pit(DFLE_DRAINAGE_FILL, expected), *keep;
    dfle_drainage_counts k = dfle_drainage_get_counts(dr);
    dfle_drainage_fill_stats fs;
    dfle_error err;
    double z[25];
    (void)state;

    assert_int_equal(k.filled, 1);
    assert_int_equal(k.flats, 6);
    assert_int_equal(k.sinks, 0);
    assert_true(dfle_drainage_area(dr)[22] == 2500.0);

    /* Filling in place gives the spill surface; routing it with pits
     * kept gives exactly the FILL routing. */
    memcpy(z, pit_z, sizeof z);
    assert_ok(dfle_drainage_fill(dr, z, &fs, &err), &err);
    assert_int_equal(fs.raised, 1);
    assert_close(fs.max_raise, 3.0, 0, 0);
    assert_close(fs.volume, 300.0, 0, 0);
    for (size_t i = 0; i < 25; i++)
        assert_true(z[i] == (i == 12 ? 5.0 : pit_z[i]));
    keep = make(&o);
    route(keep, z);
    assert_memory_equal(dfle_drainage_dir(keep), dfle_drainage_dir(dr), 25);
    assert_memory_equal(dfle_drainage_area(keep), dfle_drainage_area(dr), 25 * sizeof(double));
    dfle_drainage_free(keep);
    dfle_drainage_free(dr);
}

static void test_pit_carve(void **state)
{
    static const unsigned char expected[] = {
        1, 2, 2, 2, 3,
        0, 1, 2, 3, 4,
        0, 0, 3, 4, 4,
        0, 1, 6, 5, 4,
        7, 0, O, 4, 5,
    };
    dfle_drainage *dr = route_pit(DFLE_DRAINAGE_CARVE, expected);
    dfle_drainage_counts k = dfle_drainage_get_counts(dr);
    (void)state;
    assert_int_equal(k.pits, 1);
    assert_int_equal(k.basins, 1);
    assert_int_equal(k.carved, 2);
    assert_int_equal(k.sinks, 0);
    assert_int_equal(dfle_drainage_receivers(dr)[12], 16);
    assert_int_equal(dfle_drainage_receivers(dr)[16], 22);
    assert_true(dfle_drainage_area(dr)[22] == 2500.0);
    assert_true(dfle_drainage_area(dr)[16] == 2200.0); /* the pit's whole basin */
    dfle_drainage_free(dr);
}

/*
 *   5 4 6     1 m cells, every edge open.  Every rim cell has the centre
 *   7 1 8     below it and drains into the grid (e.g. (0,0): SE, 4/1.41
 *   9 9 9     beats E, 1), so nothing drains off and the centre is a pit
 *             collecting all 9 cells (KEEP: a sink, no outlet).
 *
 * CARVE: there is no outside basin to link to, but the pit's basin may
 * spill off the grid at any of its open-edge cells, at that cell's
 * elevation; the lowest is the 4.  The path from it to the pit is
 * reversed: the 4 becomes an outlet, the centre drains N to it.  FILL
 * gets there too, raising the centre to 4 and routing it as a one-cell
 * flat to the 4 (its low edge); the raised centre also turns (0,0) E
 * (1 beats 1/1.41) and (0,2) W (2 beats 2/1.41).
 */
static void test_carve_spills_off_open_edge(void **state)
{
    static const double z[9] = {5, 4, 6, 7, 1, 8, 9, 9, 9};
    static const unsigned char keep[] = {1, 2, 3, 0, X, 4, 7, 6, 5};
    static const unsigned char carve[] = {1, O, 3, 0, 6, 4, 7, 6, 5};
    static const unsigned char fill[] = {0, O, 4, 0, 6, 4, 7, 6, 5};
    dfle_drainage_opts o = grid(3, 3, 1, 1, DFLE_DRAINAGE_KEEP);
    dfle_drainage *dr;
    dfle_drainage_counts k;
    (void)state;

    dr = make(&o);
    route(dr, z);
    assert_codes(dr, keep);
    assert_int_equal(dfle_drainage_get_counts(dr).outlets, 0);
    assert_int_equal(dfle_drainage_get_counts(dr).sinks, 1);
    check_invariants(dr, z);
    dfle_drainage_free(dr);

    for (int dep = DFLE_DRAINAGE_FILL; dep <= DFLE_DRAINAGE_CARVE; dep++) {
        o.depressions = (enum dfle_drainage_depressions)dep;
        dr = make(&o);
        route(dr, z);
        assert_codes(dr, dep == DFLE_DRAINAGE_CARVE ? carve : fill);
        k = dfle_drainage_get_counts(dr);
        assert_int_equal(k.outlets, 1);
        assert_int_equal(k.sinks, 0);
        assert_int_equal(k.carved, dep == DFLE_DRAINAGE_CARVE ? 2 : 0);
        assert_int_equal(k.filled, dep == DFLE_DRAINAGE_FILL ? 1 : 0);
        assert_true(dfle_drainage_area(dr)[1] == 9.0);
        check_invariants(dr, z);
        dfle_drainage_free(dr);
    }
}

/* ---------------------------------------------------------------- */
/* Closed edges and a base level, carved                            */
/* ---------------------------------------------------------------- */

/*
 *   0 0 0     z = row, 1 m cells; north, west and east closed, south a
 *   1 1 1     base level.  Row 2 drains off (though every cell of it has
 *   2 2 2     lower neighbours); row 1 drains N; row 0 cannot leave and
 *             is a flat without low edge: three pits.  KEEP leaves them.
 *
 * CARVE: basins b1..b3 are the columns (pit and the cell below it).
 * Links are found from b1 up: (0,0)-(0,1) cost 0, (1,0)-(2,1) cost 2
 * (SE comes before S), from b2 (0,1)-(0,2) cost 0, (1,1)-(2,2) cost 2,
 * from b3 (1,2)-(2,2) cost 2.  Kruskal takes the two 0s, then the first
 * 2: b1 drains out over (1,0) -> (2,1), b2 into b1 over (0,1) -> (0,0),
 * b3 into b2 over (0,2) -> (0,1).  Carving b1 reverses (1,0) -> (0,0):
 * the pit (0,0) drains S, (1,0) SE; b2's and b3's pits are their pass
 * cells and drain W.  Four cells carved; area 7 cells at (2,1).
 */
static void test_base_level_carve(void **state)
{
    static const unsigned char keep[] = {
        X, X, X,
        6, 6, 6,
        O, O, O,
    };
    static const unsigned char carve[] = {
        2, 4, 4,
        1, 6, 6,
        O, O, O,
    };
    static const double z[9] = {0, 0, 0, 1, 1, 1, 2, 2, 2};
    dfle_drainage_opts o = grid(3, 3, 1, 1, DFLE_DRAINAGE_KEEP);
    dfle_drainage *dr;
    dfle_drainage_counts k;
    (void)state;

    o.edge[DFLE_DRAINAGE_NORTH] = o.edge[DFLE_DRAINAGE_WEST] = o.edge[DFLE_DRAINAGE_EAST] =
        DFLE_DRAINAGE_CLOSED;
    o.edge[DFLE_DRAINAGE_SOUTH] = DFLE_DRAINAGE_BASE_LEVEL;
    dr = make(&o);
    route(dr, z);
    assert_codes(dr, keep);
    assert_int_equal(dfle_drainage_get_counts(dr).sinks, 3);
    check_invariants(dr, z);
    dfle_drainage_free(dr);

    o.depressions = DFLE_DRAINAGE_CARVE;
    dr = make(&o);
    route(dr, z);
    assert_codes(dr, carve);
    k = dfle_drainage_get_counts(dr);
    assert_int_equal(k.basins, 3);
    assert_int_equal(k.carved, 4);
    assert_int_equal(k.sinks, 0);
    assert_int_equal(k.outlets, 3);
    assert_true(dfle_drainage_area(dr)[7] == 7.0);
    assert_true(dfle_drainage_area(dr)[6] == 1.0);
    check_invariants(dr, z);
    dfle_drainage_free(dr);

    /* An open south edge instead: row 2 drains into the grid (N), and
     * row 0 is a flat with no way out. */
    o.edge[DFLE_DRAINAGE_SOUTH] = DFLE_DRAINAGE_OPEN;
    o.depressions = DFLE_DRAINAGE_KEEP;
    dr = make(&o);
    route(dr, z);
    assert_int_equal(dfle_drainage_dir(dr)[7], 6);
    assert_int_equal(dfle_drainage_get_counts(dr).outlets, 0);
    assert_int_equal(dfle_drainage_get_counts(dr).sinks, 3);
    check_invariants(dr, z);
    dfle_drainage_free(dr);
}

/* ---------------------------------------------------------------- */
/* NoData                                                           */
/* ---------------------------------------------------------------- */

/* A 5 x 5 bowl around a NoData hole: z = distance from the centre, the
 * centre NaN.  The four cells at distance 1 have no lower data neighbour;
 * the diagonal ones (1.41) drain to the first of them (E or W of the
 * column, in neighbour order).  With NoData open those four drain into
 * the hole (off the grid); closed (and every edge closed) they are sinks,
 * four one-cell pits on no flat (none drains, so none is a low edge).
 * CARVE joins them at cost 1 (diagonal neighbours of equal z) with no
 * way out: the region keeps one sink, its lowest pit first in index
 * order, (1,2), and all 24 cells drain to it. */
static void test_nodata_hole(void **state)
{
    dfle_drainage_opts o = grid(5, 5, 1, 1, DFLE_DRAINAGE_KEEP);
    dfle_drainage *dr;
    double z[25];
    const size_t ring[4] = {7, 11, 13, 17};
    (void)state;

    for (size_t i = 0; i < 25; i++) {
        double dr_ = (double)(i / 5) - 2, dc = (double)(i % 5) - 2;
        z[i] = sqrt(dr_ * dr_ + dc * dc);
    }
    z[12] = NAN;
    dr = make(&o);
    route(dr, z);
    for (int s = 0; s < 4; s++)
        assert_int_equal(dfle_drainage_dir(dr)[ring[s]], O);
    assert_int_equal(dfle_drainage_dir(dr)[6], 0);  /* (1,1) E to (1,2) */
    assert_int_equal(dfle_drainage_dir(dr)[12], N_);
    assert_int_equal(dfle_drainage_get_counts(dr).data, 24);
    assert_int_equal(dfle_drainage_get_counts(dr).sinks, 0);
    check_invariants(dr, z);
    dfle_drainage_free(dr);

    for (int s = 0; s < 4; s++)
        o.edge[s] = DFLE_DRAINAGE_CLOSED;
    o.nodata = DFLE_DRAINAGE_CLOSED;
    dr = make(&o);
    route(dr, z);
    for (int s = 0; s < 4; s++)
        assert_int_equal(dfle_drainage_dir(dr)[ring[s]], X);
    assert_int_equal(dfle_drainage_get_counts(dr).sinks, 4);
    assert_int_equal(dfle_drainage_get_counts(dr).outlets, 0);
    check_invariants(dr, z);
    dfle_drainage_free(dr);

    o.depressions = DFLE_DRAINAGE_CARVE;
    dr = make(&o);
    route(dr, z);
    assert_int_equal(dfle_drainage_get_counts(dr).sinks, 1);
    assert_int_equal(dfle_drainage_dir(dr)[7], X);
    assert_true(dfle_drainage_area(dr)[7] == 24.0);
    check_invariants(dr, z);
    dfle_drainage_free(dr);

    /* Filling cannot start anywhere: nothing changes. */
    {
        dfle_drainage_fill_stats fs;
        dfle_error err;
        double zc[25];
        memcpy(zc, z, sizeof zc);
        dr = make(&o);
        assert_ok(dfle_drainage_fill(dr, zc, &fs, &err), &err);
        assert_int_equal(fs.raised, 0);
        assert_memory_equal(zc, z, sizeof zc);
        dfle_drainage_free(dr);
    }
}

/* A plane rising eastwards (z = column) with a NoData cell at (2,3):
 * (2,4) would drain SW round the hole (SW before NW at equal slopes);
 * with NoData a base level it drains off the grid instead, and with
 * NoData open it still drains SW, having a lower neighbour. */
static void test_nodata_base_level(void **state)
{
    dfle_drainage_opts o = grid(6, 5, 1, 1, DFLE_DRAINAGE_KEEP);
    dfle_drainage *dr;
    double z[30];
    (void)state;

    for (size_t i = 0; i < 30; i++)
        z[i] = (double)(i % 6);
    z[2 * 6 + 3] = NAN;
    dr = make(&o);
    route(dr, z);
    assert_int_equal(dfle_drainage_dir(dr)[2 * 6 + 4], 3);
    assert_int_equal(dfle_drainage_dir(dr)[2 * 6 + 2], 4);
    check_invariants(dr, z);
    dfle_drainage_free(dr);

    o.nodata = DFLE_DRAINAGE_BASE_LEVEL;
    dr = make(&o);
    route(dr, z);
    assert_int_equal(dfle_drainage_dir(dr)[2 * 6 + 4], O);
    assert_int_equal(dfle_drainage_dir(dr)[1 * 6 + 3], O);
    assert_int_equal(dfle_drainage_dir(dr)[1 * 6 + 1], 4); /* not next to it */
    check_invariants(dr, z);
    dfle_drainage_free(dr);
}

/* ---------------------------------------------------------------- */
/* Random grids: invariants, and routing again                      */
/* ---------------------------------------------------------------- */

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static double uniform(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* kind 0: noise; 1: integer noise (many flats and ties); 2: integer
 * noise with NoData holes; 3: a tilted surface with noise. */
static void random_grid(double *z, size_t nx, size_t ny, int kind)
{
    for (size_t i = 0; i < nx * ny; i++) {
        double u = uniform();
        switch (kind) {
        case 0: z[i] = u; break;
        case 1: z[i] = floor(4 * u); break;
        case 2: z[i] = uniform() < 0.1 ? NAN : floor(3 * u); break;
        default: z[i] = 0.01 * (double)(i / nx) + 0.05 * u; break;
        }
    }
}

static void test_invariants_random(void **state)
{
    static const size_t sizes[][2] = {{1, 1}, {1, 9}, {9, 1}, {2, 2}, {17, 13}, {60, 45}};
    (void)state;
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
        for (int kind = 0; kind < 4; kind++)
            for (int dep = 0; dep < 3; dep++)
                for (int edges = 0; edges < 6; edges++) {
                    size_t nx = sizes[s][0], ny = sizes[s][1];
                    dfle_drainage_opts o = grid(nx, ny, 3, 2, (enum dfle_drainage_depressions)dep);
                    o.order = (enum dfle_drainage_order)(edges % 3); /* each order */
                    double *z = malloc(nx * ny * sizeof *z);
                    dfle_drainage *dr;
                    assert_non_null(z);
                    random_grid(z, nx, ny, kind);
                    z[0] = 1.0; /* at least one data cell */
                    if (edges / 2 == 1) { /* a landscape model's: base level, closed */
                        o.edge[DFLE_DRAINAGE_SOUTH] = DFLE_DRAINAGE_BASE_LEVEL;
                        o.edge[DFLE_DRAINAGE_NORTH] = DFLE_DRAINAGE_CLOSED;
                        o.edge[DFLE_DRAINAGE_EAST] = DFLE_DRAINAGE_CLOSED;
                        o.nodata = DFLE_DRAINAGE_CLOSED;
                    } else if (edges / 2 == 2) { /* no way out at all */
                        for (int e = 0; e < 4; e++)
                            o.edge[e] = DFLE_DRAINAGE_CLOSED;
                        o.nodata = DFLE_DRAINAGE_CLOSED;
                    }
                    dr = make(&o);
                    route(dr, z);
                    check_invariants(dr, z);
                    {
                        dfle_drainage_counts k = dfle_drainage_get_counts(dr);
                        if (dep != DFLE_DRAINAGE_KEEP && edges / 2 == 0)
                            assert_int_equal(k.sinks, 0); /* every pit handled */
                        if (dep == DFLE_DRAINAGE_KEEP)
                            assert_int_equal(k.sinks, k.pits);
                    }
                    dfle_drainage_free(dr);
                    free(z);
                }
}

/* The same answer from an object that routed other elevations before
 * as from a fresh one (trimmed once), in every mode; the arrays are
 * reused, not reallocated, and routing the first surface again needs
 * no more memory than the first time round. */
static void test_reroute_matches_fresh(void **state)
{
    const size_t nx = 70, ny = 50, n = nx * ny;
    double *z1 = malloc(n * sizeof *z1), *z2 = malloc(n * sizeof *z2);
    (void)state;
    assert_non_null(z1);
    assert_non_null(z2);
    for (int dep = 0; dep < 6; dep++)
        for (int kind = 0; kind < 4; kind++) {
            dfle_drainage_opts o = grid(nx, ny, 5, 5, (enum dfle_drainage_depressions)(dep / 2));
            dfle_drainage *used, *fresh;
            const uint32_t *rcv_before, *off_u, *off_f, *don_u, *don_f, *st_u, *st_f;
            size_t ns_u, ns_f, mem;
            dfle_drainage_counts ku, kf;

            o.order = (enum dfle_drainage_order)(dep % 3); /* each order */
            random_grid(z1, nx, ny, kind);
            random_grid(z2, nx, ny, (kind + 1) % 4);
            used = make(&o);
            route(used, z1);
            rcv_before = dfle_drainage_receivers(used);
            route(used, z2);
            mem = dfle_drainage_memory(used);
            route(used, z1);
            route(used, z2);
            assert_ptr_equal(dfle_drainage_receivers(used), rcv_before);
            assert_int_equal(dfle_drainage_memory(used), mem);
            fresh = make(&o);
            route(fresh, z1);
            dfle_drainage_trim(fresh); /* results kept, workspace not */
            assert_true(dfle_drainage_memory(fresh) < mem);
            assert_non_null(dfle_drainage_dir(fresh));
            route(fresh, z2);

            assert_memory_equal(dfle_drainage_receivers(used), dfle_drainage_receivers(fresh),
                                n * sizeof(uint32_t));
            assert_memory_equal(dfle_drainage_dir(used), dfle_drainage_dir(fresh), n);
            don_u = dfle_drainage_donors(used, &off_u);
            don_f = dfle_drainage_donors(fresh, &off_f);
            assert_memory_equal(off_u, off_f, (n + 1) * sizeof(uint32_t));
            assert_memory_equal(don_u, don_f, off_f[n] * sizeof(uint32_t));
            st_u = dfle_drainage_stack(used, &ns_u);
            st_f = dfle_drainage_stack(fresh, &ns_f);
            assert_int_equal(ns_u, ns_f);
            assert_memory_equal(st_u, st_f, ns_f * sizeof(uint32_t));
            assert_memory_equal(dfle_drainage_area(used), dfle_drainage_area(fresh),
                                n * sizeof(double));
            ku = dfle_drainage_get_counts(used);
            kf = dfle_drainage_get_counts(fresh);
            assert_memory_equal(&ku, &kf, sizeof ku);
            check_invariants(used, z2);
            dfle_drainage_free(used);
            dfle_drainage_free(fresh);
        }
    free(z1);
    free(z2);
}

/* CARVE on noise: every pit drains out, receivers stay neighbours, and
 * no elevation is touched (the caller's array is const, but check). */
static void test_carve_noise(void **state)
{
    const size_t nx = 120, ny = 90, n = nx * ny;
    dfle_drainage_opts o = grid(nx, ny, 1, 1, DFLE_DRAINAGE_CARVE);
    double *z = malloc(n * sizeof *z), *copy = malloc(n * sizeof *copy);
    dfle_drainage *dr;
    dfle_drainage_counts k;
    (void)state;
    assert_non_null(z);
    assert_non_null(copy);
    random_grid(z, nx, ny, 0);
    memcpy(copy, z, n * sizeof *z);
    for (int s = 0; s < 4; s++)
        o.edge[s] = DFLE_DRAINAGE_BASE_LEVEL;
    dr = make(&o);
    route(dr, z);
    k = dfle_drainage_get_counts(dr);
    assert_true(k.pits > n / 20); /* noise: about one cell in nine */
    assert_int_equal(k.basins, k.pits);
    assert_true(k.carved >= k.basins);
    assert_int_equal(k.sinks, 0);
    assert_int_equal(k.outlets, 2 * (nx + ny) - 4);
    assert_memory_equal(z, copy, n * sizeof *z);
    check_invariants(dr, z);
    dfle_drainage_free(dr);
    free(z);
    free(copy);
}

/* The basin graph routes each pit out over its lowest passes: along
 * the carved flow path from a pit, the highest elevation met is the
 * pit's spill elevation, which priority-flood computes independently
 * (the minimax property of a minimum spanning tree).  Checked for every
 * pit of noisy grids, with NoData holes and a closed edge; the largest
 * has more links than the radix sort takes a byte at a time. */
static void test_carve_minimax(void **state)
{
    static const size_t sides[] = {40, 150, 450};
    (void)state;
    for (size_t s = 0; s < sizeof sides / sizeof sides[0]; s++)
        for (int kind = 0; kind < 4; kind++) {
            size_t nx = sides[s], ny = sides[s] - 7, n = nx * ny, n_stack, pits = 0;
            dfle_drainage_opts o = grid(nx, ny, 2, 3, DFLE_DRAINAGE_CARVE);
            double *z = malloc(n * sizeof *z), *filled = malloc(n * sizeof *filled);
            double *highest = malloc(n * sizeof *highest);
            dfle_drainage *carve, *keep;
            const uint32_t *rcv, *stack;
            const unsigned char *pit_dir;
            dfle_error err;
            assert_non_null(z);
            assert_non_null(filled);
            assert_non_null(highest);
            random_grid(z, nx, ny, kind);
            z[0] = 1.0;
            o.edge[DFLE_DRAINAGE_EAST] = DFLE_DRAINAGE_CLOSED;
            o.edge[DFLE_DRAINAGE_SOUTH] = kind % 2 ? DFLE_DRAINAGE_BASE_LEVEL
                                                   : DFLE_DRAINAGE_OPEN;
            carve = make(&o);
            route(carve, z);
            check_invariants(carve, z);
            assert_int_equal(dfle_drainage_get_counts(carve).sinks, 0);
            o.depressions = DFLE_DRAINAGE_KEEP;
            keep = make(&o);
            route(keep, z);
            memcpy(filled, z, n * sizeof *z);
            assert_ok(dfle_drainage_fill(keep, filled, NULL, &err), &err);
            /* Highest elevation on the way out, receivers first. */
            rcv = dfle_drainage_receivers(carve);
            stack = dfle_drainage_stack(carve, &n_stack);
            for (size_t j = 0; j < n_stack; j++) {
                uint32_t c = stack[j];
                highest[c] = rcv[c] == c || z[c] > highest[rcv[c]] ? z[c] : highest[rcv[c]];
            }
            pit_dir = dfle_drainage_dir(keep);
            for (size_t i = 0; i < n; i++)
                if (pit_dir[i] == X) {
                    pits++;
                    if (highest[i] != filled[i]) {
                        print_error("%zu x %zu, kind %d: pit %zu spills at %.17g, "
                                    "carved path peaks at %.17g\n", nx, ny, kind, i,
                                    filled[i], highest[i]);
                        fail();
                    }
                }
            assert_true(pits > 0);
            assert_int_equal(dfle_drainage_get_counts(carve).pits, pits);
            dfle_drainage_free(carve);
            dfle_drainage_free(keep);
            free(z);
            free(filled);
            free(highest);
        }
}

/* ---------------------------------------------------------------- */
/* Geometry and errors                                              */
/* ---------------------------------------------------------------- */

/* Hysteresis: a cell keeps its last receiver while that slope is within
 * the margin of the steepest; plain D8 takes the first of a tie in the
 * order E, SE, S, ... */
static void test_hysteresis(void **state)
{
    /* The centre (cell 4) drains S to cell 7 first; then E (cell 5)
     * ties with S, is steeper by round-off, and by a metre. */
    double z[9] = {20, 20, 20, 20, 10, 5, 20, 0, 20};
    dfle_drainage_opts o = grid(3, 3, 1, 1, DFLE_DRAINAGE_KEEP);
    dfle_drainage *sticky, *plain;
    dfle_error err = {0, ""};
    (void)state;
    for (int s = 0; s < 4; s++)
        o.edge[s] = DFLE_DRAINAGE_CLOSED;
    sticky = make(&o);
    plain = make(&o);
    assert_int_equal(dfle_drainage_set_hysteresis(sticky, -0.1, &err), DFLE_EINVAL);
    assert_int_equal(dfle_drainage_set_hysteresis(sticky, 1.0, &err), DFLE_EINVAL);
    assert_ok(dfle_drainage_set_hysteresis(sticky, 1e-9, &err), &err);
    assert_ok(dfle_drainage_route(sticky, z, &err), &err);
    assert_int_equal(dfle_drainage_dir(sticky)[4], 2);
    z[5] = 0; /* an exact tie */
    assert_ok(dfle_drainage_route(sticky, z, &err), &err);
    assert_ok(dfle_drainage_route(plain, z, &err), &err);
    assert_int_equal(dfle_drainage_dir(sticky)[4], 2);
    assert_int_equal(dfle_drainage_receivers(sticky)[4], 7);
    assert_int_equal(dfle_drainage_dir(plain)[4], 0);
    z[5] = -1e-12; /* E steeper by 1e-13 relative: within the margin */
    assert_ok(dfle_drainage_route(sticky, z, &err), &err);
    assert_int_equal(dfle_drainage_dir(sticky)[4], 2);
    z[5] = -1; /* E steeper by 10 %: D8's choice */
    assert_ok(dfle_drainage_route(sticky, z, &err), &err);
    assert_int_equal(dfle_drainage_dir(sticky)[4], 0);
    assert_int_equal(dfle_drainage_receivers(sticky)[4], 5);
    z[5] = 0; /* tied again: now E is the receiver it keeps */
    assert_ok(dfle_drainage_route(sticky, z, &err), &err);
    assert_int_equal(dfle_drainage_dir(sticky)[4], 0);
    dfle_drainage_free(sticky);
    dfle_drainage_free(plain);
}

static void test_geometry(void **state)
{
    dfle_drainage_opts o = grid(4, 3, 3, 4, DFLE_DRAINAGE_KEEP);
    dfle_drainage *dr = make(&o);
    (void)state;
    assert_int_equal(dfle_drainage_neighbour(dr, 5, 0), 6);  /* E  */
    assert_int_equal(dfle_drainage_neighbour(dr, 5, 1), 10); /* SE */
    assert_int_equal(dfle_drainage_neighbour(dr, 5, 6), 1);  /* N  */
    assert_int_equal(dfle_drainage_neighbour(dr, 5, 7), 2);  /* NE */
    assert_int_equal(dfle_drainage_neighbour(dr, 4, 4), -1); /* W of column 0 */
    assert_int_equal(dfle_drainage_neighbour(dr, 1, 6), -1); /* N of row 0 */
    assert_int_equal(dfle_drainage_neighbour(dr, 12, 0), -1); /* no such cell */
    assert_close(dfle_drainage_length(dr, 0), 3.0, 0, 0);
    assert_close(dfle_drainage_length(dr, 2), 4.0, 0, 0);
    assert_close(dfle_drainage_length(dr, 3), 5.0, 0, 0);
    assert_true(isnan(dfle_drainage_length(dr, 8)));
    /* Nothing to read before the first route. */
    assert_null(dfle_drainage_receivers(dr));
    assert_null(dfle_drainage_dir(dr));
    assert_null(dfle_drainage_area(dr));
    assert_null(dfle_drainage_stack(dr, NULL));
    assert_true(dfle_drainage_memory(dr) >= 12 * 25);
    dfle_drainage_free(dr);
    dfle_drainage_free(NULL);
}

static void test_errors(void **state)
{
    dfle_drainage_opts o = grid(3, 3, 1, 1, DFLE_DRAINAGE_KEEP);
    dfle_drainage *dr = NULL;
    dfle_error err;
    double z[9] = {NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
    (void)state;

    assert_int_equal(dfle_drainage_new(NULL, &dr, &err), DFLE_EINVAL);
    assert_null(dr);
    o.nx = 0;
    assert_int_equal(dfle_drainage_new(&o, &dr, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "0 x 3");
    o.nx = 100000;
    o.ny = 100000;
    assert_int_equal(dfle_drainage_new(&o, &dr, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "2^32");
    o = grid(3, 3, 0, 1, DFLE_DRAINAGE_KEEP);
    assert_int_equal(dfle_drainage_new(&o, &dr, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "dx = 0");
    o = grid(3, 3, 1, 1, DFLE_DRAINAGE_KEEP);
    o.edge[2] = (enum dfle_drainage_edge)7;
    assert_int_equal(dfle_drainage_new(&o, &dr, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "edge[2]");
    o = grid(3, 3, 1, 1, (enum dfle_drainage_depressions)5);
    assert_int_equal(dfle_drainage_new(&o, &dr, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "depressions");
    o = grid(3, 3, 1, 1, DFLE_DRAINAGE_KEEP);
    o.order = (enum dfle_drainage_order)3;
    assert_int_equal(dfle_drainage_new(&o, &dr, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "order = 3");
    assert_null(dr);

    o = grid(3, 3, 1, 1, DFLE_DRAINAGE_KEEP);
    dr = make(&o);
    assert_int_equal(dfle_drainage_route(dr, z, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "every cell is NoData");
    z[4] = INFINITY;
    assert_int_equal(dfle_drainage_route(dr, z, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "cell 4 (row 1, column 1) is infinite");
    assert_int_equal(dfle_drainage_route(dr, NULL, &err), DFLE_EINVAL);
    assert_int_equal(dfle_drainage_fill(dr, NULL, NULL, &err), DFLE_EINVAL);
    assert_null(dfle_drainage_dir(dr)); /* a failed route leaves nothing */
    dfle_drainage_free(dr);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tilted_plane),
        cmocka_unit_test(test_stack_orders),
        cmocka_unit_test(test_closed_edge_flat),
        cmocka_unit_test(test_flat_grid),
        cmocka_unit_test(test_pit_keep),
        cmocka_unit_test(test_pit_fill),
        cmocka_unit_test(test_pit_carve),
        cmocka_unit_test(test_carve_spills_off_open_edge),
        cmocka_unit_test(test_base_level_carve),
        cmocka_unit_test(test_nodata_hole),
        cmocka_unit_test(test_nodata_base_level),
        cmocka_unit_test(test_invariants_random),
        cmocka_unit_test(test_reroute_matches_fresh),
        cmocka_unit_test(test_carve_noise),
        cmocka_unit_test(test_carve_minimax),
        cmocka_unit_test(test_hysteresis),
        cmocka_unit_test(test_geometry),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
