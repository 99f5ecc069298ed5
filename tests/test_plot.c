/*
 * test_plot.c - figures through gnuplot: the files are really written,
 * hostile paths and labels are quoted, and every failure is a status and
 * a message rather than a crash, a stray file or noise on stderr.
 *
 * Each test gets its own temporary directory (mkdtemp), emptied and
 * removed by the teardown.  Tests that change DFLE_GNUPLOT put the old
 * value back.
 */
#ifndef _POSIX_C_SOURCE /* mkdtemp, setenv, strdup, dup2 */
#define _POSIX_C_SOURCE 200809L
#endif
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "dfle/plot.h"
#include "dfle_test.h"

typedef struct fixture {
    char dir[64];
    char path[512];
} fixture;

static int setup(void **state)
{
    fixture *fx = calloc(1, sizeof *fx);
    if (fx == NULL) return -1;
    strcpy(fx->dir, "/tmp/dfle-test-plot-XXXXXX");
    if (mkdtemp(fx->dir) == NULL) {
        free(fx);
        return -1;
    }
    *state = fx;
    return 0;
}

static int teardown(void **state)
{
    fixture *fx = *state;
    DIR *d = opendir(fx->dir);
    struct dirent *de;
    char p[600];
    while (d != NULL && (de = readdir(d)) != NULL) {
        if (strcmp(de->d_name, ".") == 0 || strcmp(de->d_name, "..") == 0)
            continue;
        snprintf(p, sizeof p, "%s/%s", fx->dir, de->d_name);
        unlink(p);
    }
    if (d != NULL) closedir(d);
    int rc = rmdir(fx->dir);
    free(fx);
    return rc;
}

/* fx->path = <dir>/<name> */
static const char *in_dir(fixture *fx, const char *name)
{
    snprintf(fx->path, sizeof fx->path, "%s/%s", fx->dir, name);
    return fx->path;
}

static size_t dir_entries(const fixture *fx)
{
    DIR *d = opendir(fx->dir);
    size_t k = 0;
    struct dirent *de;
    while (d != NULL && (de = readdir(d)) != NULL)
        k += strcmp(de->d_name, ".") != 0 && strcmp(de->d_name, "..") != 0;
    if (d != NULL) closedir(d);
    return k;
}

/* First `cap` bytes of a file; returns how many were read (0 if none). */
static size_t head(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) return 0;
    size_t k = fread(buf, 1, cap, f);
    fclose(f);
    return k;
}

static void assert_png(const char *path)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n',
                                         0x1a, '\n'};
    char buf[8];
    struct stat sb;
    assert_int_equal(stat(path, &sb), 0);
    assert_true(sb.st_size > 1000);
    assert_int_equal(head(path, buf, sizeof buf), 8);
    assert_memory_equal(buf, sig, 8);
}

static void assert_svg(const char *path)
{
    char buf[4096];
    size_t k = head(path, buf, sizeof buf - 1);
    buf[k] = '\0';
    assert_true(k > 100);
    assert_true(strncmp(buf, "<?xml", 5) == 0 || strstr(buf, "<svg") != NULL);
}

static void assert_missing(const char *path)
{
    struct stat sb;
    assert_int_not_equal(stat(path, &sb), 0);
}

/* Slope-area data shaped like the paper's Fig. 1, with Eq. (2) bins. */
enum { NPTS = 400, NBINS = 20 };
static double sa_A[NPTS], sa_S[NPTS];
static double b_A[NBINS], b_lo[NBINS], b_hi[NBINS], b_S[NBINS];
static double b_q25[NBINS], b_q75[NBINS];
static size_t b_cnt[NBINS];

static void make_slope_area(dfle_bins *bins, dfle_eq2_fit *fit)
{
    for (int i = 0; i < NPTS; i++) {
        double x = 5.0 * i;
        sa_A[i] = 1000 + 25 * pow(x, 5.0 / 3.0);
        sa_S[i] = 0.7 / (1 + pow(sa_A[i] / 2e4, 1.2)) * (1 + 0.2 * sin(i));
    }
    for (int j = 0; j < NBINS; j++) {
        b_lo[j] = 1000 * pow(8000.0, j / (double)NBINS);
        b_hi[j] = 1000 * pow(8000.0, (j + 1) / (double)NBINS);
        b_A[j] = sqrt(b_lo[j] * b_hi[j]);
        b_S[j] = 0.7 / (1 + pow(b_A[j] / 2e4, 1.2));
        b_q25[j] = 0.8 * b_S[j];
        b_q75[j] = 1.2 * b_S[j];
        b_cnt[j] = 10;
    }
    b_q25[3] = NAN; /* a bin without quartiles must not break the plot */
    *bins = (dfle_bins){NBINS, NBINS, 0, b_A, b_lo, b_hi, b_S, b_S,
                        b_q25, b_q75, b_S, b_cnt};
    *fit = (dfle_eq2_fit){0};
    fit->S_df = 0.7;
    fit->A_df = 2e4;
    fit->a2 = 1.2;
    fit->r2 = 0.987;
}

static void test_xy_png(void **state)
{
    fixture *fx = *state;
    double x[50], y1[50], y2[50];
    for (int i = 0; i < 50; i++) {
        x[i] = i;
        y1[i] = sqrt(i);
        y2[i] = 0.1 * i;
    }
    y1[10] = NAN; /* a gap, not a failure */
    dfle_plot_series s[2] = {{"sqrt", 50, x, y1, 1, NULL, NULL, NULL, NULL, 0},
                             {NULL, 50, x, y2, 0, NULL, NULL, NULL, NULL, 0}};
    dfle_plot_opts o = {"Title", "x (m)", "y", 0, 0, 640, 480, NULL, 0};
    dfle_error err = {0};
    assert_ok(dfle_plot_xy(in_dir(fx, "xy.png"), &o, s, 2, &err), &err);
    assert_png(fx->path);
    assert_ok(dfle_plot_xy(in_dir(fx, "xy_default.png"), NULL, s, 1, &err),
              &err);
    assert_png(fx->path);
}

/* A colour value per point: a third column drawn on a palette with a
 * colour box; points whose colour cannot be placed are left out. */
static void test_xy_colour(void **state)
{
    fixture *fx = *state;
    double x[40], y[40], c[40];
    for (int i = 0; i < 40; i++) {
        x[i] = i;
        y[i] = 0.5 * i;
        c[i] = 1.0 + i;
    }
    c[3] = NAN; /* left out, not a failure */
    dfle_plot_series s = {"coloured", 40, x, y, 0, c, NULL, NULL, NULL, 0};
    dfle_plot_opts o = {"colour", "x", "y", 0, 0, 0, 0, "U (m/yr)", 1};
    dfle_error err = {0};
    assert_ok(dfle_plot_xy(in_dir(fx, "colour.png"), &o, &s, 1, &err), &err);
    assert_png(fx->path);
    /* On a log colour scale no point with a colour <= 0 can be placed. */
    for (int i = 0; i < 40; i++)
        c[i] = -1.0;
    assert_int_equal(dfle_plot_xy(in_dir(fx, "colour2.png"), &o, &s, 1, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "no finite points");
}

static void test_xy_log_svg(void **state)
{
    fixture *fx = *state;
    double x[5] = {-1, 1, 10, 100, 1000}, y[5] = {1, 0, 2, 3, 4};
    dfle_plot_series s = {"log", 5, x, y, 1, NULL, NULL, NULL, NULL, 0};
    dfle_plot_opts o = {NULL, NULL, NULL, 1, 1, 0, 0, NULL, 0};
    dfle_error err = {0};
    /* The points with x <= 0 or y <= 0 are dropped from the log plot. */
    assert_ok(dfle_plot_xy(in_dir(fx, "xy.svg"), &o, &s, 1, &err), &err);
    assert_svg(fx->path);
}

/* A band between lo and hi (filled, translucent) with a dashed line of
 * its own colour; lo without hi is refused. */
static void test_xy_band(void **state)
{
    fixture *fx = *state;
    double x[20], lo[20], hi[20], y[20];
    for (int i = 0; i < 20; i++) {
        x[i] = 1e3 * pow(10, i / 5.0);
        y[i] = 0.5 * pow(x[i] / 1e3, -0.3);
        lo[i] = 0.8 * y[i];
        hi[i] = 1.25 * y[i];
    }
    dfle_plot_series s[2] = {{"band", 20, x, NULL, 0, NULL, lo, hi, "#9ecae1", 0},
                             {"median", 20, x, y, 1, NULL, NULL, NULL, "#08306b", 1}};
    dfle_plot_opts o = {"Bands", "A", "S", 1, 1, 640, 480, NULL, 0};
    dfle_error err = {0};
    assert_ok(dfle_plot_xy(in_dir(fx, "band.png"), &o, s, 2, &err), &err);
    assert_png(fx->path);
    s[0].hi = NULL;
    assert_int_equal(dfle_plot_xy(in_dir(fx, "band2.png"), &o, s, 2, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "only one of lo, hi");
}

/* The corner plot of correlated samples, one axis logarithmic; too few
 * parameters or samples are refused before gnuplot starts. */
static void test_corner(void **state)
{
    fixture *fx = *state;
    enum { N = 3000 };
    static double x[N * 3];
    const char *labels[3] = {"{/:Italic U}", "{/Symbol g}", "k_{df}"};
    int logs[3] = {1, 0, 1};
    double truth[3] = {3e-4, 0.5, NAN};
    dfle_corner_opts o = {"Corner", labels, logs, truth, 120, 20};
    dfle_error err = {0};
    uint64_t st = 88172645463325252ULL;
    for (int i = 0; i < N; i++) {
        double u[3];
        for (int k = 0; k < 3; k++) { /* xorshift, then a sum of 4: roughly normal */
            double v = 0;
            for (int r = 0; r < 4; r++) {
                st ^= st << 13, st ^= st >> 7, st ^= st << 17;
                v += (double)(st >> 11) / 9007199254740992.0 - 0.5;
            }
            u[k] = v;
        }
        x[3 * i] = 3e-4 * exp(0.3 * u[0]);
        x[3 * i + 1] = 0.5 + 0.2 * (0.8 * u[0] + 0.6 * u[1]);
        x[3 * i + 2] = 1e-4 * exp(u[2] + u[1]);
    }
    assert_ok(dfle_plot_corner(in_dir(fx, "corner.png"), &o, 3, N, x, &err), &err);
    assert_png(fx->path);
    assert_ok(dfle_plot_corner(in_dir(fx, "corner.svg"), NULL, 2, N, x, &err), &err);
    assert_int_equal(dfle_plot_corner(in_dir(fx, "c0.png"), &o, 0, N, x, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_corner(in_dir(fx, "c1.png"), &o, 3, 1, x, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "at least 2 samples");
    assert_int_equal(dfle_plot_corner(in_dir(fx, "c.jpg"), &o, 3, N, x, &err), DFLE_EINVAL);
}

static void test_slope_area_png(void **state)
{
    fixture *fx = *state;
    dfle_bins bins;
    dfle_eq2_fit fit;
    dfle_error err = {0};
    make_slope_area(&bins, &fit);
    assert_ok(dfle_plot_slope_area(in_dir(fx, "sa.png"), "Fig. 1", NPTS, sa_A,
                                   sa_S, &bins, &fit, &err), &err);
    assert_png(fx->path);
    /* Raw points only, and with a fit whose A_df lies beyond the data. */
    assert_ok(dfle_plot_slope_area(in_dir(fx, "raw.png"), NULL, NPTS, sa_A,
                                   sa_S, NULL, NULL, &err), &err);
    assert_png(fx->path);
    fit.A_df = 1e9;
    bins.S_q25 = bins.S_q75 = NULL;
    assert_ok(dfle_plot_slope_area(in_dir(fx, "far.svg"), NULL, NPTS, sa_A,
                                   sa_S, &bins, &fit, &err), &err);
    assert_svg(fx->path);
}

static void test_profile_png(void **state)
{
    fixture *fx = *state;
    double x[100], z[100], S[100];
    for (int i = 0; i < 100; i++) {
        x[i] = 5.0 * i;
        S[i] = 0.5 / (1 + 0.05 * i);
    }
    z[99] = 0;
    for (int i = 98; i >= 0; i--) z[i] = z[i + 1] + 5 * S[i];
    S[99] = NAN; /* no downstream difference at the outlet */
    dfle_error err = {0};
    assert_ok(dfle_plot_profile(in_dir(fx, "p.png"), "Profile", 100, x, z, S,
                                &err), &err);
    assert_png(fx->path);
    assert_ok(dfle_plot_profile(in_dir(fx, "p1.png"), NULL, 100, x, z, NULL,
                                &err), &err);
    assert_png(fx->path);
    S[50] = -0.01; /* a reversed slope: linear slope axis, still a plot */
    assert_ok(dfle_plot_profile(in_dir(fx, "p2.svg"), NULL, 100, x, z, S,
                                &err), &err);
    assert_svg(fx->path);
}

/* Quotes, a space, backquotes and a leading '|' are all just characters
 * of the file name; nothing is run and nothing else is created. */
static void test_hostile_path(void **state)
{
    fixture *fx = *state;
    static const char *const names[] = {
        "my \"quoted\" plot.png", "it's `touch INJ` $HOME @x \\n.png",
        "|touch INJ2.png", "~x.svg"};
    double x[3] = {1, 2, 3}, y[3] = {3, 1, 2};
    dfle_plot_series s = {"a 'label' with `touch INJ3`\nand a new line", 3,
                          x, y, 1, NULL, NULL, NULL, NULL, 0};
    dfle_plot_opts o = {"it's \"fine\"", "x\\", "`touch INJ4`", 0, 0, 0, 0, NULL, 0};
    dfle_error err = {0};
    char cwd[4096];
    assert_non_null(getcwd(cwd, sizeof cwd));
    int rc = 0;
    assert_int_equal(chdir(fx->dir), 0); /* relative names, too */
    for (size_t k = 0; k < 4 && rc == 0; k++)
        rc = dfle_plot_xy(names[k], &o, &s, 1, &err);
    assert_int_equal(chdir(cwd), 0);
    assert_ok(rc, &err);
    assert_png(in_dir(fx, names[0]));
    assert_png(in_dir(fx, names[1]));
    assert_png(in_dir(fx, names[2]));
    assert_svg(in_dir(fx, names[3]));
    assert_int_equal(dir_entries(fx), 4);
}

static void test_bad_extension(void **state)
{
    fixture *fx = *state;
    static const char *const bad[] = {"plot.pdf", "plot", "dir.png/plot",
                                      "plot.png.txt"};
    double x[2] = {1, 2}, y[2] = {1, 2};
    dfle_plot_series s = {NULL, 2, x, y, 1, NULL, NULL, NULL, NULL, 0};
    dfle_error err = {0};
    for (size_t k = 0; k < 4; k++) {
        assert_int_equal(dfle_plot_xy(in_dir(fx, bad[k]), NULL, &s, 1, &err),
                         DFLE_EINVAL);
        assert_msg_contains(err.msg, fx->path);
        assert_msg_contains(err.msg, ".png or .svg");
    }
    assert_int_equal(dfle_plot_profile(in_dir(fx, "p.jpg"), NULL, 2, x, y,
                                       NULL, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "p.jpg");
    assert_int_equal(dfle_plot_slope_area(in_dir(fx, "s.eps"), NULL, 2, x, y,
                                          NULL, NULL, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "s.eps");
    assert_int_equal(dir_entries(fx), 0);
}

static void test_bad_arguments(void **state)
{
    fixture *fx = *state;
    double x[2] = {1, 2}, y[2] = {1, 2};
    dfle_plot_series s = {NULL, 2, x, y, 1, NULL, NULL, NULL, NULL, 0},
                     empty = {NULL, 0, NULL, NULL, 1, NULL, NULL, NULL, NULL, 0};
    dfle_plot_series nox = {NULL, 2, NULL, y, 1, NULL, NULL, NULL, NULL, 0};
    dfle_plot_opts tiny = {NULL, NULL, NULL, 0, 0, 10, 10, NULL, 0};
    dfle_eq2_fit fit = {0};
    dfle_error err = {0};
    const char *p = in_dir(fx, "a.png");
    assert_int_equal(dfle_plot_xy(NULL, NULL, &s, 1, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_xy("", NULL, &s, 1, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_xy(p, NULL, &s, 0, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_xy(p, NULL, NULL, 1, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_xy(p, NULL, &empty, 1, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_xy(p, NULL, &nox, 1, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "series 0");
    assert_int_equal(dfle_plot_xy(p, &tiny, &s, 1, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_slope_area(p, NULL, 0, x, y, NULL, NULL, &err),
                     DFLE_EINVAL);
    assert_int_equal(dfle_plot_slope_area(p, NULL, 2, NULL, y, NULL, NULL,
                                          &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_slope_area(p, NULL, 2, x, y, NULL, &fit, &err),
                     DFLE_EINVAL); /* S_df = A_df = 0 cannot be drawn */
    assert_int_equal(dfle_plot_profile(p, NULL, 0, x, y, NULL, &err),
                     DFLE_EINVAL);
    assert_int_equal(dfle_plot_profile(p, NULL, 2, x, NULL, NULL, &err),
                     DFLE_EINVAL);
    /* err may be NULL */
    assert_int_equal(dfle_plot_profile(p, NULL, 0, x, y, NULL, NULL),
                     DFLE_EINVAL);
    assert_int_equal(dir_entries(fx), 0);
}

static void test_nothing_finite(void **state)
{
    fixture *fx = *state;
    double nan3[3] = {NAN, NAN, NAN}, x[3] = {1, 2, 3}, neg[3] = {-1, 0, -2};
    dfle_plot_series s = {"nan", 3, x, nan3, 1, NULL, NULL, NULL, NULL, 0},
                     sn = {"neg", 3, x, neg, 0, NULL, NULL, NULL, NULL, 0};
    dfle_plot_opts logy = {NULL, NULL, NULL, 0, 1, 0, 0, NULL, 0};
    dfle_error err = {0};
    const char *p = in_dir(fx, "a.png");
    assert_int_equal(dfle_plot_xy(p, NULL, &s, 1, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "finite");
    assert_int_equal(dfle_plot_xy(p, &logy, &sn, 1, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_slope_area(p, NULL, 3, x, nan3, NULL, NULL,
                                          &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_slope_area(p, NULL, 3, x, neg, NULL, NULL,
                                          &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_profile(p, NULL, 3, x, nan3, NULL, &err),
                     DFLE_EINVAL);
    assert_int_equal(dfle_plot_profile(p, NULL, 3, x, x, nan3, &err),
                     DFLE_EINVAL);
    assert_int_equal(dir_entries(fx), 0);
}

static void test_unwritable(void **state)
{
    fixture *fx = *state;
    double x[2] = {1, 2}, y[2] = {1, 2};
    dfle_plot_series s = {NULL, 2, x, y, 1, NULL, NULL, NULL, NULL, 0};
    dfle_error err = {0};
    /* A regular file as a directory fails even for root. */
    int fd = open(in_dir(fx, "file"), O_WRONLY | O_CREAT, 0644);
    assert_true(fd >= 0);
    close(fd);
    assert_int_equal(dfle_plot_xy(in_dir(fx, "file/x.png"), NULL, &s, 1,
                                  &err), DFLE_EIO);
    assert_msg_contains(err.msg, fx->path);
    assert_int_equal(dfle_plot_profile(in_dir(fx, "no/such/dir/p.svg"), NULL,
                                       2, x, y, y, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "no/such/dir/p.svg");
    assert_int_equal(mkdir(in_dir(fx, "d.png"), 0755), 0);
    assert_int_equal(dfle_plot_xy(fx->path, NULL, &s, 1, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "d.png");
    rmdir(fx->path);
}

/* Run f with DFLE_GNUPLOT = prog, then put the old value back. */
static int with_gnuplot(const char *prog, int (*f)(fixture *, dfle_error *),
                        fixture *fx, dfle_error *err)
{
    const char *old = getenv("DFLE_GNUPLOT");
    char *saved = old != NULL ? strdup(old) : NULL;
    setenv("DFLE_GNUPLOT", prog, 1);
    int rc = f(fx, err);
    if (saved != NULL) setenv("DFLE_GNUPLOT", saved, 1);
    else unsetenv("DFLE_GNUPLOT");
    free(saved);
    return rc;
}

/* Enough data that writing it to a gnuplot that is not there raises
 * SIGPIPE, which must not kill the caller. */
static int plot_big(fixture *fx, dfle_error *err)
{
    enum { N = 100000 };
    double *x = malloc(N * sizeof *x);
    if (x == NULL) return -100;
    for (int i = 0; i < N; i++) x[i] = i + 1.0;
    int rc = dfle_plot_slope_area(in_dir(fx, "big.png"), NULL, N, x, x, NULL,
                                  NULL, err);
    free(x);
    return rc;
}

static void write_script(const char *path, const char *body)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(body, f);
    fclose(f);
    assert_int_equal(chmod(path, 0755), 0);
}

static void test_gnuplot_missing(void **state)
{
    fixture *fx = *state;
    dfle_error err = {0};
    /* gnuplot's (here: sh's) complaint goes into the message, never to
     * our stderr: check by pointing fd 2 at a file for the call. */
    int saved = dup(2);
    int efd = open(in_dir(fx, "stderr.txt"), O_WRONLY | O_CREAT, 0644);
    assert_true(saved >= 0 && efd >= 0);
    fflush(stderr);
    dup2(efd, 2);
    int rc = with_gnuplot("/nonexistent/gnuplot", plot_big, fx, &err);
    dup2(saved, 2);
    close(saved);
    close(efd);
    assert_int_equal(rc, DFLE_EEXTERNAL);
    assert_msg_contains(err.msg, "gnuplot could not be run");
    assert_msg_contains(err.msg, "/nonexistent/gnuplot");
    assert_msg_contains(err.msg, "apt-get install gnuplot-nox");
    assert_msg_contains(err.msg, "DFLE_GNUPLOT");
    struct stat sb;
    assert_int_equal(stat(in_dir(fx, "stderr.txt"), &sb), 0);
    assert_int_equal(sb.st_size, 0);
    assert_missing(in_dir(fx, "big.png")); /* no empty file left */
}

static int plot_small(fixture *fx, dfle_error *err)
{
    double x[3] = {1, 2, 3};
    dfle_plot_series s = {"s", 3, x, x, 1, NULL, NULL, NULL, NULL, 0};
    return dfle_plot_xy(in_dir(fx, "small.png"), NULL, &s, 1, err);
}

static void test_gnuplot_fails(void **state)
{
    fixture *fx = *state;
    char prog[600];
    dfle_error err = {0};
    /* A "gnuplot" that reads the script, complains and fails. */
    snprintf(prog, sizeof prog, "%s/bad gnuplot's", fx->dir);
    write_script(prog, "#!/bin/sh\ncat >/dev/null\n"
                       "echo 'line 3: boom, undefined thing' >&2\nexit 1\n");
    assert_int_equal(with_gnuplot(prog, plot_small, fx, &err), DFLE_EEXTERNAL);
    assert_msg_contains(err.msg, "boom, undefined thing");
    assert_missing(in_dir(fx, "small.png"));
    /* One that exits happily without writing an image. */
    write_script(prog, "#!/bin/sh\ncat >/dev/null\nexit 0\n");
    assert_int_equal(with_gnuplot(prog, plot_small, fx, &err), DFLE_EEXTERNAL);
    assert_msg_contains(err.msg, "wrote nothing");
    assert_missing(in_dir(fx, "small.png"));
    /* A wrapper with a space and a quote in its name that runs gnuplot. */
    write_script(prog, "#!/bin/sh\nexec gnuplot \"$@\"\n");
    assert_ok(with_gnuplot(prog, plot_small, fx, &err), &err);
    assert_png(in_dir(fx, "small.png"));
}

/* Bytes of a file, for comparing an image before and after. */
static long file_size(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 ? (long)sb.st_size : -1;
}

/* A disk that fills up leaves gnuplot's image cut short while gnuplot
 * exits 0: the cut image must not replace the good one, and the error
 * must say so (it once reported success). */
static void test_truncated_image_keeps_the_old_one(void **state)
{
    fixture *fx = *state;
    char prog[600];
    dfle_error err = {0};
    assert_ok(plot_small(fx, &err), &err);
    long good = file_size(in_dir(fx, "small.png"));
    assert_true(good > 1000);
    /* gnuplot, then cut what it wrote to 100 bytes. */
    snprintf(prog, sizeof prog, "%s/cutting-gnuplot", fx->dir);
    write_script(prog, "#!/bin/sh\n"
                       "gp=$(cat)\n"
                       "out=$(printf '%s\\n' \"$gp\" | sed -n \"s/^set output '\\([^']*\\)'$/\\1/p\")\n"
                       "printf '%s\\n' \"$gp\" | gnuplot || exit\n"
                       "head -c 100 \"$out\" > \"$out.cut\" && mv \"$out.cut\" \"$out\"\n");
    assert_int_equal(with_gnuplot(prog, plot_small, fx, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "incomplete");
    assert_int_equal(file_size(in_dir(fx, "small.png")), good);
    assert_png(in_dir(fx, "small.png"));
}

/* Under a file-size limit gnuplot is stopped (or its writes fail): an
 * error that says so, not "install gnuplot", and the old image stays. */
static void test_size_limit_keeps_the_old_image(void **state)
{
    fixture *fx = *state;
    dfle_error err = {0};
    struct rlimit old, small;
    assert_ok(plot_small(fx, &err), &err);
    long good = file_size(in_dir(fx, "small.png"));
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    small = old;
    small.rlim_cur = 2048;
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &small), 0);
    int st = plot_small(fx, &err);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &old), 0);
    assert_true(st == DFLE_EEXTERNAL || st == DFLE_EIO);
    assert_null(strstr(err.msg, "install"));
    assert_int_equal(file_size(in_dir(fx, "small.png")), good);
}

/* A plot killed with -9 leaves its temporary image; the next plot of
 * the same file removes it, and no stray file is ever left in TMPDIR. */
static void test_leftover_of_a_killed_plot_is_removed(void **state)
{
    fixture *fx = *state;
    dfle_error err = {0};
    char leftover[600];
    snprintf(leftover, sizeof leftover, "%s/.small.png.999999999.123456", fx->dir);
    int fd = open(leftover, O_WRONLY | O_CREAT, 0644);
    assert_true(fd >= 0);
    close(fd);
    assert_ok(plot_small(fx, &err), &err);
    assert_missing(leftover);
    assert_png(in_dir(fx, "small.png"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_xy_png, setup, teardown),
        cmocka_unit_test_setup_teardown(test_xy_colour, setup, teardown),
        cmocka_unit_test_setup_teardown(test_xy_log_svg, setup, teardown),
        cmocka_unit_test_setup_teardown(test_xy_band, setup, teardown),
        cmocka_unit_test_setup_teardown(test_corner, setup, teardown),
        cmocka_unit_test_setup_teardown(test_slope_area_png, setup, teardown),
        cmocka_unit_test_setup_teardown(test_profile_png, setup, teardown),
        cmocka_unit_test_setup_teardown(test_hostile_path, setup, teardown),
        cmocka_unit_test_setup_teardown(test_bad_extension, setup, teardown),
        cmocka_unit_test_setup_teardown(test_bad_arguments, setup, teardown),
        cmocka_unit_test_setup_teardown(test_nothing_finite, setup, teardown),
        cmocka_unit_test_setup_teardown(test_unwritable, setup, teardown),
        cmocka_unit_test_setup_teardown(test_gnuplot_missing, setup, teardown),
        cmocka_unit_test_setup_teardown(test_gnuplot_fails, setup, teardown),
        cmocka_unit_test_setup_teardown(test_truncated_image_keeps_the_old_one, setup, teardown),
        cmocka_unit_test_setup_teardown(test_size_limit_keeps_the_old_image, setup, teardown),
        cmocka_unit_test_setup_teardown(test_leftover_of_a_killed_plot_is_removed, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
