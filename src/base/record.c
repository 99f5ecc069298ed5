/*
 * record.c - the provenance of an output (dfle/record.h): entries in
 * sections, written as CSV comment lines, as a JSON run record, and the
 * CSV table writer that puts them above its data.
 *
 * Entries live in one array in the order they were added, each tagged
 * with its section; writers walk the sections in order and pick their
 * entries, so a section continued later still reads as one.  Records
 * are small (tens of entries), so lookups are linear.
 *
 * JSON is written by hand rather than through a library: the format
 * needs strings escaped, numbers that read back exactly and no NaN, which
 * fits in a page, and every user of the C library would otherwise need
 * one more package.
 */
#include "dfle/record.h"

#include "dfle/file.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef DFLE_VERSION
#define DFLE_VERSION "unknown"
#endif

enum { T_NUMBER, T_BOOL, T_TEXT, T_LIST };

typedef struct entry {
    int section; /* -1: top level */
    int param;   /* a component's option */
    int type;
    char *key, *unit, *text; /* text: T_TEXT */
    double num;              /* T_NUMBER, T_BOOL */
    char **items;            /* T_LIST */
    size_t nitems;
} entry;

typedef struct section {
    char *name, *kind;
} section;

struct dfle_record {
    entry *e;
    size_t n, cap;
    section *s;
    size_t ns, scap;
    int current; /* section entries go to; -1 top level */
    int failed;  /* an allocation failed */
};

static char *dup_str(const char *s)
{
    size_t len;
    char *d;
    if (s == NULL)
        return NULL;
    len = strlen(s);
    if ((d = malloc(len + 1)) != NULL)
        memcpy(d, s, len + 1);
    return d;
}

static void entry_clear(entry *e)
{
    free(e->key);
    free(e->unit);
    free(e->text);
    for (size_t i = 0; i < e->nitems; i++)
        free(e->items[i]);
    free(e->items);
    memset(e, 0, sizeof *e);
}

int dfle_record_new(dfle_record **out, dfle_error *err)
{
    if ((*out = calloc(1, sizeof **out)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "record: out of memory");
    (*out)->current = -1;
    return DFLE_OK;
}

void dfle_record_free(dfle_record *r)
{
    if (r == NULL)
        return;
    for (size_t i = 0; i < r->n; i++)
        entry_clear(&r->e[i]);
    for (size_t i = 0; i < r->ns; i++) {
        free(r->s[i].name);
        free(r->s[i].kind);
    }
    free(r->e);
    free(r->s);
    free(r);
}

void dfle_record_section(dfle_record *r, const char *name, const char *kind)
{
    size_t i;
    if (r == NULL)
        return;
    if (name == NULL) {
        r->current = -1;
        return;
    }
    for (i = 0; i < r->ns && strcmp(r->s[i].name, name) != 0; i++)
        ;
    if (i == r->ns) {
        if (r->ns == r->scap) {
            size_t cap = r->scap ? 2 * r->scap : 8;
            section *s = realloc(r->s, cap * sizeof *s);
            if (s == NULL) {
                r->failed = 1;
                return;
            }
            r->s = s;
            r->scap = cap;
        }
        r->s[i].kind = NULL;
        if ((r->s[i].name = dup_str(name)) == NULL) {
            r->failed = 1;
            return;
        }
        r->ns++;
    }
    if (kind != NULL) {
        char *k = dup_str(kind);
        if (k == NULL) {
            r->failed = 1;
            return;
        }
        free(r->s[i].kind);
        r->s[i].kind = k;
    }
    r->current = (int)i;
}

int dfle_record_has_section(const dfle_record *r, const char *name)
{
    for (size_t i = 0; r != NULL && name != NULL && i < r->ns; i++)
        if (strcmp(r->s[i].name, name) == 0)
            return 1;
    return 0;
}

/* The entry `key` of the current section, new or emptied for reuse. */
static entry *slot(dfle_record *r, const char *key, int param)
{
    entry *e = NULL;
    if (r == NULL || key == NULL)
        return NULL;
    for (size_t i = 0; i < r->n && e == NULL; i++)
        if (r->e[i].section == r->current && r->e[i].param == param &&
            strcmp(r->e[i].key, key) == 0)
            e = &r->e[i];
    if (e != NULL) {
        char *k = e->key;
        e->key = NULL;
        entry_clear(e);
        e->key = k;
    } else {
        if (r->n == r->cap) {
            size_t cap = r->cap ? 2 * r->cap : 32;
            entry *ne = realloc(r->e, cap * sizeof *ne);
            if (ne == NULL) {
                r->failed = 1;
                return NULL;
            }
            r->e = ne;
            r->cap = cap;
        }
        e = &r->e[r->n];
        memset(e, 0, sizeof *e);
        if ((e->key = dup_str(key)) == NULL) {
            r->failed = 1;
            return NULL;
        }
        r->n++;
    }
    e->section = r->current;
    e->param = param;
    return e;
}

static void add_number(dfle_record *r, const char *key, double v, const char *unit, int param,
                       int type)
{
    entry *e = slot(r, key, param);
    if (e == NULL)
        return;
    e->type = type;
    e->num = v;
    if (unit != NULL && unit[0] != '\0' && (e->unit = dup_str(unit)) == NULL)
        r->failed = 1;
}

static void add_text(dfle_record *r, const char *key, const char *text, int param)
{
    entry *e;
    if (text == NULL) {
        /* Removal: the entry goes, the order of the others stays. */
        for (size_t i = 0; r != NULL && key != NULL && i < r->n; i++)
            if (r->e[i].section == r->current && r->e[i].param == param &&
                strcmp(r->e[i].key, key) == 0) {
                entry_clear(&r->e[i]);
                memmove(&r->e[i], &r->e[i + 1], (r->n - i - 1) * sizeof *r->e);
                r->n--;
                break;
            }
        return;
    }
    if ((e = slot(r, key, param)) == NULL)
        return;
    e->type = T_TEXT;
    if ((e->text = dup_str(text)) == NULL)
        r->failed = 1;
}

void dfle_record_number(dfle_record *r, const char *key, double v, const char *unit)
{
    add_number(r, key, v, unit, 0, T_NUMBER);
}

void dfle_record_bool(dfle_record *r, const char *key, int v)
{
    add_number(r, key, v != 0, NULL, 0, T_BOOL);
}

void dfle_record_text(dfle_record *r, const char *key, const char *text)
{
    add_text(r, key, text, 0);
}

void dfle_record_param_number(dfle_record *r, const char *key, double v, const char *unit)
{
    add_number(r, key, v, unit, 1, T_NUMBER);
}

void dfle_record_param_bool(dfle_record *r, const char *key, int v)
{
    add_number(r, key, v != 0, NULL, 1, T_BOOL);
}

void dfle_record_param_text(dfle_record *r, const char *key, const char *text)
{
    add_text(r, key, text, 1);
}

void dfle_record_list(dfle_record *r, const char *key, const char *const *items, size_t n)
{
    entry *e = slot(r, key, 0);
    if (e == NULL)
        return;
    e->type = T_LIST;
    if (n > 0 && (e->items = calloc(n, sizeof *e->items)) == NULL) {
        r->failed = 1;
        return;
    }
    for (size_t i = 0; i < n; i++) {
        if ((e->items[i] = dup_str(items[i] != NULL ? items[i] : "")) == NULL) {
            r->failed = 1;
            return;
        }
        e->nitems++;
    }
}

void dfle_record_params(dfle_record *r, const dfle_param *p, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (p[i].is_switch)
            dfle_record_param_bool(r, p[i].name, p[i].value != 0);
        else
            dfle_record_param_number(r, p[i].name, p[i].value, p[i].unit);
    }
}

void dfle_record_stamp(dfle_record *r)
{
    const char *sde = getenv("SOURCE_DATE_EPOCH");
    time_t t = time(NULL);
    struct tm tm;
    char buf[40];

    if (sde != NULL && sde[0] != '\0') {
        char *end;
        long long v;
        errno = 0;
        v = strtoll(sde, &end, 10);
        if (errno == 0 && *end == '\0' && v >= 0)
            t = (time_t)v;
    }
    dfle_record_section(r, NULL, NULL);
    dfle_record_text(r, "dfle", DFLE_VERSION);
    if (gmtime_r(&t, &tm) != NULL && strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm) > 0)
        dfle_record_text(r, "date", buf);
}

int dfle_record_status(const dfle_record *r, dfle_error *err)
{
    if (r != NULL && r->failed)
        return dfle_error_set(err, DFLE_ENOMEM, "record: out of memory");
    return DFLE_OK;
}

int dfle_record_each(const dfle_record *r, int (*fn)(void *ud, const dfle_record_entry *e),
                     void *ud)
{
    static const enum dfle_record_type types[] = {
        [T_NUMBER] = DFLE_RECORD_NUMBER, [T_BOOL] = DFLE_RECORD_BOOL,
        [T_TEXT] = DFLE_RECORD_TEXT, [T_LIST] = DFLE_RECORD_LIST};
    if (r == NULL)
        return 0;
    for (int s = -1; s < (int)r->ns; s++) {
        int seen = 0, rc;
        dfle_record_entry v;
        memset(&v, 0, sizeof v);
        if (s >= 0) {
            v.section = r->s[s].name;
            v.kind = r->s[s].kind;
        }
        for (size_t i = 0; i < r->n; i++) {
            const entry *e = &r->e[i];
            if (e->section != s)
                continue;
            seen = 1;
            v.key = e->key;
            v.unit = e->unit;
            v.type = types[e->type];
            v.param = e->param;
            v.num = e->num;
            v.text = e->text;
            v.items = (const char *const *)e->items;
            v.nitems = e->nitems;
            if ((rc = fn(ud, &v)) != 0)
                return rc;
        }
        if (s >= 0 && !seen) {
            v.key = NULL;
            if ((rc = fn(ud, &v)) != 0)
                return rc;
        }
    }
    return 0;
}

/* ---- Numbers and texts ------------------------------------------- */

const char *dfle_number_text(double v, char *buf)
{
    if (isnan(v))
        return strcpy(buf, "nan");
    if (isinf(v))
        return strcpy(buf, v > 0 ? "inf" : "-inf");
    /* 15 digits print most numbers as people wrote them (0.1, not
     * 0.10000000000000001); more only when the shorter text would read
     * back as another double. */
    for (int digits = 15; digits <= 17; digits++) {
        snprintf(buf, 32, "%.*g", digits, v);
        if (strtod(buf, NULL) == v)
            break;
    }
    return buf;
}

/* A text in a comment line: as it is when it is one plain word, else in
 * double quotes (inner quotes doubled); line breaks and tabs become
 * spaces so the comment stays one line. */
static void put_comment_text(FILE *fp, const char *s)
{
    int plain = s[0] != '\0';
    for (const char *p = s; *p != '\0' && plain; p++)
        plain = !(*p == ' ' || *p == ',' || *p == '"' || *p == '=' || *p == '\t' ||
                  *p == '\n' || *p == '\r');
    if (!plain)
        fputc('"', fp);
    for (const char *p = s; *p != '\0'; p++) {
        if (*p == '\n' || *p == '\r' || *p == '\t')
            fputc(' ', fp);
        else if (*p == '"')
            fputs("\"\"", fp);
        else
            fputc(*p, fp);
    }
    if (!plain)
        fputc('"', fp);
}

/* A list item as a shell word: single quotes when it holds anything but
 * letters, digits and -_./:=+,@% (a command line can be pasted back). */
static void put_shell_word(FILE *fp, const char *s)
{
    int plain = s[0] != '\0';
    for (const char *p = s; *p != '\0' && plain; p++)
        plain = (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') ||
                (*p >= '0' && *p <= '9') || strchr("-_./:=+,@%", *p) != NULL;
    if (plain) {
        fputs(s, fp);
        return;
    }
    fputc('\'', fp);
    for (const char *p = s; *p != '\0'; p++) {
        if (*p == '\'')
            fputs("'\\''", fp);
        else if (*p == '\n' || *p == '\r')
            fputc(' ', fp);
        else
            fputc(*p, fp);
    }
    fputc('\'', fp);
}

static void put_comment_value(FILE *fp, const entry *e)
{
    char buf[32];
    switch (e->type) {
    case T_NUMBER:
        fputs(dfle_number_text(e->num, buf), fp);
        if (e->unit != NULL)
            fprintf(fp, " %s", e->unit);
        break;
    case T_BOOL:
        fputs(e->num != 0 ? "true" : "false", fp);
        break;
    case T_TEXT:
        put_comment_text(fp, e->text);
        break;
    default:
        for (size_t i = 0; i < e->nitems; i++) {
            if (i > 0)
                fputc(' ', fp);
            put_shell_word(fp, e->items[i]);
        }
    }
}

/* A key or a name in a comment line: line breaks would end the comment. */
static void put_comment_name(FILE *fp, const char *s)
{
    for (; *s != '\0'; s++)
        fputc(*s == '\n' || *s == '\r' ? ' ' : *s, fp);
}

void dfle_record_write_comments(const dfle_record *r, FILE *fp)
{
    if (r == NULL)
        return;
    for (size_t i = 0; i < r->n; i++) {
        if (r->e[i].section != -1)
            continue;
        fputs("# ", fp);
        put_comment_name(fp, r->e[i].key);
        fputs(": ", fp);
        put_comment_value(fp, &r->e[i]);
        fputc('\n', fp);
    }
    for (size_t k = 0; k < r->ns; k++) {
        int first = 1;
        fputs("# ", fp);
        put_comment_name(fp, r->s[k].name);
        if (r->s[k].kind != NULL) {
            fputc(' ', fp);
            put_comment_name(fp, r->s[k].kind);
        }
        for (size_t i = 0; i < r->n; i++) {
            if (r->e[i].section != (int)k)
                continue;
            fputs(first ? ": " : ", ", fp);
            first = 0;
            put_comment_name(fp, r->e[i].key);
            fputc('=', fp);
            put_comment_value(fp, &r->e[i]);
        }
        fputc('\n', fp);
    }
}

/* ---- JSON --------------------------------------------------------- */

/* Length of the valid UTF-8 sequence at s (1-4), or 0 if it is not one
 * (a stray continuation byte, an overlong form, a surrogate, past
 * U+10FFFF, or cut short). */
static size_t utf8_length(const unsigned char *s)
{
    size_t len;
    unsigned long cp;
    if (s[0] < 0x80)
        return 1;
    if (s[0] >= 0xC2 && s[0] <= 0xDF)
        len = 2, cp = s[0] & 0x1F;
    else if (s[0] >= 0xE0 && s[0] <= 0xEF)
        len = 3, cp = s[0] & 0x0F;
    else if (s[0] >= 0xF0 && s[0] <= 0xF4)
        len = 4, cp = s[0] & 0x07;
    else
        return 0;
    for (size_t i = 1; i < len; i++) {
        if ((s[i] & 0xC0) != 0x80)
            return 0; /* also stops at the NUL */
        cp = cp << 6 | (s[i] & 0x3F);
    }
    if ((len == 3 && (cp < 0x800 || (cp >= 0xD800 && cp <= 0xDFFF))) ||
        (len == 4 && (cp < 0x10000 || cp > 0x10FFFF)))
        return 0;
    return len;
}

static void json_string(FILE *fp, const char *s)
{
    const unsigned char *p = (const unsigned char *)s;
    fputc('"', fp);
    while (*p != '\0') {
        size_t len;
        if (*p == '"' || *p == '\\') {
            fputc('\\', fp);
            fputc(*p++, fp);
        } else if (*p < 0x20) {
            static const char short_form[] = "btn\0fr"; /* \b \t \n, \f \r */
            if (*p >= 8 && *p <= 13 && *p != 11)
                fprintf(fp, "\\%c", short_form[*p - 8]);
            else
                fprintf(fp, "\\u%04x", *p);
            p++;
        } else if ((len = utf8_length(p)) > 0) {
            fwrite(p, 1, len, fp);
            p += len;
        } else {
            fputs("\xEF\xBF\xBD", fp); /* U+FFFD for a byte that is not UTF-8 */
            p++;
        }
    }
    fputc('"', fp);
}

static void json_value(FILE *fp, const entry *e)
{
    char buf[32];
    switch (e->type) {
    case T_NUMBER:
        fputs(isfinite(e->num) ? dfle_number_text(e->num, buf) : "null", fp);
        break;
    case T_BOOL:
        fputs(e->num != 0 ? "true" : "false", fp);
        break;
    case T_TEXT:
        json_string(fp, e->text);
        break;
    default:
        fputc('[', fp);
        for (size_t i = 0; i < e->nitems; i++) {
            if (i > 0)
                fputs(", ", fp);
            json_string(fp, e->items[i]);
        }
        fputc(']', fp);
    }
}

/* Members "key": value of section k (-1: top level) whose param flag is
 * `param` (-1: any) and, for units, that have a unit; one a line at
 * `indent`.  *first says whether a comma is due. */
static void json_members(FILE *fp, const dfle_record *r, int k, int param, int units,
                         const char *indent, int *first)
{
    for (size_t i = 0; i < r->n; i++) {
        const entry *e = &r->e[i];
        int seen = 0;
        if (e->section != k || (param >= 0 && e->param != param) || (units && e->unit == NULL))
            continue;
        /* A parameter and a value of the same name share one unit entry. */
        for (size_t j = 0; units && j < i && !seen; j++)
            seen = r->e[j].section == k && r->e[j].unit != NULL && strcmp(r->e[j].key, e->key) == 0;
        if (seen)
            continue;
        fprintf(fp, "%s\n%s", *first ? "" : ",", indent);
        *first = 0;
        json_string(fp, e->key);
        fputs(": ", fp);
        if (units)
            json_string(fp, e->unit);
        else
            json_value(fp, e);
    }
}

/* A nested object "name": { members } when it has any. */
static void json_group(FILE *fp, const dfle_record *r, int k, const char *name, int param,
                       int units, const char *indent, const char *inner, int *first)
{
    int inner_first = 1, any = 0;
    for (size_t i = 0; i < r->n && !any; i++)
        any = r->e[i].section == k && (param < 0 || r->e[i].param == param) &&
              (!units || r->e[i].unit != NULL);
    if (!any)
        return;
    fprintf(fp, "%s\n%s\"%s\": {", *first ? "" : ",", indent, name);
    *first = 0;
    json_members(fp, r, k, param, units, inner, &inner_first);
    fprintf(fp, "\n%s}", indent);
}

int dfle_record_write_json(const dfle_record *r, const char *path, dfle_error *err)
{
    dfle_file out;
    int st, first = 1;

    if ((st = dfle_record_status(r, err)) != DFLE_OK)
        return st;
    if ((st = dfle_file_begin(&out, path, "record", err)) != DFLE_OK)
        return st;
    fputc('{', out.fp);
    json_members(out.fp, r, -1, -1, 0, "  ", &first);
    json_group(out.fp, r, -1, "units", -1, 1, "  ", "    ", &first);
    for (size_t k = 0; k < r->ns; k++) {
        int inner = 1;
        fprintf(out.fp, "%s\n  ", first ? "" : ",");
        first = 0;
        json_string(out.fp, r->s[k].name);
        fputs(": {", out.fp);
        if (r->s[k].kind != NULL) {
            fputs("\n    \"kind\": ", out.fp);
            json_string(out.fp, r->s[k].kind);
            inner = 0;
        }
        json_members(out.fp, r, (int)k, 0, 0, "    ", &inner);
        json_group(out.fp, r, (int)k, "params", 1, 0, "    ", "      ", &inner);
        json_group(out.fp, r, (int)k, "units", -1, 1, "    ", "      ", &inner);
        fputs(inner ? "}" : "\n  }", out.fp);
    }
    fputs(first ? "}\n" : "\n}\n", out.fp);
    return dfle_file_commit(&out, err);
}

/* ---- Tables ------------------------------------------------------- */

char *dfle_units_line(const char *const *names, const char *const *units, size_t n)
{
    static const char head[] = "# units: ";
    size_t len = sizeof head, used;
    char *line;
    int any = 0;

    for (size_t i = 0; i < n; i++)
        if (units[i] != NULL && units[i][0] != '\0') {
            len += strlen(names[i]) + strlen(units[i]) + 3;
            any = 1;
        }
    if (!any || (line = malloc(len)) == NULL)
        return NULL;
    memcpy(line, head, sizeof head);
    used = sizeof head - 1;
    for (size_t i = 0; i < n; i++)
        if (units[i] != NULL && units[i][0] != '\0')
            used += (size_t)snprintf(line + used, len - used, "%s%s=%s",
                                     used > sizeof head - 1 ? ", " : "", names[i], units[i]);
    return line;
}

/* A column name must survive the header and the units line. */
static int bad_name(const char *s)
{
    return s == NULL || s[0] == '\0' || s[0] == '#' || strpbrk(s, ",\"=\r\n") != NULL;
}

static void put_csv_text(FILE *fp, const char *s)
{
    size_t len = strlen(s);
    int quote = len > 0 && (s[0] == ' ' || s[0] == '\t' || s[len - 1] == ' ' ||
                            s[len - 1] == '\t' || strpbrk(s, ",\"\r\n#") != NULL);
    if (!quote) {
        fputs(s, fp);
        return;
    }
    fputc('"', fp);
    for (; *s != '\0'; s++) {
        if (*s == '"')
            fputc('"', fp);
        fputc(*s, fp);
    }
    fputc('"', fp);
}

int dfle_table_write(const char *path, const char *who, const dfle_record *rec,
                     const dfle_column *cols, size_t ncols, size_t nrows, int digits,
                     dfle_error *err)
{
    const char **names, **units;
    char *line;
    dfle_file out;
    int st;

    if ((st = dfle_record_status(rec, err)) != DFLE_OK)
        return st;
    if (ncols == 0)
        return dfle_error_set(err, DFLE_EINVAL, "%s: a table needs at least one column", who);
    for (size_t j = 0; j < ncols; j++)
        if (bad_name(cols[j].name) || (cols[j].unit != NULL && strpbrk(cols[j].unit, ",=\r\n")))
            return dfle_error_set(err, DFLE_EINVAL, "%s: column %zu: '%s'%s%s cannot go into a "
                                  "CSV header (empty, or a comma, quote, '=', '#' or line break)",
                                  who, j + 1, cols[j].name != NULL ? cols[j].name : "(null)",
                                  cols[j].unit != NULL ? " with unit " : "",
                                  cols[j].unit != NULL ? cols[j].unit : "");
    names = malloc(2 * ncols * sizeof *names);
    if (names == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "%s: out of memory", who);
    units = names + ncols;
    for (size_t j = 0; j < ncols; j++) {
        names[j] = cols[j].name;
        units[j] = cols[j].unit;
    }
    line = dfle_units_line(names, units, ncols);
    free(names);
    if ((st = dfle_file_begin(&out, path, who, err)) != DFLE_OK) {
        free(line);
        return st;
    }
    dfle_record_write_comments(rec, out.fp);
    if (line != NULL)
        fprintf(out.fp, "%s\n", line);
    free(line);
    for (size_t j = 0; j < ncols; j++)
        fprintf(out.fp, "%s%s", j ? "," : "", cols[j].name);
    fputc('\n', out.fp);
    for (size_t i = 0; i < nrows; i++) {
        for (size_t j = 0; j < ncols; j++) {
            char buf[40];
            if (j > 0)
                fputc(',', out.fp);
            if (cols[j].num == NULL) {
                if (cols[j].text != NULL && cols[j].text[i] != NULL)
                    put_csv_text(out.fp, cols[j].text[i]);
            } else if (digits > 0 && isfinite(cols[j].num[i])) {
                fprintf(out.fp, "%.*g", digits, cols[j].num[i]);
            } else {
                fputs(dfle_number_text(cols[j].num[i], buf), out.fp);
            }
        }
        fputc('\n', out.fp);
    }
    return dfle_file_commit(&out, err);
}
