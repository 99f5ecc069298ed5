/*
 * landscape_memory.c - what a grid needs, and what this process may
 * still have.
 *
 * A grid too large for the machine was built cell by cell until the
 * kernel's out-of-memory killer ended the process without a word (a
 * 20000 x 20000 grid needs about 37 GB), or, under a memory limit, met
 * its first failed allocation only after half a minute of work.  So a
 * landscape compares its estimate with the memory available before it
 * allocates anything, and names both when the estimate is more.
 *
 * The estimate is what dfle_landscape_memory reports of a landscape that
 * has run (its arrays, the routing's, the debris-flow model's) plus what
 * a run holds while it goes (the direct rounds' scratch and the state
 * kept for the fixed-point check).  The routing's arrays, the basin
 * graph's included, hold at most ROUTING_BYTES a cell on a surface of
 * pure noise (a pit every nine cells; tests/test_landscape.c checks the
 * estimate against a run).
 */
#include "landscape/landscape_internal.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

/* The routing of pure noise: 62 bytes a cell of arrays, and the basin
 * graph of its pits (measured: at most 66 in all on 250^2-1000^2). */
#define ROUTING_BYTES 72.0

/* Bytes a cell while a run goes: the surface the direct rounds started
 * from (8), then either a round's slopes, hillslope marks and flows
 * (8 + 1 + 8) or the state a fixed-point check goes back to (z 8,
 * receivers 4, dz/dt 4, directions 1). */
#define RUN_BYTES (8.0 + 17.0)

/* The network (7 indices, 4 doubles, 3 bytes a node; a shape is
 * written into it, not copied) and the landscape's cell <-> node maps
 * (the erodibility scales by node are counted with the fields). */
double ls_network_bytes(size_t n, size_t n_data)
{
    const double nd = (double)n_data;
    return nd * (7 * sizeof(size_t) + 4 * sizeof(double) + 3) + (double)n * sizeof(uint32_t) +
           nd * sizeof(uint32_t);
}

double ls_model_bytes(size_t n, size_t n_data)
{
    const double nd = (double)n_data;
    /* The model's fields (9 doubles, an index, a flow: model.c), the
     * gathered views its law reads on scattered nodes (5 doubles and a
     * flow), made on first use, then the network's. */
    double b = nd * (9 * sizeof(double) + sizeof(size_t) + DFLE_FLOW_ARRAYS * sizeof(double));
    b += nd * (5 + DFLE_FLOW_ARRAYS) * sizeof(double);
    /* Not counted: the celerity's perturbed copies (4 doubles, an index,
     * a flow: 112 bytes a data cell) that only the explicit method,
     * a reference, makes. */
    return b + ls_network_bytes(n, n_data);
}

size_t dfle_landscape_memory_estimate(const dfle_landscape_opts *o, size_t n_data)
{
    const double n = (double)o->nx * (double)o->ny;
    double b = (double)sizeof(struct dfle_landscape) + ROUTING_BYTES * n;
    b += n * (sizeof(double) + sizeof(uint32_t) + sizeof(float)); /* z, rcv_prev, dzdt */
    b += n * sizeof(double);                                      /* z_undo */
    b += (o->U.grid != NULL || o->U.fn != NULL) * n * sizeof(double);
    b += (o->K_scale.grid != NULL || o->K_scale.fn != NULL) * n * sizeof(double);
    b += (o->df_scale.grid != NULL || o->df_scale.fn != NULL) * n * sizeof(double);
    if (o->router != NULL) {
        b += ls_model_bytes(o->nx * o->ny, n_data);
        /* the scales by node the model reads */
        b += ((o->K_scale.grid != NULL || o->K_scale.fn != NULL || o->K_scale.value != 1.0) +
              (o->df_scale.grid != NULL || o->df_scale.fn != NULL || o->df_scale.value != 1.0)) *
             (double)n_data * sizeof(double);
    }
    b += RUN_BYTES * n;
    return b < (double)SIZE_MAX ? (size_t)b : SIZE_MAX;
}

/* The first number after `key` in a text file, or -1. */
static double file_number(const char *path, const char *key)
{
    char line[512];
    double v = -1;
    FILE *f = fopen(path, "r");
    if (f == NULL)
        return -1;
    while (fgets(line, sizeof line, f) != NULL) {
        if (key == NULL || strncmp(line, key, strlen(key)) == 0) {
            const char *p = line + (key != NULL ? strlen(key) : 0);
            char *end;
            double x = strtod(p, &end);
            if (end != p)
                v = x;
            break;
        }
    }
    fclose(f);
    return v;
}

/* Take a limit if it is the least so far. */
static void consider(double bytes, const char *why, size_t *best, char *what, size_t cap)
{
    if (!(bytes >= 0))
        bytes = 0;
    if (bytes < (double)*best) {
        *best = bytes < (double)SIZE_MAX ? (size_t)bytes : SIZE_MAX;
        snprintf(what, cap, "%s", why);
    }
}

/* cgroup v2: the least of memory.max - memory.current from this
 * process's cgroup up to the root. */
static void cgroup_v2(size_t *best, char *what, size_t cap)
{
    char line[512], dir[768];
    FILE *f = fopen("/proc/self/cgroup", "r");
    if (f == NULL)
        return;
    dir[0] = '\0';
    while (fgets(line, sizeof line, f) != NULL)
        if (strncmp(line, "0::", 3) == 0) {
            line[strcspn(line, "\n")] = '\0';
            snprintf(dir, sizeof dir, "/sys/fs/cgroup%s", line + 3);
        }
    fclose(f);
    while (dir[0] != '\0') {
        char path[800], why[900];
        double max, cur;
        char *slash;
        snprintf(path, sizeof path, "%s/memory.max", dir);
        max = file_number(path, NULL); /* "max" (no limit) reads as -1 */
        snprintf(path, sizeof path, "%s/memory.current", dir);
        cur = file_number(path, NULL);
        if (max > 0 && cur >= 0) {
            snprintf(why, sizeof why, "the cgroup's memory limit (%s/memory.max, %.3g GB) less "
                     "its use", dir, max / 1e9);
            consider(max - cur, why, best, what, cap);
        }
        slash = strrchr(dir, '/');
        if (slash == NULL || strcmp(dir, "/sys/fs/cgroup") == 0)
            break;
        *slash = '\0';
    }
}

/* A resource limit less what the process already holds of it. */
static void rlimit_less(int resource, const char *status_key, const char *name, size_t *best,
                        char *what, size_t cap)
{
    struct rlimit rl;
    double held;
    char why[200];
    if (getrlimit(resource, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY)
        return;
    held = file_number("/proc/self/status", status_key) * 1024.0;
    if (held < 0)
        held = 0;
    snprintf(why, sizeof why, "the process's limit (%s, %.3g GB) less the %.3g GB it holds",
             name, (double)rl.rlim_cur / 1e9, held / 1e9);
    consider((double)rl.rlim_cur - held, why, best, what, cap);
}

size_t ls_memory_available(char *what, size_t cap)
{
    size_t best = SIZE_MAX;
    double avail = file_number("/proc/meminfo", "MemAvailable:");
    snprintf(what, cap, "no known limit");
    if (avail >= 0)
        consider(avail * 1024.0, "the memory available (MemAvailable in /proc/meminfo)", &best,
                 what, cap);
    cgroup_v2(&best, what, cap);
    rlimit_less(RLIMIT_AS, "VmSize:", "ulimit -v", &best, what, cap);
    rlimit_less(RLIMIT_DATA, "VmData:", "ulimit -d", &best, what, cap);
    return best;
}

/* Far out, neighbouring cell centres round to one coordinate (x0 =
 * 1e300 made every centre the same and maps failed later, in gnuplot):
 * the corner's precision must be a small part of a cell. */
static int check_corner(const dfle_landscape_opts *o, dfle_error *err)
{
    const double y0 = isnan(o->y0) ? (double)o->ny * o->dy : o->y0;
    const double x1 = o->x0 + (double)o->nx * o->dx, y1 = y0 - (double)o->ny * o->dy;
    const double far = fmax(fmax(fabs(o->x0), fabs(x1)), fmax(fabs(y0), fabs(y1)));
    const double cell = fmin(o->dx, o->dy);
    if (isfinite(o->x0) && isfinite(y0) && isfinite(x1) && isfinite(y1) &&
        far * DBL_EPSILON <= 1e-4 * cell)
        return DFLE_OK;
    return dfle_error_set(err, DFLE_EINVAL, "landscape: x0 = %g m, y0 = %g m put the grid where "
                          "cells of %g x %g m cannot be told apart (map coordinates there are "
                          "resolved to %.3g m); give the corner in metres of a projected map, "
                          "within %.3g m of 0", o->x0, y0, o->dx, o->dy, far * DBL_EPSILON,
                          1e-4 * cell / DBL_EPSILON);
}

int dfle_landscape_check_grid(const dfle_landscape_opts *o, size_t extra, dfle_error *err)
{
    char what[1024];
    double need, n;
    size_t avail;
    int st;

    if (o->nx < 1 || o->ny < 1 || o->nx > SIZE_MAX / o->ny)
        return dfle_error_set(err, DFLE_EINVAL, "landscape: the grid must have nx, ny >= 1 "
                              "(got %zu x %zu)", o->nx, o->ny);
    if (!(isfinite(o->dx) && o->dx > 0 && isfinite(o->dy) && o->dy > 0))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: dx and dy must be finite and > 0 m "
                              "(got %g, %g)", o->dx, o->dy);
    if ((st = check_corner(o, err)) != DFLE_OK)
        return st;
    /* A grid too large was built cell by cell until the kernel's
     * out-of-memory killer ended the process without a word.  All cells
     * count as data here: NoData is known only once z is read. */
    n = (double)o->nx * (double)o->ny;
    need = (double)dfle_landscape_memory_estimate(o, o->nx * o->ny) + (double)extra;
    avail = ls_memory_available(what, sizeof what);
    if (need <= (double)avail)
        return DFLE_OK;
    return dfle_error_set(err, DFLE_ENOMEM, "landscape: a grid of %zu x %zu cells needs about "
                          "%.3g GB (%.0f bytes a cell with the scratch of a run; ls.memory "
                          "reports what a landscape holds), more than %s: %.3g GB; use a "
                          "coarser or smaller grid", o->nx, o->ny, need / 1e9, need / n, what,
                          (double)avail / 1e9);
}
