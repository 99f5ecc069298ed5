/*
 * dem_tiff.c - a TIFF's GDAL_NODATA tag, read from the file itself.
 *
 * GDAL stores a GeoTIFF's NoData value as text in a TIFF tag of its own
 * (42113) and reads it with an atof that turns any word into 0: a file
 * whose tag says "abc" was read with NoData = 0, and every cell at
 * exactly 0 m (sea level, a reservoir) silently became NoData.  GDAL
 * gives no way to see the text it parsed, so the reader looks at the
 * tag here, in the first image file directory (classic TIFF and
 * BigTIFF), and refuses a value that is no number.
 */
#include "dem/dem_tiff.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TAG_GDAL_NODATA 42113
#define TYPE_ASCII 2

typedef struct tiff {
    FILE *f;
    int big_endian, big_tiff;
} tiff;

static int read_at(tiff *t, uint64_t off, void *buf, size_t n)
{
    if (off > (uint64_t)INT64_MAX || fseeko(t->f, (off_t)off, SEEK_SET) != 0)
        return 0;
    return fread(buf, 1, n, t->f) == n;
}

static uint64_t get(const tiff *t, const unsigned char *b, int bytes)
{
    uint64_t v = 0;
    for (int i = 0; i < bytes; i++)
        v |= (uint64_t)b[t->big_endian ? bytes - 1 - i : i] << (8 * i);
    return v;
}

int dem_tiff_nodata_text(const char *path, char *buf, size_t cap)
{
    unsigned char head[16], e[20];
    uint64_t ifd, count;
    tiff t = {NULL, 0, 0};
    int found = 0;

    if (cap == 0 || strncmp(path, "/vsi", 4) == 0 || (t.f = fopen(path, "rb")) == NULL)
        return 0;
    if (fread(head, 1, 16, t.f) < 8 || !(memcmp(head, "II", 2) == 0 || memcmp(head, "MM", 2) == 0))
        goto done;
    t.big_endian = head[0] == 'M';
    switch (get(&t, head + 2, 2)) {
    case 42:
        ifd = get(&t, head + 4, 4);
        break;
    case 43:
        t.big_tiff = 1;
        ifd = get(&t, head + 8, 8);
        break;
    default:
        goto done;
    }
    {
        const int cbytes = t.big_tiff ? 8 : 2, esize = t.big_tiff ? 20 : 12;
        const int vbytes = t.big_tiff ? 8 : 4;
        if (!read_at(&t, ifd, head, (size_t)cbytes))
            goto done;
        count = get(&t, head, cbytes);
        for (uint64_t k = 0; k < count && k < 4096; k++) {
            uint64_t n, where;
            if (!read_at(&t, ifd + (uint64_t)cbytes + k * (uint64_t)esize, e, (size_t)esize))
                goto done;
            if (get(&t, e, 2) != TAG_GDAL_NODATA || get(&t, e + 2, 2) != TYPE_ASCII)
                continue;
            n = get(&t, e + 4, vbytes);
            if (n == 0)
                goto done;
            /* The text is inline when it fits in the value field; a longer
             * one than buf holds is cut (no number is that long). */
            if (n <= (uint64_t)vbytes) {
                memcpy(buf, e + 4 + vbytes, (size_t)n);
            } else {
                where = get(&t, e + 4 + vbytes, vbytes);
                n = n < cap ? n : cap - 1;
                if (!read_at(&t, where, buf, (size_t)n))
                    goto done;
            }
            n = n < cap ? n : cap - 1;
            buf[n] = '\0';
            found = 1;
            break;
        }
    }
done:
    fclose(t.f);
    return found;
}

int dem_tiff_nodata_valid(const char *text)
{
    const char *s = text;
    char *end;
    while (*s == ' ' || *s == '\t')
        s++;
    if (*s == '\0')
        return 1;
    (void)strtod(s, &end);
    if (end == s)
        return 0;
    while (*end == ' ' || *end == '\t' || *end == '\n' || *end == '\r')
        end++;
    return *end == '\0';
}
