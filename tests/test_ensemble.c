/*
 * test_ensemble.c - the ensemble file layer (dfle/ensemble.h): streamed
 * rows, resume over a truncated last line, the sorted rewrite, gather of
 * shards, and the index queue (shards, done samples, limit, threads,
 * indices given back).
 */
#define _XOPEN_SOURCE 700 /* mknod */
#include "dfle_test.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/sysmacros.h> /* makedev */
#include <unistd.h>

#include "dfle/ensemble.h"

#define META "# dfle.ensemble v1 n=6 test"
#define HEADER "index,x,status,reason"

static char dir[64];

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/dfle-test-ens-XXXXXX");
    return mkdtemp(dir) == NULL;
}

static int teardown(void **state)
{
    char cmd[128];
    (void)state;
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) != 0;
}

static void path(char *buf, size_t len, const char *name)
{
    snprintf(buf, len, "%s/%s", dir, name);
}

static void row(char *buf, size_t len, size_t i)
{
    snprintf(buf, len, "%zu,%g,ok,\"\"", i, 0.5 * (double)i);
}

static const char *expected =
    META "\n" HEADER "\n1,0.5,ok,\"\"\n2,1,ok,\"\"\n3,1.5,ok,\"\"\n4,2,ok,\"\"\n5,2.5,ok,\"\"\n"
         "6,3,ok,\"\"\n";

static void test_stream_sort_resume(void **state)
{
    char p[128], r[64];
    dfle_ens_file *f;
    dfle_error err;
    FILE *fp;
    char *text;
    static const size_t order[] = {4, 2, 6};
    (void)state;

    path(p, sizeof p, "a.csv");
    assert_ok(dfle_ens_file_open(p, META, NULL, HEADER, 6, 1, &f, &err), &err);
    for (size_t k = 0; k < 3; k++) {
        row(r, sizeof r, order[k]);
        assert_ok(dfle_ens_file_append(f, order[k], r, &err), &err);
    }
    /* a repeated or out-of-range sample is refused */
    row(r, sizeof r, 4);
    assert_int_equal(dfle_ens_file_append(f, 4, r, &err), DFLE_EINVAL);
    row(r, sizeof r, 7);
    assert_int_equal(dfle_ens_file_append(f, 7, r, &err), DFLE_EINVAL);
    /* rows are on disk, in finishing order, before closing */
    text = dfle_test_slurp(p);
    assert_string_equal(text, META "\n" HEADER "\n4,2,ok,\"\"\n2,1,ok,\"\"\n6,3,ok,\"\"\n");
    free(text);
    assert_ok(dfle_ens_file_close(f, 0, &err), &err);

    /* a killed writer left half a row */
    fp = fopen(p, "ab");
    fputs("5,2.", fp);
    fclose(fp);
    assert_ok(dfle_ens_file_open(p, META, NULL, HEADER, 6, 1, &f, &err), &err);
    assert_int_equal(dfle_ens_file_ndone(f), 3);
    assert_true(dfle_ens_file_done(f, 2));
    assert_false(dfle_ens_file_done(f, 5));
    for (size_t i = 1; i <= 6; i++)
        if (!dfle_ens_file_done(f, i)) {
            row(r, sizeof r, i);
            assert_ok(dfle_ens_file_append(f, i, r, &err), &err);
        }
    assert_ok(dfle_ens_file_close(f, 1, &err), &err);
    text = dfle_test_slurp(p);
    assert_string_equal(text, expected);
    free(text);

    /* another ensemble's file is refused; resume = 0 replaces it */
    assert_int_equal(dfle_ens_file_open(p, "# other", NULL, HEADER, 6, 1, &f, &err), DFLE_EINVAL);
    assert_non_null(strstr(err.msg, "different ensemble"));
    assert_ok(dfle_ens_file_open(p, "# other", NULL, HEADER, 6, 0, &f, &err), &err);
    assert_int_equal(dfle_ens_file_ndone(f), 0);
    assert_ok(dfle_ens_file_close(f, 1, &err), &err);
    text = dfle_test_slurp(p);
    assert_string_equal(text, "# other\n" HEADER "\n");
    free(text);
}

/* Comment lines between meta and header: written with a new file,
 * kept by resume (not compared: they describe, meta and header
 * identify), by the sorted rewrite and by gather (the first file's);
 * CSV readers skip them. */
static void test_comment_lines(void **state)
{
    char p[128], q[128], out[128], r[64];
    const char *files[2];
    dfle_ens_file *f;
    dfle_ens_table *t;
    dfle_error err;
    char *text;
    (void)state;

    path(p, sizeof p, "c.csv");
    path(q, sizeof q, "d.csv");
    path(out, sizeof out, "cd.csv");
    assert_int_equal(dfle_ens_file_open(p, META, "# ok\nnot a comment", HEADER, 6, 1, &f, &err),
                     DFLE_EINVAL);
    assert_ok(dfle_ens_file_open(p, META, "# dfle: 9\n# units: x=m", HEADER, 6, 1, &f, &err), &err);
    row(r, sizeof r, 3);
    assert_ok(dfle_ens_file_append(f, 3, r, &err), &err);
    assert_ok(dfle_ens_file_close(f, 0, &err), &err);
    /* resumed by another version: its rows count, the lines stay */
    assert_ok(dfle_ens_file_open(p, META, "# dfle: 10", HEADER, 6, 1, &f, &err), &err);
    assert_int_equal(dfle_ens_file_ndone(f), 1);
    row(r, sizeof r, 1);
    assert_ok(dfle_ens_file_append(f, 1, r, &err), &err);
    assert_ok(dfle_ens_file_close(f, 1, &err), &err);
    text = dfle_test_slurp(p);
    assert_string_equal(text, META "\n# dfle: 9\n# units: x=m\n" HEADER
                              "\n1,0.5,ok,\"\"\n3,1.5,ok,\"\"\n");
    free(text);
    assert_ok(dfle_ens_table_read(p, &t, &err), &err);
    assert_string_equal(t->comments, "# dfle: 9\n# units: x=m");
    assert_string_equal(t->header, HEADER);
    assert_int_equal(t->nrows, 2);
    dfle_ens_table_free(t);
    /* gather: the first file's lines */
    assert_ok(dfle_ens_file_open(q, META, NULL, HEADER, 6, 1, &f, &err), &err);
    row(r, sizeof r, 2);
    assert_ok(dfle_ens_file_append(f, 2, r, &err), &err);
    assert_ok(dfle_ens_file_close(f, 1, &err), &err);
    files[0] = p;
    files[1] = q;
    assert_ok(dfle_ens_gather(files, 2, out, NULL, &err), &err);
    text = dfle_test_slurp(out);
    assert_string_equal(text, META "\n# dfle: 9\n# units: x=m\n" HEADER
                              "\n1,0.5,ok,\"\"\n2,1,ok,\"\"\n3,1.5,ok,\"\"\n");
    free(text);
    remove(p);
    remove(q);
    remove(out);
}

static void test_gather_shards(void **state)
{
    char p[3][128], out[128], r[64];
    const char *files[3];
    dfle_ens_file *f;
    dfle_ens_queue *q;
    dfle_error err;
    size_t i, nrows;
    char *text;
    (void)state;

    for (size_t s = 1; s <= 3; s++) {
        char name[32];
        snprintf(name, sizeof name, "s%zu.csv", s);
        path(p[s - 1], sizeof p[s - 1], name);
        files[3 - s] = p[s - 1];
        assert_ok(dfle_ens_file_open(p[s - 1], META, NULL, HEADER, 6, 1, &f, &err), &err);
        assert_ok(dfle_ens_queue_new(6, s, 3, f, 0, &q, &err), &err);
        assert_int_equal(dfle_ens_queue_total(q), 2);
        while (dfle_ens_queue_next(q, &i)) {
            assert_int_equal((i - 1) % 3, s - 1);
            row(r, sizeof r, i);
            assert_ok(dfle_ens_file_append(f, i, r, &err), &err);
        }
        dfle_ens_queue_free(q);
        assert_ok(dfle_ens_file_close(f, 1, &err), &err);
    }
    path(out, sizeof out, "all.csv");
    assert_ok(dfle_ens_gather(files, 3, out, &nrows, &err), &err);
    assert_int_equal(nrows, 6);
    text = dfle_test_slurp(out);
    assert_string_equal(text, expected);
    free(text);
    /* the same file twice: identical rows are merged */
    files[1] = out;
    assert_ok(dfle_ens_gather(files, 3, out, &nrows, &err), &err);
    assert_int_equal(nrows, 6);
    /* a conflicting row is an error naming both files */
    {
        FILE *fp = fopen(p[0], "ab");
        fputs("2,9,ok,\"\"\n", fp);
        fclose(fp);
    }
    files[0] = p[0];
    files[1] = p[1];
    assert_int_equal(dfle_ens_gather(files, 2, out, &nrows, &err), DFLE_EINVAL);
    assert_non_null(strstr(err.msg, "sample 2 differs"));
    /* shard queue rule */
    assert_true(dfle_ens_in_shard(7, 1, 3));
    assert_false(dfle_ens_in_shard(7, 2, 3));
    assert_true(dfle_ens_in_shard(7, 0, 0));
}

typedef struct shared {
    dfle_ens_queue *q;
    size_t count[101];
} shared;

static void *drain(void *arg)
{
    shared *s = arg;
    size_t i;
    while (dfle_ens_queue_next(s->q, &i))
        s->count[i]++; /* each index is handed out once: no two threads write one slot */
    return NULL;
}

static void test_queue_threads_limit(void **state)
{
    shared s;
    pthread_t t[4];
    dfle_error err;
    dfle_ens_queue *q;
    size_t i, got = 0;
    (void)state;

    memset(&s, 0, sizeof s);
    assert_ok(dfle_ens_queue_new(100, 0, 0, NULL, 0, &s.q, &err), &err);
    for (int k = 0; k < 4; k++)
        assert_int_equal(pthread_create(&t[k], NULL, drain, &s), 0);
    for (int k = 0; k < 4; k++)
        pthread_join(t[k], NULL);
    for (size_t k = 1; k <= 100; k++)
        assert_int_equal(s.count[k], 1);
    dfle_ens_queue_free(s.q);

    assert_ok(dfle_ens_queue_new(100, 2, 4, NULL, 5, &q, &err), &err);
    assert_int_equal(dfle_ens_queue_total(q), 5);
    while (dfle_ens_queue_next(q, &i))
        got++;
    assert_int_equal(got, 5);
    dfle_ens_queue_free(q);

    /* An index given back (its worker lost) comes out again, first, and
     * counts once within the limit. */
    assert_ok(dfle_ens_queue_new(10, 0, 0, NULL, 4, &q, &err), &err);
    assert_true(dfle_ens_queue_next(q, &i) && i == 1);
    assert_true(dfle_ens_queue_next(q, &i) && i == 2);
    assert_ok(dfle_ens_queue_give_back(q, 1, &err), &err);
    assert_true(dfle_ens_queue_next(q, &i) && i == 1);
    assert_true(dfle_ens_queue_next(q, &i) && i == 3);
    assert_true(dfle_ens_queue_next(q, &i) && i == 4);
    assert_false(dfle_ens_queue_next(q, &i));
    assert_ok(dfle_ens_queue_give_back(q, 4, &err), &err);
    assert_true(dfle_ens_queue_next(q, &i) && i == 4);
    assert_false(dfle_ens_queue_next(q, &i));
    dfle_ens_queue_free(q);
    assert_int_equal(dfle_ens_queue_new(10, 5, 4, NULL, 0, &q, &err), DFLE_EINVAL);
}

static void test_malformed_files(void **state)
{
    char p[128];
    dfle_ens_table *t;
    dfle_error err;
    FILE *fp;
    (void)state;

    path(p, sizeof p, "bad.csv");
    fp = fopen(p, "wb");
    fputs(META "\n" HEADER "\n1,a\nx,b\n", fp);
    fclose(fp);
    assert_int_equal(dfle_ens_table_read(p, &t, &err), DFLE_EINVAL);
    assert_non_null(strstr(err.msg, ":4:"));
    fp = fopen(p, "wb");
    fputs(META "\n" HEADER "\n1,a\n1,b\n", fp);
    fclose(fp);
    assert_int_equal(dfle_ens_table_read(p, &t, &err), DFLE_EINVAL);
    assert_non_null(strstr(err.msg, "appears twice"));
    fp = fopen(p, "wb");
    fputs("a,b\n", fp);
    fclose(fp);
    assert_int_equal(dfle_ens_table_read(p, &t, &err), DFLE_EINVAL);
    path(p, sizeof p, "missing.csv");
    assert_int_equal(dfle_ens_table_read(p, &t, &err), DFLE_EIO);
}

/* Two runs with one `out` once interleaved their rows (duplicates, a
 * torn line): the second must stop at once, saying why, and the first
 * must write on unharmed.  A device as `out` must be refused, never read
 * without end (a zero device) nor written into (a full one): nodes made
 * here, never /dev's own (an earlier bug replaced /dev/null). */
static void test_one_writer_per_file(void **state)
{
    char p[128], r[64];
    dfle_ens_file *a, *b = NULL;
    dfle_error err;
    (void)state;
    path(p, sizeof p, "locked.csv");
    assert_ok(dfle_ens_file_open(p, META, NULL, HEADER, 6, 1, &a, &err), &err);
    row(r, sizeof r, 1);
    assert_ok(dfle_ens_file_append(a, 1, r, &err), &err);
    assert_int_equal(dfle_ens_file_open(p, META, NULL, HEADER, 6, 1, &b, &err), DFLE_EIO);
    assert_null(b);
    assert_msg_contains(err.msg, "being written by another run");
    row(r, sizeof r, 2);
    assert_ok(dfle_ens_file_append(a, 2, r, &err), &err);
    assert_ok(dfle_ens_file_close(a, 0, &err), &err);
    /* Once the first has finished, the file is free again and resumes. */
    assert_ok(dfle_ens_file_open(p, META, NULL, HEADER, 6, 1, &b, &err), &err);
    assert_int_equal(dfle_ens_file_ndone(b), 2);
    assert_ok(dfle_ens_file_close(b, 0, &err), &err);
    for (int k = 0; k < 3; k++) {
        char dev[128];
        dfle_ens_table *t;
        path(dev, sizeof dev, k == 0 ? "fifo" : k == 1 ? "zero" : "full");
        if (k == 0)
            assert_int_equal(mkfifo(dev, 0600), 0);
        else if (mknod(dev, S_IFCHR | 0600, makedev(1, k == 1 ? 5 : 7)) != 0)
            continue; /* not root: the FIFO alone */
        assert_int_equal(dfle_ens_file_open(dev, META, NULL, HEADER, 6, 1, &b, &err), DFLE_EINVAL);
        assert_msg_contains(err.msg, "regular file");
        assert_int_equal(dfle_ens_table_read(dev, &t, &err), DFLE_EIO);
        assert_msg_contains(err.msg, "not a regular file");
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stream_sort_resume),
        cmocka_unit_test(test_comment_lines),
        cmocka_unit_test(test_gather_shards),
        cmocka_unit_test(test_queue_threads_limit),
        cmocka_unit_test(test_malformed_files),
        cmocka_unit_test(test_one_writer_per_file),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
