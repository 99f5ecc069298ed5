/*
 * drainage_internal.h - the dfle_drainage structure, the D8 neighbour
 * geometry and the steps of a routing, shared by the files of
 * src/drainage/ (one step each).  Not installed.
 *
 * Memory is the landscape model's constraint (it re-routes every time
 * step and must stay lean per cell), so the steps share their scratch:
 * the n-cell work arrays are allocated on first need and kept, and a
 * step may borrow an output array that a later step rewrites anyway.
 * Which step borrows what is written at each step below.
 */
#ifndef DFLE_DRAINAGE_INTERNAL_H
#define DFLE_DRAINAGE_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "dfle/drainage.h"

#define DIR_OUT DFLE_DRAINAGE_DIR_OUT
#define DIR_SINK DFLE_DRAINAGE_DIR_SINK
#define DIR_NODATA DFLE_DRAINAGE_DIR_NODATA

/* Loops that visit the grid in no spatial order (a FIFO of the flow
 * tree) fetch the cells of coming iterations this far ahead. */
#define DRAINAGE_AHEAD 8
#if defined(__GNUC__) || defined(__clang__)
#define DRAINAGE_PREFETCH(p) __builtin_prefetch(p)
#else
#define DRAINAGE_PREFETCH(p) ((void)(p))
#endif

/* Basin-graph workspace (drainage_basins.c), sized by the number of
 * basins and links, grown on demand and kept. */
typedef struct drainage_link {
    double w;        /* pass elevation: the higher of the two cells      */
    uint32_t a, b;   /* the basins it joins: a a pit's, b (0 = outside)  */
    uint32_t i, j;   /* the pass: cell i in a, j in b (or off the grid)  */
} drainage_link;

/* A tree link seen from one of its basins: the basin at the other end
 * would drain over it from its cell `in` to `out` in this one. */
typedef struct drainage_adj {
    uint32_t to, in, out;
} drainage_adj;

typedef struct drainage_basins {
    size_t cap;          /* basins the arrays below can hold; they are
                            one block of DRAINAGE_BASIN_WORDS(cap)      */
    void *block;
    uint32_t *start;     /* cap + 1: basin b's cells are members[start[b] ..
                            start[b + 1]) (members borrow the stack)     */
    uint32_t *owner;     /* cap: basin that last made a link to b        */
    uint32_t *pos;       /* cap: that link's index                       */
    uint32_t *up;        /* cap: union-find parent                       */
    uint32_t *tree_off;  /* cap + 1: tree links by basin (compressed rows) */
    uint64_t *best_key;  /* cap: a component's cheapest link's cost     */
    uint32_t *queue;     /* cap                                          */
    uint32_t *in, *out;  /* cap each: the pass a basin drains over, from
                            its cell `in` to `out` in the next basin    */
    drainage_link *link, *spare; /* link_cap each; spare: scratch (the
                                     spanning tree, its links by basin) */
    size_t n_link, link_cap;
} drainage_basins;

#define DRAINAGE_BASIN_WORDS(cap) (10 * (cap) + 2)

/* Priority-flood's queue (drainage_fill.c): (z, index) pairs. */
typedef struct drainage_heap_item {
    double z;
    uint32_t i;
} drainage_heap_item;

struct dfle_drainage {
    dfle_drainage_opts o;
    size_t n;
    double len[8];          /* distance to neighbour k [m]              */
    long long step[8];      /* index offset of neighbour k              */
    double inv_nx;          /* 1 / nx, for drainage_row                  */

    unsigned char *outlet;  /* n: cells that always drain off, or NULL  */
    double hysteresis;      /* relative slope margin to keep a receiver */
    int dirs_kept;          /* dir[] holds the last routing's directions */
    int dirs_given;         /* dir[] was put back (dfle_drainage_keep_directions) */

    /* Outputs of the last route, valid while `routed`. */
    int routed;
    uint32_t *rcv;          /* receiver; own index for roots            */
    unsigned char *dir;     /* dfle_drainage_dir_code                   */
    uint32_t *don_off;      /* n + 1                                    */
    uint32_t *don;          /* n                                        */
    uint32_t *stack;        /* n_stack data cells, roots first          */
    size_t n_stack;
    double *area;           /* [m^2]                                    */
    dfle_drainage_counts counts;

    /* Workspace, allocated on first need and kept. */
    unsigned char *mark;    /* n: the stack's donors left (Kahn) or next
                               donor (depth-first); fill's closed flags */
    uint32_t *work[3];      /* n each: fill, flats and basins (see there) */
    double *zfill;          /* n: the filled copy (FILL)                */
    drainage_heap_item *heap;
    size_t heap_cap;
    int32_t *height;        /* flats: largest `away` per flat label     */
    size_t height_cap;
    drainage_basins bg;
};

/* The eight neighbours in D8 preference order E, SE, S, SW, W, NW, N,
 * NE (ESRI codes 1 << k); rows grow southwards. */
extern const int dfle_drainage_dr[8];
extern const int dfle_drainage_dc[8];

/* Index of neighbour k of cell (r, c), or -1 off the grid. */
static inline long long drainage_nb(const dfle_drainage *dr, size_t r, size_t c, int k)
{
    long long rr = (long long)r + dfle_drainage_dr[k];
    long long cc = (long long)c + dfle_drainage_dc[k];
    if (rr < 0 || cc < 0 || rr >= (long long)dr->o.ny || cc >= (long long)dr->o.nx)
        return -1;
    return rr * (long long)dr->o.nx + cc;
}

/* The row of cell i without a division (the basin graph asks it of
 * most cells): the product is within one of the row, then corrected. */
static inline uint32_t drainage_row(const dfle_drainage *dr, uint32_t i)
{
    uint32_t nx = (uint32_t)dr->o.nx, r = (uint32_t)((double)i * dr->inv_nx);
    if ((uint64_t)r * nx > i)
        r--;
    else if ((uint64_t)(r + 1) * nx <= i)
        r++;
    return r;
}

/* 1 if cell (r, c) is not on the grid's outer ring, so all eight
 * neighbours exist and are i + step[k]. */
static inline int drainage_interior(const dfle_drainage *dr, size_t r, size_t c)
{
    return r > 0 && c > 0 && r + 1 < dr->o.ny && c + 1 < dr->o.nx;
}

/* How data cell i may leave the grid: the most open of the kinds of
 * the edges it lies on and, with a NoData neighbour, of the NoData
 * border; DFLE_DRAINAGE_CLOSED when it may not (drainage.c). */
enum dfle_drainage_edge drainage_exit(const dfle_drainage *dr, const double *z, size_t i);
/* The same, given whether the cell has a NoData neighbour. */
enum dfle_drainage_edge drainage_exit_known(const dfle_drainage *dr, size_t i, int nodata_nb);

/* An n-cell work array (0..2), allocated on first use; NULL if out of
 * memory. */
uint32_t *drainage_work(dfle_drainage *dr, int k);
unsigned char *drainage_mark(dfle_drainage *dr);

/* The steps, in the order dfle_drainage_route runs them.  Those that
 * can fail return DFLE_OK or a status with err set. */

/* drainage_fill.c: priority-flood of z in place (dfle_drainage_fill). */

/* drainage_d8.c: dir and rcv by steepest descent (or the last
 * direction, within the hysteresis margin); cells with no lower
 * neighbour drain out or become DIR_SINK.  Lists the sinks in stack[]
 * (borrowed until the stack is built) and returns how many; counts the
 * data cells and notes an infinite elevation on the way. */
size_t drainage_d8(dfle_drainage *dr, const double *z, size_t *n_data, int *infinite);

/* drainage_flats.c: route the sinks on flats that have a draining edge;
 * the sinks are stack[0 .. n_sinks).  Borrows don, don_off and stack,
 * work[0..2].  Sets counts.flats. */
int drainage_flats(dfle_drainage *dr, const double *z, size_t n_sinks, dfle_error *err);

/* drainage_tree.c: donors from rcv; the stack in the order of the
 * options (DFLE_ENUMERIC on a cycle, which would be a bug), drainage
 * area (NaN on NoData) and counts.outlets and counts.sinks. */
void drainage_donors(dfle_drainage *dr);
int drainage_stack(dfle_drainage *dr, size_t n_data, dfle_error *err);

/* drainage_basins.c: reroute every sink through the basin graph.
 * Needs donors; borrows stack and work[0]; leaves donors stale. */
int drainage_carve(dfle_drainage *dr, const double *z, dfle_error *err);

/* The direction code from cell a to its neighbour b. */
unsigned char drainage_code(const dfle_drainage *dr, size_t a, size_t b);

#endif
