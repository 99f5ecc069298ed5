/*
 * channel.c - the 1D channel grid (node positions, drainage area, width).
 *
 * Geometry is computed once at construction and never changes, so the
 * model and the routers read plain arrays in their inner loops.  With the
 * default Hack-law geometry and A_max = 8 km^2 the outlet lands near
 * x = 2010 m, about 400 nodes at dx = 5 m (doc/model.md, Check values).
 */
#include "dfle/channel.h"

#include "dfle/param.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>

struct dfle_channel {
    unsigned long long id; /* unique per process: caches key on it */
    size_t n;
    double dx; /* [m] */
    double *x; /* [m], one block holding x, A and w */
    double *A; /* [m^2] */
    double *w; /* [m] */
    int hack;  /* built by dfle_channel_new: opts holds what was asked */
    dfle_channel_opts opts;
};

/* Far more nodes than any 1D profile needs; stops a typo such as
 * dx = 5e-6 from allocating gigabytes. */
#define CHANNEL_MAX_NODES 10000000u

/* Ids start at 1 so 0 can mean "no channel" in a cache. */
static atomic_ullong next_channel_id = 1;

void dfle_channel_opts_default(dfle_channel_opts *o)
{
    o->dx = 5.0;
    o->A0 = 1000.0;
    o->hack_coef = 25.0;
    o->hack_exp = 5.0 / 3.0;
    o->k_w = 0.05;
    o->b = 0.3;
    o->A_max = 8e6;
    o->length = 0.0;
}

static int channel_alloc(size_t n, double dx, dfle_channel **out,
                         dfle_error *err)
{
    dfle_channel *ch;
    double *block;

    /* dx is finite, but (n - 1) dx need not be (dx = 1e308): x would be
     * inf beyond some node, and every distance after it. */
    if (!isfinite((double)(n - 1) * dx))
        return dfle_error_set(err, DFLE_EINVAL, "channel: %zu nodes of dx = %g m reach beyond "
                              "the largest number (x at the outlet is not finite)", n, dx);
    ch = malloc(sizeof *ch);
    block = calloc(3 * n, sizeof *block);
    if (ch == NULL || block == NULL) {
        free(ch);
        free(block);
        return dfle_error_set(err, DFLE_ENOMEM, "channel: out of memory for %zu nodes", n);
    }
    ch->id = atomic_fetch_add(&next_channel_id, 1);
    ch->hack = 0;
    ch->n = n;
    ch->dx = dx;
    ch->x = block;
    ch->A = block + n;
    ch->w = block + 2 * n;
    for (size_t i = 0; i < n; i++)
        ch->x[i] = (double)i * dx;
    *out = ch;
    return DFLE_OK;
}

#define CHECK(cond, ...)                                                      \
    do {                                                                      \
        if (!(cond))                                                          \
            return dfle_error_set(err, DFLE_EINVAL, __VA_ARGS__);             \
    } while (0)

int dfle_channel_new(const dfle_channel_opts *o, dfle_channel **out,
                     dfle_error *err)
{
    double length;
    size_t n;
    int st;

    *out = NULL;
    CHECK(isfinite(o->dx) && o->dx > 0, "channel: dx must be > 0 m (got %g)", o->dx);
    CHECK(isfinite(o->A0) && o->A0 > 0, "channel: A0 must be > 0 m^2 (got %g)", o->A0);
    CHECK(isfinite(o->hack_coef) && o->hack_coef >= 0,
          "channel: hack_coef must be >= 0 (got %g)", o->hack_coef);
    CHECK(isfinite(o->hack_exp) && o->hack_exp > 0,
          "channel: hack_exp must be > 0 (got %g)", o->hack_exp);
    CHECK(isfinite(o->k_w) && o->k_w > 0, "channel: k_w must be > 0 (got %g)", o->k_w);
    CHECK(isfinite(o->b), "channel: b must be a finite number (got %g)", o->b);
    CHECK(isfinite(o->length) && o->length >= 0,
          "channel: length must be >= 0 m (got %g)", o->length);

    if (o->length > 0) {
        length = o->length;
    } else {
        CHECK(isfinite(o->A_max) && o->A_max > o->A0,
              "channel: A_max must be > A0 = %g m^2 (got %g)", o->A0, o->A_max);
        CHECK(o->hack_coef > 0,
              "channel: hack_coef must be > 0 to reach A_max; give length instead");
        /* Invert A(x) = A0 + c x^p for the distance at which A = A_max. */
        length = pow((o->A_max - o->A0) / o->hack_coef, 1.0 / o->hack_exp);
    }
    /* Ceil so the outlet is the first node with A >= A_max; the small
     * slack keeps an exact multiple of dx from gaining a node to rounding. */
    {
        double intervals = ceil(length / o->dx - 1e-9);
        CHECK(intervals >= 2, "channel: length %g m with dx = %g m gives fewer than 3 nodes",
              length, o->dx);
        CHECK(intervals < CHANNEL_MAX_NODES,
              "channel: length %g m / dx %g m is more than %u nodes", length, o->dx,
              CHANNEL_MAX_NODES);
        n = (size_t)intervals + 1;
    }
    st = channel_alloc(n, o->dx, out, err);
    if (st != DFLE_OK)
        return st;
    (*out)->hack = 1;
    (*out)->opts = *o;
    for (size_t i = 0; i < n; i++) {
        dfle_channel *ch = *out;
        ch->A[i] = o->A0 + o->hack_coef * pow(ch->x[i], o->hack_exp);
        ch->w[i] = o->k_w * pow(ch->A[i], o->b);
        /* Extreme exponents overflow here; say so now, not as NaN later. */
        if (!(isfinite(ch->A[i]) && isfinite(ch->w[i]) && ch->w[i] > 0)) {
            dfle_error_set(err, DFLE_EINVAL,
                           "channel: A = %g m^2, w = %g m at node %zu (x = %g m) are not "
                           "finite and positive; check hack_coef, hack_exp, k_w and b",
                           ch->A[i], ch->w[i], i + 1, ch->x[i]);
            dfle_channel_free(ch);
            *out = NULL;
            return DFLE_EINVAL;
        }
    }
    return DFLE_OK;
}

int dfle_channel_new_from_arrays(size_t n, double dx, const double *A,
                                 const double *w, dfle_channel **out,
                                 dfle_error *err)
{
    int st;

    *out = NULL;
    CHECK(n >= 3, "channel: need at least 3 nodes (got %zu)", n);
    CHECK(n < CHANNEL_MAX_NODES, "channel: %zu nodes is too many", n);
    CHECK(isfinite(dx) && dx > 0, "channel: dx must be > 0 m (got %g)", dx);
    CHECK(A != NULL && w != NULL, "channel: A and w arrays are required");
    for (size_t i = 0; i < n; i++) {
        CHECK(isfinite(A[i]) && A[i] > 0, "channel: A at node %zu must be > 0 m^2 (got %g)",
              i + 1, A[i]);
        CHECK(i == 0 || A[i] >= A[i - 1],
              "channel: A must not decrease downstream (node %zu: %g < %g)", i + 1, A[i],
              A[i - 1]);
        CHECK(isfinite(w[i]) && w[i] > 0, "channel: w at node %zu must be > 0 m (got %g)",
              i + 1, w[i]);
    }
    st = channel_alloc(n, dx, out, err);
    if (st != DFLE_OK)
        return st;
    for (size_t i = 0; i < n; i++) {
        (*out)->A[i] = A[i];
        (*out)->w[i] = w[i];
    }
    return DFLE_OK;
}

void dfle_channel_free(dfle_channel *ch)
{
    if (ch == NULL)
        return;
    free(ch->x);
    free(ch);
}

unsigned long long dfle_channel_id(const dfle_channel *ch) { return ch->id; }
size_t dfle_channel_size(const dfle_channel *ch) { return ch->n; }
double dfle_channel_dx(const dfle_channel *ch) { return ch->dx; }
const double *dfle_channel_x(const dfle_channel *ch) { return ch->x; }
const double *dfle_channel_A(const dfle_channel *ch) { return ch->A; }
const double *dfle_channel_w(const dfle_channel *ch) { return ch->w; }

const char *dfle_channel_kind(const dfle_channel *ch) { return ch->hack ? "hack" : "arrays"; }

size_t dfle_channel_params(const dfle_channel *ch, dfle_param *out, size_t cap)
{
    const dfle_channel_opts *o = &ch->opts;
    /* The options as given (A_max is the area asked for; the outlet's is
     * dfle_channel_A at n - 1), so they rebuild the same channel. */
    const dfle_param p[] = {
        {"dx", ch->dx, "m", 0},
        {"A0", o->A0, "m^2", 0},
        {"hack_coef", o->hack_coef, "m^(2-hack_exp)", 0},
        {"hack_exp", o->hack_exp, "", 0},
        {"k_w", o->k_w, "m^(1-2 b)", 0},
        {"b", o->b, "", 0},
        {"A_max", o->A_max, "m^2", 0},
        {"length", o->length, "m", 0},
    };
    /* A channel from node arrays has no formula behind it: only dx. */
    return dfle_param_copy(p, ch->hack ? sizeof p / sizeof p[0] : 1, out, cap);
}
