/*
 * test_file.c - files written whole or not at all (dfle/file.h): the old
 * file survives every failure, no temporary file is left behind, a dead
 * writer's leftover is cleaned up, and what is not a regular file (a
 * FIFO, a symbolic link) is never replaced by one.
 */
#define _XOPEN_SOURCE 700 /* mkdtemp */
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "dfle_test.h"

#include "dfle/file.h"

typedef struct dir {
    char path[256];
} dir;

static int setup(void **state)
{
    dir *d = calloc(1, sizeof *d);
    if (d == NULL)
        return -1;
    snprintf(d->path, sizeof d->path, "%s/dfle-file-XXXXXX",
             getenv("TMPDIR") != NULL ? getenv("TMPDIR") : "/tmp");
    if (mkdtemp(d->path) == NULL) {
        free(d);
        return -1;
    }
    *state = d;
    return 0;
}

static int teardown(void **state)
{
    dir *d = *state;
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", d->path);
    if (system(cmd) != 0)
        return -1;
    free(d);
    return 0;
}

static void put(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}

static void assert_contents(const char *path, const char *text)
{
    char buf[256] = {0};
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    assert_string_equal(buf, text);
}

/* Entries of the directory other than the names given (NULL-ended). */
static int stray_entries(const char *dirpath, const char *const *keep)
{
    char cmd[512], line[512];
    int n = 0;
    snprintf(cmd, sizeof cmd, "ls -A '%s'", dirpath);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    while (fgets(line, sizeof line, p) != NULL) {
        int kept = 0;
        line[strcspn(line, "\n")] = '\0';
        for (size_t k = 0; keep[k] != NULL; k++)
            kept |= strcmp(line, keep[k]) == 0;
        if (!kept) {
            print_message("stray entry: %s\n", line);
            n++;
        }
    }
    pclose(p);
    return n;
}

static void replaces_whole_and_leaves_nothing_behind(void **state)
{
    dir *d = *state;
    char path[300];
    dfle_file f;
    dfle_error err;
    const char *const keep[] = {"out.csv", NULL};
    snprintf(path, sizeof path, "%s/out.csv", d->path);
    put(path, "old\n");
    assert_ok(dfle_file_begin(&f, path, "test", &err), &err);
    fputs("new\n", f.fp);
    assert_contents(path, "old\n"); /* readers see the old file until commit */
    assert_ok(dfle_file_commit(&f, &err), &err);
    assert_contents(path, "new\n");
    assert_int_equal(stray_entries(d->path, keep), 0);
}

static void abort_keeps_the_old_file(void **state)
{
    dir *d = *state;
    char path[300];
    dfle_file f;
    dfle_error err;
    const char *const keep[] = {"out.csv", NULL};
    snprintf(path, sizeof path, "%s/out.csv", d->path);
    put(path, "old\n");
    assert_ok(dfle_file_begin(&f, path, "test", &err), &err);
    fputs("half of a new", f.fp);
    dfle_file_abort(&f);
    assert_contents(path, "old\n");
    assert_int_equal(stray_entries(d->path, keep), 0);
}

/* Under a file-size limit the write fails with the system's reason and
 * the good file stays (it was once replaced by a truncated one). */
static void file_size_limit_keeps_the_old_file(void **state)
{
    dir *d = *state;
    char path[300];
    dfle_file f;
    dfle_error err;
    struct rlimit old, small;
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    const char *const keep[] = {"out.csv", NULL};
    snprintf(path, sizeof path, "%s/out.csv", d->path);
    put(path, "old\n");
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    small = old;
    small.rlim_cur = 4096;
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &small), 0);
    assert_ok(dfle_file_begin(&f, path, "test", &err), &err);
    for (int i = 0; i < 10000; i++)
        fputs("0123456789\n", f.fp);
    int st = dfle_file_commit(&f, &err);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &old), 0);
    signal(SIGXFSZ, old_handler);
    assert_int_equal(st, DFLE_EIO);
    assert_msg_contains(err.msg, "test: cannot write");
    assert_msg_contains(err.msg, strerror(EFBIG));
    assert_contents(path, "old\n");
    assert_int_equal(stray_entries(d->path, keep), 0);
}

/* A leftover of a killed writer is removed by the next write of the same
 * target; one of a live process (pid 1) and another target's are not. */
static void dead_writers_leftovers_are_cleaned(void **state)
{
    dir *d = *state;
    char path[300], dead[400], live[400], other[400];
    dfle_file f;
    dfle_error err;
    const char *const keep[] = {"out.csv", ".out.csv.1.123456", ".b.csv.999999999.123456", NULL};
    snprintf(path, sizeof path, "%s/out.csv", d->path);
    snprintf(dead, sizeof dead, "%s/.out.csv.999999999.123456", d->path);
    snprintf(live, sizeof live, "%s/.out.csv.1.123456", d->path);
    snprintf(other, sizeof other, "%s/.b.csv.999999999.123456", d->path);
    put(dead, "");
    put(live, "");
    put(other, "");
    assert_ok(dfle_file_begin(&f, path, "test", &err), &err);
    fputs("x\n", f.fp);
    assert_ok(dfle_file_commit(&f, &err), &err);
    assert_int_equal(access(dead, F_OK), -1);
    assert_int_equal(access(live, F_OK), 0);
    assert_int_equal(access(other, F_OK), 0);
    assert_int_equal(stray_entries(d->path, keep), 0);
}

/* A FIFO (like a device) is written in place: renaming over it would
 * put a plain file where it was (it once replaced /dev/null). */
static void a_fifo_stays_a_fifo(void **state)
{
    dir *d = *state;
    char path[300], buf[16] = {0};
    dfle_file f;
    dfle_error err;
    struct stat st;
    snprintf(path, sizeof path, "%s/pipe", d->path);
    assert_int_equal(mkfifo(path, 0600), 0);
    int rd = open(path, O_RDONLY | O_NONBLOCK); /* a reader, so the writer can open */
    assert_true(rd >= 0);
    assert_ok(dfle_file_begin(&f, path, "test", &err), &err);
    fputs("hello", f.fp);
    assert_ok(dfle_file_commit(&f, &err), &err);
    assert_int_equal(read(rd, buf, sizeof buf - 1), 5);
    assert_string_equal(buf, "hello");
    close(rd);
    assert_int_equal(stat(path, &st), 0);
    assert_true(S_ISFIFO(st.st_mode));
}

/* A FIFO no process reads is an error at once: the open used to wait for
 * a reader for ever (found by the fuzzer).  SIGALRM ends a hang here. */
static void a_fifo_without_a_reader_is_an_error(void **state)
{
    dir *d = *state;
    char path[300];
    dfle_file f;
    dfle_error err;
    struct stat st;
    snprintf(path, sizeof path, "%s/pipe", d->path);
    assert_int_equal(mkfifo(path, 0600), 0);
    alarm(20);
    assert_int_equal(dfle_file_begin(&f, path, "test", &err), DFLE_EIO);
    alarm(0);
    assert_msg_contains(err.msg, "test: cannot write");
    assert_msg_contains(err.msg, "it is a FIFO that no process is reading");
    assert_int_equal(stat(path, &st), 0);
    assert_true(S_ISFIFO(st.st_mode));
}

/* For the writers whose library may remove what it was told to create
 * (libnetcdf) or seeks in it (GDAL): a temporary file always, and a
 * FIFO, a device or a link to one refused, left as it was; a regular
 * file, a new name and a link to a file are written as ever. */
static void regular_only_refuses_nodes(void **state)
{
    dir *d = *state;
    char fifo[300], link[300], target[300], fresh[300];
    const char *to;
    dfle_file f;
    dfle_error err;
    struct stat st;
    FILE *fp;
    snprintf(fifo, sizeof fifo, "%s/pipe", d->path);
    snprintf(link, sizeof link, "%s/link", d->path);
    snprintf(target, sizeof target, "%s/target", d->path);
    snprintf(fresh, sizeof fresh, "%s/fresh", d->path);
    assert_int_equal(mkfifo(fifo, 0600), 0);
    assert_int_equal(symlink(fifo, link), 0);
    assert_int_equal(dfle_file_begin_regular(&f, fifo, "nc", &to, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "nc: cannot write");
    assert_msg_contains(err.msg, "it is a FIFO");
    assert_int_equal(dfle_file_begin_regular(&f, link, "nc", &to, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "it is a link to a FIFO");
    assert_int_equal(dfle_file_begin_regular(&f, d->path, "nc", &to, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "it is a directory");
    assert_int_equal(lstat(link, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_int_equal(stat(fifo, &st), 0);
    assert_true(S_ISFIFO(st.st_mode));
    /* A new name: a temporary file, renamed at the commit. */
    assert_ok(dfle_file_begin_regular(&f, fresh, "nc", &to, &err), &err);
    assert_string_not_equal(to, fresh);
    assert_non_null(fp = fopen(to, "w"));
    fputs("x", fp);
    fclose(fp);
    assert_ok(dfle_file_commit(&f, &err), &err);
    assert_int_equal(stat(fresh, &st), 0);
    assert_true(S_ISREG(st.st_mode) && st.st_size == 1);
    /* A link to a regular file: the file replaced, the link kept. */
    assert_non_null(fp = fopen(target, "w"));
    fclose(fp);
    unlink(link);
    assert_int_equal(symlink(target, link), 0);
    assert_ok(dfle_file_begin_regular(&f, link, "nc", &to, &err), &err);
    assert_non_null(fp = fopen(to, "w"));
    fputs("yy", fp);
    fclose(fp);
    assert_ok(dfle_file_commit(&f, &err), &err);
    assert_int_equal(lstat(link, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_int_equal(stat(target, &st), 0);
    assert_int_equal(st.st_size, 2);
}

/* A name of NAME_MAX bytes is written like any other: the temporary
 * name beside it is shortened (it was too long for the file system). */
static void the_longest_names_are_written(void **state)
{
    dir *d = *state;
    char name[256], path[600];
    dfle_file f;
    dfle_error err;
    const char *const keep[] = {name, NULL};
    memset(name, 'n', 255);
    name[255] = '\0';
    memcpy(name + 251, ".csv", 4);
    snprintf(path, sizeof path, "%s/%s", d->path, name);
    for (int round = 0; round < 2; round++) {
        assert_ok(dfle_file_begin(&f, path, "test", &err), &err);
        fputs(round ? "new\n" : "old\n", f.fp);
        assert_ok(dfle_file_commit(&f, &err), &err);
    }
    assert_contents(path, "new\n");
    assert_int_equal(stray_entries(d->path, keep), 0);
}

/* A symbolic link stays a link; the file it points at is replaced. */
static void a_link_stays_a_link(void **state)
{
    dir *d = *state;
    char path[300], link[300];
    dfle_file f;
    dfle_error err;
    struct stat st;
    snprintf(path, sizeof path, "%s/target.csv", d->path);
    snprintf(link, sizeof link, "%s/link.csv", d->path);
    put(path, "old\n");
    assert_int_equal(symlink(path, link), 0);
    assert_ok(dfle_file_begin(&f, link, "test", &err), &err);
    fputs("new\n", f.fp);
    assert_ok(dfle_file_commit(&f, &err), &err);
    assert_int_equal(lstat(link, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_contents(path, "new\n");
}

static void bad_targets_say_why(void **state)
{
    dir *d = *state;
    char path[300];
    dfle_file f;
    dfle_error err;
    assert_int_equal(dfle_file_begin(&f, d->path, "test", &err), DFLE_EIO);
    assert_msg_contains(err.msg, "is a directory");
    snprintf(path, sizeof path, "%s/no/such/dir.csv", d->path);
    assert_int_equal(dfle_file_begin(&f, path, "test", &err), DFLE_EIO);
    assert_msg_contains(err.msg, strerror(ENOENT));
    assert_int_equal(dfle_file_begin(&f, "", "test", &err), DFLE_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(replaces_whole_and_leaves_nothing_behind, setup, teardown),
        cmocka_unit_test_setup_teardown(abort_keeps_the_old_file, setup, teardown),
        cmocka_unit_test_setup_teardown(file_size_limit_keeps_the_old_file, setup, teardown),
        cmocka_unit_test_setup_teardown(dead_writers_leftovers_are_cleaned, setup, teardown),
        cmocka_unit_test_setup_teardown(a_fifo_stays_a_fifo, setup, teardown),
        cmocka_unit_test_setup_teardown(a_fifo_without_a_reader_is_an_error, setup, teardown),
        cmocka_unit_test_setup_teardown(regular_only_refuses_nodes, setup, teardown),
        cmocka_unit_test_setup_teardown(the_longest_names_are_written, setup, teardown),
        cmocka_unit_test_setup_teardown(a_link_stays_a_link, setup, teardown),
        cmocka_unit_test_setup_teardown(bad_targets_say_why, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
