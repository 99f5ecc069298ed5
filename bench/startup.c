/*
 * startup.c - what a dfle process costs before it does anything: the
 * CPU time (user + system, from wait4) of `dfle -q` on an empty script
 * and on one that reads a 3 x 3 DEM, each beside the same script with
 * GDAL and libnetcdf preloaded (LD_PRELOAD), which is what every process
 * paid when dfle linked them: their hundred-odd libraries loaded,
 * relocated and initialised at start.  The median of several runs, and
 * a stock `lua5.4 -e ''` for scale when its path is given.
 *
 *   build/bench/startup path/to/dfle ["libgdal.so.N libnetcdf.so.M" [path/to/lua5.4]]
 *
 * For many small jobs (SLURM arrays, shards) this is the floor of each.
 * Figures only: nothing here asserts on time.
 */
#define _DEFAULT_SOURCE /* wait4 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define REPS 21

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median CPU and wall seconds of REPS runs of argv (after one to warm
 * the page cache), with LD_PRELOAD = preload unless NULL; -1 if a run
 * fails. */
static int measure(char *const argv[], const char *preload, double *cpu, double *wall)
{
    double c[REPS], w[REPS];
    for (int k = -1; k < REPS; k++) {
        struct timespec t0, t1;
        struct rusage ru;
        int status;
        pid_t pid;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        if ((pid = fork()) < 0)
            return -1;
        if (pid == 0) {
            if (preload != NULL)
                setenv("LD_PRELOAD", preload, 1);
            execv(argv[0], argv);
            _exit(127);
        }
        if (wait4(pid, &status, 0, &ru) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
            fprintf(stderr, "startup: %s %s failed\n", argv[0], argv[1]);
            return -1;
        }
        clock_gettime(CLOCK_MONOTONIC, &t1);
        if (k < 0)
            continue;
        c[k] = (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
               1e-6 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
        w[k] = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    }
    qsort(c, REPS, sizeof c[0], by_value);
    qsort(w, REPS, sizeof w[0], by_value);
    *cpu = c[REPS / 2];
    *wall = w[REPS / 2];
    return 0;
}

static int write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (f == NULL)
        return -1;
    fputs(text, f);
    return fclose(f);
}

int main(int argc, char **argv)
{
    char dir[] = "/tmp/dfle_bench_startup_XXXXXX", empty[64], dem[64], asc[64], code[160];
    const char *preload = argc > 2 && argv[2][0] != '\0' ? argv[2] : NULL;
    double cpu[4], wall[4], lua_cpu = 0, lua_wall = 0;
    int st = 1;

    if (argc < 2) {
        fprintf(stderr, "usage: startup path/to/dfle [preload [path/to/lua5.4]]\n");
        return 2;
    }
    if (mkdtemp(dir) == NULL)
        return 1;
    snprintf(empty, sizeof empty, "%s/empty.lua", dir);
    snprintf(dem, sizeof dem, "%s/dem.lua", dir);
    snprintf(asc, sizeof asc, "%s/dem.asc", dir);
    snprintf(code, sizeof code, "assert(dfle.dem.read('%s').nx == 3)\n", asc);
    if (write_file(empty, "") == 0 && write_file(dem, code) == 0 &&
        write_file(asc, "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\n"
                        "3 2 1\n3 2 1\n3 2 1\n") == 0) {
        char *run_empty[] = {argv[1], "-q", empty, NULL}, *run_dem[] = {argv[1], "-q", dem, NULL};
        char *run_lua[] = {argc > 3 ? argv[3] : NULL, "-e", "", NULL};
        st = measure(run_empty, NULL, &cpu[0], &wall[0]) ||
             measure(run_dem, NULL, &cpu[1], &wall[1]) ||
             (preload != NULL && (measure(run_empty, preload, &cpu[2], &wall[2]) ||
                                  measure(run_dem, preload, &cpu[3], &wall[3]))) ||
             (run_lua[0] != NULL && measure(run_lua, NULL, &lua_cpu, &lua_wall));
    }
    if (st == 0) {
        printf("start-up: CPU of one `dfle -q script` process (median of %d; wall in brackets)\n",
               REPS);
        printf("  empty script: %.1f ms (%.1f ms); target: a few ms", 1e3 * cpu[0], 1e3 * wall[0]);
        if (argc > 3)
            printf(", lua5.4 -e '' takes %.1f ms (%.1f ms)", 1e3 * lua_cpu, 1e3 * lua_wall);
        printf("\n");
        if (preload != NULL)
            printf("    with GDAL and netCDF preloaded, as when dfle linked them: %.1f ms "
                   "(%.1f ms), %.0fx\n", 1e3 * cpu[2], 1e3 * wall[2], cpu[2] / cpu[0]);
        printf("  a script reading a 3 x 3 DEM (GDAL loaded on use): %.1f ms (%.1f ms)",
               1e3 * cpu[1], 1e3 * wall[1]);
        if (preload != NULL)
            printf("; target: no more than with GDAL linked, %.1f ms (%.1f ms)", 1e3 * cpu[3],
                   1e3 * wall[3]);
        printf("\n");
    }
    remove(empty);
    remove(dem);
    remove(asc);
    rmdir(dir);
    return st;
}
