/*
 * test_plot_map.c - maps for papers and the chi figures (plot.h): what
 * the scripts sent to gnuplot say (axis labels with the CRS, ticks, the
 * page fitted to the map at equal scales, scale bar, north arrow, the
 * legend's place), the CRS checks, the chi plot beside slope-area with
 * frames of one height, and the corner plot's truth and factors.
 */
#ifndef _POSIX_C_SOURCE /* mkdtemp, setenv, strdup */
#define _POSIX_C_SOURCE 200809L
#endif
#include <string.h>

#include "dfle/plot.h"
#include "dfle_test.h"
#include "plot_fixture.h"

enum { NX = 60, NY = 30 };
static double grid_z[NX * NY];
static dfle_plot_map the_map;
static dfle_plot_opts *the_opts;

static int map_plot(fixture *fx, dfle_error *err)
{
    return dfle_plot_map_draw(fx->path, the_opts, &the_map, err);
}

/* A tilted plane with ridges, 60 x 30 cells of 30 m in UTM 11N
 * coordinates near Big Tujunga; NaN (outside) where nodata says. */
static void make_map(int hole)
{
    for (int r = 0; r < NY; r++)
        for (int c = 0; c < NX; c++) {
            double v = 1000 + 5.0 * r + 20 * sin(c / 3.0);
            /* a catchment's outline: its top-left corner empty */
            if (hole && r < NY / 2 && c < NX / 2)
                v = NAN;
            grid_z[r * NX + c] = v;
        }
    the_map = (dfle_plot_map){.nx = NX, .ny = NY, .x0 = 396000, .y0 = 3805920, .dx = 30,
                              .dy = 30, .z = grid_z};
    the_opts = NULL;
}

/* The number after `key` in the script (the first match). */
static double script_number(const char *sc, const char *key)
{
    const char *p = strstr(sc, key);
    assert_non_null(p);
    return strtod(p + strlen(key), NULL);
}

static void test_map_axes_name_the_crs(void **state)
{
    fixture *fx = *state;
    char prog[600];
    dfle_error err = {0};
    make_map(0);
    the_map.dx = the_map.dy = 200; /* 12 x 6 km: ticks every km */
    teeing_gnuplot(fx, prog, sizeof prog);
    in_dir(fx, "map.png");
    the_map.crs = "EPSG:32611";
    assert_ok(with_gnuplot(prog, map_plot, fx, &err), &err);
    const char *sc = last_script(fx);
    assert_non_null(strstr(sc, "'Easting (km, EPSG:32611)'"));
    assert_non_null(strstr(sc, "'Northing (km, EPSG:32611)'"));
    assert_non_null(strstr(sc, "'WGS 84 / UTM zone 11N'")); /* beside the scale bar */
    /* whole kilometres, labelled as such: '3805', never '3805.0' */
    assert_non_null(strstr(sc, "'3805' 3805"));
    assert_null(strstr(sc, "3805.0'"));
    assert_png(fx->path);
    /* no CRS: plain x and y */
    the_map.crs = NULL;
    assert_ok(with_gnuplot(prog, map_plot, fx, &err), &err);
    sc = last_script(fx);
    assert_non_null(strstr(sc, "'{/:Italic x} (km)'"));
    assert_null(strstr(sc, "Easting"));
}

static void test_map_crs_refused(void **state)
{
    fixture *fx = *state;
    dfle_error err = {0};
    make_map(0);
    the_map.crs = "EPSG:4326";
    assert_int_equal(dfle_plot_map_draw(in_dir(fx, "m.png"), NULL, &the_map, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "geographic");
    the_map.crs = "EPSG:2229"; /* California zone 5, US survey feet */
    assert_int_equal(dfle_plot_map_draw(fx->path, NULL, &the_map, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "not metres");
    the_map.crs = "not a CRS at all";
    assert_int_equal(dfle_plot_map_draw(fx->path, NULL, &the_map, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "not one GDAL reads");
    assert_int_equal(dir_entries(fx), 0); /* nothing was drawn */
}

/* The frame has the map's proportions (equal scales) and the page is
 * the frame plus its labels: no empty band above or below. */
static void test_map_page_fits_the_map(void **state)
{
    fixture *fx = *state;
    char prog[600];
    dfle_error err = {0};
    const int shapes[2][2] = {{NX, NY}, {NY, NX}}; /* wide, then tall */
    teeing_gnuplot(fx, prog, sizeof prog);
    for (int k = 0; k < 2; k++) {
        make_map(0);
        the_map.nx = (size_t)shapes[k][0], the_map.ny = (size_t)shapes[k][1];
        in_dir(fx, "fit.png");
        assert_ok(with_gnuplot(prog, map_plot, fx, &err), &err);
        const char *sc = last_script(fx);
        const char *t = strstr(sc, "pngcairo size ");
        assert_non_null(t);
        double W = strtod(t + 14, NULL), H = strtod(strchr(t + 14, ',') + 1, NULL);
        double l = script_number(sc, "set lmargin at screen "), r = script_number(sc, "set rmargin at screen ");
        double tp = script_number(sc, "set tmargin at screen "), b = script_number(sc, "set bmargin at screen ");
        double aspect = ((r - l) * W) / ((tp - b) * H);
        assert_close(aspect, (double)shapes[k][0] / shapes[k][1], 2e-3, 0);
        /* above the frame: a line's room; below: ticks and the axis label,
         * at 150 dpi and 9 pt (18.75 px a font size) */
        assert_true((1 - tp) * H < 1.0 * 18.75 + 2);
        assert_true(b * H < 4.3 * 18.75 + 2);
        /* a tall map is no wider than it needs: at most 16 cm square */
        assert_true(W <= 945 + 1 && H <= 945 + 1);
        assert_png(fx->path);
    }
}

/* Scale bar and north arrow always; the legend in an empty corner when
 * there is one, else below the frame. */
static void test_map_furniture(void **state)
{
    fixture *fx = *state;
    char prog[600];
    double ch[NX * NY];
    dfle_error err = {0};
    teeing_gnuplot(fx, prog, sizeof prog);
    for (int hole = 1; hole >= 0; hole--) {
        make_map(hole);
        for (int i = 0; i < NX * NY; i++)
            ch[i] = (i % NX) == 40;
        the_map.channel = ch;
        in_dir(fx, "f.png");
        assert_ok(with_gnuplot(prog, map_plot, fx, &err), &err);
        const char *sc = last_script(fx);
        assert_non_null(strstr(sc, "set object 301 rect")); /* the bar's black half */
        assert_non_null(strstr(sc, "set object 302 rect")); /* its white half */
        assert_true(strstr(sc, "'km'") != NULL || strstr(sc, "'m'") != NULL); /* its unit */
        assert_non_null(strstr(sc, "set arrow 311 from")); /* north */
        assert_non_null(strstr(sc, "'{/:Bold N}'"));
        assert_non_null(strstr(sc, "'Channel network'"));
        if (hole)
            assert_non_null(strstr(sc, "set object 320 rect")); /* boxed, inside */
        else
            assert_null(strstr(sc, "set object 320 rect")); /* below the frame */
    }
}

/* Points coloured by a value: the colour box spans its 2nd to 98th
 * percentile unless the options say (of 0..100 without 50: the 2nd and
 * 99th of the 100 values, 1 and 99); a value that is not finite is not
 * drawn. */
static void test_map_points(void **state)
{
    fixture *fx = *state;
    char prog[600];
    double x[101], y[101], v[101], a[101];
    dfle_error err = {0};
    dfle_plot_opts o = {0};
    for (int i = 0; i < 101; i++) {
        x[i] = 396000 + 15 + 10 * i;
        y[i] = 3805920 - 400;
        v[i] = i; /* 0..100: percentiles 2 and 98 */
        a[i] = 1e4 * (i + 1);
    }
    v[50] = NAN;
    dfle_plot_map_points pts = {.n = 101, .x = x, .y = y, .value = v, .size = a};
    make_map(0);
    the_map.points = &pts;
    teeing_gnuplot(fx, prog, sizeof prog);
    in_dir(fx, "p.png");
    assert_ok(with_gnuplot(prog, map_plot, fx, &err), &err);
    const char *sc = last_script(fx);
    assert_non_null(strstr(sc, "$pts << EOD"));
    assert_non_null(strstr(sc, "with points pt 7 ps variable lc palette"));
    assert_close(script_number(sc, "set cbrange ["), 1, 0, 1e-9);
    {
        const char *p = strstr(sc, "set cbrange [");
        assert_close(strtod(strchr(p, ':') + 1, NULL), 99, 0, 1e-9);
    }
    {
        /* 100 rows: the NaN one left out */
        const char *p = strstr(sc, "$pts << EOD\n") + 12, *e = strstr(p, "EOD");
        int rows = 0;
        for (; p < e; p++)
            rows += *p == '\n';
        assert_int_equal(rows, 100);
    }
    o.c = (dfle_plot_axis){.has_lo = 1, .lo = 10, .has_hi = 1, .hi = 20, .label = "k"};
    the_opts = &o;
    assert_ok(with_gnuplot(prog, map_plot, fx, &err), &err);
    assert_non_null(strstr(last_script(fx), "set cbrange [10:20]"));
    assert_png(fx->path);
}

/* ---- chi ---------------------------------------------------------------- */

enum { NC = 200 };
static double c_chi[NC], c_z[NC], c_k[NC], c_A[NC];
static dfle_plot_chi_data the_chi;

static void make_chi(void)
{
    for (int i = 0; i < NC; i++) {
        c_A[i] = 1e4 * (NC - i);
        c_chi[i] = 0.05 * i;
        c_z[i] = 500 + 100 * c_chi[i];
        c_k[i] = 100;
    }
    the_chi = (dfle_plot_chi_data){.n = NC, .chi = c_chi, .z = c_z, .k_sn = c_k, .A = c_A,
                                   .A_min = 1e5, .theta_ref = 0.45, .A0 = 1, .M_chi = 100,
                                   .z_b = 500, .r2 = 1};
}

static int chi_plot(fixture *fx, dfle_error *err)
{
    return dfle_plot_chi(fx->path, NULL, &the_chi, err);
}

static int sa_chi_plot(fixture *fx, dfle_error *err)
{
    double A[NC], S[NC];
    for (int i = 0; i < NC; i++)
        A[i] = c_A[i], S[i] = 100 * pow(c_A[i], -0.45);
    dfle_plot_opts o = {.title = "both"};
    return dfle_plot_slope_area_chi(fx->path, &o, NC, A, S, NULL, NULL, &the_chi, err);
}

static void test_chi_plot(void **state)
{
    fixture *fx = *state;
    char prog[600];
    dfle_error err = {0};
    make_chi();
    teeing_gnuplot(fx, prog, sizeof prog);
    in_dir(fx, "chi.png");
    assert_ok(with_gnuplot(prog, chi_plot, fx, &err), &err);
    const char *sc = last_script(fx);
    assert_non_null(strstr(sc, "{/:Italic k}_{sn} = 100 m^{0.9}, {/:Italic R}^2 = 1.000"));
    assert_non_null(strstr(sc, "{/:Italic θ}_{ref} = 0.45"));
    assert_non_null(strstr(sc, "{/:Italic A} < 1×10^{5} m^2 (not fitted)"));
    assert_non_null(strstr(sc, "'{/:Italic k}_{sn} (m^{0.9})'"));
    assert_png(fx->path);
    the_chi.theta_ref = NAN;
    assert_int_equal(dfle_plot_chi(in_dir(fx, "bad.png"), NULL, &the_chi, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "theta_ref");
}

/* Slope-area and chi side by side: two frames of one height and one
 * bottom, the page's title above both. */
static void test_slope_area_beside_chi(void **state)
{
    fixture *fx = *state;
    char prog[600];
    dfle_error err = {0};
    make_chi();
    teeing_gnuplot(fx, prog, sizeof prog);
    in_dir(fx, "sa_chi.png");
    assert_ok(with_gnuplot(prog, sa_chi_plot, fx, &err), &err);
    const char *sc = last_script(fx), *second;
    double t1 = script_number(sc, "set tmargin at screen ");
    double b1 = script_number(sc, "set bmargin at screen ");
    second = strstr(strstr(sc, "set bmargin at screen ") + 1, "set tmargin at screen ");
    assert_non_null(second);
    assert_close(script_number(second, "set tmargin at screen "), t1, 0, 1e-9);
    assert_close(script_number(second, "set bmargin at screen "), b1, 0, 1e-9);
    assert_non_null(strstr(sc, "'(a) Slope-area'"));
    assert_non_null(strstr(sc, "'both'"));
    assert_png(fx->path);
}

/* ---- corner ------------------------------------------------------------- */

enum { NS = 400 };
static double cs[NS * 2];

static int corner_plot(fixture *fx, dfle_error *err)
{
    static const char *const labels[2] = {"{/:Italic U} (mm/yr)", "{/:Italic k}_{df} (s^{−1} yr^{−1})"};
    static const double truth[2] = {0.4, 1.0e-4};
    dfle_corner_opts co = {.labels = labels, .truth = truth};
    return dfle_plot_corner(fx->path, NULL, &co, 2, NS, cs, err);
}

/* A truth beyond the samples stands clear of the frame; the diagonal's
 * factor is its axis's; the unit follows the value. */
static void test_corner_truth_and_factor(void **state)
{
    fixture *fx = *state;
    char prog[600];
    dfle_error err = {0};
    for (int i = 0; i < NS; i++) {
        cs[2 * i] = 0.2 + 0.15 * (i % 97) / 96.0;           /* U: 0.2..0.35, truth 0.4 */
        cs[2 * i + 1] = 1.05e-4 + 0.1e-4 * (i % 89) / 88.0; /* k_df about 1.1e-4 */
    }
    teeing_gnuplot(fx, prog, sizeof prog);
    in_dir(fx, "corner.png");
    assert_ok(with_gnuplot(prog, corner_plot, fx, &err), &err);
    const char *sc = last_script(fx);
    const char *xr = strstr(sc, "set xrange [");
    assert_non_null(xr);
    double lo = strtod(xr + 12, NULL), hi = strtod(strchr(xr, ':') + 1, NULL);
    assert_true((hi - 0.4) >= 0.099 * (hi - lo)); /* a tenth of the axis clear */
    assert_non_null(strstr(sc, "set arrow 4 from 0.4, graph 0"));
    assert_non_null(strstr(sc, " mm/yr'")); /* "U = 0.275^{+}_{-} mm/yr" */
    /* k_df's axis is labelled with a factor: the header has the same */
    {
        const char *ax = strstr(sc, "'{/:Italic k}_{df} (×10^{");
        const char *head = strstr(sc, "{/:Italic k}_{df} = ");
        char factor[32], line[400];
        assert_non_null(ax);
        assert_non_null(head);
        ax += strlen("'{/:Italic k}_{df} (");
        snprintf(factor, sizeof factor, "%.*s", (int)(strchr(ax, '}') + 1 - ax), ax);
        snprintf(line, sizeof line, "%.*s", (int)(strchr(head, '\n') - head), head);
        assert_non_null(strstr(line, factor));
    }
    assert_png(fx->path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_map_axes_name_the_crs, setup, teardown),
        cmocka_unit_test_setup_teardown(test_map_crs_refused, setup, teardown),
        cmocka_unit_test_setup_teardown(test_map_page_fits_the_map, setup, teardown),
        cmocka_unit_test_setup_teardown(test_map_furniture, setup, teardown),
        cmocka_unit_test_setup_teardown(test_map_points, setup, teardown),
        cmocka_unit_test_setup_teardown(test_chi_plot, setup, teardown),
        cmocka_unit_test_setup_teardown(test_slope_area_beside_chi, setup, teardown),
        cmocka_unit_test_setup_teardown(test_corner_truth_and_factor, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
