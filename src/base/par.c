/*
 * par.c - the serial side of parallel loops (par.h): a loop without a
 * pool, or too small to share, runs here in the calling thread.
 */
#include "dfle/par.h"

int dfle_par_workers(const dfle_par *p)
{
    return p != NULL && p->ops != NULL && p->workers > 1 ? p->workers : 1;
}

int dfle_par_run(const dfle_par *p, size_t n, dfle_par_fn fn, void *arg, dfle_error *err)
{
    if (dfle_par_workers(p) > 1 && n > 1) {
        if (p->ops->version < 1 || p->ops->version > DFLE_PAR_VERSION || p->ops->run == NULL)
            return dfle_error_set(err, DFLE_EINVAL, "par %s: ops version %d, this library knows "
                                  "1 to %d, with run()", p->ops->name != NULL ? p->ops->name : "?",
                                  p->ops->version, DFLE_PAR_VERSION);
        return p->ops->run(p->ud, n, fn, arg, err);
    }
    for (size_t i = 0; i < n; i++)
        fn(arg, i);
    return DFLE_OK;
}
