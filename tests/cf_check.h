/*
 * cf_check.h - what every NetCDF file dfle writes must say, checked with
 * libnetcdf (the tests link it), for tests/test_netcdf.c.
 *
 *  - Conventions "CF-1.8", history, source, dfle_version;
 *  - no featureType (dfle writes grids and tables, none of CF's discrete
 *    sampling geometries);
 *  - every `units` attribute in UDUNITS' syntax: unit symbols with
 *    integer powers ("m2", "kg/m3", "m/yr", "1"), no '^', no fractional
 *    power ("m2.5", which UDUNITS reads as 0.5 m2) and, where libudunits2
 *    is installed (it is loaded if present), one that UDUNITS parses;
 *  - a time coordinate either "<unit> since <date>" with a calendar, or
 *    a plain duration for series longer than a date can count;
 *  - every grid_mapping names a variable with grid_mapping_name;
 *  - no global text attribute that is a number (numbers as numbers);
 *  - a flag variable (flag_meanings) is an integer with flag_values.
 */
#ifndef DFLE_TEST_CF_CHECK_H
#define DFLE_TEST_CF_CHECK_H

#include <ctype.h>
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <netcdf.h>

#include "dfle_test.h"

/* libudunits2, when the system has it: ut_read_xml, ut_parse, ut_free. */
typedef struct cf_udunits {
    int tried;
    void *lib, *system;
    void *(*parse)(const void *, const char *, int);
    void (*free_unit)(void *);
} cf_udunits;

static cf_udunits cf_ud;

static inline void cf_udunits_open(void)
{
    void *(*read_xml)(const char *);
    void *(*set_handler)(void *);
    if (cf_ud.tried)
        return;
    cf_ud.tried = 1;
    if ((cf_ud.lib = dlopen("libudunits2.so.0", RTLD_NOW | RTLD_LOCAL)) == NULL)
        return;
    read_xml = (void *(*)(const char *))dlsym(cf_ud.lib, "ut_read_xml");
    set_handler = (void *(*)(void *))dlsym(cf_ud.lib, "ut_set_error_message_handler");
    cf_ud.parse = (void *(*)(const void *, const char *, int))dlsym(cf_ud.lib, "ut_parse");
    cf_ud.free_unit = (void (*)(void *))dlsym(cf_ud.lib, "ut_free");
    if (set_handler != NULL) {
        void *ignore = dlsym(cf_ud.lib, "ut_ignore");
        if (ignore != NULL)
            set_handler(ignore);
    }
    if (read_xml != NULL && cf_ud.parse != NULL && cf_ud.free_unit != NULL)
        cf_ud.system = read_xml(NULL);
}

/* 1 if `u` parses with UDUNITS (or UDUNITS is not installed). */
static inline int cf_udunits_parses(const char *u)
{
    void *unit;
    cf_udunits_open();
    if (cf_ud.system == NULL)
        return 1;
    if ((unit = cf_ud.parse(cf_ud.system, u, 0 /* UT_ASCII */)) == NULL)
        return 0;
    cf_ud.free_unit(unit);
    return 1;
}

/* UDUNITS' syntax as dfle writes it: symbols with integer powers, apart
 * by blanks or one '/', or "1"; a time's "<unit> since <date>". */
static inline int cf_units_syntax(const char *u)
{
    const char *p = u;
    if (strcmp(u, "1") == 0)
        return 1;
    if (strstr(u, " since ") != NULL)
        return strncmp(u, "common_years since ", 19) == 0;
    while (*p != '\0') {
        if (!(isalpha((unsigned char)*p) || *p == '_'))
            return 0;
        while (isalpha((unsigned char)*p) || *p == '_')
            p++;
        if (*p == '-')
            p++;
        while (isdigit((unsigned char)*p))
            p++;
        if (*p == '.' || *p == '^' || *p == '(')
            return 0;
        if (*p == ' ' || *p == '/')
            p++;
        else if (*p != '\0')
            return 0;
    }
    return 1;
}

static inline char *cf_text_att(int ncid, int var, const char *name)
{
    size_t len;
    char *s;
    nc_type t;
    if (nc_inq_att(ncid, var, name, &t, &len) != NC_NOERR || t != NC_CHAR)
        return NULL;
    s = calloc(len + 1, 1);
    assert_non_null(s);
    assert_int_equal(nc_get_att_text(ncid, var, name, s), NC_NOERR);
    return s;
}

static inline int cf_is_number(const char *s)
{
    char *end;
    while (*s == ' ')
        s++;
    if (*s == '\0')
        return 0;
    (void)strtod(s, &end);
    return end != s && *end == '\0';
}

static inline void cf_fail(const char *path, const char *what, const char *detail)
{
    print_error("%s: %s (%s)\n", path, what, detail != NULL ? detail : "");
    fail();
}

/* Everything above, for the file at `path`. */
static inline void cf_check_file(const char *path)
{
    int ncid, nvars, ngatts;
    char *s;
    assert_int_equal(nc_open(path, NC_NOWRITE, &ncid), NC_NOERR);
    if ((s = cf_text_att(ncid, NC_GLOBAL, "Conventions")) == NULL || strcmp(s, "CF-1.8") != 0)
        cf_fail(path, "no Conventions = CF-1.8", s);
    free(s);
    for (const char *const *k = (const char *const[]){"history", "source", "dfle_version", NULL};
         *k != NULL; k++) {
        if ((s = cf_text_att(ncid, NC_GLOBAL, *k)) == NULL || s[0] == '\0')
            cf_fail(path, "a global attribute is missing", *k);
        free(s);
    }
    if ((s = cf_text_att(ncid, NC_GLOBAL, "featureType")) != NULL)
        cf_fail(path, "featureType set", s);
    free(s);
    assert_int_equal(nc_inq_natts(ncid, &ngatts), NC_NOERR);
    for (int a = 0; a < ngatts; a++) {
        char name[NC_MAX_NAME + 1];
        assert_int_equal(nc_inq_attname(ncid, NC_GLOBAL, a, name), NC_NOERR);
        if ((s = cf_text_att(ncid, NC_GLOBAL, name)) != NULL && cf_is_number(s))
            cf_fail(path, "a number stored as text in a global attribute", name);
        free(s);
    }
    assert_int_equal(nc_inq_nvars(ncid, &nvars), NC_NOERR);
    for (int v = 0; v < nvars; v++) {
        char name[NC_MAX_NAME + 1];
        nc_type type;
        size_t len;
        assert_int_equal(nc_inq_varname(ncid, v, name), NC_NOERR);
        assert_int_equal(nc_inq_vartype(ncid, v, &type), NC_NOERR);
        if ((s = cf_text_att(ncid, v, "units")) != NULL) {
            if (!cf_units_syntax(s))
                cf_fail(path, "units not in UDUNITS' syntax", s);
            if (!cf_udunits_parses(s))
                cf_fail(path, "units UDUNITS does not parse", s);
            if (strstr(s, " since ") != NULL) {
                char *cal = cf_text_att(ncid, v, "calendar");
                if (cal == NULL || strcmp(cal, "noleap") != 0)
                    cf_fail(path, "a time coordinate without its calendar", name);
                free(cal);
            }
            free(s);
        } else if (strcmp(name, "time") == 0) {
            cf_fail(path, "time without units", NULL);
        }
        if ((s = cf_text_att(ncid, v, "grid_mapping")) != NULL) {
            int gm;
            char *gname;
            if (nc_inq_varid(ncid, s, &gm) != NC_NOERR)
                cf_fail(path, "grid_mapping names no variable", s);
            gname = cf_text_att(ncid, gm, "grid_mapping_name");
            if (gname == NULL)
                cf_fail(path, "the grid mapping has no grid_mapping_name", s);
            free(gname);
        }
        free(s);
        if ((s = cf_text_att(ncid, v, "flag_meanings")) != NULL) {
            nc_type ft;
            if (type != NC_BYTE || nc_inq_att(ncid, v, "flag_values", &ft, &len) != NC_NOERR ||
                ft != NC_BYTE)
                cf_fail(path, "a flag variable that is not a byte with byte flag_values", name);
        }
        free(s);
    }
    nc_close(ncid);
}

#endif
