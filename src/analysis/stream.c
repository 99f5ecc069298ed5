/*
 * stream.c - counter-based random streams (see dfle/stream.h for the
 * exact generator).  Kept apart from the Latin hypercube's MT19937
 * (sampling.c) because the two answer different needs: a design is one
 * long sequence; a parallel sampler needs a fresh, independent stream for
 * every (step, walker) that any thread can open without the others.
 */
#include "dfle/stream.h"

#include <math.h>

#define GOLDEN 0x9e3779b97f4a7c15ULL

static uint64_t mix(uint64_t z)
{
    z ^= z >> 30;
    z *= 0xbf58476d1ce4e5b9ULL;
    z ^= z >> 27;
    z *= 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

void dfle_stream_init(dfle_stream *s, uint64_t seed, uint64_t a, uint64_t b, uint64_t c)
{
    /* Each word is mixed before it is folded in, so keys that differ only
     * by swapping words, (1, 0) and (0, 1), are unrelated. */
    uint64_t k = mix(seed + GOLDEN);
    k = mix(k ^ mix(a + GOLDEN));
    k = mix(k ^ mix(b + GOLDEN));
    k = mix(k ^ mix(c + GOLDEN));
    s->key = k;
    s->n = 0;
}

uint64_t dfle_stream_u64(dfle_stream *s)
{
    s->n++;
    return mix(s->key + s->n * GOLDEN);
}

double dfle_stream_uniform(dfle_stream *s)
{
    return ((double)(dfle_stream_u64(s) >> 11) + 0.5) * 0x1.0p-53;
}

uint64_t dfle_stream_below(dfle_stream *s, uint64_t m)
{
    /* 2^64 mod m computed in 64 bits as (2^64 - m) mod m. */
    uint64_t limit, w;
    if (m <= 1)
        return 0;
    limit = UINT64_MAX - ((0 - m) % m); /* largest w of an unbiased draw */
    do
        w = dfle_stream_u64(s);
    while (w > limit);
    return w % m;
}

double dfle_stream_normal(dfle_stream *s)
{
    double u1 = dfle_stream_uniform(s), u2 = dfle_stream_uniform(s);
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}
