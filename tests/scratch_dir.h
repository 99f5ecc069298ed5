/*
 * scratch_dir.h - one scratch directory for a test program's files:
 * made under /tmp by the group setup, removed with all it holds by the
 * group teardown, so a failed test leaves nothing behind and two test
 * programs never share a file.
 *
 * Include after defining _XOPEN_SOURCE 700 (mkdtemp), then
 *     static char dir[] = "/tmp/dfle_test_<name>_XXXXXX";
 *     ... scratch_dir_make(dir) ... scratch_path(buf, cap, dir, "a.tif") ...
 */
#ifndef DFLE_SCRATCH_DIR_H
#define DFLE_SCRATCH_DIR_H

#include <stdio.h>
#include <stdlib.h>

/* Make the directory from its template (which ends in XXXXXX): 0 on success. */
static inline int scratch_dir_make(char *tmpl)
{
    return mkdtemp(tmpl) == NULL;
}

/* Remove the directory and everything the tests wrote in it: 0 on success. */
static inline int scratch_dir_remove(const char *dir)
{
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd);
}

/* buf = dir/name. */
static inline void scratch_path(char *buf, size_t cap, const char *dir, const char *name)
{
    snprintf(buf, cap, "%s/%s", dir, name);
}

#endif
