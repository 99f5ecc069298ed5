/*
 * router_process_network.c - the process-based router on a drainage
 * network: one debris flow from every channel head (source), each routed
 * down its own path of receivers as a 1D channel of that path's cell
 * lengths, widths, slopes and areas (router_process_path.c), as if it
 * were alone, then the flows combined node by node.
 *
 * Combined (flow.h's record, what the law and the combine rule read):
 *   reach     the flows that reach the node (each down to its furthest
 *             wet node, as in 1D): the count of the combine rule;
 *   integral  the mean of their Eq. (11) sums, and t_p the mean of their
 *             passage times, so that E_df is the mean erosion of one of
 *             them and the rule weighs it by the count ("count": the
 *             sum of every flow's erosion; "any": one flow's mean);
 *   h, v, Q, tau  the peaks of all of them; M the volume of all of them.
 *
 * The re-routing rule (Sect. 2.2), per head: each head's last routing is
 * kept with the slopes, lengths and widths of its path, and a head is
 * routed again only when its path is another one (a receiver or length
 * on it changed), a width on it moved by the fraction reroute_dw or a
 * slope by reroute_dS or more since that head's last routing.  Between
 * routings the kept sums stand and the law applies the current slope
 * (Eq. 11).  So a change in one tributary re-routes only the flows that
 * cross it, and the work follows the total length of the paths routed
 * again, not the grid.
 *
 * Only the cells a flow could feel are compared: those it wetted and
 * the two below its furthest wet cell (a step's window is the wet
 * cells and one more on each side; the reconstruction at that dry
 * cell's lower face reads the next).  A flow that stopped halfway down
 * its path routes to the same numbers whatever the path does below
 * them, and on a landscape the paths' lower reaches change receiver
 * and width at every step (hillslope cells trading area between
 * channels), which re-routed every head crossing them without a
 * difference to any flow.
 */
#include "routers/router_process_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Per node of a path: what a head's last routing kept. */
#define KEPT_ARRAYS (DFLE_FLOW_ARRAYS + 1) /* the flow's arrays, then arrival */

typedef struct head {
    size_t node;       /* the source */
    size_t off, len;   /* its path in the path arrays */
    size_t runout_end; /* of its flow: the nodes [0, runout_end) of its path */
    size_t felt;       /* the nodes [0, felt) its routing depends on     */
} head;

/* One generation of paths: heads and their paths, concatenated. */
typedef struct paths {
    head *heads;
    size_t n_heads, cap_heads;
    size_t total, cap_total;
    size_t *node;          /* path nodes                        */
    double *len, *w, *S;   /* cell length, width, slope routed  */
    double *kept;          /* KEPT_ARRAYS x total, by head: each head's
                            * block of KEPT_ARRAYS x len values  */
} paths;

struct process_network {
    unsigned long long net_id;
    size_t n;
    paths cur, next;
    size_t *head_of;   /* n: the head index in cur of a source, or (size_t)-1 */
    double *arrival;   /* n: first arrival of any flow [s] */
    /* Scratch for one path (grown to the longest). */
    size_t cap_path;
    double *gS, *gA, *scratch;
};

static void paths_free(paths *p)
{
    free(p->heads);
    free(p->node);
    free(p->len);
    free(p->w);
    free(p->S);
    free(p->kept);
    memset(p, 0, sizeof *p);
}

void dfle_process_network_free(process_network *c)
{
    if (c == NULL)
        return;
    paths_free(&c->cur);
    paths_free(&c->next);
    free(c->head_of);
    free(c->arrival);
    free(c->gS);
    free(c->gA);
    free(c->scratch);
    free(c);
}

static int grow(void **a, size_t *cap, size_t want, size_t size)
{
    void *b;
    size_t c;
    if (want <= *cap)
        return 0;
    c = *cap > 0 ? *cap : 16;
    while (c < want)
        c *= 2;
    b = realloc(*a, c * size);
    if (b == NULL)
        return -1;
    *a = b;
    *cap = c;
    return 0;
}

/* Room for `total` path nodes in p. */
static int paths_reserve(paths *p, size_t total)
{
    size_t cap = p->cap_total, c;
    void *a;
    if (total <= cap)
        return 0;
    c = cap > 0 ? cap : 64;
    while (c < total)
        c *= 2;
    if ((a = realloc(p->node, c * sizeof *p->node)) == NULL)
        return -1;
    p->node = a;
    if ((a = realloc(p->len, c * sizeof *p->len)) == NULL)
        return -1;
    p->len = a;
    if ((a = realloc(p->w, c * sizeof *p->w)) == NULL)
        return -1;
    p->w = a;
    if ((a = realloc(p->S, c * sizeof *p->S)) == NULL)
        return -1;
    p->S = a;
    if ((a = realloc(p->kept, KEPT_ARRAYS * c * sizeof *p->kept)) == NULL)
        return -1;
    p->kept = a;
    p->cap_total = c;
    return 0;
}

/* The paths of net's sources into p: each from its source down the
 * receivers to a base level.  A base level's cell has the length of the
 * link above it on the path (its own is none: it drains nowhere).  A
 * source that is itself a base level releases a flow that leaves at
 * once and has no path. */
static int build_paths(const dfle_network *net, paths *p, dfle_error *err)
{
    const size_t n = dfle_network_size(net), *recv = dfle_network_receivers(net);
    const unsigned char *src = dfle_network_sources(net);
    const double *L = dfle_network_length(net), *w = dfle_network_w(net);

    p->n_heads = 0;
    p->total = 0;
    for (size_t s = 0; s < n; s++) {
        head *h;
        size_t i = s;
        if (!src[s] || recv[s] == s)
            continue;
        if (grow((void **)&p->heads, &p->cap_heads, p->n_heads + 1, sizeof *p->heads) != 0)
            goto nomem;
        h = &p->heads[p->n_heads++];
        h->node = s;
        h->off = p->total;
        h->runout_end = 0;
        h->felt = 0;
        for (;;) {
            const int base = recv[i] == i;
            if (paths_reserve(p, p->total + 1) != 0)
                goto nomem;
            p->node[p->total] = i;
            p->len[p->total] = base ? p->len[p->total - 1] : L[i];
            p->w[p->total] = w[i];
            p->total++;
            if (base)
                break;
            i = recv[i];
        }
        h->len = p->total - h->off;
    }
    return DFLE_OK;
nomem:
    return dfle_error_set(err, DFLE_ENOMEM, "router.process: out of memory for the paths of "
                          "%zu heads", p->n_heads);
}

/* 1 if head h of `now` can keep the routing of head o of `old`: on the
 * cells o's flow felt, the same nodes and lengths, no width moved by the
 * fraction dw and no slope by dS or more. */
static int can_keep(const paths *now, const head *h, const paths *old, const head *o,
                    const double *S, double dS, double dw)
{
    /* A flow that felt its whole path left at its base level: a path
     * that goes on from there is another one. */
    if (h->len < o->felt || (o->felt == o->len && h->len != o->len))
        return 0;
    for (size_t j = 0; j < o->felt; j++) {
        const size_t a = h->off + j, b = o->off + j;
        if (now->node[a] != old->node[b] || now->len[a] != old->len[b] ||
            !(fabs(now->w[a] - old->w[b]) < dw * old->w[b]) ||
            !(fabs(S[now->node[a]] - old->S[b]) < dS))
            return 0;
    }
    return 1;
}

/* Head h of `now` takes the kept routing of head o of `old` (can_keep):
 * the kept arrays and slopes node for node; below the cells the flow
 * felt, where the two paths may part, each array goes on with o's
 * value there (what a flow leaves on cells it never reached) and the
 * slopes with those of now, for the next comparison. */
static void keep_routing(paths *now, head *h, const paths *old, const head *o, const double *S)
{
    const double *from = old->kept + KEPT_ARRAYS * o->off;
    double *to = now->kept + KEPT_ARRAYS * h->off;
    for (size_t a = 0; a < KEPT_ARRAYS; a++)
        for (size_t j = 0; j < h->len; j++)
            to[a * h->len + j] = from[a * o->len + (j < o->len ? j : o->len - 1)];
    for (size_t j = 0; j < h->len; j++)
        now->S[h->off + j] = j < o->felt ? old->S[o->off + j] : S[now->node[h->off + j]];
    h->runout_end = o->runout_end;
    h->felt = o->felt;
}

static int scratch_reserve(process_network *c, size_t len)
{
    if (len <= c->cap_path)
        return 0;
    free(c->gS);
    free(c->gA);
    free(c->scratch);
    c->gS = malloc(len * sizeof *c->gS);
    c->gA = malloc(len * sizeof *c->gA);
    c->scratch = malloc(len * sizeof *c->scratch);
    c->cap_path = 0;
    if (c->gS == NULL || c->gA == NULL || c->scratch == NULL)
        return -1;
    c->cap_path = len;
    return 0;
}

/* Route head h of p over S, its results into its kept block. */
static int route_head(process_network *c, const dfle_process_opts *o, const dfle_network *net,
                      paths *p, head *h, const double *S, const dfle_flow *model_flow,
                      process_path_result *r, dfle_error *err)
{
    const double *A = dfle_network_A(net);
    double *kept = p->kept + KEPT_ARRAYS * h->off;
    dfle_flow f;
    int st;

    if (scratch_reserve(c, h->len) != 0)
        return dfle_error_set(err, DFLE_ENOMEM, "router.process: out of memory for a path of "
                              "%zu nodes", h->len);
    for (size_t j = 0; j < h->len; j++) {
        const size_t i = p->node[h->off + j];
        c->gS[j] = S[i];
        c->gA[j] = A[i];
        p->S[h->off + j] = S[i];
    }
    dfle_flow_bind(&f, kept, h->len);
    f.integrand = model_flow->integrand;
    f.integrand_state = model_flow->integrand_state;
    {
        const process_path path = {.n = h->len, .dx = p->len + h->off, .dx0 = 0.0,
                                   .w = p->w + h->off, .S = c->gS, .A = c->gA};
        st = dfle_process_route_path(o, &path, &f, kept + DFLE_FLOW_ARRAYS * h->len, c->scratch,
                                     NULL, r, err);
    }
    if (st != DFLE_OK) {
        /* Head nodes are 1-based in messages, as elsewhere. */
        size_t used = err != NULL ? strlen(err->msg) : 0;
        if (err != NULL && used + 40 < sizeof err->msg)
            snprintf(err->msg + used, sizeof err->msg - used, " (the flow from head node %zu)",
                     h->node + 1);
        return st;
    }
    h->runout_end = f.runout_end;
    /* The cells it wetted (a depth or a volume passed) and two below. */
    h->felt = 0;
    for (size_t j = 0; j < h->len; j++)
        if (f.h[j] > 0 || f.M[j] > 0)
            h->felt = j + 1;
    h->felt = h->felt + 2 < h->len ? h->felt + 2 : h->len;
    return DFLE_OK;
}

static process_network *cache_new(size_t n)
{
    process_network *c = calloc(1, sizeof *c);
    if (c == NULL)
        return NULL;
    c->head_of = malloc(n * sizeof *c->head_of);
    c->arrival = malloc(n * sizeof *c->arrival);
    if (c->head_of == NULL || c->arrival == NULL) {
        dfle_process_network_free(c);
        return NULL;
    }
    for (size_t i = 0; i < n; i++)
        c->head_of[i] = (size_t)-1;
    c->n = n;
    return c;
}

/* The flows of every head into one record (the file's comment). */
static void combine(process_network *c, const paths *p, dfle_flow *flow)
{
    const size_t n = c->n;
    size_t reached = 0;

    dfle_flow_clear(flow);
    flow->time_resolved = 1;
    for (size_t i = 0; i < n; i++)
        c->arrival[i] = NAN;
    for (size_t k = 0; k < p->n_heads; k++) {
        const head *h = &p->heads[k];
        const double *kept = p->kept + KEPT_ARRAYS * h->off;
        dfle_flow f;
        const double *arr = kept + DFLE_FLOW_ARRAYS * h->len;
        dfle_flow_bind(&f, (double *)kept, h->len);
        for (size_t j = 0; j < h->runout_end; j++) {
            const size_t i = p->node[h->off + j];
            flow->reach[i] += 1.0;
            flow->integral[i] += f.integral[j];
            flow->t_p[i] += f.t_p[j];
            flow->M[i] += f.M[j];
            flow->h[i] = fmax(flow->h[i], f.h[j]);
            flow->v[i] = fmax(flow->v[i], f.v[j]);
            flow->Q[i] = fmax(flow->Q[i], f.Q[j]);
            flow->tau[i] = fmax(flow->tau[i], f.tau[j]);
            if (!(arr[j] >= c->arrival[i])) /* NaN: none yet */
                c->arrival[i] = isnan(arr[j]) ? c->arrival[i] : arr[j];
        }
    }
    for (size_t i = 0; i < n; i++)
        if (flow->reach[i] > 0) {
            flow->integral[i] /= flow->reach[i];
            flow->t_p[i] /= flow->reach[i];
            flow->Theta[i] = 1.0;
            reached++;
        }
    flow->runout_end = reached;
}

int dfle_process_route_network(process_network **cache, const dfle_process_opts *o,
                               const dfle_network *net, const double *S, dfle_flow *flow,
                               dfle_process_report *rep, dfle_error *err)
{
    const size_t n = dfle_network_size(net);
    process_network *c = *cache;
    size_t routed = 0, head_routings = rep->head_routings, calls = rep->route_calls + 1;
    double vin = 0, vout = 0, vleft = 0, dur = 0, verr = 0;
    size_t steps = 0, cell_steps = 0;
    int end = DFLE_PROCESS_LEFT, st;
    paths tmp;

    if (c != NULL && c->n != n) {
        dfle_process_network_free(c);
        *cache = c = NULL;
    }
    if (c == NULL && (*cache = c = cache_new(n)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "router.process: out of memory for %zu nodes", n);
    if (c->net_id != dfle_network_id(net)) { /* another network: nothing kept applies */
        c->cur.n_heads = 0;
        for (size_t i = 0; i < n; i++)
            c->head_of[i] = (size_t)-1;
    }
    c->net_id = dfle_network_id(net);
    if ((st = build_paths(net, &c->next, err)) != DFLE_OK)
        return st;
    for (size_t k = 0; k < c->next.n_heads; k++) {
        head *h = &c->next.heads[k];
        const size_t ko = c->head_of[h->node];
        const head *old = ko != (size_t)-1 ? &c->cur.heads[ko] : NULL;
        if (old != NULL &&
            can_keep(&c->next, h, &c->cur, old, S, o->reroute_dS, o->reroute_dw)) {
            /* Its last routing stands: the kept sums, and the slopes it was
             * routed over (the rule compares with those, not with these). */
            keep_routing(&c->next, h, &c->cur, old, S);
            continue;
        }
        process_path_result r;
        if ((st = route_head(c, o, net, &c->next, h, S, flow, &r, err)) != DFLE_OK) {
            /* Nothing kept is trusted after a failed routing. */
            c->net_id = 0;
            return st;
        }
        routed++;
        head_routings++;
        vin += r.volume_in, vout += r.volume_out, vleft += r.volume_left;
        dur = fmax(dur, r.duration);
        steps += r.steps, cell_steps += r.cell_steps;
        verr = fmax(verr, fabs(r.volume_in - r.volume_out - r.volume_left) / r.volume_in);
        if (r.end == DFLE_PROCESS_TIME || (r.end == DFLE_PROCESS_REST && end == DFLE_PROCESS_LEFT))
            end = r.end;
    }
    /* The new generation is the one kept. */
    for (size_t k = 0; k < c->cur.n_heads; k++)
        c->head_of[c->cur.heads[k].node] = (size_t)-1;
    tmp = c->cur, c->cur = c->next, c->next = tmp;
    for (size_t k = 0; k < c->cur.n_heads; k++)
        c->head_of[c->cur.heads[k].node] = k;
    combine(c, &c->cur, flow);
    *rep = (dfle_process_report){
        .routed = 1, .end = end, .volume_in = vin, .volume_out = vout, .volume_left = vleft,
        .duration = dur, .steps = steps, .cell_steps = cell_steps, .n = n,
        .arrival = c->arrival, .heads_network = 1, .heads = c->cur.n_heads,
        .heads_routed = routed, .head_routings = head_routings, .route_calls = calls,
        .volume_error = verr,
    };
    return DFLE_OK;
}
