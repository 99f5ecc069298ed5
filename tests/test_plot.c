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
#include "plot_fixture.h"
/* The axis module is tested directly: that tick labels never touch is a
 * property of plot_axes.c, checked over many ranges and lengths. */
#include "io/plot_internal.h"

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
    dfle_plot_series s[2] = {{.label = "sqrt", .n = 50, .x = x, .y = y1, .style = DFLE_PLOT_LINES},
                             {.n = 50, .x = x, .y = y2}};
    dfle_plot_opts o = {.title = "Title", .x.label = "x (m)", .y.label = "y", .width = 640,
                        .height = 480, .unit = DFLE_PLOT_PX};
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
    dfle_plot_series s = {.label = "coloured", .n = 40, .x = x, .y = y, .c = c};
    dfle_plot_opts o = {.title = "colour", .x.label = "x", .y.label = "y",
                        .c = {.label = "U (m/yr)", .log = 1}};
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
    dfle_plot_series s = {.label = "log", .n = 5, .x = x, .y = y, .style = DFLE_PLOT_LINES};
    dfle_plot_opts o = {.x.log = 1, .y.log = 1};
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
    dfle_plot_series s[2] = {{.label = "band", .n = 20, .x = x, .lo = lo, .hi = hi, .rgb = "#9ecae1"},
                             {.label = "median", .n = 20, .x = x, .y = y, .style = DFLE_PLOT_LINES, .rgb = "#08306b", .dash = 1}};
    dfle_plot_opts o = {.title = "Bands", .x = {.label = "A", .log = 1},
                        .y = {.label = "S", .log = 1}, .width = 640, .height = 480,
                        .unit = DFLE_PLOT_PX};
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
    /* gamma held by an upper bound at 0.8: a line and a note */
    double blo[3] = {NAN, NAN, NAN}, bhi[3] = {NAN, 0.8, NAN};
    dfle_corner_opts o = {labels, logs, truth, 20, blo, bhi};
    dfle_plot_opts po = {.title = "Corner", .width = 12};
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
    assert_ok(dfle_plot_corner(in_dir(fx, "corner.png"), &po, &o, 3, N, x, &err), &err);
    assert_png(fx->path);
    assert_ok(dfle_plot_corner(in_dir(fx, "corner.svg"), NULL, NULL, 2, N, x, &err), &err);
    assert_ok(dfle_plot_corner(in_dir(fx, "bound.svg"), &po, &o, 3, N, x, &err), &err);
    {
        FILE *f = fopen(fx->path, "r");
        static char text[1 << 20];
        size_t len = f != NULL ? fread(text, 1, sizeof text - 1, f) : 0;
        if (f != NULL)
            fclose(f);
        text[len] = '\0';
        assert_non_null(strstr(text, "prior bound"));
        assert_null(strstr(strstr(text, "prior bound") + 1, "prior bound")); /* once */
    }
    assert_int_equal(dfle_plot_corner(in_dir(fx, "c0.png"), &po, &o, 0, N, x, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_corner(in_dir(fx, "c1.png"), &po, &o, 3, 1, x, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "at least 2 samples");
    assert_int_equal(dfle_plot_corner(in_dir(fx, "c.jpg"), &po, &o, 3, N, x, &err), DFLE_EINVAL);
}

static void test_slope_area_png(void **state)
{
    fixture *fx = *state;
    dfle_bins bins;
    dfle_eq2_fit fit;
    dfle_plot_opts title = {.title = "Fig. 1"};
    dfle_error err = {0};
    make_slope_area(&bins, &fit);
    assert_ok(dfle_plot_slope_area(in_dir(fx, "sa.png"), &title, NPTS, sa_A,
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
    dfle_plot_opts title = {.title = "Profile"};
    dfle_error err = {0};
    assert_ok(dfle_plot_profile(in_dir(fx, "p.png"), &title, 100, x, z, S,
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
    dfle_plot_series s = {.label = "a 'label' with `touch INJ3`\nand a new line", .n = 3, .x = x, .y = y, .style = DFLE_PLOT_LINES};
    dfle_plot_opts o = {.title = "it's \"fine\"", .x.label = "x\\", .y.label = "`touch INJ4`"};
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
    static const char *const bad[] = {"plot.eps", "plot", "dir.png/plot",
                                      "plot.png.txt"};
    double x[2] = {1, 2}, y[2] = {1, 2};
    dfle_plot_series s = {.n = 2, .x = x, .y = y, .style = DFLE_PLOT_LINES};
    dfle_error err = {0};
    for (size_t k = 0; k < 4; k++) {
        assert_int_equal(dfle_plot_xy(in_dir(fx, bad[k]), NULL, &s, 1, &err),
                         DFLE_EINVAL);
        assert_msg_contains(err.msg, fx->path);
        assert_msg_contains(err.msg, ".png, .pdf or .svg");
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
    dfle_plot_series s = {.n = 2, .x = x, .y = y, .style = DFLE_PLOT_LINES},
                     empty = {.n = 0, .style = DFLE_PLOT_LINES};
    dfle_plot_series nox = {.n = 2, .y = y, .style = DFLE_PLOT_LINES};
    dfle_plot_opts tiny = {.width = 10, .height = 10, .unit = DFLE_PLOT_PX};
    dfle_eq2_fit fit = {0};
    dfle_error err = {0};
    const char *p = in_dir(fx, "a.png");
    assert_int_equal(dfle_plot_xy(NULL, NULL, &s, 1, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_xy("", NULL, &s, 1, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_xy(p, NULL, &s, 0, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_xy(p, NULL, NULL, 1, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_xy(p, NULL, &empty, 1, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_xy(p, NULL, &nox, 1, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "series 1");
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
    dfle_plot_series s = {.label = "nan", .n = 3, .x = x, .y = nan3, .style = DFLE_PLOT_LINES},
                     sn = {.label = "neg", .n = 3, .x = x, .y = neg};
    dfle_plot_opts logy = {.y.log = 1};
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
    dfle_plot_series s = {.n = 2, .x = x, .y = y, .style = DFLE_PLOT_LINES};
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

/* Three points to `name` in the fixture's directory. */
static int plot_three(fixture *fx, const char *name, dfle_error *err)
{
    double x[3] = {1, 2, 3};
    dfle_plot_series s = {.label = "s", .n = 3, .x = x, .y = x, .style = DFLE_PLOT_LINES};
    return dfle_plot_xy(in_dir(fx, name), NULL, &s, 1, err);
}

static int plot_small(fixture *fx, dfle_error *err) { return plot_three(fx, "small.png", err); }
static int plot_pdf(fixture *fx, dfle_error *err) { return plot_three(fx, "t.pdf", err); }

/* f run with a "gnuplot" that is the shell script `body`. */
static int with_fake_gnuplot(fixture *fx, const char *body, int (*f)(fixture *, dfle_error *),
                             dfle_error *err)
{
    char prog[600];
    snprintf(prog, sizeof prog, "%s/fake gnuplot's", fx->dir);
    write_script(prog, body);
    return with_gnuplot(prog, f, fx, err);
}

static void test_gnuplot_fails(void **state)
{
    fixture *fx = *state;
    dfle_error err = {0};
    /* A "gnuplot" that reads the script, complains and fails. */
    assert_int_equal(with_fake_gnuplot(fx, "#!/bin/sh\ncat >/dev/null\n"
                                           "echo 'line 3: boom, undefined thing' >&2\nexit 1\n",
                                       plot_small, &err), DFLE_EEXTERNAL);
    assert_msg_contains(err.msg, "boom, undefined thing");
    assert_missing(in_dir(fx, "small.png"));
    /* One that exits happily without writing an image. */
    assert_int_equal(with_fake_gnuplot(fx, "#!/bin/sh\ncat >/dev/null\nexit 0\n", plot_small,
                                       &err), DFLE_EEXTERNAL);
    assert_msg_contains(err.msg, "wrote nothing");
    assert_missing(in_dir(fx, "small.png"));
    /* A wrapper with a space and a quote in its name that runs gnuplot. */
    assert_ok(with_fake_gnuplot(fx, "#!/bin/sh\nexec gnuplot \"$@\"\n", plot_small, &err),
              &err);
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


/* ------------------------------------------------------------------ */
/* The shared options: names, checks, and what reaches gnuplot          */
/* ------------------------------------------------------------------ */

/* Every name a script may use parses to its value; a wrong one is an
 * error naming the option and listing what it could be. */
static void test_option_names(void **state)
{
    (void)state;
    dfle_error err = {0};
    char rgb[8];
    assert_int_equal(dfle_plot_parse_legend("top left", "legend", &err), DFLE_LEGEND_TOP_LEFT);
    assert_int_equal(dfle_plot_parse_legend("below", "legend", &err), DFLE_LEGEND_BELOW);
    assert_int_equal(dfle_plot_parse_legend("outside right", "legend", &err),
                     DFLE_LEGEND_OUTSIDE_RIGHT);
    assert_int_equal(dfle_plot_parse_legend("middle", "legend", &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "legend 'middle' is not a legend position");
    assert_msg_contains(err.msg, "'top right'");
    assert_int_equal(dfle_plot_parse_legend(NULL, "legend", &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_parse_unit("in", "size unit", &err), DFLE_PLOT_IN);
    assert_int_equal(dfle_plot_parse_unit("mm", "size unit", &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "size unit 'mm'");
    assert_msg_contains(err.msg, "'cm', 'in', 'px'");
    assert_int_equal(dfle_plot_parse_style("linespoints", "style", &err), DFLE_PLOT_LINESPOINTS);
    assert_int_equal(dfle_plot_parse_style("bars", "style", &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_parse_dash("dashdot", "dash", &err), DFLE_DASH_DASHDOT);
    assert_int_equal(dfle_plot_parse_dash("dotted", "dash", &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_parse_marker("open down triangle", "marker", &err),
                     DFLE_MARKER_OPEN_DOWN_TRIANGLE);
    assert_int_equal(dfle_plot_parse_marker("hexagon", "marker", &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "marker 'hexagon'");
    assert_ok(dfle_plot_colour("black", "rgb", rgb, &err), &err);
    assert_string_equal(rgb, "#000000");
    assert_ok(dfle_plot_colour("sky blue", "rgb", rgb, &err), &err);
    assert_string_equal(rgb, "#56B4E9");
    assert_ok(dfle_plot_colour("#12ab3C", "rgb", rgb, &err), &err);
    assert_string_equal(rgb, "#12ab3C");
    assert_int_equal(dfle_plot_colour("#12ab3", "rgb", rgb, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_colour("#12ab3g", "rgb", rgb, &err), DFLE_EINVAL);
    assert_int_equal(dfle_plot_colour("red", "series 2: rgb", rgb, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "series 2: rgb 'red' is not a colour");
    assert_msg_contains(err.msg, "vermillion");
    /* the house labels, and the factor to their unit */
    double f = 0;
    assert_string_equal(dfle_plot_label("S", &f), "Slope, {/:Italic S} (m/m)");
    assert_true(f == 1);
    assert_non_null(strstr(dfle_plot_label("U", &f), "(mm/yr)"));
    assert_true(f == 1e3);
    assert_null(dfle_plot_label("nope", &f));
    assert_string_equal(dfle_plot_label_name(0), "x");
    char num[64];
    dfle_plot_number(num, sizeof num, 1.42e5);
    assert_string_equal(num, "1.42×10^{5}");
    dfle_plot_number(num, sizeof num, 0.5);
    assert_string_equal(num, "0.5");
    /* not finite: a word, not a crash on an exponent that is not there */
    dfle_plot_number(num, sizeof num, INFINITY);
    assert_string_equal(num, "inf");
    dfle_plot_number(num, sizeof num, -INFINITY);
    assert_string_equal(num, "-inf");
    dfle_plot_number(num, sizeof num, NAN);
    assert_string_equal(num, "NaN");
}

/* Bad values of the shared options are refused before gnuplot starts,
 * each message naming the option. */
static void test_option_checks(void **state)
{
    fixture *fx = *state;
    static const struct {
        dfle_plot_opts o;
        const char *msg;
    } bad[] = {
        {{.x = {.has_lo = 1, .lo = 5, .has_hi = 1, .hi = 1}}, "xrange must be increasing"},
        {{.y = {.has_lo = 1, .lo = NAN}}, "yrange must be finite"},
        {{.x = {.log = 1, .has_lo = 1, .lo = 0}}, "xrange must be > 0 on a logarithmic axis"},
        {{.c = {.step = -1}}, "cticks spacing must be > 0"},
        {{.y = {.log = 1, .step = 2}}, "yticks: a spacing (2) needs a linear axis"},
        {{.x = {.log = 2}}, "x log must be -1, 0 or 1"},
        {{.width = -3}, "size must be positive"},
        {{.width = 1, .unit = DFLE_PLOT_CM}, "outside 2 to 200 cm"},
        {{.width = 300, .unit = DFLE_PLOT_CM}, "outside 2 to 200 cm"},
        {{.width = 60, .unit = DFLE_PLOT_IN, .dpi = 600}, "more than 20000 px"},
        {{.unit = 7}, "size unit 7"},
        {{.dpi = 10}, "dpi must be from 30 to 2400"},
        {{.font = "Helvetica,200"}, "from 4 to 72"},
        {{.font = "Helvetica,big"}, "from 4 to 72"},
        {{.legend = 99}, "legend 99"},
    };
    double x[3] = {1, 2, 3}, ticks[2] = {1, NAN};
    dfle_plot_series s = {.n = 3, .x = x, .y = x, .style = DFLE_PLOT_LINES};
    dfle_error err = {0};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        assert_int_equal(dfle_plot_xy(in_dir(fx, "a.png"), &bad[k].o, &s, 1, &err), DFLE_EINVAL);
        assert_msg_contains(err.msg, bad[k].msg);
    }
    /* ticks: finite, and positive on a log axis; the series' styles */
    dfle_plot_opts o = {.x = {.ticks = ticks, .nticks = 2}};
    assert_int_equal(dfle_plot_xy(in_dir(fx, "a.png"), &o, &s, 1, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "xticks[2] must be a finite number");
    s.width = 30;
    assert_int_equal(dfle_plot_xy(in_dir(fx, "a.png"), NULL, &s, 1, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "series 1: width must be from 0 to 20 pt");
    s.width = 0;
    s.rgb = "mauve";
    assert_int_equal(dfle_plot_xy(in_dir(fx, "a.png"), NULL, &s, 1, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "series 1: rgb 'mauve' is not a colour");
    /* a log axis the data cannot be on: the figure names the range */
    dfle_plot_opts lg = {.y = {.log = 1, .has_lo = 1, .lo = -1}};
    s.rgb = NULL;
    assert_int_equal(dfle_plot_xy(in_dir(fx, "a.png"), &lg, &s, 1, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "yrange must be > 0");
    assert_int_equal(dir_entries(fx), 0);
}

static const dfle_plot_opts *script_opts;
static dfle_plot_series script_series[2];

static int plot_for_script(fixture *fx, dfle_error *err)
{
    return dfle_plot_xy(fx->path, script_opts, script_series, 2, err);
}

/* What the options say reaches the script: the terminal and its size
 * and font, ranges, log axes, ticks, the legend. */
static void test_options_reach_the_script(void **state)
{
    fixture *fx = *state;
    char prog[600];
    double x[40], y[40], y2[40], t[3] = {2, 4, 8};
    const char *tl[3] = {"two", NULL, "eight"};
    dfle_error err = {0};
    for (int i = 0; i < 40; i++) {
        x[i] = 1 + i * 0.2;
        y[i] = 1e-6 * (1 + i);
        y2[i] = 2e-6 * (1 + i);
    }
    script_series[0] = (dfle_plot_series){.label = "first", .n = 40, .x = x, .y = y,
                                          .style = DFLE_PLOT_LINES, .dash = DFLE_DASH_DOT,
                                          .width = 2};
    script_series[1] = (dfle_plot_series){.label = "second", .n = 40, .x = x, .y = y2,
                                          .marker = DFLE_MARKER_OPEN_SQUARE, .rgb = "orange"};
    teeing_gnuplot(fx, prog, sizeof prog);

    /* PDF, 17 x 11 cm, Helvetica 10, fixed ranges, explicit ticks */
    dfle_plot_opts pdf = {.title = "T", .width = 17, .height = 11, .unit = DFLE_PLOT_CM,
                          .font = "Helvetica,10", .legend = DFLE_LEGEND_BELOW,
                          .x = {.has_lo = 1, .lo = 2, .has_hi = 1, .hi = 8, .ticks = t,
                                .tick_labels = tl, .nticks = 3}};
    script_opts = &pdf;
    in_dir(fx, "o.pdf");
    assert_ok(with_gnuplot(prog, plot_for_script, fx, &err), &err);
    const char *sc = last_script(fx);
    assert_non_null(strstr(sc, "set terminal pdfcairo size 6.69291in,4.33071in enhanced "
                               "font 'Helvetica,10'"));
    assert_non_null(strstr(sc, "set xrange [2:8]"));
    assert_non_null(strstr(sc, "set xtics ('two' 2, '4' 4, 'eight' 8)"));
    assert_non_null(strstr(sc, "dt 3")); /* the dotted series */
    assert_non_null(strstr(sc, "#E69F00")); /* orange by name */
    /* y: 1e-6 .. 4e-5, labels with ×10^, never a run of zeros */
    assert_non_null(strstr(sc, "×10^{-5}"));
    assert_null(strstr(sc, "0.00001"));
    /* the legend: below, drawn by dfle (no gnuplot key), both entries */
    assert_non_null(strstr(sc, "unset key"));
    assert_non_null(strstr(sc, "'first' at screen"));
    assert_non_null(strstr(sc, "'second' at screen"));
    assert_null(strstr(sc, "set object 200 rect")); /* no box below the frame */

    /* PNG at 300 dpi: pixels from the size, fonts and lines scaled */
    dfle_plot_opts png = {.width = 17, .height = 11, .dpi = 300, .legend = DFLE_LEGEND_TOP_LEFT,
                          .y = {.log = 1, .label = "why"}, .x = {.step = 2}};
    script_opts = &png;
    in_dir(fx, "o.png");
    assert_ok(with_gnuplot(prog, plot_for_script, fx, &err), &err);
    sc = last_script(fx);
    assert_non_null(strstr(sc, "set terminal pngcairo size 2008,1299 enhanced font 'sans,9' "
                               "fontscale 3.125"));
    assert_non_null(strstr(sc, "set logscale y 10"));
    assert_non_null(strstr(sc, "set xtics ('2' 2, '4' 4, '6' 6, '8' 8"));
    assert_non_null(strstr(sc, "'why' at screen"));
    assert_non_null(strstr(sc, "set object 200 rect")); /* the legend's box, inside */
    assert_png(in_dir(fx, "o.png"));

    /* SVG in points; no legend at all */
    dfle_plot_opts svg = {.width = 4, .height = 3, .unit = DFLE_PLOT_IN,
                          .legend = DFLE_LEGEND_NONE};
    script_opts = &svg;
    in_dir(fx, "o.svg");
    assert_ok(with_gnuplot(prog, plot_for_script, fx, &err), &err);
    sc = last_script(fx);
    assert_non_null(strstr(sc, "set terminal svg size 288,216 fixed"));
    assert_null(strstr(sc, "'first' at screen"));
}

/* The colour scale's options (range, log, ticks, label), tick formats
 * and a marker's size reach the script as the caller gave them. */
static void test_colour_scale_and_formats_reach_the_script(void **state)
{
    fixture *fx = *state;
    char prog[600];
    double x[5] = {1, 2, 3, 4, 5}, y[5] = {2, 3, 5, 7, 11}, c[5] = {1, 3, 10, 30, 100};
    double ct[3] = {1, 10, 100};
    dfle_error err = {0};
    teeing_gnuplot(fx, prog, sizeof prog);
    script_series[0] = (dfle_plot_series){.label = "coloured", .n = 5, .x = x, .y = y, .c = c,
                                          .marker_size = 9};
    script_series[1] = (dfle_plot_series){.label = "plain", .n = 5, .x = x, .y = y,
                                          .marker_size = 2};
    dfle_plot_opts o = {.x = {.format = "%.2f"},
                        .y = {.format = "%.1e"},
                        .c = {.label = "colour (units)", .log = 1, .has_lo = 1, .lo = 0.5,
                              .has_hi = 1, .hi = 200, .ticks = ct, .nticks = 3}};
    script_opts = &o;
    in_dir(fx, "c.png");
    assert_ok(with_gnuplot(prog, plot_for_script, fx, &err), &err);
    const char *sc = last_script(fx);
    assert_non_null(strstr(sc, "set format x '%.2f'"));
    assert_non_null(strstr(sc, "set format y '%.1e'"));
    assert_non_null(strstr(sc, "set logscale cb 10"));
    assert_non_null(strstr(sc, "set cbrange [0.5:200]"));
    assert_non_null(strstr(sc, "set cbtics ('10^{0}' 1, '10^{1}' 10, '10^{2}' 100)"));
    assert_non_null(strstr(sc, "colour (units)"));
    /* sizes differ by the ratio given (9 pt against 2 pt) */
    double ps[2] = {0, 0};
    const char *p = sc;
    for (int k = 0; k < 2; k++) {
        p = strstr(p, " ps ");
        assert_non_null(p);
        ps[k] = strtod(p + 4, NULL);
        p += 4;
    }
    assert_true(ps[0] > 0 && ps[1] > 0);
    assert_true(fabs(fmax(ps[0], ps[1]) / fmin(ps[0], ps[1]) - 4.5) < 0.05);
    assert_png(in_dir(fx, "c.png"));
}

/* Automatic ticks: over many ranges, scales and axis lengths, the
 * labels chosen keep a gap (side by side on x, stacked on y), there are
 * at least two of them, and a log axis over two decades or more shows
 * at least four labels when there is room. */
static void test_ticks_never_touch(void **state)
{
    (void)state;
    static dfle_gp_axis a;
    static const double lens[] = {90, 200, 400};
    static const double spans[][2] = {
        {1e-6, 1e-5}, {0, 2010}, {0.87, 1.26}, {2, 8}, {-3.2, 47}, {1e5, 7.3e5},
        {1000, 8e6},  {0.02, 0.8}, {3e-5, 1.2e-4}, {0.1, 1}, {5e4, 6.6e5}, {1e-3, 4.5},
        {0.25, 0.45}, {1, 1e12}};
    for (size_t s = 0; s < sizeof spans / sizeof spans[0]; s++)
        for (int log = 0; log <= 1; log++)
            for (size_t k = 0; k < sizeof lens / sizeof lens[0]; k++)
                for (int vertical = 0; vertical <= 1; vertical++) {
                    double lo = spans[s][0], hi = spans[s][1];
                    if (log && lo <= 0)
                        continue;
                    dfle_gp_axis_range(&a, log, lo, hi, 0, NULL);
                    dfle_gp_axis_ticks(&a, lens[k], 9, vertical, NULL);
                    assert_true(a.n >= 2);
                    double ulo = log ? log10(a.lo) : a.lo, uhi = log ? log10(a.hi) : a.hi;
                    for (size_t i = 0; i < a.n; i++) {
                        double u = log ? log10(a.v[i]) : a.v[i];
                        assert_true(u >= ulo - 1e-9 * fabs(uhi - ulo) &&
                                    u <= uhi + 1e-9 * fabs(uhi - ulo));
                        assert_null(strstr(a.lab[i], "0.0000"));
                    }
                    if (log && log10(hi / lo) >= 2 && lens[k] >= 400 && vertical)
                        assert_true(a.n >= 4);
                    if (lens[k] < 150)
                        continue; /* on a 3 cm axis labels may have to touch */
                    for (size_t i = 1; i < a.n; i++) {
                        double u0 = log ? log10(a.v[i - 1]) : a.v[i - 1];
                        double u1 = log ? log10(a.v[i]) : a.v[i];
                        double gap = (u1 - u0) / (uhi - ulo) * lens[k];
                        double need = vertical ? 9 * 1.5
                                               : 9 * 0.5 * (dfle_gp_text_em(a.lab[i - 1]) +
                                                            dfle_gp_text_em(a.lab[i])) + 4;
                        assert_true(gap >= need);
                    }
                }
}

/* Narrow panels label tiny values by mantissas with one factor in the
 * axis label, which says it. */
static void test_factored_ticks(void **state)
{
    (void)state;
    static dfle_gp_axis a;
    char buf[128];
    dfle_gp_axis_range(&a, 1, 1.9e-14, 5.2e-14, 0, NULL);
    a.factor_ok = 1;
    dfle_gp_axis_ticks(&a, 110, 9, 0, NULL);
    assert_true(a.factored);
    assert_int_equal(a.factor_exp, -14);
    assert_true(a.n >= 2);
    for (size_t i = 0; i < a.n; i++)
        assert_null(strstr(a.lab[i], "10^"));
    assert_string_equal(dfle_gp_axis_label(&a, "k_e", buf, sizeof buf), "k_e (×10^{-14})");
    assert_string_equal(dfle_gp_axis_label(&a, "D (m^2/s)", buf, sizeof buf),
                        "D (×10^{-14} m^2/s)");
    /* ordinary magnitudes are not factored, nor any axis that did not ask */
    dfle_gp_axis_range(&a, 0, 0.2, 0.9, 0, NULL);
    a.factor_ok = 1;
    dfle_gp_axis_ticks(&a, 110, 9, 0, NULL);
    assert_false(a.factored);
    assert_string_equal(dfle_gp_axis_label(&a, "S", buf, sizeof buf), "S");
    dfle_gp_axis_range(&a, 0, 1e-6, 1e-5, 0, NULL);
    dfle_gp_axis_ticks(&a, 400, 9, 0, NULL);
    assert_false(a.factored);
    assert_non_null(strstr(a.lab[0], "×10^{-6}"));
    /* thousandths are decimals, factored or not */
    dfle_gp_axis_range(&a, 0, 1e-3, 9e-3, 0, NULL);
    a.factor_ok = 1;
    dfle_gp_axis_ticks(&a, 400, 9, 0, NULL);
    assert_false(a.factored);
    assert_true(a.n >= 2);
    for (size_t i = 0; i < a.n; i++) {
        assert_null(strstr(a.lab[i], "10^"));
        assert_true(strncmp(a.lab[i], "0.00", 4) == 0 || strcmp(a.lab[i], "0.01") == 0);
    }
}

/* A PDF and an SVG, really drawn: the PDF's magic and trailer, the SVG's
 * closing tag and a header that gives its size in points. */
static void test_pdf_and_svg(void **state)
{
    fixture *fx = *state;
    double x[30], y[30];
    char buf[4096];
    size_t k;
    struct stat sb;
    for (int i = 0; i < 30; i++) {
        x[i] = i + 1;
        y[i] = 1.0 / (i + 1);
    }
    dfle_plot_series s = {.label = "1/x", .n = 30, .x = x, .y = y, .style = DFLE_PLOT_LINESPOINTS};
    dfle_plot_opts o = {.title = "PDF", .width = 8.3, .unit = DFLE_PLOT_CM, .y.log = 1};
    dfle_error err = {0};
    assert_ok(dfle_plot_xy(in_dir(fx, "f.pdf"), &o, &s, 1, &err), &err);
    assert_int_equal(head(fx->path, buf, 5), 5);
    assert_memory_equal(buf, "%PDF-", 5);
    assert_int_equal(stat(fx->path, &sb), 0);
    FILE *f = fopen(fx->path, "rb");
    assert_non_null(f);
    assert_int_equal(fseek(f, -16, SEEK_END), 0);
    k = fread(buf, 1, 16, f);
    fclose(f);
    buf[k] = '\0';
    assert_non_null(strstr(buf, "%%EOF"));
    assert_ok(dfle_plot_xy(in_dir(fx, "f.svg"), &o, &s, 1, &err), &err);
    assert_svg(fx->path);
    k = head(fx->path, buf, sizeof buf - 1);
    buf[k] = '\0';
    assert_non_null(strstr(buf, "width=\"235pt\"")); /* 8.3 cm */
    assert_non_null(strstr(buf, "viewBox=\"0 0 235 "));
    f = fopen(fx->path, "rb");
    assert_non_null(f);
    assert_int_equal(fseek(f, -10, SEEK_END), 0);
    k = fread(buf, 1, 10, f);
    fclose(f);
    buf[k] = '\0';
    assert_non_null(strstr(buf, "</svg>"));
    /* the other figures take a .pdf too */
    dfle_bins bins;
    dfle_eq2_fit fit;
    make_slope_area(&bins, &fit);
    assert_ok(dfle_plot_slope_area(in_dir(fx, "sa.pdf"), NULL, NPTS, sa_A, sa_S, &bins, &fit,
                                   &err), &err);
    assert_ok(dfle_plot_profile(in_dir(fx, "p.pdf"), NULL, 30, x, y, y, &err), &err);
}

/* A gnuplot without the terminal: a message that says which terminal
 * and what to do, and no file. */
static void test_missing_terminal(void **state)
{
    fixture *fx = *state;
    dfle_error err = {0};
    assert_int_equal(with_fake_gnuplot(fx, "#!/bin/sh\ncat >/dev/null\n"
                                           "echo \"line 1: unknown or ambiguous terminal "
                                           "type; type just 'set terminal' for a list\" >&2\n"
                                           "exit 1\n", plot_pdf, &err), DFLE_EEXTERNAL);
    assert_msg_contains(err.msg, "has no pdfcairo terminal");
    assert_msg_contains(err.msg, "t.pdf");
    assert_msg_contains(err.msg, "gnuplot-nox");
    assert_missing(in_dir(fx, "t.pdf"));
}

/* Panels over one x axis, and a contact sheet of PNGs. */
static void test_panels_and_sheet(void **state)
{
    fixture *fx = *state;
    double x[50], a[50], b[50];
    char p1[600], p2[600];
    dfle_error err = {0};
    for (int i = 0; i < 50; i++) {
        x[i] = 10.0 * i;
        a[i] = 500 - i * i * 0.2;
        b[i] = 0.5 / (1 + i);
    }
    dfle_plot_series sa = {.label = "z", .n = 50, .x = x, .y = a, .style = DFLE_PLOT_LINES};
    dfle_plot_series sb = {.label = "S", .n = 50, .x = x, .y = b, .style = DFLE_PLOT_LINES};
    dfle_plot_panel P[2] = {{.series = &sa, .nseries = 1, .y = {.label = "z (m)"}, .weight = 2},
                            {.series = &sb, .nseries = 1, .y = {.label = "S", .log = 1}}};
    dfle_plot_opts o = {.x.label = "x (m)"};
    snprintf(p1, sizeof p1, "%s/panels.png", fx->dir);
    assert_ok(dfle_plot_panels(p1, &o, P, 2, &err), &err);
    assert_png(p1);
    P[1].weight = -1;
    assert_int_equal(dfle_plot_panels(in_dir(fx, "bad.png"), &o, P, 2, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "panel 2: weight");
    assert_int_equal(dfle_plot_panels(in_dir(fx, "bad.png"), &o, P, 0, &err), DFLE_EINVAL);
    snprintf(p2, sizeof p2, "%s/panels_copy.png", fx->dir);
    P[1].weight = 0;
    assert_ok(dfle_plot_panels(p2, NULL, P, 1, &err), &err);
    const char *imgs[2] = {p1, p2}, *titles[2] = {"Panels", NULL};
    assert_ok(dfle_plot_sheet(in_dir(fx, "sheet.png"), NULL, imgs, titles, 2, 2, &err), &err);
    assert_png(fx->path);
    const char *img[1] = {p1};
    snprintf(p1, sizeof p1, "%s/script.txt", fx->dir);
    write_script(p1, "not an image\n");
    assert_int_equal(dfle_plot_sheet(in_dir(fx, "s2.png"), NULL, img, NULL, 1, 0, &err),
                     DFLE_EINVAL);
    assert_msg_contains(err.msg, "is not a .png file");
    snprintf(p1, sizeof p1, "%s/fake.png", fx->dir);
    write_script(p1, "not a PNG either, though the name says so\n");
    assert_int_equal(dfle_plot_sheet(in_dir(fx, "s3.png"), NULL, img, NULL, 1, 0, &err),
                     DFLE_EINVAL);
    assert_msg_contains(err.msg, "is not a PNG image");
}

static dfle_plot_map map_for_script;
static int map_plot(fixture *fx, dfle_error *err)
{
    return dfle_plot_hillshade(fx->path, &map_for_script, err);
}

/* The map's legend names a colour only where the map shows it: reach is
 * painted over channels, so with every channel reached there is no
 * channel entry; with one channel cell beyond the reach there is. */
static void test_map_legend(void **state)
{
    fixture *fx = *state;
    char prog[600];
    double z[16], ch[16], reach[16];
    dfle_error err = {0};
    for (int i = 0; i < 16; i++) {
        z[i] = 100.0 - (double)(i / 4) * 10.0 + (double)(i % 4);
        ch[i] = (i % 4) == 1;
        reach[i] = ch[i];
    }
    map_for_script = (dfle_plot_map){.nx = 4, .ny = 4, .x0 = 0, .y0 = 120, .dx = 30, .dy = 30,
                                     .z = z, .channel = ch, .reach = reach};
    teeing_gnuplot(fx, prog, sizeof prog);
    in_dir(fx, "map.png");
    assert_ok(with_gnuplot(prog, map_plot, fx, &err), &err);
    assert_non_null(strstr(last_script(fx), "Debris-flow reach"));
    assert_null(strstr(last_script(fx), "Channel"));
    reach[13] = 0; /* the channel's last cell: rivers only */
    assert_ok(with_gnuplot(prog, map_plot, fx, &err), &err);
    assert_non_null(strstr(last_script(fx), "Channels beyond the debris-flow reach"));
    map_for_script.reach = NULL; /* a DEM's map: channels only */
    assert_ok(with_gnuplot(prog, map_plot, fx, &err), &err);
    assert_non_null(strstr(last_script(fx), "Channel network"));
    assert_null(strstr(last_script(fx), "Debris-flow reach"));
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
        cmocka_unit_test(test_option_names),
        cmocka_unit_test_setup_teardown(test_option_checks, setup, teardown),
        cmocka_unit_test_setup_teardown(test_options_reach_the_script, setup, teardown),
        cmocka_unit_test_setup_teardown(test_colour_scale_and_formats_reach_the_script, setup,
                                        teardown),
        cmocka_unit_test(test_ticks_never_touch),
        cmocka_unit_test(test_factored_ticks),
        cmocka_unit_test_setup_teardown(test_pdf_and_svg, setup, teardown),
        cmocka_unit_test_setup_teardown(test_missing_terminal, setup, teardown),
        cmocka_unit_test_setup_teardown(test_panels_and_sheet, setup, teardown),
        cmocka_unit_test_setup_teardown(test_map_legend, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
