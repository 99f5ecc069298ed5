/*
 * drainage_basins.c - routing across depressions without changing
 * elevations: the basin graph of Cordonnier, Bovy and Braun (2019), A
 * versatile, linear complexity algorithm for flow routing in
 * topographies with depressions, Earth Surface Dynamics 7, 549-562.
 *
 * After D8 and the flats, every remaining sink is the root of a basin:
 * the cells draining to it.  Cells draining off the grid make up one
 * more node, the outside (basin 0).  Two basins touch where a cell of
 * one neighbours a cell of the other; the pass between them is the
 * touching pair whose higher elevation is least, and that elevation is
 * the cost of the link.  A pit basin also touches the outside at each
 * of its cells that may leave the grid (an OPEN edge or NoData border),
 * at that cell's elevation: there the basin spills off the grid, the
 * cell becoming an outlet, as priority-flood would have it.  The
 * minimum spanning tree of the basins (Boruvka's rounds, below)
 * holds each basin's way out over the lowest passes, which
 * is where a flood would spill; oriented from the outside, it gives
 * each basin the link it drains through.  The pit
 * is then joined to that pass by reversing the receivers along the flow
 * path from the pass cell down to the pit ("carving", their Sect. 2.4),
 * and the pass cell drains into the next basin.  Every receiver stays a
 * D8 neighbour, so direction codes and lengths keep their meaning.
 *
 * Costs: a pass over the pit basins' cells and their neighbours to find
 * the links (a basin's links are kept unique by remembering, per
 * neighbouring basin, the link it last made, as Cordonnier et al. do; a
 * basin's cells are gathered by a walk up its donors), Boruvka's rounds
 * over the links (a link per pair of touching basins; each round a pass
 * over the links left, the components at least halved: no sort, which
 * took twice as long as the rounds do), and a walk of each carved path.
 * Ties in cost go to the link found first, and links are found in a
 * fixed order, so the result is reproducible.
 *
 * A region from which no basin reaches the outside (walled in by CLOSED
 * edges or NoData) keeps one sink, at its lowest pit; its other basins
 * drain to it.
 */
#include "drainage/drainage_internal.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX
#define ROOT (UINT32_MAX - 1) /* in[] of a basin that drains nowhere */

/* Room for `need` basins (the outside included).  The per-basin arrays
 * share one block (their contents never outlive a call), so growing or
 * freeing them is one call. */
static int reserve_basins(drainage_basins *bg, size_t need)
{
    size_t cap;
    uint32_t *block;
    if (need <= bg->cap)
        return 0;
    cap = need + need / 2;
    if ((block = malloc(DRAINAGE_BASIN_WORDS(cap) * sizeof *block)) == NULL)
        return -1;
    free(bg->block);
    bg->block = block;
    bg->best_key = (uint64_t *)bg->block; /* first: 8-byte words */
    bg->start = block + 2 * cap;
    bg->owner = bg->start + cap + 1;
    bg->pos = bg->owner + cap;
    bg->up = bg->pos + cap;
    bg->tree_off = bg->up + cap;
    bg->queue = bg->tree_off + cap + 1;
    bg->in = bg->queue + cap;
    bg->out = bg->in + cap;
    bg->cap = cap;
    return 0;
}

/* Room for more links (out of the way of the search's hot loop). */
static int grow_links(drainage_basins *bg)
{
    size_t cap = bg->link_cap ? 2 * bg->link_cap : 1024;
    drainage_link *l, *t;
    if (cap > ROOT) /* pos[] holds link indices as uint32 */
        cap = ROOT;
    if (cap <= bg->link_cap || (l = realloc(bg->link, cap * sizeof *l)) == NULL)
        return -1;
    bg->link = l;
    if ((t = realloc(bg->spare, cap * sizeof *t)) == NULL)
        return -1;
    bg->spare = t;
    bg->link_cap = cap;
    return 0;
}

/* Label each pit's basin by a breadth-first walk up its donors; the
 * cells of basin b (b = 1 ..) land in members[start[b] .. start[b+1]),
 * the pit first.  Basin 0, the outside, is every other data cell;
 * NoData is NONE. */
static size_t label_basins(dfle_drainage *dr, uint32_t *basin, uint32_t *members)
{
    drainage_basins *bg = &dr->bg;
    size_t m = 0;
    uint32_t b = 0;
    for (size_t i = 0; i < dr->n; i++)
        basin[i] = dr->dir[i] == DIR_NODATA ? NONE : 0;
    for (size_t p = 0; p < dr->n; p++) {
        size_t head = m;
        if (dr->dir[p] != DIR_SINK)
            continue;
        bg->start[++b] = (uint32_t)m;
        basin[p] = b;
        members[m++] = (uint32_t)p;
        while (head < m) {
            uint32_t c = members[head++];
            for (uint32_t d = dr->don_off[c]; d < dr->don_off[c + 1]; d++) {
                basin[dr->don[d]] = b;
                members[m++] = dr->don[d];
            }
        }
    }
    bg->start[b + 1] = (uint32_t)m;
    return b;
}

/* Basin a may reach basin b (0: outside) over i -> j at cost w; keep
 * the cheapest such pass per pair (the first of equal ones). */
static inline int offer(drainage_basins *bg, uint32_t a, uint32_t b, double w, uint32_t i,
                        uint32_t j)
{
    drainage_link *l;
    if (bg->owner[b] != a) {
        if (bg->n_link == bg->link_cap && grow_links(bg) != 0)
            return -1;
        bg->owner[b] = a;
        bg->pos[b] = (uint32_t)bg->n_link;
        bg->link[bg->n_link++] = (drainage_link){w, a, b, i, j};
        return 0;
    }
    l = &bg->link[bg->pos[b]];
    if (w < l->w) {
        l->w = w;
        l->i = i;
        l->j = j;
    }
    return 0;
}

/* The cheapest pass from each pit basin to each basin it touches; a
 * pair of pit basins is looked at from the lower-numbered one only.  A
 * pit basin may also leave the grid where one of its cells may (an
 * OPEN edge or NoData border: water rises to that cell and spills off),
 * at the cell's elevation, with j = NONE for "off the grid". */
static int find_links(dfle_drainage *dr, const double *z, const uint32_t *basin,
                      const uint32_t *members, uint32_t n_basins)
{
    drainage_basins *bg = &dr->bg;
    uint32_t nx = (uint32_t)dr->o.nx, end = bg->start[n_basins + 1];
    bg->n_link = 0;
    for (uint32_t b = 0; b <= n_basins; b++)
        bg->owner[b] = NONE;
    for (uint32_t a = 1; a <= n_basins; a++) {
        for (uint32_t m = bg->start[a]; m < bg->start[a + 1]; m++) {
            uint32_t i = members[m], r = drainage_row(dr, i), c = i - r * nx, across[8], to[8];
            int interior = drainage_interior(dr, r, c), at_border = 0, n_across = 0;
            const double zi = z[i];
            /* A big basin's members, in breadth-first order, leap about
             * the grid: fetch the three rows around a coming one. */
            if (m + DRAINAGE_AHEAD < end) {
                uint32_t f = members[m + DRAINAGE_AHEAD];
                if (f >= nx && f + nx < dr->n) {
                    DRAINAGE_PREFETCH(&basin[f - nx]);
                    DRAINAGE_PREFETCH(&basin[f]);
                    DRAINAGE_PREFETCH(&basin[f + nx]);
                    DRAINAGE_PREFETCH(&z[f - nx]);
                    DRAINAGE_PREFETCH(&z[f]);
                    DRAINAGE_PREFETCH(&z[f + nx]);
                }
            }
            /* Gather the neighbours this side must link to without a
             * branch per neighbour: on rough terrain whether one shares
             * the basin is a coin toss (15% faster on noise). */
            if (interior) {
                for (int k = 0; k < 8; k++) {
                    uint32_t nb = (uint32_t)((long long)i + dr->step[k]), b = basin[nb];
                    at_border |= b == NONE;
                    across[n_across] = nb;
                    to[n_across] = b;
                    n_across += (b - 1u >= a) & (b != NONE); /* b == 0 or b > a */
                }
            } else {
                for (int k = 0; k < 8; k++) {
                    long long nb = drainage_nb(dr, r, c, k);
                    uint32_t b = nb < 0 ? NONE : basin[nb];
                    at_border |= b == NONE;
                    if (b != a && b != NONE && (b == 0 || b > a)) {
                        across[n_across] = (uint32_t)nb;
                        to[n_across++] = b;
                    }
                }
            }
            for (int q = 0; q < n_across; q++) {
                uint32_t j = across[q];
                if (offer(bg, a, to[q], zi > z[j] ? zi : z[j], i, j) != 0)
                    return -1;
            }
            if (at_border && drainage_exit(dr, z, i) != DFLE_DRAINAGE_CLOSED &&
                offer(bg, a, 0, zi, i, NONE) != 0)
                return -1;
        }
    }
    return 0;
}

/* The bits of w as an unsigned key in the same order (sign flipped
 * for positives, all bits for negatives): a total order of the costs
 * in which -0 comes before +0. */
static uint64_t cost_key(double w)
{
    uint64_t b;
    memcpy(&b, &w, sizeof b);
    return b >> 63 ? ~b : b | 0x8000000000000000ull;
}

static uint32_t find(uint32_t *up, uint32_t x)
{
    while (up[x] != x) {
        up[x] = up[up[x]]; /* path halving */
        x = up[x];
    }
    return x;
}

/* The minimum spanning forest of the basin graph by Boruvka's rounds:
 * each component takes its cheapest link to another, until none has
 * one.  Links are ordered by cost and then by the order they were
 * found, a total order, so the forest is unique and is the one Kruskal
 * would build from a stable sort of the links; but no sort is needed.
 * Each round is one pass over the links that still join two components
 * (the others are dropped, in place and in order), and at least halves
 * the components.  Components are numbered afresh after each round and
 * the links renamed to those numbers, so a round's union-find is small
 * and stays in cache (finding roots among all the basins' numbers, a
 * cache miss a link, took three times as long).  The forest's links go
 * to the front of the link array, named by basin again.  Returns how
 * many. */
static size_t spanning_tree(drainage_basins *bg, const uint32_t *basin, uint32_t n_basins)
{
    /* Per component; none of these holds anything between calls. */
    uint32_t *best = bg->pos, *up = bg->up, *name = bg->queue;
    uint64_t *best_key = bg->best_key;
    drainage_link *tree = bg->spare, *t;
    size_t n_tree = 0, n_live = bg->n_link, n_comp = (size_t)n_basins + 1;
    int first = 1;
    for (size_t c = 0; c < n_comp; c++)
        name[c] = (uint32_t)c; /* round one: components are basins */
    while (n_live > 0) {
        size_t kept = 0, next = 0;
        for (size_t c = 0; c < n_comp; c++) {
            up[c] = (uint32_t)c;
            best[c] = NONE;
        }
        for (size_t l = 0; l < n_live; l++) {
            drainage_link lk = bg->link[l];
            uint64_t key;
            lk.a = name[lk.a];
            lk.b = name[lk.b];
            if (lk.a == lk.b)
                continue;
            key = cost_key(lk.w);
            /* Equal costs: the link found first, already there. */
            if (best[lk.a] == NONE || key < best_key[lk.a]) {
                best[lk.a] = (uint32_t)kept;
                best_key[lk.a] = key;
            }
            if (best[lk.b] == NONE || key < best_key[lk.b]) {
                best[lk.b] = (uint32_t)kept;
                best_key[lk.b] = key;
            }
            bg->link[kept++] = lk;
        }
        n_live = kept;
        /* The links chosen make no cycle (the order is total), but a
         * link chosen from both sides is taken once. */
        for (size_t c = 0; c < n_comp; c++) {
            const drainage_link *lk;
            uint32_t ra, rb;
            if (best[c] == NONE)
                continue;
            lk = &bg->link[best[c]];
            if ((ra = find(up, lk->a)) == (rb = find(up, lk->b)))
                continue;
            up[ra] = rb;
            tree[n_tree] = *lk;
            if (!first) { /* named by component: by basin again */
                tree[n_tree].a = basin[lk->i];
                tree[n_tree].b = lk->j == NONE ? 0 : basin[lk->j];
            }
            n_tree++;
        }
        /* Number the new components: roots first, then each the root's. */
        for (size_t c = 0; c < n_comp; c++)
            if (find(up, (uint32_t)c) == c)
                best[c] = (uint32_t)next++;
        for (size_t c = 0; c < n_comp; c++)
            name[c] = best[find(up, (uint32_t)c)];
        if (next == n_comp) /* no link joined two: the rest are apart */
            break;
        n_comp = next;
        first = 0;
    }
    t = bg->link;
    bg->link = bg->spare;
    bg->spare = t;
    return n_tree;
}

/* Breadth-first from `root` over the tree links: each basin reached
 * drains over the link it was reached by, from its cell in[] to out[].
 * A basin's links are listed with it (adj), each with the two cells,
 * so the walk reads one place per basin rather than chasing links. */
static void orient_from(drainage_basins *bg, const drainage_adj *adj, uint32_t root)
{
    size_t head = 0, tail = 0;
    bg->in[root] = ROOT;
    bg->queue[tail++] = root;
    while (head < tail) {
        uint32_t a = bg->queue[head++];
        if (head + 2 * DRAINAGE_AHEAD < tail) { /* basins in no spatial order */
            DRAINAGE_PREFETCH(&bg->tree_off[bg->queue[head + 2 * DRAINAGE_AHEAD]]);
            DRAINAGE_PREFETCH(&adj[bg->tree_off[bg->queue[head + DRAINAGE_AHEAD]]]);
        }
        for (uint32_t t = bg->tree_off[a]; t < bg->tree_off[a + 1]; t++) {
            const drainage_adj e = adj[t];
            if (bg->in[e.to] != NONE)
                continue;
            bg->in[e.to] = e.in;
            bg->out[e.to] = e.out;
            bg->queue[tail++] = e.to;
        }
    }
}

/* Orient the tree from the outside; a component that does not reach it
 * is oriented from its lowest pit, which stays a sink. */
static void orient(dfle_drainage *dr, const double *z, uint32_t n_basins, size_t n_tree)
{
    drainage_basins *bg = &dr->bg;
    uint32_t *lowest = bg->owner; /* per component; owner[] is done */
    /* 2 n_tree entries of 12 bytes in the n_link >= n_tree links' room */
    drainage_adj *adj = (drainage_adj *)(void *)bg->spare;
    memset(bg->tree_off, 0, ((size_t)n_basins + 2) * sizeof *bg->tree_off);
    for (size_t t = 0; t < n_tree; t++) {
        bg->tree_off[bg->link[t].a + 1]++;
        bg->tree_off[bg->link[t].b + 1]++;
    }
    for (uint32_t b = 0; b <= n_basins; b++)
        bg->tree_off[b + 1] += bg->tree_off[b];
    for (size_t t = 0; t < n_tree; t++) { /* tree_off[x] as cursor, as for donors */
        const drainage_link *l = &bg->link[t];
        adj[bg->tree_off[l->a]++] = (drainage_adj){l->b, l->j, l->i};
        adj[bg->tree_off[l->b]++] = (drainage_adj){l->a, l->i, l->j};
    }
    memmove(bg->tree_off + 1, bg->tree_off, ((size_t)n_basins + 1) * sizeof *bg->tree_off);
    bg->tree_off[0] = 0;

    for (uint32_t b = 0; b <= n_basins; b++)
        bg->in[b] = NONE;
    orient_from(bg, adj, 0);
    if (n_tree == n_basins)
        return;
    /* Components of the forest (spanning_tree numbered them afresh each
     * round, so up[] is theirs no more). */
    for (uint32_t b = 0; b <= n_basins; b++) {
        lowest[b] = NONE;
        bg->up[b] = b;
    }
    for (size_t t = 0; t < n_tree; t++) {
        uint32_t ra = find(bg->up, bg->link[t].a), rb = find(bg->up, bg->link[t].b);
        bg->up[ra] = rb;
    }
    for (uint32_t b = 1; b <= n_basins; b++) {
        uint32_t c = find(bg->up, b), pit = dr->stack[bg->start[b]];
        if (bg->in[b] != NONE)
            continue;
        if (lowest[c] == NONE || z[pit] < z[dr->stack[bg->start[lowest[c]]]])
            lowest[c] = b; /* ties: the pit first in index order */
    }
    for (uint32_t b = 1; b <= n_basins; b++)
        if (lowest[b] != NONE)
            orient_from(bg, adj, lowest[b]);
}

/* Reverse the receivers from basin b's pass cell down to its pit and
 * send the pass cell over the pass (or off the grid).  Returns the
 * cells changed. */
static size_t carve_path(dfle_drainage *dr, uint32_t b)
{
    uint32_t cur = dr->bg.in[b], prev = dr->bg.out[b];
    size_t changed = 0;
    for (;;) {
        uint32_t next = dr->rcv[cur];
        if (prev == NONE) {
            dr->rcv[cur] = cur;
            dr->dir[cur] = DIR_OUT;
        } else {
            dr->rcv[cur] = prev;
            dr->dir[cur] = drainage_code(dr, cur, prev);
        }
        changed++;
        if (next == cur) /* the pit, its own receiver until now */
            return changed;
        prev = cur;
        cur = next;
    }
}

int drainage_carve(dfle_drainage *dr, const double *z, dfle_error *err)
{
    drainage_basins *bg = &dr->bg;
    uint32_t *basin = drainage_work(dr, 0), n_basins;
    size_t n_tree;

    /* The stack is rebuilt after carving: until then it lists the
     * basins' members. */
    if (basin == NULL || reserve_basins(bg, dr->counts.pits + 1) != 0)
        goto nomem;
    n_basins = (uint32_t)label_basins(dr, basin, dr->stack);
    assert(n_basins == dr->counts.pits);
    if (find_links(dr, z, basin, dr->stack, n_basins) != 0)
        goto nomem;
    n_tree = spanning_tree(bg, basin, n_basins);
    orient(dr, z, n_basins, n_tree);
    for (uint32_t b = 1; b <= n_basins; b++) {
        if (b + DRAINAGE_AHEAD <= n_basins && bg->in[b + DRAINAGE_AHEAD] != ROOT) {
            DRAINAGE_PREFETCH(&dr->rcv[bg->in[b + DRAINAGE_AHEAD]]); /* pass cells: anywhere */
            DRAINAGE_PREFETCH(&dr->dir[bg->in[b + DRAINAGE_AHEAD]]);
        }
        if (bg->in[b] != ROOT)
            dr->counts.carved += carve_path(dr, b);
    }
    dr->counts.basins = n_basins;
    return DFLE_OK;
nomem:
    return dfle_error_set(err, DFLE_ENOMEM, "drainage: out of memory for the basin graph");
}
