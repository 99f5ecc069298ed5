/*
 * plot_sheet.c - a contact sheet: PNG images tiled on one page, each
 * under its title, to look at every figure of a study at once.
 *
 * gnuplot draws the images itself (`binary filetype=png with rgbimage`,
 * which needs its libgd support, as Debian's gnuplot-nox has).  Each
 * image's size is read from its PNG header first, so a tile keeps the
 * image's proportions, and a path that is not a PNG is an error naming
 * it before gnuplot starts.  Paths are read by gnuplot, so a relative
 * one gets a "./" prefix: gnuplot would run "<cmd" as a command.
 */
#include "dfle/plot.h"

#include "io/plot_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Width and height of the PNG at path, from its IHDR chunk. */
static int png_size(const char *path, unsigned long *w, unsigned long *h, dfle_error *err)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    unsigned char b[24];
    FILE *f = fopen(path, "rb");
    size_t k;
    if (f == NULL)
        return dfle_error_set(err, DFLE_EIO, "plot: cannot read image '%s'", path);
    k = fread(b, 1, sizeof b, f);
    fclose(f);
    if (k != sizeof b || memcmp(b, sig, 8) != 0 || memcmp(b + 12, "IHDR", 4) != 0)
        return dfle_error_set(err, DFLE_EINVAL, "plot: '%s' is not a PNG image (a contact sheet "
                              "takes PNG files)", path);
    *w = (unsigned long)b[16] << 24 | (unsigned long)b[17] << 16 | (unsigned long)b[18] << 8 | b[19];
    *h = (unsigned long)b[20] << 24 | (unsigned long)b[21] << 16 | (unsigned long)b[22] << 8 | b[23];
    if (*w == 0 || *h == 0)
        return dfle_error_set(err, DFLE_EINVAL, "plot: '%s' is an empty PNG image", path);
    return DFLE_OK;
}

int dfle_plot_sheet(const char *path, const dfle_plot_opts *opts, const char *const *paths,
                    const char *const *titles, size_t n, size_t columns, dfle_error *err)
{
    unsigned long *wh = NULL;
    double *aspect = NULL, total = 0, fs, tile_w, head, scale, ytop;
    size_t rows;
    dfle_gp_frame fr;
    dfle_gp_run r;
    int rc = DFLE_OK;

    if (paths == NULL || n == 0 || n > 1000)
        return dfle_error_set(err, DFLE_EINVAL, "plot: a contact sheet takes 1 to 1000 images "
                              "(got %zu)", n);
    if (columns == 0)
        columns = 3;
    if (columns > n)
        columns = n;
    rows = (n + columns - 1) / columns;
    wh = malloc(2 * n * sizeof *wh);
    aspect = calloc(rows, sizeof *aspect); /* each row as tall as its tallest image */
    if (wh == NULL || aspect == NULL) {
        rc = dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
        goto done;
    }
    for (size_t k = 0; k < n && rc == DFLE_OK; k++) {
        if (paths[k] == NULL || dfle_gp_format(paths[k], NULL) != FMT_PNG)
            rc = dfle_error_set(err, DFLE_EINVAL, "plot: image %zu ('%s') is not a .png file",
                                k + 1, paths[k] != NULL ? paths[k] : "(null)");
        else if ((rc = png_size(paths[k], &wh[2 * k], &wh[2 * k + 1], err)) == DFLE_OK)
            aspect[k / columns] = fmax(aspect[k / columns],
                                       (double)wh[2 * k + 1] / (double)wh[2 * k]);
    }
    if (rc != DFLE_OK)
        goto done;
    for (size_t i = 0; i < rows; i++)
        total += aspect[i];
    /* 9 cm tiles with a line of title each; a page of another size given
     * in opts scales them. */
    {
        double w_cm = 9.0 * (double)columns, tw = 9.0 / 2.54 * 72;
        double h_cm = ((double)rows * 1.6 * 8 + tw * total) / 72 * 2.54;
        if ((rc = dfle_gp_frame_of(path, opts, w_cm, fmin(h_cm, 199), &fr, err)) < 0)
            goto done;
    }
    fs = fr.font_pt;
    head = 1.6 * fs;
    tile_w = fr.w_pt / (double)columns;
    /* the rows' images share what the titles leave of the height */
    scale = fmin(tile_w, (fr.h_pt - (double)rows * head) / total);
    if ((rc = dfle_gp_begin_frame(&r, path, &fr, err)) < 0)
        goto done;
    fputs("set multiplot\nunset key\nunset border\nunset tics\nunset grid\nunset colorbox\n"
          "set autoscale noextend\n", r.f);
    ytop = fr.h_pt;
    for (size_t k = 0; k < n; k++) {
        size_t row = k / columns, col = k % columns;
        double iw = (double)wh[2 * k], ih = (double)wh[2 * k + 1];
        /* the image fitted into the tile under its title, centred */
        double bw = tile_w - 0.6 * fs, bh = scale * aspect[row] - 0.4 * fs;
        double s = fmin(bw / iw, bh / ih), x0 = (double)col * tile_w + (tile_w - iw * s) / 2;
        double top = ytop - head;
        const char *t = titles != NULL && titles[k] != NULL ? titles[k] : NULL;
        const char *base = strrchr(paths[k], '/');
        fprintf(r.f, "set lmargin at screen %.5f\nset rmargin at screen %.5f\n"
                "set tmargin at screen %.5f\nset bmargin at screen %.5f\n", x0 / fr.w_pt,
                (x0 + iw * s) / fr.w_pt, top / fr.h_pt, (top - ih * s) / fr.h_pt);
        fprintf(r.f, "set xrange [-0.5:%.1f]\nset yrange [-0.5:%.1f]\n", iw - 0.5, ih - 0.5);
        dfle_gp_page_label(r.f, 1, t != NULL ? t : base != NULL ? base + 1 : paths[k],
                           (double)col * tile_w + tile_w / 2, top + 0.7 * fs, 0, t == NULL,
                           &fr);
        fputs("plot ", r.f);
        if (paths[k][0] != '/')
            fputs("'./'.", r.f);
        dfle_gp_str(r.f, paths[k]);
        fputs(" binary filetype=png with rgbimage\nunset label\n", r.f);
        if (col == columns - 1 || k == n - 1)
            ytop -= head + scale * aspect[row];
    }
    fputs("unset multiplot\n", r.f);
    rc = dfle_gp_end(&r, err);
done:
    free(wh);
    free(aspect);
    return rc;
}
