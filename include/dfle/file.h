/*
 * file.h - files written whole or not at all.
 *
 * Every file dfle writes goes through here: the data go to a temporary
 * file beside the target (same directory, so same file system), which is
 * flushed to disk and then renamed over the target.  A reader, another
 * run or a crash at any moment sees the old file or the new one, never a
 * torn one; a full disk or a file-size limit leaves the old file as it
 * was and the error says what the system said.
 *
 * The temporary file is `.<name>.<pid>.XXXXXX` in the target's directory
 * (<name> cut to 200 bytes, so that the longest legal name still leaves
 * room).  One left by a process that was killed (kill -9, power loss) is
 * removed by the next write of the same target, once its process is
 * gone.  A device or a FIFO is written in place (except by
 * dfle_file_begin_regular, which refuses them); a FIFO that no process
 * is reading is an error at once, not a wait for ever.
 *
 * A file-size limit (ulimit -f) is reported as EFBIG only if SIGXFSZ is
 * ignored; the dfle command ignores it, a host program should too
 * (otherwise the signal ends the process).
 */
#ifndef DFLE_FILE_H
#define DFLE_FILE_H

#include <stdio.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_file {
    FILE *fp;   /* write here (stdio) between begin and commit */
    char *path; /* the target                                  */
    char *tmp;  /* the temporary file                          */
    const char *who; /* prefix of error messages, e.g. "model" */
    int external;    /* written by another program (begin_external) */
} dfle_file;

/* Start writing `path`: open a temporary file beside it.  `who` prefixes
 * error messages ("model: cannot write 'x.csv': ..."). */
int dfle_file_begin(dfle_file *f, const char *path, const char *who, dfle_error *err);

/* The same for a file another program writes (gnuplot): *write_to
 * receives the path it must write (the temporary file, or the target
 * itself when that is a device), valid until commit or abort; f->fp is
 * NULL.  Then dfle_file_commit or dfle_file_abort as usual. */
int dfle_file_begin_external(dfle_file *f, const char *path, const char *who,
                             const char **write_to, dfle_error *err);

/* The same for a library that may remove what it was told to write when
 * it fails (libnetcdf's nc_create does) or that must seek in it (GDAL's
 * GeoTIFF and GeoPackage drivers): only a regular file, a new name, or a
 * link to either is accepted, so *write_to is always a temporary file
 * this call made.  A device, a FIFO, a socket or a link to one is
 * refused with DFLE_EIO, saying what it is, and left as it was. */
int dfle_file_begin_regular(dfle_file *f, const char *path, const char *who,
                            const char **write_to, dfle_error *err);

/* Finish: check for write errors, flush, fsync, close and rename over
 * the target.  On failure the target is untouched, the temporary file
 * removed, and err says why (the system's reason). */
int dfle_file_commit(dfle_file *f, dfle_error *err);

/* Give up: close and remove the temporary file (f may be unbegun). */
void dfle_file_abort(dfle_file *f);

/* Largest file dfle_file_read_all reads by default [bytes]. */
#define DFLE_FILE_READ_MAX ((size_t)4 << 30)

/* Read the whole file at `path` into *text (malloc'd, NUL-terminated;
 * *len bytes before the NUL).  Only a regular file is read: a device, a
 * FIFO or a directory is refused (/dev/zero never ends), and so is a file
 * of more than max_bytes.  Messages start with the path. */
int dfle_file_read_all(const char *path, size_t max_bytes, char **text, size_t *len,
                       dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
