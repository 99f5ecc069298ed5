/*
 * network.h - the domain the model is solved on: a drainage network.
 *
 * n nodes, each draining to one receiver over a flow length L [m], with
 * a drainage area A [m^2] and a channel width w [m].  A node that is its
 * own receiver is held at base level (an outlet).  The network keeps a
 * stack (Braun and Willett 2013): every node after its receiver, base
 * levels first.  Debris flows start at the sources (channel heads).
 *
 * A 1D channel is the network in which node i drains to i + 1 over dx,
 * the outlet is the base level and node 0 is the only source
 * (dfle_network_new_chain); a landscape on a raster grid sets a new
 * network from its flow routing whenever the surface changes
 * (dfle_network_set).  Each change bumps a version number, so a router
 * or a model that caches terms derived from A or w knows when to renew
 * them; the id tells networks apart, like dfle_channel_id.
 */
#ifndef DFLE_NETWORK_H
#define DFLE_NETWORK_H

#include <stddef.h>

#include "dfle/channel.h"
#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_network dfle_network;

/* The network of a channel: node i drains to i + 1 over dx, A and w
 * from the channel, x the distance from the head, node 0 the source. */
int dfle_network_new_chain(const dfle_channel *ch, dfle_network **out, dfle_error *err);

/* An empty network of n nodes (n >= 2), to be given its shape by
 * dfle_network_set before use. */
int dfle_network_new(size_t n, dfle_network **out, dfle_error *err);

void dfle_network_free(dfle_network *net);

/* What a network is made of; arrays of n values, copied. */
typedef struct dfle_network_shape {
    const size_t *receiver;     /* receiver[i] == i: base level        */
    const double *length;       /* L_i > 0 [m]; ignored on base levels */
    const double *A;            /* drainage area > 0 [m^2]             */
    const double *w;            /* channel width > 0 [m]               */
    const double *x;            /* position along the flow [m] for
                                 * messages and output; NULL: NaN      */
    const unsigned char *source; /* 1: debris flows start here; NULL:
                                  * every node that no other drains to */
    const size_t *stack;        /* every node after its receiver, base
                                 * levels first; NULL: computed        */
    const unsigned char *channel; /* 1: a channel node, eroded by rivers
                                   * and debris flows; 0: a hillslope,
                                   * which the model does not erode;
                                   * NULL: every node is a channel     */
} dfle_network_shape;

/* Give the network a new shape (same n).  Checks that receivers are
 * nodes, that following them always ends at a base level (no cycle),
 * that a given stack is one, and that lengths, areas and widths are
 * finite and positive; DFLE_EINVAL naming the first bad node otherwise,
 * leaving the network as it was. */
int dfle_network_set(dfle_network *net, const dfle_network_shape *shape, dfle_error *err);

/* The network's own arrays, writable (n each; channel NULL unless asked
 * for), for a caller that makes a new shape at every step and would
 * otherwise copy it in (a landscape at each routing): fill receiver,
 * stack (every node after its receiver), length, A, w, source and
 * channel, then dfle_network_commit, which checks them as
 * dfle_network_set does and derives the rest (x is left unset).  A shape
 * that fails the checks cannot be left as it was: the network is then
 * unshaped (every node its own base level) and the error names the
 * first bad node. */
typedef struct dfle_network_edit_view {
    size_t *receiver, *stack;
    double *length, *A, *w;
    unsigned char *source, *channel;
} dfle_network_edit_view;
int dfle_network_edit(dfle_network *net, int with_channel, dfle_network_edit_view *view,
                      dfle_error *err);
int dfle_network_commit(dfle_network *net, dfle_error *err);

size_t dfle_network_size(const dfle_network *net);
const size_t *dfle_network_receivers(const dfle_network *net);
const double *dfle_network_length(const dfle_network *net);
const double *dfle_network_A(const dfle_network *net);
const double *dfle_network_w(const dfle_network *net);
const double *dfle_network_x(const dfle_network *net);
const size_t *dfle_network_stack(const dfle_network *net);
const unsigned char *dfle_network_sources(const dfle_network *net);
/* The channel mask of the shape, or NULL when every node is a channel. */
const unsigned char *dfle_network_channel(const dfle_network *net);
int dfle_network_is_base(const dfle_network *net, size_t i);
/* Base-level nodes, and for each the donor whose slope it repeats (the
 * one of largest area; (size_t)-1 when it has none). */
const size_t *dfle_network_bases(const dfle_network *net, size_t *n_bases);
size_t dfle_network_base_donor(const dfle_network *net, size_t i);
/* 1 if every non-base length is the same (a 1D channel). */
int dfle_network_uniform_length(const dfle_network *net);
/* 1 if the network is a single chain: node i drains to i + 1 and n - 1
 * is the only base level (what a 1D router such as the process-based
 * one needs). */
int dfle_network_is_chain(const dfle_network *net);

/* Unique for the life of the process, and bumped by every set. */
unsigned long long dfle_network_id(const dfle_network *net);
unsigned long long dfle_network_version(const dfle_network *net);

#ifdef __cplusplus
}
#endif
#endif
