/*
 * plausible.h - is a parameter's value one nature could have?
 *
 * A value can be valid (the model runs with it) and still almost surely
 * a mistake: U = 0.5 meant as mm/yr runs, as m/yr, to kilometres of
 * relief.  dfle cannot refuse such values (someone may mean them), but
 * it can say so.  This table knows the usual range of the parameters
 * whose unit is most often got wrong, and which unit the mistaken value
 * was probably in.
 */
#ifndef DFLE_PLAUSIBLE_H
#define DFLE_PLAUSIBLE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Check `value` of the parameter `name` (a constructor option name, such
 * as "U", "A_max", "tau_y").  If it lies far outside the range found in
 * nature, write one sentence into msg (room for cap bytes) naming the
 * value, its unit, the usual range and, where one fits, the likely unit
 * mistake with the value to write instead, and return 1.  Return 0 for
 * plausible values, for zero (an explicit "none": U = 0 means no
 * uplift) and for names the table does not know. */
int dfle_plausible_check(const char *name, double value, char *msg, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
