/*
 * landscape_steady.c - what steady means for a landscape, and the check
 * that a state said to be steady is one (doc/landscape.md, "What steady
 * means for a landscape").
 *
 * Judged on the cells that matter.  Most cells of a landscape are
 * threshold hillslopes, steady by construction once they stand at S_c;
 * a quantile over all cells therefore said almost nothing about the
 * channels (a 100 x 100 grid whose 0.95 quantile was 1e-15 had 9.8 % of
 * its channel cells off their steady slope by more than 1e-3, the worst
 * by 33 %).  So the channel cells (A >= A_0) and the hillslope cells are
 * judged apart, each with its own quantile and maximum of |dz/dt|/U, and
 * the state's volume balance (what erosion removes against what uplift
 * adds) with them.
 *
 * A state that meets the criterion is then checked as a fixed point: a
 * few implicit steps from it must leave the criterion met.  A surface
 * can satisfy its rates on the routing of this instant and still move
 * away once it moves (a divide that flips at the first step).
 */
#include "landscape/landscape_internal.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The quantiles of |dz/dt|/U come from histograms over the bits of the
 * ratio as a float: exponent and the top 3 bits of the mantissa, 8 bins
 * an octave (9 % wide), no logarithm per cell.  Ratios below 2^-40 share
 * the first bin, above 2^40 the last.  The fractions above tol are
 * counted exactly. */
#define Q_SHIFT 20                          /* keep exponent + 3 mantissa bits */
#define Q_FIRST ((127u - 40u) << 3)         /* 2^-40 */
#define Q_LAST ((127u + 40u) << 3)          /* 2^40  */
#define Q_BINS (Q_LAST - Q_FIRST + 2)

static unsigned q_bin(float r)
{
    uint32_t bits;
    unsigned k;
    memcpy(&bits, &r, sizeof bits);
    k = bits >> Q_SHIFT; /* r >= 0: no sign bit */
    return k < Q_FIRST ? 0 : k > Q_LAST ? Q_BINS - 1 : k - Q_FIRST + 1;
}

/* The upper edge of bin b (b in 1 .. Q_BINS - 2). */
static double q_edge(unsigned b)
{
    uint32_t bits = (uint32_t)(b - 1 + Q_FIRST + 1) << Q_SHIFT;
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

/* |dz/dt|/U over one kind of cell. */
typedef struct ratio_part {
    size_t hist[Q_BINS];
    size_t count, above;
    double sum, max;
} ratio_part;

static void part_add(ratio_part *p, double r, double tol)
{
    p->count++;
    p->sum += r;
    p->max = r > p->max ? r : p->max;
    p->above += r > tol;
    p->hist[q_bin((float)r)]++;
}

/* The quantile q of the part: at most one bin (9 %) above the exact
 * value, never above the max. */
static double part_quantile(const ratio_part *p, double q)
{
    size_t want, cum = 0;
    if (p->count == 0)
        return 0.0;
    want = (size_t)ceil(q * (double)p->count);
    for (unsigned b = 0; b < Q_BINS; b++) {
        cum += p->hist[b];
        if (cum >= want) {
            double v = b == 0 ? 0.0 : b == Q_BINS - 1 ? p->max : q_edge(b);
            return v > p->max ? p->max : v;
        }
    }
    return p->max;
}

static double part_fraction(const ratio_part *p)
{
    return p->count > 0 ? (double)p->above / (double)p->count : 0.0;
}

void ls_ratios(const dfle_landscape *ls, const ls_judge *j, dfle_landscape_status *st)
{
    const uint32_t *rcv = dfle_drainage_receivers(ls->dr);
    const double *A = dfle_drainage_area(ls->dr);
    const int uniform = ls->U.grid == NULL;
    ratio_part *all = calloc(3, sizeof *all), *chan, *hill;
    double uplift = 0.0, change = 0.0;

    if (all == NULL) { /* 46 kB: report nothing rather than fail a step */
        st->q_ratio = st->max_ratio = st->channel_max_ratio = INFINITY;
        st->frac_above = st->channel_frac_above = st->hillslope_frac_above = 1.0;
        return;
    }
    chan = all + 1;
    hill = all + 2;
    for (size_t c = 0; c < ls->n; c++) {
        double U, r;
        if (rcv[c] == c) /* base levels and NoData */
            continue;
        /* Divided, not multiplied by 1/U: a subnormal U (valid, > 0)
         * has 1/U = inf, and 0 * inf made the mean NaN where nothing
         * changed.  A ratio that overflows stops at DBL_MAX, as the
         * model's rate_ratio does (a result scripts print and compare). */
        U = uniform ? ls->U.value : ls->U.grid[c];
        r = fabs((double)ls->dzdt[c]) / U;
        r = r <= DBL_MAX ? r : DBL_MAX;
        part_add(A[c] >= ls->o.A0 ? chan : hill, r, j->tol);
        all->sum += r; /* in cell order, as its own sum */
        uplift += U;
        change += (double)ls->dzdt[c];
    }
    /* The whole is the two parts: counts and bins add exactly. */
    all->count = chan->count + hill->count;
    all->above = chan->above + hill->above;
    all->max = chan->max > hill->max ? chan->max : hill->max;
    for (unsigned b = 0; b < Q_BINS; b++)
        all->hist[b] = chan->hist[b] + hill->hist[b];
    st->max_ratio = all->max;
    st->mean_ratio = all->count > 0 ? fmin(all->sum, DBL_MAX) / (double)all->count : 0.0;
    st->frac_above = part_fraction(all);
    st->q_ratio = part_quantile(all, 0.95);
    st->channel_q_ratio = part_quantile(chan, j->channel_quantile);
    st->channel_max_ratio = chan->max;
    st->channel_frac_above = part_fraction(chan);
    st->channel_above = chan->above;
    st->hillslope_q_ratio = part_quantile(hill, j->hillslope_quantile);
    st->hillslope_max_ratio = hill->max;
    st->hillslope_frac_above = part_fraction(hill);
    /* What erosion of every kind removes is what uplift adds less what
     * the surface keeps: sum (U - dz/dt) over the cells. */
    st->uplift_flux = uplift * ls->cell_area;
    st->outflux = (uplift - change) * ls->cell_area;
    st->volume_balance = uplift > 0 ? -change / uplift : 0.0;
    free(all);
}

int ls_rates_met(const ls_judge *j, const dfle_landscape_status *st)
{
    return st->channel_frac_above <= 1.0 - j->channel_quantile + 1e-12 &&
           st->hillslope_frac_above <= 1.0 - j->hillslope_quantile + 1e-12 &&
           fabs(st->volume_balance) <= j->tol;
}

void ls_explain(const ls_judge *j, const dfle_landscape_status *st, size_t stable_steps,
                double rcv_tol, char *buf, size_t cap)
{
    const int ok_ch = st->channel_frac_above <= 1.0 - j->channel_quantile + 1e-12;
    const int ok_hs = st->hillslope_frac_above <= 1.0 - j->hillslope_quantile + 1e-12;
    const int ok_vb = fabs(st->volume_balance) <= j->tol;
    size_t used;
    snprintf(buf, cap, "not steady: %.3g%% of the channel cells (%zu of %zu) have |dz/dt| > "
             "tol U (allowed %.3g%%; their %g quantile of |dz/dt|/U is %.3g, the max %.3g)%s; "
             "hillslopes %.3g%% (allowed %.3g%%)%s; volume balance (outflux - uplift) / uplift "
             "= %.3g (allowed %g)%s", 100 * st->channel_frac_above, st->channel_above,
             st->channel_cells, 100 * (1 - j->channel_quantile), j->channel_quantile,
             st->channel_q_ratio, st->channel_max_ratio, ok_ch ? " - met" : "",
             100 * st->hillslope_frac_above, 100 * (1 - j->hillslope_quantile),
             ok_hs ? " - met" : "", st->volume_balance, j->tol, ok_vb ? " - met" : "");
    used = strlen(buf);
    if (stable_steps > 0 && used < cap)
        snprintf(buf + used, cap - used, "; %s (rcv_tol = %g)",
                 st->stable >= stable_steps ? "the network is stable"
                 : st->rcv_changes > 0 ? "receivers still change (divides migrate)"
                                       : "the network has not been stable long enough",
                 rcv_tol);
}

void ls_saved_free(ls_saved *sv)
{
    free(sv->z);
    free(sv->rcv_prev);
    free(sv->dzdt);
    free(sv->dir);
    memset(sv, 0, sizeof *sv);
}

int ls_verify(dfle_landscape *ls, const ls_judge *j, size_t steps, double dt, ls_saved *sv,
              int *passed, size_t *taken, dfle_landscape_status *worst, dfle_error *err)
{
    const size_t n = ls->n;
    const size_t stable = ls->stable, changes = ls->rcv_changes, hashes = ls->rcv_hashes;
    const int have_rates = ls->have_rates, repeat = ls->rcv_repeat;
    uint64_t hash[LS_RCV_HISTORY];
    int st = DFLE_OK;

    *passed = 1;
    *taken = 0;
    memset(worst, 0, sizeof *worst);
    if (steps == 0)
        return DFLE_OK;
    if (sv->z == NULL) {
        sv->z = malloc(n * sizeof *sv->z);
        sv->rcv_prev = malloc(n * sizeof *sv->rcv_prev);
        sv->dzdt = malloc(n * sizeof *sv->dzdt);
        sv->dir = malloc(n);
        if (sv->z == NULL || sv->rcv_prev == NULL || sv->dzdt == NULL || sv->dir == NULL) {
            ls_saved_free(sv);
            return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory for the "
                                  "fixed-point check (%zu cells)", n);
        }
    }
    /* Route first, so that the routing put back below is this state's. */
    if ((st = ls_route(ls, err)) != DFLE_OK)
        return st;
    memcpy(sv->z, ls->z, n * sizeof *sv->z);
    memcpy(sv->rcv_prev, ls->rcv_prev, n * sizeof *sv->rcv_prev);
    memcpy(sv->dzdt, ls->dzdt, n * sizeof *sv->dzdt);
    memcpy(sv->dir, dfle_drainage_dir(ls->dr), n);
    memcpy(hash, ls->rcv_hash, sizeof hash);
    for (size_t k = 0; k < steps; k++) {
        dfle_landscape_status vs;
        memset(&vs, 0, sizeof vs);
        if ((st = ls_implicit_step(ls, dt, j, &vs, err)) != DFLE_OK)
            break;
        (*taken)++;
        vs.dt = dt;
        vs.steps = k + 1;
        vs.time = (double)(k + 1) * dt;
        if (k == 0 || vs.channel_frac_above > worst->channel_frac_above ||
            !ls_rates_met(j, &vs))
            *worst = vs;
        if (!ls_rates_met(j, &vs)) {
            *passed = 0;
            break;
        }
    }
    /* Back to the state that was checked, routed as it was: the
     * hysteresis starts from the directions of its own routing, which
     * the routing then gives again (a cell keeps a receiver within the
     * margin of the steepest, and it chose that one). */
    memcpy(ls->z, sv->z, n * sizeof *ls->z);
    ls->routed = 0;
    ls->model_z_current = 0;
    if (st == DFLE_OK)
        st = dfle_drainage_keep_directions(ls->dr, sv->dir, err);
    if (st == DFLE_OK)
        st = ls_route(ls, err);
    memcpy(ls->rcv_prev, sv->rcv_prev, n * sizeof *ls->rcv_prev);
    ls->shape_current = 0; /* the network is this routing's, not rcv_prev's */
    memcpy(ls->dzdt, sv->dzdt, n * sizeof *ls->dzdt);
    memcpy(ls->rcv_hash, hash, sizeof hash);
    ls->rcv_hashes = hashes;
    ls->rcv_repeat = repeat;
    ls->stable = stable;
    ls->rcv_changes = changes;
    ls->have_rates = have_rates;
    return st;
}
