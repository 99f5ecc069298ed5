/*
 * plausible.c - usual ranges of the parameters whose unit is most often
 * got wrong (plausible.h).
 *
 * The ranges are deliberately wide, an order of magnitude or more past
 * what the field literature reports, so a warning means "almost surely
 * not what you meant", never "unusual".  A likely mistaken unit is named
 * only where converting from it lands inside the range, so the advice
 * is never itself implausible.
 */
#include "dfle/plausible.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

typedef struct plausible_range {
    const char *name;
    const char *unit;    /* dfle's unit for the parameter                 */
    double lo, hi;       /* usual range, in `unit`                        */
    const char *usual;   /* what the range is, for the message            */
    /* The unit a value below lo (above hi) was probably given in, and
     * the factor from that unit to dfle's; NULL when none is likely. */
    const char *lo_unit;
    double lo_factor;
    const char *hi_unit;
    double hi_factor;
} plausible_range;

static const plausible_range ranges[] = {
    /* Rock uplift: 0.01-10 mm/yr in active ranges; U is in m/yr, and
     * mm/yr is how papers quote it. */
    {"U", "m/yr", 1e-6, 0.02, "rock-uplift rates (0.001 to 20 mm/yr)", NULL, 0, "mm/yr", 1e-3},
    {"A_max", "m^2", 1e4, 1e11, "drainage areas of steep channels (0.01 to 100 000 km^2)",
     "km^2", 1e6, NULL, 0},
    {"A0", "m^2", 1.0, 1e7, "drainage areas at a channel head (1 m^2 to 10 km^2)", "km^2", 1e6,
     NULL, 0},
    {"length", "m", 50.0, 3e5, "channel lengths (50 m to 300 km)", "km", 1e3, NULL, 0},
    {"dx", "m", 0.05, 2000.0, "node spacings (5 cm to 2 km)", "km", 1e3, NULL, 0},
    {"M0", "m^3", 1.0, 1e7, "debris-flow volumes (1 to 10^7 m^3)", NULL, 0, NULL, 0},
    {"tau_y", "Pa", 1.0, 1e5, "debris-flow yield strengths (1 Pa to 100 kPa)", "kPa", 1e3, NULL, 0},
    {"mu", "Pa s", 1e-3, 1e5, "debris-flow viscosities (0.001 to 10^5 Pa s)", NULL, 0, NULL, 0},
    {"rho_b", "kg/m^3", 500.0, 4000.0, "bulk densities (500 to 4000 kg/m^3)", "g/cm^3", 1e3,
     NULL, 0},
    {"rho_s", "kg/m^3", 500.0, 4000.0, "sediment densities (500 to 4000 kg/m^3)", "g/cm^3", 1e3,
     NULL, 0},
    {"rho_w", "kg/m^3", 500.0, 4000.0, "water densities (about 1000 kg/m^3)", "g/cm^3", 1e3,
     NULL, 0},
    {"rho_f", "kg/m^3", 500.0, 4000.0, "fluid densities (about 1000 kg/m^3)", "g/cm^3", 1e3,
     NULL, 0},
    {"g", "m/s^2", 1.0, 30.0, "gravity (9.81 m/s^2 on Earth)", NULL, 0, NULL, 0},
    {"D_eff", "m", 1e-4, 5.0, "grain sizes (0.1 mm to 5 m)", NULL, 0, "mm", 1e-3},
    {"R_c", "m", 1e-3, 20.0, "mean annual runoff (1 mm to 20 m)", NULL, 0, "mm", 1e-3},
    /* Debris-flow erodibility (Eq. 6, E_df in m/yr: k_df absorbs the
     * flows' frequency): the paper's Tables G2-G5 span 3e-5 to 1e-3. */
    {"k_df", "m^(1-beta)/s^2", 1e-7, 0.1, "debris-flow erodibilities (1e-7 to 0.1; the paper's "
     "3e-5 to 1e-3)", NULL, 0, NULL, 0},
};

int dfle_plausible_check(const char *name, double value, char *msg, size_t cap)
{
    const plausible_range *r = NULL;
    const char *unit;
    double factor, fixed;
    int low;

    for (size_t i = 0; i < sizeof ranges / sizeof ranges[0]; i++)
        if (strcmp(name, ranges[i].name) == 0)
            r = &ranges[i];
    /* Zero is an explicit "none"; negative and non-finite values are the
     * constructors' to refuse, with their own messages. */
    if (r == NULL || !(value > 0) || !isfinite(value) || (value >= r->lo && value <= r->hi))
        return 0;
    low = value < r->lo;
    unit = low ? r->lo_unit : r->hi_unit;
    factor = low ? r->lo_factor : r->hi_factor;
    fixed = value * factor;
    if (unit != NULL && fixed >= r->lo && fixed <= r->hi)
        snprintf(msg, cap,
                 "%s = %g %s is far %s %s: %s is in %s; if you meant %g %s, write %s = %g",
                 name, value, r->unit, low ? "below" : "above", r->usual, name, r->unit, value,
                 unit, name, fixed);
    else
        snprintf(msg, cap, "%s = %g %s is far %s %s (%s is in %s)", name, value, r->unit,
                 low ? "below" : "above", r->usual, name, r->unit);
    return 1;
}
