/*
 * stream.h - counter-based random streams: many short, independent
 * streams of random numbers, each named by a key of four whole numbers.
 *
 * The ensemble sampler (mcmc.h) gives every walker update its own stream,
 * keyed by (seed, step, walker, purpose), so that a chain is a function
 * of the seed alone: whichever thread evaluates a walker, in whatever
 * order, the same numbers come out, and a run resumed at step s draws
 * exactly what an uninterrupted run draws there.  A sequential generator
 * (MT19937 in sampling.h) cannot do that without handing one state round
 * in a fixed order.
 *
 * The generator, exactly:
 *  - mix(z): z ^= z >> 30; z *= 0xbf58476d1ce4e5b9; z ^= z >> 27;
 *    z *= 0x94d049bb133111eb; z ^= z >> 31 (64-bit unsigned arithmetic,
 *    the finaliser of SplitMix64, Steele, Lea and Flood 2014);
 *  - the key of (seed, a, b, c): k = mix(seed + G), then for each of
 *    a, b, c in turn k = mix(k ^ mix(v + G)), with G = 0x9e3779b97f4a7c15;
 *  - word n (n = 1, 2, ...) of the stream is mix(k + n G): SplitMix64
 *    started at state k;
 *  - a uniform number in (0, 1) is ((w >> 11) + 0.5) / 2^53, never 0 or
 *    1, so its logarithm is finite;
 *  - a uniform index below m is w mod m, drawing again while
 *    w >= 2^64 - (2^64 mod m) (no modulo bias);
 *  - a standard normal number is Box-Muller, sqrt(-2 ln u1) cos(2 pi u2),
 *    one number per two uniforms.
 * Integers and uniforms are bit-identical on every platform; normal
 * numbers go through the C library's log, cos and sqrt.
 */
#ifndef DFLE_STREAM_H
#define DFLE_STREAM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_stream {
    uint64_t key; /* from the four key words       */
    uint64_t n;   /* words drawn so far            */
} dfle_stream;

/* The stream keyed by (seed, a, b, c), positioned at its first word. */
void dfle_stream_init(dfle_stream *s, uint64_t seed, uint64_t a, uint64_t b, uint64_t c);

uint64_t dfle_stream_u64(dfle_stream *s);
double dfle_stream_uniform(dfle_stream *s);          /* in (0, 1)        */
uint64_t dfle_stream_below(dfle_stream *s, uint64_t m); /* in [0, m), m >= 1 */
double dfle_stream_normal(dfle_stream *s);            /* N(0, 1)          */

#ifdef __cplusplus
}
#endif
#endif
