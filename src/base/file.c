/*
 * file.c - files written whole or not at all (dfle/file.h).
 *
 * Why each step: the temporary file lives in the target's directory
 * because rename() is atomic only within one file system; its name holds
 * the writer's pid so that the next writer can tell a leftover of a dead
 * process (removed) from a write in progress (left alone); fsync() before
 * rename() because a rename that reaches the disk before the data would
 * leave an empty file after a power loss; errno is captured at the call
 * that failed, so the message gives the system's reason (ENOSPC, EFBIG,
 * EACCES ...) rather than a bare "error writing"; the temporary file is
 * created with open(O_EXCL, 0666) rather than mkstemp(), whose 0600 would
 * make every output unreadable to the group: the umask applies as for
 * any new file.  Only a regular file (or a new one) is replaced that
 * way: a device, a FIFO or a terminal (/dev/stdout, /dev/null) is written
 * in place, since renaming over it would put a plain file where the
 * device was; a symbolic link is followed, so the file it points at is
 * replaced and the link stays.
 */
#define _XOPEN_SOURCE 700 /* realpath */
#include "dfle/file.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <limits.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

/* Bytes of the target's name kept in a temporary file's name: the name
 * may have up to NAME_MAX (255) bytes, and `.<name>.<pid>.NNNNNN` must
 * fit as well (it once made every legal name over 238 bytes unwritable). */
#define TMP_BASE_MAX 200

static size_t tmp_base_len(const char *base)
{
    size_t n = strlen(base);
    return n < TMP_BASE_MAX ? n : TMP_BASE_MAX;
}

/* Split path into a directory (with its '/', "" for the current one)
 * and a base name; returns the length of the directory part. */
static size_t dir_part(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash != NULL ? (size_t)(slash - path) + 1 : 0;
}

/* Remove `.<base>.<pid>.XXXXXX` files of processes that no longer exist. */
static void remove_stale(const char *path)
{
    const size_t dlen = dir_part(path);
    const char *base = path + dlen;
    const size_t blen = tmp_base_len(base);
    char dir[4096];
    DIR *d;
    struct dirent *e;

    if (dlen >= sizeof dir)
        return;
    memcpy(dir, path, dlen);
    dir[dlen] = '\0';
    if ((d = opendir(dlen ? dir : ".")) == NULL)
        return;
    while ((e = readdir(d)) != NULL) {
        const char *n = e->d_name, *p;
        char *end;
        long pid;
        char victim[4096 + 256];
        if (n[0] != '.' || strncmp(n + 1, base, blen) != 0 || n[1 + blen] != '.')
            continue;
        p = n + 2 + blen;
        pid = strtol(p, &end, 10);
        if (end == p || *end != '.' || strlen(end + 1) != 6 || pid <= 0)
            continue;
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH)
            continue; /* alive, or not ours to judge */
        if (snprintf(victim, sizeof victim, "%s%s", dir, n) < (int)sizeof victim)
            unlink(victim);
    }
    closedir(d);
}

/* Where a write of `path` really lands: the file a symbolic link points
 * at (malloc'd), or a copy of path. */
static char *real_target(const char *path)
{
    struct stat st;
    char *r;
    if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode) && (r = realpath(path, NULL)) != NULL)
        return r;
    r = malloc(strlen(path) + 1);
    if (r != NULL)
        strcpy(r, path);
    return r;
}

/* Open a device or a FIFO for writing, in place.  Without O_NONBLOCK the
 * open of a FIFO no process reads waits for a reader for ever (and a
 * signal does not end the wait: the command's handler restarts it). */
static FILE *open_in_place(const char *path, int *e)
{
    int fd = open(path, O_WRONLY | O_TRUNC | O_NOCTTY | O_NONBLOCK), fl;
    FILE *fp;
    if (fd < 0) {
        *e = errno;
        return NULL;
    }
    /* Blocking writes from here on: a slow reader is not an error. */
    if ((fl = fcntl(fd, F_GETFL)) == -1 || fcntl(fd, F_SETFL, fl & ~O_NONBLOCK) == -1 ||
        (fp = fdopen(fd, "w")) == NULL) {
        *e = errno;
        close(fd);
        return NULL;
    }
    return fp;
}

int dfle_file_begin(dfle_file *f, const char *path, const char *who, dfle_error *err)
{
    size_t dlen, len = strlen(path);
    struct stat st;
    int fd, e;

    memset(f, 0, sizeof *f);
    f->who = who;
    if (len == 0 || path[len - 1] == '/')
        return dfle_error_set(err, DFLE_EINVAL, "%s: '%s' is not a file name", who, path);
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
        /* A device or a pipe: nothing to replace, write in place. */
        if (S_ISDIR(st.st_mode))
            return dfle_error_set(err, DFLE_EIO, "%s: cannot write '%s': it is a directory",
                                  who, path);
        if ((f->fp = open_in_place(path, &e)) == NULL)
            return dfle_error_set(err, DFLE_EIO, "%s: cannot write '%s': %s", who, path,
                                  S_ISFIFO(st.st_mode) && e == ENXIO
                                      ? "it is a FIFO that no process is reading"
                                      : strerror(e));
        if ((f->path = real_target(path)) == NULL) {
            dfle_file_abort(f);
            return dfle_error_set(err, DFLE_ENOMEM, "%s: out of memory", who);
        }
        return DFLE_OK;
    }
    if ((f->path = real_target(path)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "%s: out of memory", who);
    path = f->path;
    len = strlen(path);
    dlen = dir_part(path);
    remove_stale(path);
    if ((f->tmp = malloc(len + 40)) == NULL) {
        dfle_file_abort(f);
        return dfle_error_set(err, DFLE_ENOMEM, "%s: out of memory", who);
    }
    fd = -1;
    for (int tries = 0; fd < 0 && tries < 100; tries++) {
        /* Unique within the process by the counter, across processes by
         * the pid; O_EXCL settles any collision with a leftover. */
        static atomic_uint counter;
        unsigned k = atomic_fetch_add(&counter, 1u) * 2654435761u ^ (unsigned)tries;
        snprintf(f->tmp, len + 40, "%.*s.%.*s.%ld.%06u", (int)dlen, path,
                 (int)tmp_base_len(path + dlen), path + dlen, (long)getpid(), k % 1000000u);
        fd = open(f->tmp, O_WRONLY | O_CREAT | O_EXCL, 0666);
        if (fd < 0 && errno != EEXIST)
            break;
    }
    if (fd < 0 || (f->fp = fdopen(fd, "w")) == NULL) {
        /* The message first: path is f->path, which the abort frees. */
        int code = dfle_error_set(err, DFLE_EIO, "%s: cannot write '%s': %s", who, path,
                                  strerror(errno));
        if (fd >= 0)
            close(fd);
        else
            free(f->tmp), f->tmp = NULL; /* nothing was created */
        dfle_file_abort(f);
        return code;
    }
    return DFLE_OK;
}

int dfle_file_begin_external(dfle_file *f, const char *path, const char *who,
                             const char **write_to, dfle_error *err)
{
    int st = dfle_file_begin(f, path, who, err);
    if (st != DFLE_OK)
        return st;
    /* The other program opens the file by name; ours goes (empty). */
    fclose(f->fp);
    f->fp = NULL;
    f->external = 1;
    *write_to = f->tmp != NULL ? f->tmp : f->path;
    return DFLE_OK;
}

/* What a node that is not a regular file is, for messages. */
static const char *node_kind(mode_t m)
{
    if (S_ISFIFO(m))
        return "a FIFO";
    if (S_ISCHR(m))
        return "a character device";
    if (S_ISBLK(m))
        return "a block device";
    if (S_ISSOCK(m))
        return "a socket";
    if (S_ISDIR(m))
        return "a directory";
    return "not a regular file";
}

int dfle_file_begin_regular(dfle_file *f, const char *path, const char *who,
                            const char **write_to, dfle_error *err)
{
    struct stat st, lst;
    memset(f, 0, sizeof *f);
    f->who = who;
    /* stat follows links: a link to a pipe is judged by the pipe.  The
     * node is only looked at, never opened (opening a FIFO would wait
     * for a reader, and a library told to write it could remove it). */
    if (path[0] != '\0' && stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
        int link = lstat(path, &lst) == 0 && S_ISLNK(lst.st_mode);
        if (S_ISDIR(st.st_mode))
            return dfle_error_set(err, DFLE_EIO, "%s: cannot write '%s': it is a directory",
                                  who, path);
        return dfle_error_set(err, DFLE_EIO, "%s: cannot write '%s': it is %s%s, and this "
                              "format is written to a temporary file that replaces the target; "
                              "give the name of a regular file", who, path,
                              link ? "a link to " : "", node_kind(st.st_mode));
    }
    {
        int rc = dfle_file_begin_external(f, path, who, write_to, err);
        if (rc == DFLE_OK && f->tmp == NULL) {
            /* It became a device or a FIFO since it was looked at. */
            dfle_file_abort(f);
            return dfle_error_set(err, DFLE_EIO, "%s: cannot write '%s': it is not a regular "
                                  "file", who, path);
        }
        return rc;
    }
}

/* fsync a file another program wrote, by name. */
static int sync_by_name(const char *path)
{
    int fd = open(path, O_RDONLY), e = 0;
    if (fd < 0)
        return errno;
    if (fsync(fd) != 0 && errno != EINVAL && errno != EROFS)
        e = errno;
    close(fd);
    return e;
}

int dfle_file_commit(dfle_file *f, dfle_error *err)
{
    int e = 0;

    if (f->external) {
        if (f->tmp != NULL && (e = sync_by_name(f->tmp)) == 0 && rename(f->tmp, f->path) != 0)
            e = errno;
        if (e) {
            int code = dfle_error_set(err, DFLE_EIO, "%s: cannot write '%s': %s", f->who, f->path,
                                      strerror(e));
            dfle_file_abort(f);
            return code;
        }
        free(f->tmp);
        free(f->path);
        f->tmp = f->path = NULL;
        return DFLE_OK;
    }
    if (f->fp == NULL) {
        dfle_file_abort(f);
        return dfle_error_set(err, DFLE_ESTATE, "%s: no file is being written", f->who);
    }
    /* The first failure's errno is the reason worth reporting. */
    if (ferror(f->fp))
        e = errno ? errno : EIO;
    if (!e && fflush(f->fp) != 0)
        e = errno;
    if (!e && fsync(fileno(f->fp)) != 0 && errno != EINVAL && errno != EROFS)
        e = errno; /* EINVAL/EROFS: a file that cannot be synced (a pipe, /dev/...) */
    if (fclose(f->fp) != 0 && !e)
        e = errno;
    f->fp = NULL;
    if (!e && f->tmp != NULL && rename(f->tmp, f->path) != 0)
        e = errno;
    if (e) {
        int code = dfle_error_set(err, DFLE_EIO, "%s: cannot write '%s': %s%s", f->who, f->path,
                                  strerror(e), e == ENOSPC && f->tmp != NULL ? " (the old file is kept)" : "");
        dfle_file_abort(f);
        return code;
    }
    free(f->tmp);
    free(f->path);
    f->tmp = f->path = NULL;
    return DFLE_OK;
}

void dfle_file_abort(dfle_file *f)
{
    if (f->fp != NULL)
        fclose(f->fp);
    if (f->tmp != NULL)
        unlink(f->tmp); /* never the target itself: written in place, tmp is NULL */
    free(f->tmp);
    free(f->path);
    f->fp = NULL;
    f->tmp = f->path = NULL;
}

int dfle_file_read_all(const char *path, size_t max_bytes, char **text, size_t *len,
                       dfle_error *err)
{
    struct stat sb;
    char *buf;
    size_t n = 0;
    int fd;

    *text = NULL;
    *len = 0;
    if ((fd = open(path, O_RDONLY | O_NONBLOCK)) < 0)
        return dfle_error_set(err, DFLE_EIO, "%s: cannot open: %s", path, strerror(errno));
    if (fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode)) {
        close(fd);
        return dfle_error_set(err, DFLE_EIO, "%s: not a regular file (%s)", path,
                              S_ISDIR(sb.st_mode) ? "a directory" : "a device, pipe or socket");
    }
    if ((size_t)sb.st_size > max_bytes) {
        close(fd);
        return dfle_error_set(err, DFLE_EIO, "%s: %lld bytes, more than the %zu read at most",
                              path, (long long)sb.st_size, max_bytes);
    }
    if ((buf = malloc((size_t)sb.st_size + 1)) == NULL) {
        close(fd);
        return dfle_error_set(err, DFLE_ENOMEM, "%s: out of memory", path);
    }
    /* Up to the size seen: a file that grows meanwhile (a writer still
     * appending) is read as it was, never without end. */
    while (n < (size_t)sb.st_size) {
        ssize_t got = read(fd, buf + n, (size_t)sb.st_size - n);
        if (got < 0 && errno == EINTR)
            continue;
        if (got < 0) {
            int e = errno;
            free(buf);
            close(fd);
            return dfle_error_set(err, DFLE_EIO, "%s: read error: %s", path, strerror(e));
        }
        if (got == 0)
            break; /* it shrank */
        n += (size_t)got;
    }
    close(fd);
    buf[n] = '\0';
    *text = buf;
    *len = n;
    return DFLE_OK;
}
