/*
 * plot_run.c - one gnuplot run: the terminal of the image's format, a
 * temporary image beside the target, gnuplot's exit status and messages,
 * a check that the image is whole, and the rename over the target.
 *
 * dfle does not draw: it writes one complete gnuplot script, data inline
 * as datablocks, to a gnuplot process and then checks that the image
 * exists.  Everything that can be checked before gnuplot starts (path,
 * format, options, data) is, so a bad call never starts gnuplot or
 * touches a file.
 *
 * Safety of the script: every string from the caller (labels, the output
 * path) is written in gnuplot single quotes, the only quoting in which
 * gnuplot performs no backquote (shell) substitution, no macro expansion
 * and no backslash processing.  A relative output path gets a "./" prefix
 * so that gnuplot cannot read a leading '|' as "pipe to a command" or a
 * leading '~' as the home directory.  The program named by DFLE_GNUPLOT
 * is started directly (posix_spawnp, no shell between): its standard
 * input is the script's pipe, its stdout and stderr a temporary file
 * whose first lines end up in the error message, so the library never
 * writes to the user's terminal.  A shell there (popen) cost descriptors
 * of its own: dash saves every descriptor it redirects above 10, so
 * with ulimit -n 12 or less the plot failed with "Too many open files".
 *
 * One page, three formats: the terminal line scales fonts, lines and
 * points so that a figure of a given size in cm looks the same as PNG,
 * PDF and SVG (the cairo terminals and the SVG one disagree by factors
 * of 4/3, 1/2 and 3/2 between them; see the terminal line below).
 */
#ifndef _POSIX_C_SOURCE /* popen, mkstemp, sigset_t: POSIX, not C11 */
#define _POSIX_C_SOURCE 200809L
#endif
#include "io/plot_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* The image format named by the path's extension, or a negative status.
 * Control characters are refused: they cannot be written in a
 * single-quoted gnuplot string and no sane file name needs them. */
int dfle_gp_format(const char *path, dfle_error *err)
{
    if (path == NULL || path[0] == '\0')
        return dfle_error_set(err, DFLE_EINVAL,
                              "plot: output path is NULL or empty");
    for (const char *p = path; *p != '\0'; p++)
        if ((unsigned char)*p < 0x20 || *p == 0x7f)
            return dfle_error_set(err, DFLE_EINVAL, "plot: output path '%s' "
                                  "contains a control character", path);
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (dot != NULL && (slash == NULL || dot > slash)) {
        if (strcasecmp(dot, ".png") == 0) return FMT_PNG;
        if (strcasecmp(dot, ".svg") == 0) return FMT_SVG;
        if (strcasecmp(dot, ".pdf") == 0) return FMT_PDF;
    }
    return dfle_error_set(err, DFLE_EINVAL, "plot: unsupported image format "
                          "for '%s': the name must end in .png, .pdf or .svg", path);
}

/* s as a gnuplot single-quoted string (see the file comment).  A line
 * break is spliced in as a concatenated "\n" so multi-line titles work
 * without ending the command. */
void dfle_gp_str(FILE *f, const char *s)
{
    fputc('\'', f);
    for (; *s != '\0'; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '\'') fputs("''", f);
        else if (c == '\n') fputs("'.\"\\n\".'", f);
        else fputc(c < 0x20 || c == 0x7f ? ' ' : c, f);
    }
    fputc('\'', f);
}

extern char **environ;

/* Start prog with its standard input the write end of a pipe (into
 * *to) and stdout and stderr going to errfd; 0 or an errno. */
static int spawn_gnuplot(const char *prog, int errfd, FILE **to, pid_t *pid)
{
    posix_spawn_file_actions_t fa;
    char *argv[2] = {(char *)prog, NULL};
    int fd[2], rc;
    if (pipe(fd) != 0)
        return errno;
    /* Ours only: gnuplot must not hold the write end (it would never
     * see the end of its script), nor any other of them. */
    fcntl(fd[1], F_SETFD, FD_CLOEXEC);
    if ((rc = posix_spawn_file_actions_init(&fa)) != 0) {
        close(fd[0]);
        close(fd[1]);
        return rc;
    }
    rc = posix_spawn_file_actions_adddup2(&fa, fd[0], 0);
    if (rc == 0)
        rc = posix_spawn_file_actions_adddup2(&fa, errfd, 1);
    if (rc == 0)
        rc = posix_spawn_file_actions_adddup2(&fa, errfd, 2);
    if (rc == 0 && fd[0] > 2)
        rc = posix_spawn_file_actions_addclose(&fa, fd[0]);
    if (rc == 0 && errfd > 2)
        rc = posix_spawn_file_actions_addclose(&fa, errfd);
    if (rc == 0)
        rc = posix_spawnp(pid, prog, &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    close(fd[0]);
    if (rc == 0 && (*to = fdopen(fd[1], "w")) == NULL) {
        rc = errno;
        close(fd[1]);
        waitpid(*pid, NULL, 0);
        return rc;
    }
    if (rc != 0)
        close(fd[1]);
    return rc;
}

/* The terminal for page fr.  The three terminals measure differently
 * (gnuplot 5.4, checked on the files they write): a font of size s has
 * an em of s * fontscale * 4/3 device units in pngcairo (pixels) and
 * pdfcairo (points), but pdfcairo's default fontscale is 0.5; a line of
 * width 1 is 1 px in pngcairo, 0.5 pt in pdfcairo and 1 unit in svg;
 * points are 6 px / 6 pt / 9 units across at size 1.  The factors below
 * make an em of s pt, a line of 0.5 pt per unit of width and points of
 * 6 pt per unit of size on the page, whatever the format.  An SVG is
 * drawn in units of 1 pt (its header says so, see svg_in_points). */
static void put_terminal(FILE *f, const dfle_gp_frame *fr, double lw_scale)
{
    char font[96];
    snprintf(font, sizeof font, "%s,%g", fr->family[0] != '\0' ? fr->family : "sans",
             fr->font_pt);
    if (fr->fmt == FMT_PNG) {
        double px = fr->dpi / 72.0; /* pixels per pt */
        fprintf(f, "set terminal pngcairo size %ld,%ld enhanced font ", lround(fr->w_pt * px),
                lround(fr->h_pt * px));
        dfle_gp_str(f, font);
        fprintf(f, " fontscale %.6g linewidth %.6g pointscale %.6g rounded "
                "background '#ffffff'\n", 0.75 * px, DFLE_GP_LW_PT * px * lw_scale, px);
    } else if (fr->fmt == FMT_PDF) {
        fprintf(f, "set terminal pdfcairo size %.6gin,%.6gin enhanced font ", fr->w_pt / 72,
                fr->h_pt / 72);
        dfle_gp_str(f, font);
        fprintf(f, " fontscale 0.75 linewidth %.6g rounded background '#ffffff'\n",
                2 * DFLE_GP_LW_PT * lw_scale);
    } else { /* points: dfle_gp_ps scales them, svg has no pointscale */
        fprintf(f, "set terminal svg size %ld,%ld fixed enhanced font ", lround(fr->w_pt),
                lround(fr->h_pt));
        dfle_gp_str(f, font);
        fprintf(f, " fontscale 1 linewidth %.6g rounded background '#ffffff'\n",
                DFLE_GP_LW_PT * lw_scale);
    }
}

static int begin(dfle_gp_run *r, const char *path, const dfle_gp_frame *fr, double lw_scale,
                 dfle_error *err)
{
    const char *tmp = getenv("TMPDIR");
    char errpath[512];
    int rc;
    memset(r, 0, sizeof *r);
    r->out = path;
    r->fmt = fr->fmt;
    r->svg_w_pt = fr->w_pt;
    r->svg_h_pt = fr->h_pt;
    r->prog = getenv("DFLE_GNUPLOT");
    if (r->prog == NULL || r->prog[0] == '\0') r->prog = "gnuplot";
    if (tmp == NULL || tmp[0] == '\0' || strlen(tmp) > sizeof errpath - 32)
        tmp = "/tmp";
    /* gnuplot's messages go to a file unlinked at once and inherited by
     * descriptor: whatever kills us, nothing is left behind. */
    snprintf(errpath, sizeof errpath, "%s/dfle-gnuplot-XXXXXX", tmp);
    if ((r->errfd = mkstemp(errpath)) < 0)
        return dfle_error_set(err, DFLE_EIO, "plot: cannot create a temporary "
                              "file in %s: %s", tmp, strerror(errno));
    unlink(errpath);
    /* gnuplot writes a temporary file beside the image, renamed over it
     * only once gnuplot succeeded and the image is whole: an unwritable
     * path is a clear DFLE_EIO now, and a failure later (a full disk, a
     * size limit, a kill) leaves any old image as it was. */
    rc = dfle_file_begin_external(&r->file, path, "plot", &r->write_to, err);
    if (rc == DFLE_OK) {
        sigset_t pend;
        int e = spawn_gnuplot(r->prog, r->errfd, &r->f, &r->pid);
        if (e == ENOENT || e == EACCES || e == ENOEXEC || e == ENOTDIR) {
            rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot could not be run ('%s': "
                                "%s); install it (apt-get install gnuplot-nox) or set "
                                "DFLE_GNUPLOT to the gnuplot program", r->prog, strerror(e));
        } else if (e != 0) {
            rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot could not "
                                "be run ('%s'): %s", r->prog, strerror(e));
        } else { /* after the spawn, so gnuplot keeps the caller's mask */
            sigemptyset(&r->pipeset);
            sigaddset(&r->pipeset, SIGPIPE);
            pthread_sigmask(SIG_BLOCK, &r->pipeset, &r->oldmask);
            r->pipe_pending = sigpending(&pend) == 0 &&
                              sigismember(&pend, SIGPIPE);
        }
    }
    if (rc < 0) {
        dfle_file_abort(&r->file);
        close(r->errfd);
        return rc;
    }
    path = r->write_to;
    put_terminal(r->f, fr, lw_scale);
    fprintf(r->f, "set encoding utf8\nset output %s", path[0] == '/' ? "" : "'./'.");
    dfle_gp_str(r->f, path);
    /* Light grid behind the data, thin black frame, small bar caps. */
    fputs("\nset style line 81 lt 1 lc rgb '#d0d0d0' lw 1\n"
          "set style line 82 lt 1 lc rgb '#ececec' lw 0.8\n"
          "set border lw 1.5\nset tics scale 1,0.5 front\nset bars small\n", r->f);
    return DFLE_OK;
}

int dfle_gp_begin_frame(dfle_gp_run *r, const char *path, const dfle_gp_frame *fr,
                        dfle_error *err)
{
    return begin(r, path, fr, 1.0, err);
}

/* Up to two meaningful lines of what gnuplot (or sh) said, on one line:
 * echoed commands and caret lines only repeat the script. */
static void err_text(int fd, char *out, size_t cap)
{
    char buf[1024];
    ssize_t k = lseek(fd, 0, SEEK_SET) == 0 ? read(fd, buf, sizeof buf - 1) : 0;
    buf[k > 0 ? k : 0] = '\0';
    out[0] = '\0';
    int lines = 0;
    char *save = NULL;
    for (char *ln = strtok_r(buf, "\n", &save); ln != NULL && lines < 2;
         ln = strtok_r(NULL, "\n", &save)) {
        while (*ln == ' ' || *ln == '\t') ln++;
        if (*ln == '\0' || *ln == '^' || strncmp(ln, "gnuplot>", 8) == 0)
            continue;
        size_t used = strlen(out);
        snprintf(out + used, cap - used, "%s%s", lines++ ? "; " : "", ln);
    }
    if (lines == 0) snprintf(out, cap, "no message");
}

/* `tail` (want bytes, NUL-terminated) ends with `tag` and then at most
 * white space. */
static int ends_with_tag(const unsigned char *tail, size_t want, const char *tag)
{
    size_t t = strlen(tag);
    for (size_t k = 0; k + t <= want; k++)
        if (memcmp(tail + k, tag, t) == 0 &&
            strspn((const char *)tail + k + t, " \t\r\n") == want - k - t)
            return 1;
    return 0;
}

/* A complete image ends as its format says: a PNG with its IEND chunk
 * (12 fixed bytes), an SVG with its closing tag, a PDF with %%EOF.  A
 * disk that filled up or a size limit leaves a file that does not,
 * whatever gnuplot's exit status says. */
static int image_complete(const char *path, int fmt)
{
    static const unsigned char iend[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D',
                                           0xAE, 0x42, 0x60, 0x82};
    unsigned char tail[65]; /* 64 bytes and a NUL, for strspn */
    struct stat sb;
    size_t want;
    int fd = open(path, O_RDONLY), ok = 0;
    if (fd < 0)
        return 0;
    if (fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode) && sb.st_size > 0) {
        want = (size_t)sb.st_size < sizeof tail - 1 ? (size_t)sb.st_size : sizeof tail - 1;
        if (lseek(fd, sb.st_size - (off_t)want, SEEK_SET) >= 0 &&
            read(fd, tail, want) == (ssize_t)want) {
            tail[want] = '\0';
            if (fmt == FMT_PNG)
                ok = want >= 12 && memcmp(tail + want - 12, iend, 12) == 0;
            else
                ok = ends_with_tag(tail, want, fmt == FMT_SVG ? "</svg>" : "%%EOF");
        }
    } else if (fstat(fd, &sb) == 0 && !S_ISREG(sb.st_mode)) {
        ok = 1; /* a device or a pipe: nothing to check */
    }
    close(fd);
    return ok;
}

/* gnuplot's SVG says width="432" height="288": CSS pixels, so the page
 * would show at 3/4 of its size.  Its user units are points (see
 * put_terminal); saying so in the header (width="432pt") gives the
 * size asked for in any program, the viewBox unchanged.  Only the
 * attributes of the <svg> element are touched; a file that does not
 * look as expected is left as it is. */
static int svg_in_points(const char *path, double w_pt, double h_pt)
{
    struct stat sb;
    char *buf = NULL, want_w[48], want_h[48];
    int rc = DFLE_OK;
    FILE *f;
    if (stat(path, &sb) != 0 || !S_ISREG(sb.st_mode) || sb.st_size <= 0)
        return DFLE_OK;
    snprintf(want_w, sizeof want_w, " width=\"%ld\"", lround(w_pt));
    snprintf(want_h, sizeof want_h, " height=\"%ld\"", lround(h_pt));
    if ((buf = malloc((size_t)sb.st_size + 1)) == NULL)
        return DFLE_ENOMEM;
    if ((f = fopen(path, "rb")) == NULL) {
        free(buf);
        return DFLE_EIO;
    }
    size_t len = fread(buf, 1, (size_t)sb.st_size, f);
    fclose(f);
    buf[len] = '\0';
    char *svg = strstr(buf, "<svg"), *end = svg ? strchr(svg, '>') : NULL;
    char *w = svg ? strstr(svg, want_w) : NULL, *h = svg ? strstr(svg, want_h) : NULL;
    if (end == NULL || w == NULL || h == NULL || w > end || h > end || h < w) {
        free(buf);
        return DFLE_OK;
    }
    size_t wend = (size_t)(w - buf) + strlen(want_w) - 1, hend = (size_t)(h - buf) + strlen(want_h) - 1;
    if ((f = fopen(path, "wb")) == NULL) {
        free(buf);
        return DFLE_EIO;
    }
    /* ... width="432 | pt | " height="288 | pt | "... */
    if (fwrite(buf, 1, wend, f) != wend || fputs("pt", f) < 0 ||
        fwrite(buf + wend, 1, hend - wend, f) != hend - wend || fputs("pt", f) < 0 ||
        fwrite(buf + hend, 1, len - hend, f) != len - hend)
        rc = DFLE_EIO;
    if (fclose(f) != 0)
        rc = DFLE_EIO;
    free(buf);
    return rc;
}

int dfle_gp_end(dfle_gp_run *r, dfle_error *err)
{
    char msg[300];
    struct stat sb;
    int rc = DFLE_OK;
    fputs("unset output\n", r->f);
    int werr = fflush(r->f) != 0 || ferror(r->f), st = 0, perr = 0;
    fclose(r->f); /* gnuplot sees the end of its script */
    while (waitpid(r->pid, &st, 0) < 0) {
        if (errno != EINTR) {
            st = -1;
            perr = errno;
            break;
        }
    }
    sigset_t pend;
    if (!r->pipe_pending && sigpending(&pend) == 0 &&
        sigismember(&pend, SIGPIPE)) { /* eat the SIGPIPE we caused */
        const struct timespec zero = {0, 0};
        while (sigtimedwait(&r->pipeset, NULL, &zero) < 0 && errno == EINTR) {}
    }
    pthread_sigmask(SIG_SETMASK, &r->oldmask, NULL);
    err_text(r->errfd, msg, sizeof msg);
    close(r->errfd);

    /* A wrapper script reports a program it cannot run as 126 or 127,
     * and one killed by signal n as 128 + n (a size limit is SIGXFSZ,
     * not a missing gnuplot). */
    if (st == -1)
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: could not wait for "
                            "gnuplot ('%s'): %s", r->prog, strerror(perr));
    else if (WIFEXITED(st) && (WEXITSTATUS(st) == 126 || WEXITSTATUS(st) == 127))
        /* (also a spawn whose exec failed in the child, as under
         * valgrind, which reports it by status 127) */
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot could not be "
                            "run ('%s': %s); install it (apt-get install "
                            "gnuplot-nox) or set DFLE_GNUPLOT to the gnuplot "
                            "program", r->prog, msg);
    else if (WIFSIGNALED(st) || (WIFEXITED(st) && WEXITSTATUS(st) > 128))
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot ('%s') was "
                            "killed by signal %d (%s) making '%s'", r->prog,
                            WIFSIGNALED(st) ? WTERMSIG(st) : WEXITSTATUS(st) - 128,
                            strsignal(WIFSIGNALED(st) ? WTERMSIG(st) : WEXITSTATUS(st) - 128),
                            r->out);
    else if (WEXITSTATUS(st) != 0 && strstr(msg, "unknown or ambiguous terminal") != NULL)
        /* A gnuplot built without cairo (or an old one) lacks the
         * terminal: say which and what to do, not just gnuplot's words. */
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot ('%s') has no %s "
                            "terminal to make '%s' (%s); Debian's gnuplot-nox has "
                            "pngcairo, pdfcairo and svg: install it or set "
                            "DFLE_GNUPLOT to a gnuplot that has", r->prog,
                            r->fmt == FMT_PNG ? "pngcairo" : r->fmt == FMT_PDF ? "pdfcairo"
                            : "svg", r->out, msg);
    else if (WEXITSTATUS(st) != 0)
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot ('%s') failed "
                            "making '%s': %s", r->prog, r->out, msg);
    else if (werr)
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: could not send the "
                            "script to gnuplot ('%s')", r->prog);
    else if (stat(r->write_to, &sb) == 0 && S_ISREG(sb.st_mode) && sb.st_size == 0)
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot finished but "
                            "wrote nothing to '%s'", r->out);
    else if (r->fmt == FMT_SVG && svg_in_points(r->write_to, r->svg_w_pt, r->svg_h_pt) != DFLE_OK)
        rc = dfle_error_set(err, DFLE_EIO, "plot: could not set the size in the "
                            "header of '%s' (a full disk?)", r->out);
    else if (!image_complete(r->write_to, r->fmt))
        rc = dfle_error_set(err, DFLE_EIO, "plot: gnuplot finished but '%s' is "
                            "incomplete (a full disk or a file-size limit?)%s%s",
                            r->out, strcmp(msg, "no message") ? ": " : "",
                            strcmp(msg, "no message") ? msg : "");
    /* No truncated or empty image replaces a good one. */
    if (rc != DFLE_OK) {
        dfle_file_abort(&r->file);
        return rc;
    }
    return dfle_file_commit(&r->file, err);
}
