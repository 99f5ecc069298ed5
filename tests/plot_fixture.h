/*
 * plot_fixture.h - what the figure tests share: a temporary directory
 * per test (mkdtemp; emptied and removed by the teardown), files' first
 * bytes, PNG/SVG checks, and a gnuplot that keeps the script it was sent
 * (DFLE_GNUPLOT set for one call, the old value put back).
 */
#ifndef DFLE_TEST_PLOT_FIXTURE_H
#define DFLE_TEST_PLOT_FIXTURE_H

#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "dfle/error.h"
#include "dfle_test.h"

typedef struct fixture {
    char dir[64];
    char path[512];
} fixture;

static inline int setup(void **state)
{
    fixture *fx = calloc(1, sizeof *fx);
    if (fx == NULL) return -1;
    strcpy(fx->dir, "/tmp/dfle-test-plot-XXXXXX");
    if (mkdtemp(fx->dir) == NULL) {
        free(fx);
        return -1;
    }
    *state = fx;
    return 0;
}

static inline int teardown(void **state)
{
    fixture *fx = *state;
    DIR *d = opendir(fx->dir);
    struct dirent *de;
    char p[600];
    while (d != NULL && (de = readdir(d)) != NULL) {
        if (strcmp(de->d_name, ".") == 0 || strcmp(de->d_name, "..") == 0)
            continue;
        snprintf(p, sizeof p, "%s/%s", fx->dir, de->d_name);
        unlink(p);
    }
    if (d != NULL) closedir(d);
    int rc = rmdir(fx->dir);
    free(fx);
    return rc;
}

/* fx->path = <dir>/<name> */
static inline const char *in_dir(fixture *fx, const char *name)
{
    snprintf(fx->path, sizeof fx->path, "%s/%s", fx->dir, name);
    return fx->path;
}

static inline size_t dir_entries(const fixture *fx)
{
    DIR *d = opendir(fx->dir);
    size_t k = 0;
    struct dirent *de;
    while (d != NULL && (de = readdir(d)) != NULL)
        k += strcmp(de->d_name, ".") != 0 && strcmp(de->d_name, "..") != 0;
    if (d != NULL) closedir(d);
    return k;
}

/* First `cap` bytes of a file; returns how many were read (0 if none). */
static inline size_t head(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) return 0;
    size_t k = fread(buf, 1, cap, f);
    fclose(f);
    return k;
}

static inline void assert_png(const char *path)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n',
                                         0x1a, '\n'};
    char buf[8];
    struct stat sb;
    assert_int_equal(stat(path, &sb), 0);
    assert_true(sb.st_size > 1000);
    assert_int_equal(head(path, buf, sizeof buf), 8);
    assert_memory_equal(buf, sig, 8);
}

static inline void assert_svg(const char *path)
{
    char buf[4096];
    size_t k = head(path, buf, sizeof buf - 1);
    buf[k] = '\0';
    assert_true(k > 100);
    assert_true(strncmp(buf, "<?xml", 5) == 0 || strstr(buf, "<svg") != NULL);
}

static inline void assert_missing(const char *path)
{
    struct stat sb;
    assert_int_not_equal(stat(path, &sb), 0);
}

/* Run f with DFLE_GNUPLOT = prog, then put the old value back. */
static inline int with_gnuplot(const char *prog, int (*f)(fixture *, dfle_error *),
                        fixture *fx, dfle_error *err)
{
    const char *old = getenv("DFLE_GNUPLOT");
    char *saved = old != NULL ? strdup(old) : NULL;
    setenv("DFLE_GNUPLOT", prog, 1);
    int rc = f(fx, err);
    if (saved != NULL) setenv("DFLE_GNUPLOT", saved, 1);
    else unsetenv("DFLE_GNUPLOT");
    free(saved);
    return rc;
}

/* A gnuplot that keeps a copy of the script it is sent, then draws. */
static inline const char *teeing_gnuplot(fixture *fx, char *prog, size_t cap)
{
    FILE *f;
    snprintf(prog, cap, "%s/tee-gnuplot", fx->dir);
    f = fopen(prog, "w");
    assert_non_null(f);
    fprintf(f, "#!/bin/sh\ntee '%s/script.gp' | gnuplot\n", fx->dir);
    fclose(f);
    assert_int_equal(chmod(prog, 0755), 0);
    return prog;
}

/* The script gnuplot was last sent (NUL-terminated, static); leaves
 * fx->path as it was. */
static inline const char *last_script(fixture *fx)
{
    static char buf[1 << 18];
    char path[600];
    snprintf(path, sizeof path, "%s/script.gp", fx->dir);
    size_t k = head(path, buf, sizeof buf - 1);
    buf[k] = '\0';
    return buf;
}


#endif
