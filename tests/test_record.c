/* test_record.c - provenance records (record.h): comment lines, JSON,
 * numbers that read back, and the CSV table writer, read back by
 * dfle's own CSV reader. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "dfle_test.h"
#include "dfle/csv.h"
#include "dfle/file.h"
#include "dfle/record.h"

static char *tmp_path(const char *suffix)
{
    static int k;
    char *p = malloc(128);
    snprintf(p, 128, "/tmp/outputs-test-record-%ld-%d%s", (long)getpid(), k++, suffix);
    return p;
}

static char *read_text(const char *path)
{
    char *text;
    size_t len;
    dfle_error err;
    assert_ok(dfle_file_read_all(path, 1 << 20, &text, &len, &err), &err);
    return text;
}

static char *comments_of(const dfle_record *r)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *fp = open_memstream(&buf, &len);
    assert_non_null(fp);
    dfle_record_write_comments(r, fp);
    fclose(fp);
    return buf;
}

/* A record with every kind of entry, sections continued and replaced. */
static dfle_record *sample_record(void)
{
    dfle_record *r;
    dfle_error err;
    const char *cmd[] = {"dfle", "my run.lua", "--quick"};
    const dfle_param p[] = {{"M0", 3000, "m^3", 0}, {"gamma", 0.5, "", 0}, {"scaled", 1, "", 1}};
    assert_ok(dfle_record_new(&r, &err), &err);
    dfle_record_text(r, "dfle", "9.9");
    dfle_record_list(r, "command", cmd, 3);
    dfle_record_section(r, "router", "empirical");
    dfle_record_params(r, p, 3);
    dfle_record_section(r, "run", NULL);
    dfle_record_text(r, "reason", "steady");
    dfle_record_number(r, "time", 2.5e6, "yr");
    dfle_record_bool(r, "converged", 1);
    dfle_record_text(r, "note", "a \"quoted\", long\nnote");
    dfle_record_number(r, "rate", NAN, NULL);
    dfle_record_section(r, "router", NULL); /* continued: same section */
    dfle_record_number(r, "n", 403, NULL);
    dfle_record_param_number(r, "gamma", 0.25, ""); /* replaced in place */
    dfle_record_section(r, "fluvial", "off"); /* a section with no entries */
    assert_ok(dfle_record_status(r, &err), &err);
    return r;
}

static void comment_lines(void **state)
{
    dfle_record *r = sample_record();
    char *text = comments_of(r);
    (void)state;
    assert_string_equal(text,
                        "# dfle: 9.9\n"
                        "# command: dfle 'my run.lua' --quick\n"
                        "# router empirical: M0=3000 m^3, gamma=0.25, scaled=true, n=403\n"
                        "# run: reason=steady, time=2500000 yr, converged=true, "
                        "note=\"a \"\"quoted\"\", long note\", rate=nan\n"
                        "# fluvial off\n");
    free(text);
    /* A removed entry is gone; the others keep their order. */
    dfle_record_section(r, NULL, NULL);
    dfle_record_text(r, "command", NULL);
    dfle_record_text(r, "date", "today");
    text = comments_of(r);
    assert_non_null(strstr(text, "# dfle: 9.9\n# date: today\n# router"));
    free(text);
    dfle_record_free(r);
}

static void json_record(void **state)
{
    dfle_record *r = sample_record();
    dfle_error err;
    char *path = tmp_path(".json"), *text;
    (void)state;
    dfle_record_section(r, NULL, NULL);
    dfle_record_text(r, "odd", "tab\there \\ \x01 caf\xC3\xA9 bad\xFF end");
    assert_ok(dfle_record_write_json(r, path, &err), &err);
    text = read_text(path);
    assert_string_equal(text,
                        "{\n"
                        "  \"dfle\": \"9.9\",\n"
                        "  \"command\": [\"dfle\", \"my run.lua\", \"--quick\"],\n"
                        "  \"odd\": \"tab\\there \\\\ \\u0001 caf\xC3\xA9 bad\xEF\xBF\xBD end\",\n"
                        "  \"router\": {\n"
                        "    \"kind\": \"empirical\",\n"
                        "    \"n\": 403,\n"
                        "    \"params\": {\n"
                        "      \"M0\": 3000,\n"
                        "      \"gamma\": 0.25,\n"
                        "      \"scaled\": true\n"
                        "    },\n"
                        "    \"units\": {\n"
                        "      \"M0\": \"m^3\"\n"
                        "    }\n"
                        "  },\n"
                        "  \"run\": {\n"
                        "    \"reason\": \"steady\",\n"
                        "    \"time\": 2500000,\n"
                        "    \"converged\": true,\n"
                        "    \"note\": \"a \\\"quoted\\\", long\\nnote\",\n"
                        "    \"rate\": null,\n"
                        "    \"units\": {\n"
                        "      \"time\": \"yr\"\n"
                        "    }\n"
                        "  },\n"
                        "  \"fluvial\": {\n"
                        "    \"kind\": \"off\"\n"
                        "  }\n"
                        "}\n");
    free(text);
    unlink(path);
    free(path);
    dfle_record_free(r);
}

static void empty_record_is_an_empty_object(void **state)
{
    dfle_record *r;
    dfle_error err;
    char *path = tmp_path(".json"), *text;
    (void)state;
    assert_ok(dfle_record_new(&r, &err), &err);
    dfle_record_section(r, "empty", NULL);
    assert_ok(dfle_record_write_json(r, path, &err), &err);
    text = read_text(path);
    assert_string_equal(text, "{\n  \"empty\": {}\n}\n");
    free(text);
    unlink(path);
    free(path);
    dfle_record_free(r);
}

static void numbers_read_back(void **state)
{
    char buf[32];
    const double v[] = {0.1, 1.0 / 3.0, 403, 5e-4, 1e300, -2.5e-310, 2.4539238302491e-10,
                        0.30000000000000004};
    (void)state;
    assert_string_equal(dfle_number_text(0.1, buf), "0.1");
    assert_string_equal(dfle_number_text(403, buf), "403");
    assert_string_equal(dfle_number_text(5e-4, buf), "0.0005");
    assert_string_equal(dfle_number_text(NAN, buf), "nan");
    assert_string_equal(dfle_number_text(-INFINITY, buf), "-inf");
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++) {
        dfle_number_text(v[i], buf);
        assert_true(strtod(buf, NULL) == v[i]);
    }
    assert_string_equal(dfle_number_text(1.0 / 3.0, buf), "0.3333333333333333");
}

static void stamp_takes_source_date_epoch(void **state)
{
    dfle_record *r;
    dfle_error err;
    char *text;
    (void)state;
    setenv("SOURCE_DATE_EPOCH", "86461", 1);
    assert_ok(dfle_record_new(&r, &err), &err);
    dfle_record_stamp(r);
    text = comments_of(r);
    assert_non_null(strstr(text, "# date: 1970-01-02T00:01:01Z\n"));
    assert_true(strncmp(text, "# dfle: ", 8) == 0);
    free(text);
    unsetenv("SOURCE_DATE_EPOCH");
    dfle_record_stamp(r); /* now: a date of this century */
    text = comments_of(r);
    assert_non_null(strstr(text, "# date: 20"));
    free(text);
    dfle_record_free(r);
}

/* The table: comments, units, plain names; dfle's reader reads it back. */
static void table_reads_back(void **state)
{
    dfle_record *r;
    dfle_error err;
    dfle_csv *csv;
    const double *col;
    char *path = tmp_path(".csv"), *text;
    const double A[3] = {1000, 2.5e4, 1.0 / 3.0}, S[3] = {0.5, NAN, INFINITY};
    const char *label[3] = {"plain", "a, b", NULL};
    const dfle_column cols[] = {
        {"A", "m^2", A, NULL}, {"S", "-", S, NULL}, {"label", NULL, NULL, label}};
    (void)state;
    assert_ok(dfle_record_new(&r, &err), &err);
    dfle_record_text(r, "about", "a test table");
    assert_ok(dfle_table_write(path, "test", r, cols, 3, 3, 0, &err), &err);
    text = read_text(path);
    assert_string_equal(text, "# about: \"a test table\"\n"
                              "# units: A=m^2, S=-\n"
                              "A,S,label\n"
                              "1000,0.5,plain\n"
                              "25000,nan,\"a, b\"\n"
                              "0.3333333333333333,inf,\n");
    free(text);
    assert_ok(dfle_csv_read(path, &csv, &err), &err);
    assert_int_equal(csv->ncols, 3);
    assert_int_equal(csv->nrows, 3);
    assert_ok(dfle_csv_column(csv, "A", &col, &err), &err);
    assert_true(col[2] == 1.0 / 3.0);
    assert_ok(dfle_csv_column(csv, "S", &col, &err), &err);
    assert_true(isnan(col[1]) && isinf(col[2]));
    dfle_csv_free(csv);
    /* digits > 0: that many significant digits */
    assert_ok(dfle_table_write(path, "test", NULL, cols, 2, 3, 4, &err), &err);
    text = read_text(path);
    assert_string_equal(text, "# units: A=m^2, S=-\nA,S\n1000,0.5\n2.5e+04,nan\n0.3333,inf\n");
    free(text);
    unlink(path);
    free(path);
    dfle_record_free(r);
}

static void table_refuses_bad_names(void **state)
{
    dfle_error err;
    const double v[1] = {1};
    const dfle_column bad[] = {{"a,b", NULL, v, NULL}};
    const dfle_column bad_unit[] = {{"a", "m=2", v, NULL}};
    const dfle_column hash[] = {{"#a", NULL, v, NULL}};
    (void)state;
    assert_int_equal(dfle_table_write("/tmp/outputs-never", "t", NULL, bad, 1, 1, 0, &err),
                     DFLE_EINVAL);
    assert_msg_contains(err.msg, "a,b");
    assert_int_equal(dfle_table_write("/tmp/outputs-never", "t", NULL, bad_unit, 1, 1, 0, &err),
                     DFLE_EINVAL);
    assert_int_equal(dfle_table_write("/tmp/outputs-never", "t", NULL, hash, 1, 1, 0, &err),
                     DFLE_EINVAL);
    assert_int_equal(access("/tmp/outputs-never", F_OK), -1);
    assert_int_equal(dfle_table_write("/nonexistent-dir/x.csv", "t", NULL, hash + 0, 0, 1, 0,
                                      &err), DFLE_EINVAL);
}

static void units_line(void **state)
{
    const char *names[] = {"index", "x", "S", "status"};
    const char *units[] = {NULL, "m", "-", ""};
    char *line = dfle_units_line(names, units, 4);
    (void)state;
    assert_string_equal(line, "# units: x=m, S=-");
    free(line);
    assert_null(dfle_units_line(names, units, 1));
}

/* The walk a writer of a flat store takes, the names it gives, CF's
 * history line, and units in UDUNITS' syntax. */
typedef struct walk {
    char seen[1024];
} walk;

static int visit(void *ud, const dfle_record_entry *e)
{
    walk *w = ud;
    char name[128];
    dfle_record_flat_name(e, name, sizeof name);
    snprintf(w->seen + strlen(w->seen), sizeof w->seen - strlen(w->seen), "%s%s%s", name,
             e->type == DFLE_RECORD_NUMBER && e->key != NULL ? "#" : "", ";");
    return 0;
}

static void flat_walk(void **state)
{
    dfle_record *r;
    dfle_error err;
    walk w = {""};
    char buf[256];
    const char *argv[] = {"dfle", "my run.lua", "it's"};
    (void)state;
    assert_ok(dfle_record_new(&r, &err), &err);
    assert_int_equal(dfle_record_history(r, buf, sizeof buf), 0);
    dfle_record_text(r, "date", "2025-06-01T10:00:00Z");
    dfle_record_list(r, "command", argv, 3);
    dfle_record_section(r, "router", "empirical");
    dfle_record_param_number(r, "M0", 3000, "m^(3-2 gamma)");
    dfle_record_section(r, "off part", "off"); /* a section with nothing in it */
    dfle_record_section(r, "router", NULL);
    dfle_record_param_number(r, "1st", 1, NULL); /* continues "router" */
    dfle_record_section(r, NULL, NULL);
    dfle_record_text(r, "about", "a test");
    assert_int_equal(dfle_record_each(r, visit, &w), 0);
    assert_string_equal(w.seen, "date_created;dfle_command;comment;router_M0#;router_1st#;"
                                "off_part;");
    assert_int_equal(dfle_record_history(r, buf, sizeof buf), 1);
    assert_string_equal(buf, "2025-06-01T10:00:00Z: dfle 'my run.lua' 'it'\\''s'");
    {
        dfle_record_entry e = {.section = NULL, .key = "1"};
        dfle_record_flat_name(&e, buf, sizeof buf);
        assert_string_equal(buf, "dfle_1");
        e.section = "9 lives";
        e.key = "x";
        dfle_record_flat_name(&e, buf, sizeof buf);
        assert_string_equal(buf, "x_9_lives_x");
    }
    dfle_record_free(r);
}

static void udunits_syntax(void **state)
{
    static const char *const ok[][2] = {
        {"m^2", "m2"},       {"-", "1"},         {"", "1"},          {"m/yr", "m/yr"},
        {"kg/m^3", "kg/m3"}, {"m^3/s", "m3/s"},  {"Pa s", "Pa s"},   {"m^-1", "m-1"},
        {"1/yr", "1/yr"},    {"m^2/yr", "m2/yr"}, {"m s^-2", "m s-2"}, {"m2", "m2"}};
    static const char *const no[] = {"m^2.5 s^2 kg^-1.5", "m^(1-2 m_s)/yr", "s m^-1/3",
                                     "m^(3-2 gamma)", "10 m", "m^", NULL};
    char buf[64];
    (void)state;
    for (size_t k = 0; k < sizeof ok / sizeof ok[0]; k++) {
        assert_int_equal(dfle_units_udunits(ok[k][0], buf, sizeof buf), 1);
        assert_string_equal(buf, ok[k][1]);
    }
    for (size_t k = 0; no[k] != NULL; k++)
        assert_int_equal(dfle_units_udunits(no[k], buf, sizeof buf), 0);
    assert_int_equal(dfle_units_udunits(NULL, buf, sizeof buf), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(comment_lines),
        cmocka_unit_test(json_record),
        cmocka_unit_test(empty_record_is_an_empty_object),
        cmocka_unit_test(numbers_read_back),
        cmocka_unit_test(stamp_takes_source_date_epoch),
        cmocka_unit_test(table_reads_back),
        cmocka_unit_test(table_refuses_bad_names),
        cmocka_unit_test(units_line),
        cmocka_unit_test(flat_walk),
        cmocka_unit_test(udunits_syntax),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
