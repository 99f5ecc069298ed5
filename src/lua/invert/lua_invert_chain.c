/*
 * lua_invert_chain.c - the chain as CSV rows: one row per walker and
 * step, written as the chain grows, read back to resume.
 *
 *   # dfle.invert v1 seed=1 walkers=32 a=2 params=U:log-uniform[...];... data=...
 *   index,step,walker,U,gamma,k_df,sigma,log_post,log_like,proposal
 *   1,0,1,0.00031...,0.52...,0.00018...,0.21...,-12.3...,-15.1...,initial
 *
 * index = step K + walker (1-based walker), so the file layer of
 * ensembles (dfle/ensemble.h: streamed rows, a cut last line dropped on
 * reopening, the sorted atomic rewrite at the end) serves as it is.
 * Numbers carry 17 significant digits: they read back to the same
 * doubles, which is what lets a resumed chain continue bit for bit.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lua/invert/lua_invert_internal.h"

static int grow(inv_run *R, size_t need)
{
    char *p;
    if (need <= R->rowcap)
        return 0;
    p = realloc(R->row, need * 2);
    if (p == NULL)
        return -1;
    R->row = p;
    R->rowcap = need * 2;
    return 0;
}

int inv_format_row(inv_run *R, size_t step, size_t k)
{
    const size_t K = R->walkers, d = R->d, at = step * K + k;
    size_t len = 0;
    int w;
    if (grow(R, 64 + 26 * (d + 2) + 32) != 0)
        return -1;
    w = snprintf(R->row, R->rowcap, "%zu,%zu,%zu", at + 1, step, k + 1);
    len = (size_t)w;
    for (size_t j = 0; j < d; j++)
        len += (size_t)snprintf(R->row + len, R->rowcap - len, ",%.17g", R->X[at * d + j]);
    len += (size_t)snprintf(R->row + len, R->rowcap - len, ",%.17g,%.17g,%s", R->LP[at],
                            R->LL[at], inv_status_name[R->ST[at]]);
    return 0;
}

static int status_code(const char *s, size_t len)
{
    for (int c = 0; c < INV_NSTATUS; c++)
        if (strlen(inv_status_name[c]) == len && strncmp(inv_status_name[c], s, len) == 0)
            return c;
    return -1;
}

/* The next comma-separated number of *p. */
static int next_number(const char **p, double *v)
{
    char *end;
    errno = 0;
    *v = strtod(*p, &end);
    if (end == *p || (*end != ',' && *end != '\0'))
        return -1;
    *p = *end == ',' ? end + 1 : end;
    return 0;
}

int inv_read_chain(inv_run *R, const char *path, char *msg, size_t msglen)
{
    const size_t K = R->walkers, d = R->d;
    dfle_ens_table *t = NULL;
    dfle_error err;
    unsigned char *seen = NULL;
    int st = -1;

    R->have = 0;
    if (dfle_ens_table_read(path, &t, &err) != DFLE_OK) {
        snprintf(msg, msglen, "%s", err.msg);
        return -1;
    }
    seen = calloc((R->steps + 1) * K, 1);
    if (seen == NULL) {
        snprintf(msg, msglen, "out of memory");
        goto done;
    }
    for (size_t r = 0; r < t->nrows; r++) {
        const char *p = t->rows[r];
        double v, step, walker;
        size_t at;
        int c;
        if (next_number(&p, &v) != 0 || next_number(&p, &step) != 0 ||
            next_number(&p, &walker) != 0 || step < 0 || walker < 1 || walker > (double)K ||
            step != floor(step) || walker != floor(walker))
            goto bad;
        if (step > (double)R->steps)
            continue; /* a longer chain than asked for: its first steps serve */
        at = (size_t)step * K + (size_t)walker - 1;
        if (t->index[r] != at + 1)
            goto bad;
        for (size_t j = 0; j < d; j++)
            if (next_number(&p, &R->X[at * d + j]) != 0)
                goto bad;
        if (next_number(&p, &R->LP[at]) != 0 || next_number(&p, &R->LL[at]) != 0)
            goto bad;
        if ((c = status_code(p, strlen(p))) < 0)
            goto bad;
        R->ST[at] = (unsigned char)c;
        seen[at] = 1;
        continue;
    bad:
        snprintf(msg, msglen, "%s: row %zu ('%.80s') is not a row of this chain", path,
                 t->index[r], t->rows[r]);
        goto done;
    }
    /* Complete steps from the start; a step cut short by a kill is redone
     * (its rows come out the same). */
    for (size_t s = 0; s <= R->steps; s++) {
        size_t k = 0;
        while (k < K && seen[s * K + k])
            k++;
        if (k < K)
            break;
        R->have = s + 1;
    }
    st = 0;
done:
    free(seen);
    dfle_ens_table_free(t);
    return st;
}
