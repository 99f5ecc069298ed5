/*
 * record.h - what produced an output, written with it: the provenance
 * of a result as comment lines at the top of its CSV file and as a JSON
 * run record beside it.
 *
 * A record holds entries (name, value, unit) in order: top-level ones
 * (the dfle version, the date, the command, the script) and named
 * sections ("channel", "router", "run", ...), each with an optional
 * kind (the router's name, "empirical") and its entries.  An entry is a
 * number, a text, a true/false value or a list of texts; in a section it
 * is either a parameter (a component's option, listed under "params" in
 * JSON, so its names never clash with dfle's own) or a plain value.
 *
 * Comment lines ('#' first: pandas comment='#', R comment.char='#',
 * dfle's own CSV reader skip them):
 *
 *     # dfle: 0.1.0
 *     # date: 2025-06-01T10:00:00Z
 *     # command: dfle run.lua --quick out
 *     # router empirical: M0=3000 m^(3-2 gamma), gamma=0.5, tau_y=300 Pa
 *     # units: x=m, A=m^2, S=-
 *     x,A,S
 *
 * The JSON record is one object: the top-level entries as members, each
 * section an object {"kind": ..., <plain values>, "params": {...},
 * "units": {...}}; NaN and infinities are null, texts UTF-8 (invalid
 * bytes become U+FFFD).  Formats in doc/lua-api.md, "Output files".
 *
 * Building never fails midway: an allocation failure is remembered and
 * returned by dfle_record_status and by every writer, so a caller adds
 * entries without checking each one (as SQLite keeps its last error).
 */
#ifndef DFLE_RECORD_H
#define DFLE_RECORD_H

#include <stddef.h>
#include <stdio.h>

#include "dfle/error.h"
#include "dfle/param.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_record dfle_record;

int dfle_record_new(dfle_record **out, dfle_error *err);
void dfle_record_free(dfle_record *r); /* accepts NULL */

/* Entries added from now on go to section `name` (NULL: the top level).
 * `kind` (may be NULL) names the kind of component.  A section already
 * in the record is continued, its kind replaced if `kind` is given. */
void dfle_record_section(dfle_record *r, const char *name, const char *kind);

/* 1 if the record has a section of that name. */
int dfle_record_has_section(const dfle_record *r, const char *name);

/* Add entry `key` to the current section, or replace the entry of that
 * key there.  `unit` may be NULL or "" (none). */
void dfle_record_number(dfle_record *r, const char *key, double v, const char *unit);
void dfle_record_bool(dfle_record *r, const char *key, int v);
/* text NULL removes the entry. */
void dfle_record_text(dfle_record *r, const char *key, const char *text);
void dfle_record_list(dfle_record *r, const char *key, const char *const *items, size_t n);

/* The same as parameters of the current section's component. */
void dfle_record_param_number(dfle_record *r, const char *key, double v, const char *unit);
void dfle_record_param_bool(dfle_record *r, const char *key, int v);
void dfle_record_param_text(dfle_record *r, const char *key, const char *text);
/* A params op's list (a switch as true/false). */
void dfle_record_params(dfle_record *r, const dfle_param *p, size_t n);

/* Top-level "dfle" (this version) and "date": now in UTC as
 * 2025-06-01T10:00:00Z, or the time in SOURCE_DATE_EPOCH (seconds since
 * 1970, the reproducible-builds convention) when that is set, so a test
 * or a user who wants identical files gets them. */
void dfle_record_stamp(dfle_record *r);

/* DFLE_OK, or DFLE_ENOMEM if an entry could not be added. */
int dfle_record_status(const dfle_record *r, dfle_error *err);

/* One entry as a visitor sees it (dfle_record_each): `section` and
 * `kind` are NULL at the top level; `unit` NULL when none. */
enum dfle_record_type {
    DFLE_RECORD_NUMBER,
    DFLE_RECORD_BOOL,  /* num is 0 or 1 */
    DFLE_RECORD_TEXT,
    DFLE_RECORD_LIST   /* items[0 .. nitems) */
};
typedef struct dfle_record_entry {
    const char *section, *kind, *key, *unit;
    enum dfle_record_type type;
    int param;                 /* a component's option */
    double num;
    const char *text;
    const char *const *items;
    size_t nitems;
} dfle_record_entry;

/* Call fn for every entry in the order the writers use (the top level
 * first, then each section in the order it was begun); a nonzero return
 * stops the walk and is returned.  A section without entries is visited
 * once, with key NULL, so that its kind is seen. */
int dfle_record_each(const dfle_record *r, int (*fn)(void *ud, const dfle_record_entry *e),
                     void *ud);

/* The name of an entry in a flat store of name = value (NetCDF global
 * attributes, GDAL metadata): the top level's "dfle" as "dfle_version",
 * "date" as "date_created", "about" as "comment", other keys as
 * dfle_<key>; a section's entry as <section>_<key>, a section's kind
 * (key NULL) as <section>.  Characters other than letters, digits and
 * "_.-+@" become '_', and a name never starts with anything but a
 * letter (netCDF's rule). */
void dfle_record_flat_name(const dfle_record_entry *e, char *buf, size_t cap);

/* Items as one text: apart by blanks, in a shell's single quotes where
 * an item needs them, so a command line reads back as typed. */
void dfle_record_join(const char *const *items, size_t n, char *buf, size_t cap);

/* CF's history line, "<date>: <command>", from the top-level date and
 * command; 0 (buf untouched) when the record has neither. */
int dfle_record_history(const dfle_record *r, char *buf, size_t cap);

/* The record as '#' lines (top-level entries one a line, each section
 * on one line); a stream error is left in ferror(fp). */
void dfle_record_write_comments(const dfle_record *r, FILE *fp);

/* The record as a JSON file at `path`, written whole (file.h). */
int dfle_record_write_json(const dfle_record *r, const char *path, dfle_error *err);

/* The comment line naming the unit of each column,
 * "# units: x=m, A=m^2, S=-" (no newline), malloc'd; columns whose unit
 * is NULL or "" (text, indices) are left out; NULL if none is left or
 * memory ran out.  "-" is a dimensionless number. */
char *dfle_units_line(const char *const *names, const char *const *units, size_t n);

/* A dfle unit ("m^2", "kg/m^3", "-", "m/yr") in the syntax UDUNITS
 * reads, CF's `units` ("m2", "kg/m3", "1", "m/yr"), into buf; 0 when
 * UDUNITS has no way to say it (a fractional or symbolic exponent:
 * "m^2.5 s^2 kg^-1.5", "m^(1-2 m_s)/yr"), which it would otherwise read
 * as another unit ("m2.5" as 0.5 m2). */
int dfle_units_udunits(const char *unit, char *buf, size_t cap);

/* One column of a table: numbers or texts. */
typedef struct dfle_column {
    const char *name;        /* plain name, as a script uses it: "A"     */
    const char *unit;        /* "m^2"; "-" dimensionless; NULL/"" none   */
    const double *num;       /* nrows numbers, or NULL for ...            */
    const char *const *text; /* ... nrows texts (NULL: an empty field)    */
} dfle_column;

/* Write a CSV table to `path`, whole or not at all (file.h): the record
 * as comment lines (rec may be NULL), the units line, the header of
 * plain column names, then nrows rows.  Numbers with `digits`
 * significant digits, or (digits 0) the shortest text that reads back
 * to the same double; NaN as "nan", infinities as "inf" and "-inf".
 * Texts are quoted when they hold a comma, a quote, a line break, a '#'
 * or blanks at either end.  `who` prefixes error messages.  DFLE_EINVAL
 * for a column name that would break the header or the units line
 * (empty, or with a comma, quote, '=', '#' or line break). */
int dfle_table_write(const char *path, const char *who, const dfle_record *rec,
                     const dfle_column *cols, size_t ncols, size_t nrows, int digits,
                     dfle_error *err);

/* v as the shortest text that reads back to the same double (at most
 * 17 significant digits); "nan", "inf", "-inf" otherwise.  buf holds at
 * least 32 bytes. */
const char *dfle_number_text(double v, char *buf);

#ifdef __cplusplus
}
#endif
#endif
