/*
 * record_flat.c - a record (record.h) for stores of name = value: the
 * names of its entries as NetCDF global attributes and GDAL metadata
 * items take them, CF's history line, a list as one line of text, and
 * dfle's units in the syntax UDUNITS reads (the `units` of CF).
 *
 * Only the public walk (dfle_record_each) is used: these read a record
 * the way any writer of a format would.
 */
#include "dfle/record.h"

#include <ctype.h>
#include <stdio.h>
#include <string.h>

static void flat_part(char *out, size_t cap, size_t *k, const char *s)
{
    for (; *s != '\0' && *k + 1 < cap; s++) {
        unsigned char c = (unsigned char)*s;
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                 strchr("_.-+@", c) != NULL;
        out[(*k)++] = ok ? (char)c : '_';
    }
}

void dfle_record_flat_name(const dfle_record_entry *e, char *out, size_t cap)
{
    size_t k = 0;
    if (cap == 0)
        return;
    if (e->section == NULL) {
        const char *key = e->key != NULL ? e->key : "";
        if (strcmp(key, "dfle") == 0)
            key = "dfle_version";
        else if (strcmp(key, "date") == 0)
            key = "date_created";
        else if (strcmp(key, "about") == 0)
            key = "comment";
        else
            flat_part(out, cap, &k, "dfle_");
        flat_part(out, cap, &k, key);
    } else {
        flat_part(out, cap, &k, e->section);
        if (e->key != NULL) {
            flat_part(out, cap, &k, "_");
            flat_part(out, cap, &k, e->key);
        }
    }
    out[k] = '\0';
    if (!((out[0] >= 'a' && out[0] <= 'z') || (out[0] >= 'A' && out[0] <= 'Z'))) {
        /* "x_" first: a name of "_..." or "1..." is reserved or invalid. */
        size_t len = strlen(out), keep = len + 3 <= cap ? len : (cap > 3 ? cap - 3 : 0);
        memmove(out + 2, out, keep);
        out[0] = 'x';
        out[1] = '_';
        out[keep + 2 < cap ? keep + 2 : cap - 1] = '\0';
    }
}

/* A list as one text: items apart by blanks, a shell's quotes around an
 * item that needs them (the command line reads back as typed). */
void dfle_record_join(const char *const *items, size_t n, char *out, size_t cap)
{
    size_t k = 0;
    if (cap == 0)
        return;
    out[0] = '\0';
    for (size_t i = 0; i < n && k + 1 < cap; i++) {
        const char *it = items[i];
        int quote = it[0] == '\0' || strpbrk(it, " \t\n'\"$`\\|&;<>()*?[]#~") != NULL;
        if (i > 0)
            out[k++] = ' ';
        if (quote && k + 1 < cap)
            out[k++] = '\'';
        for (; *it != '\0' && k + 5 < cap; it++) {
            if (*it == '\'' && quote) {
                memcpy(out + k, "'\\''", 4);
                k += 4;
            } else {
                out[k++] = *it;
            }
        }
        if (quote && k + 1 < cap)
            out[k++] = '\'';
        out[k] = '\0';
    }
}

typedef struct history_ctx {
    const char *date;
    char command[4096];
} history_ctx;

static int find_history(void *ud, const dfle_record_entry *e)
{
    history_ctx *h = ud;
    if (e->section != NULL || e->key == NULL)
        return 0;
    if (strcmp(e->key, "date") == 0 && e->type == DFLE_RECORD_TEXT)
        h->date = e->text;
    else if (strcmp(e->key, "command") == 0 && e->type == DFLE_RECORD_LIST)
        dfle_record_join(e->items, e->nitems, h->command, sizeof h->command);
    return 0;
}

int dfle_record_history(const dfle_record *r, char *buf, size_t cap)
{
    history_ctx h;
    memset(&h, 0, sizeof h);
    dfle_record_each(r, find_history, &h);
    if (h.date == NULL && h.command[0] == '\0')
        return 0;
    snprintf(buf, cap, "%s: %s", h.date != NULL ? h.date : "(unknown time)",
             h.command[0] != '\0' ? h.command : "dfle");
    return 1;
}


int dfle_units_udunits(const char *u, char *buf, size_t cap)
{
    size_t k = 0;
    const char *p = u;
#define PUT(ch)                                                                              \
    do {                                                                                     \
        if (k + 1 >= cap)                                                                    \
            return 0;                                                                        \
        buf[k++] = (ch);                                                                     \
    } while (0)
    if (u == NULL)
        return 0;
    if (u[0] == '\0' || strcmp(u, "-") == 0 || strcmp(u, "1") == 0) {
        snprintf(buf, cap, "1");
        return cap > 1;
    }
    while (*p != '\0') {
        if (isalpha((unsigned char)*p) || *p == '_') {
            while (isalpha((unsigned char)*p) || *p == '_')
                PUT(*p++);
            if (*p == '^')
                p++;
            else if (!(isdigit((unsigned char)*p) || *p == '-'))
                continue; /* no exponent */
            if (*p == '-' || *p == '+') {
                if (*p == '-')
                    PUT('-');
                p++;
            }
            if (!isdigit((unsigned char)*p))
                return 0; /* "m^(1-2 m)": symbolic */
            while (isdigit((unsigned char)*p))
                PUT(*p++);
            if ((*p == '.' || *p == '/') && isdigit((unsigned char)p[1]))
                return 0; /* "m^2.5", "m^-1/3": fractional */
        } else if (*p == ' ' || *p == '*') {
            if (k > 0 && buf[k - 1] != ' ')
                PUT(' ');
            p++;
        } else if (*p == '/') {
            if (k > 0 && buf[k - 1] == ' ')
                k--;
            PUT('/');
            p++;
            while (*p == ' ')
                p++;
        } else if (*p == '1' && (p == u || p[-1] == ' ') && (p[1] == '/' || p[1] == '\0')) {
            PUT(*p++); /* "1/yr" */
        } else {
            return 0;
        }
    }
#undef PUT
    while (k > 0 && buf[k - 1] == ' ')
        k--;
    buf[k] = '\0';
    return k > 0;
}

