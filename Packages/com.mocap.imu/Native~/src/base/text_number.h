/* Numbers in the engine's text formats (calibration files, BVH, model metadata) are written and
 * read with a '.' decimal point whatever LC_NUMERIC the host process chose: an editor or a .NET
 * host may run with the user's locale, where printf writes "0,5" and strtod stops at "0.5". */
#ifndef MOCAP_TEXT_NUMBER_H
#define MOCAP_TEXT_NUMBER_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* strtod for text written with '.', in any locale. Same contract as strtod (leading
 * whitespace, *end after the number, end == s when there is none). */
double text_strtod(const char *s, char **end);

/* snprintf of one number (fmt holds one double conversion, e.g. "%.9g") with '.' as the decimal
 * point in any locale. Returns what snprintf returns. */
int text_format_double(char *buf, size_t cap, const char *fmt, double value);

/* The decimal point of the current C locale (LC_NUMERIC). */
char text_locale_point(void);

/* Replaces the locale's decimal point in text by '.'. */
void text_use_dot(char *text, char locale_point);

#ifdef __cplusplus
}
#endif
#endif
