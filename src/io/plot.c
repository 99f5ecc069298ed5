/*
 * plot.c - publication figures (x-y, slope-area, long profile) via gnuplot.
 *
 * dfle does not draw: it writes one complete gnuplot script, data inline
 * as datablocks, to a gnuplot process and then checks that the image
 * exists.  Everything that can be checked before gnuplot starts (path,
 * format, data) is, so a bad call never starts gnuplot or touches a file.
 *
 * Safety of the script: every string from the caller (labels, the output
 * path) is written in gnuplot single quotes, the only quoting in which
 * gnuplot performs no backquote (shell) substitution, no macro expansion
 * and no backslash processing.  A relative output path gets a "./" prefix
 * so that gnuplot cannot read a leading '|' as "pipe to a command" or a
 * leading '~' as the home directory.  The program named by DFLE_GNUPLOT
 * is single-quoted for /bin/sh.  gnuplot's stdout and stderr go to a
 * temporary file whose first lines end up in the error message, so the
 * library never writes to the user's terminal.
 *
 * Labels and titles are gnuplot "enhanced text": m^2 and S_{df} render as
 * super- and subscripts, which is what the figures need.
 */
#ifndef _POSIX_C_SOURCE /* popen, mkstemp, sigset_t: POSIX, not C11 */
#define _POSIX_C_SOURCE 200809L
#endif
#include "dfle/plot.h"

#include "dfle/file.h"
#include "io/plot_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

enum { FIT_SAMPLES = 200 };

/* Okabe-Ito colours: distinguishable with colour-blindness and in print. */
const char *const dfle_gp_palette[DFLE_GP_NPALETTE] = {"#0072B2", "#D55E00", "#009E73",
                                      "#CC79A7", "#E69F00", "#56B4E9",
                                      "#000000"};

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
    }
    return dfle_error_set(err, DFLE_EINVAL, "plot: unsupported image format "
                          "for '%s': the name must end in .png or .svg", path);
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

/* Append s, single-quoted for /bin/sh (' becomes '\''), to dst. */
static void sh_quote(char *dst, const char *s)
{
    dst += strlen(dst);
    *dst++ = '\'';
    for (; *s != '\0'; s++) {
        if (*s == '\'') { memcpy(dst, "'\\''", 4); dst += 4; }
        else *dst++ = *s;
    }
    strcpy(dst, "'");
}


int dfle_gp_begin(dfle_gp_run *r, const char *path, int fmt, int w, int h,
                    dfle_error *err)
{
    const char *tmp = getenv("TMPDIR");
    char errpath[512];
    int rc;
    memset(r, 0, sizeof *r);
    r->out = path;
    r->fmt = fmt;
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
    char *cmd = malloc(4 * strlen(r->prog) + 64);
    if (rc == DFLE_OK && cmd == NULL) {
        rc = dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
    } else if (rc == DFLE_OK) {
        sigset_t pend;
        cmd[0] = '\0';
        sh_quote(cmd, r->prog);
        snprintf(cmd + strlen(cmd), 64, " 2>&%d 1>&2", r->errfd);
        if ((r->f = popen(cmd, "w")) == NULL) {
            rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot could not "
                                "be run ('%s'): %s", r->prog, strerror(errno));
        } else { /* after popen, so gnuplot keeps the caller's mask */
            sigemptyset(&r->pipeset);
            sigaddset(&r->pipeset, SIGPIPE);
            pthread_sigmask(SIG_BLOCK, &r->pipeset, &r->oldmask);
            r->pipe_pending = sigpending(&pend) == 0 &&
                              sigismember(&pend, SIGPIPE);
        }
    }
    free(cmd);
    if (rc < 0) {
        dfle_file_abort(&r->file);
        close(r->errfd);
        return rc;
    }
    path = r->write_to;
    fprintf(r->f, "set terminal %s size %d,%d enhanced font 'sans,12' "
            "linewidth 1.2 background '#ffffff'\nset encoding utf8\n"
            "set output %s", fmt == FMT_PNG ? "pngcairo" : "svg", w, h,
            path[0] == '/' ? "" : "'./'.");
    dfle_gp_str(r->f, path);
    /* Light grid behind the data, thin black frame, small bar caps. */
    fputs("\nset style line 81 lt 1 lc rgb '#d0d0d0' lw 0.6\n"
          "set style line 82 lt 1 lc rgb '#ececec' lw 0.4\n"
          "set border lw 1.0\nset tics scale 1.2,0.6\nset bars small\n", r->f);
    return DFLE_OK;
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

/* A complete image ends as its format says: a PNG with its IEND chunk
 * (12 fixed bytes), an SVG with its closing tag.  A disk that filled up
 * or a size limit leaves a file that does not, whatever gnuplot's exit
 * status says. */
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
            else /* the tag, then at most white space */
                for (size_t k = 0; k + 6 <= want && !ok; k++)
                    ok = memcmp(tail + k, "</svg>", 6) == 0 &&
                         strspn((const char *)tail + k + 6, " \t\r\n") ==
                             want - k - 6;
        }
    } else if (fstat(fd, &sb) == 0 && !S_ISREG(sb.st_mode)) {
        ok = 1; /* a device or a pipe: nothing to check */
    }
    close(fd);
    return ok;
}

int dfle_gp_end(dfle_gp_run *r, dfle_error *err)
{
    char msg[300];
    struct stat sb;
    int rc = DFLE_OK;
    fputs("unset output\n", r->f);
    int werr = fflush(r->f) != 0 || ferror(r->f);
    int st = pclose(r->f), perr = errno;
    sigset_t pend;
    if (!r->pipe_pending && sigpending(&pend) == 0 &&
        sigismember(&pend, SIGPIPE)) { /* eat the SIGPIPE we caused */
        const struct timespec zero = {0, 0};
        while (sigtimedwait(&r->pipeset, NULL, &zero) < 0 && errno == EINTR) {}
    }
    pthread_sigmask(SIG_SETMASK, &r->oldmask, NULL);
    err_text(r->errfd, msg, sizeof msg);
    close(r->errfd);

    /* sh reports a program it cannot run as 126 or 127, and one killed
     * by signal n as 128 + n (a size limit is SIGXFSZ, not a missing
     * gnuplot). */
    if (st == -1)
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: could not wait for "
                            "gnuplot ('%s'): %s", r->prog, strerror(perr));
    else if (WIFEXITED(st) && (WEXITSTATUS(st) == 126 || WEXITSTATUS(st) == 127))
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot could not be "
                            "run (%s); install it (apt-get install "
                            "gnuplot-nox) or set DFLE_GNUPLOT to the gnuplot "
                            "program", msg);
    else if (WIFSIGNALED(st) || (WIFEXITED(st) && WEXITSTATUS(st) > 128))
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot ('%s') was "
                            "killed by signal %d (%s) making '%s'", r->prog,
                            WIFSIGNALED(st) ? WTERMSIG(st) : WEXITSTATUS(st) - 128,
                            strsignal(WIFSIGNALED(st) ? WTERMSIG(st) : WEXITSTATUS(st) - 128),
                            r->out);
    else if (WEXITSTATUS(st) != 0)
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot ('%s') failed "
                            "making '%s': %s", r->prog, r->out, msg);
    else if (werr)
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: could not send the "
                            "script to gnuplot ('%s')", r->prog);
    else if (stat(r->write_to, &sb) == 0 && S_ISREG(sb.st_mode) && sb.st_size == 0)
        rc = dfle_error_set(err, DFLE_EEXTERNAL, "plot: gnuplot finished but "
                            "wrote nothing to '%s'", r->out);
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

static int usable(double x, double y, int logx, int logy)
{
    return isfinite(x) && isfinite(y) && (!logx || x > 0) && (!logy || y > 0);
}

/* One thing drawn from n rows (x, y), optionally with error-bar ends
 * lo/hi.  Unusable rows (non-finite, or <= 0 on a log axis) are left
 * out; in a line they leave a gap rather than a false join. */
typedef struct layer {
    size_t n;
    const double *x, *y, *lo, *hi;
    const char *with, *color; /* gnuplot "with" clause, "#rrggbb" */
    const char *title;        /* legend text; NULL: none */
    size_t used;              /* usable rows, set by ext_scan */
    const double *c;          /* colour value per row, or NULL */
    int logc;                 /* colour scale is logarithmic */
    int band;                 /* filled between lo and hi (columns 3, 4) */
} layer;

/* Extent of the layers in axis units (log10 on log axes) and how many
 * points fall in each corner box (top right, top left, bottom left,
 * bottom right) of the size the key will take: the key goes in the
 * emptiest one, so it does not hide data. */
typedef struct extent {
    double x0, x1, y0, y1;
    int logx, logy;
    double kw, kh;       /* key size, fraction of the frame */
    size_t n, corner[4]; /* corners counted by put_blocks */
} extent;

static double ax(double v, int lg) { return lg ? log10(v) : v; }

/* Widen [lo, hi] (log10 units) to 1, 2 or 5 times a power of ten:
 * tighter than gnuplot's whole decades, still ending on round numbers.
 * Data on a round value (A0 = 1000 m^2 is common) would sit on the
 * frame and vanish behind it, so pad by 0.005 decades (1 %) first. */
static void nice_log(double *lo, double *hi)
{
    const double l2 = log10(2.0), l5 = log10(5.0), eps = 1e-9;
    *lo -= 0.005;
    *hi += 0.005;
    double d = floor(*lo + eps), m = *lo - d;
    *lo = d + (m >= l5 - eps ? l5 : m >= l2 - eps ? l2 : 0);
    d = floor(*hi - eps);
    m = *hi - d;
    *hi = d + (m <= l2 + eps ? l2 : m <= l5 + eps ? l5 : 1);
    if (*hi < *lo + 0.1) { *lo -= l2; *hi += l2; } /* one value: 0.5x..2x */
}

/* A row is drawn when its x, y (and colour, if any) can be placed. */
static int row_ok(const layer *l, size_t i, int logx, int logy)
{
    if (l->band)
        return usable(l->x[i], l->lo[i], logx, logy) && usable(l->x[i], l->hi[i], logx, logy);
    if (!usable(l->x[i], l->y[i], logx, logy))
        return 0;
    return l->c == NULL || (isfinite(l->c[i]) && (!l->logc || l->c[i] > 0));
}

static void ext_scan(extent *e, layer *L, size_t nl, int logx, int logy,
                     double keyw)
{
    size_t ntitles = 0;
    memset(e, 0, sizeof *e);
    e->x0 = e->y0 = HUGE_VAL;
    e->x1 = e->y1 = -HUGE_VAL;
    e->logx = logx;
    e->logy = logy;
    for (size_t k = 0; k < nl; k++) {
        ntitles += L[k].title != NULL;
        L[k].used = 0;
        for (size_t i = 0; i < L[k].n; i++) {
            if (!row_ok(&L[k], i, logx, logy)) continue;
            double u = ax(L[k].x[i], logx), v = ax(L[k].band ? L[k].lo[i] : L[k].y[i], logy);
            e->x0 = fmin(e->x0, u); e->x1 = fmax(e->x1, u);
            e->y0 = fmin(e->y0, v); e->y1 = fmax(e->y1, v);
            if (L[k].band) {
                v = ax(L[k].hi[i], logy);
                e->y0 = fmin(e->y0, v); e->y1 = fmax(e->y1, v);
            }
            L[k].used++;
        }
        e->n += L[k].used;
    }
    if (e->n == 0) return;
    if (logx) nice_log(&e->x0, &e->x1);
    if (logy) nice_log(&e->y0, &e->y1);
    e->kw = keyw;
    e->kh = fmin(0.5, 0.075 * (double)(ntitles + 1));
}

static double frac(double v, double lo, double hi)
{
    return hi > lo ? (v - lo) / (hi - lo) : 0.5;
}

/* Datablocks $<name>0, $<name>1, ... holding the usable rows; each row
 * is counted against the corner boxes on the way. */
static void put_blocks(FILE *f, const char *name, const layer *L, size_t nl,
                       extent *e)
{
    for (size_t k = 0; k < nl; k++) {
        int gap = 0;
        fprintf(f, "$%s%zu << EOD\n", name, k);
        for (size_t i = 0; i < L[k].n; i++) {
            double x = L[k].x[i], y = L[k].band ? L[k].hi[i] : L[k].y[i];
            if (!row_ok(&L[k], i, e->logx, e->logy)) {
                if (gap) fputs("\n", f); /* a blank line breaks a line */
                gap = 0;
                continue;
            }
            gap = 1;
            double u = frac(ax(x, e->logx), e->x0, e->x1);
            double v = frac(ax(y, e->logy), e->y0, e->y1);
            int r = u >= 1 - e->kw, l = u <= e->kw;
            int t = v >= 1 - e->kh, b = v <= e->kh;
            e->corner[0] += (size_t)(t && r);
            e->corner[1] += (size_t)(t && l);
            e->corner[2] += (size_t)(b && l);
            e->corner[3] += (size_t)(b && r);
            fprintf(f, "%.17g %.17g", x, y);
            if (L[k].lo != NULL) { /* a bad quartile draws no bar */
                double lo = L[k].lo[i], hi = L[k].hi[i];
                fprintf(f, " %.17g %.17g", usable(x, lo, 0, e->logy) ? lo : y,
                        usable(x, hi, 0, e->logy) ? hi : y);
            }
            if (L[k].c != NULL)
                fprintf(f, " %.17g", L[k].c[i]);
            fputs("\n", f);
        }
        fputs("EOD\n", f);
    }
}

/* Log axes get the range the corner count assumed (dfle_gp_log_axis). */
void dfle_gp_log_axis(FILE *f, char c, double lo, double hi, int labels)
{
    static const double mant[5] = {1, 2, 3, 5, 7};
    double span = hi - lo;
    /* Tics of tiny or huge values read better as 2×10^{-4} than 0.0002. */
    const char *small = hi < -2 || lo >= 4 ? "%.0t×10^{%T}" : "%g";
    fprintf(f, "set logscale %c 10\nset m%ctics 10\nset %crange [%.17g:"
            "%.17g]\nset format %c '%s'\n", c, c, c, pow(10, lo),
            pow(10, hi), c, !labels ? "" : span >= 2 ? "10^{%L}" : small);
    if (span >= 2) {
        fprintf(f, "set %ctics autofreq\n", c);
        return;
    }
    if (span < 0.5) {
        /* Under half a decade 1, 2, 5 x 10^n leave one tic or none: take
         * 3 to 6 evenly spaced round values, 1, 2 or 5 times a power of 10. */
        double v0 = pow(10, lo), v1 = pow(10, hi), raw = (v1 - v0) / 4;
        double p10 = pow(10, floor(log10(raw))), step = raw / p10 < 1.5 ? p10
                     : raw / p10 < 3.5 ? 2 * p10 : raw / p10 < 7.5 ? 5 * p10 : 10 * p10;
        int dec = (int)floor(log10(v1)) - (int)floor(log10(step));
        char fmt[32];
        if (dec < 0)
            dec = 0;
        if (hi < -2 || lo >= 4)
            snprintf(fmt, sizeof fmt, "%%.%dt×10^{%%T}", dec);
        else
            snprintf(fmt, sizeof fmt, "%%g");
        fprintf(f, "set format %c '%s'\nset %ctics (", c, labels ? fmt : "", c);
        for (double v = ceil(v0 / step) * step, k = 0; v <= v1 * (1 + 1e-12); v += step, k++)
            fprintf(f, "%s%.17g", k > 0 ? ", " : "", v);
        fputs(")\n", f);
        return;
    }
    const char *sep = "(";
    fprintf(f, "set %ctics ", c);
    for (double d = floor(lo); d <= ceil(hi); d++)
        for (int m = 0; m < 5; m++) {
            double v = log10(mant[m]) + d;
            if ((span >= 1 && (m == 2 || m == 4)) || v < lo - 1e-9 ||
                v > hi + 1e-9) continue;
            fprintf(f, "%s%.17g", sep, mant[m] * pow(10, d));
            sep = ", ";
        }
    fputs(*sep == '(' ? "autofreq\n" : ")\n", f);
}

static void put_axes(FILE *f, const extent *e)
{
    if (e->logx)
        dfle_gp_log_axis(f, 'x', e->x0, e->x1, 1);
    if (e->logy)
        dfle_gp_log_axis(f, 'y', e->y0, e->y1, 1);
    fprintf(f, "set grid xtics ytics%s%s back ls 81, ls 82\n",
            e->logx ? " mxtics" : "", e->logy ? " mytics" : "");
}

static void put_label(FILE *f, const char *what, const char *text)
{
    if (text == NULL) return;
    fprintf(f, "set %s ", what);
    dfle_gp_str(f, text);
    fputs("\n", f);
}

/* The key, in the emptiest corner, then the plot command. */
static void put_plot(FILE *f, const char *name, const layer *L, size_t nl,
                     const extent *e)
{
    static const char *const where[4] = {"top right", "top left",
                                         "bottom left", "bottom right"};
    int best = 0, titled = 0, first = 1;
    for (int i = 1; i < 4; i++)
        if (e->corner[i] < e->corner[best]) best = i;
    for (size_t k = 0; k < nl; k++) titled |= L[k].title != NULL;
    if (titled)
        fprintf(f, "set key inside %s Left reverse opaque box lt 1 lc rgb "
                "'#b0b0b0' lw 0.8 samplen 2.5 spacing 1.15 width 1 height "
                "0.5\n", where[best]);
    else
        fputs("unset key\n", f);
    fputs("plot", f);
    for (size_t k = 0; k < nl; k++) {
        if (L[k].used == 0) continue; /* gnuplot refuses an empty block */
        if (L[k].c != NULL) /* colour from the palette, by the third column */
            fprintf(f, "%s $%s%zu using 1:2:3 with %s lc palette", first ? "" : ",", name, k,
                    L[k].with);
        else
            fprintf(f, "%s $%s%zu using %s with %s lc rgb '%s'", first ? "" :
                    ",", name, k, L[k].band ? "1:3:4" : L[k].lo ? "1:2:3:4" : "1:2",
                    L[k].with, L[k].color);
        if (L[k].title != NULL) { fputs(" title ", f); dfle_gp_str(f, L[k].title); }
        else fputs(" notitle", f);
        first = 0;
    }
    fputs("\n", f);
}

/* Series with a colour value per point share one perceptually uniform
 * scale (viridis-like) with a labelled colour box. */
static void put_colour(FILE *f, const layer *L, size_t nl, const char *label)
{
    int any = 0, logc = 0;
    for (size_t k = 0; k < nl; k++)
        if (L[k].c != NULL) {
            any = 1;
            logc |= L[k].logc;
        }
    if (!any) return;
    fputs("set palette defined (0 '#440154', 0.25 '#3b528b', 0.5 '#21918c', "
          "0.75 '#5ec962', 1 '#fde725')\nset colorbox\n", f);
    if (logc) fputs("set logscale cb 10\nset format cb '%g'\n", f);
    put_label(f, "cblabel", label);
}

/* A whole single-panel figure; `extra` goes in just before "plot". */
static int figure(const char *path, int fmt, int w, int h, const char *title,
                  const char *xl, const char *yl, const char *cl, extent *e,
                  const layer *L, size_t nl, const char *extra,
                  dfle_error *err)
{
    dfle_gp_run r;
    int rc = dfle_gp_begin(&r, path, fmt, w, h, err);
    if (rc < 0) return rc;
    put_blocks(r.f, "d", L, nl, e);
    put_label(r.f, "title", title);
    put_label(r.f, "xlabel", xl);
    put_label(r.f, "ylabel", yl);
    put_axes(r.f, e);
    put_colour(r.f, L, nl, cl);
    if (extra != NULL) fputs(extra, r.f);
    put_plot(r.f, "d", L, nl, e);
    return dfle_gp_end(&r, err);
}

int dfle_plot_xy(const char *path, const dfle_plot_opts *opts,
                 const dfle_plot_series *series, size_t nseries,
                 dfle_error *err)
{
    static const dfle_plot_opts none = {0};
    enum { NPAL = DFLE_GP_NPALETTE };
    const dfle_plot_opts *o = opts != NULL ? opts : &none;
    int fmt = dfle_gp_format(path, err);
    if (fmt < 0) return fmt;
    int w = o->width > 0 ? o->width : 900, h = o->height > 0 ? o->height : 600;
    if (w < 64 || h < 64 || w > 10000 || h > 10000)
        return dfle_error_set(err, DFLE_EINVAL, "plot: image size %dx%d "
                              "outside 64..10000 pixels", w, h);
    if (series == NULL || nseries == 0)
        return dfle_error_set(err, DFLE_EINVAL, "plot: no series to plot");
    for (size_t k = 0; k < nseries; k++) {
        const dfle_plot_series *q = &series[k];
        int band = q->lo != NULL || q->hi != NULL;
        if (q->n > 0 && (q->x == NULL || (!band && q->y == NULL) ||
                         (band && (q->lo == NULL || q->hi == NULL))))
            return dfle_error_set(err, DFLE_EINVAL, "plot: series %zu has "
                                  "NULL x or y (or only one of lo, hi)", k);
    }
    layer *L = malloc(nseries * sizeof *L);
    if (L == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
    for (size_t k = 0; k < nseries; k++) {
        const dfle_plot_series *s = &series[k];
        int band = s->lo != NULL;
        L[k] = (layer){s->n, s->x, band ? s->hi : s->y, s->lo, s->hi,
                       band ? "filledcurves fs transparent solid 0.3 noborder"
                       : s->lines ? (s->dash ? "lines lw 2 dt 2" : "lines lw 2")
                       : "points pt 7 ps 0.6",
                       s->rgb != NULL ? s->rgb : dfle_gp_palette[k % NPAL], s->label, 0,
                       band ? NULL : s->c, o->logc != 0, band};
    }
    extent e;
    int rc;
    ext_scan(&e, L, nseries, o->logx != 0, o->logy != 0, 0.4);
    if (e.n == 0)
        rc = dfle_error_set(err, DFLE_EINVAL, "plot: no finite points%s to "
                            "plot in '%s'", e.logx || e.logy ?
                            " (positive on log axes)" : "", path);
    else
        rc = figure(path, fmt, w, h, o->title, o->xlabel, o->ylabel, o->clabel, &e, L,
                    nseries, NULL, err);
    free(L);
    return rc;
}

/* Eq. (2), S = S_df / (1 + (A/A_df)^a2), here rather than from
 * analysis.c so that plotting does not depend on the fitting code. */
static double eq2(const dfle_eq2_fit *fit, double A)
{
    return fit->S_df / (1.0 + pow(A / fit->A_df, fit->a2));
}

/* v for a legend: 3 significant digits; large or small values as
 * "1.2×10^{4}" (enhanced text). */
void dfle_gp_number(char *buf, size_t cap, double v)
{
    double a = fabs(v);
    if (a == 0 || (a >= 1e-3 && a < 1e4)) {
        snprintf(buf, cap, "%.3g", v);
        return;
    }
    char m[16];
    snprintf(m, sizeof m, "%.2e", v); /* rounds the mantissa for us */
    char *ep = strchr(m, 'e');
    int ex = (int)strtol(ep + 1, NULL, 10);
    *ep = '\0';
    while (ep > m && (ep[-1] == '0' || ep[-1] == '.')) *--ep = '\0';
    snprintf(buf, cap, "%s×10^{%d}", m, ex);
}

int dfle_plot_slope_area(const char *path, const char *title, size_t n,
                         const double *A, const double *S,
                         const dfle_bins *bins, const dfle_eq2_fit *fit,
                         dfle_error *err)
{
    int fmt = dfle_gp_format(path, err);
    if (fmt < 0) return fmt;
    if (n == 0 || A == NULL || S == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "plot: slope-area data "
                              "missing (n = %zu, A or S NULL)", n);
    if (bins != NULL && bins->n > 0 && (bins->A == NULL || !bins->S_mean))
        return dfle_error_set(err, DFLE_EINVAL, "plot: bins have NULL A or "
                              "S_mean");
    if (fit != NULL && !(isfinite(fit->S_df) && fit->S_df > 0 &&
                         isfinite(fit->A_df) && fit->A_df > 0 &&
                         isfinite(fit->a2)))
        return dfle_error_set(err, DFLE_EINVAL, "plot: fit cannot be drawn "
                              "(S_df = %g, A_df = %g, a2 = %g)", fit->S_df,
                              fit->A_df, fit->a2);
    double amin = HUGE_VAL, amax = -HUGE_VAL;
    for (size_t i = 0; i < n; i++)
        if (usable(A[i], S[i], 1, 1)) {
            amin = fmin(amin, A[i]);
            amax = fmax(amax, A[i]);
        }
    if (amin > amax)
        return dfle_error_set(err, DFLE_EINVAL, "plot: no slope-area pair "
                              "with finite A > 0 and S > 0 for '%s'", path);

    layer L[4];
    size_t nl = 0;
    L[nl++] = (layer){n, A, S, NULL, NULL, "points pt 7 ps 0.35", "#a8a8a8",
                      "Data", 0, NULL, 0, 0};
    if (bins != NULL && bins->n > 0) {
        int bars = bins->S_q25 != NULL && bins->S_q75 != NULL;
        L[nl++] = (layer){bins->n, bins->A, bins->S_mean,
                          bars ? bins->S_q25 : NULL, bars ? bins->S_q75 : NULL,
                          bars ? "yerrorbars pt 7 ps 1 lw 1" : "points pt 7 ps 1",
                          "#000000", bars ? "Binned mean (quartiles)"
                          : "Binned mean", 0, NULL, 0, 0};
    }
    /* The curve spans the data's areas; A_df is marked only inside it. */
    double fa[FIT_SAMPLES], fs[FIT_SAMPLES], mark_a = 0, mark_s = 0;
    char ftitle[320] = "", mtitle[96] = "", extra[200] = "";
    if (fit != NULL) {
        char sdf[40], adf[40], a2[40], r2[32] = "";
        for (int i = 0; i < FIT_SAMPLES; i++) {
            fa[i] = amin * pow(amax / amin, i / (FIT_SAMPLES - 1.0));
            fs[i] = eq2(fit, fa[i]);
        }
        dfle_gp_number(sdf, sizeof sdf, fit->S_df);
        dfle_gp_number(adf, sizeof adf, fit->A_df);
        dfle_gp_number(a2, sizeof a2, fit->a2);
        if (isfinite(fit->r2))
            snprintf(r2, sizeof r2, ", {/:Italic R}^2 = %.3f", fit->r2);
        int mark = fit->A_df >= amin && fit->A_df <= amax;
        snprintf(ftitle, sizeof ftitle, "Eq. (2): {/:Italic S}_{df} = %s, "
                 "{/:Italic a}_2 = %s%s%s%s%s", sdf, a2, r2,
                 mark ? "" : ", {/:Italic A}_{df} = ", mark ? "" : adf,
                 mark ? "" : " m^2");
        L[nl++] = (layer){FIT_SAMPLES, fa, fs, NULL, NULL, "lines lw 2.5",
                          "#d01c1c", ftitle, 0, NULL, 0, 0};
        if (mark) { /* as in the paper's Fig. 1: open circle at (A_df,
                     * S_df/2) on the curve and a dashed line at A_df */
            mark_a = fit->A_df;
            mark_s = eq2(fit, fit->A_df);
            snprintf(mtitle, sizeof mtitle, "{/:Italic A}_{df} = %s m^2", adf);
            L[nl++] = (layer){1, &mark_a, &mark_s, NULL, NULL,
                              "points pt 6 ps 2.2 lw 2", "#d01c1c", mtitle, 0, NULL, 0, 0};
            snprintf(extra, sizeof extra, "set arrow from %.17g, graph 0 to "
                     "%.17g, graph 1 nohead dt 2 lw 1 lc rgb '#d01c1c' back\n",
                     mark_a, mark_a);
        }
    }
    extent e;
    ext_scan(&e, L, nl, 1, 1, 0.55);
    return figure(path, fmt, 900, 650, title,
                  "Drainage area, {/:Italic A} (m^2)", "Slope, {/:Italic S}", NULL,
                  &e, L, nl, extra, err);
}

int dfle_plot_profile(const char *path, const char *title, size_t n,
                      const double *x, const double *z, const double *S,
                      dfle_error *err)
{
    int fmt = dfle_gp_format(path, err);
    if (fmt < 0) return fmt;
    if (n == 0 || x == NULL || z == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "plot: profile data missing "
                              "(n = %zu, x or z NULL)", n);
    layer top = {n, x, z, NULL, NULL, "lines lw 2", "#1f3b73", NULL, 0, NULL, 0, 0};
    layer bot = {n, x, S, NULL, NULL, "lines lw 1.6", "#D55E00", NULL, 0, NULL, 0, 0};
    extent et, eb;
    ext_scan(&et, &top, 1, 0, 0, 0);
    if (et.n == 0)
        return dfle_error_set(err, DFLE_EINVAL, "plot: no profile point with "
                              "finite x and z for '%s'", path);
    const char *xl = "Distance from channel head, {/:Italic x} (m)";
    if (S == NULL)
        return figure(path, fmt, 900, 500, title, xl,
                      "Elevation, {/:Italic z} (m)", NULL, &et, &top, 1, NULL, err);
    int logS = 1; /* log slope axis unless some finite slope is <= 0 */
    for (size_t i = 0; i < n; i++)
        if (isfinite(x[i]) && isfinite(S[i]) && S[i] <= 0) logS = 0;
    ext_scan(&eb, &bot, 1, 0, logS, 0);
    if (eb.n == 0)
        return dfle_error_set(err, DFLE_EINVAL, "plot: no profile point "
                              "with finite x and S for '%s'", path);
    /* Both panels share one fixed x range, so their frames line up. */
    double x0 = fmin(et.x0, eb.x0), x1 = fmax(et.x1, eb.x1);
    dfle_gp_run r;
    int rc = dfle_gp_begin(&r, path, fmt, 900, 750, err);
    if (rc < 0) return rc;
    put_blocks(r.f, "z", &top, 1, &et);
    put_blocks(r.f, "s", &bot, 1, &eb);
    if (x1 > x0) fprintf(r.f, "set xrange [%.17g:%.17g]\n", x0, x1);
    put_label(r.f, "title", title);
    put_axes(r.f, &et);
    /* Fixed margins line the frames up; the y labels are placed on the
     * screen, not beside the tic labels, so they line up too. */
    double ttop = title ? 0.92 : 0.96;
    fprintf(r.f, "set multiplot\nset lmargin at screen 0.11\n"
            "set rmargin at screen 0.96\nset tmargin at screen %g\n"
            "set bmargin at screen 0.555\nset format x ''\n"
            "set label 1 'Elevation, {/:Italic z} (m)' at screen 0.025, "
            "screen %g center rotate by 90\n", ttop, (ttop + 0.555) / 2);
    put_plot(r.f, "z", &top, 1, &et);
    fputs("unset title\nunset label 1\nset format x '% h'\n"
          "set tmargin at screen 0.50\nset bmargin at screen 0.09\n"
          "set label 2 'Slope, {/:Italic S}' at screen 0.025, screen 0.295 "
          "center rotate by 90\n", r.f);
    put_label(r.f, "xlabel", xl);
    put_axes(r.f, &eb);
    put_plot(r.f, "s", &bot, 1, &eb);
    fputs("unset multiplot\n", r.f);
    return dfle_gp_end(&r, err);
}

/* ---------------------------------------------------------------- */
/* Maps: shaded relief, channels, debris-flow reach                  */
/* ---------------------------------------------------------------- */

/* The hypsometric tint, in gnuplot's palette and in C alike. */
static const double tint_at[5] = {0.0, 0.25, 0.5, 0.75, 1.0};
static const unsigned tint_rgb[5] = {0x2f6b3a, 0x8fae5d, 0xd8c98e, 0xa9825a, 0xf4f1ea};

static double tint_channel(double f, int shift)
{
    int k = 0;
    while (k < 3 && f > tint_at[k + 1])
        k++;
    double u = (f - tint_at[k]) / (tint_at[k + 1] - tint_at[k]);
    double a = (tint_rgb[k] >> shift) & 255, b = (tint_rgb[k + 1] >> shift) & 255;
    return a + u * (b - a);
}

/* Horn's hillshade of cell (r, c) in [0, 1], from the neighbours that
 * have data (a missing one takes the centre's elevation). */
static double shade_at(const dfle_plot_map *m, size_t r, size_t c, size_t step)
{
    double zz[3][3], zc = m->z[r * m->nx + c];
    for (int i = -1; i <= 1; i++)
        for (int j = -1; j <= 1; j++) {
            long long rr = (long long)r + i * (long long)step, cc = (long long)c + j * (long long)step;
            double v = zc;
            if (rr >= 0 && cc >= 0 && rr < (long long)m->ny && cc < (long long)m->nx &&
                !isnan(m->z[rr * (long long)m->nx + cc]))
                v = m->z[rr * (long long)m->nx + cc];
            zz[i + 1][j + 1] = v;
        }
    /* ESRI's formulation: rows of zz run north to south. */
    const double pi = 3.14159265358979323846;
    const double zenith = (90.0 - 45.0) * pi / 180.0, azimuth = (360.0 - 315.0 + 90.0) * pi / 180.0;
    double hx = 8.0 * m->dx * (double)step, hy = 8.0 * m->dy * (double)step;
    double dzdx = ((zz[0][2] + 2 * zz[1][2] + zz[2][2]) - (zz[0][0] + 2 * zz[1][0] + zz[2][0])) / hx;
    double dzdy = ((zz[2][0] + 2 * zz[2][1] + zz[2][2]) - (zz[0][0] + 2 * zz[0][1] + zz[0][2])) / hy;
    double slope = atan(hypot(dzdx, dzdy)), aspect = atan2(dzdy, -dzdx);
    double v = cos(zenith) * cos(slope) + sin(zenith) * sin(slope) * cos(azimuth - aspect);
    return v < 0 ? 0 : v > 1 ? 1 : v;
}

int dfle_plot_hillshade(const char *path, const dfle_plot_map *m, dfle_error *err)
{
    int fmt = dfle_gp_format(path, err);
    double zmin = HUGE_VAL, zmax = -HUGE_VAL;
    size_t step = 1, cols, rows;
    if (fmt < 0) return fmt;
    if (m == NULL || m->z == NULL || m->nx < 2 || m->ny < 2 || !(m->dx > 0) || !(m->dy > 0))
        return dfle_error_set(err, DFLE_EINVAL, "plot: a map needs at least 2 x 2 cells of "
                              "positive size and elevations");
    for (size_t i = 0; i < m->nx * m->ny; i++)
        if (!isnan(m->z[i])) {
            zmin = fmin(zmin, m->z[i]);
            zmax = fmax(zmax, m->z[i]);
        }
    if (zmin > zmax)
        return dfle_error_set(err, DFLE_EINVAL, "plot: every cell of the map is NoData");
    /* The map frames the data: the box of the cells with elevations. */
    size_t r0 = m->ny, r1 = 0, c0 = m->nx, c1 = 0;
    for (size_t i = 0; i < m->nx * m->ny; i++)
        if (!isnan(m->z[i])) {
            size_t rr = i / m->nx, cc = i % m->nx;
            r0 = rr < r0 ? rr : r0, r1 = rr > r1 ? rr : r1;
            c0 = cc < c0 ? cc : c0, c1 = cc > c1 ? cc : c1;
        }
    while ((m->nx / step) * (m->ny / step) > 1500000)
        step++;
    cols = (m->nx + step - 1) / step;
    rows = (m->ny + step - 1) / step;
    /* Pixels: the map's aspect, about 900 wide plus room for the key. */
    double wkm = (double)(c1 - c0 + 1) * m->dx, hkm = (double)(r1 - r0 + 1) * m->dy;
    int w = 1000, h = (int)(80 + 820.0 * hkm / wkm);
    if (h > 1400) { h = 1400; w = (int)(150 + 1250.0 * wkm / hkm); }
    if (h < 400) h = 400;
    dfle_gp_run r;
    int rc = dfle_gp_begin(&r, path, fmt, w, h, err);
    if (rc < 0) return rc;
    /* One packed RGB value per cell (0xRRGGBB), a matrix datablock. */
    fputs("$img << EOD\n", r.f);
    for (size_t rr = 0; rr < rows; rr++) {
        for (size_t cc = 0; cc < cols; cc++) {
            size_t i = rr * step * m->nx + cc * step;
            unsigned rgb = 0xffffff;
            if (!isnan(m->z[i])) {
                double f = zmax > zmin ? (m->z[i] - zmin) / (zmax - zmin) : 0.5;
                double sh = 0.35 + 0.65 * shade_at(m, rr * step, cc * step, step);
                unsigned R = (unsigned)(tint_channel(f, 16) * sh), G = (unsigned)(tint_channel(f, 8) * sh),
                         B = (unsigned)(tint_channel(f, 0) * sh);
                if (m->channel != NULL && m->channel[i] > 0) R = 0x00, G = 0x72, B = 0xB2;
                if (m->reach != NULL && m->reach[i] > 0) R = 0xD5, G = 0x5E, B = 0x00;
                rgb = (R << 16) | (G << 8) | B;
            }
            fprintf(r.f, "%s%u", cc ? " " : "", rgb);
        }
        fputs("\n", r.f);
    }
    fputs("EOD\n", r.f);
    /* A 2 x 2 image off the map gives the colour box its scale. */
    {
        double fx = m->x0 / 1000 - 1e6, fy = m->y0 / 1000 + 1e6;
        fprintf(r.f, "$cb << EOD\n%.17g %.17g %.17g\n%.17g %.17g %.17g\n\n%.17g %.17g %.17g\n"
                "%.17g %.17g %.17g\nEOD\n", fx, fy, zmin, fx + 1, fy, zmax, fx, fy + 1, zmin,
                fx + 1, fy + 1, zmax);
    }
    put_label(r.f, "title", m->title);
    fputs("set xlabel 'Easting (km)'\nset ylabel 'Northing (km)'\n", r.f);
    fputs("set size ratio -1\nset tics out nomirror\nset format x '%.1f'\nset format y '%.1f'\n", r.f);
    fprintf(r.f, "set xrange [%.17g:%.17g]\nset yrange [%.17g:%.17g]\n",
            (m->x0 + (double)c0 * m->dx) / 1000, (m->x0 + (double)(c1 + 1) * m->dx) / 1000,
            (m->y0 - (double)(r1 + 1) * m->dy) / 1000, (m->y0 - (double)r0 * m->dy) / 1000);
    fprintf(r.f, "set cbrange [%.17g:%.17g]\nset cblabel 'Elevation (m)'\nset colorbox\n", zmin,
            zmax > zmin ? zmax : zmin + 1);
    fputs("set palette defined (", r.f);
    for (int k = 0; k < 5; k++)
        fprintf(r.f, "%s%g '#%06x'", k ? ", " : "", tint_at[k], tint_rgb[k]);
    fputs(")\n", r.f);
    fputs("set bmargin 6\nset key at screen 0.5, screen 0.015 center bottom horizontal Left "
          "reverse samplen 1.5 spacing 1.2 width 2 box lt 1 lc rgb '#b0b0b0'\n", r.f);
    /* Cell centres in km: column c at x0 + (c + 0.5) dx (every step-th). */
    double sx = m->dx * (double)step / 1000, sy = m->dy * (double)step / 1000;
    fprintf(r.f, "plot $img matrix using (%.17g + ($1 + 0.5) * %.17g):(%.17g - ($2 + 0.5) * "
            "%.17g):(int($3) >> 16 & 255):(int($3) >> 8 & 255):(int($3) & 255) with rgbimage "
            "notitle, ", m->x0 / 1000, sx, m->y0 / 1000, sy);
    fputs("$cb using 1:2:3 with image notitle", r.f); /* the colour box's scale */
    if (m->channel != NULL) {
        fputs(", NaN with lines lw 6 lc rgb '#0072B2' title ", r.f);
        dfle_gp_str(r.f, m->channel_label != NULL ? m->channel_label : "Channel network");
    }
    if (m->reach != NULL) {
        fputs(", NaN with lines lw 6 lc rgb '#D55E00' title ", r.f);
        dfle_gp_str(r.f, m->reach_label != NULL ? m->reach_label : "Debris-flow reach");
    }
    fputs("\n", r.f);
    return dfle_gp_end(&r, err);
}
