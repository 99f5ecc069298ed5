/*
 * network.c - the drainage network the model is solved on (network.h).
 *
 * Everything the model and the routers need of the topology is derived
 * here once per shape: the stack (when none is given), the base levels
 * and the donor each one takes its slope from, whether the lengths are
 * uniform and whether the network is a plain chain.  A landscape sets a
 * new shape every time its flow routing changes, so set() reuses the
 * arrays and allocates nothing after the first call.
 *
 * A shape is validated before anything is copied: a bad one leaves the
 * network as it was.  The stack, when computed, is Kahn's order from the
 * base levels up (a breadth-first walk over donors), which is O(n) and
 * needs no recursion.
 */
#include "dfle/network.h"

#include <assert.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define NO_NODE ((size_t)-1)

struct dfle_network {
    size_t n;
    unsigned long long id, version;
    /* One block each, see alloc_arrays(). */
    size_t *recv, *stack, *base, *base_donor, *ndonor, *first_donor, *donor;
    double *len, *A, *w, *x;
    unsigned char *source;
    unsigned char *channel; /* n bytes, allocated on first use */
    unsigned char *seen;    /* n bytes: a given stack's check (first use) */
    int x_unset;            /* x is all NaN (no shape gave one)          */
    int editing;            /* dfle_network_edit: 1, 2 with a channel mask */
    int has_channel;        /* the shape gave a channel mask   */
    size_t n_base;
    int uniform_len, chain;
};

/* Ids and versions come from one counter: unique for the process, so a
 * cache keyed on a version can never be fooled by a freed network whose
 * memory was reused. */
static atomic_ullong next_stamp = 1;

static unsigned long long stamp(void) { return atomic_fetch_add(&next_stamp, 1); }

static int alloc_arrays(dfle_network *net, dfle_error *err)
{
    const size_t n = net->n;
    net->recv = malloc(7 * n * sizeof(size_t));
    net->len = malloc(4 * n * sizeof(double));
    net->source = malloc(n);
    if (net->recv == NULL || net->len == NULL || net->source == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "network: out of memory for %zu nodes", n);
    net->stack = net->recv + n;
    net->base = net->recv + 2 * n;
    net->base_donor = net->recv + 3 * n;
    net->ndonor = net->recv + 4 * n;
    net->first_donor = net->recv + 5 * n;
    net->donor = net->recv + 6 * n;
    net->A = net->len + n;
    net->w = net->len + 2 * n;
    net->x = net->len + 3 * n;
    return DFLE_OK;
}

int dfle_network_new(size_t n, dfle_network **out, dfle_error *err)
{
    dfle_network *net;
    int st;

    *out = NULL;
    if (n < 2)
        return dfle_error_set(err, DFLE_EINVAL, "network: needs at least 2 nodes (got %zu)", n);
    if ((net = calloc(1, sizeof *net)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "network: out of memory");
    net->n = n;
    net->id = stamp();
    if ((st = alloc_arrays(net, err)) != DFLE_OK) {
        dfle_network_free(net);
        return st;
    }
    /* Valid but unshaped: every node its own base level. */
    for (size_t i = 0; i < n; i++) {
        net->recv[i] = i;
        net->stack[i] = i;
        net->len[i] = 1.0;
        net->A[i] = net->w[i] = 1.0;
        net->x[i] = NAN;
        net->source[i] = 0;
    }
    net->x_unset = 1;
    net->version = stamp();
    *out = net;
    return DFLE_OK;
}

void dfle_network_free(dfle_network *net)
{
    if (net == NULL)
        return;
    free(net->recv);
    free(net->len);
    free(net->source);
    free(net->channel);
    free(net->seen);
    free(net);
}

/* Donors in compressed rows (first_donor[i] .. + ndonor[i] in donor[]),
 * in increasing index order. */
static void index_donors(dfle_network *net)
{
    const size_t n = net->n;
    size_t k = 0;
    memset(net->ndonor, 0, n * sizeof *net->ndonor);
    for (size_t i = 0; i < n; i++)
        if (net->recv[i] != i)
            net->ndonor[net->recv[i]]++;
    for (size_t i = 0; i < n; i++) {
        net->first_donor[i] = k;
        k += net->ndonor[i];
        net->ndonor[i] = 0;
    }
    for (size_t i = 0; i < n; i++)
        if (net->recv[i] != i) {
            size_t r = net->recv[i];
            net->donor[net->first_donor[r] + net->ndonor[r]++] = i;
        }
}

/* Kahn's order from the base levels up; returns the number of nodes
 * reached (n unless a cycle hides some). */
static size_t build_stack(dfle_network *net)
{
    size_t head = 0, tail = 0;
    for (size_t i = 0; i < net->n; i++)
        if (net->recv[i] == i)
            net->stack[tail++] = i;
    while (head < tail) {
        size_t r = net->stack[head++];
        for (size_t k = 0; k < net->ndonor[r]; k++)
            net->stack[tail++] = net->donor[net->first_donor[r] + k];
    }
    return tail;
}

/* Base levels, their slope donors, uniform lengths, chain-ness. */
static void derive(dfle_network *net)
{
    const size_t n = net->n;
    double L0 = NAN;
    net->n_base = 0;
    net->uniform_len = 1;
    net->chain = net->recv[n - 1] == n - 1;
    for (size_t i = 0; i < n; i++) {
        if (net->recv[i] == i) {
            size_t best = NO_NODE;
            for (size_t k = 0; k < net->ndonor[i]; k++) {
                size_t d = net->donor[net->first_donor[i] + k];
                if (best == NO_NODE || net->A[d] > net->A[best])
                    best = d;
            }
            net->base[net->n_base++] = i;
            net->base_donor[i] = best;
        } else {
            net->base_donor[i] = NO_NODE;
            if (isnan(L0))
                L0 = net->len[i];
            else if (net->len[i] != L0)
                net->uniform_len = 0;
        }
        if (i + 1 < n && net->recv[i] != i + 1)
            net->chain = 0;
    }
}

/* The checks of a shape: receivers are nodes, lengths, areas and
 * widths finite and positive, and a given stack a permutation with every
 * node after its receiver (so no cycle either). */
static int check_shape(dfle_network *net, const size_t *recv, const double *len, const double *A,
                       const double *w, const size_t *stack, dfle_error *err)
{
    const size_t n = net->n;
    for (size_t i = 0; i < n; i++) {
        const size_t r = recv[i];
        if (r >= n)
            return dfle_error_set(err, DFLE_EINVAL, "network: node %zu drains to %zu, not a node "
                                  "(n = %zu)", i + 1, r + 1, n);
        if (!(isfinite(A[i]) && A[i] > 0) || !(isfinite(w[i]) && w[i] > 0))
            return dfle_error_set(err, DFLE_EINVAL, "network: node %zu has A = %g m^2, w = %g m "
                                  "(both must be finite and > 0)", i + 1, A[i], w[i]);
        if (r != i && !(isfinite(len[i]) && len[i] > 0))
            return dfle_error_set(err, DFLE_EINVAL, "network: node %zu has flow length %g m "
                                  "(must be finite and > 0)", i + 1, len[i]);
    }
    if (stack != NULL) {
        /* Each node's receiver already seen when the node comes.  A byte
         * a node kept with the network: a landscape gives a stack at
         * every routing. */
        unsigned char *seen = net->seen;
        if (seen == NULL && (seen = net->seen = malloc(n)) == NULL)
            return dfle_error_set(err, DFLE_ENOMEM, "network: out of memory");
        memset(seen, 0, n);
        for (size_t k = 0; k < n; k++) {
            if (stack[k] >= n || seen[stack[k]])
                return dfle_error_set(err, DFLE_EINVAL, "network: the stack is not a permutation "
                                      "of the nodes (entry %zu)", k + 1);
            seen[stack[k]] = 1;
        }
        memset(seen, 0, n);
        for (size_t k = 0; k < n; k++) {
            const size_t i = stack[k], r = recv[i];
            if (r != i && !seen[r])
                return dfle_error_set(err, DFLE_EINVAL, "network: in the stack node %zu comes "
                                      "before its receiver %zu", i + 1, r + 1);
            seen[i] = 1;
        }
    }
    return DFLE_OK;
}

/* A valid network with no shape (every node its own base level), for
 * when a shape already written into it fails its checks. */
static void unshape(dfle_network *net)
{
    for (size_t i = 0; i < net->n; i++) {
        net->recv[i] = net->stack[i] = i;
        if (!(isfinite(net->len[i]) && net->len[i] > 0))
            net->len[i] = 1.0;
        if (!(isfinite(net->A[i]) && net->A[i] > 0))
            net->A[i] = 1.0;
        if (!(isfinite(net->w[i]) && net->w[i] > 0))
            net->w[i] = 1.0;
        net->source[i] = 0;
    }
    net->has_channel = 0;
    index_donors(net);
    derive(net);
    net->version = stamp();
}

int dfle_network_set(dfle_network *net, const dfle_network_shape *s, dfle_error *err)
{
    const size_t n = net->n;
    int st;

    if (s->receiver == NULL || s->length == NULL || s->A == NULL || s->w == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "network: receiver, length, A and w are required");
    if ((st = check_shape(net, s->receiver, s->length, s->A, s->w, s->stack, err)) != DFLE_OK)
        return st;
    if (s->channel != NULL && net->channel == NULL && (net->channel = malloc(n)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "network: out of memory");
    net->editing = 0;
    memcpy(net->recv, s->receiver, n * sizeof *net->recv);
    memcpy(net->len, s->length, n * sizeof *net->len);
    memcpy(net->A, s->A, n * sizeof *net->A);
    memcpy(net->w, s->w, n * sizeof *net->w);
    if (s->x != NULL)
        memcpy(net->x, s->x, n * sizeof *net->x);
    else if (!net->x_unset)
        for (size_t i = 0; i < n; i++)
            net->x[i] = NAN;
    net->x_unset = s->x == NULL;
    index_donors(net);
    if (s->stack != NULL) {
        memcpy(net->stack, s->stack, n * sizeof *net->stack);
    } else if (build_stack(net) != n) {
        /* A cycle: some nodes never reach a base level.  Find one. */
        size_t bad = 0;
        unsigned char *seen = calloc(n, 1);
        for (size_t k = 0; seen != NULL && k < n; k++)
            seen[net->stack[k]] = 1;
        while (seen != NULL && bad < n && seen[bad])
            bad++;
        free(seen);
        unshape(net); /* valid, rather than a broken one */
        return dfle_error_set(err, DFLE_EINVAL, "network: node %zu never reaches a base level "
                              "(its receivers form a cycle)", bad + 1);
    }
    for (size_t i = 0; i < n; i++)
        net->source[i] = s->source != NULL ? s->source[i] != 0 : net->ndonor[i] == 0;
    net->has_channel = s->channel != NULL;
    if (net->has_channel)
        for (size_t i = 0; i < n; i++)
            net->channel[i] = s->channel[i] != 0;
    derive(net);
    net->version = stamp();
    return DFLE_OK;
}

int dfle_network_edit(dfle_network *net, int with_channel, dfle_network_edit_view *v,
                      dfle_error *err)
{
    if (with_channel && net->channel == NULL && (net->channel = malloc(net->n)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "network: out of memory");
    v->receiver = net->recv;
    v->stack = net->stack;
    v->length = net->len;
    v->A = net->A;
    v->w = net->w;
    v->source = net->source;
    v->channel = with_channel ? net->channel : NULL;
    net->editing = with_channel ? 2 : 1;
    return DFLE_OK;
}

int dfle_network_commit(dfle_network *net, dfle_error *err)
{
    const size_t n = net->n;
    int st;

    if (!net->editing)
        return dfle_error_set(err, DFLE_ESTATE, "network: commit without an edit");
    if ((st = check_shape(net, net->recv, net->len, net->A, net->w, net->stack, err)) != DFLE_OK) {
        net->editing = 0;
        unshape(net);
        return st;
    }
    if (!net->x_unset)
        for (size_t i = 0; i < n; i++)
            net->x[i] = NAN;
    net->x_unset = 1;
    index_donors(net);
    for (size_t i = 0; i < n; i++)
        net->source[i] = net->source[i] != 0;
    net->has_channel = net->editing == 2;
    if (net->has_channel)
        for (size_t i = 0; i < n; i++)
            net->channel[i] = net->channel[i] != 0;
    net->editing = 0;
    derive(net);
    net->version = stamp();
    return DFLE_OK;
}

int dfle_network_new_chain(const dfle_channel *ch, dfle_network **out, dfle_error *err)
{
    const size_t n = dfle_channel_size(ch);
    const double dx = dfle_channel_dx(ch);
    dfle_network *net;
    size_t *recv = NULL;
    double *len = NULL;
    unsigned char *source = NULL;
    int st;

    *out = NULL;
    if ((st = dfle_network_new(n, &net, err)) != DFLE_OK)
        return st;
    recv = malloc(n * sizeof *recv);
    len = malloc(n * sizeof *len);
    source = calloc(n, 1);
    if (recv == NULL || len == NULL || source == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "network: out of memory for %zu nodes", n);
    } else {
        for (size_t i = 0; i < n; i++) {
            recv[i] = i + 1 < n ? i + 1 : i;
            len[i] = dx;
        }
        source[0] = 1; /* the channel head */
        const dfle_network_shape shape = {.receiver = recv, .length = len,
                                          .A = dfle_channel_A(ch), .w = dfle_channel_w(ch),
                                          .x = dfle_channel_x(ch), .source = source};
        st = dfle_network_set(net, &shape, err);
    }
    free(recv);
    free(len);
    free(source);
    if (st != DFLE_OK) {
        dfle_network_free(net);
        return st;
    }
    assert(net->chain && net->uniform_len);
    *out = net;
    return DFLE_OK;
}

size_t dfle_network_size(const dfle_network *net) { return net->n; }
const size_t *dfle_network_receivers(const dfle_network *net) { return net->recv; }
const double *dfle_network_length(const dfle_network *net) { return net->len; }
const double *dfle_network_A(const dfle_network *net) { return net->A; }
const double *dfle_network_w(const dfle_network *net) { return net->w; }
const double *dfle_network_x(const dfle_network *net) { return net->x; }
const size_t *dfle_network_stack(const dfle_network *net) { return net->stack; }
const unsigned char *dfle_network_sources(const dfle_network *net) { return net->source; }
const unsigned char *dfle_network_channel(const dfle_network *net)
{
    return net->has_channel ? net->channel : NULL;
}
int dfle_network_uniform_length(const dfle_network *net) { return net->uniform_len; }
int dfle_network_is_chain(const dfle_network *net) { return net->chain; }
unsigned long long dfle_network_id(const dfle_network *net) { return net->id; }
unsigned long long dfle_network_version(const dfle_network *net) { return net->version; }

int dfle_network_is_base(const dfle_network *net, size_t i)
{
    assert(i < net->n);
    return net->recv[i] == i;
}

const size_t *dfle_network_bases(const dfle_network *net, size_t *n_bases)
{
    *n_bases = net->n_base;
    return net->base;
}

size_t dfle_network_base_donor(const dfle_network *net, size_t i)
{
    assert(i < net->n);
    return net->base_donor[i];
}
