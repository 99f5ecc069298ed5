/*
 * error.h - status codes and the error record every dfle call can fill.
 *
 * The library never prints and never exits.  A function that can fail
 * returns an int status (DFLE_OK or a negative code) and, when the caller
 * passes a dfle_error, leaves a human-readable message there naming the
 * parameter or quantity at fault.  Passing NULL for the error record is
 * always allowed; the status alone is then all the caller gets.
 */
#ifndef DFLE_ERROR_H
#define DFLE_ERROR_H

#ifdef __cplusplus
extern "C" {
#endif

enum dfle_status {
    DFLE_OK = 0,
    DFLE_EINVAL = -1,    /* a parameter is missing, out of range or NaN  */
    DFLE_ENOMEM = -2,    /* an allocation failed                         */
    DFLE_ENUMERIC = -3,  /* NaN or Inf appeared in a simulation          */
    DFLE_EIO = -4,       /* a file could not be read or written          */
    DFLE_ECALLBACK = -5, /* a user-supplied callback (e.g. Lua) failed   */
    DFLE_ESTATE = -6,    /* the object is not in a state for this call   */
    DFLE_EFIT = -7,      /* a fit did not converge or had too few points */
    DFLE_ECANCELED = -8, /* a progress callback asked the run to stop    */
    DFLE_EEXTERNAL = -9  /* an external program (gnuplot) failed, or a   */
                         /* library (GDAL, netCDF) could not be loaded   */
};

#define DFLE_ERROR_MSG_MAX 512

typedef struct dfle_error {
    int code;                     /* last status, DFLE_OK when clear */
    char msg[DFLE_ERROR_MSG_MAX]; /* message for that status         */
} dfle_error;

/* Record `code` and a printf-style message in `err` (which may be NULL).
 * A NaN formatted by %g, %f or %e reads "NaN" (printf says "nan" or
 * "-nan").  Returns `code` so callers can write `return dfle_error_set(...)`. */
int dfle_error_set(dfle_error *err, int code, const char *fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Reset `err` (may be NULL) to DFLE_OK with an empty message. */
void dfle_error_clear(dfle_error *err);

/* A short fixed description of a status code, e.g. "invalid parameter". */
const char *dfle_status_string(int code);

#ifdef __cplusplus
}
#endif
#endif
