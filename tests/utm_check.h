/*
 * utm_check.h - the inverse transverse Mercator of Snyder (1987, Map
 * Projections: A Working Manual, USGS Prof. Paper 1395, eqs. 8-18 to
 * 8-25) on WGS 84, written out here so that the longitude and latitude
 * dfle gets from GDAL/PROJ are checked against formulas that do not
 * come from either.  Within a UTM zone the series is good to well under
 * a millimetre.
 */
#ifndef DFLE_TEST_UTM_CHECK_H
#define DFLE_TEST_UTM_CHECK_H

#include <math.h>

/* (E, N) of UTM zone `zone`, northern hemisphere, to degrees. */
static inline void utm_to_lonlat(int zone, double E, double N, double *lon, double *lat)
{
    const double a = 6378137.0, f = 1 / 298.257223563, k0 = 0.9996;
    const double e2 = f * (2 - f), ep2 = e2 / (1 - e2), e4 = e2 * e2, e6 = e4 * e2;
    const double e1 = (1 - sqrt(1 - e2)) / (1 + sqrt(1 - e2));
    const double x = E - 500000.0, M = N / k0;
    const double mu = M / (a * (1 - e2 / 4 - 3 * e4 / 64 - 5 * e6 / 256));
    const double p1 = mu + (3 * e1 / 2 - 27 * pow(e1, 3) / 32) * sin(2 * mu) +
                      (21 * e1 * e1 / 16 - 55 * pow(e1, 4) / 32) * sin(4 * mu) +
                      (151 * pow(e1, 3) / 96) * sin(6 * mu) + (1097 * pow(e1, 4) / 512) * sin(8 * mu);
    const double s = sin(p1), c = cos(p1), t = tan(p1);
    const double C1 = ep2 * c * c, T1 = t * t, N1 = a / sqrt(1 - e2 * s * s);
    const double R1 = a * (1 - e2) / pow(1 - e2 * s * s, 1.5), D = x / (N1 * k0);
    const double phi = p1 - (N1 * t / R1) *
                                (D * D / 2 -
                                 (5 + 3 * T1 + 10 * C1 - 4 * C1 * C1 - 9 * ep2) * pow(D, 4) / 24 +
                                 (61 + 90 * T1 + 298 * C1 + 45 * T1 * T1 - 252 * ep2 - 3 * C1 * C1) *
                                     pow(D, 6) / 720);
    const double lam = (D - (1 + 2 * T1 + C1) * pow(D, 3) / 6 +
                        (5 - 2 * C1 + 28 * T1 - 3 * C1 * C1 + 8 * ep2 + 24 * T1 * T1) * pow(D, 5) /
                            120) /
                       c;
    const double deg = 57.29577951308232; /* 180 / pi */
    *lat = phi * deg;
    *lon = (double)(6 * zone - 183) + lam * deg;
}

#endif
